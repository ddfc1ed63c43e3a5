// Fig. 2.12: actuators of one robot driven alone and together, with the tip trajectory of each.
#include "softkin/experiments/results.hpp"
#include "softkin/experiments/runner.hpp"
#include "softkin/solver/factory/fk_factory.hpp"
#include "softkin/solver/fk/fk_solver.hpp"
#include "softkin/solver/robots/robots.hpp"

#include <cstdio>
#include <sstream>

namespace softkin {

nlohmann::json RunActuationPaths(const Config& cfg, const std::string& dir, bool verbose) {
  const std::string robot = cfg.String("robot", "three_chamber");
  const int res = cfg.Int("res", 0);
  // Each path is "a+b+...": those actuators move together from their rest value to end_value,
  // the others stay at rest. Every path starts from the rest shape.
  const std::vector<std::string> paths = cfg.StringList("paths", {});
  const int steps = cfg.Int("steps", 8);
  const double end_value = cfg.Number("end_value", 0.0);
  Scene scene = ConfigRobot(cfg, robot, res);
  FkOptions opts = cfg.Solver(scene.solver);
  cfg.CheckNoUnknownKeys();
  if (paths.empty()) cfg.Fail("paths", "a non-empty array of \"a+b+...\" actuator groups");
  if (steps < 1) cfg.Fail("steps", "an integer >= 1");
  const int tip = scene.marker_index("tip");
  if (tip < 0) throw std::invalid_argument("robot '" + robot + "' has no 'tip' marker");

  std::vector<std::vector<int>> groups;
  for (const std::string& p : paths) {
    std::vector<int> g;
    std::stringstream ss(p);
    std::string name;
    while (std::getline(ss, name, '+')) {
      const int a = scene.actuator_index(name);
      if (a < 0) cfg.Fail("paths", "groups of actuator names of robot '" + robot + "', got '" + p + "'");
      g.push_back(a);
    }
    if (g.empty()) cfg.Fail("paths", "non-empty actuator groups");
    for (int a : g) {
      const Actuator& act = scene.actuators[a];
      if (end_value > 0 && (end_value < act.min || end_value > act.max))
        cfg.Fail("end_value", "a value inside the range of actuator '" + act.name + "'");
    }
    groups.push_back(g);
  }

  auto model = std::make_shared<const Model>(scene);
  auto solver = MakeFkSolver(model, opts);
  CsvWriter csv(dir + "/paths.csv", {"path", "step", "value", "tip_x", "tip_y", "tip_z",
                                     "iterations", "time_s", "converged"});
  const Eigen::MatrixX3d rest_tips = scene.marker_positions(scene.mesh.vertices);
  nlohmann::json rows = nlohmann::json::array();
  int failures = 0;
  double total_s = 0;
  for (size_t p = 0; p < groups.size(); ++p) {
    // Each actuator of the group goes from its rest value to end_value (default: its far end).
    auto end_of = [&](int a) {
      return end_value > 0 ? end_value : scene.actuators[a].FarEnd();
    };
    const Actuator& first = scene.actuators[groups[p][0]];
    const double v_end = end_of(groups[p][0]);
    csv.RowStrings({paths[p], "0", std::to_string(first.rest), std::to_string(rest_tips(tip, 0)),
                    std::to_string(rest_tips(tip, 1)), std::to_string(rest_tips(tip, 2)), "0", "0",
                    "1"});
    Eigen::VectorXd c = scene.rest_actuation();
    Eigen::MatrixX3d X = scene.mesh.vertices, X_prev = X, guess;
    double path_s = 0;
    int path_iters = 0;
    nlohmann::json tips = nlohmann::json::array();
    for (int s = 1; s <= steps; ++s) {
      for (int a : groups[p]) {
        const Actuator& act = scene.actuators[a];
        c[a] = act.rest + (end_of(a) - act.rest) * double(s) / steps;
      }
      guess = s > 1 ? Eigen::MatrixX3d(2.0 * X - X_prev) : X;  // secant predictor
      const FkResult r = solver->Solve(c, &guess);
      if (r.status == FkStatus::InvalidInput) throw std::runtime_error(r.message);
      X_prev = X;
      X = r.positions;
      const bool ok = r.status == FkStatus::Converged;
      failures += !ok;
      path_s += r.time_s;
      path_iters += r.iterations;
      const Eigen::MatrixX3d P = scene.marker_positions(X);
      tips.push_back({P(tip, 0), P(tip, 1), P(tip, 2)});
      csv.RowStrings({paths[p], std::to_string(s), std::to_string(c[groups[p][0]]),
                      std::to_string(P(tip, 0)), std::to_string(P(tip, 1)),
                      std::to_string(P(tip, 2)), std::to_string(r.iterations),
                      std::to_string(r.time_s), ok ? "1" : "0"});
      if (verbose)
        std::fprintf(stderr, "  [%s %d/%d] %s\n", paths[p].c_str(), s, steps, r.BriefReport().c_str());
    }
    total_s += path_s;
    rows.push_back({{"path", paths[p]}, {"end_value", v_end}, {"tips", tips},
                    {"solve_s", path_s}, {"iterations", path_iters}});
  }
  nlohmann::json j;
  j["robot"] = robot;
  j["n_tets"] = scene.mesh.num_tets();
  j["n_vertices"] = scene.mesh.num_vertices();
  j["paths"] = rows;
  j["rest_tip"] = {rest_tips(tip, 0), rest_tips(tip, 1), rest_tips(tip, 2)};
  j["total_solve_s"] = total_s;
  j["non_converged_steps"] = failures;
  return j;
}

}  // namespace softkin
