#include "softkin/ik/ik_solver.hpp"

#include "softkin/ik/gauss_newton.hpp"
#include "softkin/ik/nlopt_ik.hpp"
#include "softkin/ik/soft_line_search.hpp"

#include <cmath>
#include <iomanip>
#include <sstream>
#include <stdexcept>
#include <utility>

namespace softkin {
namespace {

const std::vector<std::pair<IkMethod, const char*>>& MethodNames() {
  static const std::vector<std::pair<IkMethod, const char*>> names = {
      {IkMethod::kSoftLineSearch, "softls"},    {IkMethod::kNloptMma, "nlopt-mma"},
      {IkMethod::kNloptLbfgs, "nlopt-lbfgs"},   {IkMethod::kNloptSlsqp, "nlopt-slsqp"},
      {IkMethod::kNloptCcsaq, "nlopt-ccsaq"},   {IkMethod::kNloptBobyqa, "nlopt-bobyqa"},
      {IkMethod::kGaussNewton, "gauss-newton"}, {IkMethod::kBroyden, "broyden"}};
  return names;
}

const std::vector<std::pair<IkTermination, const char*>>& TerminationNames() {
  static const std::vector<std::pair<IkTermination, const char*>> names = {
      {IkTermination::kConverged, "converged"},
      {IkTermination::kNoProgress, "no-progress"},
      {IkTermination::kMaxIterations, "max-iterations"},
      {IkTermination::kMaxEvaluations, "max-evaluations"},
      {IkTermination::kMaxTime, "max-time"},
      {IkTermination::kKinematicsFailure, "kinematics-failure"},
      {IkTermination::kObjectiveFailure, "objective-failure"},
      {IkTermination::kSolverFailure, "solver-failure"}};
  return names;
}

}  // namespace

std::string IkMethodToString(IkMethod m) {
  for (const auto& [k, v] : MethodNames())
    if (k == m) return v;
  return "unknown";
}

bool StringToIkMethod(const std::string& s, IkMethod* m) {
  for (const auto& [k, v] : MethodNames())
    if (s == v) {
      *m = k;
      return true;
    }
  return false;
}

std::vector<IkMethod> AllIkMethods() {
  std::vector<IkMethod> out;
  for (const auto& kv : MethodNames()) out.push_back(kv.first);
  return out;
}

std::string IkMethodNames() {
  std::string s;
  for (const auto& kv : MethodNames()) s += (s.empty() ? "" : ", ") + std::string(kv.second);
  return s;
}

std::string IkGradientToString(IkGradient g) {
  return g == IkGradient::kJacobian ? "jacobian" : "central-difference";
}

bool StringToIkGradient(const std::string& s, IkGradient* g) {
  if (s == "jacobian")
    *g = IkGradient::kJacobian;
  else if (s == "central-difference")
    *g = IkGradient::kCentralDifference;
  else
    return false;
  return true;
}

std::string IkTerminationToString(IkTermination t) {
  for (const auto& [k, v] : TerminationNames())
    if (k == t) return v;
  return "unknown";
}

bool StringToIkTermination(const std::string& s, IkTermination* t) {
  for (const auto& [k, v] : TerminationNames())
    if (s == v) {
      *t = k;
      return true;
    }
  return false;
}

bool IkOptions::IsValid(std::string* why) const {
  std::ostringstream s;
  auto finite = [](double v) { return std::isfinite(v); };
  if (IkMethodToString(method) == "unknown")
    s << "method: unknown value";
  else if (!(finite(fd_step) && fd_step > 0 && fd_step <= 0.5))
    s << "fd_step must be in (0, 0.5], got " << fd_step;
  else if (!(finite(lambda) && lambda >= 0))
    s << "lambda must be >= 0, got " << lambda;
  else if (max_iterations < 1)
    s << "max_iterations must be >= 1, got " << max_iterations;
  else if (max_evaluations < 1)
    s << "max_evaluations must be >= 1, got " << max_evaluations;
  else if (!(finite(max_time_s) && max_time_s > 0))
    s << "max_time_s must be > 0, got " << max_time_s;
  else if (!(finite(function_tolerance) && function_tolerance >= 0))
    s << "function_tolerance must be >= 0, got " << function_tolerance;
  else if (!(finite(parameter_tolerance) && parameter_tolerance >= 0))
    s << "parameter_tolerance must be >= 0, got " << parameter_tolerance;
  else if (!(finite(tau) && tau > 0 && tau < 1))
    s << "tau must be in (0, 1), got " << tau;
  else if (max_shrinks < 1)
    s << "max_shrinks must be >= 1, got " << max_shrinks;
  else if (max_expansions < 0)
    s << "max_expansions must be >= 0, got " << max_expansions;
  else if (!(finite(initial_damping) && initial_damping > 0))
    s << "initial_damping must be > 0, got " << initial_damping;
  else if (!(finite(max_damping) && max_damping > initial_damping))
    s << "max_damping must be > initial_damping, got " << max_damping;
  else if (!initial_jacobian.allFinite())
    s << "initial_jacobian has a non-finite entry";
  if (why) *why = s.str();
  return s.str().empty();
}

std::string IkSummary::BriefReport() const {
  std::ostringstream s;
  s << IkMethodToString(method) << " (" << IkGradientToString(gradient)
    << "): " << IkTerminationToString(termination) << ", O " << std::setprecision(4)
    << initial_objective << " -> " << final_objective << " in " << iterations << " iterations, "
    << evaluations << " evaluations (" << jacobian_evaluations << " with J";
  if (secant_updates > 0) s << ", " << secant_updates << " secant updates";
  s << "), " << fk_solves << " FK solves, " << std::setprecision(3) << time_s * 1e3 << " ms";
  if (!message.empty()) s << "; " << message;
  return s.str();
}

IkResult SolveIk(Kinematics& kin, const Objective& objective,
                 const Eigen::Ref<const Eigen::VectorXd>& c0, const IkOptions& options) {
  std::string why;
  if (!options.IsValid(&why)) throw std::invalid_argument("IkOptions: " + why);
  why = CheckKinematicsInput(kin, c0);
  if (!why.empty()) throw std::invalid_argument("IK initial actuation c0: " + why);
  if (objective.num_points() != kin.num_points())
    throw std::invalid_argument("IK: the objective " + objective.name() + " was built for " +
                                std::to_string(objective.num_points()) + " tracked points, " +
                                kin.name() + " tracks " + std::to_string(kin.num_points()));
  switch (options.method) {
    case IkMethod::kSoftLineSearch:
      return SolveSoftLineSearch(kin, objective, c0, options);
    case IkMethod::kGaussNewton:
    case IkMethod::kBroyden:
      if (objective.num_residuals() == 0)
        throw std::invalid_argument("IK: " + IkMethodToString(options.method) +
                                    " needs a least-squares objective; " + objective.name() +
                                    " has none");
      if (options.method == IkMethod::kBroyden && options.initial_jacobian.size() > 0 &&
          (options.initial_jacobian.rows() != 3 * kin.num_points() ||
           options.initial_jacobian.cols() != kin.num_actuators()))
        throw std::invalid_argument(
            "IK: initial_jacobian is " + std::to_string(options.initial_jacobian.rows()) + " x " +
            std::to_string(options.initial_jacobian.cols()) +
            ", expected 3 #points x #actuators = " + std::to_string(3 * kin.num_points()) + " x " +
            std::to_string(kin.num_actuators()));
      return SolveGaussNewton(kin, objective, c0, options);
    default:
      return SolveNlopt(kin, objective, c0, options);
  }
}

}  // namespace softkin
