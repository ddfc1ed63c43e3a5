#pragma once
/// \file energy.hpp
/// The FK energy of Eq. 2.10 as a function of the vertex positions, for solvers other than the
/// local-global one (and for tests).
///
///   E(X; c) = sum_i w_i Vol_i || N V_i^d - T_i(X; c) ||_F^2,
///
/// where T_i is the element's target (targets.hpp) computed at X: the rotations are the best-fit
/// ones, the body target blends with R_omega, and the pneumatic local ratios alpha_i depend on the
/// current volumes (Sec. 2.3.3).
#include "softkin/solver/fk/model.hpp"

#include <vector>

namespace softkin {

/// E(X; c). X: #V x 3 positions, mm; c: actuation vector (one value per actuator).
double Energy(const Model& model, const Eigen::Ref<const Eigen::MatrixX3d>& X,
              const Eigen::Ref<const Eigen::VectorXd>& c);

/// The exact gradient dE/dX (#V x 3, rows of fixed vertices included) of Energy(), including the
/// dependence of the blended body targets on the current volume and of the local ratios alpha_i on
/// all chamber volumes. The rotations need no derivative: each R_i is the minimiser of its term.
/// Returns E as well.
double EnergyAndGradient(const Model& model, const Eigen::Ref<const Eigen::MatrixX3d>& X,
                         const Eigen::Ref<const Eigen::VectorXd>& c, Eigen::MatrixX3d* grad);

/// E and its exact gradient with the per-element actuation ratios held at `ratios` (one per
/// element, as ComputeLocalRatios returns them; kVented elements add nothing). This is the energy
/// the Ceres and Ipopt solvers minimise between two ratio updates (nlp_solvers.hpp). Body terms
/// are exact, blending (R_omega < 1) included.
double FixedRatioEnergyAndGradient(const Model& model, const Eigen::Ref<const Eigen::MatrixX3d>& X,
                                   const std::vector<double>& ratios, Eigen::MatrixX3d* grad);

/// The local-global residual 2 (A X - B(X)) (#V x 3): the gradient with the targets T_i frozen at
/// X. Local-global iterations drive it to zero. It equals the exact gradient when every body has
/// R_omega = 1 and the actuation ratios are held fixed; otherwise the two differ (the fixed point
/// of Algorithm 1 is not a stationary point of E when R_omega < 1).
double FrozenTargetGradient(const Model& model, const Eigen::Ref<const Eigen::MatrixX3d>& X,
                            const Eigen::Ref<const Eigen::VectorXd>& c, Eigen::MatrixX3d* grad);

/// Checks the actuation vector: right length, finite, within each actuator's [min, max]. Throws
/// std::invalid_argument naming the actuator and its range.
void CheckActuation(const Model& model, const Eigen::Ref<const Eigen::VectorXd>& c);

}  // namespace softkin
