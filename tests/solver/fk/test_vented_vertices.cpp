// VentedVertices / PlaceVentedVertices: the inner vertices of vented chamber sides, which feel no
// force, are put at one well-defined place, the same for every solver: back at rest when the
// walls are, and where the cavity keeps its rest shape best when they move.
#include "softkin/solver/fk/vented_vertices.hpp"

#include "softkin/solver/fk/rotation.hpp"
#include "softkin/solver/robots/robots.hpp"

#include <gtest/gtest.h>

#include <Eigen/Geometry>

#include <algorithm>
#include <cmath>
#include <limits>
#include <memory>
#include <random>
#include <set>

namespace softkin {
namespace {

std::shared_ptr<const Model> Manipulator() {
  static const auto model = std::make_shared<const Model>(MakeRobot("finger_manipulator", 8));
  return model;
}

/// Rest positions bent smoothly in the x-y plane (no solve needed), with the inner vertices
/// scattered by up to `noise` mm.
Eigen::MatrixX3d Bent(const Model& m, const std::vector<int>& inner, double noise, int seed) {
  Eigen::MatrixX3d X = m.rest_positions();
  for (int v = 0; v < X.rows(); ++v) X(v, 1) -= 0.002 * X(v, 0) * X(v, 0);
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(-noise, noise);
  for (int v : inner)
    for (int d = 0; d < 3; ++d) X(v, d) += u(rng);
  return X;
}

/// The vented elements at `c`.
std::vector<char> Vented(const Model& m, const Eigen::VectorXd& c) {
  std::vector<char> vented(m.elements().size(), 0);
  for (int g = 0; g < m.num_groups(); ++g)
    if (m.GroupVented(g, c))
      for (int i : m.group_elements(g)) vented[i] = 1;
  return vented;
}

/// The largest gradient, over the inner vertices, of the vented elements' as-rigid-as-possible
/// energy sum_e wv_e |D_e - P_e R_e^T|^2 (R_e the best rotation at X, which is stationary).
double LargestGradient(const Model& m, const Eigen::VectorXd& c, const std::vector<int>& inner,
                       const Eigen::MatrixX3d& X) {
  const std::vector<char> vented = Vented(m, c);
  Eigen::MatrixX3d grad = Eigen::MatrixX3d::Zero(X.rows(), 3);
  for (size_t i = 0; i < m.elements().size(); ++i) {
    if (!vented[i]) continue;
    const ModelElement& e = m.elements()[i];
    ElemRows D = ElemRows::Zero();
    for (int j = 0; j < e.k; ++j) D.row(j) = X.row(e.v[j]);
    CenterRows(D, e.k);
    const Eigen::Matrix3d R = BestRotation(D.transpose() * e.rest);
    for (int j = 0; j < e.k; ++j)
      grad.row(e.v[j]) += 2.0 * e.wv * (D.row(j) - e.rest.row(j) * R.transpose());
  }
  double worst = 0.0;
  for (int v : inner) worst = std::max(worst, grad.row(v).norm());
  return worst;
}

/// Vented elements with a non-positive volume at X.
int FoldedVented(const Model& m, const Eigen::VectorXd& c, const Eigen::MatrixX3d& X) {
  const std::vector<char> vented = Vented(m, c);
  int folded = 0;
  for (size_t i = 0; i < m.elements().size(); ++i) {
    if (!vented[i]) continue;
    const ModelElement& e = m.elements()[i];
    ElemRows D = ElemRows::Zero();
    for (int j = 0; j < e.k; ++j) D.row(j) = X.row(e.v[j]);
    folded += RowsVolume(D, e.k) <= 0.0;
  }
  return folded;
}

TEST(VentedVertices, AreTheInnerVerticesOfTheVentedSideOnly) {
  const Model& m = *Manipulator();
  const Eigen::Vector3d right(0.5, 0.0, 0.0), left(-0.5, 0.0, 0.0);
  const std::vector<int> a = VentedVertices(m, right), b = VentedVertices(m, left);
  // Section 1 inflates one side; the other side of section 1 and both sides of sections 2 and 3
  // (at rest, so vented) have inner vertices: the cavities are two cells across at res 8.
  ASSERT_FALSE(a.empty());
  ASSERT_EQ(a.size(), b.size());
  // The mesh is mirror-symmetric about y = 10: the two sets are mirror images of each other.
  std::set<std::array<long, 3>> mirrored;
  for (int v : b)
    mirrored.insert({std::lround(1e6 * m.rest_positions()(v, 0)),
                     std::lround(1e6 * (20.0 - m.rest_positions()(v, 1))),
                     std::lround(1e6 * m.rest_positions()(v, 2))});
  for (int v : a)
    EXPECT_TRUE(mirrored.count({std::lround(1e6 * m.rest_positions()(v, 0)),
                                std::lround(1e6 * m.rest_positions()(v, 1)),
                                std::lround(1e6 * m.rest_positions()(v, 2))}))
        << "vertex " << v << " has no mirror image in the other set";
  // Inflating sections 2 and 3 too leaves one vented side in each: fewer inner vertices. A robot
  // without signed actuators has none.
  EXPECT_LT(VentedVertices(m, Eigen::Vector3d(0.5, 0.5, 0.5)).size(), a.size());
  const Model three(MakeRobot("three_chamber", 3));
  EXPECT_TRUE(VentedVertices(three, Eigen::Vector3d(1.5, 1.0, 1.0)).empty());
}

TEST(PlaceVentedVertices, KeepsTheRestShapeAndFitsTheCavityAsRigidlyAsPossible) {
  const Model& m = *Manipulator();
  const Eigen::VectorXd c = Eigen::Vector3d(0.5, 0.0, 0.0);
  const std::vector<int> inner = VentedVertices(m, c);
  ASSERT_FALSE(inner.empty());
  std::vector<char> is_inner(m.num_vertices(), 0);
  for (int v : inner) is_inner[v] = 1;
  // Walls at rest: the inner vertices go back to rest, wherever they were.
  Eigen::MatrixX3d rest = m.rest_positions();
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> u(-20.0, 20.0);
  for (int v : inner)
    for (int d = 0; d < 3; ++d) rest(v, d) += u(rng);
  PlaceVentedVertices(m, c, &rest);
  EXPECT_LT((rest - m.rest_positions()).cwiseAbs().maxCoeff(), 1e-12 * m.size());

  // Bent walls: the inner vertices, scattered by up to 20 mm, end at a stationary point of the
  // cavity's as-rigid-as-possible energy, the same from any scatter, with no element folded.
  Eigen::MatrixX3d X1 = Bent(m, inner, 20.0, 1), X2 = Bent(m, inner, 20.0, 2);
  const Eigen::MatrixX3d before = X1;
  ASSERT_GT(LargestGradient(m, c, inner, X1), 1.0);
  ASSERT_GT(FoldedVented(m, c, X1), 0);
  PlaceVentedVertices(m, c, &X1);
  PlaceVentedVertices(m, c, &X2);
  EXPECT_LT(LargestGradient(m, c, inner, X1), 1e-6 * m.size());
  EXPECT_EQ(FoldedVented(m, c, X1), 0);
  EXPECT_LT((X1 - X2).cwiseAbs().maxCoeff(), 1e-9 * m.size());
  for (int v = 0; v < m.num_vertices(); ++v) {
    if (is_inner[v]) continue;
    ASSERT_EQ(X1.row(v), before.row(v)) << "vertex " << v;  // no other vertex moves
  }
  // Idempotent.
  Eigen::MatrixX3d again = X1;
  PlaceVentedVertices(m, c, &again);
  EXPECT_LT((again - X1).cwiseAbs().maxCoeff(), 1e-8 * m.size());
}

TEST(PlaceVentedVertices, CommutesWithRigidMotionAndLeavesNonFiniteStatesAlone) {
  const Model& m = *Manipulator();
  const Eigen::VectorXd c = Eigen::Vector3d(0.0, -0.7, 0.3);
  const std::vector<int> inner = VentedVertices(m, c);
  ASSERT_FALSE(inner.empty());
  const Eigen::Matrix3d Q =
      Eigen::AngleAxisd(0.7, Eigen::Vector3d(1.0, -2.0, 0.5).normalized()).toRotationMatrix();
  const Eigen::RowVector3d t(12.0, -40.0, 3.0);
  Eigen::MatrixX3d X = Bent(m, inner, 5.0, 3);
  Eigen::MatrixX3d moved = (X * Q.transpose()).rowwise() + t;
  PlaceVentedVertices(m, c, &X);
  PlaceVentedVertices(m, c, &moved);
  const Eigen::MatrixX3d expected = (X * Q.transpose()).rowwise() + t;
  EXPECT_LT((moved - expected).cwiseAbs().maxCoeff(), 1e-9 * m.size());

  Eigen::MatrixX3d bad = Bent(m, inner, 5.0, 4);
  bad(0, 0) = std::numeric_limits<double>::quiet_NaN();
  const Eigen::MatrixX3d copy = bad;
  PlaceVentedVertices(m, c, &bad);
  for (int v : inner) EXPECT_EQ(bad.row(v), copy.row(v));
}

}  // namespace
}  // namespace softkin
