#pragma once
/// \file
/// Inverse kinematics (thesis Ch. 4): minimise an Objective O(p(c)) over the box-bounded
/// actuation c in [c_min, c_max] of a Kinematics. One entry point, SolveIk, dispatches to
///  - `softls`: Algorithm 3, gradient descent with the soft line search (ik/soft_line_search.hpp);
///  - `nlopt-mma`, `nlopt-lbfgs`, `nlopt-slsqp`, `nlopt-ccsaq`, `nlopt-bobyqa`: NLopt's LD_MMA,
///    LD_LBFGS, LD_SLSQP, LD_CCSAQ and (derivative-free) LN_BOBYQA with bounds (ik/nlopt_ik.hpp);
///  - `gauss-newton`: damped least squares on the residual Jacobian (ik/gauss_newton.hpp);
///  - `broyden`: the same steps with J from the Kinematics only at the start (none when one is
///    handed over in IkOptions::initial_jacobian) and after a failed step, and Broyden's secant
///    update in between (ik/gauss_newton.hpp).
/// Options follow the Ceres pattern (IsValid), results come with an IkSummary (termination type,
/// message, iterations, objective history, evaluation and FK counts, time, BriefReport()).

#include "softkin/ik/kinematics.hpp"
#include "softkin/ik/objectives.hpp"

#include <Eigen/Core>

#include <string>
#include <vector>

namespace softkin {

enum class IkMethod {
  kSoftLineSearch,  ///< "softls"
  kNloptMma,        ///< "nlopt-mma"   (LD_MMA)
  kNloptLbfgs,      ///< "nlopt-lbfgs" (LD_LBFGS)
  kNloptSlsqp,      ///< "nlopt-slsqp" (LD_SLSQP)
  kNloptCcsaq,      ///< "nlopt-ccsaq" (LD_CCSAQ)
  kNloptBobyqa,     ///< "nlopt-bobyqa" (LN_BOBYQA, derivative-free)
  kGaussNewton,     ///< "gauss-newton"
  kBroyden,         ///< "broyden" (gauss-newton with secant-updated J)
};
std::string IkMethodToString(IkMethod m);
/// false (and *m untouched) for an unknown name.
bool StringToIkMethod(const std::string& s, IkMethod* m);
/// Every method, in enum order.
std::vector<IkMethod> AllIkMethods();
/// "softls, nlopt-mma, ..." for error messages and CLI help.
std::string IkMethodNames();

/// Where dO/dc comes from.
enum class IkGradient {
  kJacobian,           ///< "jacobian": dO/dc = J^T dO/dp, with J from the Kinematics
  kCentralDifference,  ///< "central-difference": Eq. 4.2 on O(c), 2 #actuators evaluations
};
std::string IkGradientToString(IkGradient g);
bool StringToIkGradient(const std::string& s, IkGradient* g);

struct IkOptions {
  IkMethod method = IkMethod::kSoftLineSearch;
  IkGradient gradient = IkGradient::kJacobian;
  /// Central-difference step, as a fraction of each actuator's range (Eq. 4.2's Delta c); a probe
  /// that would leave the box becomes one-sided. In (0, 0.5].
  double fd_step = 1e-4;
  /// lambda: stop as soon as O <= lambda (units of O: mm^2 for the objectives in objectives.hpp;
  /// the thesis's 0.2 mm distance is lambda = 0.2^2 = 0.04 for point tracking). >= 0.
  double lambda = 0.04;
  /// i_max: iterations of softls / gauss-newton (the thesis uses 30 per waypoint). NLopt has no
  /// iteration notion; it is bounded by max_evaluations. >= 1.
  int max_iterations = 30;
  /// Cap on objective evaluations (each is one Kinematics::Evaluate, or 2 #actuators + 0 with
  /// central differences counted one by one), for every method. >= 1.
  int max_evaluations = 300;
  /// Wall-time cap, s (> 0).
  double max_time_s = 60.0;
  /// Stop when an accepted step lowers O by less than this fraction of O (NLopt ftol_rel). >= 0.
  double function_tolerance = 1e-12;
  /// Stop when an accepted step moves every actuator by less than this fraction of its range
  /// (NLopt xtol_abs = this times the range). >= 0.
  double parameter_tolerance = 1e-10;

  // ---- softls (Algorithm 3) ----
  double tau = 0.1;         ///< shrink ratio of the step, in (0, 1)
  int max_shrinks = 30;     ///< shrinking steps before giving up on descent (>= 1)
  int max_expansions = 50;  ///< expanding steps per line search (>= 0)
  /// Search along -grad in coordinates scaled to [0, 1] per actuator (direction component a
  /// multiplied by range_a^2), so that Delta h = 1 means the same for actuators of any unit. false
  /// is the thesis's raw gradient.
  bool normalize_by_range = true;

  // ---- gauss-newton ----
  double initial_damping = 1e-3;  ///< Levenberg mu at the start, relative to max diag(J^T J) (> 0)
  double max_damping = 1e12;      ///< give up when mu exceeds this (> initial_damping)

  // ---- broyden ----
  /// dp/dc at c0 (3 #points x #actuators, e.g. IkResult::J of the previous waypoint), used instead
  /// of evaluating J there. Empty: J is evaluated at c0. Ignored by the other methods. Must be
  /// finite; its size is checked against the kinematics.
  Eigen::MatrixXd initial_jacobian;

  /// True if every field is in range; else false and *why (if given) names the field.
  bool IsValid(std::string* why) const;
};

enum class IkTermination {
  kConverged,          ///< "converged": O <= lambda
  kNoProgress,         ///< "no-progress": a (local) minimum above lambda: no descent step, or
                       ///< the function / parameter tolerance was met
  kMaxIterations,      ///< "max-iterations": i_max reached above lambda
  kMaxEvaluations,     ///< "max-evaluations"
  kMaxTime,            ///< "max-time"
  kKinematicsFailure,  ///< "kinematics-failure": Kinematics::Evaluate returned ok = false
  kObjectiveFailure,   ///< "objective-failure": the objective is undefined (ObjectiveError)
  kSolverFailure,      ///< "solver-failure": the optimiser itself failed (e.g. NLopt's codes)
};
std::string IkTerminationToString(IkTermination t);
bool StringToIkTermination(const std::string& s, IkTermination* t);

struct IkSummary {
  IkMethod method = IkMethod::kSoftLineSearch;
  IkGradient gradient = IkGradient::kJacobian;
  IkTermination termination = IkTermination::kSolverFailure;
  std::string message;  ///< why it stopped, in words
  int iterations = 0;   ///< accepted steps (softls, gauss-newton); evaluations (NLopt)
  /// O at the start and after each iteration (softls, gauss-newton), or the best O so far after
  /// each evaluation (NLopt); history.front() is O(c0) when c0 could be evaluated.
  std::vector<double> history;
  int evaluations = 0;           ///< Kinematics::Evaluate calls
  int jacobian_evaluations = 0;  ///< of which with the Jacobian
  int secant_updates = 0;        ///< broyden: rank-one updates of J (0 for the other methods)
  long long fk_solves = 0;       ///< forward solves they took (Kinematics::total_fk_solves delta)
  double time_s = 0.0;           ///< wall time
  double initial_objective = 0.0;
  double final_objective = 0.0;
  /// converged or not, one line: "softls: converged, O 0.3 -> 0.01 in 5 iterations, ..."
  std::string BriefReport() const;
  bool converged() const { return termination == IkTermination::kConverged; }
};

struct IkResult {
  Eigen::VectorXd c;       ///< #actuators, the best actuation found (within the box)
  Eigen::MatrixX3d p;      ///< #points x 3, the tracked points at c, mm
  double objective = 0.0;  ///< O(p(c))
  /// Body elements inverted in the simulated state at c (KinematicsEval): > 0 means p is not a
  /// physical answer, whatever the termination says about the objective.
  int inverted_elements = 0;
  double min_volume_ratio = 1.0;
  /// broyden only: its dp/dc at c (evaluated or secant-updated), to hand to the next solve as
  /// IkOptions::initial_jacobian; empty for the other methods or when c is not its last iterate.
  Eigen::MatrixXd J;
  IkSummary summary;
};

/// Minimises `objective` over c in [kin.lower(), kin.upper()] from c0.
/// Throws std::invalid_argument for invalid options, a c0 of the wrong size / non-finite / outside
/// the box, or an objective built for another number of tracked points. Every failure after that
/// (kinematics, objective, optimiser) is reported in the summary; no other exception escapes.
/// If c0 itself cannot be evaluated, the result has c = c0, an empty p and objective 0 with the
/// failure termination.
IkResult SolveIk(Kinematics& kin, const Objective& objective,
                 const Eigen::Ref<const Eigen::VectorXd>& c0, const IkOptions& options);

}  // namespace softkin
