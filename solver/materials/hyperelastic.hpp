#pragma once
/// \file hyperelastic.hpp
/// Hyperelastic body elements (thesis Sec. 3.3.1, Eq. 3.6-3.7) and how their strain-dependent
/// shape parameter R_omega(eps) is derived from a first-order Mooney-Rivlin law.
///
/// Target of a hyperelastic body element (current frame, centred rows D = N V^d, P = N V, R the
/// best rotation from P to D):
///     V_blend = (1 - rho) D + rho P R^T,   rho = R_omega(eps(D))                (Eq. 3.6)
///     V^t     = (Vol(P) / Vol(V_blend))^(1/3) V_blend                         (Eq. 3.7)
/// i.e. the current shape blended with the rotated rest shape, then rescaled to the rest volume
/// (incompressibility). The thesis writes the volume factor without the cube root; a uniform
/// scale that restores the volume needs it. eps is the equivalent (von Mises) Hencky strain of
/// the element's deformation gradient F: sqrt(2/3 |dev log U|^2), which is |ln lambda| for an
/// incompressible uniaxial stretch lambda.
///
/// Deriving R_omega(eps) (the thesis defers to its reference [115]; this is our derivation):
/// under a homogeneous uniaxial stretch lambda with free lateral faces, the local-global fixed
/// point of Eq. 3.6-3.7 with a constant rho has
///   - lateral stretch l solving l = T_22, where T = diag(a, b, b) / (a b^2)^(1/3),
///     a = (1 - rho) lambda + rho, b = (1 - rho) l + rho;
///   - nominal axial stress (per unit element weight) s = 2 (lambda - T_11), the force the held
///     end feels (the frozen-target gradient of w ||F - R T||^2).
/// At small strain s = 2 * 3 rho / (2 + rho) * (lambda - 1) and Poisson's ratio is
/// (1 - rho) / (2 + rho). A Mooney-Rivlin solid has P(lambda) = 2 (lambda - lambda^-2)
/// (c1 + c2 / lambda) and small-strain modulus E = 6 (c1 + c2). Given the material's R_omega at
/// zero strain rho0 (its stiffness relative to the other materials, Sec. 2.4), the scale
/// k = s'(1; rho0) / E fixes the units, and for each stretch lambda the fit finds, by bisection,
/// the rho in [0, 1] whose response matches: s(lambda; rho) = k P(lambda). The knots (eps, rho) of
/// the tension branch make the curve; R_omega(eps) interpolates them linearly and is held
/// constant beyond the last knot. A test checks the fit against a simulated bar.
#include <Eigen/Dense>

#include <string>
#include <vector>

namespace softkin {

/// First-order Mooney-Rivlin constants (MPa): W = c1 (I1 - 3) + c2 (I2 - 3), incompressible.
struct MooneyRivlin {
  double c1 = 0, c2 = 0;
  /// Uniaxial nominal stress at stretch lambda (incompressible): 2 (l - l^-2)(c1 + c2 / l).
  double NominalStress(double lambda) const;
  /// Small-strain Young's modulus 6 (c1 + c2).
  double Modulus() const { return 6.0 * (c1 + c2); }
};

/// The named materials of the thesis (Sec. 3.4): "ecoflex-00-30" (c1 = 0.0418, c2 = 0.0106) and
/// "dragon-skin-20" (c1 = 0.119, c2 = 0.023). Returns false for other names.
bool NamedMooneyRivlin(const std::string& name, MooneyRivlin* out);
/// The names NamedMooneyRivlin knows, for messages.
std::vector<std::string> NamedMooneyRivlinNames();

/// Homogeneous uniaxial response of the Eq. 3.6-3.7 target at stretch lambda > 0 with a constant
/// blending parameter rho in [0, 1]: returns s = 2 (lambda - T_11) (nominal stress per unit
/// weight); `lateral` (optional) receives the lateral stretch l.
double BlendUniaxialStress(double lambda, double rho, double* lateral = nullptr);

class ROmegaCurve;

/// The same homogeneous uniaxial state with R_omega following `curve`: the fixed point of
/// rho = curve(eps(lambda, l)) (iterated until rho changes by < 1e-12, at most 500 times). Returns
/// s; `lateral` and `rho` (optional) receive the state.
double CurveUniaxialStress(const ROmegaCurve& curve, double lambda, double* lateral = nullptr,
                           double* rho = nullptr);

/// Equivalent Hencky strain sqrt(2/3 |dev ln U|^2) of a deformation gradient (its singular values
/// floored at 1e-6).
double EquivalentStrain(const Eigen::Matrix3d& F);

/// The gradient d eps / dF of EquivalentStrain (Frobenius pairing: d eps = <G, dF>). With
/// C = F^T F and e = ln(C) / 2 (the Hencky strain of U), eps^2 = 2/3 |dev e|^2 gives
///     G = (2 / (3 eps)) F (dev e) C^-1,
/// a smooth function of C computed from a backward-stable eigendecomposition, so it stays accurate
/// where principal stretches coincide. Zero where eps < 1e-12 (eps is a norm of the strain and has
/// no derivative at zero; Eq. 3.6 multiplies it by a zero difference there) or where F is singular.
Eigen::Matrix3d EquivalentStrainGradient(const Eigen::Matrix3d& F);

/// R_omega as a function of strain: linear between knots, constant outside them.
class ROmegaCurve {
 public:
  ROmegaCurve() = default;
  /// Knots with strictly increasing eps and rho in [0, 1]; throws std::invalid_argument otherwise.
  ROmegaCurve(std::vector<double> eps, std::vector<double> rho);
  double operator()(double eps) const;
  /// d R_omega / d eps: the slope of the knot interval that holds eps, 0 outside the knots (where
  /// the curve is constant). At a knot, the slope of the interval to its right.
  double Slope(double eps) const;
  const std::vector<double>& eps() const { return eps_; }
  const std::vector<double>& rho() const { return rho_; }
  bool empty() const { return eps_.empty(); }

 private:
  std::vector<double> eps_, rho_;
};

/// Fits R_omega(eps) for a Mooney-Rivlin material whose zero-strain R_omega is rho0 in (0, 1], on
/// uniaxial stretches 1 .. lambda_max (n knots). Throws std::invalid_argument for c1 + c2 <= 0,
/// c1 < 0, c2 < 0, rho0 outside (0, 1], lambda_max <= 1 or n < 2.
ROmegaCurve FitMooneyRivlinROmega(const MooneyRivlin& m, double rho0, double lambda_max = 4.0,
                                  int n = 61);

}  // namespace softkin
