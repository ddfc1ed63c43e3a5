#pragma once
/// \file targets.hpp
/// Target shapes V^t of Sec. 2.3 (the local step of Algorithm 1, lines 4-5).
///  - Body elements: shape blending (Eq. 2.3-2.5), V^t = R_w N(R V) + (1 - R_w) N(S V^d), where R is
///    the best rotation from the rest shape to the current one and S scales the current shape back
///    to the rest volume. Note: the thesis writes S = diag(r, r, r) with r = Vol(V)/Vol(V^d); a
///    uniform scale that restores the volume is the cube root of that ratio, which is what is used.
///  - Pneumatic elements: the rest shape scaled by cbrt(alpha_i) about its centre (Eq. 2.8), rotated
///    to the current shape.
/// The blended target is already aligned with the current shape: D^T T is symmetric positive
/// semi-definite, so the final rotation R_i of Eq. 2.10 is the identity and is not recomputed.
#include "solver/model.hpp"

#include <vector>

namespace softkin {

/// Per-element local actuation ratios alpha_i (pneumatic, 1 for body elements) for actuation c at
/// positions X (#V x 3). Sec. 2.3.3: the ratios are proportional to each element's current volume
/// ratio rho_i = Vol(V_i^d)/u_i and scaled so that sum_i alpha_i u_i = alpha U exactly (Eq. 2.8).
/// This is the least-norm correction of the current ratios in the metric sum_i (u_i/rho_i)
/// (alpha_i - rho_i)^2. `achieved` (optional) receives each actuator's current volume ratio
/// sum_i Vol(V_i^d) / U.
void ComputeLocalRatios(const Model& model, const Eigen::Ref<const Eigen::MatrixX3d>& X,
                        const Eigen::Ref<const Eigen::VectorXd>& c, std::vector<double>* ratios,
                        std::vector<double>* achieved = nullptr);

/// Target of one element: D = N V^d (centred current rows), ratio = alpha_i (pneumatic, ignored
/// for body). Writes the centred target T, already rotated to the current frame.
void ElementTarget(const ModelElement& e, const ElemRows& D, double ratio, ElemRows* T);

/// The local step: for every element computes its target (stored as w_i Vol_i * T in `weighted`,
/// #E entries, allocated by the caller or resized here once) and returns the energy
/// E = sum_i w_i Vol_i ||N V_i^d - T_i||_F^2 (Eq. 2.10). Runs in parallel, no heap allocation per
/// element.
double LocalStep(const Model& model, const Eigen::Ref<const Eigen::MatrixX3d>& X,
                 const std::vector<double>& ratios, std::vector<ElemRows>* weighted, int threads = 0);

/// Gathers sum_i w_i Vol_i S_i^T T_i into a #V x 3 matrix (the right-hand side of Eq. 2.11).
void AssembleRhs(const Model& model, const std::vector<ElemRows>& weighted, Eigen::MatrixX3d* B,
                 int threads = 0);

}  // namespace softkin
