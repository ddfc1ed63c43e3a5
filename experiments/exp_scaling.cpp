// Solver scaling: iterations and time per vertex of FK solvers as the mesh is refined, for
// issue #33's target (Newton iterations grow by at most 2x from ~5k to ~150k tets).
#include "softkin/experiments/results.hpp"
#include "softkin/experiments/runner.hpp"
#include "softkin/solver/common/enum_names.hpp"
#include "softkin/solver/factory/fk_factory.hpp"
#include "softkin/solver/fk/fk_solver.hpp"

#include <algorithm>
#include <chrono>
#include <cstdio>

namespace softkin {

namespace {

/// One robot of a solver_scaling config: its resolutions, actuation and solvers.
struct ScalingCase {
  std::string robot;
  std::vector<int> resolutions;
  std::vector<double> actuation;  ///< one value per actuator
  std::vector<FkOptions> solvers;
};

/// The keys of a solver_scaling config: "cases" (an array of {robot, resolutions, actuation,
/// solvers}) and the shared "solver" options.
std::vector<ScalingCase> ReadScalingCases(const Config& cfg) {
  const FkOptions base = cfg.Solver(FkOptions{});
  const nlohmann::json cases = cfg.Raw("cases");
  cfg.CheckNoUnknownKeys();
  if (!cases.is_array() || cases.empty())
    cfg.Fail("cases", "a non-empty array of {robot, resolutions, actuation, solvers} objects");
  std::vector<ScalingCase> out;
  for (size_t i = 0; i < cases.size(); ++i) {
    const std::string at = "cases[" + std::to_string(i) + "]";
    const nlohmann::json& c = cases[i];
    if (!c.is_object()) cfg.Fail(at, "an object {robot, resolutions, actuation, solvers}");
    for (const auto& [key, value] : c.items())
      if (key != "robot" && key != "resolutions" && key != "actuation" && key != "solvers")
        cfg.Fail(at + "." + key, "no such key (robot, resolutions, actuation, solvers)");
    ScalingCase sc;
    if (!c.contains("robot") || !c["robot"].is_string())
      cfg.Fail(at + ".robot", "an embedded robot name (see `softkin robots`)");
    sc.robot = c["robot"].get<std::string>();
    auto ints = [&](const std::string& key) {
      std::vector<int> v;
      if (c.contains(key) && c[key].is_array())
        for (const auto& x : c[key])
          if (x.is_number_integer() && x.get<int>() >= 1) v.push_back(x.get<int>());
      if (v.empty() || v.size() != c[key].size())
        cfg.Fail(at + "." + key, "a non-empty array of robot resolutions (integers >= 1)");
      return v;
    };
    sc.resolutions = ints("resolutions");
    if (!c.contains("actuation") || !c["actuation"].is_array())
      cfg.Fail(at + ".actuation", "an array with one number per actuator");
    for (const auto& x : c["actuation"]) {
      if (!x.is_number()) cfg.Fail(at + ".actuation", "an array with one number per actuator");
      sc.actuation.push_back(x.get<double>());
    }
    if (!c.contains("solvers") || !c["solvers"].is_array() || c["solvers"].empty())
      cfg.Fail(at + ".solvers", "a non-empty array of FK solver names");
    for (const auto& x : c["solvers"]) {
      FkOptions o = base;
      try {
        o.solver = FkSolverTypeFromString(x.is_string() ? x.get<std::string>() : "");
      } catch (const std::invalid_argument&) {
        cfg.Fail(at + ".solvers", "FK solver names, each one of " + NameList(FkSolverTypeNames()));
      }
      sc.solvers.push_back(o);
    }
    out.push_back(sc);
  }
  return out;
}

/// One (robot, res, solver) solve from rest: its row of scaling.csv.
nlohmann::json SolveOnce(const Config& cfg, const ScalingCase& sc, const std::string& at, int res,
                         const std::shared_ptr<const Model>& model, const FkOptions& opts,
                         bool verbose) {
  Eigen::VectorXd c = model->scene().rest_actuation();
  if (static_cast<Eigen::Index>(sc.actuation.size()) != c.size())
    cfg.Fail(at + ".actuation",
             "one value per actuator of '" + sc.robot + "' (" + std::to_string(c.size()) + ")");
  for (int i = 0; i < c.size(); ++i) c[i] = sc.actuation[i];
  const FkResult r = MakeFkSolver(model, opts)->Solve(c);
  if (r.status == FkStatus::InvalidInput)
    throw std::invalid_argument(cfg.path() + ": " + at + ": " + r.message);
  const int nv = model->num_vertices();
  if (verbose)
    std::fprintf(stderr, "  %s res %d (%d tets): %s\n", sc.robot.c_str(), res,
                 model->scene().mesh.num_tets(), r.BriefReport().c_str());
  return {{"robot", sc.robot},
          {"solver", ToString(opts.solver)},
          {"res", res},
          {"n_vertices", nv},
          {"n_tets", model->scene().mesh.num_tets()},
          {"iterations", r.iterations},
          {"linear_iterations", r.linear_iterations},
          {"solve_s", r.time_s},
          {"us_per_vertex", 1e6 * r.time_s / nv},
          {"residual_ratio", r.gradient_ratio},
          {"converged", r.status == FkStatus::Converged ? 1 : 0},
          {"status", FkStatusToString(r.status)}};
}

}  // namespace

nlohmann::json RunSolverScaling(const Config& cfg, const std::string& dir, bool verbose) {
  const std::vector<ScalingCase> cases = ReadScalingCases(cfg);
  if (cfg.check_only()) return {};  // only the settings were asked for (Config::check_only)
  CsvWriter csv(dir + "/scaling.csv",
                {"robot", "solver", "res", "n_vertices", "n_tets", "iterations",
                 "linear_iterations", "solve_s", "us_per_vertex", "residual_ratio", "converged"});
  nlohmann::json rows = nlohmann::json::array(), growth = nlohmann::json::object();
  for (size_t i = 0; i < cases.size(); ++i) {
    const ScalingCase& sc = cases[i];
    const std::string at = "cases[" + std::to_string(i) + "]";
    std::vector<nlohmann::json> by_solver(sc.solvers.size());
    for (int res : sc.resolutions) {
      auto model = std::make_shared<const Model>(ConfigRobot(cfg, sc.robot, res));
      for (size_t k = 0; k < sc.solvers.size(); ++k) {
        nlohmann::json row = SolveOnce(cfg, sc, at, res, model, sc.solvers[k], verbose);
        csv.RowJson(row);
        rows.push_back(row);
        by_solver[k].push_back(row);
      }
    }
    // Growth of the iteration count and of the time per vertex from the coarsest to the finest
    // mesh, per solver (only if both ends converged).
    for (size_t k = 0; k < sc.solvers.size(); ++k) {
      const nlohmann::json& first = by_solver[k].front();
      const nlohmann::json& last = by_solver[k].back();
      nlohmann::json g = {{"tets", {first["n_tets"], last["n_tets"]}},
                          {"iterations", {first["iterations"], last["iterations"]}},
                          {"us_per_vertex", {first["us_per_vertex"], last["us_per_vertex"]}},
                          {"all_converged", std::all_of(by_solver[k].begin(), by_solver[k].end(),
                                                        [](const nlohmann::json& r) {
                                                          return r["converged"] == 1;
                                                        })}};
      if (first["converged"] == 1 && last["converged"] == 1) {
        g["iteration_growth"] =
            last["iterations"].get<double>() / std::max(1.0, first["iterations"].get<double>());
        g["us_per_vertex_growth"] =
            last["us_per_vertex"].get<double>() / first["us_per_vertex"].get<double>();
      }
      growth[sc.robot][ToString(sc.solvers[k].solver)] = g;
    }
  }
  return {{"rows", rows}, {"growth", growth}};
}

}  // namespace softkin
