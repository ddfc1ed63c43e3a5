// Fig. 2.13: cost and convergence of the FK solve under mesh refinement.
#include "softkin/experiments/results.hpp"
#include "softkin/experiments/runner.hpp"
#include "softkin/solver/factory/fk_factory.hpp"
#include "softkin/solver/fk/fk_solver.hpp"
#include "softkin/solver/robots/robots.hpp"
#include "softkin/solver/common/stopwatch.hpp"

#include <chrono>
#include <cstdio>
#include <iostream>

namespace softkin {

namespace {

/// The keys of a resolution_sweep config.
struct ResolutionParams {
  std::string robot;
  std::vector<int> resolutions;
  std::vector<double> actuation;  ///< one value per actuator (empty: rest)
  FkOptions opts;
};

ResolutionParams ReadResolutionParams(const Config& cfg) {
  ResolutionParams p;
  p.robot = cfg.String("robot", "pneumatic_finger");
  p.resolutions = cfg.IntList("resolutions", {});
  p.actuation = cfg.NumberList("actuation", {});
  p.opts = cfg.Solver(FkOptions{});
  cfg.CheckNoUnknownKeys();
  if (p.resolutions.empty()) cfg.Fail("resolutions", "a non-empty array of robot resolutions");
  return p;
}

/// One resolution: build, factor and solve; a row of resolution.csv and its entry.
nlohmann::json SolveAtResolution(const Config& cfg, const ResolutionParams& p, int res,
                                 CsvWriter* csv, bool verbose) {
  const auto t0 = std::chrono::steady_clock::now();
  Scene scene = ConfigRobot(cfg, p.robot, res);
  auto model = std::make_shared<const Model>(scene);
  const double build_s = SecondsSince(t0);
  Eigen::VectorXd c = scene.rest_actuation();
  if (!p.actuation.empty()) {
    if (static_cast<Eigen::Index>(p.actuation.size()) != c.size())
      cfg.Fail("actuation",
               "one value per actuator of '" + p.robot + "' (" + std::to_string(c.size()) + ")");
    for (int i = 0; i < c.size(); ++i) c[i] = p.actuation[i];
  }
  auto solver = MakeFkSolver(model, p.opts);
  FkResult r = solver->Solve(c);
  if (r.status == FkStatus::InvalidInput)
    throw std::invalid_argument(cfg.path() + ": " + r.message);
  const Eigen::MatrixX3d P = scene.marker_positions(r.positions);
  const int tip = scene.marker_index("tip");
  const double ms_it = 1e3 * r.time_s / std::max(1, r.iterations);
  const double us_it_v = 1e6 * r.time_s / std::max(1, r.iterations) / scene.mesh.num_vertices();
  csv->Row({double(res), double(scene.mesh.num_vertices()), double(scene.mesh.num_tets()), build_s,
            model->factor_time_s(), double(r.iterations), r.time_s, ms_it, us_it_v, P(tip, 0),
            P(tip, 1), P(tip, 2), r.status == FkStatus::Converged ? 1.0 : 0.0});
  if (verbose)
    std::fprintf(stderr, "  res %d: %d tets, %s\n", res, scene.mesh.num_tets(),
                 r.BriefReport().c_str());
  return {{"res", res},
          {"n_vertices", scene.mesh.num_vertices()},
          {"n_tets", scene.mesh.num_tets()},
          {"iterations", r.iterations},
          {"ms_per_iteration", ms_it},
          {"us_per_iteration_per_vertex", us_it_v},
          {"solve_s", r.time_s},
          {"status", FkStatusToString(r.status)},
          {"tip", {P(tip, 0), P(tip, 1), P(tip, 2)}}};
}

}  // namespace

nlohmann::json RunResolutionSweep(const Config& cfg, const std::string& dir, bool verbose) {
  const ResolutionParams p = ReadResolutionParams(cfg);
  if (cfg.check_only()) return {};  // only the settings were asked for (Config::check_only)
  CsvWriter csv(
      dir + "/resolution.csv",
      {"res", "n_vertices", "n_tets", "build_s", "factor_s", "iterations", "solve_s",
       "ms_per_iteration", "us_per_iteration_per_vertex", "tip_x", "tip_y", "tip_z", "converged"});
  nlohmann::json rows = nlohmann::json::array();
  for (int res : p.resolutions) rows.push_back(SolveAtResolution(cfg, p, res, &csv, verbose));
  nlohmann::json j;
  j["robot"] = p.robot;
  j["rows"] = rows;
  // Tip convergence: distance of each tip to the finest one.
  const auto& fin = rows.back()["tip"];
  nlohmann::json dist = nlohmann::json::array();
  for (const auto& r : rows) {
    double d2 = 0;
    for (int k = 0; k < 3; ++k) {
      const double d = r["tip"][k].get<double>() - fin[k].get<double>();
      d2 += d * d;
    }
    dist.push_back(std::sqrt(d2));
  }
  j["tip_distance_to_finest_mm"] = dist;
  const double first = rows.front()["us_per_iteration_per_vertex"].get<double>();
  const double last = rows.back()["us_per_iteration_per_vertex"].get<double>();
  j["per_vertex_iteration_cost_growth"] = last / first;
  return j;
}

}  // namespace softkin
