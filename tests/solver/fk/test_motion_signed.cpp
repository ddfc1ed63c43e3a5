// Tests of the actuators added with the actuation groups:
//  - Motion*:       displacement and twist actuators (prescribed rigid motion of a vertex set);
//  - Signed*:       signed two-sided pneumatic actuators (negative_regions, gain).
// The boundary conditions added with them are tested in test_constraints.cpp. The physics tests
// use small voxel bars (<= 1.2k tets) solved to a tight tolerance, and check identities that
// follow from symmetry or from the boundary conditions themselves.
#include "softkin/solver/fk/energy.hpp"
#include "softkin/solver/factory/fk_factory.hpp"
#include "softkin/solver/fk/fk_solver.hpp"
#include "softkin/solver/mesh/mesh_gen.hpp"
#include "softkin/solver/fk/model.hpp"
#include "tests/solver/fk/constraints_test_util.hpp"
#include "tests/solver/test_util.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <functional>
#include <iterator>
#include <limits>
#include <map>
#include <memory>
#include <random>
#include <set>
#include <stdexcept>
#include <string>
#include <tuple>
#include <vector>

namespace softkin {
namespace {

using namespace constraints_test;
using test::MatrixNear;

const double kPi = std::acos(-1.0);

Scene TwoSidedBar(double gain = 1.0);  // Signed tests

// ---------------------------------------------------------------------------------------------
// Motion: displacement and twist actuators
// ---------------------------------------------------------------------------------------------

Actuator Displacement(const std::string& name, std::vector<int> vertices, Eigen::Vector3d axis,
                      double min = -5.0, double max = 5.0) {
  Actuator a;
  a.name = name;
  a.type = ActuatorType::Displacement;
  a.vertices = std::move(vertices);
  a.axis = axis;
  a.min = min;
  a.max = max;
  a.rest = 0.0;
  return a;
}

Actuator Twist(const std::string& name, std::vector<int> vertices, Eigen::Vector3d axis,
               Eigen::Vector3d centre) {
  Actuator a;
  a.name = name;
  a.type = ActuatorType::Twist;
  a.vertices = std::move(vertices);
  a.axis = axis;
  a.centre = centre;
  a.min = -180.0;
  a.max = 180.0;
  a.rest = 0.0;
  return a;
}

/// Body-only bar of unit cubes (cells along x, y, z), x = 0 face fixed, the x = L face moved by
/// `act` (its vertices are filled in here). region(i) tags cell column i.
Scene MotionBar(const Eigen::Vector3i& cells, Actuator act, const std::map<int, Material>& body,
                const std::function<int(int)>& region = nullptr) {
  Scene s = test::VoxelScene(
      cells, 1.0, [&](const Eigen::Vector3i& c) { return region ? region(c.x()) : 0; }, body, {},
      "motion_bar");
  act.vertices = Plane(s.mesh, 0, cells.x());
  s.actuators = {act};
  s.validate();
  return s;
}

TEST(Motion, DisplacementStretchesSymmetricallyAndLandsExactly) {
  const Scene s =
      MotionBar({10, 4, 4}, Displacement("pull", {}, Eigen::Vector3d::UnitX()), {{0, Rigid()}});
  auto model = std::make_shared<const Model>(s);
  EXPECT_EQ(model->num_groups(), 0);  // motion actuators have no elements
  EXPECT_EQ(model->num_factors(), 1);
  EXPECT_EQ(static_cast<int>(model->fixed_vertices().size()), 50);  // both end faces
  const Actuator& a = s.actuators[0];
  // At rest (d = 0) the rest shape is the solution, with zero energy.
  const FkResult r0 = SolveRest(model);
  ASSERT_EQ(r0.status, FkStatus::Converged) << r0.BriefReport();
  EXPECT_LE(r0.iterations, 2);
  EXPECT_TRUE(MatrixNear(r0.positions, s.mesh.vertices, 1e-12));
  EXPECT_LE(r0.energy, 1e-24);
  EXPECT_EQ(r0.volume_ratios[0], 0.0);  // a motion actuator reports its prescribed value
  double prev_energy = 0;
  for (double d : {1.0, 2.5}) {
    const FkResult r = SolveTight(model, Vec1(d));
    ASSERT_EQ(r.status, FkStatus::Converged) << r.BriefReport();
    EXPECT_EQ(r.volume_ratios[0], d);
    for (int v : a.vertices) {
      EXPECT_EQ(r.positions(v, 0), s.mesh.vertices(v, 0) + d);
      EXPECT_EQ(r.positions(v, 1), s.mesh.vertices(v, 1));
      EXPECT_EQ(r.positions(v, 2), s.mesh.vertices(v, 2));
    }
    for (int v : s.fixed) EXPECT_TRUE(r.positions.row(v) == s.mesh.vertices.row(v));
    // The solver's energy is the energy of its answer, and stretching costs energy, more when
    // stretched further.
    EXPECT_NEAR(r.energy, Energy(*model, r.positions, Vec1(d)), 1e-9 * r.energy);
    EXPECT_GT(r.energy, prev_energy);
    prev_energy = r.energy;
    // Mirror symmetry about y = 2 and z = 2 (even cell counts: the voxel split is symmetric).
    // Anderson's path is symmetric up to round-off only; the answer is within the stopping
    // tolerance of the symmetric fixed point.
    const double sy = MirrorDefect(r.positions, MirrorPartner(s.mesh, 1, 2.0), 1, 2.0);
    const double sz = MirrorDefect(r.positions, MirrorPartner(s.mesh, 2, 2.0), 2, 2.0);
    // The problem is also invariant under x -> L - x followed by a translation d along x (it swaps
    // the clamped and moved faces), so the mid-plane x = 5 moves by exactly d / 2.
    double mid = 0;
    for (int v : Plane(s.mesh, 0, 5.0))
      mid = std::max(mid, std::abs(r.positions(v, 0) - 5.0 - 0.5 * d));
    std::printf(
        "  d = %.1f: energy %.5g, asymmetry y %.2g z %.2g mm, mid-plane error %.2g mm, "
        "%d iterations\n",
        d, r.energy, sy, sz, mid, r.iterations);
    // Bound: 1e-7 of the size, as in Constraints.SymmetryPlaneHalfModelMatchesFullModel.
    EXPECT_LT(sy, 1e-7 * model->size());
    EXPECT_LT(sz, 1e-7 * model->size());
    EXPECT_LT(mid, 1e-7 * model->size());
  }
}

TEST(Motion, DisplacementAxisIsNormalised) {
  // A shear: the end face moved along z; the axis need not be a unit vector.
  const Scene s =
      MotionBar({6, 2, 2}, Displacement("shear", {}, Eigen::Vector3d(0, 0, 3.0)), {{0, Rigid()}});
  auto model = std::make_shared<const Model>(s);
  const FkResult r = SolveTight(model, Vec1(-1.5));
  ASSERT_EQ(r.status, FkStatus::Converged) << r.BriefReport();
  for (int v : s.actuators[0].vertices) {
    EXPECT_EQ(r.positions(v, 0), s.mesh.vertices(v, 0));
    EXPECT_EQ(r.positions(v, 1), s.mesh.vertices(v, 1));
    EXPECT_NEAR(r.positions(v, 2), s.mesh.vertices(v, 2) - 1.5, 1e-15);
  }
  // The free vertices follow: the mid-plane drops by between 0 and 1.5 mm.
  for (int v : Plane(s.mesh, 0, 3.0)) {
    const double dz = r.positions(v, 2) - s.mesh.vertices(v, 2);
    EXPECT_LT(dz, -0.1);
    EXPECT_GT(dz, -1.5);
  }
}

/// Mean rotation angle (rad, right-hand about +x) of the cross-section x = x0 about the line
/// y = z = 2, from rest to X: the mean over its off-axis vertices of the angle change.
double SectionAngle(const Mesh& m, const Eigen::MatrixX3d& X, double x0) {
  double sum = 0;
  int n = 0;
  for (int v : Plane(m, 0, x0)) {
    const Eigen::Vector2d p0(m.vertices(v, 1) - 2.0, m.vertices(v, 2) - 2.0);
    const Eigen::Vector2d p(X(v, 1) - 2.0, X(v, 2) - 2.0);
    if (p0.norm() < 1e-9) continue;
    sum += std::atan2(p0.x() * p.y() - p0.y() * p.x(), p0.dot(p));
    ++n;
  }
  return sum / n;
}

TEST(Motion, TwistRotatesEndExactlyAndMidSectionByHalf) {
  const Eigen::Vector3d centre(0.0, 2.0, 2.0);
  const Scene s =
      MotionBar({12, 4, 4}, Twist("twist", {}, Eigen::Vector3d::UnitX(), centre), {{0, Rigid()}});
  auto model = std::make_shared<const Model>(s);
  const double theta_deg = 60.0, theta = theta_deg * kPi / 180.0;
  const FkResult r = SolveTight(model, Vec1(theta_deg));
  ASSERT_EQ(r.status, FkStatus::Converged) << r.BriefReport();
  const Eigen::Matrix3d R = Eigen::AngleAxisd(theta, Eigen::Vector3d::UnitX()).toRotationMatrix();
  for (int v : s.actuators[0].vertices) {
    const Eigen::Vector3d p0 = s.mesh.vertices.row(v).transpose();
    const Eigen::Vector3d want = centre + R * (p0 - centre);
    EXPECT_LT((r.positions.row(v).transpose() - want).norm(), 1e-12) << "vertex " << v;
  }
  EXPECT_NEAR(SectionAngle(s.mesh, r.positions, 12.0), theta, 1e-12);
  const double a_mid = SectionAngle(s.mesh, r.positions, 6.0);
  const double a_q1 = SectionAngle(s.mesh, r.positions, 3.0);
  const double a_q3 = SectionAngle(s.mesh, r.positions, 9.0);
  std::printf(
      "  twist %.0f deg: sections at x = 3, 6, 9 rotate %.4f, %.6f, %.4f deg; energy %.4g; "
      "%d iterations\n",
      theta_deg, a_q1 * 180 / kPi, a_mid * 180 / kPi, a_q3 * 180 / kPi, r.energy, r.iterations);
  // Symmetry: x -> L - x, then y -> 4 - y, then rotation by theta about the axis maps the problem
  // onto itself (it swaps the clamped and twisted ends), and maps the mid-section's angle a to
  // theta - a. The answer is unique, so a = theta / 2 up to the solver's tolerance (1e-9 * size per
  // iteration, ~1e-8 rad for this 13 mm bar; 1e-6 rad allows a contraction rate of 0.99).
  EXPECT_NEAR(a_mid, 0.5 * theta, 1e-6);
  // The same symmetry pairs x = 3 with x = 9.
  EXPECT_NEAR(a_q1 + a_q3, theta, 1e-6);
  // Uniform bar, uniform twist: the quarter sections rotate by about theta / 4 and 3 theta / 4.
  // On this coarse mesh the clamped ends (no warping allowed) stiffen the bar near them; measured
  // 0.17 degrees off, allow 1 degree.
  EXPECT_NEAR(a_q1, 0.25 * theta, 1.0 * kPi / 180.0);
  EXPECT_GT(a_q1, 0.0);
  EXPECT_LT(a_q1, a_mid);
  EXPECT_LT(a_mid, a_q3);
  EXPECT_LT(a_q3, theta);
  // Opposite twist, mirror image: the rotation angle flips sign.
  const FkResult rn = SolveTight(model, Vec1(-theta_deg));
  ASSERT_EQ(rn.status, FkStatus::Converged) << rn.BriefReport();
  EXPECT_NEAR(SectionAngle(s.mesh, rn.positions, 3.0), -a_q1, 1e-6);
}

TEST(Motion, SofterHalfOfTwoMaterialBarStretchesMore) {
  // Cells 0..5 (x < 6): weight 1; cells 6..11: weight w. Both ARAP. Pulled by d along x. In 1D the
  // two halves carry the same force, w_soft e_soft = w_stiff e_stiff, so the strain ratio is w.
  auto strain_ratio = [](double w) {
    const Scene s =
        MotionBar({12, 2, 2}, Displacement("pull", {}, Eigen::Vector3d::UnitX()),
                  {{0, Rigid(1.0)}, {1, Rigid(w)}}, [](int i) { return i < 6 ? 0 : 1; });
    auto model = std::make_shared<const Model>(s);
    const double d = 1.2;
    const FkResult r = SolveTight(model, Vec1(d));
    EXPECT_EQ(r.status, FkStatus::Converged) << r.BriefReport();
    double u = 0;
    const std::vector<int> mid = Plane(s.mesh, 0, 6.0);
    for (int v : mid) u += (r.positions(v, 0) - 6.0) / mid.size();
    const double soft = u / 6.0, stiff = (d - u) / 6.0;
    std::printf("  weight ratio %.0f: strain soft %.4f, stiff %.4f, ratio %.3f (%d iterations)\n",
                w, soft, stiff, soft / stiff, r.iterations);
    return soft / stiff;
  };
  const double r1 = strain_ratio(1.0), r2 = strain_ratio(2.0), r4 = strain_ratio(4.0);
  // Equal weights: the bar is uniform and x-symmetric, the interface moves by d / 2 exactly.
  EXPECT_NEAR(r1, 1.0, 1e-6);
  EXPECT_GT(r2, 1.2);
  EXPECT_GT(r4, r2 + 0.5);
  // Close to the 1D law: the clamped ends and the interface (where the halves' cross-sections
  // must match) perturb it slightly; measured 2 % and 4 % low, allow 8 %.
  EXPECT_NEAR(r2, 2.0, 0.16);
  EXPECT_NEAR(r4, 4.0, 0.32);
}

TEST(Motion, MotionsOfOneVertexComposeInActuatorOrder) {
  // scene.hpp: a vertex moved by several motion actuators gets their motions composed in actuator
  // order, each applied to the position left by the previous ones; a twist's axis is fixed in
  // space. A twist about x and a shift along y do not commute, so the order shows.
  const Eigen::Vector3d centre(0.0, 1.0, 1.0);
  const Scene base =
      MotionBar({6, 2, 2}, Twist("twist", {}, Eigen::Vector3d::UnitX(), centre), {{0, Rigid()}});
  const std::vector<int> face = base.actuators[0].vertices;
  const Actuator shift = Displacement("shift", face, Eigen::Vector3d::UnitY());
  Scene twist_first = base, shift_first = base;
  twist_first.actuators = {base.actuators[0], shift};
  shift_first.actuators = {shift, base.actuators[0]};
  ASSERT_NO_THROW(twist_first.validate());
  ASSERT_NO_THROW(shift_first.validate());
  const double deg = 30.0, d = 0.8;
  const Eigen::Matrix3d R =
      Eigen::AngleAxisd(deg * kPi / 180.0, Eigen::Vector3d::UnitX()).toRotationMatrix();
  auto model = std::make_shared<const Model>(twist_first);
  EXPECT_EQ(static_cast<int>(model->fixed_vertices().size()), 2 * 9);  // the two end faces
  Eigen::VectorXd c(2);
  c << deg, d;
  const FkResult r = SolveTight(model, c);
  ASSERT_EQ(r.status, FkStatus::Converged) << r.BriefReport();
  Eigen::MatrixX3d Y = base.mesh.vertices;
  const Model other(shift_first);
  Eigen::VectorXd c2(2);
  c2 << d, deg;
  other.ApplyConstraints(c2, &Y);
  double differ = 0;
  for (int v : face) {
    const Eigen::Vector3d p = base.mesh.vertices.row(v).transpose();
    const Eigen::Vector3d a = centre + R * (p - centre) + d * Eigen::Vector3d::UnitY();
    const Eigen::Vector3d b = centre + R * (p + d * Eigen::Vector3d::UnitY() - centre);
    EXPECT_LT((r.positions.row(v).transpose() - a).norm(), 1e-12) << "vertex " << v;
    EXPECT_LT((Y.row(v).transpose() - b).norm(), 1e-12) << "vertex " << v;
    differ = std::max(differ, (a - b).norm());
  }
  EXPECT_GT(differ, 0.1);  // the two orders really are different motions
}

TEST(Motion, RestValueConvergesAtOnceUnderTightTolerance) {
  // At the rest actuation the rest shape is the exact answer (zero energy) and the residual is
  // round-off, so the solver should stop at once whatever the tolerances. With gradient_tolerance
  // 1e-10 it does not: the reference residual is floored at 1e-8 * sum(w Vol) * size
  // (local_global.cpp), the round-off residual's ratio to it stays ~1e-8, and the solver runs to
  // its iteration cap (20000 iterations, ~5-10 s on these bars) although the positions are exact.
  // Same for signed (value 0) and plain pneumatic actuators (rest ratio 1). Capped at 50 iterations
  // here.
  const Scene motion =
      MotionBar({10, 4, 4}, Displacement("pull", {}, Eigen::Vector3d::UnitX()), {{0, Rigid()}});
  const Scene chamber = QuadrantChamberBar();
  const Scene two_sided = TwoSidedBar();
  for (const Scene* s : {&motion, &two_sided, &chamber}) {
    auto model = std::make_shared<const Model>(*s);
    FkOptions o = Tight();
    o.max_iterations = 50;
    const FkResult r = MakeFkSolver(model, o)->Solve(s->rest_actuation());
    // Positions stay at rest up to the round-off of the iterations run (~1e-12 mm after 50).
    EXPECT_TRUE(MatrixNear(r.positions, s->mesh.vertices, 1e-10)) << s->name;
    EXPECT_EQ(r.status, FkStatus::Converged) << s->name << ": " << r.BriefReport();
  }
}

TEST(Motion, ValidateRejectsBadMotionActuators) {
  const Scene good =
      MotionBar({4, 2, 2}, Displacement("pull", {}, Eigen::Vector3d::UnitX()), {{0, Rigid()}});
  ASSERT_NO_THROW(good.validate());
  {
    Scene s = good;  // motion actuators have no regions
    s.actuators[0].regions = {0};
    ExpectValidateRejects(s, "no regions");
  }
  {
    Scene s = good;
    s.actuators[0].vertices.clear();
    ExpectValidateRejects(s, "at least one moved vertex");
  }
  {
    Scene s = good;
    s.actuators[0].axis = Eigen::Vector3d::Zero();
    ExpectValidateRejects(s, "non-zero axis");
  }
  {
    Scene s = good;
    s.actuators[0].axis = Eigen::Vector3d(std::nan(""), 0, 0);
    ExpectValidateRejects(s, "non-zero axis");
  }
  {
    Scene s = good;  // twist about a non-finite centre
    s.actuators[0].type = ActuatorType::Twist;
    s.actuators[0].centre = Eigen::Vector3d(0, std::numeric_limits<double>::infinity(), 0);
    ExpectValidateRejects(s, "centre");
  }
  {
    Scene s = good;  // a vertex listed twice by one actuator
    s.actuators[0].vertices.push_back(s.actuators[0].vertices[3]);
    ExpectValidateRejects(s, "listed twice");
  }
  {
    Scene s = good;  // a fixed vertex that is also moved
    s.actuators[0].vertices.push_back(s.fixed[0]);
    std::sort(s.actuators[0].vertices.begin(), s.actuators[0].vertices.end());
    ExpectValidateRejects(s, "both fixed and moved");
  }
  {
    Scene s = good;
    s.actuators[0].vertices.push_back(s.mesh.num_vertices());
    ExpectValidateRejects(s, "out of range");
  }
  {
    Scene s = good;  // only motion actuators move vertices
    Actuator p = test::Pneumatic("p", {});
    p.vertices = {0};
    s.actuators.push_back(p);
    ExpectValidateRejects(s, "only displacement and twist");
  }
  {
    Scene s = good;
    s.actuators[0].max = std::numeric_limits<double>::infinity();
    ExpectValidateRejects(s, "finite range");
  }
  {
    // A moved face alone (nothing fixed) is a valid support: it pins every coordinate it moves.
    Scene s = good;
    s.fixed.clear();
    EXPECT_NO_THROW(s.validate());
  }
}

// ---------------------------------------------------------------------------------------------
// Signed: two-sided pneumatic actuators
// ---------------------------------------------------------------------------------------------

Actuator SignedPneumatic(double gain = 1.0) {
  Actuator a = test::Pneumatic("bend", {1}, 5.0, -0.6, 0.6);
  a.rest = 0.0;
  a.negative_regions = {2};
  a.gain = gain;
  return a;
}

/// 12 x 6 x 2 bar of unit cubes, x = 0 face fixed: for x >= 1 the cells j = 4, 5 (+y side) are
/// chamber region 1 and j = 0, 1 (-y side) region 2, around a body spine j = 2, 3 (region 0). The
/// bar and its split are mirror-symmetric about y = 3, with regions 1 and 2 swapped.
Scene TwoSidedBar(double gain) {
  return test::VoxelScene(
      {12, 6, 2}, 1.0,
      [](const Eigen::Vector3i& c) {
        if (c.x() < 1 || (c.y() >= 2 && c.y() <= 3)) return 0;
        return c.y() >= 4 ? 1 : 2;
      },
      {{0, Rigid()}}, {SignedPneumatic(gain)}, "two_sided_bar");
}

TEST(Signed, GroupsAndRatios) {
  const Scene s = TwoSidedBar(2.0);
  const Model m(s);
  ASSERT_EQ(m.num_groups(), 2);
  EXPECT_EQ(m.group_actuator(0), 0);
  EXPECT_EQ(m.group_actuator(1), 0);
  EXPECT_EQ(m.group_side(0), 1);
  EXPECT_EQ(m.group_side(1), -1);
  EXPECT_EQ(m.group_elements(0).size(), 11u * 2 * 2 * 6);  // 11 x 2 x 2 cells of 6 tets
  EXPECT_EQ(m.group_elements(1).size(), m.group_elements(0).size());
  for (int i : m.group_elements(0)) EXPECT_EQ(s.mesh.elements[i].region, 1);
  for (int i : m.group_elements(1)) EXPECT_EQ(s.mesh.elements[i].region, 2);
  EXPECT_NEAR(m.group_rest_measure(0), 44.0, 1e-12);
  EXPECT_NEAR(m.group_rest_measure(1), 44.0, 1e-12);
  // v > 0 drives the positive side to 1 + gain v, v < 0 the negative side to 1 + gain |v|.
  EXPECT_DOUBLE_EQ(m.GroupRatio(0, Vec1(0.25)), 1.5);
  EXPECT_DOUBLE_EQ(m.GroupRatio(1, Vec1(0.25)), 1.0);
  EXPECT_DOUBLE_EQ(m.GroupRatio(0, Vec1(-0.25)), 1.0);
  EXPECT_DOUBLE_EQ(m.GroupRatio(1, Vec1(-0.25)), 1.5);
  EXPECT_DOUBLE_EQ(m.GroupRatio(0, Vec1(0.0)), 1.0);
  EXPECT_DOUBLE_EQ(m.GroupRatio(1, Vec1(0.0)), 1.0);
  // ActuatorValue inverts GroupRatio on the active side: (rho - 1) / gain with the sign of v.
  EXPECT_DOUBLE_EQ(m.ActuatorValue(0, {1.5, 1.0}, Vec1(0.25)), 0.25);
  EXPECT_DOUBLE_EQ(m.ActuatorValue(0, {1.0, 1.5}, Vec1(-0.25)), -0.25);
  EXPECT_DOUBLE_EQ(m.ActuatorValue(0, {1.3, 1.0}, Vec1(0.25)), 0.15);  // achieved short of v
  EXPECT_DOUBLE_EQ(m.actuator_rest_measure(0), m.group_rest_measure(0));
}

TEST(Signed, OppositeValuesGiveMirrorImages) {
  const Scene s = TwoSidedBar();
  auto model = std::make_shared<const Model>(s);
  const std::vector<int> partner = MirrorPartner(s.mesh, 1, 3.0);
  for (int v = 0; v < s.mesh.num_vertices(); ++v) ASSERT_GE(partner[v], 0);
  // At rest (v = 0) nothing moves.
  const FkResult r0 = SolveRest(model);
  ASSERT_EQ(r0.status, FkStatus::Converged) << r0.BriefReport();
  EXPECT_LE(r0.iterations, 2);
  EXPECT_TRUE(MatrixNear(r0.positions, s.mesh.vertices, 1e-12));
  EXPECT_EQ(r0.volume_ratios[0], 0.0);

  const int tip = s.marker_index("tip");
  const double y0 = s.marker_positions(s.mesh.vertices)(tip, 1);
  for (double v : {0.3, 0.6}) {
    const FkResult rp = SolveTight(model, Vec1(v)), rn = SolveTight(model, Vec1(-v));
    ASSERT_EQ(rp.status, FkStatus::Converged) << rp.BriefReport();
    ASSERT_EQ(rn.status, FkStatus::Converged) << rn.BriefReport();
    const double dist = MirrorDistance(rp.positions, rn.positions, partner, 1, 3.0);
    const double bend = s.marker_positions(rp.positions)(tip, 1) - y0;
    // Achieved value (from both sides' volume ratios) and each side's volume ratio, measured here.
    const double pos = RegionVolumeRatio(s.mesh, rp.positions, 1);
    const double neg = RegionVolumeRatio(s.mesh, rp.positions, 2);
    std::printf(
        "  v = +-%.1f: tip y %+.3f mm, mirror distance %.2g mm, achieved %+.5f / %+.5f, "
        "driven side %.5f, passive side %.5f (%d / %d iterations)\n",
        v, bend, dist, rp.volume_ratios[0], rn.volume_ratios[0], pos, neg, rp.iterations,
        rn.iterations);
    // Inflating the +y chamber bends the bar towards -y.
    EXPECT_LT(bend, -1.0);
    // v and -v are mirror images, to the solver's tolerance (1e-7 of the size: see
    // Constraints.SymmetryPlaneHalfModelMatchesFullModel).
    EXPECT_LT(dist, 1e-7 * model->size());
    EXPECT_NEAR(rn.volume_ratios[0], -rp.volume_ratios[0], 1e-6);
    // The reported value inverts the active side's achieved volume ratio: (V+ / V+0 - 1) / gain
    // (the inactive side is vented, targets.hpp, and does not enter it).
    EXPECT_NEAR(rp.volume_ratios[0], pos - 1.0, 1e-12);
    // The volume target is soft (chamber weight 5 against the body's 1): the spine, a third of the
    // cross-section at a fifth of the chamber's weight, resists the growth a little, so the chamber
    // falls short of 1 + v but reaches most of it. Measured 96.5-97 % of v; bound 90 %.
    EXPECT_LT(rp.volume_ratios[0], v);
    EXPECT_GT(rp.volume_ratios[0], 0.9 * v);
  }
}

TEST(Signed, InactiveSideIsVentedLikeEmptySpace) {
  // For v > 0 the -y chambers are vented (targets.hpp: target = current shape, no energy, no
  // force), so the vertices that belong to other elements must sit where they would if the -y
  // chamber cells were not there at all and the +y chamber were an ordinary chamber at 1 + gain v.
  // (Vertices of vented elements only are left undetermined by the model: not compared.)
  const double gain = 2.0, v = 0.2;
  const Scene s = TwoSidedBar(gain);
  const Scene cut = test::VoxelScene(
      {12, 6, 2}, 1.0,
      [](const Eigen::Vector3i& c) {
        if (c.x() < 1 || (c.y() >= 2 && c.y() <= 3)) return 0;
        return c.y() >= 4 ? 1 : -1;
      },
      {{0, Rigid()}}, {test::Pneumatic("p", {1}, 5.0, 1.0, 2.0)}, "cut_bar");
  const FkResult rs = SolveTight(std::make_shared<const Model>(s), Vec1(v));
  const FkResult rc = SolveTight(std::make_shared<const Model>(cut), Vec1(1.0 + gain * v));
  ASSERT_EQ(rs.status, FkStatus::Converged) << rs.BriefReport();
  ASSERT_EQ(rc.status, FkStatus::Converged) << rc.BriefReport();
  const std::vector<int> same = SamePosition(cut.mesh, s.mesh);
  double worst = 0, moved = 0;
  for (int q = 0; q < cut.mesh.num_vertices(); ++q) {
    ASSERT_GE(same[q], 0);
    worst = std::max(worst, (rc.positions.row(q) - rs.positions.row(same[q])).norm());
    moved = std::max(moved, (rc.positions.row(q) - cut.mesh.vertices.row(q)).norm());
  }
  const double vented = RegionVolumeRatio(s.mesh, rs.positions, 2);
  std::printf(
      "  signed v = %.1f vs cut bar at %.1f: max distance %.3g mm (max displacement %.3f "
      "mm); achieved %.6f vs %.6f; vented side's volume ratio %.4f\n",
      v, 1.0 + gain * v, worst, moved, rs.volume_ratios[0], rc.volume_ratios[0], vented);
  EXPECT_GT(moved, 1.0);
  // Both solved to the tight tolerance: 1e-7 of the size as in
  // Constraints.SymmetryPlaneHalfModelMatchesFullModel (measured ~2e-9 of the size).
  EXPECT_LT(worst, 1e-7 * cut.mesh.size());
  // Same chamber volume, read as a signed value (v) and as a ratio (1 + gain v).
  EXPECT_NEAR(1.0 + gain * rs.volume_ratios[0], rc.volume_ratios[0], 1e-7);
  // No energy in the vented cells: the energies agree.
  EXPECT_NEAR(rs.energy, rc.energy, 1e-6 * rc.energy);
}

TEST(Signed, ValidateRejectsBadSignedActuators) {
  const Scene good = TwoSidedBar();
  ASSERT_NO_THROW(good.validate());
  {
    Scene s = good;  // rest must be 0 (here min <= rest <= max still holds)
    s.actuators[0].rest = 0.1;
    ExpectValidateRejects(s, "signed actuator has rest 0");
  }
  {
    Scene s = good;  // min > 0 (with rest = min, so only the signed rule is broken)
    s.actuators[0].min = 0.1;
    s.actuators[0].rest = 0.1;
    ExpectValidateRejects(s, "min <= 0 <= max");
  }
  {
    Scene s = good;
    s.actuators[0].max = -0.1;
    s.actuators[0].rest = -0.1;
    ExpectValidateRejects(s, "min <= 0 <= max");
  }
  for (double g : {0.0, -1.0, std::nan(""), std::numeric_limits<double>::infinity()}) {
    Scene s = good;
    s.actuators[0].gain = g;
    ExpectValidateRejects(s, "gain must be > 0");
  }
  {
    Scene s = good;  // only pneumatic actuators are signed
    s.actuators[0].type = ActuatorType::Dea;
    ExpectValidateRejects(s, "only pneumatic actuators can be signed");
  }
  {
    Scene s = good;
    s.actuators[0].type = ActuatorType::Cable;
    s.actuators[0].path = {{0, 1, 1}, {12, 1, 1}};
    ExpectValidateRejects(s, "only pneumatic actuators can be signed");
  }
  {
    Scene s = good;  // one region on both sides
    s.actuators[0].negative_regions = {2, 1};
    ExpectValidateRejects(s, "region 1");
  }
  {
    Scene s = good;  // the negative side selects no element (region 2 then has no role either)
    s.body[2] = Rigid();
    s.actuators[0].negative_regions = {7};
    ExpectValidateRejects(s, "negative side");
  }
}

}  // namespace
}  // namespace softkin
