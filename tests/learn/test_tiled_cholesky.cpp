// The tiled Cholesky factorisation: it solves SPD systems like Eigen's LLT, gives the same bits for
// any thread count, and reports a matrix that is not positive definite.
#include "softkin/learn/tiled_cholesky.hpp"

#include "learn_test_util.hpp"

#include <Eigen/Cholesky>

#include <cstring>

namespace softkin {
namespace {

Eigen::MatrixXd RandomSpd(int n, unsigned seed) {
  const Eigen::MatrixXd J = test::UniformSamples(n + 20, n, -1, 1, seed);
  Eigen::MatrixXd H = J.transpose() * J;
  H.diagonal().array() += 1e-3;
  return H;
}

TEST(TiledCholesky, SolvesLikeEigenForEveryTiling) {
  const int n = 157;  // not a multiple of any tile below
  const Eigen::MatrixXd H = RandomSpd(n, 1);
  const Eigen::VectorXd b = test::UniformSamples(n, 1, -1, 1, 2);
  const Eigen::VectorXd x_ref = H.llt().solve(b);
  for (int tile : {1, 16, 50, 157, 400}) {
    Eigen::MatrixXd A = H;
    ASSERT_TRUE(TiledCholeskyInPlace(A, tile, 1)) << tile;
    Eigen::MatrixXd L = A.triangularView<Eigen::Lower>();
    EXPECT_TRUE(test::NearMatrix(L * L.transpose(), H, 1e-12, 1e-12)) << "tile " << tile;
    Eigen::VectorXd x = b;
    TiledCholeskySolveInPlace(A, x);
    EXPECT_TRUE(test::NearMatrix(x, x_ref, 1e-8, 1e-10)) << "tile " << tile;
    EXPECT_LT((H * x - b).norm(), 1e-9 * b.norm()) << "tile " << tile;
  }
}

TEST(TiledCholesky, BitwiseIdenticalForOneAndTwoThreads) {
  const Eigen::MatrixXd H = RandomSpd(300, 3);
  Eigen::MatrixXd A1 = H, A2 = H;
  ASSERT_TRUE(TiledCholeskyInPlace(A1, 64, 1));
  ASSERT_TRUE(TiledCholeskyInPlace(A2, 64, 2));
  const Eigen::MatrixXd L1 = A1.triangularView<Eigen::Lower>(),
                        L2 = A2.triangularView<Eigen::Lower>();
  EXPECT_EQ(std::memcmp(L1.data(), L2.data(), sizeof(double) * L1.size()), 0);
}

TEST(TiledCholesky, ReportsAnIndefiniteMatrix) {
  Eigen::MatrixXd H = RandomSpd(90, 4);
  H(70, 70) = -1.0;  // a negative pivot in the third tile
  Eigen::MatrixXd A = H;
  EXPECT_FALSE(TiledCholeskyInPlace(A, 32, 2));
}

}  // namespace
}  // namespace softkin
