#pragma once
/// \file
/// The evaluator the IK solvers share: O(c) = Objective(p(c)) and dO/dc (through J, or by central
/// differences, Eq. 4.2), with evaluation / FK counting, the best point seen, the time budget, and
/// failures turned into an IkTermination plus message instead of exceptions.

#include "softkin/ik/ik_solver.hpp"

#include <chrono>

namespace softkin {

/// One evaluation of O at c.
struct IkPoint {
  bool ok = false;
  IkTermination failure = IkTermination::kKinematicsFailure;  ///< when !ok
  std::string message;                                        ///< when !ok
  double value = 0.0;                                         ///< O(c)
  Eigen::VectorXd grad;  ///< dO/dc (#actuators), when requested
  Eigen::MatrixX3d p;    ///< tracked points at c
  Eigen::MatrixXd J;     ///< dp/dc, when requested with the Jacobian gradient
};

class IkProblem {
 public:
  /// kin, objective and options must outlive the problem. Starts the clock.
  IkProblem(Kinematics& kin, const Objective& objective, const IkOptions& options);

  int n() const { return kin_.num_actuators(); }
  const Eigen::VectorXd& lower() const { return kin_.lower(); }
  const Eigen::VectorXd& upper() const { return kin_.upper(); }
  /// upper - lower (per actuator).
  const Eigen::VectorXd& range() const { return range_; }
  /// c clamped into the box.
  Eigen::VectorXd Project(const Eigen::Ref<const Eigen::VectorXd>& c) const;

  /// O(c) and, with with_gradient, dO/dc by options.gradient. c must lie in the box.
  /// with_jacobian_too: also fill IkPoint::J (the residual methods need it); implies the
  /// Jacobian gradient source for that call.
  IkPoint Evaluate(const Eigen::Ref<const Eigen::VectorXd>& c, bool with_gradient,
                   bool with_jacobian_too = false);
  /// Residuals r(p) and dr/dc = dr/dp J at an IkPoint evaluated with its Jacobian. false if the
  /// objective has no least-squares form; throws ObjectiveError like the objective.
  bool Residuals(const IkPoint& at, Eigen::VectorXd* r, Eigen::MatrixXd* dr_dc) const;

  /// True when another evaluation would exceed max_evaluations or the time is up; *why says which.
  bool OutOfBudget(IkTermination* why, std::string* message) const;
  double elapsed_s() const;
  /// The shared "no progress" stop of the descent methods after an accepted step: the objective
  /// fell from o_prev to o_now by less than function_tolerance * o_prev, or the step (as a
  /// fraction of the range) was below parameter_tolerance. Sets termination kNoProgress and the
  /// message in *summary and returns true when it applies.
  bool Stalled(double o_prev, double o_now, double step, IkSummary* summary) const;
  /// The descent methods' stop at the top of an iteration: O = value <= lambda (kConverged), or
  /// `iterations` reached max_iterations (kMaxIterations). Sets the termination and message in
  /// *summary and returns true when one applies.
  bool Finished(double value, int iterations, IkSummary* summary) const;

  int evaluations() const { return evaluations_; }
  int jacobian_evaluations() const { return jacobian_evaluations_; }
  long long fk_solves() const { return kin_.total_fk_solves() - fk_start_; }
  bool has_best() const { return has_best_; }
  const Eigen::VectorXd& best_c() const { return best_c_; }
  double best_value() const { return best_value_; }
  const Eigen::MatrixX3d& best_p() const { return best_p_; }

  /// Fills the counts, time and objective fields of `summary` and the result's c, p, objective
  /// from the best point seen (or c0 when nothing could be evaluated).
  IkResult Finish(const Eigen::Ref<const Eigen::VectorXd>& c0, IkSummary summary) const;

 private:
  // track_best: false for central-difference probes (the best point is an iterate or a trial).
  IkPoint EvaluateOnce(const Eigen::Ref<const Eigen::VectorXd>& c, bool with_jacobian,
                       bool track_best);

  Kinematics& kin_;
  const Objective& objective_;
  const IkOptions& options_;
  Eigen::VectorXd range_;
  std::chrono::steady_clock::time_point start_;
  long long fk_start_;
  int evaluations_ = 0, jacobian_evaluations_ = 0;
  bool has_best_ = false;
  Eigen::VectorXd best_c_;
  double best_value_ = 0.0;
  Eigen::MatrixX3d best_p_;
  int best_inverted_ = 0;  ///< inverted body elements in the state behind best_p_
  double best_min_volume_ratio_ = 1.0;
};

}  // namespace softkin
