#pragma once
/// \file
/// Least-squares circle through 3D points, and the derivative of its diameter with respect to the
/// points: the curvature measure f_fit(V) of the grasp objective (thesis Eq. 4.7).
///
/// Method (documented in docs/ik.md):
///  1. The circle's plane. Either given (a unit normal, e.g. the motion plane of a planar robot:
///     the y axis for `multi_segment_gripper`), or the least-squares plane through the points: the
///     centroid m and the eigenvector of the smallest eigenvalue of the scatter matrix
///     C = sum_i (x_i - m)(x_i - m)^T.
///  2. The points are expressed in an orthonormal basis (e1, e2) of that plane, u_i = E^T (x_i -
///  m).
///  3. The algebraic (Kasa) fit: minimise sum_i (|u_i|^2 + D u_ix + E u_iy + F)^2 over (D, E, F), a
///     linear least-squares problem; r^2 = (D^2 + E^2)/4 - F. It is exact on noise-free points of a
///     circle (and biased towards smaller radii under noise, which IK does not mind).
/// The diameter's gradient is analytic: reverse mode through the least-squares solve, plus, for a
/// fitted plane, the tilt of the plane through the eigenvector perturbation of C (only the
/// out-of-plane part matters, since the radius is invariant under in-plane rotations of the basis).

#include <Eigen/Core>

#include <string>

namespace softkin {

struct CircleFit {
  bool ok = false;  ///< false: degenerate input; `message` says why, the rest is unset
  std::string message;
  Eigen::Vector3d center = Eigen::Vector3d::Zero();  ///< mm
  Eigen::Vector3d normal = Eigen::Vector3d::Zero();  ///< unit normal of the circle's plane
  double radius = 0.0;                               ///< mm
  double diameter = 0.0;                             ///< 2 radius, mm
  double rms_residual = 0.0;  ///< RMS of (|u_i - center| - radius) in the plane, mm
  /// #points x 3: d(diameter)/d(x_i), filled when requested (dimensionless).
  Eigen::MatrixX3d d_diameter;
};

/// Fits a circle to `points` (#points x 3, mm; at least 3, not collinear in the plane).
/// `plane_normal`: a nonzero vector fixing the circle's plane normal (it is normalised), or the
/// zero vector to fit the plane to the points as well (which needs the points to span a plane
/// clearly: the two in-plane eigenvalues must exceed the normal one by a relative 1e-10). With
/// `with_derivative`, fills d_diameter. Never throws; a degenerate input gives ok = false.
CircleFit FitCircle(const Eigen::Ref<const Eigen::MatrixX3d>& points,
                    const Eigen::Vector3d& plane_normal, bool with_derivative);

}  // namespace softkin
