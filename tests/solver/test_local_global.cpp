// Tests of the local-global FK solver (solver/local_global.hpp, Algorithm 1) and of the Anderson
// accelerator (solver/anderson.hpp). The checks are properties of the solution (rest shape,
// symmetry, direction of bending, warm/cold and scale invariance, agreement between solvers and
// with a tightly converged reference), not stored numbers.
#include "solver/anderson.hpp"
#include "solver/energy.hpp"
#include "solver/fk_solver.hpp"
#include "solver/local_global.hpp"
#include "solver/robots.hpp"

#include "tests/solver/test_util.hpp"

#include <Eigen/Eigenvalues>
#include <gtest/gtest.h>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <memory>
#include <random>
#include <string>

namespace softkin {
namespace {

using test::MatrixNear;

struct Solved {
  FkResult r;
  Eigen::MatrixX3d markers;
};

// Builds the model and a solver for `opts`, solves c (optionally warm-started).
Solved SolveScene(const Scene& s, const Eigen::VectorXd& c, const FkOptions& opts,
           const Eigen::MatrixX3d* warm = nullptr) {
  auto model = std::make_shared<const Model>(s);
  auto solver = MakeFkSolver(model, opts);
  Solved out;
  out.r = solver->Solve(c, warm);
  out.markers = s.marker_positions(out.r.positions);
  return out;
}

Eigen::VectorXd Vec(std::initializer_list<double> v) {
  Eigen::VectorXd x(v.size());
  int i = 0;
  for (double d : v) x[i++] = d;
  return x;
}

FkOptions Opts(const std::string& solver = "lg-aa") {
  FkOptions o;
  o.solver = solver;
  return o;
}

const Scene& ThreeChamber3() {
  static const Scene s = MakeRobot("three_chamber", 3);
  return s;
}

Eigen::Vector3d Tip(const Scene& s, const FkResult& r) {
  return s.marker_positions(r.positions).row(s.marker_index("tip")).transpose();
}

// ---------------------------------------------------------------------------------------------
// Local-global
// ---------------------------------------------------------------------------------------------

TEST(LocalGlobal, RestActuationReturnsRestShape) {
  const Scene mixed = test::VoxelScene(
      {6, 2, 2}, 1.0, [](const Eigen::Vector3i& c) { return c.z() == 1 && c.x() > 0 ? 2 : (c.x() == 5 ? 1 : 0); },
      {{0, Material{"a", 1.0, 1.0}}, {1, Material{"b", 0.3, 1.0}}}, {test::Pneumatic("p", {2})});
  for (const Scene* s : {&ThreeChamber3(), &mixed})
    for (const char* name : {"lg", "lg-aa"}) {
      const Solved out = SolveScene(*s, s->rest_actuation(), Opts(name));
      EXPECT_EQ(out.r.status, FkStatus::Converged) << s->name << " " << name << ": "
                                                   << out.r.BriefReport();
      EXPECT_LE(out.r.iterations, 2) << s->name << " " << name;
      EXPECT_TRUE(MatrixNear(out.r.positions, s->mesh.vertices, 1e-12 * s->mesh.size()))
          << s->name << " " << name;
      EXPECT_LE(out.r.energy, 1e-20 * std::pow(s->mesh.size(), 5)) << s->name;
      for (double v : out.r.volume_ratios) EXPECT_NEAR(v, 1.0, 1e-12);
    }
}

TEST(LocalGlobal, AchievedVolumeRatioIsSoftConstraint) {
  Scene s = ThreeChamber3();
  const Eigen::VectorXd c = Vec({1.5, 1.0, 1.0});
  const Solved w5 = SolveScene(s, c, Opts());
  ASSERT_EQ(w5.r.status, FkStatus::Converged) << w5.r.BriefReport();
  const double v5 = w5.r.volume_ratios[0];
  EXPECT_GT(v5, 1.3);
  EXPECT_LE(v5, 1.5);
  for (auto& a : s.actuators) a.weight = 50.0;
  const Solved w50 = SolveScene(s, c, Opts());
  ASSERT_EQ(w50.r.status, FkStatus::Converged) << w50.r.BriefReport();
  const double v50 = w50.r.volume_ratios[0];
  EXPECT_LE(v50, 1.5);
  EXPECT_LT(std::abs(v50 - 1.5), std::abs(v5 - 1.5));
  std::printf("  c1 = 1.5: achieved %.5f (weight 5, %d it), %.5f (weight 50, %d it); "
              "c2, c3 achieved %.5f, %.5f\n",
              v5, w5.r.iterations, v50, w50.r.iterations, w5.r.volume_ratios[1],
              w5.r.volume_ratios[2]);
}

TEST(LocalGlobal, EqualInflationKeepsTipOnAxis) {
  for (int res : {3, 4}) {
    const Scene s = MakeRobot("three_chamber", res);
    const Solved out = SolveScene(s, Vec({1.4, 1.4, 1.4}), Opts());
    ASSERT_EQ(out.r.status, FkStatus::Converged) << out.r.BriefReport();
    const Eigen::Vector3d tip = Tip(s, out.r);
    const Eigen::Vector3d tip0 = s.marker_positions(s.mesh.vertices).row(0).transpose();
    const double size = s.mesh.size();
    std::printf("  res %d: tip (%.3g, %.6f, %.3g), rest y %.3f, %d iterations\n", res, tip.x(),
                tip.y(), tip.z(), tip0.y(), out.r.iterations);
    EXPECT_LT(std::abs(tip.x()), 1e-6 * size);
    EXPECT_LT(std::abs(tip.z()), 1e-6 * size);
    EXPECT_GT(tip.y() - tip0.y(), 0.5);  // elongation along +y, mm
  }
}

TEST(LocalGlobal, SingleChamberBendsTipAway) {
  const Scene& s = ThreeChamber3();
  const double pi = std::acos(-1.0);
  const Eigen::Vector3d tip0 = s.marker_positions(s.mesh.vertices).row(0).transpose();
  Eigen::Vector2d d[3];
  for (int k = 0; k < 3; ++k) {
    Eigen::VectorXd c = s.rest_actuation();
    c[k] = 1.6;
    const Solved out = SolveScene(s, c, Opts());
    ASSERT_EQ(out.r.status, FkStatus::Converged) << out.r.BriefReport();
    const Eigen::Vector3d tip = Tip(s, out.r);
    d[k] = Eigen::Vector2d(tip.x() - tip0.x(), tip.z() - tip0.z());
    const double phi = (180.0 + 120.0 * k) * pi / 180.0;  // chamber position in the x-z plane
    const Eigen::Vector2d u(std::cos(phi), std::sin(phi));
    std::printf("  c%d: tip moves (%.4f, %.4f) in x-z (|d| = %.3f mm), cos to chamber %.6f\n",
                k + 1, d[k].x(), d[k].y(), d[k].norm(), d[k].dot(u) / d[k].norm());
    EXPECT_GT(d[k].norm(), 1.0);
    EXPECT_LT(d[k].dot(u), -0.99 * d[k].norm()) << "tip must move away from chamber " << k + 1;
  }
  // Exact 3-fold symmetry of the mesh: the three bends are 120-degree rotations of each other.
  const Eigen::Matrix2d R120 = Eigen::Rotation2Dd(2.0 * pi / 3.0).toRotationMatrix();
  EXPECT_TRUE(MatrixNear(d[1], R120 * d[0], 1e-8 * s.mesh.size()));
  EXPECT_TRUE(MatrixNear(d[2], R120 * d[1], 1e-8 * s.mesh.size()));
}

TEST(LocalGlobal, WarmStartEqualsColdStart) {
  const Scene& s = ThreeChamber3();
  const FkOptions o = Opts();
  auto model = std::make_shared<const Model>(s);
  auto solver = MakeFkSolver(model, o);
  const Eigen::VectorXd c = Vec({1.5, 1.2, 1.0});
  const FkResult cold = solver->Solve(c);
  ASSERT_EQ(cold.status, FkStatus::Converged) << cold.BriefReport();
  const FkResult again = solver->Solve(c, &cold.positions);
  const FkResult nearby = solver->Solve(Vec({1.45, 1.25, 1.05}));
  ASSERT_EQ(nearby.status, FkStatus::Converged);
  const FkResult from_near = solver->Solve(c, &nearby.positions);
  const double tol = 10.0 * o.tolerance * model->size();
  const Eigen::MatrixX3d mc = s.marker_positions(cold.positions);
  for (const FkResult* w : {&again, &from_near}) {
    EXPECT_EQ(w->status, FkStatus::Converged) << w->BriefReport();
    EXPECT_TRUE(MatrixNear(s.marker_positions(w->positions), mc, tol));
  }
  std::printf("  cold %d it, warm(self) %d it, warm(nearby) %d it; |diff| %.3g / %.3g mm "
              "(bound %.3g)\n",
              cold.iterations, again.iterations, from_near.iterations,
              (s.marker_positions(again.positions) - mc).cwiseAbs().maxCoeff(),
              (s.marker_positions(from_near.positions) - mc).cwiseAbs().maxCoeff(), tol);
  EXPECT_LE(again.iterations, 3);  // starting at the solution
  EXPECT_LT(from_near.iterations, cold.iterations);
}

TEST(LocalGlobal, ScaleInvariance) {
  const Scene& s = ThreeChamber3();
  const Eigen::VectorXd c = Vec({1.6, 1.0, 1.2});
  const Solved base = SolveScene(s, c, Opts());
  ASSERT_EQ(base.r.status, FkStatus::Converged);
  const double size = s.mesh.size();
  for (double k : {1e3, 1e-3}) {
    Scene sk = s;
    sk.mesh.vertices *= k;
    const Solved out = SolveScene(sk, c, Opts());
    EXPECT_EQ(out.r.status, FkStatus::Converged) << "scale " << k << ": " << out.r.BriefReport();
    const Eigen::MatrixX3d back = out.r.positions / k;
    EXPECT_TRUE(MatrixNear(back, base.r.positions, 1e-4 * size)) << "scale " << k;
    EXPECT_LE(std::abs(out.r.iterations - base.r.iterations), 0.1 * base.r.iterations + 0.5)
        << "scale " << k;
    std::printf("  scale %g: %d vs %d iterations, max |X/k - X| = %.3g mm\n", k,
                out.r.iterations, base.r.iterations,
                (back - base.r.positions).cwiseAbs().maxCoeff());
  }
}

TEST(LocalGlobal, PlainAndAndersonAgree) {
  const Scene& s = ThreeChamber3();
  const Eigen::VectorXd c = Vec({1.5, 1.0, 1.0});
  const auto t0 = std::chrono::steady_clock::now();
  const Solved lg = SolveScene(s, c, Opts("lg"));
  const auto t1 = std::chrono::steady_clock::now();
  const Solved aa = SolveScene(s, c, Opts("lg-aa"));
  const auto t2 = std::chrono::steady_clock::now();
  EXPECT_EQ(lg.r.status, FkStatus::Converged) << lg.r.BriefReport();
  EXPECT_EQ(aa.r.status, FkStatus::Converged) << aa.r.BriefReport();
  EXPECT_TRUE(MatrixNear(lg.markers, aa.markers, 1e-3 * s.mesh.size()));
  EXPECT_LT(aa.r.iterations, lg.r.iterations);
  std::printf("  lg: %d it (%.3f s), lg-aa: %d it (%.3f s, %d accepted, %d rejected); "
              "max marker diff %.3g mm\n",
              lg.r.iterations, std::chrono::duration<double>(t1 - t0).count(), aa.r.iterations,
              std::chrono::duration<double>(t2 - t1).count(), aa.r.aa_accepted, aa.r.aa_rejected,
              (lg.markers - aa.markers).cwiseAbs().maxCoeff());
}

TEST(LocalGlobal, StatusReporting) {
  const Scene& s = ThreeChamber3();
  auto model = std::make_shared<const Model>(s);
  FkOptions o = Opts();
  o.max_iterations = 2;
  auto capped = MakeFkSolver(model, o);
  const FkResult cap = capped->Solve(Vec({1.5, 1.0, 1.0}));
  EXPECT_EQ(cap.status, FkStatus::IterationCap) << cap.BriefReport();
  EXPECT_EQ(cap.iterations, 2);
  EXPECT_TRUE(cap.positions.allFinite());
  EXPECT_EQ(cap.positions.rows(), model->num_vertices());
  EXPECT_FALSE(cap.message.empty());

  auto solver = MakeFkSolver(model, Opts());
  const FkResult out = solver->Solve(Vec({1.0, 3.5, 1.0}));  // c2 above its max of 3
  EXPECT_EQ(out.status, FkStatus::InvalidInput);
  EXPECT_NE(out.message.find("c2"), std::string::npos) << out.message;
  const FkResult low = solver->Solve(Vec({1.0, 1.0, 0.5}));  // c3 below its min of 1
  EXPECT_EQ(low.status, FkStatus::InvalidInput);
  EXPECT_NE(low.message.find("c3"), std::string::npos) << low.message;
  const FkResult nan = solver->Solve(Vec({std::nan(""), 1.0, 1.0}));
  EXPECT_EQ(nan.status, FkStatus::InvalidInput);
  EXPECT_NE(nan.message.find("c1"), std::string::npos) << nan.message;
  const FkResult len = solver->Solve(Vec({1.2, 1.2}));
  EXPECT_EQ(len.status, FkStatus::InvalidInput) << len.message;
  EXPECT_FALSE(len.message.empty());
  Eigen::MatrixX3d bad = s.mesh.vertices;
  bad(bad.rows() - 1, 1) = std::nan("");
  const FkResult w = solver->Solve(Vec({1.2, 1.0, 1.0}), &bad);
  EXPECT_EQ(w.status, FkStatus::InvalidInput);
  EXPECT_NE(w.message.find("warm start"), std::string::npos) << w.message;
  const Eigen::MatrixX3d short_ws = s.mesh.vertices.topRows(10);
  EXPECT_EQ(solver->Solve(Vec({1.2, 1.0, 1.0}), &short_ws).status, FkStatus::InvalidInput);
  // Invalid input never leaves NaN positions behind.
  for (const FkResult* r : {&out, &low, &nan, &len, &w}) EXPECT_TRUE(r->positions.allFinite());
  // The solver is still usable afterwards.
  EXPECT_EQ(solver->Solve(Vec({1.2, 1.0, 1.0})).status, FkStatus::Converged);
}

TEST(LocalGlobal, ContinuationMatchesSingleStep) {
  const Scene& s = ThreeChamber3();
  const Eigen::VectorXd c = Vec({1.8, 1.0, 1.3});
  FkOptions o = Opts();
  const Solved one = SolveScene(s, c, o);
  o.continuation_steps = 4;
  const Solved four = SolveScene(s, c, o);
  ASSERT_EQ(one.r.status, FkStatus::Converged);
  ASSERT_EQ(four.r.status, FkStatus::Converged);
  const double tol = 10.0 * o.tolerance * s.mesh.size();
  EXPECT_TRUE(MatrixNear(four.markers, one.markers, tol));
  EXPECT_TRUE(MatrixNear(four.r.positions, one.r.positions, tol));
  std::printf("  1 step %d it, 4 steps %d it; max position diff %.3g mm (bound %.3g)\n",
              one.r.iterations, four.r.iterations,
              (four.r.positions - one.r.positions).cwiseAbs().maxCoeff(), tol);
}

// A long thin strip: bottom layer rigid body, top layer one pneumatic actuator, x = 0 end fixed.
// Bending-dominated, where plain local-global creeps and a vertex-move-only stopping rule stops
// far from the solution.
TEST(LocalGlobal, ThinStripCurvatureMatchesTightReference) {
  const Scene s = test::VoxelScene(
      {60, 6, 2}, 1.0, [](const Eigen::Vector3i& c) { return c.z() == 1 ? 1 : 0; },
      {{0, Material{"layer", 1.0, 1.0}}}, {test::Pneumatic("top", {1})}, "thin_strip");
  const Eigen::VectorXd c = Vec({1.3});
  const int a = NearestVertex(s.mesh, {0, 3, 1});
  const int b = NearestVertex(s.mesh, {30, 3, 1});
  const int e = NearestVertex(s.mesh, {60, 3, 1});
  auto curvature = [&](const Eigen::MatrixX3d& X) {
    return test::Curvature3(X.row(a).transpose(), X.row(b).transpose(), X.row(e).transpose());
  };
  auto timed = [&](const FkOptions& o, const char* what) {
    const auto t0 = std::chrono::steady_clock::now();
    const Solved out = SolveScene(s, c, o);
    const double dt =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    std::printf("  %-28s %-14s %6d it, residual ratio %.3g, curvature %.6f 1/mm, %.2f s\n", what,
                FkStatusToString(out.r.status), out.r.iterations, out.r.gradient_ratio,
                curvature(out.r.positions), dt);
    return out;
  };
  FkOptions ref_o = Opts("lg");
  ref_o.tolerance = 1e-12;
  ref_o.gradient_tolerance = 1e-12;
  ref_o.max_iterations = 20000;
  const Solved ref = timed(ref_o, "reference (lg, 1e-12)");
  const Solved def = timed(Opts(), "default (lg-aa)");
  FkOptions trap_o = Opts("lg");
  trap_o.gradient_tolerance = 1e9;
  const Solved trap = timed(trap_o, "move-only stop (lg, gtol 1e9)");
  FkOptions lgdef_o = Opts("lg");
  const Solved lgdef = timed(lgdef_o, "default (lg)");

  const double k_ref = curvature(ref.r.positions);
  const double k_def = curvature(def.r.positions);
  const double k_trap = curvature(trap.r.positions);
  EXPECT_GT(k_ref, 1e-3);  // it really bends
  EXPECT_EQ(def.r.status, FkStatus::Converged);
  EXPECT_NEAR(k_def, k_ref, 0.01 * k_ref) << "default options vs reference";
  EXPECT_GT(std::abs(k_trap - k_ref), std::abs(k_def - k_ref))
      << "the move-only stopping rule should stop further from the reference";
  std::printf("  curvature error vs reference: default %.3g %%, move-only %.3g %%, lg default "
              "%.3g %%\n",
              100 * std::abs(k_def - k_ref) / k_ref, 100 * std::abs(k_trap - k_ref) / k_ref,
              100 * std::abs(curvature(lgdef.r.positions) - k_ref) / k_ref);
}

// ---------------------------------------------------------------------------------------------
// Anderson
// ---------------------------------------------------------------------------------------------

struct LinearMap {
  Eigen::MatrixXd A;
  Eigen::VectorXd b, xstar;
};

// x <- A x + b in R^10 with A non-symmetric, spectral radius 0.9.
LinearMap MakeContraction(unsigned seed) {
  std::mt19937 rng(seed);
  const int n = 10;
  LinearMap L;
  Eigen::VectorXd lam(n);
  for (int i = 0; i < n; ++i) lam[i] = 0.9 * (i % 2 ? 1.0 : -1.0) * (1.0 - 0.08 * (i / 2));
  lam[0] = 0.9;
  Eigen::MatrixXd S = Eigen::MatrixXd::Identity(n, n) + 0.3 * test::RandomMatrix(rng, n, n);
  L.A = S * lam.asDiagonal() * S.inverse();
  L.b = test::RandomMatrix(rng, n, 1);
  L.xstar = (Eigen::MatrixXd::Identity(n, n) - L.A).lu().solve(L.b);
  return L;
}

int IterateToTolerance(const LinearMap& L, Anderson* aa, double tol, int cap) {
  Eigen::VectorXd x = Eigen::VectorXd::Zero(L.b.size());
  for (int k = 1; k <= cap; ++k) {
    const Eigen::VectorXd g = L.A * x + L.b;
    const Eigen::VectorXd f = g - x;
    x = aa ? aa->Compute(g, f) : g;
    if ((x - L.xstar).norm() < tol * L.xstar.norm()) return k;
  }
  return cap + 1;
}

TEST(Anderson, AcceleratesLinearContraction) {
  const LinearMap L = MakeContraction(5);
  Eigen::EigenSolver<Eigen::MatrixXd> es(L.A);
  const double rho = es.eigenvalues().cwiseAbs().maxCoeff();
  ASSERT_NEAR(rho, 0.9, 1e-9);
  const int plain = IterateToTolerance(L, nullptr, 1e-10, 5000);
  Anderson aa(10, 5);
  const int acc = IterateToTolerance(L, &aa, 1e-10, 5000);
  Anderson aa_full(10, 10);
  const int acc_full = IterateToTolerance(L, &aa_full, 1e-10, 5000);
  std::printf("  plain %d iterations, Anderson(m=5) %d, Anderson(m=10) %d\n", plain, acc,
              acc_full);
  EXPECT_GT(plain, 150);
  EXPECT_LT(acc, plain / 4);
  // With a window covering the whole space Anderson is GMRES-like: exact within ~n + 1 steps
  // (allow a few more for rounding).
  EXPECT_LE(acc_full, 16);
}

TEST(Anderson, FirstStepAndReset) {
  const LinearMap L = MakeContraction(6);
  Anderson aa(10, 4);
  EXPECT_EQ(aa.history(), 0);
  Eigen::VectorXd x = Eigen::VectorXd::Zero(10);
  Eigen::VectorXd g = L.A * x + L.b;
  Eigen::VectorXd out = aa.Compute(g, g - x);
  EXPECT_TRUE(MatrixNear(out, g, 0.0));  // the first call returns G(x) itself
  EXPECT_EQ(aa.history(), 0);
  for (int k = 0; k < 6; ++k) {
    x = out;
    g = L.A * x + L.b;
    out = aa.Compute(g, g - x);
  }
  EXPECT_EQ(aa.history(), 4);  // capped at the window
  EXPECT_FALSE(MatrixNear(out, g, 1e-12));  // an accelerated step differs from G(x)
  aa.Reset();
  EXPECT_EQ(aa.history(), 0);
  // After a reset the history is gone: the next call again returns G(x), and the following ones
  // match a fresh accelerator fed the same sequence.
  Anderson fresh(10, 4);
  x = out;
  g = L.A * x + L.b;
  const Eigen::VectorXd r1 = aa.Compute(g, g - x);
  const Eigen::VectorXd f1 = fresh.Compute(g, g - x);
  EXPECT_TRUE(MatrixNear(r1, g, 0.0));
  Eigen::VectorXd xa = r1, xf = f1;
  for (int k = 0; k < 5; ++k) {
    const Eigen::VectorXd ga = L.A * xa + L.b, gf = L.A * xf + L.b;
    xa = aa.Compute(ga, ga - xa);
    xf = fresh.Compute(gf, gf - xf);
    ASSERT_TRUE(MatrixNear(xa, xf, 0.0)) << "step " << k;
  }
}

}  // namespace
}  // namespace softkin
