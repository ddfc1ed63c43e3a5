#include "softkin/solver/newton/auto_solver.hpp"

#include "softkin/solver/common/text_format.hpp"
#include "softkin/solver/newton/newton_solver.hpp"
#include "softkin/solver/sensitivity/equilibrium_jacobian.hpp"
#include "softkin/solver/common/stopwatch.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <stdexcept>

namespace softkin {

namespace {
using Clock = std::chrono::steady_clock;
}  // namespace

AutoSolver::AutoSolver(std::shared_ptr<const Model> model, const FkOptions& options,
                       ContactTermFactory contacts)
    : FkSolver(std::move(model)), options_(options), contacts_(std::move(contacts)) {
  std::string why;
  if (!options_.IsValid(&why)) throw std::invalid_argument("solver options: " + why);
  contacts_active_ = ContactHandlingActive(model_->scene(), options_.collision);
  set_limits(limits_);
}

void AutoSolver::set_limits(const Limits& limits) {
  if (limits.lg_iterations < 1)
    throw std::invalid_argument("auto solver: lg_iterations must be an integer >= 1, got " +
                                std::to_string(limits.lg_iterations));
  if (!(limits.near_factor >= 1.0))
    throw std::invalid_argument("auto solver: near_factor must be a number >= 1, got " +
                                FormatNumber(limits.near_factor));
  if (!(limits.newton_time_factor > 0.0) || !std::isfinite(limits.newton_time_factor))
    throw std::invalid_argument("auto solver: newton_time_factor must be a number > 0, got " +
                                FormatNumber(limits.newton_time_factor));
  limits_ = limits;
  lg_ = std::make_unique<LocalGlobalSolver>(
      model_, With(FkSolverType::kLgAa, options_.max_iterations, options_.time_limit_s), contacts_);
}

FkOptions AutoSolver::With(FkSolverType type, int max_iterations, double time_limit_s) const {
  FkOptions o = options_;
  o.solver = type;
  o.max_iterations = max_iterations;
  o.time_limit_s = time_limit_s;
  return o;
}

FkResult AutoSolver::SolveImpl(const Eigen::Ref<const Eigen::VectorXd>& c,
                               const Eigen::MatrixX3d* warm_start) {
  const auto t0 = Clock::now();
  // With contacts, only a solve from the rest shape may switch (the header says why).
  const bool may_switch = (!contacts_active_ || warm_start == nullptr) &&
                          limits_.lg_iterations < options_.max_iterations;
  lg_->set_checkpoint(may_switch ? limits_.lg_iterations : 0,
                      limits_.near_factor * options_.gradient_tolerance);
  FkResult lg = lg_->Solve(c, warm_start);
  lg.solver = name();
  // Stopped at the checkpoint: an iteration cap below the user's.
  const bool stopped =
      may_switch && lg.status == FkStatus::IterationCap && lg.iterations < options_.max_iterations;
  if (!stopped) return lg;

  // newton from the same start, within its budget and the user's time limit.
  const double limit = options_.time_limit_s;
  auto left = [&]() { return limit > 0 ? std::max(1e-3, limit - Seconds(t0, Clock::now())) : 0.0; };
  const double budget = limits_.newton_time_factor * Seconds(t0, Clock::now());
  const bool user_bound = limit > 0 && left() <= budget;
  NewtonSolver newton(
      model_, With(FkSolverType::kNewton, options_.max_iterations, user_bound ? left() : budget),
      contacts_);
  FkResult nw = newton.Solve(c, warm_start);
  std::string note = "auto: lg-aa was at residual ratio " + FormatNumber(lg.gradient_ratio) +
                     " after " + std::to_string(lg.iterations) + " iterations; newton from " +
                     (warm_start ? "the warm start" : "the rest shape");
  // The result, and the counts of the solves that are not in it.
  FkResult r;
  int iterations = lg.iterations;
  double local_s = lg.local_time_s, global_s = lg.global_time_s;
  if (nw.status == FkStatus::Converged || nw.status == FkStatus::Inverted) {
    r = std::move(nw);
    note += " solved it";
  } else if (user_bound) {
    // The user's time is up. newton's last state may belong to an intermediate load step, so
    // the answer is lg-aa's state at the checkpoint, never a worse one.
    note += std::string(" had not converged when the time limit ran out (") +
            FkStatusToString(nw.status) + ", " + std::to_string(nw.iterations) +
            " iterations); returned lg-aa's state";
    iterations = nw.iterations;
    local_s = nw.local_time_s;
    global_s = nw.global_time_s;
    r = std::move(lg);
    r.linear_iterations = nw.linear_iterations;
    r.status = FkStatus::TimeLimit;
    r.message = "time limit of " + FormatNumber(limit) + " s reached";
  } else {
    // newton did not make it within its budget: lg-aa goes on from where it stopped. With
    // contacts that state may belong to one of lg-aa's intermediate stages (a load step cut back
    // where the contact response tangled), and a new solve from it at the full actuation would
    // start without that solve's springs (on membrane res 32 it tangled at once, docs/newton.md),
    // so lg-aa solves again from the same start (the rest shape), whole.
    const bool again = contacts_active_;
    note += " had not converged after " + FormatNumber(budget, 3) + " s (" +
            FkStatusToString(nw.status) + ", " + std::to_string(nw.iterations) + " iterations); " +
            (again ? "solved again with lg-aa from the rest shape"
                   : "continued with lg-aa from where it stopped");
    const Eigen::MatrixX3d X = lg.positions;
    LocalGlobalSolver rest(
        model_,
        With(FkSolverType::kLgAa, options_.max_iterations - (again ? 0 : lg.iterations), left()),
        contacts_);
    r = rest.Solve(c, again ? warm_start : &X);
    iterations += nw.iterations;
    local_s += nw.local_time_s;
    global_s += nw.global_time_s;
    r.linear_iterations = nw.linear_iterations;
  }
  r.message = r.message.empty() ? note : note + "; " + r.message;
  r.solver = name();
  r.iterations += iterations;
  r.local_time_s += local_s;
  r.global_time_s += global_s;
  r.time_s = Seconds(t0, Clock::now());
  return r;
}

}  // namespace softkin
