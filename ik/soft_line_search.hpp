#pragma once
/// \file
/// Algorithm 3 (thesis Sec. 4.2): gradient descent with the soft line search, on the box.
///
/// Each iteration i (at most i_max = options.max_iterations, while O > lambda):
///  1. the descent direction d = -grad O (times range^2 per actuator if normalize_by_range), with
///     the components that push against an active bound set to zero;
///  2. shrinking: Delta h = 1, then Delta h *= tau (0.1) until O(P(c + Delta h d)) < O(c), P the
///     projection onto [c_min, c_max] (at most max_shrinks times);
///  3. expanding: h = Delta h, then h += Delta h while O(P(c + (h + Delta h) d)) keeps strictly
///     decreasing (at most max_expansions times, and never past the point where the projection
///     stops moving);
///  4. c = P(c + h d).
/// Only strict decreases are ever accepted, so O falls monotonically and every iterate lies in
/// the box. A failed evaluation of a trial point counts as no decrease (the search shrinks away
/// from it); a failure at an accepted point (where the gradient is needed) ends the solve.
/// The thesis writes c + h grad O; the step here goes downhill, as the text intends.

#include "softkin/ik/ik_solver.hpp"

namespace softkin {

/// The softls method of SolveIk (which checks the inputs; call that instead).
IkResult SolveSoftLineSearch(Kinematics& kin, const Objective& objective,
                             const Eigen::Ref<const Eigen::VectorXd>& c0, const IkOptions& options);

}  // namespace softkin
