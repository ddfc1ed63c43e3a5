#include "solver/rotation.hpp"

#include <Eigen/Eigenvalues>
#include <Eigen/SVD>
#include <Eigen/LU>
#include <cmath>

namespace softkin {

// Polar factor through the closed-form eigen-decomposition of the symmetric M^T M = V S^2 V^T:
// u_i = M v_i / s_i, and the column of the smallest singular value is completed by a cross
// product so that det(U) = det(V) = +1. That flips the smallest singular direction exactly when
// det(M) < 0, which is the reflection-safe optimum (Kabsch/Umeyama). Several times faster than a
// 3x3 Jacobi SVD and allocation-free.
Eigen::Matrix3d BestRotation(const Eigen::Matrix3d& M) {
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eig;
  eig.computeDirect(M.transpose() * M);  // eigenvalues ascending
  Eigen::Matrix3d V = eig.eigenvectors();
  if (V.determinant() < 0) V.col(0) = -V.col(0);
  const Eigen::Vector3d lam = eig.eigenvalues().cwiseMax(0.0);
  const double scale = lam(2);
  if (!(scale > 0.0) || !std::isfinite(scale)) return Eigen::Matrix3d::Identity();
  Eigen::Vector3d u2 = M * V.col(2);
  u2.normalize();
  Eigen::Vector3d u1 = M * V.col(1);
  u1 -= u2.dot(u1) * u2;
  const double n1 = u1.norm();
  if (n1 > 1e-12 * std::sqrt(scale)) {
    u1 /= n1;
  } else {
    // Rank one: any unit vector orthogonal to u2.
    u1 = u2.unitOrthogonal();
  }
  Eigen::Matrix3d U;
  U.col(2) = u2;
  U.col(1) = u1;
  U.col(0) = u1.cross(u2);
  Eigen::Matrix3d R = U * V.transpose();
  // One Newton step of the polar iteration, R <- (R + R^-T) / 2, removes the O(eps * cond^2)
  // loss of orthogonality that forming M^T M causes.
  R = 0.5 * (R + R.inverse().transpose());
  return R;
}

/// Reference implementation with a Jacobi SVD (used in tests and the benchmark baseline).
Eigen::Matrix3d BestRotationSvd(const Eigen::Matrix3d& M) {
  Eigen::JacobiSVD<Eigen::Matrix3d> svd(M, Eigen::ComputeFullU | Eigen::ComputeFullV);
  Eigen::Matrix3d U = svd.matrixU();
  const Eigen::Matrix3d& Vs = svd.matrixV();
  if ((U * Vs.transpose()).determinant() < 0.0) U.col(2) = -U.col(2);
  return U * Vs.transpose();
}

}  // namespace softkin
