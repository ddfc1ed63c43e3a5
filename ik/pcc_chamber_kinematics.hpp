#pragma once
/// \file
/// The piecewise-constant-curvature (PCC) model of `three_chamber` (thesis Table 5.1's "PCC
/// analytical" baseline, and the analytical data source of Fig. 5.14; refs. [129, 80] there):
/// chamber extensions -> arc parameters (kappa, phi, l) -> tip position, in closed form.
///
/// Frame as in solver/robots/three_chamber.cpp: y is the long axis (base face y = 0), the
/// cross-section is the x-z plane, chamber k (actuator c_{k+1}, k = 0, 1, 2) sits at distance d
/// from the axis in the direction u_k = (cos psi_k, sin psi_k) of the (x, z) plane, psi_k = 180 +
/// 120 k degrees.
///
/// Model:
///  - chamber k lengthens with its volume ratio: l_k = L_c (1 + g (c_k - 1));
///  - the arc of the chamber section has the mean length l = (l_0 + l_1 + l_2)/3 and the bending
///    vector (in the x-z plane, pointing to the centre of curvature)
///        b = -2 / (3 l d) * sum_k l_k u_k,   kappa = |b|,  phi = atan2(b_z, b_x),
///    the least-squares inverse of l_k = l (1 - kappa d cos(psi_k - phi)): the section bends away
///    from its longest chamber;
///  - the tip: a straight base block of length `base` along +y, the arc, and a straight cap of
///    length `cap` along the arc's end tangent. With t = kappa^2 l^2, g(t) = (1 - cos sqrt t)/t and
///    h(t) = sin(sqrt t)/sqrt t (Taylor series near 0, so everything is smooth at kappa = 0):
///        arc end   = (0, base, 0) + [b l^2 g(t)]_xz + [l h(t)]_y,
///        tangent   = [b l h(t)]_xz + [1 - t g(t)]_y,
///        tip       = arc end + cap * tangent.
/// J = dp/dc by forward-mode automatic differentiation (ceres::Jet) of the same code.
/// Default lengths are the robot's (8 + 120 + 8 mm, d = 13 mm); the gain g is a free parameter
/// fitted to data by FitPccChamber (the thesis fits its PCC model to measurements likewise).

#include "softkin/ik/kinematics.hpp"

#include <string>

namespace softkin {

struct PccChamberParams {
  double base = 8.0;                ///< straight base block, mm (>= 0)
  double chamber_length = 120.0;    ///< L_c, chamber section at rest, mm (> 0)
  double cap = 8.0;                 ///< straight cap above the chambers, mm (>= 0)
  double offset = 13.0;             ///< d, chamber axis distance from the centre line, mm (> 0)
  double gain = 0.3;                ///< g, chamber elongation per unit of (c - 1) (> 0)
  double lower = 1.0, upper = 3.0;  ///< actuation box (volume ratios), lower < upper
  double rest = 1.0;                ///< rest actuation, in [lower, upper]
  bool IsValid(std::string* why) const;
};

struct PccArc {
  double kappa = 0;   ///< curvature, 1/mm
  double phi = 0;     ///< bending direction in the x-z plane, rad (atan2(z, x); 0 when straight)
  double length = 0;  ///< arc length of the chamber section, mm
};

class PccChamberKinematics : public Kinematics {
 public:
  /// Throws std::invalid_argument for invalid params.
  explicit PccChamberKinematics(const PccChamberParams& params = PccChamberParams());
  std::string name() const override { return "pcc-chamber"; }
  int num_actuators() const override { return 3; }
  const std::vector<std::string>& point_names() const override { return names_; }
  const Eigen::VectorXd& lower() const override { return lower_; }
  const Eigen::VectorXd& upper() const override { return upper_; }
  Eigen::VectorXd rest() const override { return Eigen::VectorXd::Constant(3, params_.rest); }
  /// Closed form (fk_solves = 1); ok = false only for bad c.
  KinematicsEval Evaluate(const Eigen::Ref<const Eigen::VectorXd>& c, bool with_jacobian) override;
  long long total_fk_solves() const override { return evaluations_; }
  const PccChamberParams& params() const { return params_; }
  /// The arc parameters at c (no bounds check).
  PccArc ArcParameters(const Eigen::Ref<const Eigen::VectorXd>& c) const;
  /// The tip at c for any params (no checks): the model itself.
  static Eigen::Vector3d Tip(const PccChamberParams& params, const Eigen::Vector3d& c);

 private:
  PccChamberParams params_;
  std::vector<std::string> names_{"tip"};
  Eigen::VectorXd lower_, upper_;
  long long evaluations_ = 0;
};

struct PccFitResult {
  PccChamberParams params;  ///< start with gain, offset and cap fitted
  double rms_mm = 0;        ///< RMS tip distance over the samples after the fit
  double rms_start_mm = 0;  ///< ... with the start parameters
  int iterations = 0;
};

/// Fits gain g, offset d and cap length (the axial offset of the tip) of the model to samples
/// (C: n x 3 actuations, P: n x 3 tip positions, mm) by damped Gauss-Newton (Levenberg) from
/// `start` (after a coarse scan of gain x 10^[-1, 0.5] and offset x [0.6, 1.6] that picks the
/// basin: the tip moves by about its own length over the box, so the cost is far from quadratic).
/// Throws std::invalid_argument for mismatched sizes, fewer than 3 samples or
/// non-finite data.
PccFitResult FitPccChamber(const Eigen::Ref<const Eigen::MatrixXd>& C,
                           const Eigen::Ref<const Eigen::MatrixXd>& P,
                           const PccChamberParams& start = PccChamberParams());

}  // namespace softkin
