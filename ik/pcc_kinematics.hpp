#pragma once
/// \file
/// An analytical piecewise-constant-curvature (PCC) model of a 3-cable soft finger: a Kinematics
/// with closed-form p(c) and J(c). It is a model in its own right (Table 5.1's "PCC analytical"
/// baseline) and the nonlinear, bounded test bed of the IK code.
///
/// Geometry (mm): the backbone starts at the origin along +z, with length L at rest. Three cables
/// run parallel to it at distance d, at angles psi_i = 2 pi i / 3 around it (cable i lies in the
/// direction u_i = (cos psi_i, sin psi_i, 0)). The actuation c_i in [0, c_max] is the length cable
/// i is pulled in (mm); rest is c = 0.
///
/// Equations (PCC: one circular arc):
///  - bending vector  b = 2 / (3 d L) * sum_i c_i u_i   (|b| = curvature kappa in 1/mm; the finger
///    bends towards the pulled cables; this inverts the PCC cable-length relation
///    Delta_i = L d kappa cos(psi_i - phi) in the least-squares sense);
///  - backbone length s = L - a (c_1 + c_2 + c_3)/3 (a = `axial` in {0, 1}: equal pulls compress
///    the backbone, which keeps the map from c to the tip locally invertible);
///  - the point at arc length sigma: with t = |b|^2 sigma^2,
///      p_xy = b sigma^2 g(t),  p_z = sigma h(t),  g(t) = (1 - cos sqrt t)/t,  h(t) = sin(sqrt
///      t)/sqrt t
///    (the arc (1 - cos theta)/kappa, sin(theta)/kappa written so it is smooth through kappa = 0;
///    g and h use their Taylor series for small t).
/// Tracked points: "tip" (sigma = s) and "backbone[j]" at sigma = s (j + 1)/K, j = 0..K-1
/// (backbone[K-1] is the tip again). Points of one arc lie on a circle of diameter 2/kappa, which
/// makes the grasp objective's fit checkable.

#include "softkin/ik/kinematics.hpp"

namespace softkin {

struct PccParams {
  double length = 100.0;      ///< L, rest backbone length, mm (> 0)
  double cable_offset = 6.0;  ///< d, cable distance from the backbone, mm (> 0)
  double max_pull = 20.0;     ///< c_max, mm (> 0)
  int backbone_points = 8;    ///< K >= 1 tracked points along the backbone
  bool axial = true;          ///< equal pulls compress the backbone (a = 1) or not (a = 0)
  /// True if every field is in range; else false and *why (if given) names the field.
  bool IsValid(std::string* why) const;
};

class PccKinematics : public Kinematics {
 public:
  /// Throws std::invalid_argument for invalid params.
  explicit PccKinematics(const PccParams& params = PccParams());
  std::string name() const override { return "pcc"; }
  int num_actuators() const override { return 3; }
  const std::vector<std::string>& point_names() const override { return names_; }
  const Eigen::VectorXd& lower() const override { return lower_; }
  const Eigen::VectorXd& upper() const override { return upper_; }
  Eigen::VectorXd rest() const override { return Eigen::VectorXd::Zero(3); }
  /// Closed form; fk_solves = 1 (one model evaluation). ok = false only for bad c.
  KinematicsEval Evaluate(const Eigen::Ref<const Eigen::VectorXd>& c, bool with_jacobian) override;
  long long total_fk_solves() const override { return evaluations_; }
  const PccParams& params() const { return params_; }
  /// The curvature |b| (1/mm) at c (no checks).
  double Curvature(const Eigen::Ref<const Eigen::VectorXd>& c) const;

 private:
  PccParams params_;
  std::vector<std::string> names_;
  Eigen::VectorXd lower_, upper_;
  long long evaluations_ = 0;
};

}  // namespace softkin
