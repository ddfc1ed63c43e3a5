// Fig. 3.7 (thesis Sec. 3.3.2, Algorithm 2): the twisting robot inflated progressively with chamber
// remeshing up to alpha = 115, with the shapes at alpha = 5, 28 and 115, against alpha = 28
// applied at once on the initial mesh without remeshing.
#include "softkin/experiments/results.hpp"
#include "softkin/experiments/runner.hpp"
#include "softkin/solver/factory/fk_factory.hpp"
#include "softkin/solver/fk/fk_solver.hpp"
#include "softkin/solver/mesh/io/mesh_io.hpp"
#include "softkin/solver/fk/model.hpp"
#include "softkin/solver/remesh/remesh.hpp"
#include "softkin/solver/robots/robot_twisting.hpp"
#include "softkin/solver/common/stopwatch.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <memory>

namespace softkin {

namespace {

/// The chamber tets of `mesh` alone (same vertex array), for writing the chamber surface.
Mesh ChamberPart(const Mesh& mesh, const std::vector<int>& regions) {
  Mesh m;
  m.vertices = mesh.vertices;
  for (const auto& e : mesh.elements)
    if (std::find(regions.begin(), regions.end(), e.region) != regions.end())
      m.elements.push_back(e);
  return m;
}

std::string Tag(const std::string& variant, double alpha) {
  char buf[64];
  std::snprintf(buf, sizeof buf, "%s_a%g", variant.c_str(), alpha);
  return buf;
}

/// The keys of a twisting_remesh config, checked against the robot.
struct TwistingRemeshParams {
  std::string robot;
  int res = 1;
  std::vector<double> alphas;  ///< increasing chamber volume ratios; the last is the target
  double at_once = 28;         ///< the ratio applied at once, without remeshing
  double alpha_max = 4.0, d_max = 4.0;
  int sections = 20;  ///< of the twist profile
  bool write_vtu = true;
  Scene scene;
  double build_s = 0;       ///< the robot's generation, s
  ProgressiveOptions popt;  ///< Algorithm 2's options (no on_step)
  std::vector<int> chamber_regions;
};

TwistingRemeshParams ReadTwistingRemeshParams(const Config& cfg) {
  TwistingRemeshParams p;
  p.robot = cfg.String("robot", "twisting_robot");
  p.res = cfg.Int("res", 1);
  p.alphas = cfg.NumberList("alphas", {5, 28, 115});
  p.at_once = cfg.Number("at_once_alpha", 28);
  p.alpha_max = cfg.Number("alpha_max", 4.0);
  p.d_max = cfg.Number("d_max", 4.0);
  const double step = cfg.Number("step", 0.0);
  const std::string method_name = cfg.String("remesh_method", "auto");
  const std::string rest_name = cfg.String("chamber_rest", "remeshed");
  const int remesh_iterations = cfg.Int("remesh_iterations", 3);
  const int max_remeshes = cfg.Int("max_remeshes_per_step", 2);
  p.sections = cfg.Int("sections", 20);
  p.write_vtu = cfg.Bool("vtu", true);
  if (p.robot != "twisting_robot")
    cfg.Fail("robot",
             "twisting_robot (the twist is measured about its z axis over its 100 mm length)");
  const auto t_build0 = std::chrono::steady_clock::now();
  p.scene = ConfigRobot(cfg, p.robot, p.res);
  p.build_s = SecondsSince(t_build0);
  p.scene.solver = cfg.Solver(p.scene.solver);
  cfg.CheckNoUnknownKeys();
  const std::vector<double>& alphas = p.alphas;
  if (alphas.empty()) cfg.Fail("alphas", "a non-empty list of chamber volume ratios > 1");
  for (size_t i = 0; i < alphas.size(); ++i)
    if (!(alphas[i] > 1) || (i > 0 && !(alphas[i] > alphas[i - 1])))
      cfg.Fail("alphas", "increasing chamber volume ratios > 1");
  const Actuator& act = p.scene.actuators.at(ChamberActuator(p.scene));
  if (alphas.back() > act.max)
    cfg.Fail("alphas", "ratios up to the chamber's maximum " + std::to_string(act.max));
  if (!(p.at_once > 1) || p.at_once > act.max)
    cfg.Fail("at_once_alpha", "a chamber volume ratio in (1, max]");
  if (p.sections < 2 || p.sections > 100) cfg.Fail("sections", "an integer in [2, 100]");
  if (remesh_iterations < 1) cfg.Fail("remesh_iterations", "an integer >= 1");
  if (max_remeshes < 1) cfg.Fail("max_remeshes_per_step", "an integer >= 1");
  ProgressiveOptions& popt = p.popt;
  popt.criteria = {p.alpha_max, p.d_max};
  popt.step = step;
  popt.max_remeshes_per_step = max_remeshes;
  if (!RemeshMethodFromString(method_name, &popt.remesh_options.method))
    cfg.Fail("remesh_method", "auto, chamber or whole");
  if (!ChamberRestFromString(rest_name, &popt.remesh_options.rest))
    cfg.Fail("chamber_rest", "remeshed or original");
  popt.remesh_options.region.iterations = remesh_iterations;
  popt.remesh_options.region.seed = cfg.seed();
  popt.remesh_options.tessellation =
      TwistingRobotTessellation(p.res, cfg.NumberMap("robot_params"));
  popt.remesh_options.tessellation.seed = cfg.seed();
  popt.snapshots.assign(alphas.begin(), alphas.end() - 1);
  std::string why;
  if (!popt.IsValid(&why)) cfg.Fail(why.substr(0, why.find(':')), why);
  p.chamber_regions = act.regions;
  return p;
}

std::string Fmt(double v) {
  char b[32];
  std::snprintf(b, sizeof b, "%.9g", v);
  return std::string(b);
}

/// The experiment's outputs: steps.csv, twist_profile.csv, shapes.csv, the shapes' OBJ and VTU
/// files (shapes/) and the VTU frames of the progressive run.
class TwistingOutput {
 public:
  TwistingOutput(const TwistingRemeshParams& p, const std::string& dir, bool verbose)
      : p_(p),
        dir_(dir),
        verbose_(verbose),
        steps_csv_(
            dir + "/steps.csv",
            {"variant", "k", "alpha", "remeshes", "methods", "remesh_failures", "tets",
             "chamber_tets", "mesh_s", "solver_s", "iterations", "status", "chamber_volume_ratio",
             "max_volume_ratio", "max_distortion", "tip_twist_deg", "tip_x", "tip_y", "tip_z"}),
        profile_csv_(dir + "/twist_profile.csv", {"variant", "alpha", "section", "z", "twist_deg"}),
        shapes_csv_(dir + "/shapes.csv",
                    {"variant", "alpha", "tip_twist_deg", "chamber_volume_ratio", "remeshes",
                     "tets", "inverted_tets", "mesh_s", "solver_s", "tip_x", "tip_y", "tip_z",
                     "outer_obj", "chamber_obj", "vtu"}),
        tip_(p.scene.marker_index("tip")) {}

  /// Writes one shape: surfaces (outer, chamber) as OBJ for the figure, the mesh as VTU, a row of
  /// shapes.csv and the twist profile; returns its summary entry.
  nlohmann::json RecordShape(const std::string& variant, double alpha, const Scene& s,
                             const Eigen::MatrixX3d& X, double volume_ratio, int remeshes,
                             double mesh_s, double solver_s) {
    const int sections = p_.sections, tip = tip_;
    const std::string tag = Tag(variant, alpha);
    const std::vector<double> prof = Twist(s, X);
    for (int i = 0; i < sections; ++i)
      profile_csv_.RowStrings({variant, Fmt(alpha), std::to_string(i),
                               Fmt(kTwistLength * (i + 1) / sections), Fmt(prof[i])});
    const std::string outer = "shapes/" + tag + "_outer.obj",
                      chamber = "shapes/" + tag + "_chamber.obj";
    WriteSurfaceObj(dir_ + "/" + outer, s.mesh, X);
    WriteSurfaceObj(dir_ + "/" + chamber, ChamberPart(s.mesh, p_.chamber_regions), X);
    std::string vtu;
    if (p_.write_vtu) {
      vtu = "shapes/" + tag + ".vtu";
      WriteVtu(dir_ + "/" + vtu, s.mesh, X, s.region_rest.regions, &s.region_rest.positions);
      if (variant == "progressive") frames_.emplace_back(alpha, vtu);
    }
    const Eigen::MatrixX3d P = s.marker_positions(X);
    const int inverted = CountInvertedElements(s.mesh, X);
    shapes_csv_.RowStrings({variant, Fmt(alpha), Fmt(prof.back()), Fmt(volume_ratio),
                            std::to_string(remeshes), std::to_string(s.mesh.num_tets()),
                            std::to_string(inverted), Fmt(mesh_s), Fmt(solver_s), Fmt(P(tip, 0)),
                            Fmt(P(tip, 1)), Fmt(P(tip, 2)), outer, chamber, vtu});
    return nlohmann::json{{"alpha", alpha},
                          {"tip_twist_deg", prof.back()},
                          {"chamber_volume_ratio", volume_ratio},
                          {"remeshes", remeshes},
                          {"tets", s.mesh.num_tets()},
                          {"inverted_tets", inverted},
                          {"mesh_seconds", mesh_s},
                          {"solver_seconds", solver_s},
                          {"tip", {P(tip, 0), P(tip, 1), P(tip, 2)}}};
  }

  /// A row of steps.csv (and a progress line) for one step of a variant.
  void LogStep(const std::string& variant, const ProgressiveStep& st, const Scene& s,
               const Eigen::MatrixX3d& X) {
    const int tip = tip_;
    const std::vector<double> prof = Twist(s, X);
    const Eigen::MatrixX3d P = s.marker_positions(X);
    steps_csv_.RowStrings(
        {variant, std::to_string(st.k), Fmt(st.alpha), std::to_string(st.remeshes), st.methods,
         std::to_string(st.remesh_failures), std::to_string(st.tets),
         std::to_string(st.chamber_tets), Fmt(st.mesh_seconds), Fmt(st.solver_seconds),
         std::to_string(st.iterations), FkStatusToString(st.status), Fmt(st.chamber_volume_ratio),
         Fmt(st.max_volume_ratio), Fmt(st.max_distortion), Fmt(prof.back()), Fmt(P(tip, 0)),
         Fmt(P(tip, 1)), Fmt(P(tip, 2))});
    if (verbose_)
      std::fprintf(stderr,
                   "  %s alpha %g: %s, %d iterations, %.1f s; %d remesh(es)%s%s, %d tets; chamber "
                   "x%.2f, tip twist %.1f deg\n",
                   variant.c_str(), st.alpha, FkStatusToString(st.status), st.iterations,
                   st.solver_seconds, st.remeshes, st.methods.empty() ? "" : " ",
                   st.methods.c_str(), st.tets, st.chamber_volume_ratio, prof.back());
  }

  /// progressive.pvd over the progressive shapes' VTU files, if any.
  void WriteFrames() const {
    if (!frames_.empty()) WritePvd(dir_ + "/progressive.pvd", frames_);
  }

 private:
  std::vector<double> Twist(const Scene& s, const Eigen::MatrixX3d& X) const {
    return TwistProfileDegrees(s, X, kTwistLength, p_.sections);
  }

  const TwistingRemeshParams& p_;
  std::string dir_;
  bool verbose_;
  CsvWriter steps_csv_, profile_csv_, shapes_csv_;
  int tip_;
  std::vector<std::pair<double, std::string>> frames_;
};

/// The progressive run's shapes at its snapshots and at the end (if it got there), with the
/// remeshes and times up to each.
nlohmann::json ProgressiveShapes(const TwistingRemeshParams& p, const ProgressiveResult& prog,
                                 TwistingOutput* out) {
  nlohmann::json shapes = nlohmann::json::array();
  // Cumulative counts up to each snapshot.
  auto upto = [&](double alpha, auto field) {
    double v = 0;
    for (const auto& st : prog.steps)
      if (st.alpha <= alpha + 1e-12) v += field(st);
    return v;
  };
  auto add = [&](double alpha, const Scene& s, const Eigen::MatrixX3d& X, double ratio) {
    shapes.push_back(
        out->RecordShape("progressive", alpha, s, X, ratio,
                         static_cast<int>(upto(
                             alpha, [](const ProgressiveStep& st) { return double(st.remeshes); })),
                         upto(alpha, [](const ProgressiveStep& st) { return st.mesh_seconds; }),
                         upto(alpha, [](const ProgressiveStep& st) { return st.solver_seconds; })));
  };
  for (const auto& snap : prog.snapshots)
    add(snap.alpha, snap.scene, snap.positions, snap.chamber_volume_ratio);
  if (prog.completed) add(p.alphas.back(), prog.scene, prog.positions, prog.chamber_volume_ratio);
  return shapes;
}

/// at_once_alpha applied at once on the initial mesh, without remeshing.
nlohmann::json SolveAtOnce(const TwistingRemeshParams& p, TwistingOutput* out) {
  const Scene& scene = p.scene;
  const std::vector<int>& chamber_regions = p.chamber_regions;
  auto model = std::make_shared<const Model>(scene);
  auto solver = MakeFkSolver(model, scene.solver);
  Eigen::VectorXd c = scene.rest_actuation();
  c[ChamberActuator(scene)] = p.at_once;
  const FkResult r = solver->Solve(c);
  if (r.status == FkStatus::InvalidInput) throw std::runtime_error("at_once_alpha: " + r.message);
  const double ratio = RegionVolume(scene.mesh, r.positions, chamber_regions) /
                       RegionVolume(scene.mesh, scene.mesh.vertices, chamber_regions);
  nlohmann::json once =
      out->RecordShape("at_once", p.at_once, scene, r.positions, ratio, 0, 0.0, r.time_s);
  once["status"] = FkStatusToString(r.status);
  once["iterations"] = r.iterations;
  ProgressiveStep st;
  st.k = 1;
  st.alpha = p.at_once;
  st.tets = scene.mesh.num_tets();
  st.solver_seconds = r.time_s;
  st.iterations = r.iterations;
  st.status = r.status;
  st.chamber_volume_ratio = ratio;
  const RemeshCheck chk =
      CheckRemesh(scene.mesh, scene.mesh.vertices, r.positions, chamber_regions, p.popt.criteria);
  st.max_volume_ratio = chk.max_volume_ratio;
  st.max_distortion = chk.max_distortion;
  for (const auto& e : scene.mesh.elements)
    if (std::find(chamber_regions.begin(), chamber_regions.end(), e.region) !=
        chamber_regions.end())
      ++st.chamber_tets;
  out->LogStep("at_once", st, scene, r.positions);
  return once;
}

/// The progressive run's summary, with its remeshes split into whole-body and chamber-only ones.
nlohmann::json ProgressiveJson(const ProgressiveResult& prog, const nlohmann::json& shapes) {
  int whole = 0, chamber_only = 0;
  for (const auto& st : prog.steps) {
    for (size_t p = 0; p < st.methods.size();) {
      const size_t q = std::min(st.methods.find('+', p), st.methods.size());
      const std::string m = st.methods.substr(p, q - p);
      (m == "whole" ? whole : chamber_only)++;
      p = q + 1;
    }
  }
  return {{"status", FkStatusToString(prog.status)},
          {"completed", prog.completed},
          {"message", prog.message},
          {"steps", prog.steps.size()},
          {"remeshes", prog.remeshes},
          {"remesh_failures", prog.remesh_failures},
          {"first_remesh_failure", prog.first_remesh_failure},
          {"remeshes_whole", whole},
          {"remeshes_chamber_only", chamber_only},
          {"final_tets", prog.scene.mesh.num_tets()},
          {"chamber_volume_ratio", prog.chamber_volume_ratio},
          {"mesh_seconds", prog.mesh_seconds},
          {"solver_seconds", prog.solver_seconds},
          {"mesh_seconds_per_remesh", prog.remeshes > 0 ? prog.mesh_seconds / prog.remeshes : 0.0},
          {"solver_seconds_per_step",
           prog.steps.empty() ? 0.0 : prog.solver_seconds / prog.steps.size()},
          {"shapes", shapes}};
}

}  // namespace

nlohmann::json RunTwistingRemesh(const Config& cfg, const std::string& dir, bool verbose) {
  const TwistingRemeshParams p = ReadTwistingRemeshParams(cfg);
  if (cfg.check_only()) return {};  // only the settings were asked for (Config::check_only)
  std::filesystem::create_directories(dir + "/shapes");
  TwistingOutput out(p, dir, verbose);

  // ---- progressive, with remeshing ----
  ProgressiveOptions popt = p.popt;
  popt.on_step = [&out](const ProgressiveStep& st, const Scene& s, const Eigen::MatrixX3d& X) {
    out.LogStep("progressive", st, s, X);
  };
  const ProgressiveResult prog = SolveProgressive(p.scene, p.alphas.back(), popt);
  if (verbose) std::fprintf(stderr, "  progressive: %s\n", prog.BriefReport().c_str());
  const nlohmann::json prog_shapes = ProgressiveShapes(p, prog, &out);
  out.WriteFrames();

  // ---- at once, no remeshing ----
  const nlohmann::json once = SolveAtOnce(p, &out);

  nlohmann::json j;
  j["robot"] = p.robot;
  j["res"] = p.res;
  j["initial_tets"] = p.scene.mesh.num_tets();
  j["robot_build_seconds"] = p.build_s;
  j["alpha_max"] = p.alpha_max;
  j["d_max"] = p.d_max;
  j["chamber_rest"] = ChamberRestToString(p.popt.remesh_options.rest);
  j["progressive"] = ProgressiveJson(prog, prog_shapes);
  j["at_once"] = once;
  j["thesis_table_3_1_twisting"] = {{"tets", 28198},
                                    {"mesh_gen_s", 2.81},
                                    {"collision_check_s", 0.03},
                                    {"collision_response_s", 1.71},
                                    {"solver_s", 3.54}};
  return j;
}

}  // namespace softkin
