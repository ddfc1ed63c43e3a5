#pragma once
/// \file nlp_solvers.hpp
/// The FK energy of Eq. 2.10 handed to general-purpose optimisers, for comparison with the
/// local-global solver (local_global.hpp):
///  - "ceres": a Ceres least-squares problem. One residual block per element,
///    sqrt(w_i Vol_i) (N V_i^d - R_i N V_i^t), with a rotation parameter block per element
///    (angle-axis, started at the best-fit rotation), one 3-vector block per vertex (fixed and
///    moved vertices constant, vertices held on some axes through a SubsetManifold), automatic
///    derivatives, Levenberg-Marquardt with sparse normal Cholesky through SuiteSparse.
///  - "ipopt-lbfgs": an Ipopt TNLP over the free vertex coordinates with the rotation-free energy
///    E(x) = sum_i w_i Vol_i min_R ||N V_i^d - R N V_i^t||^2 and its exact gradient
///    (FixedRatioEnergyAndGradient); limited-memory (L-BFGS) Hessian.
///  - "ipopt-newton": the same TNLP with the local-global matrix 2 A (Eq. 2.11, the Hessian with
///    the rotations and targets frozen) as a Gauss-Newton Hessian: constant, sparse, positive
///    definite on the free coordinates. It is not the exact Hessian: it drops how the best-fit
///    rotations turn with x.
///  - "ipopt-hard": the "straightforward method" Sec. 2.3.3 warns about. Only the body energy,
///    and each active actuation group's measure held exactly by an equality constraint:
///    sum_i Vol_i(x) = alpha U (Eq. 3.2; the chamber volume, its cavity being meshed), the cable
///    length L_R + sum_i l_i |F_i d| = s L, the DEA area sum_i a_i = lambda A. The actuation
///    elements carry no energy, so vertices inside a meshed cavity are free (their positions do
///    not change the body energy nor the cavity volume; they stay where they start). L-BFGS
///    Hessian. Its energy is reported as Eq. 2.10 at the result, for comparison; it does not
///    minimise that energy.
///
/// Actuation ratios. The local step distributes an actuator's ratio over its elements in
/// proportion to their current measures (Sec. 2.3.3), so the targets depend on x through all
/// chamber volumes at once. The local-global fixed point is a stationary point of E with the
/// ratios frozen at their values there, not of E with the ratios as functions of x. To reach that
/// same point, these solvers alternate: compute the ratios at x (ComputeLocalRatios), minimise E
/// with those ratios frozen, and repeat ("ratio updates") until the stopping rule of the
/// local-global solver holds: the last update moved no vertex more than tolerance * size and the
/// gradient at frozen ratios(x) is below gradient_tolerance times its reference (at the rest shape
/// for the same actuation). FkResult::iterations counts the optimiser's iterations summed over the
/// updates; the message gives the number of updates.
///
/// Body elements with R_omega < 1 have blended targets that depend on the current volume.
/// Ipopt minimises that energy exactly (its gradient includes the blending term). Ceres supports
/// R_omega = 1 only and reports invalid_input otherwise. The local-global iteration treats the
/// blended target as frozen in each global step, so its fixed point is not a stationary point of
/// E when R_omega < 1; comparisons between the solvers use R_omega = 1 bodies (every solver then
/// minimises the same function and reaches the same positions).
#include "softkin/solver/fk/fk_solver.hpp"

#include <memory>
#include <string>

namespace softkin {

/// Whether this build has the Ceres / Ipopt solvers (both are required dependencies today; kept as
/// functions so callers need not change if they become optional).
bool HasCeresSolver();
bool HasIpoptSolver();

/// Builds "ceres", "ipopt-lbfgs", "ipopt-newton" or "ipopt-hard" (options.solver). Throws
/// std::invalid_argument for any other solver.
std::unique_ptr<FkSolver> MakeNlpSolver(std::shared_ptr<const Model> model,
                                        const FkOptions& options);

}  // namespace softkin
