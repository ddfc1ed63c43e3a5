#include "softkin/solver/newton/auto_solver.hpp"

#include "softkin/solver/common/text_format.hpp"
#include "softkin/solver/fk/local_global.hpp"
#include "softkin/solver/newton/newton_solver.hpp"
#include "softkin/solver/sensitivity/equilibrium_jacobian.hpp"

#include <algorithm>
#include <chrono>
#include <stdexcept>

namespace softkin {

namespace {
using Clock = std::chrono::steady_clock;
double Seconds(Clock::time_point a, Clock::time_point b) {
  return std::chrono::duration<double>(b - a).count();
}
}  // namespace

AutoSolver::AutoSolver(std::shared_ptr<const Model> model, const FkOptions& options,
                       ContactTermFactory contacts)
    : FkSolver(std::move(model)), options_(options), contacts_(std::move(contacts)) {
  std::string why;
  if (!options_.IsValid(&why)) throw std::invalid_argument("solver options: " + why);
  newton_covers_ = EquilibriumJacobianUnsupported(*model_).empty() &&
                   !ContactHandlingActive(model_->scene(), options_.collision);
}

void AutoSolver::set_limits(const Limits& limits) {
  if (limits.lg_iterations < 1)
    throw std::invalid_argument("auto solver: lg_iterations must be an integer >= 1, got " +
                                std::to_string(limits.lg_iterations));
  if (!(limits.near_factor >= 1.0))
    throw std::invalid_argument("auto solver: near_factor must be a number >= 1, got " +
                                FormatNumber(limits.near_factor));
  limits_ = limits;
  lg_.reset();
}

std::unique_ptr<FkSolver> AutoSolver::Make(FkSolverType type, int max_iterations,
                                           double time_limit_s) const {
  FkOptions o = options_;
  o.solver = type;
  o.max_iterations = max_iterations;
  o.time_limit_s = time_limit_s;
  if (type == FkSolverType::kNewton) return std::make_unique<NewtonSolver>(model_, o, contacts_);
  return std::make_unique<LocalGlobalSolver>(model_, o, contacts_);
}

FkResult AutoSolver::SolveImpl(const Eigen::Ref<const Eigen::VectorXd>& c,
                               const Eigen::MatrixX3d* warm_start) {
  const auto t0 = Clock::now();
  const int cap = options_.max_iterations;
  const double limit = options_.time_limit_s;
  // The time left of this call's limit (0: none).
  auto left = [&]() { return limit > 0 ? std::max(1e-3, limit - Seconds(t0, Clock::now())) : 0.0; };
  const int first = newton_covers_ ? std::min(cap, limits_.lg_iterations) : cap;
  if (limit > 0 || !lg_) lg_ = Make(FkSolverType::kLgAa, first, limit);
  FkResult lg = lg_->Solve(c, warm_start);
  int lg_iterations = lg.iterations;
  double lg_local = lg.local_time_s, lg_global = lg.global_time_s;
  if (lg.status == FkStatus::IterationCap && lg.iterations < cap &&
      lg.gradient_ratio <= limits_.near_factor * options_.gradient_tolerance) {
    // Nearly there: one more round from where it stopped.
    const Eigen::MatrixX3d X = lg.positions;
    lg = Make(FkSolverType::kLgAa, std::min(limits_.lg_iterations, cap - lg_iterations), left())
             ->Solve(c, &X);
    lg_iterations += lg.iterations;
    lg_local += lg.local_time_s;
    lg_global += lg.global_time_s;
  }
  lg.iterations = lg_iterations;
  lg.local_time_s = lg_local;
  lg.global_time_s = lg_global;
  lg.solver = name();
  const bool switch_to_newton = lg.status == FkStatus::IterationCap && lg_iterations < cap;
  if (!switch_to_newton) {
    lg.time_s = Seconds(t0, Clock::now());
    return lg;
  }
  if (limit > 0 || !newton_) newton_ = Make(FkSolverType::kNewton, cap, left());
  FkResult r = newton_->Solve(c, warm_start);
  const std::string note = "auto: lg-aa had not converged after " + std::to_string(lg_iterations) +
                           " iterations (residual ratio " + FormatNumber(lg.gradient_ratio) +
                           "); solved with newton from " +
                           (warm_start ? "the warm start" : "the rest shape");
  r.message = r.message.empty() ? note : note + "; " + r.message;
  r.solver = name();
  r.iterations += lg_iterations;
  r.local_time_s += lg_local;
  r.global_time_s += lg_global;
  r.time_s = Seconds(t0, Clock::now());
  return r;
}

}  // namespace softkin
