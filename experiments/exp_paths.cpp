// Fig. 2.12: actuators of one robot driven alone and together, with the tip trajectory of each.
#include "softkin/experiments/results.hpp"
#include "softkin/experiments/runner.hpp"
#include "softkin/solver/factory/fk_factory.hpp"
#include "softkin/solver/fk/fk_solver.hpp"
#include "softkin/solver/robots/robots.hpp"

#include <cstdio>
#include <sstream>

namespace softkin {

namespace {

/// The keys of an actuation_paths config, checked against the robot.
struct ActuationPathsParams {
  std::string robot;
  // Each path is "a+b+...": those actuators move together from their rest value to end_value,
  // the others stay at rest. Every path starts from the rest shape.
  std::vector<std::string> paths;
  std::vector<std::vector<int>> groups;  ///< the actuators of each path
  int steps = 8;
  double end_value = 0;  ///< 0: each actuator's far end
  Scene scene;
  FkOptions opts;
  int tip = -1;
};

ActuationPathsParams ReadActuationPathsParams(const Config& cfg) {
  ActuationPathsParams p;
  p.robot = cfg.String("robot", "three_chamber");
  const int res = cfg.Int("res", 0);
  p.paths = cfg.StringList("paths", {});
  p.steps = cfg.Int("steps", 8);
  p.end_value = cfg.Number("end_value", 0.0);
  p.scene = ConfigRobot(cfg, p.robot, res);
  p.opts = cfg.Solver(p.scene.solver);
  cfg.CheckNoUnknownKeys();
  if (p.paths.empty()) cfg.Fail("paths", "a non-empty array of \"a+b+...\" actuator groups");
  if (p.steps < 1) cfg.Fail("steps", "an integer >= 1");
  p.tip = p.scene.marker_index("tip");
  if (p.tip < 0) throw std::invalid_argument("robot '" + p.robot + "' has no 'tip' marker");
  for (const std::string& path : p.paths) {
    std::vector<int> g;
    std::stringstream ss(path);
    std::string name;
    while (std::getline(ss, name, '+')) {
      const int a = p.scene.actuator_index(name);
      if (a < 0)
        cfg.Fail("paths",
                 "groups of actuator names of robot '" + p.robot + "', got '" + path + "'");
      g.push_back(a);
    }
    if (g.empty()) cfg.Fail("paths", "non-empty actuator groups");
    for (int a : g) {
      const Actuator& act = p.scene.actuators[a];
      if (p.end_value > 0 && (p.end_value < act.min || p.end_value > act.max))
        cfg.Fail("end_value", "a value inside the range of actuator '" + act.name + "'");
    }
    p.groups.push_back(g);
  }
  return p;
}

/// Drives path k from rest in `steps` warm-started steps: rows of paths.csv and its entry.
nlohmann::json SweepPath(const ActuationPathsParams& p, size_t k, FkSolver& solver, CsvWriter* csv,
                         int* failures, double* total_s, bool verbose) {
  const Scene& scene = p.scene;
  const std::vector<int>& group = p.groups[k];
  const std::string& path = p.paths[k];
  const int tip = p.tip, steps = p.steps;
  // Each actuator of the group goes from its rest value to end_value (default: its far end).
  auto end_of = [&](int a) { return p.end_value > 0 ? p.end_value : scene.actuators[a].FarEnd(); };
  const Actuator& first = scene.actuators[group[0]];
  const double v_end = end_of(group[0]);
  const Eigen::MatrixX3d rest_tips = scene.marker_positions(scene.mesh.vertices);
  csv->RowStrings({path, "0", std::to_string(first.rest), std::to_string(rest_tips(tip, 0)),
                   std::to_string(rest_tips(tip, 1)), std::to_string(rest_tips(tip, 2)), "0", "0",
                   "1"});
  Eigen::VectorXd c = scene.rest_actuation();
  Eigen::MatrixX3d X = scene.mesh.vertices, X_prev = X, guess;
  double path_s = 0;
  int path_iters = 0;
  nlohmann::json tips = nlohmann::json::array();
  for (int s = 1; s <= steps; ++s) {
    for (int a : group) {
      const Actuator& act = scene.actuators[a];
      c[a] = act.rest + (end_of(a) - act.rest) * double(s) / steps;
    }
    guess = s > 1 ? Eigen::MatrixX3d(2.0 * X - X_prev) : X;  // secant predictor
    const FkResult r = solver.Solve(c, &guess);
    if (r.status == FkStatus::InvalidInput) throw std::runtime_error(r.message);
    X_prev = X;
    X = r.positions;
    const bool ok = r.status == FkStatus::Converged;
    *failures += !ok;
    path_s += r.time_s;
    path_iters += r.iterations;
    const Eigen::MatrixX3d P = scene.marker_positions(X);
    tips.push_back({P(tip, 0), P(tip, 1), P(tip, 2)});
    csv->RowStrings({path, std::to_string(s), std::to_string(c[group[0]]),
                     std::to_string(P(tip, 0)), std::to_string(P(tip, 1)),
                     std::to_string(P(tip, 2)), std::to_string(r.iterations),
                     std::to_string(r.time_s), ok ? "1" : "0"});
    if (verbose)
      std::fprintf(stderr, "  [%s %d/%d] %s\n", path.c_str(), s, steps, r.BriefReport().c_str());
  }
  *total_s += path_s;
  return {{"path", path},
          {"end_value", v_end},
          {"tips", tips},
          {"solve_s", path_s},
          {"iterations", path_iters}};
}

}  // namespace

nlohmann::json RunActuationPaths(const Config& cfg, const std::string& dir, bool verbose) {
  const ActuationPathsParams p = ReadActuationPathsParams(cfg);
  if (cfg.check_only()) return {};  // only the settings were asked for (Config::check_only)
  const Scene& scene = p.scene;
  const int tip = p.tip;
  auto model = std::make_shared<const Model>(scene);
  auto solver = MakeFkSolver(model, p.opts);
  CsvWriter csv(dir + "/paths.csv", {"path", "step", "value", "tip_x", "tip_y", "tip_z",
                                     "iterations", "time_s", "converged"});
  const Eigen::MatrixX3d rest_tips = scene.marker_positions(scene.mesh.vertices);
  nlohmann::json rows = nlohmann::json::array();
  int failures = 0;
  double total_s = 0;
  for (size_t k = 0; k < p.groups.size(); ++k)
    rows.push_back(SweepPath(p, k, *solver, &csv, &failures, &total_s, verbose));
  nlohmann::json j;
  j["robot"] = p.robot;
  j["n_tets"] = scene.mesh.num_tets();
  j["n_vertices"] = scene.mesh.num_vertices();
  j["paths"] = rows;
  j["rest_tip"] = {rest_tips(tip, 0), rest_tips(tip, 1), rest_tips(tip, 2)};
  j["total_solve_s"] = total_s;
  j["non_converged_steps"] = failures;
  return j;
}

}  // namespace softkin
