#include "softkin/ik/nlopt_ik.hpp"

#include "softkin/ik/ik_problem.hpp"

#include <nlopt.hpp>

#include <cassert>
#include <sstream>
#include <vector>

namespace softkin {
namespace {

nlopt::algorithm Algorithm(IkMethod m) {
  switch (m) {
    case IkMethod::kNloptMma:
      return nlopt::LD_MMA;
    case IkMethod::kNloptLbfgs:
      return nlopt::LD_LBFGS;
    case IkMethod::kNloptSlsqp:
      return nlopt::LD_SLSQP;
    case IkMethod::kNloptCcsaq:
      return nlopt::LD_CCSAQ;
    case IkMethod::kNloptBobyqa:
      return nlopt::LN_BOBYQA;
    default:
      break;
  }
  assert(false && "not an NLopt method");
  return nlopt::LN_BOBYQA;
}

struct Context {
  IkProblem* problem = nullptr;
  IkSummary* summary = nullptr;
  bool stopped = false;  // by us: a failed evaluation or the budget
  IkTermination stop_reason = IkTermination::kSolverFailure;
  std::string stop_message;
};

double ObjectiveCallback(const std::vector<double>& x, std::vector<double>& grad, void* data) {
  Context& ctx = *static_cast<Context*>(data);
  IkProblem& P = *ctx.problem;
  std::string msg;
  IkTermination why;
  if (P.OutOfBudget(&why, &msg)) {
    ctx.stopped = true;
    ctx.stop_reason = why;
    ctx.stop_message = msg;
    throw nlopt::forced_stop();
  }
  const Eigen::VectorXd c = P.Project(Eigen::Map<const Eigen::VectorXd>(x.data(), x.size()));
  const IkPoint pt = P.Evaluate(c, !grad.empty());
  if (!pt.ok) {
    ctx.stopped = true;
    ctx.stop_reason = pt.failure;
    ctx.stop_message = pt.message;
    throw nlopt::forced_stop();
  }
  if (!grad.empty()) Eigen::Map<Eigen::VectorXd>(grad.data(), grad.size()) = pt.grad;
  ctx.summary->history.push_back(P.best_value());
  ++ctx.summary->iterations;
  return pt.value;
}

}  // namespace

IkResult SolveNlopt(Kinematics& kin, const Objective& objective,
                    const Eigen::Ref<const Eigen::VectorXd>& c0, const IkOptions& options) {
  IkProblem P(kin, objective, options);
  IkSummary S;
  Context ctx;
  ctx.problem = &P;
  ctx.summary = &S;
  const int n = P.n();
  std::vector<double> x(c0.data(), c0.data() + n);
  std::vector<double> lo(P.lower().data(), P.lower().data() + n);
  std::vector<double> hi(P.upper().data(), P.upper().data() + n);
  std::vector<double> xtol(n);
  for (int a = 0; a < n; ++a) xtol[a] = options.parameter_tolerance * P.range()[a];

  nlopt::result code = nlopt::FAILURE;
  std::string failure;  // NLopt's own error, if any
  try {
    nlopt::opt opt(Algorithm(options.method), static_cast<unsigned>(n));
    opt.set_lower_bounds(lo);
    opt.set_upper_bounds(hi);
    opt.set_min_objective(ObjectiveCallback, &ctx);
    opt.set_stopval(options.lambda);
    opt.set_ftol_rel(options.function_tolerance);
    opt.set_xtol_abs(xtol);
    opt.set_maxeval(options.max_evaluations);
    opt.set_maxtime(options.max_time_s);
    if (options.method == IkMethod::kNloptBobyqa) {
      std::vector<double> step(n);
      for (int a = 0; a < n; ++a) step[a] = 0.1 * P.range()[a];
      opt.set_initial_step(step);
    }
    double f = 0.0;
    code = opt.optimize(x, f);
  } catch (const nlopt::forced_stop&) {
    code = nlopt::FORCED_STOP;
  } catch (const nlopt::roundoff_limited&) {
    code = nlopt::ROUNDOFF_LIMITED;
  } catch (const std::invalid_argument& e) {
    code = nlopt::INVALID_ARGS;
    failure = e.what();
  } catch (const std::bad_alloc&) {
    code = nlopt::OUT_OF_MEMORY;
    failure = "out of memory";
  } catch (const std::exception& e) {  // nlopt's generic failure (std::runtime_error)
    code = nlopt::FAILURE;
    failure = e.what();
  }

  std::ostringstream m;
  if (P.has_best() && P.best_value() <= options.lambda) {
    S.termination = IkTermination::kConverged;
    m << "O = " << P.best_value() << " <= lambda = " << options.lambda;
  } else if (ctx.stopped) {
    S.termination = ctx.stop_reason;
    m << ctx.stop_message;
  } else {
    switch (code) {
      case nlopt::STOPVAL_REACHED:
        S.termination = IkTermination::kConverged;
        m << "NLopt: stopval reached";
        break;
      case nlopt::FTOL_REACHED:
        S.termination = IkTermination::kNoProgress;
        m << "NLopt: ftol_rel reached";
        break;
      case nlopt::XTOL_REACHED:
        S.termination = IkTermination::kNoProgress;
        m << "NLopt: xtol reached";
        break;
      case nlopt::SUCCESS:
        S.termination = IkTermination::kNoProgress;
        m << "NLopt: success (a local minimum above lambda)";
        break;
      case nlopt::ROUNDOFF_LIMITED:
        S.termination = IkTermination::kNoProgress;
        m << "NLopt: roundoff limited";
        break;
      case nlopt::MAXEVAL_REACHED:
        S.termination = IkTermination::kMaxEvaluations;
        m << "NLopt: maxeval = " << options.max_evaluations << " reached";
        break;
      case nlopt::MAXTIME_REACHED:
        S.termination = IkTermination::kMaxTime;
        m << "NLopt: maxtime = " << options.max_time_s << " s reached";
        break;
      default:
        S.termination = IkTermination::kSolverFailure;
        m << "NLopt failed (code " << static_cast<int>(code) << ")";
        if (!failure.empty()) m << ": " << failure;
        break;
    }
  }
  S.message = m.str();
  // history.front() is O(c0): every one of these algorithms evaluates x0 first.
  return P.Finish(c0, S);
}

}  // namespace softkin
