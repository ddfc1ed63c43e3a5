#pragma once
/// \file targets.hpp
/// Target shapes V^t of Sec. 2.3 (the local step of Algorithm 1, lines 4-5).
///  - Body elements: shape blending (Eq. 2.3-2.5), V^t = R_w N(R V) + (1 - R_w) N(S V^d), where R
///  is
///    the best rotation from the rest shape to the current one and S scales the current shape back
///    to the rest volume. Note: the thesis writes S = diag(r, r, r) with r = Vol(V)/Vol(V^d); a
///    uniform scale that restores the volume is the cube root of that ratio, which is what is used.
///  - Hyperelastic body elements (Eq. 3.6-3.7, hyperelastic.hpp): the current shape blended with
///    the rotated rest shape by R_omega(strain), rescaled to the rest volume.
///  - Actuation elements: the rest shape reshaped by the local ratio (actuation.hpp: pneumatic
///    cbrt(alpha_i) I, Eq. 2.8; cable shrink s_i along the cable, Eq. 2.6; DEA in-plane
///    sqrt(lambda_i) and thickness 1/lambda_i, Eq. 2.7), then rotated onto the current shape.
/// The blended target is already aligned with the current shape: D^T T is symmetric positive
/// semi-definite, so the final rotation R_i of Eq. 2.10 is the identity and is not recomputed.
#include "softkin/solver/fk/model.hpp"

#include <vector>

namespace softkin {

/// Measures below this fraction of their rest value count as this fraction (inverted or collapsed
/// elements), so that ratios stay positive and finite.
constexpr double kMinMeasure = 1e-6;

/// Ratio that marks the elements of a vented chamber: the inactive side of a signed pneumatic
/// actuator, whose air escapes (thesis Sec. 5.3.1: only one side of a section is pressurised at a
/// time). Such an element's target is its own current shape, so it adds no energy and no force:
/// the cavity is empty space, free to change volume.
constexpr double kVented = -1.0;

/// Per-element local actuation ratios r_i (alpha_i, s_i or lambda_i; 1 for body elements) for
/// actuation c at positions X (#V x 3). Sec. 2.3.3: the ratios are proportional to each element's
/// current measure ratio rho_i = m_i(X) / mu_i (actuation.hpp) and scaled so that each actuator's
/// group's constraint holds exactly: sum_i r_i mu_i = rho (M + L_R) - L_R (Eq. 2.6-2.8; L_R = 0
/// except for cables; rho = Model::GroupRatio, i.e. c[a] for an unsigned actuator). This is the
/// least-norm correction of the current ratios in the metric sum_i (mu_i / rho_i) (r_i - rho_i)^2.
/// `achieved` (optional) receives each actuator's current value: the ratio
/// (sum_i m_i + L_R) / (M + L_R) (volume, cable length or area ratio), the signed value implied by
/// active side's volume ratio for a signed actuator (0 at value 0), c[a] for a motion actuator.
/// The inactive side of a signed actuator is vented: its elements get ratio kVented.
void ComputeLocalRatios(const Model& model, const Eigen::Ref<const Eigen::MatrixX3d>& X,
                        const Eigen::Ref<const Eigen::VectorXd>& c, std::vector<double>* ratios,
                        std::vector<double>* achieved = nullptr);

/// Deformation gradient F of an element from its centred current rows D: the least-squares affine
/// map of its centred rest rows onto D (exact for a tet).
Eigen::Matrix3d DeformationGradient(const ModelElement& e, const ElemRows& D);

/// A hyperelastic blend (Eq. 3.6) whose volume falls below this fraction of the rest volume
/// (an inverted or nearly flat element at a small R_omega) is not rescaled as it is: its weight
/// moves toward the rotated rest shape until its volume reaches the fraction, so that the volume
/// rescale of Eq. 3.7 stays within a factor of 2 and never turns an inverted blend into a large
/// inverted target.
constexpr double kMinBlendVolume = 0.125;

/// Blend weight t >= rho of the rotated rest rows Rr (P R^T) against the current rows D (both
/// centred) for a hyperelastic body element: rho itself when Vol(t Rr + (1 - t) D) >=
/// kMinBlendVolume * rest_volume, otherwise the t in (rho, 1] where the blend's volume reaches that
/// floor (the blend's volume is a cubic in t, solved by Newton's method kept inside [rho, 1];
/// Vol(Rr) = rest_volume). The target's volume factor is then at most 2.
double HyperelasticBlendWeight(const ElemRows& Rr, const ElemRows& D, int k, double rho,
                               double rest_volume);

/// Target of one element: D = N V^d (centred current rows; rows past k are ignored), ratio = r_i
/// (ignored for body). Writes the centred target T (rows past k zero), already rotated to the
/// current frame.
void ElementTarget(const ModelElement& e, const ElemRows& D, double ratio, ElemRows* T);

/// The local step: for every element computes its target (stored as w_i Vol_i * T in `weighted`,
/// #E entries, allocated by the caller or resized here once) and returns the energy
/// E = sum_i w_i Vol_i ||N V_i^d - T_i||_F^2 (Eq. 2.10). Runs in parallel, no heap allocation per
/// element.
double LocalStep(const Model& model, const Eigen::Ref<const Eigen::MatrixX3d>& X,
                 const std::vector<double>& ratios, std::vector<ElemRows>* weighted,
                 int threads = 0);

/// Gathers sum_i w_i Vol_i S_i^T T_i into a #V x 3 matrix (the right-hand side of Eq. 2.11).
void AssembleRhs(const Model& model, const std::vector<ElemRows>& weighted, Eigen::MatrixX3d* B,
                 int threads = 0);

}  // namespace softkin
