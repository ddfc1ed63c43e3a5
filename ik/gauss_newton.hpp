#pragma once
/// \file
/// Damped least squares (Levenberg) on the residual Jacobian, for objectives with a least-squares
/// form O = |r(p(c))|^2 (point tracking, shape matching, and every objective in objectives.hpp).
///
/// In coordinates scaled to [0, 1] per actuator (u = (c - c_min)/range, so the damping treats all
/// actuators alike), with A = dr/du = dr/dp J diag(range) and g = A^T r, each iteration:
///  1. the free set: actuators not at a bound that the steepest-descent direction -g pushes
///  against;
///  2. solve (A_F^T A_F + mu I) du_F = -g_F on the free set, c_trial = P(c + diag(range) du),
///     P the projection onto the box;
///  3. accept if O(c_trial) < O(c) (then mu /= 10), else mu *= 10 and retry; give up (no-progress)
///     when mu exceeds max_damping.
/// mu starts at initial_damping times the largest diagonal entry of A^T A. Stopping: O <= lambda,
/// i_max accepted steps, function / parameter tolerance, budget. Only decreases are accepted.
/// Each iteration evaluates the Jacobian once, at the accepted point.
///
/// `broyden` (IkMethod::kBroyden) takes the same steps but evaluates J only at c0 (not even there
/// when IkOptions::initial_jacobian is given, e.g. the previous waypoint's IkResult::J) and after
/// a step made with an updated J fails (a trial without decrease, or a stall). After each accepted
/// step, J gets Broyden's rank-one secant update in the scaled coordinates:
///     J += (dp - J dc) w^T / (dc^T w),   w_a = dc_a / range_a^2,
/// so that J dc = dp holds for the step just taken and J changes least in the Frobenius norm of
/// J diag(range). On the simulator a Jacobian costs one to two forward solves, and along a smooth
/// path J barely changes between waypoints: a warm waypoint then costs its trial solves only.

#include "softkin/ik/ik_solver.hpp"

namespace softkin {

/// The gauss-newton and broyden methods of SolveIk (which checks the inputs; call that instead).
/// The objective must have num_residuals() > 0.
IkResult SolveGaussNewton(Kinematics& kin, const Objective& objective,
                          const Eigen::Ref<const Eigen::VectorXd>& c0, const IkOptions& options);

}  // namespace softkin
