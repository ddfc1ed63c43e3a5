// Ablation: plain local-global against Anderson-accelerated, at mid and full actuation.
#include "experiments/results.hpp"
#include "experiments/runner.hpp"
#include "solver/fk_solver.hpp"
#include "solver/robots.hpp"

#include <cstdio>
#include <iostream>

namespace softkin {

nlohmann::json RunAaAblation(const Config& cfg, const std::string& dir, bool verbose) {
  const std::vector<std::string> robots =
      cfg.StringList("robots", {"pneumatic_finger", "three_chamber"});
  const std::vector<int> res = cfg.IntList("resolutions", {});
  const std::vector<double> levels = cfg.NumberList("levels", {0.5, 1.0});
  FkOptions base = cfg.Solver(FkOptions{});
  cfg.CheckNoUnknownKeys();
  if (!res.empty() && res.size() != robots.size())
    cfg.Fail("resolutions", "one resolution per robot (or none for the defaults)");

  CsvWriter csv(dir + "/aa_ablation.csv",
                {"robot", "level", "solver", "iterations", "time_s", "energy", "status",
                 "aa_rejected"});
  nlohmann::json cases = nlohmann::json::array();
  double min_ratio = 1e300;
  for (size_t ri = 0; ri < robots.size(); ++ri) {
    Scene scene = MakeRobot(robots[ri], res.empty() ? 0 : res[ri]);
    auto model = std::make_shared<const Model>(scene);
    for (double level : levels) {
      // All actuators driven to the same fraction of their range.
      Eigen::VectorXd c = scene.rest_actuation();
      for (int a = 0; a < c.size(); ++a)
        c[a] = scene.actuators[a].rest + level * (scene.actuators[a].max - scene.actuators[a].rest);
      nlohmann::json row{{"robot", robots[ri]}, {"level", level}};
      for (const char* name : {"lg", "lg-aa"}) {
        FkOptions o = base;
        o.solver = name;
        FkResult r = MakeFkSolver(model, o)->Solve(c);
        csv.RowStrings({robots[ri], std::to_string(level), name, std::to_string(r.iterations),
                        std::to_string(r.time_s), std::to_string(r.energy),
                        FkStatusToString(r.status), std::to_string(r.aa_rejected)});
        row[name] = {{"iterations", r.iterations}, {"time_s", r.time_s}, {"energy", r.energy},
                     {"status", FkStatusToString(r.status)}};
        if (verbose) std::fprintf(stderr, "  %s level %.2f: %s\n", robots[ri].c_str(), level,
                                  r.BriefReport().c_str());
      }
      const double ratio = row["lg"]["iterations"].get<double>() /
                           std::max(1.0, row["lg-aa"]["iterations"].get<double>());
      row["iteration_ratio"] = ratio;
      row["time_ratio"] = row["lg"]["time_s"].get<double>() /
                          std::max(1e-12, row["lg-aa"]["time_s"].get<double>());
      if (level == 1.0) min_ratio = std::min(min_ratio, ratio);
      cases.push_back(row);
    }
  }
  nlohmann::json j;
  j["cases"] = cases;
  j["min_iteration_ratio_full_actuation"] = min_ratio < 1e300 ? nlohmann::json(min_ratio) : nlohmann::json(nullptr);
  return j;
}

}  // namespace softkin
