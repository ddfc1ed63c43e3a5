/// \file test_gmres.cpp
/// GmresColumn (solver/sensitivity/gmres.hpp): stopping a solve inside a cycle.
#include "softkin/solver/sensitivity/gmres.hpp"

#include <gtest/gtest.h>

#include <Eigen/Core>

namespace softkin {
namespace {

// GmresColumn::Stop keeps the correction of the unfinished cycle, and estimate() follows the
// residual within a cycle (before Stop, a caller that gave up early got y = 0 and rel = 1).
TEST(Gmres, StopKeepsTheCycleSoFar) {
  const int n = 40;
  Eigen::MatrixXd A = Eigen::MatrixXd::Identity(n, n);
  for (int i = 0; i < n; ++i) A(i, i) = 1.0 + i;  // eigenvalues 1..40: many products to converge
  const Eigen::VectorXd b = Eigen::VectorXd::Ones(n);
  GmresColumn gm(b, Eigen::VectorXd::Zero(n), n, n, 1e-12);
  double last = 1.0;
  for (int k = 0; k < 5; ++k) {
    gm.Consume(A * gm.Request());
    EXPECT_LE(gm.estimate(), last + 1e-15);
    last = gm.estimate();
  }
  EXPECT_FALSE(gm.done());
  EXPECT_EQ(gm.rel(), 1.0);  // the cycle has not ended
  EXPECT_LT(last, 0.9);
  gm.Stop();
  EXPECT_TRUE(gm.done());
  const double true_rel = (b - A * gm.y()).norm() / b.norm();
  EXPECT_NEAR(gm.rel(), true_rel, 1e-10);
  EXPECT_NEAR(gm.rel(), last, 1e-12);
  EXPECT_GT(gm.y().norm(), 0.0);
}

}  // namespace
}  // namespace softkin
