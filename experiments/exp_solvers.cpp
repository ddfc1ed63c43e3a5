// Table 2.2: the same bending sweep of pneumatic_finger solved by every FK method, each
// warm-started along the sweep exactly like fig2_11 (secant predictor), with the same stopping
// rule. Times to 90 / 180 / 240 degrees, iterations, final energy and its gap to the lowest,
// status, distance to the lg-aa shape and the tip trajectory of every method.
#include "experiments/measure.hpp"
#include "experiments/results.hpp"
#include "experiments/runner.hpp"
#include "solver/fk_solver.hpp"
#include "solver/robots.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <limits>
#include <map>
#include <memory>

namespace softkin {
namespace {

/// Methods named in the issue that this build does not run yet, with the reason.
const std::map<std::string, std::string> kNotRun = {
    {"sofa", "SOFA is not available on this machine (no Debian package); no row is filled in"},
};

std::string Key(std::string name) {
  std::replace(name.begin(), name.end(), '-', '_');
  return name;
}

}  // namespace

nlohmann::json RunSolverComparison(const Config& cfg, const std::string& dir, bool verbose) {
  const std::string robot = cfg.String("robot", "pneumatic_finger");
  const int res = cfg.Int("res", 0);
  const int steps = cfg.Int("steps", 12);
  const double end_value_cfg = cfg.Number("end_value", 0.0);
  std::vector<double> milestones = cfg.NumberList("milestones_deg", {90, 180, 240});
  const std::vector<std::string> methods =
      cfg.StringList("methods", {"lg-aa", "lg", "ceres", "ipopt-lbfgs", "ipopt-newton"});
  // Wall-clock budget of one method's whole sweep (s); a method that runs out is reported with
  // status time_limit and the milestones it reached.
  const double budget = cfg.Number("time_limit_s", 600.0);
  Scene scene = ConfigRobot(cfg, robot, res);
  const FkOptions base = cfg.Solver(scene.solver);
  cfg.CheckNoUnknownKeys();
  if (steps < 1) cfg.Fail("steps", "an integer >= 1");
  if (!(budget > 0)) cfg.Fail("time_limit_s", "a number of seconds > 0");
  if (methods.empty() || methods[0] != "lg-aa")
    cfg.Fail("methods", "a list of FK solver names starting with lg-aa (the reference shape)");
  const auto names = FkSolverNames();
  for (const auto& m : methods)
    if (std::find(names.begin(), names.end(), m) == names.end() && !kNotRun.count(m))
      cfg.Fail("methods", "FK solver names (lg, lg-aa, ceres, ipopt-lbfgs, ipopt-newton, "
                          "ipopt-hard, calculix-linear, calculix-nonlinear, sofa)");
  const Actuator& act = scene.actuators.at(0);
  const double vmax = end_value_cfg > 0 ? end_value_cfg : act.FarEnd();
  if (vmax > act.max || vmax < act.min || vmax == act.rest)
    cfg.Fail("end_value", "a value in [min, max] of actuator '" + act.name + "', not its rest value");
  const int tip = scene.marker_index("tip");
  if (tip < 0 || scene.marker_index("tip_top") < 0 || scene.marker_index("tip_bottom") < 0)
    cfg.Fail("robot", "a robot with tip, tip_top and tip_bottom markers (e.g. pneumatic_finger)");

  auto model = std::make_shared<const Model>(scene);
  CsvWriter csv(dir + "/trajectories.csv",
                {"method", "step", "actuation", "bend_deg", "tip_x", "tip_y", "tip_z", "iterations",
                 "time_s", "cumulative_s", "energy", "residual_ratio", "status"});
  nlohmann::json out_methods = nlohmann::json::object();
  std::map<std::string, Eigen::MatrixX3d> finals;
  std::map<std::string, double> total_time, final_energy;
  std::map<std::string, bool> all_converged;
  for (const std::string& name : methods) {
    const std::string key = Key(name);
    if (kNotRun.count(name)) {
      out_methods[key] = {{"status", "not_run"}, {"reason", kNotRun.at(name)}};
      if (verbose) std::fprintf(stderr, "  %s: not run (%s)\n", name.c_str(), kNotRun.at(name).c_str());
      continue;
    }
    FkOptions o = base;
    o.solver = name;
    o.continuation_steps = 1;
    auto solver = MakeFkSolver(model, o);
    BendAngle bend(scene);
    Eigen::VectorXd c = scene.rest_actuation();
    Eigen::MatrixX3d X = scene.mesh.vertices, X_prev = X;
    double cumulative = 0;
    int iterations = 0;
    std::string status = "converged";
    std::vector<double> reach(milestones.size(), -1.0);
    nlohmann::json tips = nlohmann::json::array();
    FkResult r;
    int done = 0;
    // FEM (CalculiX) loads from rest in increments: each step is its own run from the rest
    // shape, and the time to an angle is that of the run that reaches it. The others are
    // warm-started along the sweep and their time to an angle is cumulative.
    const bool fem = name.rfind("calculix", 0) == 0;
    double fem_spent = 0;
    for (int s = 1; s <= steps; ++s) {
      c[0] = act.rest + (vmax - act.rest) * double(s) / steps;
      const Eigen::MatrixX3d guess = s > 1 ? Eigen::MatrixX3d(2 * X - X_prev) : X;
      o.time_limit_s = std::max(1e-3, budget - (fem ? fem_spent : cumulative));
      solver = MakeFkSolver(model, o);  // cheap: the model (and its factor) is shared
      r = fem ? solver->Solve(c) : solver->Solve(c, &guess);
      if (fem) {
        fem_spent += r.time_s;
        cumulative = 0;  // the time of this run alone
      }
      if (r.status == FkStatus::InvalidInput) throw std::runtime_error(name + ": " + r.message);
      X_prev = X;
      X = r.positions;
      cumulative += r.time_s;
      iterations += r.iterations;
      const double ang = bend(X);
      for (size_t q = 0; q < milestones.size(); ++q)
        if (reach[q] < 0 && ang >= milestones[q] && r.status == FkStatus::Converged) reach[q] = cumulative;
      const Eigen::MatrixX3d P = scene.marker_positions(X);
      tips.push_back({P(tip, 0), P(tip, 1), P(tip, 2)});
      csv.RowStrings({name, std::to_string(s), std::to_string(c[0]), std::to_string(ang),
                      std::to_string(P(tip, 0)), std::to_string(P(tip, 1)), std::to_string(P(tip, 2)),
                      std::to_string(r.iterations), std::to_string(r.time_s),
                      std::to_string(cumulative), std::to_string(r.energy),
                      std::to_string(r.gradient_ratio), FkStatusToString(r.status)});
      if (verbose)
        std::fprintf(stderr, "  %s [%d/%d] %s = %.3f  bend %.1f deg  %s\n", name.c_str(), s, steps,
                     act.name.c_str(), c[0], ang, r.BriefReport().c_str());
      done = s;
      if (r.status != FkStatus::Converged) {
        status = FkStatusToString(r.status);
        if (r.status == FkStatus::TimeLimit || r.status == FkStatus::Diverged) break;
      }
    }
    nlohmann::json mj;
    for (size_t q = 0; q < milestones.size(); ++q) {
      char k[32];
      std::snprintf(k, sizeof(k), "t%.0f_s", milestones[q]);
      mj[k] = reach[q] >= 0 ? nlohmann::json(reach[q]) : nlohmann::json(nullptr);
    }
    mj["iterations"] = iterations;
    mj["energy"] = r.energy;
    mj["status"] = status;
    mj["steps_done"] = done;
    mj["total_s"] = cumulative;  // FEM: the last run's time (from rest to the last step)
    if (fem) mj["fem_all_runs_s"] = fem_spent;
    mj["final_bend_deg"] = bend(X);
    mj["tips"] = tips;
    out_methods[key] = mj;
    if (done == steps) {
      finals[name] = X;
      final_energy[name] = r.energy;
    }
    total_time[name] = cumulative;
    all_converged[name] = status == "converged" && done == steps;
  }

  // Energy gaps (to the lowest final energy any method reached at the end value) and distances to
  // the lg-aa shape.
  double lowest = std::numeric_limits<double>::infinity();
  for (const auto& [n, e] : final_energy) lowest = std::min(lowest, e);
  for (const std::string& name : methods) {
    const std::string key = Key(name);
    if (!final_energy.count(name)) {
      if (!kNotRun.count(name)) {
        out_methods[key]["energy_gap"] = nullptr;
        out_methods[key]["max_distance_to_lg_aa_mm"] = nullptr;
      }
      continue;
    }
    out_methods[key]["energy_gap"] = (final_energy[name] - lowest) / std::abs(lowest);
    out_methods[key]["max_distance_to_lg_aa_mm"] =
        finals.count("lg-aa") ? (finals[name] - finals["lg-aa"]).rowwise().norm().maxCoeff() : 0.0;
  }
  // Headline: the fastest Ceres / Ipopt method that reached the same energy (1e-6 relative to the
  // lg-aa one) over the whole sweep, divided by lg-aa's time. If none did, the ratio of the
  // fastest one's time spent (a lower bound on the speed-up) with lower_bound = true.
  nlohmann::json j;
  const double t_aa = total_time.count("lg-aa") ? total_time["lg-aa"] : 0.0;
  double best = std::numeric_limits<double>::infinity(), best_bound = 0;
  std::string best_name, bound_name;
  for (const std::string& name : {"ceres", "ipopt-lbfgs", "ipopt-newton"}) {
    if (!total_time.count(name)) continue;
    const bool same = all_converged[name] && final_energy.count("lg-aa") &&
                      std::abs(final_energy[name] - final_energy["lg-aa"]) <=
                          1e-6 * std::abs(final_energy["lg-aa"]);
    if (same && total_time[name] < best) {
      best = total_time[name];
      best_name = name;
    }
    if (!same && total_time[name] > best_bound) {
      best_bound = total_time[name];
      bound_name = name;
    }
  }
  if (t_aa > 0 && !best_name.empty()) {
    j["speedup_vs_best_nlp"] = best / t_aa;
    j["speedup_vs_best_nlp_method"] = best_name;
    j["speedup_vs_best_nlp_lower_bound"] = false;
  } else if (t_aa > 0 && !bound_name.empty()) {
    j["speedup_vs_best_nlp"] = best_bound / t_aa;
    j["speedup_vs_best_nlp_method"] = bound_name;
    j["speedup_vs_best_nlp_lower_bound"] = true;
  } else {
    j["speedup_vs_best_nlp"] = nullptr;
  }
  // lg-aa against calculix-nonlinear at the largest milestone both reached (the thesis: 240).
  j["speedup_vs_calculix_nonlinear"] = nullptr;
  if (out_methods.contains("calculix_nonlinear") && out_methods.contains("lg_aa") &&
      out_methods["calculix_nonlinear"].contains("iterations")) {
    for (size_t q = milestones.size(); q-- > 0;) {
      char k[32];
      std::snprintf(k, sizeof(k), "t%.0f_s", milestones[q]);
      const auto& a = out_methods["lg_aa"][k];
      const auto& f = out_methods["calculix_nonlinear"][k];
      if (a.is_number() && f.is_number() && a.get<double>() > 0) {
        j["speedup_vs_calculix_nonlinear"] = f.get<double>() / a.get<double>();
        j["speedup_vs_calculix_nonlinear_at_deg"] = milestones[q];
        break;
      }
    }
  }
  j["methods"] = out_methods;
  j["robot"] = robot;
  j["n_tets"] = scene.mesh.num_tets();
  j["n_vertices"] = scene.mesh.num_vertices();
  j["steps"] = steps;
  j["end_value"] = vmax;
  j["time_limit_s"] = budget;
  j["gradient_tolerance"] = base.gradient_tolerance;
  j["tolerance"] = base.tolerance;
  j["lowest_energy"] = std::isfinite(lowest) ? nlohmann::json(lowest) : nlohmann::json(nullptr);
  if (robot == "pneumatic_finger")
    j["thesis_table_2_2"] = {
        {"ours", {{"elements", 45802}, {"t90_s", 8.5}, {"t180_s", 15.2}, {"t240_s", 23.2}}},
        {"fem1_abaqus_linear", {{"elements", 44774}, {"t90_s", 240}, {"t180_s", 529}, {"t240_s", 820}}},
        {"fem2_abaqus_nonlinear", {{"elements", 44774}, {"t90_s", 288}, {"t180_s", 636}, {"t240_s", 1068}}},
        {"sofa", {{"elements", 44900}, {"t90_s", 3.8}}}};
  return j;
}

}  // namespace softkin
