#pragma once
/// \file rotation.hpp
/// Reflection-safe best-fit rotations (the SVD step of Algorithm 1, line 5).
#include <Eigen/Dense>

namespace softkin {

/// The rotation R (det R = +1) that maximises tr(R^T M), i.e. the rotational polar factor of the
/// 3x3 cross-covariance M. If det(U V^T) < 0 the singular vector of the smallest singular value is
/// negated, so an inverted element never yields a reflection.
Eigen::Matrix3d BestRotation(const Eigen::Matrix3d& M);

/// How many matrices BestRotations iterates on together.
constexpr int kRotationBatch = 8;

/// R[i] = BestRotation(M[i]) for i < n, bit for bit, several times faster per matrix: the
/// iteration runs on kRotationBatch matrices at once in vectorisable loops.
void BestRotations(const Eigen::Matrix3d* M, int n, Eigen::Matrix3d* R);

}  // namespace softkin

namespace softkin {
/// The same rotation from the closed-form eigen-decomposition of M^T M (BestRotation's fallback
/// for inverted and nearly singular M; reference for tests and benchmarks).
Eigen::Matrix3d BestRotationEigen(const Eigen::Matrix3d& M);
/// The same rotation computed with Eigen's 3x3 JacobiSVD (reference for tests and benchmarks).
Eigen::Matrix3d BestRotationSvd(const Eigen::Matrix3d& M);
}  // namespace softkin
