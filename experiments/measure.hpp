#pragma once
/// \file measure.hpp
/// Measurements taken on FK results for experiments: the bending angle of a robot's distal end.
#include "softkin/solver/scene/scene.hpp"

#include <Eigen/Dense>

namespace softkin {

/// Tracks the bending angle (degrees) of the distal end face, unwrapped along a sweep so that it
/// can exceed 180. It uses markers `tip_top` and `tip_bottom` (the end face's upper and lower
/// parts): the angle is the rotation of the vector tip_bottom -> tip_top about the axis normal to
/// the plane of the rest vector and the first bent one. Throws std::invalid_argument if the markers
/// are missing.
class BendAngle {
 public:
  explicit BendAngle(const Scene& scene);
  /// Angle for positions X (#V x 3), unwrapped relative to the previous call.
  double operator()(const Eigen::Ref<const Eigen::MatrixX3d>& X);

 private:
  const Scene& scene_;
  int top_, bottom_;
  Eigen::Vector3d u0_, axis_ = Eigen::Vector3d::Zero();
  double last_ = 0.0;
};

}  // namespace softkin
