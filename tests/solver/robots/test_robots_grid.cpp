// Every embedded robot converges over a grid across its actuation range on a coarse mesh, plus the
// physics each new robot is built to show: the redundancy of finger_manipulator, the DEA crawler's
// sliding foot and flat state, the bimaterial bar's interface, the two materials of the cable
// gripper. The number of failed grid points is printed; the goal (and the assertion) is none.
#include "softkin/solver/factory/fk_factory.hpp"
#include "softkin/solver/fk/fk_solver.hpp"
#include "softkin/solver/fk/model.hpp"
#include "softkin/solver/mesh/element_geometry.hpp"
#include "softkin/solver/remesh/remesh.hpp"
#include "softkin/solver/robots/robots.hpp"
#include "tests/solver/robots/mirror_test_util.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <functional>
#include <iostream>
#include <limits>
#include <map>
#include <string>

namespace softkin {
namespace {

/// What SolveGrid found: points whose solve failed (iteration cap, divergence, time limit), and
/// points that met the tolerance at a state with inverted body elements (status inverted).
struct GridOutcome {
  int failed = 0, inverted = 0;
};

/// Points that failed or ended inverted (for robots whose range inverts nothing).
int FailedOrInverted(const GridOutcome& g) { return g.failed + g.inverted; }

/// Solves every point of the grid values[0] x values[1] x ... (one list per actuator) in
/// serpentine order, each warm-started from the previous solution (as a sweep or a dataset
/// generator would). `check` runs on every point that met the tolerance (converged or inverted).
GridOutcome SolveGrid(
    const Scene& s, const std::vector<std::vector<double>>& values,
    const std::function<void(const Eigen::VectorXd&, const FkResult&)>& check = nullptr) {
  auto model = std::make_shared<const Model>(s);
  auto solver = MakeFkSolver(model, s.solver);
  const int m = s.num_actuators();
  std::vector<int> idx(m, 0), dir(m, 1);
  Eigen::MatrixX3d X = model->rest_positions();
  GridOutcome out;
  int solves = 0;
  while (true) {
    Eigen::VectorXd c(m);
    for (int a = 0; a < m; ++a) c[a] = values[a][idx[a]];
    const FkResult r = solver->Solve(c, &X);
    ++solves;
    if (r.status != FkStatus::Converged && r.status != FkStatus::Inverted) {
      ++out.failed;
      ADD_FAILURE() << s.name << " actuation " << c.transpose() << ": " << r.BriefReport();
    } else {
      // An inverted state is never reported as converged (FkSolver::Solve).
      EXPECT_EQ(r.status == FkStatus::Inverted, r.inverted_elements > 0);
      out.inverted += r.status == FkStatus::Inverted;
      if (r.status == FkStatus::Inverted)
        std::cout << "  " << s.name << " at (" << c.transpose() << "): " << r.inverted_elements
                  << " inverted body elements, smallest volume ratio " << r.min_volume_ratio
                  << "\n";
      X = r.positions;
      if (check) check(c, r);
    }
    // Serpentine increment: the last actuator moves fastest and reverses direction at each end.
    int a = m - 1;
    while (a >= 0) {
      const int next = idx[a] + dir[a];
      if (next >= 0 && next < static_cast<int>(values[a].size())) {
        idx[a] = next;
        break;
      }
      dir[a] = -dir[a];
      --a;
    }
    if (a < 0) break;
  }
  std::printf("  %s (%d tets, %d prisms): %d of %d grid points failed, %d inverted\n",
              s.name.c_str(), s.mesh.num_tets(), s.mesh.num_prisms(), out.failed, solves,
              out.inverted);
  return out;
}

Eigen::Vector3d Marker(const Scene& s, const Eigen::MatrixX3d& X, const char* name) {
  const int m = s.marker_index(name);
  EXPECT_GE(m, 0) << name;
  return s.marker_positions(X).row(m).transpose();
}

TEST(RobotGrid, PneumaticFinger) {
  const Scene s = MakeRobot("pneumatic_finger", 6);
  const GridOutcome g = SolveGrid(s, {{1.0, 4.0, 7.0, 10.0}});
  EXPECT_EQ(g.failed, 0);
  // At the top of the range (alpha = 10) this coarse mesh crushes some of its one-cell walls
  // between inflated chambers (80 elements, docs/solvers.md); alpha <= 7 does not.
  EXPECT_LE(g.inverted, 1);
}

TEST(RobotGrid, ThreeChamber) {
  const Scene s = MakeRobot("three_chamber", 3);
  const GridOutcome g = SolveGrid(s, {{1, 2, 3}, {1, 2, 3}, {1, 2, 3}});
  EXPECT_EQ(g.failed, 0);
  EXPECT_EQ(g.inverted, 0);
}

TEST(RobotGrid, FingerManipulatorIsPlanarAndMirrorSymmetric) {
  const Scene s = MakeRobot("finger_manipulator", 6);
  const Eigen::Vector3d tip0 = Marker(s, s.mesh.vertices, "tip");
  const double size = s.mesh.size();
  std::map<std::vector<double>, Eigen::Vector3d> tips;
  double turn1 = 0;  // section 1's turn at (3, 0, 0): the straight sections 2-3 point j1 -> tip
  const GridOutcome g = SolveGrid(s, {{-3, 0, 3}, {-3, 0, 3}, {-3, 0, 3}},
                                  [&](const Eigen::VectorXd& c, const FkResult& r) {
                                    const Eigen::Vector3d p = Marker(s, r.positions, "tip");
                                    if (c == Eigen::Vector3d(3, 0, 0)) {
                                      const Eigen::Vector3d d = p - Marker(s, r.positions, "j1");
                                      turn1 = std::atan2(-d.y(), d.x()) * 180.0 / M_PI;
                                    }
                                    // Planar in x-y: the mesh is mirror-symmetric about z = mid
                                    // thickness at this res (4 cells through it; at res 8 and 12
                                    // the snapped mesh has 5 and 7 and is not, docs/fidelity.md);
                                    // bound: the stopping rule (1e-5 of the size).
                                    EXPECT_NEAR(p.z(), tip0.z(), 1e-4 * size) << c.transpose();
                                    tips[{c[0], c[1], c[2]}] = p;
                                  });
  EXPECT_EQ(g.failed, 0);
  // At |v| = 3 the chambers (weight 20) crush 10 wall elements of their section between them:
  // every grid point but the rest has inverted elements (docs/solvers.md, "Inverted states").
  EXPECT_LE(g.inverted, 26);
  // v and -v are mirror images about y = 10 (the section layout is mirror-symmetric).
  for (const auto& [c, p] : tips) {
    auto it = tips.find({-c[0], -c[1], -c[2]});
    if (it == tips.end()) continue;
    EXPECT_NEAR(p.x(), it->second.x(), 1e-3 * size);
    EXPECT_NEAR(p.y() - tip0.y(), -(it->second.y() - tip0.y()), 1e-3 * size);
  }
  // Positive values bend towards -y.
  const std::vector<double> pos{3, 0, 0};
  EXPECT_LT(tips[pos].y(), tip0.y() - 10.0);
  // About 43 degrees at this res 6 (3.3 mm walls), 73 at the default res 8 (2.5 mm walls); the
  // thesis reaches up to 120.
  std::printf("  section 1 turns %.1f degrees at (3, 0, 0)\n", turn1);
  EXPECT_GT(turn1, 35.0);
}

TEST(RobotRedundancy, FingerManipulatorReachesOneTipWithTwoActuations) {
  // m = 3 > n = 2: the tip of actuation (0.7, 0.7, 0.7) is the target; with the third section's
  // value changed to 0 (straight), find (v1, v2) that put the tip back on the target by Newton's
  // method with a finite-difference Jacobian. FK must converge at both actuations and at every
  // Newton step, and the two actuations must differ clearly. (From (1, 1, 1) the answer needs
  // v2 = 1.58, where two wall elements of section 2 invert: status inverted.)
  const Scene s = MakeRobot("finger_manipulator", 6);
  auto model = std::make_shared<const Model>(s);
  auto solver = MakeFkSolver(model, s.solver);
  auto tip_of = [&](const Eigen::VectorXd& c, Eigen::MatrixX3d* X) {
    const FkResult r = solver->Solve(c, X);
    EXPECT_EQ(r.status, FkStatus::Converged) << c.transpose() << ": " << r.BriefReport();
    *X = r.positions;
    const Eigen::Vector3d p = Marker(s, r.positions, "tip");
    return Eigen::Vector2d(p.x(), p.y());
  };
  Eigen::MatrixX3d X = model->rest_positions();
  const Eigen::Vector3d ref(0.7, 0.7, 0.7);
  const Eigen::Vector2d target = tip_of(ref, &X);
  Eigen::VectorXd c(3);
  c << 0.7, 0.7, 0.0;
  Eigen::MatrixX3d Xc = model->rest_positions();
  Eigen::Vector2d p = tip_of(c, &Xc);
  for (int it = 0; it < 15 && (p - target).norm() > 0.05; ++it) {
    Eigen::Matrix2d J;
    for (int q = 0; q < 2; ++q) {
      Eigen::VectorXd cq = c;
      const double dv = c[q] > 0 ? -1e-2 : 1e-2;  // one-sided, towards the range's inside
      cq[q] += dv;
      Eigen::MatrixX3d Xq = Xc;
      J.col(q) = (tip_of(cq, &Xq) - p) / dv;
    }
    Eigen::Vector2d step = J.fullPivLu().solve(target - p);
    if (step.norm() > 0.5) step *= 0.5 / step.norm();  // trust region in actuation units
    c.head<2>() = (c.head<2>() + step).cwiseMax(-3.0).cwiseMin(3.0);
    p = tip_of(c, &Xc);
  }
  std::printf("  actuation (%.3f, %.3f, %.3f) puts the tip within %.3f mm of (0.7, 0.7, 0.7)'s\n",
              c[0], c[1], c[2], (p - target).norm());
  EXPECT_LT((p - target).norm(), 0.1);
  EXPECT_GT((c - Eigen::VectorXd(ref)).norm(), 0.5) << "the two actuations coincide";
}

TEST(RobotGrid, MultiSegmentGripperCurlsInPlane) {
  const Scene s = MakeRobot("multi_segment_gripper", 6);
  const Eigen::Vector3d tip0 = Marker(s, s.mesh.vertices, "tip");
  const double size = s.mesh.size();
  const GridOutcome g = SolveGrid(s, {{1, 4.5, 8}, {1, 4.5, 8}, {1, 4.5, 8}},
                                  [&](const Eigen::VectorXd& c, const FkResult& r) {
                                    const Eigen::Vector3d p = Marker(s, r.positions, "tip");
                                    EXPECT_NEAR(p.y(), tip0.y(), 1e-4 * size) << c.transpose();
                                    if (c.maxCoeff() > 1.0) {
                                      EXPECT_LT(p.z(), tip0.z() - 1.0) << c.transpose();
                                    }
                                    // Only the first segment at its top value flattens a few
                                    // elements.
                                    if (c[0] < 8.0) {
                                      EXPECT_EQ(r.inverted_elements, 0) << c.transpose();
                                    }
                                  });
  EXPECT_EQ(g.failed, 0);
  EXPECT_LE(g.inverted, 9);
  // The grip layer belongs to the third segment, beyond P0.
  const Eigen::Vector3d p0 = Marker(s, s.mesh.vertices, "P0");
  const Eigen::Vector3d grip = Marker(s, s.mesh.vertices, "grip_layer");
  EXPECT_GT(grip.x(), p0.x());
  EXPECT_LT(grip.z(), 2.0);
}

TEST(RobotGrid, DeaCrawlerSlidesOnTheGroundAndFlattens) {
  const Scene s = MakeRobot("dea_crawler", 4);
  const Model model(s);
  const int front = s.marker_index("front_foot");
  double last_spacing = 0, last_apex = 1e9;
  EXPECT_EQ(
      FailedOrInverted(SolveGrid(
          s, {{0.7, 0.775, 0.85, 0.925, 1.0}},
          [&](const Eigen::VectorXd& c, const FkResult& r) {
            // The front foot stays on the ground exactly (held z), the rear is pinned.
            for (int v : s.markers[front].vertices)
              EXPECT_EQ(r.positions(v, 2), s.mesh.vertices(v, 2));
            for (int v : s.fixed) EXPECT_EQ(r.positions.row(v), s.mesh.vertices.row(v));
            const double spacing =
                (Marker(s, r.positions, "front_foot") - Marker(s, r.positions, "rear_foot")).norm();
            const double apex = Marker(s, r.positions, "apex").z();
            // Relaxing the membrane spreads the legs and lowers the arch.
            EXPECT_GT(spacing, last_spacing) << c.transpose();
            EXPECT_LT(apex, last_apex) << c.transpose();
            last_spacing = spacing;
            last_apex = apex;
            if (c[0] == 1.0) {
              // lambda = 1 is the flat fabricated state: zero energy, rest positions.
              EXPECT_LT(r.energy, 1e-8);
              EXPECT_LT((r.positions - s.mesh.vertices).cwiseAbs().maxCoeff(), 1e-3);
            }
          })),
      0);
  // The released state arches well above the flat strip and pulls the feet together.
  const FkResult r = SolveFk(s, s.rest_actuation());
  ASSERT_EQ(r.status, FkStatus::Converged);
  EXPECT_GT(Marker(s, r.positions, "apex").z(), Marker(s, s.mesh.vertices, "apex").z() + 2.0);
  EXPECT_NEAR(r.volume_ratios[0], 0.7, 0.1);
}

TEST(RobotGrid, BimaterialBarTwistAndStretch) {
  const Scene s = MakeRobot("bimaterial_bar", 3);
  const int tip = s.marker_index("tip");
  // Twists of +-90 degrees over the 80 mm bar (the thesis's twisting test turns the end by a
  // similar amount); the warm start jumps 90 degrees at a time.
  EXPECT_EQ(FailedOrInverted(SolveGrid(
                s, {{-90, 0, 90}, {0, 20, 40}},
                [&](const Eigen::VectorXd& c, const FkResult& r) {
                  // The end face is where the motion puts it: its centre on the axis,
                  // moved by the stretch.
                  const Eigen::Vector3d p = s.marker_positions(r.positions).row(tip).transpose();
                  const Eigen::Vector3d p0 =
                      s.marker_positions(s.mesh.vertices).row(tip).transpose();
                  EXPECT_NEAR((p - p0 - Eigen::Vector3d(c[1], 0, 0)).norm(), 0.0, 1e-9);
                })),
            0);
}

TEST(RobotBimaterialBar, InterfaceFollowsTheParameterAndTheSofterSideStretchesMore) {
  for (double iface : {0.3, 0.5}) {
    for (double wb : {1.0, 4.0}) {
      const Scene s = MakeRobot("bimaterial_bar", 3, {{"interface", iface}, {"weight_b", wb}});
      Eigen::VectorXd c(2);
      c << 0.0, 16.0;
      const FkResult r = SolveFk(s, c);
      ASSERT_EQ(r.status, FkStatus::Converged) << r.BriefReport();
      const double L = s.mesh.vertices.col(0).maxCoeff();
      const double xi0 = Marker(s, s.mesh.vertices, "interface").x();
      const double xi = Marker(s, r.positions, "interface").x();
      EXPECT_NEAR(xi0, iface * L, 0.5 * L / 27 + 1e-9);  // snapped to a cell face
      const double strain_a = (xi - xi0) / xi0, strain_b = (L + 16.0 - xi - (L - xi0)) / (L - xi0);
      // A uniform bar stretches uniformly; B four times heavier stretches about four times less
      // (a series of two springs whose stiffness ratio is the weight ratio).
      if (wb == 1.0) {
        EXPECT_NEAR(strain_a / strain_b, 1.0, 0.02);
      }
      if (wb == 4.0) {
        EXPECT_NEAR(strain_a / strain_b, 4.0, 0.4);
      }
    }
  }
}

TEST(RobotGrid, CableGripperTwoMaterialDistributions) {
  std::map<std::string, Eigen::Vector3d> m3;
  for (const auto& [label, params] : std::vector<std::pair<std::string, RobotParams>>{
           {"uniform", {}}, {"stiff_links", {{"link_weight", 8.0}}}}) {
    const Scene s = MakeRobot("cable_gripper", 4, params);
    const Eigen::Vector3d tip0 = Marker(s, s.mesh.vertices, "tip");
    Eigen::Vector3d last;
    EXPECT_EQ(FailedOrInverted(SolveGrid(s, {{1.0, 0.875, 0.75, 0.625, 0.5}},
                                         [&](const Eigen::VectorXd& c, const FkResult& r) {
                                           last = Marker(s, r.positions, "m3");
                                           if (c[0] < 1.0) {
                                             EXPECT_GT(Marker(s, r.positions, "tip").z(),
                                                       tip0.z() + 1.0);
                                           }
                                         })),
              0)
        << label;
    m3[label] = last;
  }
  // The material distribution changes the shape (Fig. 2.9).
  EXPECT_GT((m3["uniform"] - m3["stiff_links"]).norm(), 2.0);
}

TEST(RobotParams, UnknownOrOutOfRangeParametersAreRejectedByName) {
  try {
    MakeRobot("bimaterial_bar", 3, {{"interfac", 0.3}});
    ADD_FAILURE() << "no throw";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("unknown parameter 'interfac'"), std::string::npos)
        << e.what();
    EXPECT_NE(std::string(e.what()).find("interface"), std::string::npos) << e.what();
  }
  try {
    MakeRobot("dea_crawler", 4, {{"frame_thickness", -1}});
    ADD_FAILURE() << "no throw";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("'frame_thickness' must be in [0.2, 5]"),
              std::string::npos)
        << e.what();
  }
  try {
    MakeRobot("bilayer_strip", 1, {{"cell_length", 0.01}});  // would be 10,000 cells long
    ADD_FAILURE() << "no throw";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("cell_length must be 0 (cubic cells) or at least 0.25"),
              std::string::npos)
        << e.what();
  }
  try {
    MakeRobot("bilayer_strip", 1, {{"hyperelastic", 0.5}});
    ADD_FAILURE() << "no throw";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("'hyperelastic' must be 0 (Ch. 2 shape blending, "
                                         "R_omega 1) or 1 (Ecoflex 00-30 Mooney-Rivlin), got 0.5"),
              std::string::npos)
        << e.what();
  }
  const Scene mr = MakeRobot("bilayer_strip", 1, {{"hyperelastic", 1}});
  EXPECT_TRUE(mr.body.at(0).hyperelastic());
  EXPECT_FALSE(MakeRobot("bilayer_strip", 1).body.at(0).hyperelastic());
  EXPECT_THROW(MakeRobot("three_chamber", 3, {{"gain", 1}}), std::invalid_argument);
}

}  // namespace
}  // namespace softkin

namespace softkin {
namespace {

// pneumatic_finger with design_grid = 1: the grid lines sit on the nominal dimensions, so the
// chambers' rest volume is the design's at every resolution (16 cavities of 5 x 17 x 10.5 mm),
// odd resolutions included, and the mesh is mirror-symmetric about y = 10, so a bend stays in
// that plane.
TEST(RobotGrid, PneumaticFingerDesignGridKeepsItsDimensionsAndSymmetry) {
  const double nominal = 16 * 5.0 * 17.0 * 10.5;
  for (int res : {5, 6, 7, 9}) {
    const Scene s = MakeRobot("pneumatic_finger", res, {{"design_grid", 1.0}});
    const Model m(s);
    EXPECT_NEAR(m.actuator_rest_measure(0), nominal, 1e-6 * nominal) << "res " << res;
    // Every vertex has its mirror image in y = 10.
    EXPECT_EQ(test::UnmatchedMirrorVertices(s.mesh, 10.0), 0) << "res " << res;
    EXPECT_EQ(test::UnmatchedMirrorElements(s.mesh, 1, 10.0), 0) << "res " << res;
  }
  const Scene s = MakeRobot("pneumatic_finger", 7, {{"design_grid", 1.0}});
  auto model = std::make_shared<const Model>(s);
  const FkResult r = MakeFkSolver(model, FkOptions{})->Solve(Eigen::VectorXd::Constant(1, 2.0));
  ASSERT_EQ(r.status, FkStatus::Converged) << r.message;
  const Eigen::RowVector3d tip = s.marker_positions(r.positions).row(s.marker_index("tip"));
  EXPECT_NEAR(tip.y(), 10.0, 1e-4);  // odd res: in the mirror plane
  EXPECT_LT(tip.z(), 0.0);
  EXPECT_THROW(MakeRobot("pneumatic_finger", 7, {{"design_grid", 0.5}}), std::invalid_argument);
}

/// The volume of a region's tets.
double RegionVolume(const Mesh& mesh, int region) {
  double v = 0.0;
  for (const Element& e : mesh.elements)
    if (e.region == region)
      v += TetVolume6(mesh.vertices.row(e.v[0]), mesh.vertices.row(e.v[1]),
                      mesh.vertices.row(e.v[2]), mesh.vertices.row(e.v[3])) /
           6.0;
  return v;
}

/// a and b have the same vertex positions (in any order) and as many elements.
void ExpectSameVerticesAndElementCount(const Mesh& a, const Mesh& b) {
  ASSERT_EQ(a.num_vertices(), b.num_vertices());
  ASSERT_EQ(a.num_elements(), b.num_elements());
  const auto at = test::VerticesByPosition(b);
  EXPECT_EQ(at.size(), static_cast<size_t>(b.num_vertices()));  // no two vertices coincide
  int missing = 0;
  for (int v = 0; v < a.num_vertices(); ++v)
    missing += !at.count(test::KeyOf(a.vertices.row(v).transpose()));
  EXPECT_EQ(missing, 0);
}

// cable_finger with design_grid = 1: each knuckle's bridge is the nominal 10 x 25 x 7.5 mm block
// and its tendon 10 mm long at every res (snapped, both change with res: the gaps are 8.33 and
// 12.5 mm wide at res 6 and 8), the mesh is mirror-symmetric about y = 12.5, and at the default
// res 10, where the design's dimensions fall on whole cells, it is the snapped mesh itself.
TEST(RobotGrid, CableFingerDesignGridKeepsItsDimensionsAndSymmetry) {
  const double nominal = 10.0 * 25.0 * 7.5;
  bool snapped_differs = false;
  for (int res : {6, 7, 9, 13}) {
    const Scene s = MakeRobot("cable_finger", res, {{"design_grid", 1.0}});
    const Model m(s);
    for (int k = 0; k < 3; ++k) {
      EXPECT_NEAR(RegionVolume(s.mesh, k + 1), nominal, 1e-9 * nominal) << "res " << res;
      EXPECT_NEAR(m.actuator_rest_measure(k), 10.0, 1e-9) << "res " << res;
    }
    EXPECT_NEAR(s.mesh.vertices.col(0).maxCoeff(), 120.0, 1e-9);
    EXPECT_NEAR(s.mesh.vertices.col(2).maxCoeff(), 25.0, 1e-9);
    EXPECT_EQ(test::UnmatchedMirrorVertices(s.mesh, 12.5), 0) << "res " << res;
    EXPECT_EQ(test::UnmatchedMirrorElements(s.mesh, 1, 12.5), 0) << "res " << res;
    const Scene snapped = MakeRobot("cable_finger", res);
    snapped_differs |= std::abs(RegionVolume(snapped.mesh, 1) - nominal) > 1.0;
  }
  EXPECT_TRUE(snapped_differs);  // the design grid is not what the default grid already was
  // Res 10: the design's dimensions are whole cells of 2.5 mm, and the two meshes coincide.
  const Scene d10 = MakeRobot("cable_finger", 10, {{"design_grid", 1.0}});
  const Scene s10 = MakeRobot("cable_finger", 10);
  ExpectSameVerticesAndElementCount(d10.mesh, s10.mesh);
  // A bend at an odd res stays in the mirror plane and curls the tip up (+z).
  const Scene s = MakeRobot("cable_finger", 7, {{"design_grid", 1.0}});
  auto model = std::make_shared<const Model>(s);
  const FkResult r = MakeFkSolver(model, FkOptions{})->Solve(Eigen::Vector3d(0.8, 0.8, 0.8));
  ASSERT_EQ(r.status, FkStatus::Converged) << r.message;
  const Eigen::RowVector3d tip = s.marker_positions(r.positions).row(s.marker_index("tip"));
  EXPECT_NEAR(tip.y(), 12.5, 1e-4);
  EXPECT_GT(tip.z(), 25.0);
  EXPECT_THROW(MakeRobot("cable_finger", 7, {{"design_grid", 2.0}}), std::invalid_argument);
}

// membrane with design_grid = 1 keeps the default res 20's dimensions at every res: a 10.5 mm
// membrane 2 mm above the roofs at z = 37.5, and four cavities of 75 x 75 x 12.5 mm inside
// 12.5 mm walls; the mesh is mirror-symmetric about x = 125 and y = 125, and at res 20 it is the
// snapped mesh itself. Snapped, the membrane is one cell less 2 mm thick (18.8 mm at res 12).
TEST(RobotGrid, MembraneDesignGridKeepsItsDimensionsAndSymmetry) {
  auto membrane_z = [](const Scene& s) {
    double lo = std::numeric_limits<double>::infinity(), hi = -lo;
    for (const Element& e : s.mesh.elements)
      if (e.region == 0)
        for (int q = 0; q < e.k(); ++q) {
          lo = std::min(lo, s.mesh.vertices(e.v[q], 2));
          hi = std::max(hi, s.mesh.vertices(e.v[q], 2));
        }
    return std::make_pair(lo, hi);
  };
  const double cavity = 75.0 * 75.0 * 12.5, membrane = 250.0 * 250.0 * 10.5;
  for (int res : {12, 13, 24, 32}) {
    const Scene s = MakeRobot("membrane", res, {{"design_grid", 1.0}});
    for (int q = 0; q < 4; ++q)
      EXPECT_NEAR(RegionVolume(s.mesh, 2 + q), cavity, 1e-9 * cavity) << "res " << res;
    EXPECT_NEAR(RegionVolume(s.mesh, 0), membrane, 1e-9 * membrane) << "res " << res;
    const auto [lo, hi] = membrane_z(s);
    EXPECT_NEAR(lo, 39.5, 1e-9) << "res " << res;
    EXPECT_NEAR(hi, 50.0, 1e-9) << "res " << res;
    EXPECT_EQ(test::UnmatchedMirrorElements(s.mesh, 0, 125.0), 0) << "res " << res;
    EXPECT_EQ(test::UnmatchedMirrorElements(s.mesh, 1, 125.0), 0) << "res " << res;
    EXPECT_TRUE(s.solver.collision.self);
  }
  const Scene snapped = MakeRobot("membrane", 12);
  EXPECT_NEAR(membrane_z(snapped).second - membrane_z(snapped).first, 250.0 / 12 - 2.0, 1e-9);
  // Res 20: the design's dimensions are whole cells of 12.5 mm, and the two meshes coincide.
  const Scene d20 = MakeRobot("membrane", 20, {{"design_grid", 1.0}});
  const Scene s20 = MakeRobot("membrane", 20);
  ExpectSameVerticesAndElementCount(d20.mesh, s20.mesh);
  EXPECT_EQ(d20.fixed.size(), s20.fixed.size());
  EXPECT_THROW(MakeRobot("membrane", 20, {{"design_grid", 0.5}}), std::invalid_argument);
}

// chamber_weight is the chamber elements' w_i of Eq. 2.10: the default is the thesis's 5, and a
// softer fill lags its target, so at the same alpha it reaches a smaller volume and bends less.
TEST(RobotGrid, PneumaticFingerChamberWeightSoftensTheFill) {
  EXPECT_EQ(MakeRobot("pneumatic_finger", 5).actuators[0].weight, 5.0);
  auto solve = [](double weight) {
    const Scene s =
        MakeRobot("pneumatic_finger", 5, {{"design_grid", 1.0}, {"chamber_weight", weight}});
    EXPECT_EQ(s.actuators[0].weight, weight);
    auto model = std::make_shared<const Model>(s);
    const FkResult r = MakeFkSolver(model, FkOptions{})->Solve(Eigen::VectorXd::Constant(1, 2.0));
    EXPECT_EQ(r.status, FkStatus::Converged) << r.message;
    const Eigen::RowVector3d tip = s.marker_positions(r.positions).row(s.marker_index("tip"));
    return std::make_pair(r.volume_ratios[0], tip.z());
  };
  const auto [stiff_volume, stiff_z] = solve(5.0);
  const auto [soft_volume, soft_z] = solve(0.5);
  EXPECT_GT(stiff_volume, 1.7);
  EXPECT_LT(soft_volume, stiff_volume - 0.1);
  EXPECT_LT(stiff_z, soft_z - 5.0);  // the finger curls towards -z
  try {
    MakeRobot("pneumatic_finger", 5, {{"chamber_weight", 0.0}});
    ADD_FAILURE() << "chamber_weight 0 was accepted";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("chamber_weight"), std::string::npos) << e.what();
  }
}

// multi_segment_gripper takes the same parameter, for all three chambers, snapped or on the
// design grid; a soft fill reaches less volume at the same actuation.
TEST(RobotGrid, MultiSegmentGripperChamberWeightSoftensEveryChamber) {
  for (const auto& a : MakeRobot("multi_segment_gripper", 6).actuators) EXPECT_EQ(a.weight, 5.0);
  for (double grid : {0.0, 1.0})
    for (const auto& a :
         MakeRobot("multi_segment_gripper", 6, {{"design_grid", grid}, {"chamber_weight", 0.05}})
             .actuators)
      EXPECT_EQ(a.weight, 0.05);
  auto volume = [](double weight) {
    const Scene s =
        MakeRobot("multi_segment_gripper", 6, {{"design_grid", 1.0}, {"chamber_weight", weight}});
    FkOptions o;
    o.solver = FkSolverType::kNewton;
    const FkResult r =
        MakeFkSolver(std::make_shared<const Model>(s), o)->Solve(Eigen::Vector3d(2.0, 1.0, 1.0));
    EXPECT_EQ(r.status, FkStatus::Converged) << r.message;
    return r.volume_ratios[0];
  };
  const double stiff = volume(5.0), soft = volume(0.05);
  EXPECT_GT(stiff, 1.8);
  EXPECT_LT(soft, stiff - 0.3);
  EXPECT_GT(soft, 1.01);
  try {
    MakeRobot("multi_segment_gripper", 6, {{"chamber_weight", 101.0}});
    ADD_FAILURE() << "chamber_weight 101 was accepted";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("chamber_weight"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace softkin

namespace softkin {
namespace {

// finger_manipulator with design_grid = 1: its walls, cavities and spine keep their nominal size
// at every resolution, odd ones included (each side of each section: 6 cavities of 4 x 7 x 9 mm),
// the mesh is mirror-symmetric about y = 10 (the +y chambers of a section mirror its -y ones),
// and the snapped default is still the robot without the parameter.
TEST(RobotGrid, FingerManipulatorDesignGridKeepsItsDimensionsAndSymmetry) {
  const double nominal = 6 * 4.0 * 7.0 * 9.0;
  for (int res : {6, 7, 9, 12}) {
    SCOPED_TRACE("res " + std::to_string(res));
    const Scene s = MakeRobot("finger_manipulator", res, {{"design_grid", 1.0}});
    auto volume = [&](int region) { return RegionVolume(s.mesh, s.mesh.vertices, {region}); };
    for (int region = 1; region <= 6; ++region)
      EXPECT_NEAR(volume(region), nominal, 1e-9 * nominal) << "region " << region;
    // The spine: 3 mm wide through the full 12 mm thickness, along each section's chamber row
    // (6 x 5.5 + 1.5 = 34.5 mm).
    EXPECT_NEAR(volume(7), 3 * 3.0 * 12.0 * 34.5, 1e-9 * 3 * 3.0 * 12.0 * 34.5);
    const Eigen::RowVector3d hi = s.mesh.vertices.colwise().maxCoeff();
    EXPECT_LT((hi - Eigen::RowVector3d(141, 20, 12)).norm(), 1e-9);
    EXPECT_EQ(test::UnmatchedMirrorVertices(s.mesh, 10.0), 0);
    EXPECT_EQ(test::UnmatchedMirrorElements(s.mesh, 1, 10.0), 0);
    // Planar motion in x-y: the tets are mirror images about the mid-thickness z = 6 too (an
    // even count of cells between the floor and the roof).
    EXPECT_EQ(test::UnmatchedMirrorElements(s.mesh, 2, 6.0), 0);
    EXPECT_EQ(s.markers.size(), 3u);
  }
  // So a bend stays in the plane z = 6 (to 1e-4 of the size, above the stopping rule). Before
  // the floor-to-roof count was made even, res 7 had 3 cells there and the tip left the plane.
  {
    const Scene s = MakeRobot("finger_manipulator", 7, {{"design_grid", 1.0}});
    const FkResult r = MakeFkSolver(std::make_shared<const Model>(s), s.solver)
                           ->Solve(Eigen::Vector3d(0.2, 0.0, 0.0));
    ASSERT_EQ(r.status, FkStatus::Converged) << r.message;
    const Eigen::Vector3d tip = Marker(s, r.positions, "tip");
    EXPECT_LT(tip.y(), 10.0 - 20.0);  // it bends towards -y
    EXPECT_NEAR(tip.z(), 6.0, 1e-4 * s.mesh.size());
  }
  EXPECT_EQ(MakeRobot("finger_manipulator", 8).mesh.num_elements(), 15840);
  EXPECT_THROW(MakeRobot("finger_manipulator", 8, {{"design_grid", 0.5}}), std::invalid_argument);
}

// multi_segment_gripper with design_grid = 1: seven 5 x 17 x 10.5 mm cavities per segment at
// every resolution (the snapped grid has 4, 6, 5 and 7 at res 6, 8, 10 and 12), the 168 x 20 x 15
// mm outline, the connectors' volume, the markers, mirror symmetry about y = 10; the snapped
// default is unchanged.
TEST(RobotGrid, MultiSegmentGripperDesignGridKeepsItsDimensionsAndSymmetry) {
  const double nominal = 7 * 5.0 * 17.0 * 10.5;
  for (int res : {6, 7, 9}) {
    SCOPED_TRACE("res " + std::to_string(res));
    const Scene s = MakeRobot("multi_segment_gripper", res, {{"design_grid", 1.0}});
    auto volume = [&](int region) { return RegionVolume(s.mesh, s.mesh.vertices, {region}); };
    for (int region = 1; region <= 3; ++region)
      EXPECT_NEAR(volume(region), nominal, 1e-9 * nominal) << "region " << region;
    // Two connectors of 5 mm above the 1.5 mm layer.
    EXPECT_NEAR(volume(5), 2 * 5.0 * 20.0 * 13.5, 1e-9 * 2700.0);
    const Eigen::RowVector3d hi = s.mesh.vertices.colwise().maxCoeff();
    EXPECT_LT((hi - Eigen::RowVector3d(168, 20, 15)).norm(), 1e-9);
    EXPECT_EQ(test::UnmatchedMirrorVertices(s.mesh, 10.0), 0);
    EXPECT_EQ(test::UnmatchedMirrorElements(s.mesh, 1, 10.0), 0);
    const Eigen::MatrixX3d P = s.marker_positions(s.mesh.vertices);
    EXPECT_NEAR(P(s.marker_index("P0"), 0), 118.0, 1e-9);
    EXPECT_NEAR(P(s.marker_index("tip"), 0), 168.0, 1e-9);
    for (int v : s.markers[s.marker_index("grip_layer")].vertices) {
      EXPECT_GE(s.mesh.vertices(v, 0), 118.0 - 1e-9);
      EXPECT_LE(s.mesh.vertices(v, 2), 1.5 + 1e-9);
    }
  }
  EXPECT_EQ(MakeRobot("multi_segment_gripper", 8).mesh.num_elements(), 19296);
  EXPECT_EQ(MakeRobot("multi_segment_gripper", 8).mesh.num_vertices(), 4284);
  EXPECT_THROW(MakeRobot("multi_segment_gripper", 8, {{"design_grid", 2.0}}),
               std::invalid_argument);
}

// selfcollision_finger with design_grid = 1: its walls keep the thickness asked for at every
// resolution (the snapped grid rounds wall = 3.34 mm to 3.33 mm at res 12 and 2.86 mm at res 14),
// with the chambers that fit after the 8 mm proximal block (14 of 5 x 17 x 10.5 mm for 1.5 mm
// walls, 9 of 5 x 13.32 x 8.66 mm for 3.34 mm walls); a 0.2 mm slit between each pair of
// neighbouring chambers; the 120 x 20 x 15 mm outline; mirror symmetry about y = 10 (so a bend
// stays in that plane, odd res included); and the snapped default is unchanged.
TEST(RobotGrid, SelfCollisionFingerDesignGridKeepsItsWallsAndSlits) {
  struct Design {
    double wall;
    int chambers;
  };
  for (const Design d : {Design{1.5, 14}, Design{3.34, 9}}) {
    const double pitch = 2 * d.wall + 5.0, proximal = 120.0 - d.chambers * pitch;
    const double cavity = 5.0 * (20.0 - 2 * d.wall) * (15.0 - d.wall - 3.0);
    for (int res : {6, 7, 9}) {
      SCOPED_TRACE("wall " + std::to_string(d.wall) + ", res " + std::to_string(res));
      const Scene s =
          MakeRobot("selfcollision_finger", res, {{"wall", d.wall}, {"design_grid", 1.0}});
      EXPECT_NEAR(RegionVolume(s.mesh, s.mesh.vertices, {1}), d.chambers * cavity,
                  1e-9 * d.chambers * cavity);
      const Eigen::RowVector3d lo = s.mesh.vertices.colwise().minCoeff(),
                               hi = s.mesh.vertices.colwise().maxCoeff();
      EXPECT_LT(lo.norm(), 1e-12);
      EXPECT_LT((hi - Eigen::RowVector3d(120, 20, 15)).norm(), 1e-9);
      EXPECT_EQ(test::UnmatchedMirrorVertices(s.mesh, 10.0), 0);
      EXPECT_EQ(test::UnmatchedMirrorElements(s.mesh, 1, 10.0), 0);
      // Each slit plane x = xs has its doubled vertices 0.2 mm beyond it, above the floor only.
      for (int q = 1; q < d.chambers; ++q) {
        const double xs = proximal + q * pitch;
        int moved = 0, below_floor = 0;
        for (int v = 0; v < s.mesh.num_vertices(); ++v)
          if (std::abs(s.mesh.vertices(v, 0) - (xs + 0.2)) < 1e-9) {
            ++moved;
            if (s.mesh.vertices(v, 2) < 3.0 + 1e-9) ++below_floor;
          }
        EXPECT_GT(moved, 0) << "slit " << q;
        EXPECT_EQ(below_floor, 0) << "slit " << q;
      }
    }
  }
  const Scene snapped = MakeRobot("selfcollision_finger", 8);
  EXPECT_EQ(snapped.mesh.num_elements(), 13824);
  EXPECT_EQ(snapped.mesh.num_vertices(), 3447);
  EXPECT_THROW(MakeRobot("selfcollision_finger", 8, {{"design_grid", 0.5}}), std::invalid_argument);

  // An odd resolution bends in the mirror plane, and the response keeps the state collision-free.
  const Scene s = MakeRobot("selfcollision_finger", 7, {{"wall", 3.34}, {"design_grid", 1.0}});
  auto model = std::make_shared<const Model>(s);
  const FkResult r = MakeFkSolver(model, s.solver)->Solve(Eigen::VectorXd::Constant(1, 2.0));
  ASSERT_EQ(r.status, FkStatus::Converged) << r.message;
  const Eigen::RowVector3d tip = s.marker_positions(r.positions).row(s.marker_index("tip"));
  EXPECT_NEAR(tip.y(), 10.0, 1e-3);
  EXPECT_LT(tip.z(), -5.0);
}

}  // namespace
}  // namespace softkin
