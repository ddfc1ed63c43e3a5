// Every objective's gradient against finite differences, its least-squares form against its value
// and gradient, the chain rule through J, and the errors for missing points.
#include "softkin/ik/objectives.hpp"
#include "softkin/ik/pcc_kinematics.hpp"

#include "ik_test_models.hpp"

#include <gtest/gtest.h>

#include <memory>
#include <random>

namespace softkin {
namespace {

// A bent PCC configuration's points (9 points: tip, backbone[0..7]).
Eigen::MatrixX3d BentPoints(PccKinematics& k, const Eigen::Vector3d& c) {
  const KinematicsEval e = k.Evaluate(c, false);
  EXPECT_TRUE(e.ok);
  return e.p;
}

// Checks value/gradient against FD and the residual form against both.
void CheckObjective(const Objective& o, const Eigen::MatrixX3d& p, double rtol = 1e-6) {
  SCOPED_TRACE(o.name());
  Eigen::MatrixX3d g;
  const double v = o.Evaluate(p, &g);
  EXPECT_TRUE(std::isfinite(v));
  EXPECT_DOUBLE_EQ(o.Evaluate(p, nullptr), v);
  const Eigen::MatrixXd fd =
      test::FdGradient([&](const Eigen::MatrixXd& x) { return o.Evaluate(x, nullptr); }, p, 1e-6);
  EXPECT_TRUE(test::NearMatrix(g, fd, rtol, 1e-6 * std::max(1.0, fd.cwiseAbs().maxCoeff())));
  EXPECT_GT(g.cwiseAbs().maxCoeff(), 0.0);  // a nontrivial case
  ASSERT_GT(o.num_residuals(), 0);
  Eigen::VectorXd r;
  Eigen::MatrixXd dr;
  ASSERT_TRUE(o.Residuals(p, &r, &dr));
  EXPECT_EQ(r.size(), o.num_residuals());
  EXPECT_NEAR(r.squaredNorm(), v, 1e-10 * std::max(1.0, v));
  const Eigen::VectorXd g2 = 2.0 * dr.transpose() * r;
  Eigen::MatrixXd g2m(p.rows(), 3);
  for (int i = 0; i < p.rows(); ++i)
    for (int d = 0; d < 3; ++d) g2m(i, d) = g2[3 * i + d];
  EXPECT_TRUE(test::NearMatrix(g2m, g, 1e-9, 1e-9));
}

class ObjectivesTest : public ::testing::Test {
 protected:
  PccKinematics k;
  const std::vector<std::string>& names = k.point_names();
  Eigen::MatrixX3d p = BentPoints(k, Eigen::Vector3d(14, 4, 1));
};

TEST_F(ObjectivesTest, PointTracking) {
  PointTrackingObjective o(names, "tip", Eigen::Vector3d(10, -5, 80));
  CheckObjective(o, p);
  EXPECT_NEAR(o.Evaluate(p, nullptr), (p.row(0) - Eigen::RowVector3d(10, -5, 80)).squaredNorm(),
              1e-12);
  PointTrackingObjective at(names, "backbone[3]", p.row(4).transpose());
  EXPECT_EQ(at.Evaluate(p, nullptr), 0.0);
}

TEST_F(ObjectivesTest, MultiPointTracking) {
  MultiPointTrackingObjective o(names, {{"tip", Eigen::Vector3d(1, 2, 90), 2.0},
                                        {"backbone[2]", Eigen::Vector3d(0, 0, 40), 0.5}});
  CheckObjective(o, p);
}

TEST_F(ObjectivesTest, PickWithTwoAndThreePointNormals) {
  PickParams a;
  a.p0 = "backbone[5]";
  a.normal.points = {"backbone[4]", "backbone[6]"};
  a.center = Eigen::Vector3d(30, 5, 60);
  a.object_radius = 10;
  a.half_width = 3;
  a.omega1 = 2.0;
  CheckObjective(PickObjective(names, a), p);
  PickParams b = a;
  b.normal.points = {"backbone[0]", "backbone[3]", "tip"};  // the bending plane
  CheckObjective(PickObjective(names, b), p);
}

TEST_F(ObjectivesTest, PickIsZeroWhereBothConditionsHold) {
  // n from backbone[4] to backbone[6]; put the object centre at distance R + d from p0 orthogonal
  // to n.
  PickParams a;
  a.p0 = "backbone[5]";
  a.normal.points = {"backbone[4]", "backbone[6]"};
  a.object_radius = 10;
  a.half_width = 3;
  const Eigen::Vector3d n = (p.row(7) - p.row(5)).normalized().transpose();
  a.center = p.row(6).transpose() + 13.0 * n.unitOrthogonal();
  PickObjective o(names, a);
  EXPECT_NEAR(o.Evaluate(p, nullptr), 0.0, 1e-20);
  EXPECT_NEAR(o.Normal(p).dot(n), 1.0, 1e-12);
}

TEST_F(ObjectivesTest, Place) {
  PlaceObjective o(names, {"tip", Eigen::Vector3d(40, 10, 50), 8.0, 2.0});
  CheckObjective(o, p);
}

TEST_F(ObjectivesTest, GraspFitsTheArcsCurvature) {
  // The backbone points of one arc lie on a circle of diameter 2/kappa.
  GraspParams gp;
  gp.group = "backbone";
  gp.object_diameter = 50.0;
  GraspObjective fitted(names, gp);
  const double kappa = k.Curvature(Eigen::Vector3d(14, 4, 1));
  EXPECT_NEAR(fitted.FittedDiameter(p), 2.0 / kappa, 1e-6);
  CheckObjective(fitted, p, 1e-5);
  // With the bending plane's normal given (the tip, a backbone point and the base span it).
  const Eigen::Vector3d n = Eigen::Vector3d(p.row(0)).cross(Eigen::Vector3d(p.row(3))).normalized();
  gp.plane_normal = n;
  GraspObjective given(names, gp);
  EXPECT_NEAR(given.FittedDiameter(p), 2.0 / kappa, 1e-6);
  CheckObjective(given, p, 1e-5);
}

TEST_F(ObjectivesTest, GraspOnAStraightFingerThrowsObjectiveError) {
  GraspParams gp;
  gp.group = "backbone";
  gp.object_diameter = 50.0;
  GraspObjective o(names, gp);
  EXPECT_THROW(o.Evaluate(BentPoints(k, Eigen::Vector3d::Zero()), nullptr), ObjectiveError);
}

TEST_F(ObjectivesTest, ShapeMatching) {
  const Eigen::MatrixX3d target = BentPoints(k, Eigen::Vector3d(2, 9, 3)).bottomRows(8);
  ShapeMatchingObjective o = ShapeMatchingObjective::ForGroup(names, "backbone", target);
  CheckObjective(o, p);
  EXPECT_EQ(o.Evaluate(BentPoints(k, Eigen::Vector3d(2, 9, 3)), nullptr), 0.0);
  ShapeMatchingObjective two(names, {"tip", "backbone[0]"}, target.topRows(2));
  CheckObjective(two, p);
}

TEST_F(ObjectivesTest, WeightedSum) {
  auto a = std::make_shared<PointTrackingObjective>(names, "tip", Eigen::Vector3d(10, -5, 80));
  GraspParams gp;
  gp.group = "backbone";
  gp.object_diameter = 50.0;
  auto b = std::make_shared<GraspObjective>(names, gp);
  WeightedSumObjective s(k.num_points());
  s.Add(0.3, a).Add(2.0, b);
  CheckObjective(s, p, 1e-5);
  EXPECT_NEAR(s.Evaluate(p, nullptr), 0.3 * a->Evaluate(p, nullptr) + 2.0 * b->Evaluate(p, nullptr),
              1e-9);
  EXPECT_THROW(s.Add(-1.0, a), std::invalid_argument);
  WeightedSumObjective other(3);
  EXPECT_THROW(other.Add(1.0, a), std::invalid_argument);
}

TEST_F(ObjectivesTest, ChainRuleThroughTheJacobianMatchesDifferencesInC) {
  PickParams a;
  a.p0 = "backbone[5]";
  a.normal.points = {"backbone[4]", "backbone[6]"};
  a.center = Eigen::Vector3d(30, 5, 60);
  a.object_radius = 10;
  a.half_width = 3;
  PickObjective o(names, a);
  const Eigen::Vector3d c(7, 3, 11);
  const KinematicsEval e = k.Evaluate(c, true);
  Eigen::MatrixX3d g;
  o.Evaluate(e.p, &g);
  const Eigen::VectorXd dc = GradientWrtActuation(e.J, g);
  const Eigen::MatrixXd fd = test::FdGradient(
      [&](const Eigen::MatrixXd& x) { return o.Evaluate(k.Evaluate(x, false).p, nullptr); },
      Eigen::MatrixXd(c), 1e-6);
  EXPECT_TRUE(test::NearMatrix(dc, fd, 1e-6, 1e-8));
}

TEST_F(ObjectivesTest, MissingPointsAreNamedInTheError) {
  try {
    PointTrackingObjective o(names, "P0", Eigen::Vector3d::Zero());
    FAIL() << "no throw";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("'P0'"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("backbone[0]"), std::string::npos) << e.what();
  }
  GraspParams gp;
  gp.object_diameter = 10;
  EXPECT_THROW(GraspObjective(names, gp), std::invalid_argument);  // no grip_layer here
  PickParams pp;
  pp.p0 = "tip";
  pp.normal.points = {"tip"};
  EXPECT_THROW(PickObjective(names, pp), std::invalid_argument);
  EXPECT_THROW(PointTrackingObjective(names, "tip", Eigen::Vector3d(0, NAN, 0)),
               std::invalid_argument);
  PointTrackingObjective o(names, "tip", Eigen::Vector3d::Zero());
  EXPECT_THROW(o.Evaluate(Eigen::MatrixX3d::Zero(3, 3), nullptr), std::invalid_argument);
}

TEST(ObjectiveGroups, GroupsAreOrderedByIndexNotByName) {
  const std::vector<std::string> names{"tip", "g[10]", "g[2]", "g[0]", "g[x]", "gg[1]"};
  const std::vector<int> idx = ResolvePointGroup(names, "g", "test");
  EXPECT_EQ(idx, (std::vector<int>{3, 2, 1}));
  EXPECT_EQ(ResolvePointGroup(names, "tip", "test"), std::vector<int>{0});
  EXPECT_THROW(ResolvePointGroup(names, "h", "test"), std::invalid_argument);
}

}  // namespace
}  // namespace softkin
