// Tests of the FK energy (solver/fk/energy.hpp), the target shapes and local ratios
// (solver/fk/targets.hpp) and the best-fit rotation (solver/fk/rotation.hpp). Every check is an
// identity (zero at rest, rigid-motion invariance, finite differences, volume and congruence of
// targets), not a stored number.
#include "softkin/solver/fk/energy.hpp"
#include "softkin/solver/fk/model.hpp"
#include "softkin/solver/fk/rotation.hpp"
#include "softkin/solver/fk/targets.hpp"

#include "tests/solver/test_util.hpp"

#include <Eigen/Eigenvalues>
#include <gtest/gtest.h>
#include <omp.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <memory>
#include <cstring>
#include <limits>
#include <random>
#include <vector>

namespace softkin {
namespace {

using test::MatrixNear;
using test::MatrixRelNear;
using test::Pneumatic;
using test::RandomMatrix;
using test::RandomRotation;

// ---------------------------------------------------------------------------------------------
// Scenes
// ---------------------------------------------------------------------------------------------

// 4 x 2 x 2 voxel bar (h = 1 mm, 96 tets): region 0 body r_omega 1, region 1 body r_omega 0.3
// (the x = 3 cells), region 2 pneumatic "p" (upper layer, x = 1..2: 24 tets).
Scene MixedTetScene(double r_soft = 0.3) {
  auto region = [](const Eigen::Vector3i& c) {
    if (c.x() == 3) return 1;
    if (c.z() == 1 && (c.x() == 1 || c.x() == 2)) return 2;
    return 0;
  };
  return test::VoxelScene({4, 2, 2}, 1.0, region,
                          {{0, Material{"stiff", 1.0, 1.0}}, {1, Material{"soft", r_soft, 1.0}}},
                          {Pneumatic("p", {2})}, "mixed_tets");
}

// Hand-built prism slab 3 x 2 squares x 2 layers (24 prisms, h = 1 mm): region 0 body r_omega 1,
// region 1 body r_omega 0.3 (the i = 2 column), region 2 pneumatic "p" (top layer, i = 1).
Scene MixedPrismScene() {
  Scene s;
  s.name = "prism_slab";
  s.mesh = test::PrismSlab(3, 2, 2, 1.0, [](int i, int, int l) {
    if (i == 2) return 1;
    if (i == 1 && l == 1) return 2;
    return 0;
  });
  s.body = {{0, Material{"stiff", 1.0, 1.0}}, {1, Material{"soft", 0.3, 1.0}}};
  s.actuators = {Pneumatic("p", {2})};
  test::FinishScene(&s);
  return s;
}

double CentroidX(const Mesh& mesh, const Element& e) {
  double cx = 0;
  for (int j = 0; j < e.k(); ++j) cx += mesh.vertices(e.v[j], 0) / e.k();
  return cx;
}

// Positions rest + Gaussian noise (sigma = amp * h). Checks that no element shrinks below half of
// its rest volume, so the energy is smooth there.
Eigen::MatrixX3d Perturbed(const Model& m, double amp, unsigned seed) {
  std::mt19937 rng(seed);
  std::normal_distribution<double> n(0.0, amp);
  Eigen::MatrixX3d X = m.rest_positions();
  for (int i = 0; i < X.rows(); ++i)
    for (int d = 0; d < 3; ++d) X(i, d) += n(rng);
  for (const auto& e : m.elements()) {
    ElemRows P;
    for (int j = 0; j < e.k; ++j) P.row(j) = X.row(e.v[j]);
    EXPECT_GT(RowsVolume(P, e.k), 0.5 * e.rest_volume) << "perturbation too large";
  }
  return X;
}

// Energy scale: sum_i w_i Vol_i ||N V_i||^2 (the energy of collapsing every element to a point).
double EnergyScale(const Model& m) {
  double s = 0.0;
  for (const auto& e : m.elements()) s += e.wv * e.rest.topRows(e.k).squaredNorm();
  return s;
}

// Limits OpenMP to n threads in scope (Energy() opens a parallel region per call; thousands of
// tiny calls are dominated by thread start-up on a busy machine). Results do not depend on it.
struct ScopedOmpThreads {
  explicit ScopedOmpThreads(int n) : prev(omp_get_max_threads()) { omp_set_num_threads(n); }
  ~ScopedOmpThreads() { omp_set_num_threads(prev); }
  int prev;
};

// Central finite differences of Energy() for every vertex coordinate.
Eigen::MatrixX3d FdGradient(const Model& m, const Eigen::MatrixX3d& X, const Eigen::VectorXd& c,
                            double step) {
  ScopedOmpThreads one(1);
  Eigen::MatrixX3d G(X.rows(), 3);
  Eigen::MatrixX3d Y = X;
  for (int i = 0; i < X.rows(); ++i)
    for (int d = 0; d < 3; ++d) {
      Y(i, d) = X(i, d) + step;
      const double ep = Energy(m, Y, c);
      Y(i, d) = X(i, d) - step;
      const double em = Energy(m, Y, c);
      Y(i, d) = X(i, d);
      G(i, d) = (ep - em) / (2.0 * step);
    }
  return G;
}

// Checks EnergyAndGradient against central differences; returns the worst relative error.
double CheckGradient(const Model& m, const Eigen::MatrixX3d& X, const Eigen::VectorXd& c,
                     const char* what) {
  Eigen::MatrixX3d g;
  const double E = EnergyAndGradient(m, X, c, &g);
  EXPECT_NEAR(E, Energy(m, X, c), 1e-12 * E) << what;
  const Eigen::MatrixX3d fd = FdGradient(m, X, c, 1e-5 * m.size());
  double worst = 0.0;
  // Every component within 1e-5 relative; components smaller than 1e-3 of the largest are measured
  // against that floor (their own relative error is dominated by finite-difference rounding).
  EXPECT_TRUE(MatrixRelNear(g, fd, 1e-5, 1e-3, &worst)) << what;
  std::printf("  [%s] E = %.6g, |g|_inf = %.4g, worst relative error vs FD = %.3g\n", what, E,
              g.cwiseAbs().maxCoeff(), worst);
  return worst;
}

std::vector<double> PairwiseDistances(const ElemRows& P, int k) {
  std::vector<double> d;
  for (int a = 0; a < k; ++a)
    for (int b = a + 1; b < k; ++b) d.push_back((P.row(a) - P.row(b)).norm());
  return d;
}

// ---------------------------------------------------------------------------------------------
// Rotation
// ---------------------------------------------------------------------------------------------

void ExpectProperRotation(const Eigen::Matrix3d& R, const char* what) {
  EXPECT_TRUE(MatrixNear(R.transpose() * R, Eigen::Matrix3d::Identity(), 1e-12)) << what;
  EXPECT_NEAR(R.determinant(), 1.0, 1e-12) << what;
}

TEST(Rotation, MatchesSvdOnRandomMatrices) {
  std::mt19937 rng(1234);
  double worst = 0.0;
  int negative_det = 0;
  for (int t = 0; t < 2000; ++t) {
    const Eigen::Matrix3d M = RandomMatrix(rng, 3, 3);
    if (M.determinant() < 0) ++negative_det;
    const Eigen::Matrix3d R = BestRotation(M);
    const Eigen::Matrix3d Rs = BestRotationSvd(M);
    ExpectProperRotation(R, "BestRotation");
    ExpectProperRotation(Rs, "BestRotationSvd");
    // Condition of the polar factor: errors scale like eps / (smallest pair sum of singular
    // values); skip comparing entries only when that is tiny (never for these seeds, but keep the
    // check honest).
    Eigen::JacobiSVD<Eigen::Matrix3d> svd(M);
    const Eigen::Vector3d s = svd.singularValues();
    const double gap = (M.determinant() > 0 ? s(1) + s(2) : s(1) - s(2)) / s(0);
    if (gap < 1e-4) continue;
    const double d = (R - Rs).cwiseAbs().maxCoeff();
    worst = std::max(worst, d * gap);
    ASSERT_TRUE(MatrixNear(R, Rs, 1e-9 / gap)) << "trial " << t << "\nM =\n" << M;
  }
  std::printf("  random: %d of 2000 with det < 0; worst |R - Rsvd| * gap = %.3g\n", negative_det,
              worst);
  EXPECT_GT(negative_det, 500);  // the reflection branch was exercised
}

TEST(Rotation, ReflectionGivesBestProperRotation) {
  std::mt19937 rng(99);
  for (int t = 0; t < 20; ++t) {
    // A reflection-containing matrix with distinct singular values: Q1 diag(3, 2, -1) Q2.
    const Eigen::Matrix3d M =
        RandomRotation(rng) * Eigen::Vector3d(3.0, 2.0, -1.0).asDiagonal() * RandomRotation(rng);
    ASSERT_LT(M.determinant(), 0.0);
    const Eigen::Matrix3d R = BestRotation(M);
    ExpectProperRotation(R, "reflection case");
    const double best = (R.transpose() * M).trace();
    // The maximum of tr(R^T M) over rotations is s1 + s2 - s3 = 4.
    EXPECT_NEAR(best, 4.0, 1e-12);
    // Beats every sampled rotation, and every small perturbation of itself.
    for (int q = 0; q < 2000; ++q) {
      const Eigen::Matrix3d Q = RandomRotation(rng);
      ASSERT_LE((Q.transpose() * M).trace(), best + 1e-12);
    }
    std::normal_distribution<double> n(0.0, 1.0);
    for (int q = 0; q < 200; ++q) {
      const Eigen::Vector3d w(n(rng), n(rng), n(rng));
      const Eigen::Matrix3d Q = Eigen::AngleAxisd(1e-3, w.normalized()).toRotationMatrix() * R;
      ASSERT_LT((Q.transpose() * M).trace(), best);
    }
    EXPECT_TRUE(MatrixNear(R, BestRotationSvd(M), 1e-10));
    // A pure reflection of a rotation: M = Q diag(1, 1, -1). Best proper rotation trace = 1.
    const Eigen::Matrix3d Q0 = RandomRotation(rng);
    const Eigen::Matrix3d Mr = Q0 * Eigen::Vector3d(1.0, 2.0, -0.5).asDiagonal();
    const Eigen::Matrix3d Rr = BestRotation(Mr);
    ExpectProperRotation(Rr, "pure reflection");
    EXPECT_NEAR((Rr.transpose() * Mr).trace(), 2.5, 1e-12);
  }
}

// Degenerate inputs (rank deficient, repeated or tiny singular values, huge and tiny scales): the
// result is still optimal, has det = +1 and is orthonormal to 1e-6. (The strict 1e-12
// orthonormality check for repeated singular values is the next test.)
TEST(Rotation, DegenerateAndScaledInputs) {
  std::mt19937 rng(7);
  auto check = [](const Eigen::Matrix3d& R, const char* what) {
    EXPECT_TRUE(MatrixNear(R.transpose() * R, Eigen::Matrix3d::Identity(), 1e-6)) << what;
    EXPECT_NEAR(R.determinant(), 1.0, 1e-12) << what;
  };
  // Zero matrix: any rotation is optimal; must still be a rotation.
  ExpectProperRotation(BestRotation(Eigen::Matrix3d::Zero()), "zero");
  for (int t = 0; t < 50; ++t) {
    const Eigen::Matrix3d Q1 = RandomRotation(rng), Q2 = RandomRotation(rng);
    const Eigen::Matrix3d cases[] = {
        Q1 * Eigen::Vector3d(2.0, 1.0, 0.0).asDiagonal() * Q2,         // rank 2
        Q1 * Eigen::Vector3d(1.0, 0.0, 0.0).asDiagonal() * Q2,         // rank 1
        Q1 * Eigen::Vector3d(1.0, 1.0 + 1e-9, 0.3).asDiagonal() * Q2,  // near-repeated
        Q1 * Eigen::Vector3d(1.0, 1.0, 1.0).asDiagonal() * Q2,         // a rotation
        Q1 * Eigen::Vector3d(1.0, 1e-7, -1e-7).asDiagonal() * Q2,      // nearly rank 1, det<0
    };
    for (const auto& M : cases) {
      const Eigen::Matrix3d R = BestRotation(M);
      check(R, "degenerate");
      const double tr = (R.transpose() * M).trace();
      const double tr_svd = (BestRotationSvd(M).transpose() * M).trace();
      EXPECT_GE(tr, tr_svd - 1e-12 * M.norm()) << "M =\n" << M;
      // Scale invariance over 16 orders of magnitude.
      for (double s : {1e-8, 1e8}) {
        const Eigen::Matrix3d Rs = BestRotation(s * M);
        check(Rs, "scaled");
        EXPECT_NEAR((Rs.transpose() * M).trace(), tr, 1e-10 * M.norm());
      }
    }
    // An exact rotation is returned unchanged.
    EXPECT_TRUE(MatrixNear(BestRotation(Q1), Q1, 1e-13));
  }
}

// The header promises a rotation. With two equal singular values (M = Q1 diag(1, 1, 0.3) Q2,
// diag(2, 1, 1), or rank 1) the eigenvectors from SelfAdjointEigenSolver::computeDirect are not
// orthogonal to working precision, and R = U V^T inherits that: |R^T R - I| reaches ~1e-8
// (sqrt(eps)), where the SVD reference stays at 1e-15. EXPECTED TO FAIL until rotation.cpp
// re-orthonormalises V.
TEST(Rotation, OrthonormalWithRepeatedSingularValues) {
  std::mt19937 rng(8);
  const Eigen::Vector3d diags[] = {{1.0, 1.0, 0.3}, {2.0, 1.0, 1.0}, {1.0, 0.0, 0.0}};
  for (const auto& sv : diags) {
    double worst = 0.0, worst_svd = 0.0;
    for (int t = 0; t < 200; ++t) {
      const Eigen::Matrix3d M = RandomRotation(rng) * sv.asDiagonal() * RandomRotation(rng);
      const Eigen::Matrix3d R = BestRotation(M), Rs = BestRotationSvd(M);
      worst =
          std::max(worst, (R.transpose() * R - Eigen::Matrix3d::Identity()).cwiseAbs().maxCoeff());
      worst_svd = std::max(
          worst_svd, (Rs.transpose() * Rs - Eigen::Matrix3d::Identity()).cwiseAbs().maxCoeff());
    }
    std::printf("  singular values (%g, %g, %g): max |R^T R - I| = %.3g (SVD reference %.3g)\n",
                sv(0), sv(1), sv(2), worst, worst_svd);
    EXPECT_LE(worst, 1e-12) << "singular values " << sv.transpose();
    EXPECT_LE(worst_svd, 1e-12);
  }
}

// The batched rotations (LocalStep's path) return BestRotation's bits for every kind of input in
// every lane position, for full and partial batches: well-conditioned and strongly stretched
// matrices (Newton iteration), inverted and rank-deficient ones (eigen fallback), exact rotations
// and a NaN matrix, which must not spoil its neighbours.
TEST(Rotation, BatchMatchesSingleBitForBit) {
  std::mt19937 rng(4321);
  std::vector<Eigen::Matrix3d> M;
  for (int t = 0; t < 203; ++t) {
    const Eigen::Matrix3d Q1 = RandomRotation(rng), Q2 = RandomRotation(rng);
    switch (t % 7) {
      case 0:
        M.push_back(RandomMatrix(rng, 3, 3));
        break;
      case 1:
        M.push_back(Q1 * Eigen::Vector3d(40.0, 1.0, 0.02).asDiagonal() * Q2);
        break;
      case 2:
        M.push_back(Q1 * Eigen::Vector3d(3.0, 2.0, -1.0).asDiagonal() * Q2);
        break;
      case 3:
        M.push_back(Q1 * Eigen::Vector3d(2.0, 1.0, 0.0).asDiagonal() * Q2);
        break;
      case 4:
        M.push_back(Q1);
        break;
      case 5:
        M.push_back(1e-8 * Q1 * Eigen::Vector3d(1.0, 1.5, 1.2).asDiagonal());
        break;
      default:
        M.push_back(Q1 * Eigen::Vector3d(1.1, 0.9, 1.0).asDiagonal() * Q2);
        break;
    }
  }
  M[17](1, 2) = std::numeric_limits<double>::quiet_NaN();
  int newton_lanes = 0;
  for (int n : {1, 3, kRotationBatch, kRotationBatch + 5, static_cast<int>(M.size())}) {
    for (int first : {0, 1, 6}) {
      if (first + n > static_cast<int>(M.size())) continue;
      std::vector<Eigen::Matrix3d> R(n);
      BestRotations(M.data() + first, n, R.data());
      for (int i = 0; i < n; ++i) {
        const Eigen::Matrix3d Rs = BestRotation(M[first + i]);
        if (first + i == 17) {
          // NaN in, a rotation out (the fallback's identity), like the single call.
          ExpectProperRotation(R[i], "NaN input");
        }
        ASSERT_EQ(std::memcmp(R[i].data(), Rs.data(), sizeof(double) * 9), 0)
            << "n " << n << " first " << first << " lane " << i << "\nM =\n"
            << M[first + i] << "\nbatch\n"
            << R[i] << "\nsingle\n"
            << Rs;
        if (M[first + i].determinant() > 0.1) ++newton_lanes;
      }
    }
  }
  EXPECT_GT(newton_lanes, 100);
  // And they are the reflection-safe optimum (checked against the SVD above, spot-checked here).
  std::vector<Eigen::Matrix3d> R(M.size());
  BestRotations(M.data(), static_cast<int>(M.size()), R.data());
  for (size_t i = 0; i < M.size(); ++i) {
    if (i == 17) continue;
    const double tr = (R[i].transpose() * M[i]).trace();
    const double tr_svd = (BestRotationSvd(M[i]).transpose() * M[i]).trace();
    EXPECT_NEAR(tr, tr_svd, 1e-12 * M[i].norm()) << "matrix " << i;
  }
}

// ---------------------------------------------------------------------------------------------
// Energy
// ---------------------------------------------------------------------------------------------

void ExpectZeroAtRest(const Scene& scene, const char* what) {
  const Model m(scene);
  const Eigen::VectorXd c = scene.rest_actuation();
  const Eigen::MatrixX3d& X = m.rest_positions();
  const double scale = EnergyScale(m);
  const double gscale = scale / m.size();
  const double E = Energy(m, X, c);
  EXPECT_LE(E, 1e-24 * scale) << what;
  EXPECT_GE(E, 0.0) << what;
  Eigen::MatrixX3d g, gf;
  EXPECT_LE(EnergyAndGradient(m, X, c, &g), 1e-24 * scale) << what;
  EXPECT_LE(FrozenTargetGradient(m, X, c, &gf), 1e-24 * scale) << what;
  const Eigen::MatrixX3d zero = Eigen::MatrixX3d::Zero(X.rows(), 3);
  EXPECT_TRUE(MatrixNear(g, zero, 1e-13 * gscale)) << what << " exact gradient";
  EXPECT_TRUE(MatrixNear(gf, zero, 1e-13 * gscale)) << what << " frozen-target gradient";
  std::printf("  [%s] rest: E = %.3g (scale %.3g), |g| = %.3g, |g_frozen| = %.3g\n", what, E, scale,
              g.cwiseAbs().maxCoeff(), gf.cwiseAbs().maxCoeff());
  // The same scene away from rest has clearly nonzero energy and gradient (the checks can fail).
  Eigen::VectorXd c2 = c;
  c2.setConstant(1.5);
  EXPECT_GT(EnergyAndGradient(m, X, c2, &g), 1e-6 * scale) << what;
  EXPECT_GT(g.cwiseAbs().maxCoeff(), 1e-6 * gscale) << what;
}

TEST(Energy, ZeroWithZeroGradientAtRestTets) { ExpectZeroAtRest(MixedTetScene(), "tets"); }

TEST(Energy, ZeroWithZeroGradientAtRestPrisms) {
  const Scene s = MixedPrismScene();
  ASSERT_EQ(s.mesh.num_prisms(), 24);
  ExpectZeroAtRest(s, "prisms");
}

void ExpectRigidInvariance(const Scene& scene, unsigned seed, const char* what) {
  const Model m(scene);
  Eigen::VectorXd c = scene.rest_actuation();
  c.setConstant(1.7);
  std::mt19937 rng(seed);
  for (int t = 0; t < 5; ++t) {
    const Eigen::MatrixX3d X = Perturbed(m, 0.05, seed + t);
    const Eigen::Matrix3d Q = RandomRotation(rng);
    const Eigen::RowVector3d tr = 100.0 * RandomMatrix(rng, 1, 3);
    const Eigen::MatrixX3d Y = (X * Q.transpose()).rowwise() + tr;
    Eigen::MatrixX3d gX, gY;
    const double EX = EnergyAndGradient(m, X, c, &gX);
    const double EY = EnergyAndGradient(m, Y, c, &gY);
    EXPECT_GT(EX, 0.0);
    EXPECT_NEAR(EY, EX, 1e-10 * EX) << what;
    EXPECT_NEAR(Energy(m, Y, c), Energy(m, X, c), 1e-10 * EX) << what;
    // The gradient rotates with the body: grad(Q X + t) = grad(X) Q^T.
    EXPECT_TRUE(MatrixNear(gY, gX * Q.transpose(), 1e-8 * gX.cwiseAbs().maxCoeff())) << what;
  }
}

TEST(Energy, InvariantUnderRigidMotionTets) { ExpectRigidInvariance(MixedTetScene(), 11, "tets"); }
TEST(Energy, InvariantUnderRigidMotionPrisms) {
  ExpectRigidInvariance(MixedPrismScene(), 12, "prisms");
}

// (a) r_omega = 1 body with a single pneumatic tet, c > 1 (alpha_i = c exactly).
TEST(Energy, GradientMatchesFiniteDifferencesRigidBodySinglePneumaticTet) {
  Scene s = test::VoxelScene({3, 2, 2}, 1.0, [](const Eigen::Vector3i&) { return 0; },
                             {{0, Material{"body", 1.0, 1.0}}}, {});
  // Re-tag one tet of an interior-ish cell as the only pneumatic element.
  s.mesh.elements[6 * 7 + 2].region = 2;
  s.actuators = {Pneumatic("p", {2})};
  s.validate();
  const Model m(s);
  ASSERT_EQ(m.actuator_elements(0).size(), 1u);
  Eigen::VectorXd c(1);
  c << 1.8;
  CheckGradient(m, Perturbed(m, 0.05, 21), c, "r=1 + 1 pneumatic tet");
}

// (b) r_omega = 0.3 body everywhere (shape blending, Eq. 2.5) plus one r_omega 0 column.
TEST(Energy, GradientMatchesFiniteDifferencesBlendedBody) {
  const Scene s =
      test::VoxelScene({3, 2, 2}, 1.0, [](const Eigen::Vector3i& c) { return c.x() == 2 ? 1 : 0; },
                       {{0, Material{"soft", 0.3, 1.0}}, {1, Material{"softest", 0.0, 2.0}}}, {});
  const Model m(s);
  CheckGradient(m, Perturbed(m, 0.06, 22), Eigen::VectorXd(0), "r=0.3/0 body");
}

// (c) Many pneumatic elements in two actuators: the volume-proportional local ratios couple them.
TEST(Energy, GradientMatchesFiniteDifferencesManyPneumaticElements) {
  const Scene s = MixedTetScene();
  Scene s2 = s;
  // Split the actuator region: upper layer x = 1 -> actuator "p", x = 2 -> actuator "q".
  for (auto& e : s2.mesh.elements)
    if (e.region == 2 && CentroidX(s2.mesh, e) > 2.0) e.region = 3;
  s2.actuators = {Pneumatic("p", {2}), Pneumatic("q", {3}, 8.0)};
  s2.validate();
  const Model m(s2);
  ASSERT_EQ(m.actuator_elements(0).size(), 12u);
  ASSERT_EQ(m.actuator_elements(1).size(), 12u);
  Eigen::VectorXd c(2);
  c << 1.4, 2.2;
  const Eigen::MatrixX3d X = Perturbed(m, 0.05, 23);
  // The local ratios really are non-uniform here.
  std::vector<double> ratios;
  ComputeLocalRatios(m, X, c, &ratios);
  double lo = 1e9, hi = 0;
  for (int i : m.actuator_elements(0)) lo = std::min(lo, ratios[i]), hi = std::max(hi, ratios[i]);
  EXPECT_GT(hi - lo, 1e-3);
  CheckGradient(m, X, c, "2 actuators x 12 tets");
}

TEST(Energy, GradientMatchesFiniteDifferencesPrisms) {
  const Model m(MixedPrismScene());
  Eigen::VectorXd c(1);
  c << 1.6;
  CheckGradient(m, Perturbed(m, 0.05, 24), c, "prism slab");
}

TEST(Energy, FrozenTargetGradientEqualsExactForRigidBodiesWithoutActuators) {
  const Scene s =
      test::VoxelScene({3, 2, 2}, 1.0, [](const Eigen::Vector3i& c) { return c.x() == 2 ? 1 : 0; },
                       {{0, Material{"a", 1.0, 1.0}}, {1, Material{"b", 1.0, 3.0}}}, {});
  const Model m(s);
  const Eigen::VectorXd c(0);
  const Eigen::MatrixX3d X = Perturbed(m, 0.08, 31);
  Eigen::MatrixX3d g, gf;
  const double E = EnergyAndGradient(m, X, c, &g);
  const double Ef = FrozenTargetGradient(m, X, c, &gf);
  EXPECT_NEAR(Ef, E, 1e-12 * E);
  EXPECT_TRUE(MatrixNear(gf, g, 1e-10 * g.cwiseAbs().maxCoeff()));
  // With r_omega < 1 they differ (documented: the fixed point of Algorithm 1 is not a stationary
  // point of E then).
  const Model m2(MixedTetScene());
  Eigen::VectorXd c2(1);
  c2 << 1.0;
  const Eigen::MatrixX3d X2 = Perturbed(m2, 0.08, 32);
  EnergyAndGradient(m2, X2, c2, &g);
  FrozenTargetGradient(m2, X2, c2, &gf);
  EXPECT_GT((gf - g).norm(), 1e-3 * g.norm());
}

// ---------------------------------------------------------------------------------------------
// Targets
// ---------------------------------------------------------------------------------------------

// Centred current rows of element e: its rest shape rotated by Q, scaled by s, plus noise.
ElemRows CurrentRows(const ModelElement& e, const Eigen::Matrix3d& Q, double s, double noise,
                     std::mt19937& rng) {
  std::normal_distribution<double> n(0.0, noise);
  ElemRows D = ElemRows::Zero();
  D.topRows(e.k) = s * e.rest.topRows(e.k) * Q.transpose();
  for (int j = 0; j < e.k; ++j)
    for (int d = 0; d < 3; ++d) D(j, d) += n(rng);
  CenterRows(D, e.k);
  return D;
}

// D^T T symmetric positive semi-definite: T is aligned (best rotation) with D.
void ExpectAligned(const ElemRows& D, const ElemRows& T, int k, const char* what) {
  const Eigen::Matrix3d M = D.topRows(k).transpose() * T.topRows(k);
  EXPECT_LE((M - M.transpose()).norm(), 1e-12 * M.norm()) << what;
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> es(0.5 * (M + M.transpose()));
  EXPECT_GE(es.eigenvalues().minCoeff(), -1e-12 * M.norm()) << what;
}

void CheckTargets(const Model& m, const char* what) {
  std::mt19937 rng(41);
  int seen_body = 0, seen_pneu = 0;
  for (const auto& e0 : m.elements()) {
    const int k = e0.k;
    const Eigen::Matrix3d Q = RandomRotation(rng);
    const ElemRows D = CurrentRows(e0, Q, 1.1, 0.05, rng);
    const std::vector<double> d_rest = PairwiseDistances(e0.rest, k);
    ElemRows T;
    if (e0.role == ElementRole::Pneumatic) {
      ++seen_pneu;
      for (double alpha : {1.0, 1.5, 2.7}) {
        ElementTarget(e0, D, alpha, &T);
        EXPECT_NEAR(RowsVolume(T, k), alpha * e0.rest_volume, 1e-12 * e0.rest_volume) << what;
        const std::vector<double> dt = PairwiseDistances(T, k);
        for (size_t q = 0; q < dt.size(); ++q)
          EXPECT_NEAR(dt[q], std::cbrt(alpha) * d_rest[q], 1e-12) << what;
        EXPECT_LE(T.topRows(k).colwise().sum().norm(), 1e-13) << "centred";
        ExpectAligned(D, T, k, what);
        // A current shape that already is the rotated scaled rest shape is its own target.
        ElemRows Dx = ElemRows::Zero();
        Dx.topRows(k) = std::cbrt(alpha) * e0.rest.topRows(k) * Q.transpose();
        ElementTarget(e0, Dx, alpha, &T);
        EXPECT_TRUE(MatrixNear(T.topRows(k), Dx.topRows(k), 1e-13)) << what;
      }
      continue;
    }
    ++seen_body;
    ModelElement e = e0;
    // r_omega = 1: congruent to the rest shape, same (positive) volume, aligned with D.
    e.r_omega = 1.0;
    ElemRows T1;
    ElementTarget(e, D, 0.0, &T1);
    const std::vector<double> d1 = PairwiseDistances(T1, k);
    for (size_t q = 0; q < d1.size(); ++q) EXPECT_NEAR(d1[q], d_rest[q], 1e-12) << what;
    EXPECT_NEAR(RowsVolume(T1, k), e.rest_volume, 1e-12 * e.rest_volume) << what;
    ExpectAligned(D, T1, k, what);
    ElemRows Dr = ElemRows::Zero();
    Dr.topRows(k) = e.rest.topRows(k) * Q.transpose();
    ElementTarget(e, Dr, 0.0, &T);
    EXPECT_TRUE(MatrixNear(T.topRows(k), Dr.topRows(k), 1e-13)) << what << " rigid copy";
    // r_omega = 0: the current shape scaled back to the rest volume.
    e.r_omega = 0.0;
    ElemRows T0;
    ElementTarget(e, D, 0.0, &T0);
    EXPECT_NEAR(RowsVolume(T0, k), e.rest_volume, 1e-12 * e.rest_volume) << what;
    const double s = T0.topRows(k).cwiseProduct(D.topRows(k)).sum() / D.topRows(k).squaredNorm();
    EXPECT_TRUE(MatrixNear(T0.topRows(k), s * D.topRows(k), 1e-13)) << what << " T0 || D";
    EXPECT_NEAR(s, std::cbrt(e.rest_volume / RowsVolume(D, k)), 1e-13);
    // Linear blending (Eq. 2.5): T(0.3) = 0.3 T(1) + 0.7 T(0).
    e.r_omega = 0.3;
    ElementTarget(e, D, 0.0, &T);
    EXPECT_TRUE(MatrixNear(T.topRows(k), 0.3 * T1.topRows(k) + 0.7 * T0.topRows(k), 1e-13)) << what;
  }
  EXPECT_GT(seen_body, 0);
  EXPECT_GT(seen_pneu, 0);
}

TEST(Targets, ShapesPerElementTypeTets) { CheckTargets(Model(MixedTetScene()), "tets"); }
TEST(Targets, ShapesPerElementTypePrisms) { CheckTargets(Model(MixedPrismScene()), "prisms"); }

TEST(Targets, SinglePneumaticTetScene) {
  // One tet, all pneumatic, held 3-2-1 (no rigid motion left, free to deform): vertex 0 fixed,
  // vertex 1 held on y and z, vertex 2 on z.
  Scene s;
  s.name = "one_tet";
  s.mesh.vertices.resize(4, 3);
  s.mesh.vertices << 0, 0, 0, 2, 0, 0, 0, 1.5, 0, 0.3, 0.2, 1.2;
  Element e;
  e.v = {{0, 1, 2, 3, -1, -1}};
  e.region = 5;
  s.mesh.elements = {e};
  s.actuators = {Pneumatic("p", {5})};
  s.fixed = {0};
  s.fixed_axis[1] = {1};
  s.fixed_axis[2] = {1, 2};
  s.validate();
  const Model m(s);
  std::mt19937 rng(5);
  const ModelElement& me = m.elements()[0];
  EXPECT_NEAR(me.rest_volume, 2 * 1.5 * 1.2 / 6, 1e-15);
  const ElemRows D = CurrentRows(me, RandomRotation(rng), 0.9, 0.1, rng);
  const double alpha = 1.9;
  ElemRows T;
  ElementTarget(me, D, alpha, &T);
  EXPECT_NEAR(RowsVolume(T, 4), alpha * me.rest_volume, 1e-13);
  // Rotated scaled copy: T = cbrt(alpha) P R^T with R a proper rotation.
  const Eigen::Matrix3d M = me.rest.topRows(4).transpose() * me.rest.topRows(4);
  const Eigen::Matrix3d R =
      (M.inverse() * me.rest.topRows(4).transpose() * T.topRows(4) / std::cbrt(alpha)).transpose();
  ExpectProperRotation(R, "pneumatic target rotation");
  EXPECT_TRUE(
      MatrixNear(T.topRows(4), std::cbrt(alpha) * me.rest.topRows(4) * R.transpose(), 1e-13));
  // With a single element the local ratio is the actuation itself, for any current shape.
  Eigen::MatrixX3d X = m.rest_positions();
  X.row(3) += Eigen::RowVector3d(0.1, -0.2, 0.3);
  std::vector<double> ratios, achieved;
  Eigen::VectorXd c(1);
  c << alpha;
  ComputeLocalRatios(m, X, c, &ratios, &achieved);
  EXPECT_NEAR(ratios[0], alpha, 1e-14);
  ElemRows Xr;
  for (int j = 0; j < 4; ++j) Xr.row(j) = X.row(j);
  EXPECT_NEAR(achieved[0], RowsVolume(Xr, 4) / me.rest_volume, 1e-14);
}

void CheckLocalRatios(const Model& m, const Eigen::VectorXd& c, const char* what) {
  std::vector<double> ratios, achieved;
  // At rest: uniform ratios equal to the actuation, achieved = 1.
  ComputeLocalRatios(m, m.rest_positions(), c, &ratios, &achieved);
  for (int a = 0; a < m.num_actuators(); ++a) {
    EXPECT_NEAR(achieved[a], 1.0, 1e-14) << what;
    for (int i : m.actuator_elements(a)) EXPECT_NEAR(ratios[i], c[a], 1e-14 * c[a]) << what;
  }
  // Perturbed: sum_i alpha_i u_i = alpha U exactly, alpha_i proportional to Vol_i^d / u_i.
  std::mt19937 rng(3);
  for (int t = 0; t < 3; ++t) {
    const Eigen::MatrixX3d X = Perturbed(m, 0.08, 50 + t);
    ComputeLocalRatios(m, X, c, &ratios, &achieved);
    std::vector<char> is_act(m.elements().size(), 0);
    for (int a = 0; a < m.num_actuators(); ++a) {
      double sum = 0.0, Ud = 0.0, kmin = 1e300, kmax = 0;
      for (int i : m.actuator_elements(a)) {
        is_act[i] = 1;
        const ModelElement& e = m.elements()[i];
        sum += ratios[i] * e.rest_volume;
        ElemRows P;
        for (int j = 0; j < e.k; ++j) P.row(j) = X.row(e.v[j]);
        const double vd = RowsVolume(P, e.k);
        Ud += vd;
        const double kk = ratios[i] * e.rest_volume / vd;
        kmin = std::min(kmin, kk);
        kmax = std::max(kmax, kk);
      }
      const double U = m.actuator_rest_measure(a);
      EXPECT_NEAR(sum, c[a] * U, 1e-14 * c[a] * U) << what;
      EXPECT_NEAR(achieved[a], Ud / U, 1e-14) << what;
      EXPECT_LE(kmax - kmin, 1e-13 * kmax) << what << " proportional to current volume";
      EXPECT_GT(std::abs(achieved[a] - 1.0), 1e-6) << "perturbation changed the volume";
    }
    for (size_t i = 0; i < ratios.size(); ++i) {
      if (!is_act[i]) {
        EXPECT_EQ(ratios[i], 1.0) << "body element " << i;
      }
    }
  }
}

TEST(Targets, LocalRatiosTets) {
  Scene s = MixedTetScene();
  for (auto& e : s.mesh.elements)
    if (e.region == 2 && CentroidX(s.mesh, e) > 2.0) e.region = 3;
  s.actuators = {Pneumatic("p", {2}), Pneumatic("q", {3})};
  const Model m(s);
  Eigen::VectorXd c(2);
  c << 1.3, 2.5;
  CheckLocalRatios(m, c, "tets");
}

TEST(Targets, LocalRatiosPrisms) {
  const Model m(MixedPrismScene());
  Eigen::VectorXd c(1);
  c << 1.75;
  CheckLocalRatios(m, c, "prisms");
}

TEST(Targets, LocalStepEnergyIsSumOfElementResiduals) {
  // LocalStep's energy and weighted targets agree with ElementTarget element by element, and the
  // frozen-target gradient is 2 (A X - sum w Vol S^T T).
  const Model m(MixedTetScene());
  Eigen::VectorXd c(1);
  c << 1.5;
  const Eigen::MatrixX3d X = Perturbed(m, 0.05, 61);
  std::vector<double> ratios;
  ComputeLocalRatios(m, X, c, &ratios);
  std::vector<ElemRows> w;
  const double E = LocalStep(m, X, ratios, &w);
  double E2 = 0.0;
  Eigen::MatrixX3d B = Eigen::MatrixX3d::Zero(X.rows(), 3);
  for (size_t i = 0; i < m.elements().size(); ++i) {
    const ModelElement& e = m.elements()[i];
    ElemRows D = ElemRows::Zero(), T;
    for (int j = 0; j < e.k; ++j) D.row(j) = X.row(e.v[j]);
    CenterRows(D, e.k);
    ElementTarget(e, D, ratios[i], &T);
    E2 += e.wv * (D - T).squaredNorm();
    EXPECT_TRUE(MatrixNear(w[i], e.wv * T, 1e-14 * e.wv));
    for (int j = 0; j < e.k; ++j) B.row(e.v[j]) += e.wv * T.row(j);
  }
  EXPECT_NEAR(E, E2, 1e-12 * E);
  Eigen::MatrixX3d Ba, gf;
  AssembleRhs(m, w, &Ba);
  EXPECT_TRUE(MatrixNear(Ba, B, 1e-13));
  FrozenTargetGradient(m, X, c, &gf);
  EXPECT_TRUE(MatrixNear(gf, 2.0 * (m.A() * X - B), 1e-12));
}

}  // namespace
}  // namespace softkin
