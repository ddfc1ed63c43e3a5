#include "softkin/solver/fk/rotation.hpp"

#include <Eigen/Eigenvalues>
#include <Eigen/SVD>
#include <Eigen/LU>
#include <algorithm>
#include <cmath>

namespace softkin {

// Polar factor through the closed-form eigen-decomposition of the symmetric M^T M = V S^2 V^T:
// u_i = M v_i / s_i, and the column of the smallest singular value is completed by a cross
// product so that det(U) = det(V) = +1. That flips the smallest singular direction exactly when
// det(M) < 0, which is the reflection-safe optimum (Kabsch/Umeyama). Several times faster than a
// 3x3 Jacobi SVD and allocation-free.
Eigen::Matrix3d BestRotationEigen(const Eigen::Matrix3d& M) {
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

namespace {

// Newton's polar iteration on W matrices at once, lane l holding matrix l as x[3 r + c][l] (on
// entry M, on exit its rotation where ok[l] = 1). Each loop over the lanes is branch-free (masks
// and selects of values already computed), so for W = kRotationBatch the compiler vectorises it and
// the square roots and divisions of independent matrices overlap; every lane still goes through
// exactly the IEEE operations of the W = 1 instance, so a batch and a single call return the same
// bits. ok[l] = 0: not handled (det <= 1e-9 |M|_F^3, which also catches NaN; a step that made
// det(X) <= 0 through rounding; or no convergence in 16 steps).
template <int W>
void NewtonPolar(double x[9][W], double ok[W]) {
  double c[9][W], det[W], x2[W], cn2[W], active[W], scale[W], z[W], a[W], b[W], step2[W];
  auto cofactor = [&]() {
#pragma omp simd
    for (int l = 0; l < W; ++l) {
      c[0][l] = x[4][l] * x[8][l] - x[5][l] * x[7][l];
      c[1][l] = x[5][l] * x[6][l] - x[3][l] * x[8][l];
      c[2][l] = x[3][l] * x[7][l] - x[4][l] * x[6][l];
      c[3][l] = x[2][l] * x[7][l] - x[1][l] * x[8][l];
      c[4][l] = x[0][l] * x[8][l] - x[2][l] * x[6][l];
      c[5][l] = x[1][l] * x[6][l] - x[0][l] * x[7][l];
      c[6][l] = x[1][l] * x[5][l] - x[2][l] * x[4][l];
      c[7][l] = x[2][l] * x[3][l] - x[0][l] * x[5][l];
      c[8][l] = x[0][l] * x[4][l] - x[1][l] * x[3][l];
      det[l] = x[0][l] * c[0][l] + x[1][l] * c[1][l] + x[2][l] * c[2][l];
    }
#pragma omp simd
    for (int l = 0; l < W; ++l) {
      double sx = x[0][l] * x[0][l], sc = c[0][l] * c[0][l];
      for (int k = 1; k < 9; ++k) {
        sx += x[k][l] * x[k][l];
        sc += c[k][l] * c[k][l];
      }
      x2[l] = sx;
      cn2[l] = sc;
    }
  };
  cofactor();
#pragma omp simd
  for (int l = 0; l < W; ++l) z[l] = std::sqrt(x2[l]);
#pragma omp simd
  for (int l = 0; l < W; ++l) {
    // det <= 1e-9 |M|_F^3 catches det < 0, near-singular M and NaN (the comparison is false).
    active[l] = det[l] > 1e-9 * x2[l] * z[l] ? 1.0 : 0.0;
    ok[l] = 0.0;
    scale[l] = 1.0;
  }
  for (int it = 0; it < 16; ++it) {
// Higham's scaling z = (|X^-1|_F / |X|_F)^1/2, computed in every lane and used where scale is
// on; near the polar factor the unscaled iteration converges faster than the scaled one.
#pragma omp simd
    for (int l = 0; l < W; ++l) z[l] = std::sqrt(std::sqrt(cn2[l] / x2[l]) / det[l]);
#pragma omp simd
    for (int l = 0; l < W; ++l) {
      const double zl = z[l];
      const double zz = scale[l] > 0.0 ? zl : 1.0;
      a[l] = 0.5 * zz;
      b[l] = 0.5 / (zz * det[l]);
      step2[l] = 0.0;
    }
    for (int k = 0; k < 9; ++k)
#pragma omp simd
      for (int l = 0; l < W; ++l) {
        const double xo = x[k][l];
        const double xn = a[l] * xo + b[l] * c[k][l];
        step2[l] += (xn - xo) * (xn - xo);
        x[k][l] = active[l] > 0.0 ? xn : xo;
      }
    cofactor();
    double any = 0.0;
#pragma omp simd reduction(+ : any)
    for (int l = 0; l < W; ++l) {
      const double done = (active[l] > 0.0) & (step2[l] < 1e-18) ? 1.0 : 0.0;
      ok[l] = done > 0.0 ? 1.0 : ok[l];
      scale[l] = step2[l] < 1e-4 ? 0.0 : scale[l];
      // A step that made det(X) <= 0 (only through rounding) leaves the lane unhandled.
      active[l] = (active[l] > 0.0) & (done == 0.0) & (det[l] > 0.0) ? 1.0 : 0.0;
      any += active[l];
    }
    if (!(any > 0.0)) break;
  }
}

template <int W>
void LoadLanes(const Eigen::Matrix3d* M, int n, double x[9][W]) {
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c) {
      for (int l = 0; l < W; ++l) x[3 * r + c][l] = r == c ? 1.0 : 0.0;
      for (int l = 0; l < n; ++l) x[3 * r + c][l] = M[l](r, c);
    }
}

}  // namespace

// For det(M) > 0 the rotation is the orthogonal polar factor of M, found by Newton's polar
// iteration X <- (z X + X^-T / z) / 2 with Higham's Frobenius-norm scaling z (N. J. Higham,
// "Computing the polar decomposition with applications", SIAM J. Sci. Stat. Comput. 7(4), 1986),
// X^-T = cofactor(X) / det(X). Convergence is quadratic and the scaling makes the step count
// independent of the scale of M: 4-5 steps for the deformations of the local step. The iteration
// stops once a step changes X by less than 1e-9, so the error left is about 1e-18 plus rounding.
// Inverted (det <= 0), nearly singular (smallest singular value below about 1e-6 of the largest)
// or non-finite M, and any M that has not converged in 16 steps, go to the eigen-decomposition,
// which also handles the reflection case.
Eigen::Matrix3d BestRotation(const Eigen::Matrix3d& M) {
  double x[9][1], ok[1];
  LoadLanes<1>(&M, 1, x);
  NewtonPolar<1>(x, ok);
  if (!(ok[0] > 0.0)) return BestRotationEigen(M);
  Eigen::Matrix3d R;
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c) R(r, c) = x[3 * r + c][0];
  return R;
}

void BestRotations(const Eigen::Matrix3d* M, int n, Eigen::Matrix3d* R) {
  constexpr int W = kRotationBatch;
  for (int i0 = 0; i0 < n; i0 += W) {
    const int m = std::min(W, n - i0);
    double x[9][W], ok[W];
    LoadLanes<W>(M + i0, m, x);
    NewtonPolar<W>(x, ok);
    for (int l = 0; l < m; ++l) {
      if (!(ok[l] > 0.0)) {
        R[i0 + l] = BestRotationEigen(M[i0 + l]);
        continue;
      }
      for (int r = 0; r < 3; ++r)
        for (int c = 0; c < 3; ++c) R[i0 + l](r, c) = x[3 * r + c][l];
    }
  }
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
