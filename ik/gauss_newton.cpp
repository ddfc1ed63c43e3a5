#include "ik/gauss_newton.hpp"

#include "ik/ik_problem.hpp"

#include <Eigen/Dense>

#include <limits>
#include <sstream>

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

  IkPoint cur;
  if (!evaluate_at(c0, &cur, "at c0: ")) return P.Finish(c0, S);
  S.history.push_back(cur.value);
  Eigen::VectorXd c = c0;
  double mu = -1.0;

  while (true) {
    if (cur.value <= options.lambda) {
      S.termination = IkTermination::kConverged;
      std::ostringstream m;
      m << "O = " << cur.value << " <= lambda = " << options.lambda;
      S.message = m.str();
      break;
    }
    if (S.iterations >= options.max_iterations) {
      S.termination = IkTermination::kMaxIterations;
      S.message = "reached i_max = " + std::to_string(options.max_iterations);
      break;
    }
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
    bool accepted = false, budget = true;
    double o_trial = 0.0;
    Eigen::VectorXd c_trial;
    while (mu <= options.max_damping) {
      const Eigen::VectorXd duf =
          (Hf + mu * Eigen::MatrixXd::Identity(nf, nf)).ldlt().solve(-gf);
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
        mu = std::max(mu / 10.0, 1e-300);
        break;
      }
      mu *= 10.0;
    }
    if (!budget) break;
    if (!accepted) {
      S.termination = IkTermination::kNoProgress;
      S.message = "no decrease with damping up to max_damping";
      break;
    }
    const double step = ((c_trial - c).cwiseAbs().cwiseQuotient(
                             range.cwiseMax(std::numeric_limits<double>::min())))
                            .maxCoeff();
    const double o_prev = cur.value;
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
      S.history.push_back(o_trial);
      break;
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
  return P.Finish(c0, S);
}

}  // namespace softkin
