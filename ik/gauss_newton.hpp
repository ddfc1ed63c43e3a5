#pragma once
/// \file
/// Damped least squares (Levenberg) on the residual Jacobian, for objectives with a least-squares
/// form O = |r(p(c))|^2 (point tracking, shape matching, and every objective in objectives.hpp).
///
/// In coordinates scaled to [0, 1] per actuator (u = (c - c_min)/range, so the damping treats all
/// actuators alike), with A = dr/du = dr/dp J diag(range) and g = A^T r, each iteration:
///  1. the free set: actuators not at a bound that the steepest-descent direction -g pushes against;
///  2. solve (A_F^T A_F + mu I) du_F = -g_F on the free set, c_trial = P(c + diag(range) du),
///     P the projection onto the box;
///  3. accept if O(c_trial) < O(c) (then mu /= 10), else mu *= 10 and retry; give up (no-progress)
///     when mu exceeds max_damping.
/// mu starts at initial_damping times the largest diagonal entry of A^T A. Stopping: O <= lambda,
/// i_max accepted steps, function / parameter tolerance, budget. Only decreases are accepted.
/// Each iteration evaluates the Jacobian once, at the accepted point.

#include "ik/ik_solver.hpp"

namespace softkin {

/// The gauss-newton method of SolveIk (which checks the inputs; call that instead). The objective
/// must have num_residuals() > 0.
IkResult SolveGaussNewton(Kinematics& kin, const Objective& objective,
                          const Eigen::Ref<const Eigen::VectorXd>& c0, const IkOptions& options);

}  // namespace softkin
