#pragma once
/// \file
/// A Kinematics that drives only some actuators of another one and holds the others at fixed
/// values: the pick-and-place stages of thesis Sec. 4.4 solve for c = {c1, c2} (Eq. 4.5-4.6) with
/// the gripper segment at rest, then for the gripper alone (Eq. 4.7) with the first two held.
/// Points, bounds and Jacobian columns are those of the driven actuators, in the given order.
#include "softkin/ik/kinematics.hpp"

#include <vector>

namespace softkin {

class SubsetKinematics : public Kinematics {
 public:
  /// `base` must outlive this object. `driven`: indices of the actuators IK may change (distinct,
  /// in range, at least one); `fixed`: a full actuation vector (#base actuators, inside the box)
  /// that gives the values of the others. Throws std::invalid_argument otherwise.
  SubsetKinematics(Kinematics& base, std::vector<int> driven, const Eigen::VectorXd& fixed);

  std::string name() const override;
  int num_actuators() const override { return static_cast<int>(driven_.size()); }
  const std::vector<std::string>& point_names() const override { return base_.point_names(); }
  const Eigen::VectorXd& lower() const override { return lower_; }
  const Eigen::VectorXd& upper() const override { return upper_; }
  /// The driven actuators' values in `fixed` (where IK starts by default).
  Eigen::VectorXd rest() const override;
  KinematicsEval Evaluate(const Eigen::Ref<const Eigen::VectorXd>& c, bool with_jacobian) override;
  long long total_fk_solves() const override { return base_.total_fk_solves(); }

  /// The full actuation of `base` for driven values c (#driven).
  Eigen::VectorXd Full(const Eigen::Ref<const Eigen::VectorXd>& c) const;

 private:
  Kinematics& base_;
  std::vector<int> driven_;
  Eigen::VectorXd fixed_, lower_, upper_;
};

}  // namespace softkin
