// Symmetric designs stay symmetric: every embedded robot whose design is mirror-symmetric about a
// plane y = const has a mirror-symmetric mesh there, and an actuation that is itself symmetric
// (every actuator spans both sides of the plane) keeps its markers on the plane. The voxel split
// is mirrored cell by cell (mesh_gen.hpp), which is symmetric over an even number of cells
// across the plane; the voxel robots cut an odd count into one more cell
// (SymmetricVoxelTetMesh), so they are symmetric at odd resolutions too, and so does the prism
// grid of dea_crawler (its diagonals alternate cell by cell). Before, at res 5 and 7
// every tet leaned one way and the tips drifted off the plane (pneumatic_finger res 7 at alpha 3
// by 0.52 mm, multi_segment_gripper res 7 at (3, 3, 3) by 1.2 mm).
#include "softkin/solver/factory/fk_factory.hpp"
#include "softkin/solver/fk/fk_solver.hpp"
#include "softkin/solver/fk/model.hpp"
#include "softkin/solver/robots/robots.hpp"
#include "tests/solver/robots/mirror_test_util.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <memory>
#include <string>
#include <vector>

namespace softkin {
namespace {

struct MirrorCase {
  std::string robot;
  int res;
  double plane_y;                 ///< the design's mirror plane y = plane_y (mm)
  std::vector<double> actuation;  ///< a symmetric actuation with a clear bend
};

using test::UnmatchedMirrorVertices;

TEST(RobotSymmetry, MirrorSymmetricDesignsBendInTheirPlane) {
  const std::vector<MirrorCase> cases = {
      {"pneumatic_finger", 6, 10.0, {3.0}},
      {"pneumatic_finger", 5, 10.0, {3.0}},
      {"cable_gripper", 5, 10.0, {0.8}},
      {"cable_finger", 6, 12.5, {0.8, 0.8, 0.8}},
      {"multi_segment_gripper", 6, 10.0, {3.0, 3.0, 3.0}},
      {"cable_gripper", 6, 10.0, {0.8}},
      {"dea_crawler", 8, 10.0, {0.85}},
      {"dea_crawler", 5, 10.0, {0.85}},
      {"bilayer_strip", 1, 5.0, {1.1}},
  };
  for (const MirrorCase& c : cases) {
    SCOPED_TRACE(c.robot + " res " + std::to_string(c.res));
    const Scene s = MakeRobot(c.robot, c.res);
    EXPECT_EQ(UnmatchedMirrorVertices(s.mesh, c.plane_y), 0);
    EXPECT_EQ(test::UnmatchedMirrorElements(s.mesh, 1, c.plane_y), 0);
    auto model = std::make_shared<const Model>(s);
    const Eigen::VectorXd a =
        Eigen::Map<const Eigen::VectorXd>(c.actuation.data(), c.actuation.size());
    const FkResult r = MakeFkSolver(model, s.solver)->Solve(a);
    ASSERT_EQ(r.status, FkStatus::Converged) << r.message;
    const Eigen::MatrixX3d P0 = s.marker_positions(s.mesh.vertices);
    const Eigen::MatrixX3d P = s.marker_positions(r.positions);
    const double size = s.mesh.size();
    // Markers on the plane stay on it (to 1e-4 of the robot's size, above the stopping rule),
    // and the robot did bend: some marker moved by more than 1 % of its size.
    double moved = 0;
    int on_plane = 0;
    for (int m = 0; m < P.rows(); ++m) {
      moved = std::max(moved, (P.row(m) - P0.row(m)).norm());
      if (std::abs(P0(m, 1) - c.plane_y) < 1e-6 * size) {
        ++on_plane;
        EXPECT_NEAR(P(m, 1), c.plane_y, 1e-4 * size) << "marker " << s.markers[m].name;
      }
    }
    EXPECT_GT(on_plane, 0);
    EXPECT_GT(moved, 0.01 * size);
  }
  // Every voxel robot's mesh at odd resolutions, tet by tet (the bar about both of its planes).
  struct OddCase {
    std::string robot;
    int res;
    double plane_y;
  };
  for (const OddCase& c : std::vector<OddCase>{{"pneumatic_finger", 7, 10.0},
                                               {"cable_finger", 5, 12.5},
                                               {"cable_finger", 7, 12.5},
                                               {"multi_segment_gripper", 7, 10.0},
                                               {"cable_gripper", 7, 10.0},
                                               {"selfcollision_finger", 5, 10.0},
                                               {"dea_crawler", 7, 10.0},
                                               {"bimaterial_bar", 3, 6.0},
                                               {"bimaterial_bar", 5, 6.0}}) {
    SCOPED_TRACE(c.robot + " res " + std::to_string(c.res));
    const Mesh mesh = MakeRobot(c.robot, c.res).mesh;
    EXPECT_EQ(test::UnmatchedMirrorElements(mesh, 1, c.plane_y), 0);
    if (c.robot == "bimaterial_bar") {
      EXPECT_EQ(test::UnmatchedMirrorElements(mesh, 2, 6.0), 0);
    }
  }
  // The membrane's 2 x 2 chambers, about both mid-planes: an odd res takes one more cell across.
  for (int res : {11, 20}) {
    SCOPED_TRACE("membrane res " + std::to_string(res));
    const Mesh mesh = MakeRobot("membrane", res).mesh;
    EXPECT_EQ(test::UnmatchedMirrorElements(mesh, 0, 125.0), 0);
    EXPECT_EQ(test::UnmatchedMirrorElements(mesh, 1, 125.0), 0);
  }
  // The strip at res 3 (W / h = 15 cubic cells) is cut into an even 16 across its width.
  EXPECT_EQ(UnmatchedMirrorVertices(MakeRobot("bilayer_strip", 3).mesh, 5.0), 0);
  // The 12,000-tet strip of the benchmarks: 50 x 10 x 4 cells of 2 x 1 x 1 mm, same outline.
  const Scene strip12k = MakeRobot("bilayer_strip", 2, {{"cell_length", 2.0}});
  EXPECT_EQ(strip12k.mesh.num_elements(), 12000);
  EXPECT_EQ(UnmatchedMirrorVertices(strip12k.mesh, 5.0), 0);
  const Eigen::RowVector3d hi = strip12k.mesh.vertices.colwise().maxCoeff();
  EXPECT_LT((hi - Eigen::RowVector3d(100, 10, 4)).norm(), 1e-9);
}

// finger_manipulator moves in x-y, so its mesh must also be mirror-symmetric about its
// mid-thickness. The snapped grid rounds the 12 mm thickness to 5 / 7 / 11 cells at res 8 / 12 /
// 18 and cuts that count into one more of equal height; before, every tet leaned one way over it
// and at the default res 8 the tip left the plane by 2.6 mm at s1 = 0.5 (this test then fails both
// ways: every tet unmatched, and the tip off the plane).
TEST(RobotSymmetry, PlanarManipulatorStaysInItsPlane) {
  for (int res : {6, 7, 8, 9, 10, 12, 18}) {  // res 7 and 9 have an odd count across y too
    SCOPED_TRACE("finger_manipulator res " + std::to_string(res));
    const Mesh mesh = MakeRobot("finger_manipulator", res).mesh;
    const double mid = 0.5 * (mesh.vertices.col(2).minCoeff() + mesh.vertices.col(2).maxCoeff());
    EXPECT_EQ(test::UnmatchedMirrorElements(mesh, 2, mid), 0);
    EXPECT_EQ(test::UnmatchedMirrorElements(mesh, 1, 10.0), 0);
  }
  const Scene s = MakeRobot("finger_manipulator");
  const double mid = 0.5 * s.mesh.vertices.col(2).maxCoeff();
  const FkResult r = MakeFkSolver(std::make_shared<const Model>(s), s.solver)
                         ->Solve(Eigen::Vector3d(0.5, 0.0, 0.0));
  ASSERT_EQ(r.status, FkStatus::Converged) << r.message;
  const Eigen::MatrixX3d P0 = s.marker_positions(s.mesh.vertices);
  const Eigen::MatrixX3d P = s.marker_positions(r.positions);
  for (int m = 0; m < P.rows(); ++m) {
    SCOPED_TRACE(s.markers[m].name);
    EXPECT_NEAR(P0(m, 2), mid, 1e-9);
    EXPECT_NEAR(P(m, 2), mid, 1e-4 * s.mesh.size());
  }
  EXPECT_LT(P(s.marker_index("tip"), 1), -20.0);  // bent towards -y, out of the box y in [0, 20]
}

}  // namespace
}  // namespace softkin

namespace softkin {
namespace {

// three_chamber is mirror-symmetric about each chamber's plane: inflating c1 alone, or c2 and c3
// equally, bends it in c1's plane z = 0. Its disk used to be triangulated with a handedness
// (ties broken one way round), and the tip left that plane by 1.8-1.9 mm at res 5, 7 and 9 at
// (3, 1, 1), and by 10.8 mm at res 3 along the Fig. 2.12 path; this test then fails.
TEST(RobotSymmetry, ThreeChamberBendsInTheMirrorPlaneOfAChamber) {
  for (int res : {3, 5}) {
    const Scene s = MakeRobot("three_chamber", res);
    auto model = std::make_shared<const Model>(s);
    for (const Eigen::Vector3d& a : {Eigen::Vector3d(2.5, 1, 1), Eigen::Vector3d(1, 2, 2)}) {
      SCOPED_TRACE("res " + std::to_string(res) + ", actuation " + std::to_string(a[0]));
      const FkResult r = MakeFkSolver(model, s.solver)->Solve(a);
      ASSERT_EQ(r.status, FkStatus::Converged) << r.message;
      const Eigen::RowVector3d tip0 = s.marker_positions(s.mesh.vertices).row(0);
      const Eigen::RowVector3d tip = s.marker_positions(r.positions).row(0);
      EXPECT_GT((tip - tip0).norm(), 0.05 * s.mesh.size());
      EXPECT_NEAR(tip.z(), 0.0, 1e-4 * s.mesh.size());
    }
  }
}

}  // namespace
}  // namespace softkin
