// Fig. 2.11 / Table 2.2: bend the pneumatic finger through its range, warm-started along the sweep.
#include "softkin/experiments/fem_trajectory.hpp"
#include "softkin/experiments/measure.hpp"
#include "softkin/experiments/results.hpp"
#include "softkin/experiments/runner.hpp"
#include "softkin/solver/factory/fk_factory.hpp"
#include "softkin/solver/fk/fk_solver.hpp"
#include "softkin/solver/mesh/io/mesh_io.hpp"
#include "softkin/solver/baselines/calculix_pressure.hpp"
#include "softkin/solver/robots/robots.hpp"
#include "softkin/solver/common/stopwatch.hpp"

#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <memory>
#include <iostream>

namespace softkin {

namespace {

/// The keys of a pneumatic_bending config, checked against the robot.
struct BendingParams {
  std::string robot;
  int steps = 40;
  int vtu_every = 0;
  // Secant predictor: start each step from X_k + (X_k - X_{k-1}) (equal actuation steps) instead
  // of X_k. It is a better first guess along a smooth sweep; the solution is the same.
  bool predictor = true;
  // Actuation spacing: "linear" (equal steps) or "geometric" (equal ratios, so smaller steps at
  // the start, where the bend angle grows fastest with the volume ratio).
  std::string spacing = "linear";
  std::vector<double> milestones;  ///< bend angles whose times are reported, degrees
  Scene scene;
  double robot_build_s = 0;  ///< the robot's generation, s
  FkOptions opts;
  // The swept actuators ("actuators": [names], or "actuator": name; default the first one), all
  // set to the same value, from their common rest value to "end_value" (default: the end of their
  // range away from rest, e.g. the max volume ratio or the min cable shortening ratio).
  std::vector<int> swept;
  double vmax = 0;
  bool has_bend = false;  ///< the robot has tip_top / tip_bottom markers
  int tip = -1;
  // The pressure FEM beside the sweep (Fig. 2.11's FEM 1 / FEM 2): one ramp per law in
  // "fem_laws" (none by default) to "fem_pressure_mpa" on the swept chambers.
  std::vector<std::string> fem_laws;
  double fem_pressure = 0;
  PressureFemOptions fem;
};

/// The swept actuators, checked to share their rest value and range.
std::vector<int> SweptActuators(const Config& cfg, const Scene& scene, const std::string& robot,
                                const std::string& act_name,
                                const std::vector<std::string>& act_names) {
  if (!act_name.empty() && !act_names.empty())
    cfg.Fail("actuators", "either 'actuator' or 'actuators', not both");
  std::vector<int> swept;
  for (const std::string& n : act_names.empty() ? std::vector<std::string>{act_name} : act_names) {
    const int i = n.empty() ? 0 : scene.actuator_index(n);
    if (i < 0) {
      std::string known;
      for (const auto& act : scene.actuators) known += (known.empty() ? "" : ", ") + act.name;
      cfg.Fail(act_names.empty() ? "actuator" : "actuators",
               "names of actuators of robot '" + robot + "' (" + known + ")");
    }
    swept.push_back(i);
  }
  const Actuator& act = scene.actuators[swept[0]];
  for (int i : swept)
    if (scene.actuators[i].rest != act.rest || scene.actuators[i].min != act.min ||
        scene.actuators[i].max != act.max)
      cfg.Fail("actuators", "actuators with the same rest value and range");
  return swept;
}

BendingParams ReadBendingParams(const Config& cfg) {
  BendingParams p;
  p.robot = cfg.String("robot", "pneumatic_finger");
  const int res = cfg.Int("res", 0);
  const std::string act_name = cfg.String("actuator", "");
  const std::vector<std::string> act_names = cfg.StringList("actuators", {});
  p.steps = cfg.Int("steps", 40);
  const double end_value_cfg = cfg.Number("end_value", 0.0);
  p.vtu_every = cfg.Int("vtu_every", 0);
  p.predictor = cfg.Bool("predictor", true);
  p.spacing = cfg.String("spacing", "linear");
  p.milestones = cfg.NumberList("milestones_deg", {});
  const auto t_build0 = std::chrono::steady_clock::now();
  p.scene = ConfigRobot(cfg, p.robot, res);
  p.robot_build_s = SecondsSince(t_build0);
  p.opts = cfg.Solver(p.scene.solver);
  p.fem_laws = cfg.StringList("fem_laws", {});
  if (!p.fem_laws.empty()) {
    p.fem = ReadPressureFemOptions(cfg, 0.05, 0.0);
    p.fem_pressure = cfg.Number("fem_pressure_mpa", 0.0);
  }
  cfg.CheckNoUnknownKeys();
  if (p.steps < 1) cfg.Fail("steps", "an integer >= 1");
  if (p.spacing != "linear" && p.spacing != "geometric") cfg.Fail("spacing", "linear or geometric");
  if (p.vtu_every < 0) cfg.Fail("vtu_every", "an integer >= 0");
  p.swept = SweptActuators(cfg, p.scene, p.robot, act_name, act_names);
  const Actuator& act = p.scene.actuators[p.swept[0]];
  p.vmax = end_value_cfg > 0 ? end_value_cfg : act.FarEnd();
  if (p.vmax > act.max || p.vmax < act.min || p.vmax == act.rest)
    cfg.Fail("end_value",
             "a value in [min, max] of actuator '" + act.name + "', not its rest value");
  // The bend angle needs the tip_top / tip_bottom markers; without them it is not reported.
  p.has_bend = p.scene.marker_index("tip_top") >= 0 && p.scene.marker_index("tip_bottom") >= 0;
  if (!p.has_bend && !p.milestones.empty())
    cfg.Fail("milestones_deg",
             "no milestones: robot '" + p.robot +
                 "' has no tip_top / tip_bottom markers, so no bend angle is measured");
  if (p.has_bend && p.milestones.empty()) p.milestones = {90, 180, 240};
  p.tip = p.scene.marker_index("tip");
  if (p.tip < 0) throw std::invalid_argument("robot '" + p.robot + "' has no 'tip' marker");
  if (p.spacing == "geometric" && !(act.rest > 0))
    cfg.Fail("spacing", "linear (geometric spacing needs a positive rest value)");
  if (!p.fem_laws.empty()) {
    for (size_t i = 0; i < p.fem_laws.size(); ++i)
      CheckFemLaw(cfg, "fem_laws[" + std::to_string(i) + "]", p.fem_laws[i]);
    if (!(p.fem_pressure > 0)) cfg.Fail("fem_pressure_mpa", "the FEM's end pressure, MPa > 0");
    if (act.type != ActuatorType::Pneumatic || act.is_signed())
      cfg.Fail("fem_laws", "no FEM: the swept actuators are not unsigned pneumatic chambers");
    CheckPressureFemCanRun(cfg, "fem_laws", p.scene, p.fem.element);
  }
  return p;
}

/// What the sweep measured.
struct BendingSweep {
  double cumulative = 0.0, max_bend = 0.0;          ///< max_bend: over the converged steps
  int total_iters = 0, failures = 0, inverted = 0;  ///< inverted: steps ended `inverted`
  std::vector<double> reach;  ///< solve time to each milestone (at a converged step), -1: none
  nlohmann::json tips = nlohmann::json::array(), step_times = nlohmann::json::array();
};

/// Bends the robot through `steps` warm-started steps: rows of trajectory.csv, VTU frames.
BendingSweep Sweep(const BendingParams& p, const std::shared_ptr<const Model>& model,
                   const std::string& dir, bool verbose) {
  const Scene& scene = p.scene;
  const int steps = p.steps, tip = p.tip, a = p.swept[0];
  const Actuator& act = scene.actuators[a];
  auto solver = MakeFkSolver(model, p.opts);
  std::unique_ptr<BendAngle> bend;
  if (p.has_bend) bend = std::make_unique<BendAngle>(scene);
  CsvWriter csv(dir + "/trajectory.csv",
                {"step", "actuation", "bend_deg", "tip_x", "tip_y", "tip_z", "iterations", "time_s",
                 "cumulative_s", "energy", "volume_ratio", "residual_ratio", "converged",
                 "inverted_elements"});
  std::vector<std::pair<double, std::string>> frames;
  if (p.vtu_every > 0) std::filesystem::create_directories(dir + "/frames");
  const Eigen::MatrixX3d rest_tip = scene.marker_positions(scene.mesh.vertices);
  csv.Row({0, act.rest, 0.0, rest_tip(tip, 0), rest_tip(tip, 1), rest_tip(tip, 2), 0, 0, 0, 0, 1.0,
           0, 1, 0});

  Eigen::VectorXd c = scene.rest_actuation();
  Eigen::MatrixX3d X = scene.mesh.vertices, X_prev = X, guess;
  BendingSweep b;
  b.reach.assign(p.milestones.size(), -1.0);
  auto value = [&](int s) {
    const double t = double(s) / steps;
    return p.spacing == "geometric" ? act.rest * std::pow(p.vmax / act.rest, t)
                                    : act.rest + (p.vmax - act.rest) * t;
  };
  for (int s = 1; s <= steps; ++s) {
    for (int i : p.swept) c[i] = value(s);
    // Secant predictor, scaled by the ratio of this step to the previous one.
    const double q = s > 1 ? (value(s) - value(s - 1)) / (value(s - 1) - value(s - 2)) : 0.0;
    guess = (p.predictor && s > 1) ? Eigen::MatrixX3d(X + q * (X - X_prev)) : X;
    FkResult r = solver->Solve(c, &guess);
    if (r.status == FkStatus::InvalidInput) throw std::runtime_error(r.message);
    X_prev = X;
    X = r.positions;
    b.cumulative += r.time_s;
    b.total_iters += r.iterations;
    const bool ok = r.status == FkStatus::Converged;
    if (!ok) ++b.failures;
    b.inverted += r.status == FkStatus::Inverted;
    const double ang = p.has_bend ? (*bend)(X) : 0.0;
    if (ok) b.max_bend = std::max(b.max_bend, ang);  // of the converged steps
    // A milestone counts at a converged step only (not at one with inverted elements).
    for (size_t m = 0; m < p.milestones.size(); ++m)
      if (ok && b.reach[m] < 0 && ang >= p.milestones[m]) b.reach[m] = b.cumulative;
    const Eigen::MatrixX3d P = scene.marker_positions(X);
    b.tips.push_back({P(tip, 0), P(tip, 1), P(tip, 2)});
    b.step_times.push_back(r.time_s);
    csv.Row({double(s), c[a], ang, P(tip, 0), P(tip, 1), P(tip, 2), double(r.iterations), r.time_s,
             b.cumulative, r.energy, r.volume_ratios[a], r.gradient_ratio, ok ? 1.0 : 0.0,
             double(r.inverted_elements)});
    if (p.vtu_every > 0 && (s % p.vtu_every == 0 || s == steps)) {
      char name[64];
      std::snprintf(name, sizeof(name), "frames/step_%04d.vtu", s);
      const VtuSolveInfo info{ok, r.iterations, r.gradient_ratio, r.inverted_elements};
      WriteVtu(dir + "/" + name, scene.mesh, X, {}, nullptr, &info);
      frames.emplace_back(c[a], name);
    }
    if (verbose) {
      char bend_txt[40] = "";
      if (p.has_bend) std::snprintf(bend_txt, sizeof(bend_txt), "bend %.1f deg  ", ang);
      std::fprintf(stderr, "  [%d/%d] %s = %.3f  %s%s\n", s, steps, act.name.c_str(), c[a],
                   bend_txt, r.BriefReport().c_str());
    }
  }
  if (!frames.empty()) WritePvd(dir + "/frames.pvd", frames);
  return b;
}

/// The pressure FEM's ramps, one per law, beside the sweep (fem_trajectory.csv); null if none
/// was asked for. A FEM that cannot run (no ccx) is reported with its message, not fatal.
nlohmann::json RunFem(const BendingParams& p, const Model& model, const std::string& dir,
                      bool verbose) {
  if (p.fem_laws.empty()) return nullptr;
  CsvWriter csv(dir + "/fem_trajectory.csv", FemTrajectoryColumns());
  Eigen::VectorXd pressure = Eigen::VectorXd::Zero(p.scene.num_actuators());
  for (int i : p.swept) pressure[i] = p.fem_pressure;
  nlohmann::json j = {{"element", p.fem.element},
                      {"young_mpa", p.fem.young},
                      {"poisson", p.fem.poisson},
                      {"pressure_mpa", p.fem_pressure},
                      {"max_increment", p.fem.max_increment}};
  for (const std::string& law : p.fem_laws) {
    PressureFemOptions o = p.fem;
    o.law = law;
    if (verbose)
      std::fprintf(stderr, "  FEM (%s, %s, pressure ramp to %g MPa) ...\n", law.c_str(),
                   o.element.c_str(), p.fem_pressure);
    const FemTrajectory t = RunFemTrajectory(p.scene, model, pressure, p.swept[0], o);
    AppendFemRows(t, &csv);
    j[law] = FemTrajectorySummary(t, p.milestones);
    if (verbose)
      std::fprintf(stderr, "  FEM (%s): %zu increments, %.1f s, bend %.1f deg%s%s\n", law.c_str(),
                   t.run.increments.size(), t.run.time_s, t.max_bend_deg,
                   t.run.message.empty() ? "" : "; ", t.run.message.c_str());
  }
  return j;
}

}  // namespace

nlohmann::json RunPneumaticBending(const Config& cfg, const std::string& dir, bool verbose) {
  const BendingParams p = ReadBendingParams(cfg);
  if (cfg.check_only()) return {};  // only the settings were asked for (Config::check_only)
  const Scene& scene = p.scene;
  const auto t_model0 = std::chrono::steady_clock::now();
  auto model = std::make_shared<const Model>(scene);
  const double build_s = p.robot_build_s + SecondsSince(t_model0);
  const BendingSweep b = Sweep(p, model, dir, verbose);
  const nlohmann::json fem = RunFem(p, *model, dir, verbose);

  nlohmann::json j;
  j["robot"] = p.robot;
  j["n_vertices"] = scene.mesh.num_vertices();
  j["n_elements"] = scene.mesh.num_elements();
  j["n_tets"] = scene.mesh.num_tets();
  j["steps"] = p.steps;
  j["actuators"] = nlohmann::json::array();
  for (int i : p.swept) j["actuators"].push_back(scene.actuators[i].name);
  j["end_value"] = p.vmax;
  j["bend_measured"] = p.has_bend;
  j["max_bend_deg"] = b.max_bend;
  j["total_solve_s"] = b.cumulative;
  j["total_iterations"] = b.total_iters;
  j["model_build_s"] = build_s;
  j["factor_s"] = model->factor_time_s();
  j["non_converged_steps"] = b.failures;
  j["inverted_steps"] = b.inverted;
  j["solver"] = ToString(p.opts.solver);
  j["anderson_window"] = p.opts.anderson_window;
  j["predictor"] = p.predictor;
  j["spacing"] = p.spacing;
  for (size_t q = 0; q < p.milestones.size(); ++q) {
    char key[32];
    std::snprintf(key, sizeof(key), "t%.0f_s", p.milestones[q]);
    j[key] = b.reach[q] >= 0 ? nlohmann::json(b.reach[q]) : nlohmann::json(nullptr);
  }
  j["tips"] = b.tips;
  j["step_times_s"] = b.step_times;
  if (!fem.is_null()) j["fem"] = fem;
  if (p.robot == "pneumatic_finger")
    j["thesis_table_2_2"] = {
        {"t90_s", 8.5}, {"t180_s", 15.2}, {"t240_s", 23.2}, {"elements", 45802}};
  return j;
}

}  // namespace softkin
