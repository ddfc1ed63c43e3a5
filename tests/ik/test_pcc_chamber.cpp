// The PCC model of three_chamber: straight when the chambers agree, bending away from the longest
// chamber, 3-fold symmetric, points on the arc, J against finite differences, and the fit.
#include "softkin/ik/pcc_chamber_kinematics.hpp"

#include "ik_test_models.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <random>

namespace softkin {
namespace {

constexpr double kPi = 3.14159265358979323846;

Eigen::Vector3d Tip(PccChamberKinematics& k, const Eigen::Vector3d& c) {
  const KinematicsEval e = k.Evaluate(c, false);
  EXPECT_TRUE(e.ok) << e.message;
  return e.p.row(0).transpose();
}

TEST(PccChamber, EqualChambersGiveAStraightLongerActuator) {
  PccChamberKinematics k;
  EXPECT_TRUE(test::NearMatrix(Tip(k, Eigen::Vector3d(1, 1, 1)).transpose(),
                               Eigen::RowVector3d(0, 136, 0), 0, 1e-12));
  const PccChamberParams& p = k.params();
  for (double c : {1.5, 2.0, 3.0}) {
    const Eigen::Vector3d t = Tip(k, Eigen::Vector3d(c, c, c));
    EXPECT_NEAR(t.x(), 0.0, 1e-12);
    EXPECT_NEAR(t.z(), 0.0, 1e-12);
    EXPECT_NEAR(t.y(), p.base + p.chamber_length * (1 + p.gain * (c - 1)) + p.cap, 1e-10);
    EXPECT_NEAR(k.ArcParameters(Eigen::Vector3d(c, c, c)).kappa, 0.0, 1e-15);
  }
}

TEST(PccChamber, OneChamberBendsTheTipAwayFromIt) {
  PccChamberKinematics k;
  for (int a = 0; a < 3; ++a) {
    Eigen::Vector3d c = Eigen::Vector3d::Ones();
    c[a] = 2.5;
    const Eigen::Vector3d t = Tip(k, c);
    const double away = (180.0 + 120.0 * a + 180.0) * kPi / 180.0;  // opposite the chamber
    const Eigen::Vector2d dir(std::cos(away), std::sin(away));
    const Eigen::Vector2d lateral(t.x(), t.z());
    EXPECT_GT(lateral.norm(), 10.0) << a;
    EXPECT_NEAR(lateral.normalized().dot(dir), 1.0, 1e-12) << a;
    const PccArc arc = k.ArcParameters(c);
    EXPECT_NEAR(std::cos(arc.phi - away), 1.0, 1e-12) << a;
  }
}

TEST(PccChamber, RotatingTheActuationRotatesTheTipBy120Degrees) {
  PccChamberKinematics k;
  const Eigen::Vector3d c(1.3, 2.7, 1.9);
  const Eigen::Vector3d t0 = Tip(k, c);
  // Chamber k takes actuator k-1's value: the pattern turns by +120 degrees in phi.
  const Eigen::Vector3d t1 = Tip(k, Eigen::Vector3d(c[2], c[0], c[1]));
  const double a = 120.0 * kPi / 180.0;
  const Eigen::Vector2d r(std::cos(a) * t0.x() - std::sin(a) * t0.z(),
                          std::sin(a) * t0.x() + std::cos(a) * t0.z());
  EXPECT_NEAR(t1.x(), r.x(), 1e-10);
  EXPECT_NEAR(t1.z(), r.y(), 1e-10);
  EXPECT_NEAR(t1.y(), t0.y(), 1e-10);
}

TEST(PccChamber, TipLiesOnTheArcPlusTheTangentCap) {
  PccChamberParams p;
  p.cap = 0.0;  // then the tip is the arc's end: at distance 1/kappa from the centre of curvature
  PccChamberKinematics k(p);
  const Eigen::Vector3d c(2.6, 1.2, 1.0);
  const PccArc arc = k.ArcParameters(c);
  ASSERT_GT(arc.kappa, 1e-3);
  const Eigen::Vector3d centre(std::cos(arc.phi) / arc.kappa, p.base,
                               std::sin(arc.phi) / arc.kappa);
  const Eigen::Vector3d t = Tip(k, c);
  EXPECT_NEAR((t - centre).norm(), 1.0 / arc.kappa, 1e-9);
  // The angle swept is kappa * l.
  const Eigen::Vector3d from = Eigen::Vector3d(0, p.base, 0) - centre, to = t - centre;
  EXPECT_NEAR(std::acos(from.dot(to) / (from.norm() * to.norm())), arc.kappa * arc.length, 1e-9);
}

TEST(PccChamber, JacobianMatchesCentralDifferencesIncludingStraight) {
  PccChamberKinematics k;
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> u(1.05, 2.95);
  std::vector<Eigen::Vector3d> cs = {Eigen::Vector3d(2, 2, 2), Eigen::Vector3d(1.5, 1.5, 1.5)};
  for (int i = 0; i < 6; ++i) cs.emplace_back(u(rng), u(rng), u(rng));
  for (const Eigen::Vector3d& c : cs) {
    const KinematicsEval e = k.Evaluate(c, true);
    ASSERT_TRUE(e.ok);
    Eigen::Matrix3d fd;
    for (int a = 0; a < 3; ++a) {
      Eigen::Vector3d cp = c, cm = c;
      cp[a] += 1e-6;
      cm[a] -= 1e-6;
      fd.col(a) = (Tip(k, cp) - Tip(k, cm)) / 2e-6;
    }
    EXPECT_TRUE(test::NearMatrix(e.J, fd, 1e-6, 1e-5)) << c.transpose();
    EXPECT_TRUE(test::NearMatrix(e.p, Tip(k, c).transpose(), 0, 1e-12));
  }
}

TEST(PccChamber, BadActuationIsReportedNotThrown) {
  PccChamberKinematics k;
  EXPECT_FALSE(k.Evaluate(Eigen::Vector3d(0.5, 1, 1), true).ok);
  EXPECT_FALSE(k.Evaluate(Eigen::Vector3d(std::nan(""), 1, 1), false).ok);
  EXPECT_FALSE(k.Evaluate(Eigen::Vector2d(1, 1), false).ok);
  PccChamberParams p;
  p.offset = -1;
  EXPECT_THROW(PccChamberKinematics{p}, std::invalid_argument);
}

TEST(PccChamber, FitRecoversGainOffsetAndCap) {
  PccChamberParams truth;
  truth.gain = 0.22;
  truth.offset = 15.5;
  truth.cap = 5.0;
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> u(1.0, 3.0);
  Eigen::MatrixXd C(60, 3), P(60, 3);
  for (int i = 0; i < 60; ++i) {
    C.row(i) << u(rng), u(rng), u(rng);
    P.row(i) = PccChamberKinematics::Tip(truth, C.row(i).transpose()).transpose();
  }
  const PccFitResult f = FitPccChamber(C, P);  // from the defaults 0.3, 13, 8
  EXPECT_GT(f.rms_start_mm, 1.0);
  EXPECT_LT(f.rms_mm, 1e-6) << f.iterations << " iterations, gain " << f.params.gain << " offset "
                            << f.params.offset;
  EXPECT_NEAR(f.params.gain, 0.22, 1e-6);
  EXPECT_NEAR(f.params.offset, 15.5, 1e-5);
  EXPECT_NEAR(f.params.cap, 5.0, 1e-5);
  EXPECT_THROW(FitPccChamber(C.topRows(2), P.topRows(2)), std::invalid_argument);
  EXPECT_THROW(FitPccChamber(C, P.topRows(10)), std::invalid_argument);
  Eigen::MatrixXd Pn = P;
  Pn(3, 1) = std::nan("");
  EXPECT_THROW(FitPccChamber(C, Pn), std::invalid_argument);
}

}  // namespace
}  // namespace softkin
