/// \file test_newton_solver.cpp
/// The Newton-Krylov FK solver (solver/newton/newton_solver.hpp): its linearisation against
/// differences of the residual, the same equilibrium as lg-aa on every embedded robot, superlinear
/// convergence near the solution, and the lg-aa fallback.
#include "softkin/solver/factory/fk_factory.hpp"
#include "softkin/solver/fk/targets.hpp"
#include "softkin/solver/fk/vented_vertices.hpp"
#include "softkin/solver/newton/newton_solver.hpp"
#include "softkin/solver/robots/robots.hpp"
#include "softkin/solver/scene/scene_json.hpp"
#include "softkin/solver/sensitivity/free_operator.hpp"
#include "tests/solver/fk/fk_test_util.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <memory>
#include <random>
#include <string>
#include <vector>

namespace softkin {
namespace {

/// g(X) = A_ff x + A_fc x_c - B_f(X): the residual Newton drives to zero (free layout).
Eigen::VectorXd Residual(const Model& m, const Eigen::MatrixX3d& X, const Eigen::VectorXd& c) {
  Eigen::VectorXd g;
  m.GatherFree(m.A() * X - test::LocalGlobalRhs(m, X, c), &g);
  return g;
}

FkOptions Options(const std::string& solver, double tol, double gtol) {
  FkOptions o;
  o.solver = FkSolverTypeFromString(solver);
  o.threads = 1;
  o.tolerance = tol;
  o.gradient_tolerance = gtol;
  o.max_iterations = 200000;
  return o;
}

/// Mid-range actuation of every actuator (between its rest value and its maximum).
Eigen::VectorXd MidActuation(const Scene& s) {
  Eigen::VectorXd c = s.rest_actuation();
  for (int a = 0; a < s.num_actuators(); ++a) {
    const Actuator& act = s.actuators[a];
    const double hi = std::isfinite(act.max) ? act.max : act.rest + 1.0;
    c[a] = act.rest + (0.3 + 0.1 * a) * (hi - act.rest);
  }
  return c;
}

// The operator the solver applies, H = A_ff - K_ff, equals central differences of the residual
// along random directions at states away from the equilibrium.
TEST(NewtonSolver, JacobianOfTheResidualMatchesDifferences) {
  struct Case {
    std::string robot;
    int res;
    double value;
  };
  std::mt19937 rng(11);
  std::normal_distribution<double> nd;
  int checked = 0;
  // twisting_robot: a Mooney-Rivlin body (Eq. 3.6-3.7).
  for (const Case& k : std::vector<Case>{
           {"bilayer_strip", 1, 1.3}, {"three_chamber", 3, 1.6}, {"twisting_robot", 2, 1.8}}) {
    SCOPED_TRACE(k.robot);
    const Scene s = MakeRobot(k.robot, k.res);
    auto model = std::make_shared<const Model>(s);
    Eigen::VectorXd c = s.rest_actuation();
    c[0] = k.value;
    const FkResult r = MakeFkSolver(model, Options("lg-aa", 1e-3, 1e-2))->Solve(c);
    Eigen::MatrixX3d X = r.positions;
    for (int v = 0; v < X.rows(); ++v)
      for (int d = 0; d < 3; ++d) X(v, d) += 1e-3 * model->size() * nd(rng);
    model->ApplyConstraints(c, &X);
    EquilibriumLinearization lin;
    std::string why;
    ASSERT_TRUE(lin.Setup(*model, X, c, &why, 1)) << why;
    FreeOperator op(*model, &lin);
    for (int trial = 0; trial < 2; ++trial) {
      Eigen::VectorXd v(model->num_free_dofs());
      for (int i = 0; i < v.size(); ++i) v[i] = nd(rng);
      Eigen::MatrixX3d V = Eigen::MatrixX3d::Zero(X.rows(), 3);
      model->ScatterFree(v, &V);
      // Mooney-Rivlin: R_omega(eps) is piecewise linear (knots 0.01-0.03 of strain apart). A step
      // of 1e-6 of the size carries a few elements across a knot, and the error that adds falls
      // only in proportion to the step (2e-5, 5e-6 and 3e-9 at 1e-6, 1e-7 and 1e-8).
      const double step = k.robot == "twisting_robot" ? 1e-8 : 1e-6;
      const double h = step * model->size() / V.rowwise().norm().maxCoeff();
      const Eigen::VectorXd fd =
          (Residual(*model, X + h * V, c) - Residual(*model, X - h * V, c)) / (2.0 * h);
      const Eigen::VectorXd Hv = op.Apply(v).col(0);
      EXPECT_LT((Hv - fd).norm(), 1e-6 * fd.norm()) << "trial " << trial;
      ++checked;
    }
  }
  EXPECT_EQ(checked, 6);
}

// newton's answer is lg-aa's fixed point on every embedded robot at a small resolution: lg-aa
// started from it stays there, and lg-aa from rest ends within its own tolerance of it. (Scenes
// Newton does not cover are solved by lg-aa, and say so.)
TEST(NewtonSolver, SameStateAsLgAaOnEveryEmbeddedRobot) {
  int compared = 0, newton_solved = 0;
  for (const RobotInfo& info : ListRobots()) {
    SCOPED_TRACE(info.name);
    int res = info.default_resolution;
    // The smallest resolution each robot accepts (MakeRobot throws below it).
    for (int trial = 1; trial < info.default_resolution; ++trial) {
      try {
        MakeRobot(info.name, trial);
        res = trial;
        break;
      } catch (const std::invalid_argument&) {
      }
    }
    const Scene s = MakeRobot(info.name, res);
    if (s.mesh.num_elements() > 20000) continue;
    auto model = std::make_shared<const Model>(s);
    // With contacts the answer depends on the path (SelfContactFromRestEndsOnTheQuasiStaticPath).
    if (ContactHandlingActive(s, s.solver.collision)) continue;
    const Eigen::VectorXd c = MidActuation(s);
    const FkResult nw = MakeFkSolver(model, Options("newton", 1e-10, 1e-10))->Solve(c);
    ASSERT_EQ(nw.status, FkStatus::Converged) << nw.BriefReport();
    EXPECT_EQ(nw.solver, "newton");
    EXPECT_EQ(nw.message.find("lg-aa"), std::string::npos) << nw.message;
    ++newton_solved;
    // A fixed point of lg-aa: lg-aa started from it stops at its first test and hardly moves.
    // (newton is run 100 times tighter than lg-aa here: from a state that only just passes the
    // 1e-8 test, lg-aa crept 2.7 um along a soft mode of multi_segment_gripper in 55 iterations.)
    const FkResult again =
        MakeFkSolver(model, Options("lg-aa", 1e-8, 1e-8))->Solve(c, &nw.positions);
    EXPECT_LE(again.iterations, 2) << again.BriefReport();
    EXPECT_LT((again.positions - nw.positions).rowwise().norm().maxCoeff(), 1e-8 * model->size())
        << again.BriefReport();
    // lg-aa from rest, at its usual tolerance, ends near it (its error is its creep).
    const FkResult ref = MakeFkSolver(model, Options("lg-aa", 1e-6, 1e-7))->Solve(c);
    if (ref.status != FkStatus::Converged) continue;
    EXPECT_LT((ref.positions - nw.positions).rowwise().norm().maxCoeff(), 1e-3 * model->size())
        << nw.BriefReport() << " vs " << ref.BriefReport();
    ++compared;
  }
  EXPECT_GE(newton_solved, 7);
  EXPECT_GE(compared, 6);
}

// The unstructured Gmsh strip of issue #33 (scenes/bilayer_strip_gmsh.json, data/strip/): the
// scene reads as a clamped 100 x 10 x 4 mm bilayer whose top layer is the actuator, newton
// solves it in a few iterations to a fixed point of lg-aa (lg-aa needs about 4,100 iterations
// from rest at this actuation), and the strip curls towards -z.
TEST(NewtonSolver, GmshStripSceneIsAFixedPointOfLgAa) {
  const Scene s =
      LoadSceneJson(std::string(SOFTKIN_SOURCE_DIR) + "/scenes/bilayer_strip_gmsh.json");
  ASSERT_EQ(s.mesh.num_elements(), 12397);
  ASSERT_EQ(s.num_actuators(), 1);
  EXPECT_EQ(s.solver.solver, FkSolverType::kNewton);
  const Eigen::RowVector3d lo = s.mesh.vertices.colwise().minCoeff();
  const Eigen::RowVector3d hi = s.mesh.vertices.colwise().maxCoeff();
  EXPECT_LT((lo - Eigen::RowVector3d::Zero()).norm(), 1e-9);
  EXPECT_LT((hi - Eigen::RowVector3d(100, 10, 4)).norm(), 1e-9);
  // Top layer actuated, bottom layer body; the layers meet at z = 2.
  for (const auto& e : s.mesh.elements) {
    double z = 0.0;
    for (int k = 0; k < 4; ++k) z += 0.25 * s.mesh.vertices(e.v[k], 2);
    EXPECT_EQ(e.region, z > 2.0 ? 1 : 0);
  }
  ASSERT_GT(s.fixed.size(), 20u);
  for (int v : s.fixed) EXPECT_LT(std::abs(s.mesh.vertices(v, 0)), 1e-9);

  auto model = std::make_shared<const Model>(s);
  const Eigen::VectorXd c = Eigen::VectorXd::Constant(1, 1.1);
  const FkResult nw = MakeFkSolver(model, Options("newton", 1e-8, 1e-8))->Solve(c);
  ASSERT_EQ(nw.status, FkStatus::Converged) << nw.BriefReport();
  EXPECT_LE(nw.iterations, 12) << nw.BriefReport();
  EXPECT_EQ(nw.message.find("lg-aa"), std::string::npos) << nw.message;
  const FkResult again = MakeFkSolver(model, Options("lg-aa", 1e-6, 1e-6))->Solve(c, &nw.positions);
  EXPECT_LE(again.iterations, 2) << again.BriefReport();
  EXPECT_LT((again.positions - nw.positions).rowwise().norm().maxCoeff(), 1e-6 * model->size());
  const Eigen::MatrixX3d tip = s.marker_positions(nw.positions);
  EXPECT_LT(tip(s.marker_index("tip"), 2), -30.0);
}

// Near the solution each Newton iteration divides the residual by more than the one before.
TEST(NewtonSolver, ResidualFallsSuperlinearlyNearTheSolution) {
  const Scene s = MakeRobot("three_chamber", 3);
  auto model = std::make_shared<const Model>(s);
  NewtonSolver solver(model, Options("newton", 1e-10, 1e-11));
  Eigen::VectorXd c = s.rest_actuation();
  c[0] = 1.8;
  const FkResult r = solver.Solve(c);
  ASSERT_EQ(r.status, FkStatus::Converged) << r.BriefReport();
  const std::vector<double>& h = solver.residual_history();
  ASSERT_GE(h.size(), 4u);
  // Some three consecutive iterations with contraction factors below 0.3 that shrink.
  bool superlinear = false;
  for (size_t k = 0; k + 2 < h.size(); ++k) {
    const double q1 = h[k + 1] / h[k], q2 = h[k + 2] / h[k + 1];
    if (q1 < 0.3 && q2 < 0.5 * q1) superlinear = true;
  }
  std::string trace;
  for (double v : h) trace += std::to_string(v) + " ";
  EXPECT_TRUE(superlinear) << trace;
  EXPECT_LE(r.iterations, 12) << trace;
}

// From rest straight to the far end of the finger's range, newton reaches the state lg-aa reaches
// (with its few inverted elements: the walls between the chambers buckle at alpha 10), not a
// tangled equilibrium: the load step's tangent predictor, over the whole range, used to drive the
// walls through each other (426 inverted elements, 11 % more energy).
TEST(NewtonSolver, FarActuationFromRestReachesLgAasState) {
  const Scene s = MakeRobot("pneumatic_finger", 8);
  auto model = std::make_shared<const Model>(s);
  Eigen::VectorXd c(1);
  c << 10.0;
  FkOptions o = Options("newton", 1e-5, 1e-6);
  o.threads = 2;
  const FkResult nw = MakeFkSolver(model, o)->Solve(c);
  EXPECT_EQ(nw.message.find("lg-aa"), std::string::npos) << nw.message;
  o.solver = FkSolverType::kLgAa;
  const FkResult ref = MakeFkSolver(model, o)->Solve(c);
  // Both meet the tolerance at a state with inverted elements, and say so.
  EXPECT_EQ(ref.status, FkStatus::Inverted) << ref.BriefReport();
  EXPECT_EQ(nw.status, ref.status) << nw.BriefReport();
  EXPECT_EQ(nw.inverted_elements, ref.inverted_elements);
  EXPECT_NEAR(nw.energy, ref.energy, 1e-4 * ref.energy);
  EXPECT_LT((nw.positions - ref.positions).rowwise().norm().maxCoeff(), 1e-3 * model->size())
      << nw.BriefReport() << " vs " << ref.BriefReport();
  EXPECT_LE(nw.iterations, 15) << nw.BriefReport();
}

// A Newton solve that fails (here: at most one iteration per load step, and no step below a half)
// continues with lg-aa from its best state, says so, and converges to lg-aa's answer.
TEST(NewtonSolver, FailureContinuesWithLgAaAndSaysSo) {
  const Scene s = MakeRobot("bilayer_strip", 1);
  auto model = std::make_shared<const Model>(s);
  Eigen::VectorXd c(1);
  c << 1.1;
  NewtonSolver solver(model, Options("newton", 1e-5, 1e-6));
  solver.set_limits({1, 0.5});
  const FkResult r = solver.Solve(c);
  EXPECT_EQ(r.status, FkStatus::Converged) << r.BriefReport();
  EXPECT_NE(r.message.find("continued with lg-aa"), std::string::npos) << r.message;
  EXPECT_EQ(r.solver, "newton");
  EXPECT_GT(r.iterations, 100);  // the fallback's local-global iterations are counted
  const FkResult ref = MakeFkSolver(model, Options("lg-aa", 1e-5, 1e-6))->Solve(c);
  EXPECT_LT((r.positions - ref.positions).rowwise().norm().maxCoeff(), 1e-3 * model->size());
}

// The unloaded side of a signed chamber is vented: its targets are its current shape, so its
// inner vertices (there are some from res 8, where the cavities are two cells across) have no
// stiffness in H or in the projected Hessian P. P takes A's diagonal for them; before, its
// factorisation failed at the first step and the solve fell back to lg-aa.
TEST(NewtonSolver, VentedChamberSidesDoNotStopIt) {
  auto model = std::make_shared<const Model>(MakeRobot("finger_manipulator", 8));
  const Eigen::Vector3d c(0.5, 0.0, 0.0);
  FkOptions o = Options("newton", 1e-5, 1e-6);
  o.max_iterations = 10000;
  const FkResult nw = MakeFkSolver(model, o)->Solve(c);
  EXPECT_EQ(nw.status, FkStatus::Converged) << nw.BriefReport();
  EXPECT_EQ(nw.message, "");
  EXPECT_LT(nw.iterations, 20);
  const FkResult lg = MakeFkSolver(model, Options("lg-aa", 1e-5, 1e-6))->Solve(c);
  ASSERT_EQ(lg.status, FkStatus::Converged) << lg.BriefReport();
  // The same state on every vertex. The inner vertices of the vented sides feel no force, so
  // any position is an equilibrium for them: both solvers' answers put them at the same place
  // (vented_vertices.hpp), so that newton's, which does not move them, folds no chamber element.
  ASSERT_FALSE(VentedVertices(*model, c).empty());  // two cells across: there are some
  EXPECT_LT((nw.positions - lg.positions).rowwise().norm().maxCoeff(), 1e-3 * model->size());
  EXPECT_EQ(nw.inverted_actuation_elements, lg.inverted_actuation_elements);
}

// A Mooney-Rivlin body (Eq. 3.6-3.7) is Newton's too: the same equilibrium as lg-aa's, in a few
// iterations, and the residual falls superlinearly near it.
TEST(NewtonSolver, MooneyRivlinBodyReachesLgAasState) {
  Scene s = MakeRobot("three_chamber", 3);
  s.body[0].law = MaterialLaw::kMooneyRivlin;
  s.body[0].c1 = 0.0418;
  s.body[0].c2 = 0.0106;
  auto model = std::make_shared<const Model>(s);
  const Eigen::Vector3d c(1.8, 1.2, 1.0);
  const FkResult nw = MakeFkSolver(model, Options("newton", 1e-10, 1e-10))->Solve(c);
  ASSERT_EQ(nw.status, FkStatus::Converged) << nw.BriefReport();
  EXPECT_EQ(nw.solver, "newton");
  EXPECT_EQ(nw.message.find("lg-aa"), std::string::npos) << nw.message;
  EXPECT_LE(nw.iterations, 10) << nw.BriefReport();
  const FkResult again = MakeFkSolver(model, Options("lg-aa", 1e-8, 1e-8))->Solve(c, &nw.positions);
  EXPECT_LE(again.iterations, 2) << again.BriefReport();
  const FkResult lg = MakeFkSolver(model, Options("lg-aa", 1e-9, 1e-9))->Solve(c);
  ASSERT_EQ(lg.status, FkStatus::Converged) << lg.BriefReport();
  EXPECT_LT((lg.positions - nw.positions).rowwise().norm().maxCoeff(), 1e-5 * model->size())
      << nw.BriefReport() << " vs " << lg.BriefReport();
}

// A solver built without MakeFkSolver has no contact term: a scene with collision response is
// refused with a message that names the scene and the way out, not solved without contacts.
TEST(NewtonSolver, ContactSceneWithoutAContactTermIsRefusedByName) {
  const Scene s = MakeRobot("selfcollision_finger", 5);
  FkOptions o = Options("newton", 1e-5, 1e-6);
  o.collision = s.solver.collision;
  NewtonSolver solver(std::make_shared<const Model>(s), o);
  const FkResult r = solver.Solve(Eigen::VectorXd::Constant(1, 1.5));
  EXPECT_EQ(r.status, FkStatus::InvalidInput);
  EXPECT_NE(r.message.find("scene '" + s.name + "'"), std::string::npos) << r.message;
  EXPECT_NE(r.message.find("MakeFkSolver"), std::string::npos) << r.message;
}

// Self-contact from rest in one call (selfcollision_finger res 5, alpha 2.5). With springs that
// hold their targets between checks, the answer depends on the path the iteration takes to it:
// lg-aa in one stage ends 6.3 mm from where lg-aa in 16 small stages does (the quasi-static path,
// whose end moves by 0.01 mm between 16 and 64 stages; docs/newton.md). newton checks the
// contacts before every iteration and lets no trial point push a vertex deeper than a twentieth
// of an edge, so it finds the contacts where the quasi-static path does: its one call ends within
// 0.5 mm of the 16 stages (measured 0.04 mm), collision-free, nothing inverted, with springs in
// the final state, and with no hand-over to lg-aa.
TEST(NewtonSolver, SelfContactFromRestEndsOnTheQuasiStaticPath) {
  const Scene s = MakeRobot("selfcollision_finger", 5);
  ASSERT_TRUE(ContactHandlingActive(s, s.solver.collision));
  auto model = std::make_shared<const Model>(s);
  const Eigen::VectorXd c = Eigen::VectorXd::Constant(1, 2.5);
  FkOptions o = Options("newton", 1e-5, 1e-6);
  o.collision = s.solver.collision;
  const FkResult nw = MakeFkSolver(model, o)->Solve(c);
  ASSERT_EQ(nw.status, FkStatus::Converged) << nw.BriefReport();
  EXPECT_EQ(nw.message.find("lg-aa"), std::string::npos) << nw.message;
  EXPECT_LE(nw.iterations, 30);
  EXPECT_TRUE(nw.collision_active);
  EXPECT_GT(nw.springs, 0);
  EXPECT_TRUE(nw.collision.collision_free()) << nw.BriefReport();
  EXPECT_EQ(nw.collision.inverted_elements, 0);

  FkOptions q = Options("lg-aa", 1e-5, 1e-6);
  q.collision = s.solver.collision;
  q.continuation_steps = 16;
  const FkResult path = MakeFkSolver(model, q)->Solve(c);
  ASSERT_EQ(path.status, FkStatus::Converged) << path.BriefReport();
  const int tip = s.marker_index("tip");
  ASSERT_GE(tip, 0);
  const double gap =
      (s.marker_positions(nw.positions).row(tip) - s.marker_positions(path.positions).row(tip))
          .norm();
  EXPECT_LT(gap, 0.5) << nw.BriefReport() << " vs " << path.BriefReport();
}

// GMRES solves that stall with a fresh preconditioner hand the solve over to lg-aa, with the
// reason in the message: from the rest shape, so the iterations are lg-aa's own (compared after
// 300 of them). No embedded robot stalls GMRES within its range, so the test makes every solve
// count as stalled after one product (Limits::stall_products = 1, stall_residual = 0).
TEST(NewtonSolver, StalledKrylovSolvesHandOverToLgAa) {
  auto model = std::make_shared<const Model>(MakeRobot("bilayer_strip", 1));
  const Eigen::VectorXd c = Eigen::VectorXd::Constant(1, 1.1);
  FkOptions on = Options("newton", 1e-5, 1e-6), ol = Options("lg-aa", 1e-5, 1e-6);
  on.max_iterations = ol.max_iterations = 300;
  NewtonSolver solver(model, on);
  NewtonSolver::Limits limits;
  limits.stall_products = 1;
  limits.stall_residual = 0.0;
  solver.set_limits(limits);
  const FkResult nw = solver.Solve(c);
  const FkResult lg = MakeFkSolver(model, ol)->Solve(c);
  ASSERT_EQ(lg.status, FkStatus::IterationCap) << lg.BriefReport();
  EXPECT_EQ(nw.status, FkStatus::IterationCap) << nw.BriefReport();
  EXPECT_NE(nw.message.find("stalled 2 times"), std::string::npos) << nw.message;
  // The stall's reason counts inverted elements only where there are some.
  EXPECT_EQ(nw.message.find("elements are inverted"), std::string::npos) << nw.message;
  EXPECT_NE(nw.message.find("continued with lg-aa from the rest shape"), std::string::npos)
      << nw.message;
  EXPECT_GT(nw.linear_iterations, 0);
  EXPECT_LT((nw.positions - lg.positions).rowwise().norm().maxCoeff(), 1e-9 * model->size());
  EXPECT_NEAR(nw.energy, lg.energy, 1e-12 * lg.energy);
}

TEST(NewtonSolver, BadLimitsNameTheFieldAndTheRange) {
  auto model = std::make_shared<const Model>(MakeRobot("bilayer_strip", 1));
  NewtonSolver solver(model, Options("newton", 1e-5, 1e-6));
  auto error = [&](const NewtonSolver::Limits& l) {
    try {
      solver.set_limits(l);
    } catch (const std::invalid_argument& e) {
      return std::string(e.what());
    }
    return std::string();
  };
  NewtonSolver::Limits l;
  l.stall_products = 0;
  EXPECT_NE(error(l).find("stall_products must be an integer >= 1, got 0"), std::string::npos)
      << error(l);
  l = {};
  l.stall_residual = std::nan("");
  EXPECT_NE(error(l).find("stall_residual must be in [0, 1]"), std::string::npos) << error(l);
  l = {};
  l.min_load_step = 0.0;
  EXPECT_NE(error(l).find("min_load_step must be in (0, 1]"), std::string::npos) << error(l);
  l = {};
  l.step_iterations = -3;
  EXPECT_NE(error(l).find("step_iterations must be an integer >= 1, got -3"), std::string::npos)
      << error(l);
  EXPECT_EQ(error({}), "");  // the defaults are valid
}

TEST(NewtonSolver, UnknownSolverNameListsNewton) {
  std::string why;
  try {
    (void)FkSolverTypeFromString("newtn");
  } catch (const std::invalid_argument& e) {
    why = e.what();
  }
  EXPECT_NE(why.find("FK solver"), std::string::npos) << why;
  EXPECT_NE(why.find("newton"), std::string::npos) << why;
  EXPECT_NE(why.find("newtn"), std::string::npos) << why;
}

}  // namespace
}  // namespace softkin
