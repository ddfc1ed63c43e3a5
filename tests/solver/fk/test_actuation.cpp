// Cable and DEA actuation elements (Sec. 2.3.3, Eq. 2.6-2.7): target shapes, measures and their
// gradients, the energy gradient through the ratio distribution, and the ratios achieved by the
// solver on free specimens.
#include "softkin/solver/fk/actuation.hpp"
#include "softkin/solver/fk/energy.hpp"
#include "softkin/solver/factory/fk_factory.hpp"
#include "softkin/solver/fk/fk_solver.hpp"
#include "softkin/solver/fk/model.hpp"
#include "softkin/solver/robots/robots.hpp"
#include "softkin/solver/fk/targets.hpp"
#include "tests/solver/test_util.hpp"

#include <gtest/gtest.h>

#include <algorithm>

#include <cmath>
#include <random>

namespace softkin {
namespace {

using test::MatrixNear;

using test::Cable;
using test::Dea;

/// A 10 x 2 x 2 bar of unit cubes along x; cells with i >= body_cells are the cable's elements,
/// the rest rigid body. The cable runs along the bar's axis from x = 0 to x = 10.
Scene CableBar(int body_cells) {
  const std::vector<Eigen::Vector3d> path = {{0, 1, 1}, {10, 1, 1}};
  std::map<int, Material> body;
  if (body_cells > 0) body[0] = Material{"rigid", 1.0, 1.0};
  return test::VoxelScene(
      {10, 2, 2}, 1.0,
      [body_cells](const Eigen::Vector3i& c) { return c.x() >= body_cells ? 1 : 0; }, body,
      {Cable("tendon", {1}, path)}, "cable_bar");
}

/// An 6 x 6 one-layer prism sheet (edge 2, thickness 2), every prism a DEA element; held 3-2-1
/// on its bottom corners (free to grow in its plane and in thickness, no rigid motion left): the
/// corner at the origin fixed, the one at x = 12 held on y and z, the one at y = 12 on z.
Scene DeaSheet() {
  Scene s;
  s.name = "dea_sheet";
  s.mesh = test::PrismSlab(6, 6, 1, 2.0, [](int, int, int) { return 1; });
  s.actuators = {Dea("skin", {1})};
  auto at = [&s](double x, double y) {
    for (int v = 0; v < s.mesh.num_vertices(); ++v)
      if ((s.mesh.vertices.row(v) - Eigen::RowVector3d(x, y, 0.0)).norm() < 1e-9) return v;
    ADD_FAILURE() << "no vertex at (" << x << ", " << y << ", 0)";
    return 0;
  };
  s.fixed = {at(0, 0)};
  s.fixed_axis[1] = {at(12, 0)};
  s.fixed_axis[2] = {std::min(at(12, 0), at(0, 12)), std::max(at(12, 0), at(0, 12))};
  std::vector<int> all(s.mesh.num_vertices());
  for (int i = 0; i < s.mesh.num_vertices(); ++i) all[i] = i;
  s.markers = {{"all", all}};
  s.validate();
  return s;
}

FkOptions Tight() {
  FkOptions o;
  o.tolerance = 1e-9;
  o.gradient_tolerance = 1e-9;
  o.max_iterations = 20000;
  o.threads = 1;
  return o;
}

TEST(Actuation, DeaTargetScalesTrianglesAndThickness) {
  const Scene s = DeaSheet();
  const Model m(s);
  const ModelElement& e = m.elements()[0];
  ASSERT_EQ(e.role, ElementRole::Dea);
  EXPECT_NEAR(std::abs(e.axis.z()), 1.0, 1e-12);  // the sheet's normal
  for (double lambda : {0.6, 1.0, 1.7}) {
    ElemRows T;
    ElementTarget(e, e.rest, lambda, &T);
    const double a0 = TriangleArea(e.rest.row(0), e.rest.row(1), e.rest.row(2));
    EXPECT_NEAR(TriangleArea(T.row(0), T.row(1), T.row(2)), lambda * a0, 1e-12 * a0);
    EXPECT_NEAR(TriangleArea(T.row(3), T.row(4), T.row(5)), lambda * a0, 1e-12 * a0);
    const double t0 = (e.rest.row(3) - e.rest.row(0)).dot(e.axis.transpose());
    const double t = (T.row(3) - T.row(0)).dot(e.axis.transpose());
    EXPECT_NEAR(t, t0 / lambda, 1e-12 * std::abs(t0));
    EXPECT_NEAR(RowsVolume(T, 6), e.rest_volume, 1e-12 * e.rest_volume);  // volume kept
  }
}

TEST(Actuation, CableTargetShrinksAlongTheCableOnly) {
  const Scene s = CableBar(0);
  const Model m(s);
  std::mt19937 rng(3);
  for (int i : {0, 17, 100}) {
    const ModelElement& e = m.elements()[i];
    ASSERT_EQ(e.role, ElementRole::Cable);
    EXPECT_NEAR(e.axis.x(), 1.0, 1e-12);
    const double sr = 0.65;
    // The current shape is the reshaped rest shape rotated: the target must be exactly it.
    const Eigen::Matrix3d Q = test::RandomRotation(rng);
    ElemRows D = ElemRows::Zero();
    D.topRows(4) = e.rest.topRows(4) * ActuationShape(e, sr).transpose() * Q.transpose();
    ElemRows T;
    ElementTarget(e, D, sr, &T);
    EXPECT_TRUE(MatrixNear(T, D, 1e-12));
    // Extent along the cable scales by s, across it by 1.
    const Eigen::MatrixXd S = e.rest.topRows(4) * ActuationShape(e, sr).transpose();
    for (int j = 0; j < 4; ++j) {
      EXPECT_NEAR(S(j, 0), sr * e.rest(j, 0), 1e-12);
      EXPECT_NEAR(S(j, 1), e.rest(j, 1), 1e-12);
      EXPECT_NEAR(S(j, 2), e.rest(j, 2), 1e-12);
    }
  }
}

TEST(Actuation, CableLengthSharesAndRigidPart) {
  // Whole bar actuated: the cable lies inside for its full 10 mm, L_R = 0.
  const Model all(CableBar(0));
  EXPECT_NEAR(all.actuator_rest_measure(0), 10.0, 0.01);
  EXPECT_NEAR(all.actuator_offset(0), 0.0, 0.01);
  // First 4 cells rigid body: 6 mm inside the cable's elements, L_R = 4 mm.
  const Model half(CableBar(4));
  EXPECT_NEAR(half.actuator_rest_measure(0), 6.0, 0.01);
  EXPECT_NEAR(half.actuator_offset(0), 4.0, 0.01);
  // A path that misses the cable's elements is an error.
  Scene bad = CableBar(4);
  bad.actuators[0].path = {{0, 1, 1}, {3, 1, 1}};
  EXPECT_THROW(Model{bad}, std::invalid_argument);
}

TEST(Actuation, MeasureGradientsMatchFiniteDifferences) {
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> u(-0.15, 0.15);
  const Model cable(CableBar(0));
  const Model dea(DeaSheet());
  for (const Model* m : {&cable, &dea}) {
    for (int i : {0, 5, 31}) {
      const ModelElement& e = m->elements()[i];
      ElemRows D = e.rest;
      for (int j = 0; j < e.k; ++j)
        for (int c = 0; c < 3; ++c) D(j, c) += u(rng);
      const ElemRows G = ActuationMeasureGradient(e, D);
      const double h = 1e-6;
      for (int j = 0; j < e.k; ++j)
        for (int c = 0; c < 3; ++c) {
          ElemRows Dp = D, Dm = D;
          Dp(j, c) += h;
          Dm(j, c) -= h;
          const double fd = (ActuationMeasure(e, Dp) - ActuationMeasure(e, Dm)) / (2 * h);
          EXPECT_NEAR(G(j, c), fd, 1e-7 * (1.0 + std::abs(fd))) << "element " << i;
        }
    }
  }
}

/// Relative error of EnergyAndGradient against central differences at a random configuration.
double GradientError(const Scene& s, const Eigen::VectorXd& c, unsigned seed) {
  const Model m(s);
  std::mt19937 rng(seed);
  std::normal_distribution<double> n(0.0, 0.05);
  Eigen::MatrixX3d X = m.rest_positions();
  for (int v = 0; v < X.rows(); ++v)
    for (int k = 0; k < 3; ++k) X(v, k) += n(rng);
  Eigen::MatrixX3d G;
  EnergyAndGradient(m, X, c, &G);
  double worst = 0;
  const double h = 1e-6;
  for (int v = 0; v < X.rows(); v += 7)
    for (int k = 0; k < 3; ++k) {
      Eigen::MatrixX3d Xp = X, Xm = X;
      Xp(v, k) += h;
      Xm(v, k) -= h;
      const double fd = (Energy(m, Xp, c) - Energy(m, Xm, c)) / (2 * h);
      worst = std::max(worst, std::abs(fd - G(v, k)) / (1e-3 + std::abs(fd) + std::abs(G(v, k))));
    }
  return worst;
}

TEST(Actuation, EnergyGradientMatchesFiniteDifferences) {
  Eigen::VectorXd c(1);
  c << 0.7;
  const double ec = GradientError(CableBar(4), c, 1);
  c << 1.4;
  const double ed = GradientError(DeaSheet(), c, 2);
  std::printf("  worst relative gradient error: cable %.2e, dea %.2e\n", ec, ed);
  EXPECT_LT(ec, 1e-5);
  EXPECT_LT(ed, 1e-5);
}

TEST(Actuation, ZeroEnergyAtRestAndRigidInvariance) {
  std::mt19937 rng(5);
  for (const Scene& s : {CableBar(4), DeaSheet()}) {
    const Model m(s);
    const Eigen::VectorXd rest = s.rest_actuation();
    EXPECT_NEAR(Energy(m, m.rest_positions(), rest), 0.0, 1e-20);
    Eigen::VectorXd c = rest;
    c[0] = s.actuators[0].type == ActuatorType::Cable ? 0.8 : 1.3;
    Eigen::MatrixX3d X = m.rest_positions();
    std::normal_distribution<double> n(0.0, 0.1);
    for (int v = 0; v < X.rows(); ++v)
      for (int k = 0; k < 3; ++k) X(v, k) += n(rng);
    const Eigen::Matrix3d R = test::RandomRotation(rng);
    const Eigen::RowVector3d t(3.0, -1.0, 2.0);
    const Eigen::MatrixX3d Y = (X * R.transpose()).rowwise() + t;
    const double e0 = Energy(m, X, c), e1 = Energy(m, Y, c);
    EXPECT_NEAR(e1, e0, 1e-10 * e0) << s.name;
  }
}

TEST(Actuation, FreeCableShortensToSL) {
  // Every element is a cable element and nothing resists: the bar shortens to s L exactly (up to
  // the solver's tolerance), and its cross-section keeps its size.
  const Scene s = CableBar(0);
  auto model = std::make_shared<const Model>(s);
  for (double sr : {0.9, 0.7, 0.55}) {
    Eigen::VectorXd c(1);
    c << sr;
    const FkResult r = MakeFkSolver(model, Tight())->Solve(c);
    ASSERT_EQ(r.status, FkStatus::Converged) << r.BriefReport();
    const Eigen::MatrixX3d P = s.marker_positions(r.positions);
    EXPECT_NEAR(P(0, 0), sr * 10.0, 1e-6) << "tip x";
    EXPECT_NEAR(r.volume_ratios[0], sr, 1e-9);
    const double width = r.positions.col(1).maxCoeff() - r.positions.col(1).minCoeff();
    EXPECT_NEAR(width, 2.0, 1e-6);
  }
}

TEST(Actuation, CableWithRigidPartKeepsTotalLength) {
  // 4 mm of rigid body, 6 mm of cable elements: s L = L_R + sum s_i l_i puts the tip at s * 10.
  // The achieved ratio is a soft constraint (weight 5 against the body's 1 at the interface);
  // bound: within 0.5 % of the length.
  const Scene s = CableBar(4);
  auto model = std::make_shared<const Model>(s);
  Eigen::VectorXd c(1);
  c << 0.8;
  const FkResult r = MakeFkSolver(model, Tight())->Solve(c);
  ASSERT_EQ(r.status, FkStatus::Converged) << r.BriefReport();
  const Eigen::MatrixX3d P = s.marker_positions(r.positions);
  std::printf("  tip x %.5f (target 8), achieved length ratio %.5f\n", P(0, 0), r.volume_ratios[0]);
  EXPECT_NEAR(P(0, 0), 8.0, 0.05);
  EXPECT_NEAR(r.volume_ratios[0], 0.8, 0.004);
}

TEST(Actuation, FreeDeaSheetReachesItsAreaRatio) {
  const Scene s = DeaSheet();
  auto model = std::make_shared<const Model>(s);
  for (double lambda : {1.5, 0.7}) {
    Eigen::VectorXd c(1);
    c << lambda;
    const FkResult r = MakeFkSolver(model, Tight())->Solve(c);
    ASSERT_EQ(r.status, FkStatus::Converged) << r.BriefReport();
    EXPECT_NEAR(r.volume_ratios[0], lambda, 1e-6);
    const double thick = r.positions.col(2).maxCoeff() - r.positions.col(2).minCoeff();
    const double span = r.positions.col(0).maxCoeff() - r.positions.col(0).minCoeff();
    EXPECT_NEAR(thick, 2.0 / lambda, 1e-5);
    EXPECT_NEAR(span, 12.0 * std::sqrt(lambda), 1e-5);
  }
}

}  // namespace
}  // namespace softkin

// ---- cable_finger (the embedded cable robot) ----
namespace softkin {
namespace {

TEST(RobotsCableFinger, ActuatorsMarkersAndRegions) {
  const Scene s = MakeRobot("cable_finger");
  ASSERT_EQ(s.num_actuators(), 3);
  for (int k = 0; k < 3; ++k) {
    const Actuator& a = s.actuators[k];
    EXPECT_EQ(a.name, "t" + std::to_string(k + 1));
    EXPECT_EQ(a.type, ActuatorType::Cable);
    EXPECT_EQ(a.regions, std::vector<int>{k + 1});
    EXPECT_EQ(a.min, 0.5);
    EXPECT_EQ(a.max, 1.0);
    ASSERT_EQ(a.path.size(), 2u);
    EXPECT_NEAR((a.path[1] - a.path[0]).normalized().x(), 1.0, 1e-12);
  }
  for (const char* m : {"tip", "tip_top", "tip_bottom"}) EXPECT_GE(s.marker_index(m), 0) << m;
  const Eigen::RowVector3d hi = s.mesh.vertices.colwise().maxCoeff();
  EXPECT_LT((hi - Eigen::RowVector3d(120, 25, 25)).norm(), 1e-9);
  // Each tendon's path lies in its own elements: L_R = 0 and sum l_i = the knuckle's length.
  const Model m(s);
  for (int k = 0; k < 3; ++k) {
    EXPECT_NEAR(m.actuator_offset(k), 0.0, 0.02);
    EXPECT_NEAR(m.actuator_rest_measure(k),
                (s.actuators[k].path[1] - s.actuators[k].path[0]).norm(), 0.02);
  }
}

TEST(RobotsCableFinger, ConvergesOverItsRangeAndCurlsUpInPlane) {
  // A 3 x 3 x 3 grid over [0.5, 1]^3 on a coarse mesh (res 8, 9.2k tets), warm-started along a
  // serpentine order. (An even res: the voxel split is then mirror-symmetric about the mid-plane
  // y = 12.5.) At res 6, 6 of the 27 points stall with the residual ratio at 1.2-2e-6, just above
  // the default 1e-6: see the issue notes.
  const Scene s = MakeRobot("cable_finger", 8);
  auto model = std::make_shared<const Model>(s);
  auto solver = MakeFkSolver(model, FkOptions{});
  const int tip = s.marker_index("tip");
  const Eigen::Vector3d tip0 = s.marker_positions(s.mesh.vertices).row(tip).transpose();
  const double v[3] = {1.0, 0.75, 0.5};
  int failed = 0, solves = 0;
  Eigen::MatrixX3d X = model->rest_positions();
  for (int i = 0; i < 3; ++i)
    for (int jj = 0; jj < 3; ++jj)
      for (int kk = 0; kk < 3; ++kk) {
        const int j = (i % 2) ? 2 - jj : jj;
        const int k = ((i * 3 + jj) % 2) ? 2 - kk : kk;
        Eigen::VectorXd c(3);
        c << v[i], v[j], v[k];
        const FkResult r = solver->Solve(c, &X);
        ++solves;
        if (r.status != FkStatus::Converged) {
          ++failed;
          ADD_FAILURE() << "actuation " << c.transpose() << ": " << r.BriefReport();
          continue;
        }
        X = r.positions;
        const Eigen::Vector3d p = s.marker_positions(X).row(tip).transpose();
        // Planar: the mesh is mirror-symmetric about y = 12.5; the bound is the stopping rule's
        // tolerance (1e-5 of the size per iteration), as Anderson's path is only symmetric up to
        // round-off.
        EXPECT_NEAR(p.y(), tip0.y(), 1e-5 * model->size()) << "planar motion";
        if (c.minCoeff() < 1.0) {
          EXPECT_GT(p.z(), tip0.z() + 1.0) << c.transpose();
        }
      }
  std::printf("  cable_finger res 8: %d of %d grid points failed\n", failed, solves);
  EXPECT_EQ(failed, 0);
}

TEST(RobotsCableFinger, EachTendonBendsItsKnuckle) {
  // Pulling a tendon closer to the tip moves the tip less (shorter lever) but must move it.
  const Scene s = MakeRobot("cable_finger", 8);
  const int tip = s.marker_index("tip");
  const Eigen::Vector3d tip0 = s.marker_positions(s.mesh.vertices).row(tip).transpose();
  double lift[3];
  for (int k = 0; k < 3; ++k) {
    Eigen::VectorXd c = s.rest_actuation();
    c[k] = 0.6;
    const FkResult r = SolveFk(s, c);
    ASSERT_EQ(r.status, FkStatus::Converged) << r.BriefReport();
    EXPECT_NEAR(r.volume_ratios[k], 0.6, 0.01);  // the tendon's length ratio (weight 5)
    lift[k] = s.marker_positions(r.positions)(tip, 2) - tip0.z();
    EXPECT_GT(lift[k], 1.0) << "tendon " << k + 1;
  }
  EXPECT_GT(lift[0], lift[1]);
  EXPECT_GT(lift[1], lift[2]);
}

}  // namespace
}  // namespace softkin
