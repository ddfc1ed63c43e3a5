// The analytical PCC model: identities of the arc and its Jacobian against finite differences.
#include "softkin/ik/pcc_kinematics.hpp"

#include "ik_test_models.hpp"

#include <gtest/gtest.h>

#include <random>

namespace softkin {
namespace {

TEST(PccKinematics, RestIsStraightAndEvenlySpaced) {
  PccKinematics k;
  const KinematicsEval e = k.Evaluate(k.rest(), true);
  ASSERT_TRUE(e.ok) << e.message;
  const int K = k.params().backbone_points;
  EXPECT_EQ(k.num_points(), K + 1);
  EXPECT_TRUE(test::NearMatrix(e.p.row(0), Eigen::RowVector3d(0, 0, 100), 0, 1e-12));
  for (int j = 0; j < K; ++j) EXPECT_NEAR(e.p(1 + j, 2), 100.0 * (j + 1) / K, 1e-12) << j;
  EXPECT_EQ(e.J.rows(), 3 * k.num_points());
  EXPECT_EQ(k.total_fk_solves(), 1);
}

TEST(PccKinematics, PointsLieOnTheArcOfCurvatureKappa) {
  PccKinematics k;
  const Eigen::Vector3d c(12.0, 3.0, 0.0);
  const KinematicsEval e = k.Evaluate(c, false);
  ASSERT_TRUE(e.ok);
  const double kappa = k.Curvature(c);
  ASSERT_GT(kappa, 0.0);
  // The centre of the arc: 1/kappa from the base along the bending direction (which is the tip's
  // xy direction), in the base plane.
  Eigen::Vector3d dir(e.p(0, 0), e.p(0, 1), 0.0);
  dir.normalize();
  const Eigen::Vector3d centre = dir / kappa;
  for (int i = 0; i < k.num_points(); ++i)
    EXPECT_NEAR((e.p.row(i).transpose() - centre).norm(), 1.0 / kappa, 1e-9) << i;
  // The backbone keeps its length s = L - mean(c): the tip's arc angle is kappa s.
  const double s = 100.0 - c.sum() / 3.0;
  EXPECT_NEAR(e.p(0, 2), std::sin(kappa * s) / kappa, 1e-9);
}

TEST(PccKinematics, PullingOneCableBendsTowardsIt) {
  PccKinematics k;
  const KinematicsEval e = k.Evaluate(Eigen::Vector3d(10, 0, 0), false);
  EXPECT_GT(e.p(0, 0), 5.0);  // cable 0 lies along +x
  EXPECT_NEAR(e.p(0, 1), 0.0, 1e-12);
}

TEST(PccKinematics, JacobianMatchesCentralDifferences) {
  PccKinematics k;
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> u(0.0, 20.0);
  std::vector<Eigen::Vector3d> cs = {Eigen::Vector3d(5, 5, 5), Eigen::Vector3d(0, 0, 0.01),
                                     Eigen::Vector3d(20, 0, 0), Eigen::Vector3d(1e-3, 0, 0)};
  // Around the switch between the series and the closed form of g, h (t = 0.1, reached by one
  // cable at c ~ 2.9 for the tip and larger c for the backbone points).
  for (double cc = 2.0; cc < 12.0; cc += 0.25) cs.push_back(Eigen::Vector3d(cc, 0, 0));
  for (int r = 0; r < 10; ++r) cs.push_back(Eigen::Vector3d(u(rng), u(rng), u(rng)));
  int checked = 0;
  for (const Eigen::Vector3d& c : cs) {
    const KinematicsEval e = k.Evaluate(c, true);
    ASSERT_TRUE(e.ok) << e.message;
    Eigen::MatrixXd fd(e.J.rows(), 3);
    for (int a = 0; a < 3; ++a) {
      // Central differences inside the box; the second-order one-sided formula at a bound.
      const double h = 1e-5;
      const double sgn = c[a] - h < 0.0 ? 1.0 : (c[a] + h > 20.0 ? -1.0 : 0.0);
      auto at = [&](double off) {
        Eigen::Vector3d cc = c;
        cc[a] += off;
        return Eigen::MatrixX3d(k.Evaluate(cc, false).p);
      };
      Eigen::MatrixX3d d;
      if (sgn == 0.0)
        d = (at(h) - at(-h)) / (2 * h);
      else
        d = sgn * (-3.0 * at(0) + 4.0 * at(sgn * h) - at(2 * sgn * h)) / (2 * h);
      for (int i = 0; i < d.rows(); ++i)
        for (int dd = 0; dd < 3; ++dd) fd(3 * i + dd, a) = d(i, dd);
    }
    EXPECT_TRUE(test::NearMatrix(e.J, fd, 1e-6, 1e-7)) << "c = " << c.transpose();
    ++checked;
  }
  EXPECT_EQ(checked, static_cast<int>(cs.size()));
}

TEST(PccKinematics, RejectsActuationOutsideTheBoxAndBadParams) {
  PccKinematics k;
  const KinematicsEval e = k.Evaluate(Eigen::Vector3d(0, 21, 0), true);
  EXPECT_FALSE(e.ok);
  EXPECT_NE(e.message.find("actuator 1"), std::string::npos) << e.message;
  PccParams p;
  p.max_pull = 200;
  std::string why;
  EXPECT_FALSE(p.IsValid(&why));
  EXPECT_NE(why.find("max_pull"), std::string::npos);
  EXPECT_THROW(PccKinematics{p}, std::invalid_argument);
}

}  // namespace
}  // namespace softkin
