#pragma once
/// \file
/// IK with NLopt (the "box-constrained actuation"): LD_MMA, LD_LBFGS, LD_SLSQP, LD_CCSAQ
/// and the derivative-free LN_BOBYQA, each with c_min <= c <= c_max as NLopt bounds.
///
/// NLopt has no stopping rule by default; this sets all of them explicitly:
///  stopval = lambda, ftol_rel = function_tolerance, xtol_abs = parameter_tolerance * range,
///  maxeval = max_evaluations, maxtime = max_time_s. LN_BOBYQA starts with a step of 0.1 of each
///  range. The objective callback clamps x into the box (rounding in the optimisers can step
///  1 ulp outside) and counts the budget itself too.
/// NLopt's result codes and exceptions map to IkTermination (no exception escapes): O <= lambda
/// is `converged` whatever the code; STOPVAL -> converged; FTOL / XTOL / SUCCESS / ROUNDOFF_LIMITED
/// -> no-progress; MAXEVAL -> max-evaluations; MAXTIME -> max-time; a failed Kinematics or
/// Objective evaluation stops NLopt (nlopt::forced_stop) and is reported with its message;
/// FAILURE / INVALID_ARGS / OUT_OF_MEMORY -> solver-failure with NLopt's message.
/// The result is the best point evaluated. summary.iterations counts objective evaluations.

#include "softkin/ik/ik_solver.hpp"

namespace softkin {

/// The NLopt methods of SolveIk (which checks the inputs; call that instead). `options.method`
/// must be one of the nlopt-* methods.
IkResult SolveNlopt(Kinematics& kin, const Objective& objective,
                    const Eigen::Ref<const Eigen::VectorXd>& c0, const IkOptions& options);

}  // namespace softkin
