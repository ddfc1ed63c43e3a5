// Progressive chamber remeshing (solver/remesh/remesh.hpp, thesis Algorithm 2) and the twisting
// robot (solver/robots/robot_twisting.hpp).
#include "softkin/solver/fk/energy.hpp"
#include "softkin/solver/factory/fk_factory.hpp"
#include "softkin/solver/fk/fk_solver.hpp"
#include "softkin/solver/fk/model.hpp"
#include "softkin/solver/remesh/remesh.hpp"
#include "softkin/solver/robots/robot_twisting.hpp"
#include "softkin/solver/robots/robots.hpp"
#include "softkin/solver/fk/targets.hpp"

#include <Eigen/Geometry>
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <map>
#include <memory>
#include <set>

namespace softkin {
namespace {

/// One tet, region 1, with its reference shape a unit right tet.
Mesh OneTet() {
  Mesh m;
  m.vertices.resize(4, 3);
  m.vertices << 0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1;
  Element e;
  e.v = {0, 1, 2, 3, -1, -1};
  e.region = 1;
  m.elements.push_back(e);
  return m;
}

Eigen::MatrixX3d Apply(const Eigen::Matrix3d& F, const Eigen::MatrixX3d& V) {
  return (V * F.transpose()).rowwise() + Eigen::RowVector3d(3, -2, 5);  // plus a translation
}

TEST(Remesh, NeedsRemeshFiresPastTheThresholdsOnly) {
  const Mesh m = OneTet();
  const Eigen::MatrixX3d& P = m.vertices;
  const RemeshCriteria crit;  // alpha_max = d_max = 4
  // At rest, and after a rigid motion: nothing.
  EXPECT_FALSE(NeedsRemesh(m, P, P, {1}, crit));
  const Eigen::Matrix3d R =
      Eigen::AngleAxisd(1.1, Eigen::Vector3d(1, 2, 3).normalized()).toRotationMatrix();
  RemeshCheck c = CheckRemesh(m, P, Apply(R, P), {1}, crit);
  EXPECT_FALSE(c.needed);
  EXPECT_NEAR(c.max_volume_ratio, 1.0, 1e-12);
  EXPECT_NEAR(c.max_distortion, 1.0, 1e-12);
  // Uniform expansion to 3x the volume: below both thresholds (distortion cbrt 3).
  c = CheckRemesh(m, P, Apply(std::cbrt(3.0) * R, P), {1}, crit);
  EXPECT_FALSE(c.needed);
  EXPECT_NEAR(c.max_volume_ratio, 3.0, 1e-12);
  EXPECT_NEAR(c.max_distortion, std::cbrt(3.0), 1e-12);
  // Uniform expansion to 5x: the volume test fires, not the distortion test.
  c = CheckRemesh(m, P, Apply(std::cbrt(5.0) * Eigen::Matrix3d::Identity(), P), {1}, crit);
  EXPECT_TRUE(c.needed);
  EXPECT_EQ(c.over_volume, 1);
  EXPECT_EQ(c.over_distortion, 0);
  // Stretch by 5 along x at constant volume: the distortion test fires, not the volume test.
  c = CheckRemesh(m, P,
                  Apply(Eigen::Vector3d(5, 1 / std::sqrt(5.0), 1 / std::sqrt(5.0)).asDiagonal(), P),
                  {1}, crit);
  EXPECT_TRUE(c.needed);
  EXPECT_EQ(c.over_volume, 0);
  EXPECT_EQ(c.over_distortion, 1);
  EXPECT_NEAR(c.max_distortion, 5.0, 1e-12);
  // Compression to a fifth along z (the map from deformed to rest stretches by 5).
  c = CheckRemesh(m, P, Apply(Eigen::Vector3d(1, 1, 0.2).asDiagonal(), P), {1}, crit);
  EXPECT_TRUE(c.needed);
  EXPECT_NEAR(c.max_distortion, 5.0, 1e-12);
  // Just below / above d_max by a shear.
  Eigen::Matrix3d S = Eigen::Matrix3d::Identity();
  S(0, 1) = 3.0;  // singular values 3.30, 0.30: distortion 3.30
  EXPECT_FALSE(NeedsRemesh(m, P, Apply(S, P), {1}, crit));
  S(0, 1) = 4.0;  // 4.24
  EXPECT_TRUE(NeedsRemesh(m, P, Apply(S, P), {1}, crit));
  // Only the listed regions are checked.
  EXPECT_FALSE(NeedsRemesh(m, P, Apply(S, P), {0}, crit));
  // Looser thresholds are honoured.
  EXPECT_FALSE(NeedsRemesh(m, P, Apply(S, P), {1}, RemeshCriteria{4.0, 5.0}));
  // Bad input.
  EXPECT_THROW(CheckRemesh(m, P, P.topRows(3), {1}, crit), std::invalid_argument);
  EXPECT_THROW(CheckRemesh(m, P, P, {1}, RemeshCriteria{0.5, 4.0}), std::invalid_argument);
}

TEST(TwistingRobot, TwistAboutAxisRecoversAKnownRotation) {
  Eigen::MatrixX3d P(6, 3);
  P << 1, 0, 0, 0, 2, 0, -1, 0, 1, 0, -1, 2, 0.5, 0.5, -1, 2, 1, 0;
  for (double deg : {-170.0, -35.0, 0.0, 20.0, 120.0}) {
    const Eigen::Matrix3d Rz =
        Eigen::AngleAxisd(deg * M_PI / 180, Eigen::Vector3d::UnitZ()).toRotationMatrix();
    // A swing about an axis in the x-y plane applied after the twist does not change the twist.
    const Eigen::Matrix3d Rs =
        Eigen::AngleAxisd(0.4, Eigen::Vector3d(1, 1, 0).normalized()).toRotationMatrix();
    EXPECT_NEAR(TwistAboutAxisDegrees(P, Apply(Rz, P), Eigen::Vector3d::UnitZ()), deg, 1e-9);
    EXPECT_NEAR(TwistAboutAxisDegrees(P, Apply(Rs * Rz, P), Eigen::Vector3d::UnitZ()), deg, 1e-9);
  }
}

/// The twisting robot at res 1 (6.2k tets), built once: its default Mooney-Rivlin body, and the
/// as-rigid-as-possible body (hyperelastic = 0) used for the longer ladders; both with the
/// chamber's range raised to 120, as remeshing allows.
const Scene& Twisting() {
  static const Scene s = MakeRobot("twisting_robot", 1, {{"max_ratio", 120.0}});
  return s;
}
const Scene& TwistingArap() {
  static const Scene s =
      MakeRobot("twisting_robot", 1, {{"hyperelastic", 0.0}, {"max_ratio", 120.0}});
  return s;
}

FkResult Solve(const Scene& s, double alpha, const Eigen::MatrixX3d* warm = nullptr) {
  auto model = std::make_shared<const Model>(s);
  Eigen::VectorXd c = s.rest_actuation();
  c[0] = alpha;
  return MakeFkSolver(model, s.solver)->Solve(c, warm);
}

/// The Mooney-Rivlin robot solved at alpha = 3, once, a hundred times more tightly than the
/// scene's default (tolerance 1e-7, gradient 1e-9), so that the state the remesh tests start from
/// is the equilibrium to well below the solver's default stopping error.
const FkResult& SolvedAt3() {
  static const FkResult r = [] {
    const Scene& s = Twisting();
    FkOptions o = s.solver;
    o.tolerance = 1e-7;
    o.gradient_tolerance = 1e-9;
    Eigen::VectorXd c = s.rest_actuation();
    c[0] = 3.0;
    return MakeFkSolver(std::make_shared<const Model>(s), o)->Solve(c, nullptr);
  }();
  return r;
}

TEST(TwistingRobot, BuildsValidatesAndTwistsUnderActuation) {
  const Scene& s = Twisting();
  s.validate();
  EXPECT_EQ(s.mesh.regions(), (std::vector<int>{0, 1}));
  ASSERT_EQ(s.num_actuators(), 1);
  EXPECT_EQ(s.actuators[0].name, "chamber");
  // The default range is what the initial mesh reaches without inverted elements; remeshing
  // raises it to the thesis's 120.
  EXPECT_EQ(MakeRobot("twisting_robot", 1).actuators[0].max, 3.0);
  EXPECT_EQ(s.actuators[0].max, 120.0);
  EXPECT_TRUE(s.body.at(0).hyperelastic());
  EXPECT_DOUBLE_EQ(s.body.at(0).c1, 0.0418);
  EXPECT_DOUBLE_EQ(s.body.at(0).c2, 0.0106);
  EXPECT_FALSE(TwistingArap().body.at(0).hyperelastic());
  ASSERT_GE(s.marker_index("tip"), 0);
  EXPECT_GT(s.fixed.size(), 5u);
  for (int v : s.fixed) EXPECT_NEAR(s.mesh.vertices(v, 2), 0.0, 1e-9);
  for (int v : s.markers[s.marker_index("tip")].vertices)
    EXPECT_NEAR(s.mesh.vertices(v, 2), kTwistLength, 1e-9);
  // The chamber has vertices inside it (not only tets spanning the tube).
  std::set<int> boundary;
  for (const auto& f : RegionBoundaryFaces(s.mesh, 1)) boundary.insert(f.begin(), f.end());
  int interior = 0;
  std::set<int> chamber_vertices;
  for (const auto& e : s.mesh.elements)
    if (e.region == 1) chamber_vertices.insert(e.v.begin(), e.v.begin() + 4);
  for (int v : chamber_vertices) interior += boundary.count(v) ? 0 : 1;
  EXPECT_GT(interior, 10);
  // Deterministic: the same robot again.
  const Scene again = MakeRobot("twisting_robot", 1);
  EXPECT_EQ(again.mesh.vertices, s.mesh.vertices);
  // Inflating the helical chamber turns the tip about the long axis, more towards the tip.
  const FkResult& r = SolvedAt3();
  ASSERT_EQ(r.status, FkStatus::Converged) << r.BriefReport();
  const std::vector<double> twist = TwistProfileDegrees(s, r.positions, kTwistLength, 10);
  EXPECT_GT(std::abs(twist.back()), 5.0) << "tip twist " << twist.back() << " deg";
  EXPECT_LT(std::abs(twist[4]), std::abs(twist.back()));
  EXPECT_LT(std::abs(twist.front()), 0.5 * std::abs(twist.back()));
  // At rest nothing turns.
  for (double a : TwistProfileDegrees(s, s.mesh.vertices, kTwistLength, 10))
    EXPECT_NEAR(a, 0.0, 1e-9);
}

std::vector<std::array<int, 3>> Mapped(std::vector<std::array<int, 3>> faces,
                                       const std::vector<int>& old_index) {
  for (auto& f : faces) {
    for (int& v : f) v = old_index[v];
    std::sort(f.begin(), f.end());
  }
  std::sort(faces.begin(), faces.end());
  return faces;
}

TEST(Remesh, ChamberOnlyKeepsTheBodyAndTheChamberVolume) {
  const Scene& s = Twisting();
  const FkResult& r = SolvedAt3();
  ASSERT_EQ(r.status, FkStatus::Converged) << r.BriefReport();
  ChamberRemeshOptions o;
  o.method = RemeshMethod::ChamberOnly;
  o.rest = ChamberRest::Original;  // the rest volume is the original chamber's (see the next test
                                   // for the default)
  const ChamberRemesh rm = RemeshChamber(s, r.positions, o);
  EXPECT_EQ(rm.method, RemeshMethod::ChamberOnly);
  const Scene& n = rm.scene;
  n.validate();
  // The body's tets and rest positions are kept exactly, and so are its deformed positions.
  int nb = 0;
  for (const auto& e : s.mesh.elements) {
    if (e.region != 0) continue;
    const Element& f = n.mesh.elements[nb++];
    ASSERT_EQ(f.region, 0);
    for (int j = 0; j < 4; ++j) {
      ASSERT_EQ(rm.old_index[f.v[j]], e.v[j]);
      ASSERT_EQ(n.mesh.vertices.row(f.v[j]), s.mesh.vertices.row(e.v[j]));
      ASSERT_EQ(rm.positions.row(f.v[j]), r.positions.row(e.v[j]));
    }
  }
  // The outer boundary (body surface) and the interface are unchanged.
  EXPECT_EQ(Mapped(RegionBoundaryFaces(n.mesh, 0), rm.old_index), RegionBoundaryFaces(s.mesh, 0));
  EXPECT_EQ(Mapped(RegionBoundaryFaces(n.mesh, 1), rm.old_index), RegionBoundaryFaces(s.mesh, 1));
  EXPECT_DOUBLE_EQ(rm.outer_volume_after, rm.outer_volume_before);
  // The chamber was re-tessellated; its deformed and rest volumes are kept (its boundary is).
  EXPECT_NE(rm.chamber_tets_after, rm.chamber_tets_before);
  EXPECT_GT(rm.new_vertices + rm.removed_vertices, 0);
  EXPECT_NEAR(rm.chamber_volume_after, rm.chamber_volume_before, 1e-9 * rm.chamber_volume_before);
  EXPECT_NEAR(rm.chamber_rest_volume_after, rm.chamber_rest_volume_before,
              1e-9 * rm.chamber_rest_volume_before);
  EXPECT_TRUE(n.region_rest.regions.empty());
  for (const auto& e : n.mesh.elements)
    if (e.region == 1) {
      ASSERT_GT(SignedVolume(e, rm.positions), 0);
      ASSERT_GT(SignedVolume(e, n.mesh.vertices), 0);
    }
  // Markers and the fixed set follow the renumbering.
  ASSERT_EQ(n.fixed.size(), s.fixed.size());
  for (size_t i = 0; i < s.fixed.size(); ++i) EXPECT_EQ(rm.old_index[n.fixed[i]], s.fixed[i]);
  const int tip = s.marker_index("tip");
  EXPECT_LT(
      (n.marker_positions(rm.positions).row(tip) - s.marker_positions(r.positions).row(tip)).norm(),
      1e-12);
  // The carried state is (close to) an equilibrium of the new model: re-solving moves the tip
  // little compared with how far the actuation moved it (with the original rest shape only; with
  // the default ChamberRest::Remeshed the re-solve inflates the chamber further, next test). The
  // new chamber tets keep rest shapes pulled back through the old deformation, so the equilibrium
  // does shift, by about a fifth of the motion, and by how much depends on the CGAL tessellation,
  // which follows the last bits of the solved state. Four solves of the same equilibrium (the
  // eigen-decomposition and the Newton polar rotations, each at the scene's tolerance and at 1e-7)
  // gave drifts of 1.91, 2.06, 2.18 and 1.82 mm against a motion of 9.93 mm: 0.18-0.22 of it
  // (re-solve energies 9016.0, 8983.9, 8995.9, 8971.2; the same with lg, lg-aa and the energy
  // safeguard; the CGAL seed changes nothing). So this bound sits near the edge of that spread: the
  // shipped solver and the tight solve above give 1.82 mm, 0.183. The pulled-back rest shapes are
  // why: the thesis's re-tessellated chamber rests in its remeshed shape (ChamberRest::Remeshed,
  // the default).
  const FkResult again = Solve(n, 3.0, &rm.positions);
  // The state meets the tolerance; one body element by the chamber ends flat (volume ratio
  // -0.006), so it is reported `inverted`, never `converged`.
  ASSERT_TRUE(again.status == FkStatus::Converged || again.status == FkStatus::Inverted)
      << again.BriefReport();
  EXPECT_LE(again.inverted_elements, 1) << again.BriefReport();
  const double moved =
      (s.marker_positions(r.positions).row(tip) - s.marker_positions(s.mesh.vertices).row(tip))
          .norm();
  const double drift =
      (n.marker_positions(again.positions).row(tip) - n.marker_positions(rm.positions).row(tip))
          .norm();
  std::printf("  moved %.4f mm, drift after remesh %.4f mm; %s\n", moved, drift,
              again.BriefReport().c_str());
  EXPECT_LT(drift, 0.2 * moved) << "moved " << moved << " mm, drift after remesh " << drift
                                << " mm";
}

/// The as-rigid-as-possible robot solved at alpha = 3 (the scene's solver options), once.
const FkResult& ArapSolvedAt3() {
  static const FkResult r = Solve(TwistingArap(), 3.0);
  return r;
}

/// Per-element chamber ratios: `value` for the chamber's elements, kVented elsewhere (body
/// elements ignore it).
std::vector<double> ChamberRatios(const Model& m, int region, double value) {
  std::vector<double> r(m.elements().size(), kVented);
  for (size_t i = 0; i < r.size(); ++i)
    if (m.scene().mesh.elements[i].region == region) r[i] = value;
  return r;
}

TEST(Remesh, RemeshedChamberRestsInItsRemeshedShape) {
  // Algorithm 2, line 11 (the default ChamberRest::Remeshed): the re-tessellated chamber's rest
  // shape is the shape it was meshed in; the body keeps its own.
  const Scene& s = TwistingArap();
  const FkResult& r = ArapSolvedAt3();
  ASSERT_EQ(r.status, FkStatus::Converged) << r.BriefReport();
  ChamberRemeshOptions o;
  o.method = RemeshMethod::ChamberOnly;
  ASSERT_EQ(o.rest, ChamberRest::Remeshed);
  const ChamberRemesh rm = RemeshChamber(s, r.positions, o);
  const Scene& n = rm.scene;
  n.validate();
  ASSERT_EQ(n.region_rest.regions, std::vector<int>{1});
  EXPECT_EQ(n.region_rest.positions, rm.positions);
  // The chamber's rest volume is its volume at the remesh (the re-tessellation keeps its
  // boundary, so also its volume before).
  EXPECT_NEAR(rm.chamber_rest_volume_after, rm.chamber_volume_after,
              1e-12 * rm.chamber_volume_after);
  EXPECT_NEAR(rm.chamber_rest_volume_after, rm.chamber_volume_before,
              1e-9 * rm.chamber_volume_before);
  EXPECT_GT(rm.chamber_rest_volume_after, 2.0 * rm.chamber_rest_volume_before);
  // The Model takes the chamber tets' rest shapes from their remeshed shapes and the body tets'
  // from the (unchanged) body rest positions.
  const Model m(n);
  const Model m0(s);
  double body_before = 0, body_after = 0;
  for (size_t i = 0; i < m.elements().size(); ++i) {
    const ModelElement& e = m.elements()[i];
    const Element& el = n.mesh.elements[i];
    const Eigen::MatrixX3d& P = el.region == 1 ? rm.positions : n.mesh.vertices;
    Eigen::Matrix<double, 4, 3> rows;
    for (int j = 0; j < 4; ++j) rows.row(j) = P.row(el.v[j]);
    const Eigen::RowVector3d c = rows.colwise().mean();
    for (int j = 0; j < 4; ++j)
      ASSERT_LT((e.rest.row(j) - (rows.row(j) - c)).norm(), 1e-12 * (1 + c.norm()));
    ASSERT_NEAR(e.rest_volume, SignedVolume(el, P), 1e-12 * e.rest_volume);
    if (el.region == 0) body_after += e.rest_volume;
  }
  for (const auto& e : m0.elements())
    if (e.role == ElementRole::Body) body_before += e.rest_volume;
  EXPECT_NEAR(body_after, body_before, 1e-9 * body_before);
  // Zero energy at rest for the chamber: asked to keep its volume (ratio 1), the chamber adds
  // nothing at the remeshed state; the body's energy is the old model's at the same state.
  const std::vector<double> keep = ChamberRatios(m, 1, 1.0), vent = ChamberRatios(m, 1, kVented);
  Eigen::MatrixX3d g;
  const double e_keep = FixedRatioEnergyAndGradient(m, rm.positions, keep, &g);
  const double e_body = FixedRatioEnergyAndGradient(m, rm.positions, vent, &g);
  const double e_body_old =
      FixedRatioEnergyAndGradient(m0, r.positions, ChamberRatios(m0, 1, kVented), &g);
  EXPECT_GT(e_body, 0.0);
  EXPECT_NEAR(e_keep, e_body, 1e-9 * e_body);
  EXPECT_NEAR(e_body, e_body_old, 1e-9 * e_body_old);
  // Asked again for alpha = 3 of the original chamber (3 V_c^0 / M_k of the new rest volume), the
  // chamber, which the body held below 3 (soft actuation), inflates further towards 3.
  const double ratio_before = rm.chamber_volume_before / rm.chamber_rest_volume_before;
  const FkResult again =
      Solve(n, 3.0 * rm.chamber_rest_volume_before / rm.chamber_rest_volume_after, &rm.positions);
  // The state meets the tolerance; one body element by the chamber ends flat (volume ratio
  // -0.006), so it is reported `inverted`, never `converged`.
  ASSERT_TRUE(again.status == FkStatus::Converged || again.status == FkStatus::Inverted)
      << again.BriefReport();
  EXPECT_LE(again.inverted_elements, 1) << again.BriefReport();
  const double ratio_after =
      RegionVolume(n.mesh, again.positions, {1}) / rm.chamber_rest_volume_before;
  std::printf("  chamber volume ratio %.4f before the remesh, %.4f after re-solving\n",
              ratio_before, ratio_after);
  EXPECT_GT(ratio_after, ratio_before + 0.05);
  EXPECT_LT(ratio_after, 3.0);
  // Bad region_rest: the wrong number of rows, NaN, a region with no elements.
  Scene bad = n;
  bad.region_rest.positions.conservativeResize(bad.region_rest.positions.rows() - 1, 3);
  try {
    bad.validate();
    FAIL() << "expected an error for a short region_rest";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(
        std::string(e.what()).find("region_rest: expected one row of rest positions per vertex"),
        std::string::npos)
        << e.what();
  }
  bad = n;
  bad.region_rest.positions(3, 1) = std::nan("");
  EXPECT_THROW(bad.validate(), std::invalid_argument);
  bad = n;
  bad.region_rest.regions = {7};
  EXPECT_THROW(bad.validate(), std::invalid_argument);
}

TEST(Remesh, WholeRetessellationKeepsTheSurfacesWithinTolerance) {
  const Scene& s = Twisting();
  const FkResult& r = SolvedAt3();
  ChamberRemeshOptions o;
  o.method = RemeshMethod::Whole;
  o.rest = ChamberRest::Original;
  o.tessellation = TwistingRobotTessellation(1);
  const ChamberRemesh rm = RemeshChamber(s, r.positions, o);
  EXPECT_EQ(rm.method, RemeshMethod::Whole);
  const Scene& n = rm.scene;
  n.validate();
  // Mesh_3 re-samples the deformed surfaces: the outer surface within a fraction of the facet
  // distance's order, its volume within 2 %, the chamber's within 6 % (coarser, more curved).
  EXPECT_LT(rm.outer_deviation, 1.0);
  EXPECT_NEAR(rm.outer_volume_after, rm.outer_volume_before, 0.02 * rm.outer_volume_before);
  EXPECT_NEAR(rm.chamber_volume_after, rm.chamber_volume_before, 0.06 * rm.chamber_volume_before);
  EXPECT_NEAR(rm.chamber_rest_volume_after, rm.chamber_rest_volume_before,
              0.06 * rm.chamber_rest_volume_before);
  for (const auto& e : n.mesh.elements) ASSERT_GT(SignedVolume(e, n.mesh.vertices), 0);
  // Fixed vertices are re-found on the base, held at their rest positions; the tip face and the
  // twist carry over.
  ASSERT_GT(n.fixed.size(), 3u);
  for (int v : n.fixed) {
    EXPECT_NEAR(n.mesh.vertices(v, 2), 0.0, 1e-6);
    EXPECT_EQ(rm.positions.row(v), n.mesh.vertices.row(v));
  }
  const int tip = s.marker_index("tip");
  for (int v : n.markers[tip].vertices) EXPECT_NEAR(n.mesh.vertices(v, 2), kTwistLength, 1e-6);
  EXPECT_LT(
      (n.marker_positions(rm.positions).row(tip) - s.marker_positions(r.positions).row(tip)).norm(),
      1.0);
  const double t0 = TwistProfileDegrees(s, r.positions, kTwistLength, 10).back();
  const double t1 = TwistProfileDegrees(n, rm.positions, kTwistLength, 10).back();
  EXPECT_NEAR(t1, t0, 2.0);
  // The new model builds and a solve from the carried state runs.
  const FkResult again =
      Solve(n, 3.0 * rm.chamber_rest_volume_before / rm.chamber_rest_volume_after, &rm.positions);
  EXPECT_NE(again.status, FkStatus::InvalidInput) << again.BriefReport();
  // The default ChamberRest::Remeshed: the same tessellation (same seed), the chamber resting in
  // its new shape; only the body's interpolated rest shapes must be valid tets.
  o.rest = ChamberRest::Remeshed;
  const ChamberRemesh rr = RemeshChamber(s, r.positions, o);
  ASSERT_EQ(rr.scene.region_rest.regions, std::vector<int>{1});
  EXPECT_EQ(rr.scene.region_rest.positions, rr.positions);
  EXPECT_EQ(rr.scene.mesh.num_tets(), n.mesh.num_tets());
  EXPECT_NEAR(rr.chamber_rest_volume_after, rr.chamber_volume_after,
              1e-12 * rr.chamber_volume_after);
  EXPECT_NEAR(rr.chamber_volume_after, rr.chamber_volume_before, 0.06 * rr.chamber_volume_before);
  for (const auto& e : rr.scene.mesh.elements) {
    if (e.region == 0)
      ASSERT_GT(SignedVolume(e, rr.scene.mesh.vertices), 0);
    else
      ASSERT_GT(SignedVolume(e, rr.positions), 0);
  }
  const Model built(rr.scene);
  EXPECT_EQ(built.num_vertices(), rr.scene.mesh.num_vertices());
}

TEST(Remesh, SolveProgressiveRemeshesAndReachesTheTarget) {
  const Scene& s = TwistingArap();
  ProgressiveOptions o;
  o.snapshots = {6.0};
  int calls = 0;
  o.on_step = [&calls](const ProgressiveStep&, const Scene& sc, const Eigen::MatrixX3d& X) {
    ++calls;
    EXPECT_EQ(X.rows(), sc.mesh.num_vertices());
  };
  const ProgressiveResult p = SolveProgressive(s, 8.0, o);
  // Every step meets the tolerance; the twisted chamber's state at alpha = 4 has inverted body
  // elements before it is remeshed, so the ladder reports `inverted` (the first step not
  // converged), never `converged`.
  ASSERT_TRUE(p.status == FkStatus::Converged || p.status == FkStatus::Inverted) << p.BriefReport();
  EXPECT_TRUE(p.completed);
  ASSERT_EQ(p.steps.size(), 3u);  // 4, 6, 8
  EXPECT_EQ(calls, 3);
  EXPECT_DOUBLE_EQ(p.steps[0].alpha, 4.0);
  EXPECT_DOUBLE_EQ(p.steps[1].alpha, 6.0);
  EXPECT_DOUBLE_EQ(p.steps[2].alpha, 8.0);
  // From rest to alpha = 4 some chamber tet grows more than alpha_max = 4 times: remeshed.
  EXPECT_GT(p.steps[0].max_volume_ratio, 4.0);
  EXPECT_GE(p.steps[0].remeshes, 1);
  int counted = 0;
  for (const auto& st : p.steps) counted += st.remeshes;
  EXPECT_EQ(counted, p.remeshes);
  EXPECT_EQ(p.remesh_failures, 0) << p.first_remesh_failure;
  // The chamber inflates step by step.
  for (size_t k = 1; k < p.steps.size(); ++k)
    EXPECT_GT(p.steps[k].chamber_volume_ratio, p.steps[k - 1].chamber_volume_ratio);
  EXPECT_GT(p.chamber_volume_ratio, 3.0);
  ASSERT_EQ(p.snapshots.size(), 1u);
  EXPECT_DOUBLE_EQ(p.snapshots[0].alpha, 6.0);
  EXPECT_EQ(p.snapshots[0].positions.rows(), p.snapshots[0].scene.mesh.num_vertices());
  EXPECT_EQ(p.positions.rows(), p.scene.mesh.num_vertices());
  // The remeshed chamber rests in its remeshed shape (Algorithm 2) and is asked for alpha V_c^0
  // of its volume: it gets closer to the target than one whose new tets keep rest shapes pulled
  // back to the original chamber (ChamberRest::Original), which stays well below it.
  o.snapshots = {};
  o.on_step = nullptr;
  o.remesh_options.rest = ChamberRest::Original;
  const ProgressiveResult orig = SolveProgressive(s, 8.0, o);
  o.remesh_options.rest = ChamberRest::Remeshed;
  std::printf("  chamber volume ratio at alpha 8: %.3f (remeshed rest), %.3f (original rest)\n",
              p.chamber_volume_ratio, orig.chamber_volume_ratio);
  EXPECT_GT(orig.remeshes, 0);
  EXPECT_GT(p.chamber_volume_ratio, orig.chamber_volume_ratio + 0.5);
  EXPECT_LT(p.chamber_volume_ratio, 8.0);
  // Without remeshing the same ladder keeps the mesh.
  o.remesh = false;
  const ProgressiveResult q = SolveProgressive(s, 8.0, o);
  EXPECT_EQ(q.remeshes, 0);
  EXPECT_EQ(q.scene.mesh.num_tets(), s.mesh.num_tets());
  // An explicit ladder replaces the k * alpha_max values (the target is still added). Each
  // step's time splits into the local and global steps (no collision handling here).
  o.ladder = {2.5, 5.0};
  const ProgressiveResult l = SolveProgressive(s, 8.0, o);
  ASSERT_EQ(l.steps.size(), 3u);
  EXPECT_DOUBLE_EQ(l.steps[0].alpha, 2.5);
  EXPECT_DOUBLE_EQ(l.steps[1].alpha, 5.0);
  EXPECT_DOUBLE_EQ(l.steps[2].alpha, 8.0);
  for (const auto& st : l.steps) {
    EXPECT_FALSE(st.collision_active);
    EXPECT_EQ(st.check_seconds, 0.0);
    EXPECT_GT(st.local_global_seconds, 0.0);
    EXPECT_LE(st.local_global_seconds, st.solver_seconds);
  }
}

TEST(Remesh, ProgressiveRejectsScenesWithoutOneChamberAndBadTargets) {
  const Scene three = MakeRobot("three_chamber", 3);
  try {
    SolveProgressive(three, 2.0);
    FAIL() << "expected an error for three chambers";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("exactly one actuator"), std::string::npos) << e.what();
  }
  const Scene cable = MakeRobot("cable_finger", 5);
  EXPECT_THROW(SolveProgressive(cable, 2.0), std::invalid_argument);
  const Scene& s = Twisting();
  try {
    SolveProgressive(s, 500.0);
    FAIL() << "expected an error for alpha beyond the range";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("chamber"), std::string::npos) << e.what();
  }
  ProgressiveOptions o;
  o.snapshots = {20.0};
  EXPECT_THROW(SolveProgressive(s, 12.0, o), std::invalid_argument);
  o.snapshots = {};
  o.ladder = {3.0, 14.0};  // beyond the target
  EXPECT_THROW(SolveProgressive(s, 12.0, o), std::invalid_argument);
  o.ladder = {5.0, 3.0};  // not increasing
  try {
    SolveProgressive(s, 12.0, o);
    FAIL() << "expected an error for a decreasing ladder";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find(
                  "ladder: expected increasing volume ratios > 1, got 3 at position 1"),
              std::string::npos)
        << e.what();
  }
  o.ladder = {};
  o.criteria.d_max = 0.5;
  EXPECT_THROW(SolveProgressive(s, 12.0, o), std::invalid_argument);
}

}  // namespace
}  // namespace softkin
