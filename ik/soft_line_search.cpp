#include "softkin/ik/soft_line_search.hpp"

#include "softkin/ik/ik_problem.hpp"

#include <limits>
#include <sstream>

namespace softkin {

IkResult SolveSoftLineSearch(Kinematics& kin, const Objective& objective,
                             const Eigen::Ref<const Eigen::VectorXd>& c0,
                             const IkOptions& options) {
  IkProblem P(kin, objective, options);
  IkSummary S;
  const int n = P.n();
  const double kInf = std::numeric_limits<double>::infinity();

  IkPoint cur = P.Evaluate(c0, true);
  if (!cur.ok) {
    S.termination = cur.failure;
    S.message = "at c0: " + cur.message;
    return P.Finish(c0, S);
  }
  S.history.push_back(cur.value);
  Eigen::VectorXd c = c0;
  const Eigen::VectorXd scale = options.normalize_by_range ? Eigen::VectorXd(P.range().cwiseAbs2())
                                                           : Eigen::VectorXd::Ones(n);

  std::string last_trial_failure;
  // O at a trial point, +inf if it cannot be evaluated; false when the budget is exhausted.
  auto trial = [&](const Eigen::VectorXd& ct, double* o) {
    std::string msg;
    if (P.OutOfBudget(&S.termination, &msg)) {
      S.message = msg;
      return false;
    }
    const IkPoint t = P.Evaluate(ct, false);
    if (!t.ok) last_trial_failure = t.message;
    *o = t.ok ? t.value : kInf;
    return true;
  };

  while (true) {
    if (P.Finished(cur.value, S.iterations, &S)) break;
    // Descent direction, blocked components removed.
    Eigen::VectorXd d = -scale.cwiseProduct(cur.grad);
    for (int a = 0; a < n; ++a)
      if ((c[a] <= P.lower()[a] && d[a] < 0) || (c[a] >= P.upper()[a] && d[a] > 0)) d[a] = 0.0;
    if (d.cwiseAbs().maxCoeff() == 0.0) {
      S.termination = IkTermination::kNoProgress;
      S.message = "the projected gradient is zero (a stationary point on the box)";
      break;
    }
    // Step 1: shrinking.
    double dh = 1.0, o_new = kInf;
    Eigen::VectorXd c_new = P.Project(c + dh * d);
    bool budget = trial(c_new, &o_new);
    int shrinks = 0;
    // A trial that moves every actuator by at most parameter_tolerance of its range would end the
    // search as a stall if accepted; below that scale a simulator's O is its solver's noise, so
    // shrinking further only spends forward solves (cable_finger: 17 solves down to 1e-19).
    auto below_tolerance = [&](const Eigen::VectorXd& ct) {
      return ((ct - c).cwiseAbs().cwiseQuotient(
                  P.range().cwiseMax(std::numeric_limits<double>::min())))
                 .maxCoeff() <= options.parameter_tolerance;
    };
    bool tiny = false;
    while (budget && !(o_new < cur.value) && shrinks < options.max_shrinks) {
      dh *= options.tau;
      ++shrinks;
      c_new = P.Project(c + dh * d);
      if (c_new == c || below_tolerance(c_new)) {
        tiny = true;
        break;
      }
      budget = trial(c_new, &o_new);
    }
    if (!budget) break;
    if (!(o_new < cur.value)) {
      S.termination = IkTermination::kNoProgress;
      std::ostringstream m;
      m << "no decrease along -grad after " << shrinks << " shrinking steps (Delta h = " << dh
        << (tiny ? ", the step below parameter_tolerance" : "") << ")";
      if (!last_trial_failure.empty()) m << "; last failed trial: " << last_trial_failure;
      S.message = m.str();
      break;
    }
    // Step 2: expanding.
    double h = dh, o_opt = o_new;
    Eigen::VectorXd c_opt = c_new;
    for (int e = 0; e < options.max_expansions; ++e) {
      const Eigen::VectorXd c_try = P.Project(c + (h + dh) * d);
      if (c_try == c_opt) break;  // the projection stopped moving
      double o_try = kInf;
      if (!trial(c_try, &o_try)) {
        budget = false;
        break;
      }
      if (!(o_try < o_opt)) break;
      o_opt = o_try;
      h += dh;
      c_opt = c_try;
    }
    // Accept (a strict decrease by construction).
    const double o_prev = cur.value;
    const double step = ((c_opt - c).cwiseAbs().cwiseQuotient(
                             P.range().cwiseMax(std::numeric_limits<double>::min())))
                            .maxCoeff();
    c = c_opt;
    ++S.iterations;
    if (!budget) {  // out of budget during the expansion: keep the accepted point
      S.history.push_back(o_opt);
      break;
    }
    std::string msg;
    if (P.OutOfBudget(&S.termination, &msg)) {
      S.message = msg;
      S.history.push_back(o_opt);
      break;
    }
    cur = P.Evaluate(c, true);
    if (!cur.ok) {
      S.termination = cur.failure;
      S.message = "at an accepted point: " + cur.message;
      S.history.push_back(o_opt);
      break;
    }
    S.history.push_back(cur.value);
    if (cur.value <= options.lambda) continue;  // reported as converged at the loop's top
    if (P.Stalled(o_prev, cur.value, step, &S)) break;
  }
  return P.Finish(c0, S);
}

}  // namespace softkin
