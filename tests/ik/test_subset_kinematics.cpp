// SubsetKinematics: the driven actuators' slice of another Kinematics, the rest held fixed.
#include "softkin/ik/subset_kinematics.hpp"

#include "softkin/ik/ik_solver.hpp"
#include "ik_test_models.hpp"

#include <gtest/gtest.h>

namespace softkin {
namespace {

TEST(SubsetKinematics, PointsAndJacobianAreTheBaseColumnsAtTheFullActuation) {
  auto base = test::LinearKinematics::Random(2, 7);
  const Eigen::VectorXd fixed = (Eigen::VectorXd(3) << 1.0, 2.0, 3.0).finished();
  SubsetKinematics sub(base, {2, 0}, fixed);
  ASSERT_EQ(sub.num_actuators(), 2);
  EXPECT_EQ(sub.rest(), (Eigen::VectorXd(2) << 3.0, 1.0).finished());
  const Eigen::VectorXd c = (Eigen::VectorXd(2) << 4.0, 5.0).finished();
  const KinematicsEval e = sub.Evaluate(c, true);
  ASSERT_TRUE(e.ok) << e.message;
  const Eigen::VectorXd full = (Eigen::VectorXd(3) << 5.0, 2.0, 4.0).finished();
  EXPECT_EQ(sub.Full(c), full);
  const KinematicsEval b = base.Evaluate(full, true);
  EXPECT_EQ(e.p, b.p);
  ASSERT_EQ(e.J.cols(), 2);
  EXPECT_EQ(e.J.col(0), b.J.col(2));
  EXPECT_EQ(e.J.col(1), b.J.col(0));
  EXPECT_EQ(sub.lower()[0], base.lower()[2]);
  EXPECT_EQ(sub.upper()[1], base.upper()[0]);
}

TEST(SubsetKinematics, IkMovesOnlyTheDrivenActuators) {
  auto base = test::LinearKinematics::Random(1, 3);
  const Eigen::VectorXd fixed = Eigen::VectorXd::Constant(3, 5.0);
  // A target reachable with actuator 1 held at 5.
  const Eigen::VectorXd truth = (Eigen::VectorXd(3) << 2.0, 5.0, 7.5).finished();
  const Eigen::Vector3d target = base.Evaluate(truth, false).p.row(0).transpose();
  SubsetKinematics sub(base, {0, 2}, fixed);
  PointTrackingObjective obj(sub.point_names(), "tip", target);
  IkOptions o;
  o.method = IkMethod::kGaussNewton;
  o.lambda = 1e-10;
  const IkResult r = SolveIk(sub, obj, sub.rest(), o);
  ASSERT_TRUE(r.summary.converged()) << r.summary.BriefReport();
  EXPECT_NEAR(sub.Full(r.c)[1], 5.0, 0.0);
  EXPECT_NEAR(r.c[0], 2.0, 1e-4);
  EXPECT_NEAR(r.c[1], 7.5, 1e-4);
}

TEST(SubsetKinematics, RejectsBadSubsets) {
  auto base = test::LinearKinematics::Random(1, 3);
  const Eigen::VectorXd fixed = Eigen::VectorXd::Constant(3, 5.0);
  EXPECT_THROW(SubsetKinematics(base, {}, fixed), std::invalid_argument);
  EXPECT_THROW(SubsetKinematics(base, {0, 0}, fixed), std::invalid_argument);
  EXPECT_THROW(SubsetKinematics(base, {3}, fixed), std::invalid_argument);
  EXPECT_THROW(SubsetKinematics(base, {0}, Eigen::VectorXd::Constant(3, 11.0)),
               std::invalid_argument);
  SubsetKinematics sub(base, {1}, fixed);
  EXPECT_FALSE(sub.Evaluate(Eigen::VectorXd::Constant(1, -1.0), false).ok);
}

}  // namespace
}  // namespace softkin
