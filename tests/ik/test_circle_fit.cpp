// The least-squares circle of the grasp objective (Eq. 4.7): exact on circles, invariant under
// rigid motions, and its derivative against finite differences.
#include "softkin/ik/circle_fit.hpp"

#include "ik_test_models.hpp"

#include <Eigen/Geometry>
#include <gtest/gtest.h>

#include <random>

namespace softkin {
namespace {

// n points on an arc of `span` radians of the circle (centre, unit normal, radius).
Eigen::MatrixX3d ArcPoints(const Eigen::Vector3d& centre, const Eigen::Vector3d& normal, double r,
                           double span, int n) {
  Eigen::Vector3d e1 = normal.unitOrthogonal(), e2 = normal.cross(e1);
  Eigen::MatrixX3d p(n, 3);
  for (int i = 0; i < n; ++i) {
    const double a = 0.3 + span * i / (n - 1);
    p.row(i) = (centre + r * (std::cos(a) * e1 + std::sin(a) * e2)).transpose();
  }
  return p;
}

TEST(CircleFit, ExactOnPointsOfACircleInSeveralPlanesAndSizes) {
  std::mt19937 rng(3);
  std::normal_distribution<double> g;
  int cases = 0;
  for (double r : {0.5, 12.0, 1000.0})
    for (double span : {1.0, 3.0, 2 * M_PI * 0.95})
      for (int trial = 0; trial < 3; ++trial) {
        const Eigen::Vector3d n = Eigen::Vector3d(g(rng), g(rng), g(rng)).normalized();
        const Eigen::Vector3d centre(100 * g(rng), 100 * g(rng), 100 * g(rng));
        const Eigen::MatrixX3d p = ArcPoints(centre, n, r, span, 9);
        for (bool given : {false, true}) {
          const CircleFit f = FitCircle(p, given ? n : Eigen::Vector3d::Zero(), false);
          ASSERT_TRUE(f.ok) << f.message;
          EXPECT_NEAR(f.radius, r, 1e-8 * r) << "r " << r << " span " << span;
          EXPECT_NEAR(f.diameter, 2 * r, 2e-8 * r);
          EXPECT_LT((f.center - centre).norm(), 1e-7 * std::max(r, 1.0));
          EXPECT_NEAR(std::abs(f.normal.dot(n)), 1.0, 1e-9);
          EXPECT_LT(f.rms_residual, 1e-8 * r);
          ++cases;
        }
      }
  EXPECT_EQ(cases, 54);
}

TEST(CircleFit, InvariantUnderRigidMotion) {
  std::mt19937 rng(5);
  std::normal_distribution<double> g;
  Eigen::MatrixX3d p = ArcPoints(Eigen::Vector3d(1, 2, 3), Eigen::Vector3d::UnitY(), 20, 2.0, 12);
  for (int i = 0; i < p.rows(); ++i) p.row(i) += 0.3 * Eigen::RowVector3d(g(rng), g(rng), g(rng));
  const CircleFit a = FitCircle(p, Eigen::Vector3d::Zero(), false);
  const Eigen::Matrix3d R =
      Eigen::AngleAxisd(0.7, Eigen::Vector3d(1, -2, 0.5).normalized()).toRotationMatrix();
  Eigen::MatrixX3d q = (p * R.transpose()).rowwise() + Eigen::RowVector3d(-40, 7, 300);
  const CircleFit b = FitCircle(q, Eigen::Vector3d::Zero(), false);
  ASSERT_TRUE(a.ok && b.ok);
  EXPECT_NEAR(a.diameter, b.diameter, 1e-9 * a.diameter);
  const CircleFit c = FitCircle(q, R * Eigen::Vector3d::UnitY(), false);
  const CircleFit d = FitCircle(p, Eigen::Vector3d::UnitY(), false);
  EXPECT_NEAR(c.diameter, d.diameter, 1e-9 * d.diameter);
}

TEST(CircleFit, DiameterDerivativeMatchesFiniteDifferences) {
  std::mt19937 rng(11);
  std::normal_distribution<double> g;
  int checked = 0;
  for (int trial = 0; trial < 4; ++trial) {
    const Eigen::Vector3d n = Eigen::Vector3d(g(rng), g(rng), g(rng)).normalized();
    Eigen::MatrixX3d p = ArcPoints(Eigen::Vector3d(g(rng), g(rng), g(rng)), n, 15 + 5 * trial,
                                   1.5 + trial, 7 + trial);
    for (int i = 0; i < p.rows(); ++i) p.row(i) += 0.5 * Eigen::RowVector3d(g(rng), g(rng), g(rng));
    for (bool given : {false, true}) {
      const Eigen::Vector3d pn =
          given ? Eigen::Vector3d(n + 0.1 * Eigen::Vector3d(g(rng), g(rng), g(rng)))
                : Eigen::Vector3d::Zero();
      const CircleFit f = FitCircle(p, pn, true);
      ASSERT_TRUE(f.ok) << f.message;
      const Eigen::MatrixXd fd = test::FdGradient(
          [&](const Eigen::MatrixXd& x) {
            const CircleFit fx = FitCircle(x, pn, false);
            EXPECT_TRUE(fx.ok);
            return fx.diameter;
          },
          p, 1e-6);
      EXPECT_TRUE(test::NearMatrix(f.d_diameter, fd, 1e-5, 1e-7))
          << "trial " << trial << " given " << given;
      ++checked;
    }
  }
  EXPECT_EQ(checked, 8);
}

TEST(CircleFit, DegenerateInputsAreReportedNotNaN) {
  Eigen::MatrixX3d two(2, 3);
  two << 0, 0, 0, 1, 0, 0;
  EXPECT_FALSE(FitCircle(two, Eigen::Vector3d::Zero(), true).ok);
  Eigen::MatrixX3d line(4, 3);
  for (int i = 0; i < 4; ++i) line.row(i) << i, 2 * i, 0;
  const CircleFit f = FitCircle(line, Eigen::Vector3d::UnitZ(), true);
  EXPECT_FALSE(f.ok);
  EXPECT_NE(f.message.find("collinear"), std::string::npos) << f.message;
  EXPECT_FALSE(FitCircle(line, Eigen::Vector3d::Zero(), true).ok);
}

TEST(CircleFit, AWideSlabNeedsTheGivenPlaneNormal) {
  // A bent strip 20 mm wide in y (the gripper's grip layer): the least-squares plane of the points
  // is the strip itself, not the bending plane x-z, so the plane must be given.
  const double r = 40;
  Eigen::MatrixX3d p(30, 3);
  for (int i = 0; i < 10; ++i)
    for (int j = 0; j < 3; ++j) {
      const double a = 0.6 * i / 9;
      p.row(3 * i + j) << r * std::sin(a), 10.0 * j, r * (1 - std::cos(a));
    }
  const CircleFit given = FitCircle(p, Eigen::Vector3d::UnitY(), false);
  ASSERT_TRUE(given.ok);
  EXPECT_NEAR(given.diameter, 2 * r, 1e-8);
  const CircleFit fitted = FitCircle(p, Eigen::Vector3d::Zero(), false);
  EXPECT_FALSE(fitted.ok && std::abs(fitted.diameter - 2 * r) < 1.0);
}

}  // namespace
}  // namespace softkin
