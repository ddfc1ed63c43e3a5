#include "softkin/ik/ik_problem.hpp"
#include "softkin/solver/common/stopwatch.hpp"

#include <cmath>
#include <sstream>

namespace softkin {

IkProblem::IkProblem(Kinematics& kin, const Objective& objective, const IkOptions& options)
    : kin_(kin),
      objective_(objective),
      options_(options),
      range_(kin.upper() - kin.lower()),
      start_(std::chrono::steady_clock::now()),
      fk_start_(kin.total_fk_solves()) {}

Eigen::VectorXd IkProblem::Project(const Eigen::Ref<const Eigen::VectorXd>& c) const {
  return c.cwiseMax(lower()).cwiseMin(upper());
}

double IkProblem::elapsed_s() const { return SecondsSince(start_); }

bool IkProblem::Stalled(double o_prev, double o_now, double step, IkSummary* summary) const {
  if (o_prev - o_now <= options_.function_tolerance * o_prev) {
    summary->termination = IkTermination::kNoProgress;
    summary->message = "relative decrease of O below function_tolerance";
    return true;
  }
  if (step <= options_.parameter_tolerance) {
    summary->termination = IkTermination::kNoProgress;
    summary->message = "step below parameter_tolerance (fraction of the range)";
    return true;
  }
  return false;
}

bool IkProblem::Finished(double value, int iterations, IkSummary* summary) const {
  if (value <= options_.lambda) {
    summary->termination = IkTermination::kConverged;
    std::ostringstream m;
    m << "O = " << value << " <= lambda = " << options_.lambda;
    summary->message = m.str();
    return true;
  }
  if (iterations >= options_.max_iterations) {
    summary->termination = IkTermination::kMaxIterations;
    summary->message = "reached i_max = " + std::to_string(options_.max_iterations);
    return true;
  }
  return false;
}

bool IkProblem::OutOfBudget(IkTermination* why, std::string* message) const {
  std::ostringstream s;
  if (evaluations_ >= options_.max_evaluations) {
    *why = IkTermination::kMaxEvaluations;
    s << "reached max_evaluations = " << options_.max_evaluations;
  } else if (elapsed_s() >= options_.max_time_s) {
    *why = IkTermination::kMaxTime;
    s << "reached max_time_s = " << options_.max_time_s;
  } else {
    return false;
  }
  *message = s.str();
  return true;
}

IkPoint IkProblem::EvaluateOnce(const Eigen::Ref<const Eigen::VectorXd>& c, bool with_jacobian,
                                bool track_best) {
  IkPoint pt;
  ++evaluations_;
  if (with_jacobian) ++jacobian_evaluations_;
  KinematicsEval e = kin_.Evaluate(c, with_jacobian);
  if (!e.ok) {
    pt.failure = IkTermination::kKinematicsFailure;
    pt.message = kin_.name() + ": " + e.message;
    return pt;
  }
  if (e.p.rows() != objective_.num_points() || !e.p.allFinite() ||
      (with_jacobian &&
       (e.J.rows() != 3 * e.p.rows() || e.J.cols() != c.size() || !e.J.allFinite()))) {
    pt.failure = IkTermination::kKinematicsFailure;
    pt.message = kin_.name() + ": returned non-finite or wrongly sized points / Jacobian";
    return pt;
  }
  Eigen::MatrixX3d g;
  try {
    pt.value = objective_.Evaluate(e.p, with_jacobian ? &g : nullptr);
  } catch (const ObjectiveError& err) {
    pt.failure = IkTermination::kObjectiveFailure;
    pt.message = objective_.name() + ": " + err.what();
    return pt;
  }
  if (!std::isfinite(pt.value)) {
    pt.failure = IkTermination::kObjectiveFailure;
    pt.message = objective_.name() + ": non-finite value";
    return pt;
  }
  if (with_jacobian) pt.grad = GradientWrtActuation(e.J, g);
  pt.ok = true;
  pt.p = std::move(e.p);
  pt.J = std::move(e.J);
  if (track_best && (!has_best_ || pt.value < best_value_)) {
    has_best_ = true;
    best_c_ = c;
    best_value_ = pt.value;
    best_p_ = pt.p;
    best_inverted_ = e.inverted_elements;
    best_min_volume_ratio_ = e.min_volume_ratio;
  }
  return pt;
}

IkPoint IkProblem::Evaluate(const Eigen::Ref<const Eigen::VectorXd>& c, bool with_gradient,
                            bool with_jacobian_too) {
  const bool jac =
      with_jacobian_too || (with_gradient && options_.gradient == IkGradient::kJacobian);
  IkPoint pt = EvaluateOnce(c, jac, true);
  if (!pt.ok || !with_gradient || jac) return pt;
  // Eq. 4.2: central differences on O, one-sided where a probe would leave the box.
  pt.grad.resize(c.size());
  for (int a = 0; a < c.size(); ++a) {
    const double h = options_.fd_step * range_[a];
    Eigen::VectorXd cp = c, cm = c;
    cp[a] = std::min(c[a] + h, upper()[a]);
    cm[a] = std::max(c[a] - h, lower()[a]);
    const IkPoint fp = EvaluateOnce(cp, false, false);
    if (!fp.ok) return fp;
    const IkPoint fm = EvaluateOnce(cm, false, false);
    if (!fm.ok) return fm;
    pt.grad[a] = cp[a] > cm[a] ? (fp.value - fm.value) / (cp[a] - cm[a]) : 0.0;
  }
  return pt;
}

bool IkProblem::Residuals(const IkPoint& at, Eigen::VectorXd* r, Eigen::MatrixXd* dr_dc) const {
  if (objective_.num_residuals() == 0) return false;
  Eigen::MatrixXd dr_dp;
  objective_.Residuals(at.p, r, &dr_dp);
  *dr_dc = dr_dp * at.J;
  return true;
}

IkResult IkProblem::Finish(const Eigen::Ref<const Eigen::VectorXd>& c0, IkSummary summary) const {
  IkResult res;
  summary.method = options_.method;
  summary.gradient = options_.gradient;
  summary.evaluations = evaluations_;
  summary.jacobian_evaluations = jacobian_evaluations_;
  summary.fk_solves = fk_solves();
  summary.time_s = elapsed_s();
  if (has_best_) {
    res.c = best_c_;
    res.p = best_p_;
    res.objective = best_value_;
    res.inverted_elements = best_inverted_;
    res.min_volume_ratio = best_min_volume_ratio_;
    summary.final_objective = best_value_;
    if (summary.history.empty())
      summary.initial_objective = best_value_;
    else
      summary.initial_objective = summary.history.front();
  } else {
    res.c = c0;
  }
  res.summary = std::move(summary);
  return res;
}

}  // namespace softkin
