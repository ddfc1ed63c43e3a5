// Solver ablation: plain local-global against Anderson-accelerated variants and whole other
// solvers (newton), at mid and full actuation.
#include "softkin/experiments/results.hpp"
#include "softkin/experiments/runner.hpp"
#include "softkin/solver/common/enum_names.hpp"
#include "softkin/solver/factory/fk_factory.hpp"
#include "softkin/solver/fk/fk_solver.hpp"
#include "softkin/solver/robots/robots.hpp"

#include <algorithm>
#include <cstdio>
#include <iostream>
#include <map>
#include <stdexcept>

namespace softkin {

namespace {

/// A solver variant: plain local-global, Anderson with a window and a safeguard, or another
/// solver by name.
struct Variant {
  std::string label;
  FkOptions opts;
};

/// The keys of an aa_ablation config.
struct AaAblationParams {
  std::vector<std::string> robots;
  std::vector<int> res;        ///< per robot (empty: the defaults)
  std::vector<double> levels;  ///< fractions of the way from rest to the far end of each range
  /// lg first, then every (window, safeguard) pair, then the other solvers of "solvers"
  std::vector<Variant> variants;
};

AaAblationParams ReadAaAblationParams(const Config& cfg) {
  AaAblationParams p;
  p.robots = cfg.StringList("robots", {"pneumatic_finger", "three_chamber"});
  p.res = cfg.IntList("resolutions", {});
  p.levels = cfg.NumberList("levels", {0.5, 1.0});
  // Anderson variants: every (window, safeguard) pair, each against plain local-global.
  const std::vector<int> windows = cfg.IntList("windows", {6});
  const std::vector<std::string> guards = cfg.StringList("safeguards", {"hybrid"});
  const std::vector<std::string> solvers = cfg.StringList("solvers", {});
  FkOptions base = cfg.Solver(FkOptions{});
  cfg.CheckNoUnknownKeys();
  if (windows.empty()) cfg.Fail("windows", "a non-empty array of Anderson windows");
  if (guards.empty()) cfg.Fail("safeguards", "a non-empty array of safeguard names");
  p.variants = {{"lg", base}};
  p.variants[0].opts.solver = FkSolverType::kLg;
  for (int m : windows)
    for (const auto& g : guards) {
      Variant v{"lg-aa m=" + std::to_string(m) + " " + g, base};
      v.opts.solver = FkSolverType::kLgAa;
      v.opts.anderson_window = m;
      try {
        v.opts.anderson_safeguard = AndersonSafeguardFromString(g);
      } catch (const std::invalid_argument&) {
        cfg.Fail("safeguards",
                 "safeguard names, each one of " + NameList(AndersonSafeguardNames()));
      }
      std::string why;
      if (!v.opts.IsValid(&why)) cfg.Fail("windows", "Anderson windows, integers in [1, 50]");
      p.variants.push_back(v);
    }
  // Whole other solvers with the same options (their iterations count in their own units).
  for (const auto& name : solvers) {
    Variant v{name, base};
    try {
      v.opts.solver = FkSolverTypeFromString(name);
    } catch (const std::invalid_argument&) {
      cfg.Fail("solvers", "FK solver names, each one of " + NameList(FkSolverTypeNames()));
    }
    if (v.opts.solver == FkSolverType::kLg || v.opts.solver == FkSolverType::kLgAa)
      cfg.Fail("solvers", "solvers other than lg and lg-aa (those are the other keys' variants)");
    p.variants.push_back(v);
  }
  if (!p.res.empty() && p.res.size() != p.robots.size())
    cfg.Fail("resolutions", "one resolution per robot (or none for the defaults)");
  return p;
}

/// Every variant on one robot at one actuation level: rows of aa_ablation.csv and the case's
/// entry; the Anderson variants' iteration ratios at full actuation go into *min_ratio, the other
/// solvers' time ratios (lg / solver) at full actuation into *time_ratios.
nlohmann::json RunCase(const AaAblationParams& p, const std::string& robot, const Scene& scene,
                       const std::shared_ptr<const Model>& model, double level, CsvWriter* csv,
                       std::map<std::string, double>* min_ratio,
                       std::map<std::string, std::vector<double>>* time_ratios, bool verbose) {
  // All actuators driven the same fraction of the way from rest to the far end of their range
  // (the max volume ratio of a chamber, the min length ratio of a cable).
  Eigen::VectorXd c = scene.rest_actuation();
  for (int a = 0; a < c.size(); ++a) {
    const Actuator& act = scene.actuators[a];
    c[a] = act.rest + level * (act.FarEnd() - act.rest);
  }
  nlohmann::json row{{"robot", robot}, {"level", level}};
  double lg_iters = 0, lg_time = 0;
  bool lg_capped = false;
  for (const Variant& v : p.variants) {
    FkResult r = MakeFkSolver(model, v.opts)->Solve(c);
    const bool plain = v.opts.solver == FkSolverType::kLg;
    if (plain) {
      lg_iters = r.iterations;
      lg_time = r.time_s;
      lg_capped = r.status != FkStatus::Converged;
    }
    const double it_ratio = lg_iters / std::max(1, r.iterations);
    const double t_ratio = lg_time / std::max(1e-12, r.time_s);
    csv->RowStrings({robot, std::to_string(level), v.label, std::to_string(r.iterations),
                     std::to_string(r.time_s), std::to_string(r.energy), FkStatusToString(r.status),
                     std::to_string(r.aa_accepted), std::to_string(r.aa_rejected),
                     std::to_string(it_ratio), std::to_string(t_ratio)});
    nlohmann::json rj{{"iterations", r.iterations},
                      {"time_s", r.time_s},
                      {"energy", r.energy},
                      {"status", FkStatusToString(r.status)}};
    const bool anderson = v.opts.solver == FkSolverType::kLgAa;
    if (!plain) {
      if (anderson) {
        rj["aa_accepted"] = r.aa_accepted;
        rj["aa_rejected"] = r.aa_rejected;
      }
      if (v.opts.solver == FkSolverType::kNewton) {
        rj["linear_iterations"] = r.linear_iterations;
        rj["load_steps"] = r.load_steps;
      }
      rj["iteration_ratio"] = it_ratio;
      rj["time_ratio"] = t_ratio;
      // Plain lg stopped at the cap: its true count is higher, the ratio a lower bound.
      rj["ratio_is_lower_bound"] = lg_capped;
      if (level == 1.0 && anderson) {
        auto it = min_ratio->find(v.label);
        (*min_ratio)[v.label] = it == min_ratio->end() ? it_ratio : std::min(it->second, it_ratio);
      }
      if (level == 1.0 && !anderson) (*time_ratios)[v.label].push_back(t_ratio);
    }
    row[v.label] = rj;
    if (verbose)
      std::fprintf(stderr, "  %s level %.2f %s: %s\n", robot.c_str(), level, v.label.c_str(),
                   r.BriefReport().c_str());
  }
  return row;
}

}  // namespace

nlohmann::json RunAaAblation(const Config& cfg, const std::string& dir, bool verbose) {
  const AaAblationParams p = ReadAaAblationParams(cfg);
  if (cfg.check_only()) return {};  // only the settings were asked for (Config::check_only)
  CsvWriter csv(dir + "/aa_ablation.csv",
                {"robot", "level", "variant", "iterations", "time_s", "energy", "status",
                 "aa_accepted", "aa_rejected", "iteration_ratio", "time_ratio"});
  nlohmann::json cases = nlohmann::json::array();
  std::map<std::string, double> min_ratio;  // per Anderson variant, at full actuation
  std::map<std::string, std::vector<double>> time_ratios;  // per other solver, at full actuation
  for (size_t ri = 0; ri < p.robots.size(); ++ri) {
    Scene scene = MakeRobot(p.robots[ri], p.res.empty() ? 0 : p.res[ri]);
    auto model = std::make_shared<const Model>(scene);
    for (double level : p.levels)
      cases.push_back(
          RunCase(p, p.robots[ri], scene, model, level, &csv, &min_ratio, &time_ratios, verbose));
  }
  nlohmann::json j;
  j["cases"] = cases;
  // Headline: the first Anderson variant (the defaults unless the config says otherwise).
  const std::string head = p.variants[1].label;
  j["headline_variant"] = head;
  j["min_iteration_ratio_full_actuation"] =
      min_ratio.count(head) ? nlohmann::json(min_ratio[head]) : nlohmann::json(nullptr);
  j["min_iteration_ratio_full_actuation_by_variant"] = min_ratio;
  // Other solvers: the range of lg's time over theirs at full actuation (> 1: faster than lg).
  nlohmann::json by_solver = nlohmann::json::object();
  for (const auto& [label, ratios] : time_ratios)
    by_solver[label] = {{"min", *std::min_element(ratios.begin(), ratios.end())},
                        {"max", *std::max_element(ratios.begin(), ratios.end())}};
  j["time_ratio_full_actuation_by_solver"] = by_solver;
  return j;
}

}  // namespace softkin
