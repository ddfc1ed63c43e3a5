// fidelity_fem: SoftKin's shapes against a pressure-driven hyperelastic FEM (CalculiX, hollow
// chambers; solver/baselines/calculix_pressure.hpp), compared at the same chamber volume.
//
// Per case (a robot or a scene file, and the chamber pressures at the end of the ramp): the FEM
// ramps the pressure; at fractions of the ramp it reached, SoftKin is solved at the actuation
// whose achieved chamber volume ratios equal the FEM's cavity volume ratios (a secant iteration
// per actuator), and the two shapes are compared: tip distance, bend angle, RMS and largest
// distance over the outer-surface vertices, and centre lines (surface vertices averaged in slices
// along the robot's long axis) for the plot.
#include "softkin/experiments/fem_trajectory.hpp"
#include "softkin/experiments/matched_volume.hpp"
#include "softkin/experiments/measure.hpp"
#include "softkin/experiments/results.hpp"
#include "softkin/experiments/runner.hpp"
#include "softkin/solver/baselines/calculix_pressure.hpp"
#include "softkin/solver/factory/fk_factory.hpp"
#include "softkin/solver/mesh/element_faces.hpp"
#include "softkin/solver/robots/robots.hpp"
#include "softkin/solver/scene/scene_json.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <limits>

namespace softkin {

namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

struct FidelityCase {
  std::string label, robot, scene;
  int res = 0;
  std::map<std::string, double> params;
  std::vector<double> pressure;  ///< per actuator, MPa at the end of the ramp
  /// The case's own FEM element and largest increment ("" / 0: the config's).
  std::string fem_element;
  double max_increment = 0;
  /// Whether the case is compared again with the parameters fitted on calibrate_on.
  bool calibrated = true;
};

struct FidelityParams {
  std::vector<FidelityCase> cases;
  PressureFemOptions fem;
  std::vector<double> fractions;
  int slices = 24;
  FkOptions opts;
  std::string calibrate_on;  ///< label of the case the parameters are fitted on ("": none)
  std::array<double, 2> weight_range{0.01, 5.0};  ///< chamber weight multiplier searched
  std::array<double, 2> r_omega_range{0.0, 1.0};  ///< body R_omega searched
};

FidelityParams ReadFidelityParams(const Config& cfg) {
  FidelityParams p;
  const nlohmann::json cases = cfg.Raw("cases");
  if (!cases.is_array() || cases.empty())
    cfg.Fail("cases", "a non-empty array of {label, robot | scene, res, pressure, ...}");
  for (size_t i = 0; i < cases.size(); ++i) {
    const std::string key = "cases[" + std::to_string(i) + "]";
    const auto& c = cases[i];
    if (!c.is_object()) cfg.Fail(key, "an object");
    FidelityCase fc;
    for (const auto& [k, v] : c.items()) {
      if (k == "label" && v.is_string()) {
        fc.label = v.get<std::string>();
      } else if (k == "robot" && v.is_string()) {
        fc.robot = v.get<std::string>();
      } else if (k == "scene" && v.is_string()) {
        fc.scene = v.get<std::string>();
      } else if (k == "res" && v.is_number_integer() && v.get<int>() > 0) {
        fc.res = v.get<int>();
      } else if (k == "robot_params") {
        fc.params = cfg.NumberObject(v, key + ".robot_params");
      } else if (k == "pressure" && v.is_array() && !v.empty()) {
        for (const auto& x : v) {
          if (!x.is_number()) cfg.Fail(key + ".pressure", "an array of pressures (MPa)");
          fc.pressure.push_back(x.get<double>());
        }
      } else if (k == "fem_element") {
        fc.fem_element = v.is_string() ? v.get<std::string>() : v.dump();
        CheckFemElement(cfg, key + ".fem_element", fc.fem_element);
      } else if (k == "max_increment") {
        fc.max_increment = v.is_number() ? v.get<double>() : 0.0;
        CheckMaxIncrement(cfg, key + ".max_increment", fc.max_increment);
      } else if (k == "calibrated") {
        if (!v.is_boolean()) cfg.Fail(key + ".calibrated", "true or false");
        fc.calibrated = v.get<bool>();
      } else {
        cfg.Fail(key + "." + k,
                 "one of label (string), robot (string), scene (path), res (positive integer), "
                 "robot_params (object), pressure (array of MPa), fem_element (C3D10 or C3D4), "
                 "max_increment (fraction of the ramp), calibrated (boolean)");
      }
    }
    if (fc.label.empty()) cfg.Fail(key + ".label", "a name for the case");
    if (fc.robot.empty() == fc.scene.empty()) cfg.Fail(key, "exactly one of robot and scene");
    if (fc.pressure.empty()) cfg.Fail(key + ".pressure", "one pressure (MPa) per actuator");
    if (std::all_of(fc.pressure.begin(), fc.pressure.end(), [](double x) { return x == 0.0; }))
      cfg.Fail(key + ".pressure", "at least one non-zero pressure (MPa)");
    p.cases.push_back(fc);
  }
  p.fem = ReadPressureFemOptions(cfg, 0.02, 0.0);
  p.fem.law = cfg.String("fem_law", "neo-hooke");
  CheckFemLaw(cfg, "fem_law", p.fem.law);
  p.fractions = cfg.NumberList("fractions", {0.25, 0.5, 0.75, 1.0});
  p.slices = cfg.Int("slices", 24);
  p.opts = cfg.Solver(FkOptions{});
  p.calibrate_on = cfg.String("calibrate_on", "");
  const auto wr = cfg.NumberList("chamber_weight_scale_range", {0.01, 5.0});
  const auto rr = cfg.NumberList("body_r_omega_range", {0.0, 1.0});
  cfg.CheckNoUnknownKeys();
  if (wr.size() != 2 || !(wr[0] > 0 && wr[0] < wr[1]))
    cfg.Fail("chamber_weight_scale_range", "[lo, hi] with 0 < lo < hi");
  if (rr.size() != 2 || !(rr[0] >= 0 && rr[0] < rr[1] && rr[1] <= 1))
    cfg.Fail("body_r_omega_range", "[lo, hi] with 0 <= lo < hi <= 1");
  p.weight_range = {wr[0], wr[1]};
  p.r_omega_range = {rr[0], rr[1]};
  if (!p.calibrate_on.empty() &&
      std::none_of(p.cases.begin(), p.cases.end(),
                   [&](const FidelityCase& c) { return c.label == p.calibrate_on; }))
    cfg.Fail("calibrate_on", "the label of one of the cases");
  for (size_t i = 0; i < p.cases.size(); ++i)
    if (p.cases[i].label == p.calibrate_on && !p.cases[i].calibrated)
      cfg.Fail("cases[" + std::to_string(i) + "].calibrated",
               "true (or absent) for the case that calibrate_on fits");
  for (double f : p.fractions)
    if (!(f > 0 && f <= 1)) cfg.Fail("fractions", "fractions of the FEM ramp in (0, 1]");
  if (p.slices < 2) cfg.Fail("slices", "an integer >= 2");
  return p;
}

/// The FEM options of case c: the config's, with the case's own element and increment.
PressureFemOptions CaseFem(const FidelityParams& p, const FidelityCase& c) {
  PressureFemOptions o = p.fem;
  if (!c.fem_element.empty()) o.element = c.fem_element;
  if (c.max_increment > 0) o.max_increment = c.max_increment;
  return o;
}

Scene CaseScene(const Config& cfg, const FidelityCase& c) {
  if (!c.robot.empty()) {
    try {
      return MakeRobot(c.robot, c.res, c.params);
    } catch (const std::invalid_argument& e) {
      throw std::invalid_argument(cfg.path() + ": case '" + c.label + "': " + e.what());
    }
  }
  std::filesystem::path f(c.scene);
  if (f.is_relative() && !std::filesystem::exists(f))
    f = std::filesystem::path(SOFTKIN_SOURCE_DIR) / f;
  return LoadSceneJson(f.string());
}

/// Centre line: the mean deformed position of the surface vertices in each of `n` slices of the
/// rest shape along axis `axis` (NaN rows for slices with no vertex).
Eigen::MatrixX3d CentreLine(const Mesh& mesh, const std::vector<int>& surf,
                            const Eigen::MatrixX3d& X, int axis, int n) {
  const double lo = mesh.vertices.col(axis).minCoeff(), hi = mesh.vertices.col(axis).maxCoeff();
  Eigen::MatrixX3d sum = Eigen::MatrixX3d::Zero(n, 3);
  Eigen::VectorXd count = Eigen::VectorXd::Zero(n);
  for (int v : surf) {
    const int b = std::min(n - 1, static_cast<int>(n * (mesh.vertices(v, axis) - lo) / (hi - lo)));
    sum.row(b) += X.row(v);
    count[b] += 1;
  }
  for (int b = 0; b < n; ++b)
    sum.row(b) = count[b] > 0 ? Eigen::RowVector3d(sum.row(b) / count[b])
                              : Eigen::RowVector3d::Constant(kNaN);  // no vertex in this slice
  return sum;
}

/// One case: its scene, FEM run and what the comparison needs.
struct CaseData {
  const FidelityCase* fc = nullptr;
  Scene scene;
  PressureFemRun fem;
  std::vector<bool> loaded;
  int lead = -1, tip = -1, axis = 0;
  bool has_bend = false;
  double length = 0;
  std::vector<int> surf;
  std::vector<double> fem_angles;
  std::vector<size_t> picks;  ///< the FEM increment compared at each fraction
};

/// SoftKin's free parameters: a multiplier of every pneumatic actuator's element weight, and the
/// R_omega of every (non-Mooney-Rivlin) body region (negative: unchanged).
struct SoftKinParams {
  double weight_scale = 1.0;
  double r_omega = -1.0;
};

Scene WithParams(Scene s, const SoftKinParams& q) {
  for (auto& a : s.actuators)
    if (a.type == ActuatorType::Pneumatic) a.weight *= q.weight_scale;
  if (q.r_omega >= 0)
    for (auto& [tag, m] : s.body)
      if (!m.hyperelastic()) m.r_omega = q.r_omega;
  return s;
}

/// The comparison at one fraction.
struct Compared {
  double fraction = 0;
  size_t k = 0;
  MatchedVolume m;
  double tip_error = 0, rms = 0, worst = 0, bend = kNaN;
};

/// SoftKin with parameters q on case d: `model` is built from WithParams(d.scene, q).
std::vector<Compared> Compare(const CaseData& d, const std::shared_ptr<const Model>& model,
                              const FidelityParams& p) {
  const Scene& scene = model->scene();
  auto solver = MakeFkSolver(model, p.opts);
  std::unique_ptr<BendAngle> bend;
  if (d.has_bend) bend = std::make_unique<BendAngle>(scene);
  std::vector<Compared> out;
  Eigen::MatrixX3d warm;
  for (size_t i = 0; i < d.picks.size(); ++i) {
    const PressureFemIncrement& inc = d.fem.increments[d.picks[i]];
    Compared c;
    c.fraction = p.fractions[i];
    c.k = d.picks[i];
    c.m = SolveAtVolume(solver.get(), scene, inc.cavity_ratio, d.loaded, i ? &warm : nullptr);
    warm = c.m.r.positions;
    const Eigen::RowVector3d ft = scene.marker_positions(inc.positions).row(d.tip);
    const Eigen::RowVector3d st = scene.marker_positions(c.m.r.positions).row(d.tip);
    c.tip_error = (ft - st).norm();
    double sum2 = 0;
    int n = 0;
    for (int v : d.surf) {
      if (!inc.positions.row(v).allFinite()) continue;
      const double e = (inc.positions.row(v) - c.m.r.positions.row(v)).norm();
      sum2 += e * e;
      c.worst = std::max(c.worst, e);
      ++n;
    }
    c.rms = std::sqrt(sum2 / std::max(1, n));
    if (bend) c.bend = (*bend)(c.m.r.positions);
    out.push_back(std::move(c));
  }
  return out;
}

/// Mean tip error over the fractions, in % of the length; a failed or unmatched solve counts as
/// a large error so that the search leaves such parameters.
double MeanTipError(const CaseData& d, const SoftKinParams& q, const FidelityParams& p) {
  double sum = 0;
  const auto rows = Compare(d, std::make_shared<const Model>(WithParams(d.scene, q)), p);
  for (const auto& c : rows)
    sum +=
        c.m.r.status == FkStatus::Converged && c.m.matched ? 100.0 * c.tip_error / d.length : 1e3;
  return sum / std::max<size_t>(1, rows.size());
}

/// Golden-section search of f on [lo, hi] with `evals` evaluations; returns the best point.
template <class F>
double GoldenSearch(F f, double lo, double hi, int evals) {
  const double g = (std::sqrt(5.0) - 1.0) / 2.0;
  double a = lo, b = hi, x1 = b - g * (b - a), x2 = a + g * (b - a);
  double f1 = f(x1), f2 = f(x2);
  for (int i = 2; i < evals; ++i) {
    if (f1 <= f2) {
      b = x2;
      x2 = x1;
      f2 = f1;
      x1 = b - g * (b - a);
      f1 = f(x1);
    } else {
      a = x1;
      x1 = x2;
      f1 = f2;
      x2 = a + g * (b - a);
      f2 = f(x2);
    }
  }
  return f1 <= f2 ? x1 : x2;
}

/// Fits the weight multiplier (on a log scale) and the body R_omega to case d: two rounds of
/// coordinate-wise golden-section searches on the mean tip error.
SoftKinParams Calibrate(const CaseData& d, const FidelityParams& p, bool verbose) {
  SoftKinParams q;
  q.r_omega = d.scene.body.empty() ? 1.0 : d.scene.body.begin()->second.r_omega;
  for (int round = 0; round < 2; ++round) {
    q.weight_scale = std::exp(GoldenSearch(
        [&](double lw) {
          SoftKinParams t = q;
          t.weight_scale = std::exp(lw);
          return MeanTipError(d, t, p);
        },
        std::log(p.weight_range[0]), std::log(p.weight_range[1]), 10));
    q.r_omega = GoldenSearch(
        [&](double r) {
          SoftKinParams t = q;
          t.r_omega = r;
          return MeanTipError(d, t, p);
        },
        p.r_omega_range[0], p.r_omega_range[1], 8);
    if (verbose)
      std::fprintf(stderr, "  calibration round %d: chamber weight x %.3f, body R_omega %.3f\n",
                   round + 1, q.weight_scale, q.r_omega);
  }
  return q;
}

CaseData RunCase(const Config& cfg, const FidelityCase& fc, Scene scene, const FidelityParams& p,
                 bool verbose) {
  CaseData d;
  d.fc = &fc;
  d.scene = std::move(scene);
  const Scene& s = d.scene;
  const Eigen::VectorXd pressure =
      Eigen::Map<const Eigen::VectorXd>(fc.pressure.data(), fc.pressure.size());
  d.loaded.resize(s.num_actuators());
  for (int a = 0; a < s.num_actuators(); ++a) {
    d.loaded[a] = pressure[a] != 0.0;
    if (d.loaded[a] && d.lead < 0) d.lead = a;
  }
  d.tip = s.marker_index("tip");
  const PressureFemOptions fem = CaseFem(p, fc);
  if (verbose)
    std::fprintf(stderr, "  %s: FEM (%s, %s) on %d tets ...\n", fc.label.c_str(), fem.law.c_str(),
                 fem.element.c_str(), s.mesh.num_elements());
  const Model model(s);
  d.fem = RunPressureFem(model, pressure, fem);
  if (!d.fem.ok)
    throw std::runtime_error(cfg.path() + ": case '" + fc.label + "': " + d.fem.message);
  if (d.fem.increments.empty())
    throw std::runtime_error(cfg.path() + ": case '" + fc.label +
                             "': the FEM converged no increment: " + d.fem.message);
  if (verbose)
    std::fprintf(stderr, "  %s: %zu increments in %.1f s%s%s\n", fc.label.c_str(),
                 d.fem.increments.size(), d.fem.time_s, d.fem.reached_end ? "" : "; ",
                 d.fem.message.c_str());
  d.has_bend = s.marker_index("tip_top") >= 0 && s.marker_index("tip_bottom") >= 0;
  if (d.has_bend) {
    BendAngle bend(s);
    for (const auto& inc : d.fem.increments) d.fem_angles.push_back(bend(inc.positions));
  } else {
    d.fem_angles.assign(d.fem.increments.size(), kNaN);
  }
  const Eigen::RowVector3d ext =
      s.mesh.vertices.colwise().maxCoeff() - s.mesh.vertices.colwise().minCoeff();
  d.length = ext.maxCoeff(&d.axis);
  d.surf = BoundaryVertices(s.mesh);
  const double end_load = d.fem.increments.back().load;
  for (double f : p.fractions) {
    size_t k = 0;
    for (size_t q = 0; q < d.fem.increments.size(); ++q)
      if (std::abs(d.fem.increments[q].load - f * end_load) <
          std::abs(d.fem.increments[k].load - f * end_load))
        k = q;
    d.picks.push_back(k);
  }
  return d;
}

nlohmann::json NullIfNaN(double v) {
  return std::isnan(v) ? nlohmann::json(nullptr) : nlohmann::json(v);
}

}  // namespace

nlohmann::json RunFidelityFem(const Config& cfg, const std::string& dir, bool verbose) {
  const FidelityParams p = ReadFidelityParams(cfg);
  std::vector<Scene> scenes;
  for (size_t i = 0; i < p.cases.size(); ++i) {
    const std::string key = "cases[" + std::to_string(i) + "]";
    scenes.push_back(CaseScene(cfg, p.cases[i]));
    if (static_cast<int>(p.cases[i].pressure.size()) != scenes.back().num_actuators())
      cfg.Fail(key + ".pressure", "one pressure per actuator of '" + scenes.back().name + "' (" +
                                      std::to_string(scenes.back().num_actuators()) + ")");
    // Before any FEM runs: the case's scene must have a tip marker and be one the FEM can mesh.
    if (scenes.back().marker_index("tip") < 0)
      cfg.Fail(key, "a robot or scene with a 'tip' marker");
    try {
      BuildPressureFemMesh(Model(scenes.back()), CaseFem(p, p.cases[i]).element);
    } catch (const std::invalid_argument& e) {
      cfg.Fail(key, std::string("a scene the pressure FEM can mesh: ") + e.what());
    }
  }
  if (cfg.check_only()) return {};
  std::vector<CaseData> data;
  CsvWriter fem_csv(dir + "/fem_increments.csv", {"case", "load", "pressure_mpa", "cavity_ratio",
                                                  "tip_x", "tip_y", "tip_z", "bend_deg", "wall_s"});
  for (size_t ci = 0; ci < p.cases.size(); ++ci) {
    data.push_back(RunCase(cfg, p.cases[ci], std::move(scenes[ci]), p, verbose));
    const CaseData& d = data.back();
    for (size_t k = 0; k < d.fem.increments.size(); ++k) {
      const auto& inc = d.fem.increments[k];
      const Eigen::RowVector3d t = d.scene.marker_positions(inc.positions).row(d.tip);
      fem_csv.Row({double(ci), inc.load, inc.pressure[d.lead], inc.cavity_ratio[d.lead], t.x(),
                   t.y(), t.z(), d.fem_angles[k], inc.wall_s});
    }
  }
  // The parameter sets compared: as given, and fitted on one case if asked.
  std::vector<std::pair<std::string, SoftKinParams>> variants = {{"default", SoftKinParams{}}};
  nlohmann::json calib = nullptr;
  for (const auto& d : data)
    if (d.fc->label == p.calibrate_on) {
      const SoftKinParams q = Calibrate(d, p, verbose);
      variants.push_back({"calibrated", q});
      calib = {{"fitted_on", d.fc->label},
               {"chamber_weight_scale", q.weight_scale},
               {"body_r_omega", q.r_omega},
               {"objective", "mean tip error over the fractions, % of the length"}};
    }
  CsvWriter cmp_csv(
      dir + "/fidelity.csv",
      {"case", "calibrated", "fraction", "load", "cavity_ratio", "softkin_ratio", "actuation",
       "matched", "tip_error_mm", "tip_error_percent", "bend_fem_deg", "bend_softkin_deg",
       "surface_rms_mm", "surface_max_mm", "fem_wall_s", "softkin_s"});
  CsvWriter line_csv(dir + "/centrelines.csv",
                     {"case", "calibrated", "fraction", "model", "slice", "x", "y", "z"});
  nlohmann::json out = nlohmann::json::array();
  for (size_t ci = 0; ci < data.size(); ++ci) {
    const CaseData& d = data[ci];
    nlohmann::json entry = {{"case", d.fc->label},
                            {"robot", d.fc->robot.empty() ? d.scene.name : d.fc->robot},
                            {"res", d.fc->res},
                            {"tets", d.scene.mesh.num_elements()},
                            {"fem_element", CaseFem(p, *d.fc).element},
                            {"fem_nodes", d.fem.nodes},
                            {"fem_elements", d.fem.elements},
                            {"fem_increments", d.fem.increments.size()},
                            {"fem_reached_end", d.fem.reached_end},
                            {"fem_stopped_because", d.fem.message},
                            {"fem_time_s", d.fem.time_s},
                            {"fem_end_pressure_mpa", d.fem.increments.back().pressure[d.lead]},
                            {"fem_end_cavity_ratio", d.fem.increments.back().cavity_ratio[d.lead]},
                            {"fem_end_bend_deg", NullIfNaN(d.fem_angles.back())},
                            {"length_mm", d.length}};
    if (!p.calibrate_on.empty())
      entry["role"] = d.fc->label == p.calibrate_on ? "calibration"
                      : d.fc->calibrated            ? "hold-out"
                                                    : "default parameters only";
    for (size_t vi = 0; vi < variants.size(); ++vi) {
      const auto& [vname, q] = variants[vi];
      if (vname == "calibrated" && !d.fc->calibrated) continue;
      const auto model = std::make_shared<const Model>(WithParams(d.scene, q));
      const std::vector<Compared> rows = Compare(d, model, p);
      auto cold_solver = MakeFkSolver(model, p.opts);  // a fresh solver: nothing kept from above
      nlohmann::json jrows = nlohmann::json::array();
      double mean = 0;
      for (const Compared& c : rows) {
        const PressureFemIncrement& inc = d.fem.increments[c.k];
        const double pct = 100.0 * c.tip_error / d.length;
        mean += pct / rows.size();
        // SoftKin's cost for this shape: one cold solve from rest at the matched actuation.
        const FkResult cold = cold_solver->Solve(c.m.c);
        cmp_csv.Row({double(ci), double(vi), c.fraction, inc.load, inc.cavity_ratio[d.lead],
                     c.m.r.volume_ratios[d.lead], c.m.c[d.lead], c.m.matched ? 1.0 : 0.0,
                     c.tip_error, pct, d.fem_angles[c.k], c.bend, c.rms, c.worst, inc.wall_s,
                     cold.time_s});
        const Eigen::MatrixX3d lf =
            CentreLine(d.scene.mesh, d.surf, inc.positions, d.axis, p.slices);
        const Eigen::MatrixX3d ls =
            CentreLine(d.scene.mesh, d.surf, c.m.r.positions, d.axis, p.slices);
        for (int b = 0; b < p.slices; ++b) {
          if (!lf.row(b).allFinite() || !ls.row(b).allFinite()) continue;
          line_csv.Row(
              {double(ci), double(vi), c.fraction, 0.0, double(b), lf(b, 0), lf(b, 1), lf(b, 2)});
          line_csv.Row(
              {double(ci), double(vi), c.fraction, 1.0, double(b), ls(b, 0), ls(b, 1), ls(b, 2)});
        }
        jrows.push_back({{"fraction", c.fraction},
                         {"pressure_mpa", inc.pressure[d.lead]},
                         {"cavity_ratio", inc.cavity_ratio[d.lead]},
                         {"softkin_actuation", c.m.c[d.lead]},
                         {"matched", c.m.matched},
                         {"softkin_status", FkStatusToString(c.m.r.status)},
                         {"tip_error_mm", c.tip_error},
                         {"tip_error_percent_of_length", pct},
                         {"bend_fem_deg", NullIfNaN(d.fem_angles[c.k])},
                         {"bend_softkin_deg", NullIfNaN(c.bend)},
                         {"surface_rms_mm", c.rms},
                         {"surface_max_mm", c.worst},
                         {"fem_wall_s", inc.wall_s},
                         {"softkin_cold_s", cold.time_s}});
        if (verbose)
          std::fprintf(stderr,
                       "    %s, %s %.0f%%: cavity ratio %.3f (SoftKin c = %.3f), tip error %.2f mm "
                       "(%.1f%%), surface RMS %.2f mm\n",
                       d.fc->label.c_str(), vname.c_str(), 100 * c.fraction,
                       inc.cavity_ratio[d.lead], c.m.c[d.lead], c.tip_error, pct, c.rms);
      }
      entry[vname] = {{"rows", jrows}, {"mean_tip_error_percent_of_length", mean}};
    }
    out.push_back(entry);
  }
  nlohmann::json j;
  j["fem"] = {{"law", p.fem.law},
              {"element", p.fem.element},
              {"young_mpa", p.fem.young},
              {"poisson", p.fem.poisson},
              {"pressure_on", "cavity walls (hollow chambers), follower load under NLGEOM"}};
  j["compared_at"] = "equal chamber volume ratio (SoftKin's achieved ratio = FEM cavity ratio)";
  j["calibration"] = calib;
  j["cases"] = out;
  return j;
}

}  // namespace softkin
