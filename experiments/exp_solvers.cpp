// Table 2.2: the same bending sweep of pneumatic_finger solved by every FK method, each
// warm-started along the sweep exactly like fig2_11 (secant predictor), with the same stopping
// rule. Times to 90 / 180 / 240 degrees, iterations, final energy and its gap to the lowest,
// status, distance to the lg-aa shape and the tip trajectory of every method.
#include "softkin/experiments/fem_trajectory.hpp"
#include "softkin/experiments/measure.hpp"
#include "softkin/experiments/results.hpp"
#include "softkin/experiments/runner.hpp"
#include "softkin/solver/baselines/calculix.hpp"
#include "softkin/solver/baselines/ccx_run.hpp"
#include "softkin/solver/common/enum_names.hpp"
#include "softkin/solver/fk/energy.hpp"
#include "softkin/solver/factory/fk_factory.hpp"
#include "softkin/solver/fk/fk_solver.hpp"
#include "softkin/solver/robots/robots.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <limits>
#include <map>
#include <memory>
#include <stdexcept>

namespace softkin {
namespace {

/// Methods named in the issue that this build does not run yet, with the reason.
const std::map<std::string, std::string> kNotRun = {
    {"sofa", "SOFA is not available on this machine (no Debian package); no row is filled in"},
};

/// The pressure-driven FEM rows (calculix_pressure.hpp: hollow chambers, cavity pressure ramped
/// under NLGEOM), by method name: their material law. They are not FK solvers: their actuation is
/// a pressure, and each increment is reported at the cavity volume ratio it reached.
const std::map<std::string, std::string> kPressureFem = {
    {"calculix-pressure-linear", "linear"},
    {"calculix-pressure-nonlinear", "neo-hooke"},
};

std::string Key(std::string name) {
  std::replace(name.begin(), name.end(), '-', '_');
  return name;
}

/// The keys of a solver_comparison config, checked against the robot.
struct SolverComparisonParams {
  std::string robot;
  int steps = 12;
  std::vector<double> milestones;    ///< bend angles whose times are reported, degrees
  std::vector<std::string> methods;  ///< FK solver names, lg-aa (the reference shape) first
  // Wall-clock budget of one method's whole sweep (s); a method that runs out is reported with
  // status time_limit and the milestones it reached.
  double budget = 600.0;
  Scene scene;
  FkOptions base;           ///< the robot's solver options with the config's
  double vmax = 0;          ///< the first actuator's end value
  int tip = -1;             ///< the tip marker
  PressureFemOptions fem;   ///< the pressure FEM rows' options (law set per row)
  double fem_pressure = 0;  ///< their end pressure on the first actuator, MPa
};

SolverComparisonParams ReadSolverComparisonParams(const Config& cfg) {
  SolverComparisonParams p;
  p.robot = cfg.String("robot", "pneumatic_finger");
  const int res = cfg.Int("res", 0);
  p.steps = cfg.Int("steps", 12);
  const double end_value_cfg = cfg.Number("end_value", 0.0);
  p.milestones = cfg.NumberList("milestones_deg", {90, 180, 240});
  p.methods = cfg.StringList("methods", {"lg-aa", "lg", "ceres", "ipopt-lbfgs", "ipopt-newton"});
  p.budget = cfg.Number("time_limit_s", 600.0);
  p.scene = ConfigRobot(cfg, p.robot, res);
  p.base = cfg.Solver(p.scene.solver);
  const bool pressure_rows =
      std::any_of(p.methods.begin(), p.methods.end(),
                  [](const std::string& m) { return kPressureFem.count(m); });
  if (pressure_rows) {
    p.fem = ReadPressureFemOptions(cfg, 0.05, p.budget);
    p.fem_pressure = cfg.Number("fem_pressure_mpa", 0.0);
  }
  cfg.CheckNoUnknownKeys();
  if (p.steps < 1) cfg.Fail("steps", "an integer >= 1");
  if (!(p.budget > 0)) cfg.Fail("time_limit_s", "a number of seconds > 0");
  if (p.methods.empty() || p.methods[0] != "lg-aa")
    cfg.Fail("methods", "a list of FK solver names starting with lg-aa (the reference shape)");
  for (const auto& m : p.methods) {
    if (kNotRun.count(m) || kPressureFem.count(m)) continue;
    try {
      (void)FkSolverTypeFromString(m);
    } catch (const std::invalid_argument&) {
      std::vector<std::string> names = FkSolverTypeNames();
      for (const auto& [n, why] : kNotRun) names.push_back(n);
      for (const auto& [n, law] : kPressureFem) names.push_back(n);
      cfg.Fail("methods", "FK solver names (" + NameList(names) + ")");
    }
  }
  const Actuator& act = p.scene.actuators.at(0);
  p.vmax = end_value_cfg > 0 ? end_value_cfg : act.FarEnd();
  if (p.vmax > act.max || p.vmax < act.min || p.vmax == act.rest)
    cfg.Fail("end_value",
             "a value in [min, max] of actuator '" + act.name + "', not its rest value");
  for (const auto& m : p.methods)
    if (m.rfind("calculix", 0) == 0 && (act.type != ActuatorType::Pneumatic || act.is_signed()))
      cfg.Fail("methods",
               "no calculix-* method unless the first actuator is an unsigned pneumatic "
               "chamber (the FEM increments are read back as its volume ratio)");
  const bool any_ccx = std::any_of(p.methods.begin(), p.methods.end(), [](const std::string& m) {
    return m.rfind("calculix", 0) == 0;
  });
  if (any_ccx && FindCcx().empty())
    cfg.Fail("methods", "no calculix-* method on this machine: " + CcxMissingMessage());
  if (pressure_rows) {
    if (!(p.fem_pressure > 0))
      cfg.Fail("fem_pressure_mpa", "the pressure FEM's end pressure, MPa > 0");
    CheckPressureFemCanRun(cfg, "methods", p.scene, p.fem.element);
  }
  p.tip = p.scene.marker_index("tip");
  if (p.tip < 0 || p.scene.marker_index("tip_top") < 0 || p.scene.marker_index("tip_bottom") < 0)
    cfg.Fail("robot", "a robot with tip, tip_top and tip_bottom markers (e.g. pneumatic_finger)");
  return p;
}

/// What the headlines compare, per method name, as the sweeps left it.
struct Totals {
  nlohmann::json methods = nlohmann::json::object();  ///< the summary of each method, by Key
  std::map<std::string, Eigen::MatrixX3d> finals;     ///< shapes of the finished sweeps
  std::map<std::string, double> total_time, final_energy;
  std::map<std::string, bool> all_converged;
  std::map<std::string, int> steps_done;
  /// Elapsed s at the end of each completed step of an iterative sweep (a step whose solve met
  /// the tolerance, inverted elements or not), in order.
  std::map<std::string, std::vector<double>> step_end;
  /// (bend angle, elapsed s) of every converged step or FEM increment, in order.
  std::map<std::string, std::vector<std::pair<double, double>>> bends;
  /// (bend angle, actuation value) of lg-aa's converged steps, in order.
  std::vector<std::pair<double, double>> aa_curve;
};

/// One method's sweep: its state as it goes, and the rows it writes.
struct MethodSweep {
  MethodSweep(const SolverComparisonParams& p, const std::string& name, CsvWriter* csv,
              std::vector<std::pair<double, double>>* bends, bool verbose)
      : p(p),
        name(name),
        csv(csv),
        bends(bends),
        verbose(verbose),
        bend(p.scene),
        reach(p.milestones.size(), -1.0),
        X(p.scene.mesh.vertices) {}

  /// One row of the trajectory: the shape Xs after a step (or FEM increment) s at actuation
  /// `value`, `elapsed` seconds into the method's run.
  void Record(int s, double value, const Eigen::MatrixX3d& Xs, const FkResult& rs, double step_s,
              double elapsed, bool converged) {
    const double ang = bend(Xs);
    if (converged) bends->emplace_back(ang, elapsed);
    if (converged) curve.emplace_back(ang, value);
    for (size_t q = 0; q < p.milestones.size(); ++q)
      if (reach[q] < 0 && ang >= p.milestones[q] && converged) reach[q] = elapsed;
    const int tip = p.tip;
    const Eigen::MatrixX3d P = p.scene.marker_positions(Xs);
    tips.push_back({P(tip, 0), P(tip, 1), P(tip, 2)});
    csv->RowStrings({name, std::to_string(s), std::to_string(value), std::to_string(ang),
                     std::to_string(P(tip, 0)), std::to_string(P(tip, 1)),
                     std::to_string(P(tip, 2)), std::to_string(rs.iterations),
                     std::to_string(step_s), std::to_string(elapsed),
                     std::isfinite(rs.energy) ? std::to_string(rs.energy) : std::string(),
                     std::to_string(rs.gradient_ratio), FkStatusToString(rs.status)});
    if (verbose)
      std::fprintf(stderr, "  %s [%d] %s = %.3f  bend %.1f deg  %.2f s\n", name.c_str(), s,
                   p.scene.actuators.at(0).name.c_str(), value, ang, elapsed);
  }

  const SolverComparisonParams& p;
  const std::string& name;
  CsvWriter* csv;
  std::vector<std::pair<double, double>>* bends;
  bool verbose;
  BendAngle bend;
  std::vector<double> reach;  ///< elapsed s at each milestone, -1: not reached
  nlohmann::json tips = nlohmann::json::array();
  std::vector<std::pair<double, double>> curve;  ///< (bend angle, actuation) of converged rows
  Eigen::MatrixX3d X;                            ///< the last shape
  FkResult r;                                    ///< the last solve
  double cumulative = 0;
  int iterations = 0;
  int done = 0;                    ///< steps completed
  std::vector<double> step_end_s;  ///< elapsed s at the end of each completed step
  std::string status = "converged";
};

/// FEM loads from rest in increments: one CalculiX run to the end value in `steps` equal
/// increments (cut back by ccx where needed). Its time to an angle is the wall-clock time at which
/// the first increment at or beyond that angle converged, read as the run goes.
void SweepCalculix(const std::shared_ptr<const Model>& model, FkOptions o, MethodSweep* m) {
  const SolverComparisonParams& p = m->p;
  o.continuation_steps = p.steps;
  o.time_limit_s = p.budget;
  std::unique_ptr<FkSolver> solver = MakeFkSolver(model, o);
  Eigen::VectorXd c = p.scene.rest_actuation();
  c[0] = p.vmax;
  m->r = solver->Solve(c);
  if (m->r.status == FkStatus::InvalidInput)
    throw std::runtime_error(m->name + ": " + m->r.message);
  const auto& incs = dynamic_cast<const CalculixSolver&>(*solver).increments();
  double prev = 0;
  Eigen::VectorXd ck = c;
  for (size_t k = 0; k < incs.size(); ++k) {
    // A row per converged increment: the volume ratio its load stands for, its time, and
    // Eq. 2.10 at its shape.
    ck[0] = CalculixRatioAtLoad(p.vmax, incs[k].load);
    FkResult rk;
    rk.iterations = 1;
    rk.status = FkStatus::Converged;
    rk.energy = Energy(*model, incs[k].positions, ck);
    m->Record(static_cast<int>(k) + 1, ck[0], incs[k].positions, rk, incs[k].wall_s - prev,
              incs[k].wall_s, true);
    prev = incs[k].wall_s;
  }
  m->X = m->r.positions;
  m->cumulative = m->r.time_s;
  m->iterations = m->r.iterations;
  m->status = FkStatusToString(m->r.status);
  m->done = m->r.status == FkStatus::Converged ? p.steps : 0;
}

/// The pressure FEM: one CalculiX ramp of the first actuator's cavity pressure from rest to
/// fem_pressure_mpa, as far as it converges within the budget. A row per converged increment at
/// the cavity volume ratio it reached (no energy: Eq. 2.10 needs the chambers, which the FEM
/// leaves hollow); its time to an angle is the wall-clock time at which that increment converged.
void SweepPressureFem(const Model& model, const std::string& law, MethodSweep* m,
                      nlohmann::json* extra) {
  const SolverComparisonParams& p = m->p;
  PressureFemOptions o = p.fem;
  o.law = law;
  Eigen::VectorXd pressure = Eigen::VectorXd::Zero(p.scene.num_actuators());
  pressure[0] = p.fem_pressure;
  const FemTrajectory t = RunFemTrajectory(p.scene, model, pressure, 0, o);
  if (!t.run.ok) throw std::runtime_error(m->name + ": " + t.run.message);
  double prev = 0;
  for (size_t k = 0; k < t.run.increments.size(); ++k) {
    const PressureFemIncrement& inc = t.run.increments[k];
    FkResult rk;
    rk.iterations = 1;
    rk.status = FkStatus::Converged;
    rk.energy = std::numeric_limits<double>::quiet_NaN();
    m->Record(static_cast<int>(k) + 1, inc.cavity_ratio[0], inc.positions, rk, inc.wall_s - prev,
              inc.wall_s, true);
    prev = inc.wall_s;
    m->X = inc.positions;
  }
  m->r = FkResult{};
  m->r.energy = std::numeric_limits<double>::quiet_NaN();
  m->r.message = t.run.message;
  m->cumulative = t.run.time_s;
  m->iterations = static_cast<int>(t.run.increments.size());
  m->status = t.run.reached_end ? "reached_end" : "stopped";
  m->done = 0;  // its end state is a pressure, not the sweep's end value
  *extra = FemTrajectorySummary(t, p.milestones);
}

/// The iterative solvers: `steps` warm-started steps (secant predictor) within the budget.
void SweepIterative(const std::shared_ptr<const Model>& model, FkOptions o, MethodSweep* m) {
  const SolverComparisonParams& p = m->p;
  const Actuator& act = p.scene.actuators.at(0);
  Eigen::VectorXd c = p.scene.rest_actuation();
  Eigen::MatrixX3d X_prev = m->X;
  for (int s = 1; s <= p.steps; ++s) {
    c[0] = act.rest + (p.vmax - act.rest) * double(s) / p.steps;
    const Eigen::MatrixX3d guess = s > 1 ? Eigen::MatrixX3d(2 * m->X - X_prev) : m->X;
    o.time_limit_s = std::max(1e-3, p.budget - m->cumulative);
    std::unique_ptr<FkSolver> solver =
        MakeFkSolver(model, o);  // cheap: the model (and its factor) is shared
    m->r = solver->Solve(c, &guess);
    const FkResult& r = m->r;
    if (r.status == FkStatus::InvalidInput) throw std::runtime_error(m->name + ": " + r.message);
    X_prev = m->X;
    m->X = r.positions;
    m->cumulative += r.time_s;
    m->iterations += r.iterations;
    m->Record(s, c[0], m->X, r, r.time_s, m->cumulative, r.status == FkStatus::Converged);
    if (r.status == FkStatus::TimeLimit || r.status == FkStatus::Diverged) {
      m->status = FkStatusToString(r.status);
      break;  // step s not completed
    }
    m->done = s;
    m->step_end_s.push_back(m->cumulative);
    if (r.status != FkStatus::Converged) m->status = FkStatusToString(r.status);
  }
}

/// Runs one method's sweep and adds it to the totals.
void RunMethod(const SolverComparisonParams& p, const std::shared_ptr<const Model>& model,
               const std::string& name, CsvWriter* csv, Totals* t, bool verbose) {
  const std::string key = Key(name);
  if (kNotRun.count(name)) {
    t->methods[key] = {{"status", "not_run"}, {"reason", kNotRun.at(name)}};
    if (verbose)
      std::fprintf(stderr, "  %s: not run (%s)\n", name.c_str(), kNotRun.at(name).c_str());
    return;
  }
  FkOptions o = p.base;
  if (!kPressureFem.count(name)) o.solver = FkSolverTypeFromString(name);
  o.continuation_steps = 1;
  MethodSweep m(p, name, csv, &t->bends[name], verbose);
  nlohmann::json fem;
  if (kPressureFem.count(name))
    SweepPressureFem(*model, kPressureFem.at(name), &m, &fem);
  else if (o.solver == FkSolverType::kCalculixLinear ||
           o.solver == FkSolverType::kCalculixNonlinear)
    SweepCalculix(model, o, &m);
  else
    SweepIterative(model, o, &m);
  nlohmann::json mj;
  for (size_t q = 0; q < p.milestones.size(); ++q) {
    char k[32];
    std::snprintf(k, sizeof(k), "t%.0f_s", p.milestones[q]);
    mj[k] = m.reach[q] >= 0 ? nlohmann::json(m.reach[q]) : nlohmann::json(nullptr);
  }
  mj["iterations"] = m.iterations;
  mj["energy"] = std::isfinite(m.r.energy) ? nlohmann::json(m.r.energy) : nlohmann::json(nullptr);
  mj["status"] = m.status;
  mj["message"] = m.r.message;  // the last solve's (why a method stopped)
  mj["steps_done"] = m.done;
  mj["total_s"] = m.cumulative;
  mj["final_bend_deg"] = m.bend(m.X);
  mj["tips"] = m.tips;
  if (!fem.is_null())
    for (const char* k : {"law", "nodes", "elements", "end_pressure_mpa", "end_cavity_ratio"})
      mj[k] = fem[k];
  t->methods[key] = mj;
  if (m.done == p.steps) {
    t->finals[name] = m.X;
    t->final_energy[name] = m.r.energy;
  }
  if (name == "lg-aa") t->aa_curve = m.curve;
  t->total_time[name] = m.cumulative;
  t->steps_done[name] = m.done;
  t->step_end[name] = m.step_end_s;
  t->all_converged[name] = m.status == "converged" && m.done == p.steps;
}

/// Energy gaps (to the lowest final energy any method reached at the end value) and distances to
/// the lg-aa shape; returns the lowest energy (infinity if no sweep finished).
double AddEnergyGaps(const SolverComparisonParams& p, Totals* t) {
  double lowest = std::numeric_limits<double>::infinity();
  for (const auto& [n, e] : t->final_energy) lowest = std::min(lowest, e);
  for (const std::string& name : p.methods) {
    const std::string key = Key(name);
    if (!t->final_energy.count(name)) {
      if (!kNotRun.count(name)) {
        t->methods[key]["energy_gap"] = nullptr;
        t->methods[key]["max_distance_to_lg_aa_mm"] = nullptr;
      }
      continue;
    }
    t->methods[key]["energy_gap"] = (t->final_energy[name] - lowest) / std::abs(lowest);
    t->methods[key]["max_distance_to_lg_aa_mm"] =
        t->finals.count("lg-aa")
            ? (t->finals[name] - t->finals["lg-aa"]).rowwise().norm().maxCoeff()
            : 0.0;
  }
  return lowest;
}

// Headline 1: lg-aa against the fastest Ceres / Ipopt method. A method that ended the sweep at
// the lg-aa energy (1e-6 relative) gives its exact time ratio. One that ran out of time after
// k converged steps gives a lower bound: it spent its budget without reaching step k + 1, which
// lg-aa reached in its cumulative time to that step. The reported ratio is the smallest over the
// methods (the fastest one), flagged as a lower bound if that smallest is a bound. A method that
// converged to another energy has no comparable time and is listed as excluded. lg-aa's steps
// count as completed when their solve met the tolerance, also where the state has inverted
// elements (the finger's last steps): the other methods are timed to the same states. If no
// ratio can be formed, speedup_vs_best_nlp is null and speedup_vs_best_nlp_reason says why.
void AddSpeedupVsBestNlp(const SolverComparisonParams& p, Totals* t, nlohmann::json* j) {
  const int steps = p.steps;
  const std::vector<double>& aa_cum = t->step_end["lg-aa"];  // lg-aa's time after each step
  const char* const kExcluded =
      "the Ceres / Ipopt methods that ran are excluded (another energy, or no time)";
  std::string reason = "no Ceres or Ipopt method (ceres, ipopt-lbfgs, ipopt-newton) ran";
  double best = std::numeric_limits<double>::infinity();
  bool best_is_bound = false;
  std::string best_name;
  nlohmann::json excluded = nlohmann::json::array();
  const std::vector<std::string> nlp_methods = {"ceres", "ipopt-lbfgs", "ipopt-newton"};
  for (const std::string& name : nlp_methods) {
    if (!t->total_time.count(name)) continue;
    double ratio;
    bool bound = false;
    const size_t need = t->all_converged[name]
                            ? static_cast<size_t>(steps)
                            : static_cast<size_t>(std::min(t->steps_done[name], steps - 1)) + 1;
    if (aa_cum.size() < need) {
      reason = "lg-aa completed " + std::to_string(aa_cum.size()) + " of " + std::to_string(steps) +
               " steps, fewer than the comparison needs";
      continue;
    }
    if (t->all_converged[name]) {
      const bool same = t->final_energy.count("lg-aa") &&
                        std::abs(t->final_energy[name] - t->final_energy["lg-aa"]) <=
                            1e-6 * std::abs(t->final_energy["lg-aa"]);
      if (!same) {
        excluded.push_back(name);
        reason = kExcluded;
        continue;
      }
      ratio = t->total_time[name] / aa_cum.back();
    } else if (t->methods[Key(name)]["status"] == "time_limit") {
      ratio = t->total_time[name] / aa_cum[std::min(t->steps_done[name], steps - 1)];
      bound = true;
    } else {
      excluded.push_back(name);
      reason = kExcluded;
      continue;
    }
    if (ratio < best) {
      best = ratio;
      best_name = name;
      best_is_bound = bound;
    }
  }
  if (best_name.empty()) {
    (*j)["speedup_vs_best_nlp"] = nullptr;
    (*j)["speedup_vs_best_nlp_reason"] = reason;
  } else {
    (*j)["speedup_vs_best_nlp"] = best;
    (*j)["speedup_vs_best_nlp_method"] = best_name;
    (*j)["speedup_vs_best_nlp_lower_bound"] = best_is_bound;
  }
  (*j)["speedup_vs_best_nlp_excluded"] = excluded;
}

// lg-aa's time to bend the robot by `deg` from rest: one cold solve at the actuation where its
// sweep's bend curve (linearly interpolated from rest) reaches `deg`; -1 if the sweep never did.
double AaColdTimeToBend(const SolverComparisonParams& p, const std::shared_ptr<const Model>& model,
                        const Totals& t, double deg, nlohmann::json* info) {
  const Actuator& act = p.scene.actuators.at(0);
  double a0 = 0, v0 = act.rest;
  for (const auto& [a1, v1] : t.aa_curve) {
    if (a1 >= deg) {
      const double v = v0 + (v1 - v0) * (deg - a0) / std::max(a1 - a0, 1e-12);
      FkOptions o = p.base;
      o.solver = FkSolverType::kLgAa;
      o.continuation_steps = 1;
      Eigen::VectorXd c = p.scene.rest_actuation();
      c[0] = v;
      const FkResult r = MakeFkSolver(model, o)->Solve(c);
      BendAngle bend(p.scene);
      (*info)["actuation"] = v;
      (*info)["bend_deg"] = bend(r.positions);
      (*info)["status"] = FkStatusToString(r.status);
      (*info)["time_s"] = r.time_s;
      return r.status == FkStatus::Converged ? r.time_s : -1.0;
    }
    a0 = a1;
    v0 = v1;
  }
  return -1.0;
}

// Headline 2: lg-aa against a FEM row (`fem`): time to the largest milestone both reached (the
// thesis: 240 degrees). If the FEM reached none, the FEM's time to the largest bend it did reach
// against one cold lg-aa solve from rest to that bend (basis "fem_max_bend", AaColdTimeToBend).
void AddSpeedupVsFem(const SolverComparisonParams& p, const std::shared_ptr<const Model>& model,
                     const std::string& fem_name, Totals* t, nlohmann::json* j) {
  const std::string key = "speedup_vs_" + Key(fem_name);
  if (std::find(p.methods.begin(), p.methods.end(), fem_name) == p.methods.end()) return;
  (*j)[key] = nullptr;
  const auto& fem = t->bends[fem_name];
  const auto& aa = t->bends["lg-aa"];
  auto first_at = [](const std::vector<std::pair<double, double>>& v, double deg) {
    for (const auto& [ang, time] : v)
      if (ang >= deg) return time;
    return -1.0;
  };
  if (fem.empty() || aa.empty()) return;
  const std::vector<double>& milestones = p.milestones;
  double at = -1;
  for (size_t q = milestones.size(); q-- > 0 && at < 0;)
    if (first_at(fem, milestones[q]) > 0 && first_at(aa, milestones[q]) > 0) at = milestones[q];
  if (at < 0) {
    double fem_max = 0;
    for (const auto& [ang, time] : fem) fem_max = std::max(fem_max, ang);
    nlohmann::json cold;
    const double aa_s = fem_max > 0 ? AaColdTimeToBend(p, model, *t, fem_max, &cold) : -1.0;
    if (aa_s > 0) {
      (*j)[key] = first_at(fem, fem_max) / aa_s;
      (*j)[key + "_at_deg"] = fem_max;
      (*j)[key + "_basis"] = "fem_max_bend";
      (*j)[key + "_lg_aa_cold_solve"] = cold;
    }
    return;
  }
  (*j)[key] = first_at(fem, at) / first_at(aa, at);
  (*j)[key + "_at_deg"] = at;
  (*j)[key + "_basis"] = "milestone";
}

}  // namespace

nlohmann::json RunSolverComparison(const Config& cfg, const std::string& dir, bool verbose) {
  const SolverComparisonParams p = ReadSolverComparisonParams(cfg);
  if (cfg.check_only()) return {};  // only the settings were asked for (Config::check_only)
  auto model = std::make_shared<const Model>(p.scene);
  CsvWriter csv(dir + "/trajectories.csv",
                {"method", "step", "actuation", "bend_deg", "tip_x", "tip_y", "tip_z", "iterations",
                 "time_s", "cumulative_s", "energy", "residual_ratio", "status"});
  Totals t;
  for (const std::string& name : p.methods) RunMethod(p, model, name, &csv, &t, verbose);

  const double lowest = AddEnergyGaps(p, &t);
  nlohmann::json j;
  AddSpeedupVsBestNlp(p, &t, &j);
  for (const char* fem :
       {"calculix-nonlinear", "calculix-pressure-linear", "calculix-pressure-nonlinear"})
    AddSpeedupVsFem(p, model, fem, &t, &j);
  j["methods"] = t.methods;
  j["robot"] = p.robot;
  j["n_tets"] = p.scene.mesh.num_tets();
  j["n_vertices"] = p.scene.mesh.num_vertices();
  j["steps"] = p.steps;
  j["end_value"] = p.vmax;
  j["time_limit_s"] = p.budget;
  j["gradient_tolerance"] = p.base.gradient_tolerance;
  j["tolerance"] = p.base.tolerance;
  j["lowest_energy"] = std::isfinite(lowest) ? nlohmann::json(lowest) : nlohmann::json(nullptr);
  if (p.robot == "pneumatic_finger")
    j["thesis_table_2_2"] = {
        {"ours", {{"elements", 45802}, {"t90_s", 8.5}, {"t180_s", 15.2}, {"t240_s", 23.2}}},
        {"fem1_abaqus_linear",
         {{"elements", 44774}, {"t90_s", 240}, {"t180_s", 529}, {"t240_s", 820}}},
        {"fem2_abaqus_nonlinear",
         {{"elements", 44774}, {"t90_s", 288}, {"t180_s", 636}, {"t240_s", 1068}}},
        {"sofa", {{"elements", 44900}, {"t90_s", 3.8}}}};
  return j;
}

}  // namespace softkin
