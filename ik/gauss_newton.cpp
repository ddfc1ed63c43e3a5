#include "softkin/ik/gauss_newton.hpp"

#include "softkin/ik/ik_problem.hpp"

#include <Eigen/Dense>

#include <cmath>
#include <limits>

namespace softkin {

IkResult SolveGaussNewton(Kinematics& kin, const Objective& objective,
                          const Eigen::Ref<const Eigen::VectorXd>& c0, const IkOptions& options) {
  IkProblem P(kin, objective, options);
  IkSummary S;
  const int n = P.n();
  const Eigen::VectorXd range = P.range();

  Eigen::VectorXd r;
  Eigen::MatrixXd dr_dc;
  // Evaluates (with J) at c and the residual Jacobian; false with S filled on failure.
  auto evaluate_at = [&](const Eigen::VectorXd& c, IkPoint* pt, const char* where) {
    *pt = P.Evaluate(c, false, true);
    if (!pt->ok) {
      S.termination = pt->failure;
      S.message = std::string(where) + pt->message;
      return false;
    }
    try {
      P.Residuals(*pt, &r, &dr_dc);
    } catch (const ObjectiveError& e) {
      S.termination = IkTermination::kObjectiveFailure;
      S.message = std::string(where) + objective.name() + ": " + e.what();
      return false;
    }
    return true;
  };

  // broyden: J of `cur` is secant-updated (not fresh) until a step fails with it.
  const bool broyden = options.method == IkMethod::kBroyden;
  bool fresh = true;
  // cur.J -> r, dr_dc without a new evaluation (broyden's updated J); false with S filled.
  auto residuals_of = [&](const IkPoint& pt, const char* where) {
    try {
      P.Residuals(pt, &r, &dr_dc);
    } catch (const ObjectiveError& e) {
      S.termination = IkTermination::kObjectiveFailure;
      S.message = std::string(where) + objective.name() + ": " + e.what();
      return false;
    }
    return true;
  };

  IkPoint cur;
  Eigen::VectorXd c = c0;
  auto finish = [&]() {
    IkResult res = P.Finish(c0, S);
    if (broyden && cur.J.size() > 0 && res.c == c) res.J = cur.J;
    return res;
  };
  if (broyden && options.initial_jacobian.size() > 0) {
    cur = P.Evaluate(c0, false);
    if (!cur.ok) {
      S.termination = cur.failure;
      S.message = "at c0: " + cur.message;
      return finish();
    }
    cur.J = options.initial_jacobian;
    fresh = false;
    if (!residuals_of(cur, "at c0: ")) return finish();
  } else if (!evaluate_at(c0, &cur, "at c0: ")) {
    return finish();
  }
  S.history.push_back(cur.value);
  double mu = -1.0;

  while (true) {
    if (P.Finished(cur.value, S.iterations, &S)) break;
    const Eigen::MatrixXd A = dr_dc * range.asDiagonal();
    const Eigen::VectorXd g = A.transpose() * r;
    const Eigen::MatrixXd H = A.transpose() * A;
    if (mu < 0.0) mu = options.initial_damping * std::max(H.diagonal().maxCoeff(), 1e-300);
    std::vector<int> free;
    for (int a = 0; a < n; ++a) {
      const bool blocked = range[a] <= 0.0 || (c[a] <= P.lower()[a] && g[a] > 0) ||
                           (c[a] >= P.upper()[a] && g[a] < 0);
      if (!blocked) free.push_back(a);
    }
    if (free.empty()) {
      S.termination = IkTermination::kNoProgress;
      S.message = "the projected gradient is zero (a stationary point on the box)";
      break;
    }
    const int nf = static_cast<int>(free.size());
    Eigen::MatrixXd Hf(nf, nf);
    Eigen::VectorXd gf(nf);
    for (int i = 0; i < nf; ++i) {
      gf[i] = g[free[i]];
      for (int j = 0; j < nf; ++j) Hf(i, j) = H(free[i], free[j]);
    }
    bool accepted = false, budget = true, refresh = false;
    double o_trial = 0.0;
    Eigen::VectorXd c_trial;
    Eigen::MatrixX3d p_trial;
    while (mu <= options.max_damping) {
      const Eigen::VectorXd duf = (Hf + mu * Eigen::MatrixXd::Identity(nf, nf)).ldlt().solve(-gf);
      Eigen::VectorXd dc = Eigen::VectorXd::Zero(n);
      for (int i = 0; i < nf; ++i) dc[free[i]] = range[free[i]] * duf[i];
      c_trial = P.Project(c + dc);
      if (c_trial == c) {
        mu *= 10.0;
        continue;
      }
      std::string msg;
      if (P.OutOfBudget(&S.termination, &msg)) {
        S.message = msg;
        budget = false;
        break;
      }
      const IkPoint t = P.Evaluate(c_trial, false);
      if (t.ok && t.value < cur.value) {
        accepted = true;
        o_trial = t.value;
        p_trial = t.p;
        mu = std::max(mu / 10.0, 1e-300);
        break;
      }
      if (broyden && !fresh) {  // the updated J may be what failed: evaluate J before damping
        refresh = true;
        break;
      }
      mu *= 10.0;
    }
    if (!budget) break;
    if (refresh) {
      std::string msg;
      if (P.OutOfBudget(&S.termination, &msg)) {
        S.message = msg;
        break;
      }
      if (!evaluate_at(c, &cur, "re-evaluating J after a failed secant step: ")) break;
      fresh = true;
      continue;
    }
    if (!accepted) {
      S.termination = IkTermination::kNoProgress;
      S.message = "no decrease with damping up to max_damping";
      break;
    }
    const double step =
        ((c_trial - c).cwiseAbs().cwiseQuotient(range.cwiseMax(std::numeric_limits<double>::min())))
            .maxCoeff();
    const double o_prev = cur.value;
    const bool step_had_fresh_j = fresh;
    if (broyden) {
      // Broyden's update in the scaled coordinates u (minimal change of J diag(range) in the
      // Frobenius norm): J += (dp - J dc) w^T / (dc^T w), w = dc / range^2.
      const Eigen::VectorXd dc = c_trial - c;
      const Eigen::VectorXd w =
          dc.cwiseQuotient(range.cwiseMax(std::numeric_limits<double>::min()).cwiseAbs2());
      const double den = dc.dot(w);
      const int np = static_cast<int>(p_trial.rows());
      Eigen::VectorXd dp(3 * np);
      for (int q = 0; q < np; ++q)
        for (int d = 0; d < 3; ++d) dp[3 * q + d] = p_trial(q, d) - cur.p(q, d);
      if (den > 0.0 && std::isfinite(den)) {
        cur.J += (dp - cur.J * dc) * (w.transpose() / den);
        ++S.secant_updates;
      }
      cur.p = p_trial;
      cur.value = o_trial;
      fresh = false;
    }
    c = c_trial;
    ++S.iterations;
    std::string msg;
    if (P.OutOfBudget(&S.termination, &msg)) {
      S.message = msg;
      S.history.push_back(o_trial);
      break;
    }
    // The trial already gave O at c: decide whether to stop before paying for J there (on the
    // simulator a Jacobian costs about one forward solve). The loop's stopping tests see the
    // same value, since the kinematics at the same c give the same p.
    if (o_trial > options.lambda && P.Stalled(o_prev, o_trial, step, &S)) {
      if (broyden && !step_had_fresh_j) {
        // A stall with a secant-updated J may be the update's fault: evaluate J at c and go on.
        S.termination = IkTermination::kSolverFailure;
        S.message.clear();
        S.history.push_back(o_trial);
        if (P.OutOfBudget(&S.termination, &msg)) {
          S.message = msg;
          break;
        }
        if (!evaluate_at(c, &cur, "at an accepted point: ")) break;
        fresh = true;
        continue;
      }
      S.history.push_back(o_trial);
      break;
    }
    if (broyden) {
      S.history.push_back(o_trial);
      if (!residuals_of(cur, "at an accepted point: ")) break;
      continue;  // converged / i_max are reported at the top of the loop
    }
    if (o_trial <= options.lambda || S.iterations >= options.max_iterations) {
      S.history.push_back(o_trial);
      cur.value = o_trial;
      continue;  // converged or i_max: reported at the top of the loop
    }
    if (!evaluate_at(c, &cur, "at an accepted point: ")) {
      S.history.push_back(o_trial);
      break;
    }
    S.history.push_back(cur.value);
  }
  return finish();
}

}  // namespace softkin
