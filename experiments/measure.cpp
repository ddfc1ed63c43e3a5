#include "softkin/experiments/measure.hpp"

#include <cmath>
#include <stdexcept>

namespace softkin {

BendAngle::BendAngle(const Scene& scene) : scene_(scene) {
  top_ = scene.marker_index("tip_top");
  bottom_ = scene.marker_index("tip_bottom");
  if (top_ < 0 || bottom_ < 0)
    throw std::invalid_argument("scene '" + scene.name +
                                "': the bending angle needs markers 'tip_top' and 'tip_bottom'");
  const Eigen::MatrixX3d P = scene.marker_positions(scene.mesh.vertices);
  u0_ = (P.row(top_) - P.row(bottom_)).transpose().normalized();
}

double BendAngle::operator()(const Eigen::Ref<const Eigen::MatrixX3d>& X) {
  const Eigen::MatrixX3d P = scene_.marker_positions(X);
  const Eigen::Vector3d u = (P.row(top_) - P.row(bottom_)).transpose().normalized();
  if (axis_.squaredNorm() == 0.0) {
    const Eigen::Vector3d a = u0_.cross(u);
    if (a.norm() < 1e-9) return 0.0;
    axis_ = a.normalized();
  }
  // Signed angle about axis_, unwrapped to be within pi of the previous value.
  double ang = std::atan2(axis_.dot(u0_.cross(u)), u0_.dot(u));
  while (ang - last_ > M_PI) ang -= 2 * M_PI;
  while (ang - last_ < -M_PI) ang += 2 * M_PI;
  last_ = ang;
  return ang * 180.0 / M_PI;
}

}  // namespace softkin
