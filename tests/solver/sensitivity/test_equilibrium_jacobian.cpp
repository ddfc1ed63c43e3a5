// Tests of the implicit differentiation of the local-global equilibrium
// (solver/sensitivity/equilibrium_jacobian.hpp): the exact derivative of the global step's
// right-hand side against central differences on every supported element kind, dX/dc against
// differences of tightly converged forward solves, and the failure paths (unsupported law, GMRES
// budget).
#include "softkin/solver/sensitivity/equilibrium_jacobian.hpp"
#include "softkin/solver/factory/fk_factory.hpp"
#include "softkin/solver/fk/fk_solver.hpp"
#include "softkin/solver/robots/robots.hpp"
#include "softkin/solver/fk/targets.hpp"
#include "tests/solver/fk/fk_test_util.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <memory>
#include <random>
#include <string>

namespace softkin {
namespace {

Eigen::VectorXd Vec(std::initializer_list<double> v) {
  Eigen::VectorXd x(v.size());
  int i = 0;
  for (double d : v) x[i++] = d;
  return x;
}

using test::LocalGlobalRhs;

FkOptions Opts(double tol = 1e-6, double gtol = 1e-7) {
  FkOptions o;
  o.solver = FkSolverType::kLgAa;
  o.threads = 1;
  o.tolerance = tol;
  o.gradient_tolerance = gtol;
  return o;
}

struct Case {
  std::string robot;
  int res;
  RobotParams params;
  Eigen::VectorXd c;
  bool mooney_rivlin = false;  ///< make the first body region Ecoflex 00-30 (Eq. 3.6-3.7)
};

Scene CaseScene(const Case& k) {
  Scene s = MakeRobot(k.robot, k.res, k.params);
  if (k.mooney_rivlin) {
    Material& m = s.body.begin()->second;
    m.law = MaterialLaw::kMooneyRivlin;
    m.c1 = 0.0418;
    m.c2 = 0.0106;
  }
  return s;
}

// The linearised right-hand side equals central differences of B along random directions in
// positions and actuation, at a generic state near the equilibrium (every element kind: rigid and
// blended and hyperelastic bodies, pneumatic, vented, cable, DEA, motion actuators).
TEST(EquilibriumJacobian, RhsDerivativeMatchesCentralDifferences) {
  const std::vector<Case> cases = {
      {"three_chamber", 3, {}, Vec({2.0, 1.4, 1.1})},
      {"cable_finger", 5, {}, Vec({0.8, 0.9, 0.95})},
      {"dea_crawler", 4, {}, Vec({0.85})},
      {"finger_manipulator", 6, {{"body_r_omega", 0.6}}, Vec({1.5, -1.0, 0.5})},
      {"bimaterial_bar", 2, {{"r_omega_b", 0.4}}, Vec({30.0, 10.0})},
      {"finger_manipulator", 6, {{"body_r_omega", 1.0}}, Vec({1.5, -1.0, 0.5})},
      {"finger_manipulator", 6, {{"body_r_omega", 1.0}}, Vec({0.5, -0.2, 0.1})},
      {"three_chamber", 3, {}, Vec({2.0, 1.4, 1.1}), true},
      {"twisting_robot", 2, {}, Vec({2.0})},
  };
  std::mt19937 rng(7);
  std::normal_distribution<double> nd;
  int checked = 0;
  for (const Case& k : cases) {
    SCOPED_TRACE(k.robot);
    const Scene s = CaseScene(k);
    ASSERT_EQ(k.c.size(), s.num_actuators());
    auto model = std::make_shared<const Model>(s);
    auto solver = MakeFkSolver(model, Opts(1e-4, 1e-3));
    const FkResult r = solver->Solve(k.c);
    ASSERT_TRUE(r.positions.allFinite());
    // A generic nearby state (not exactly an equilibrium), prescribed coordinates kept.
    Eigen::MatrixX3d X = r.positions;
    for (int v = 0; v < X.rows(); ++v)
      for (int d = 0; d < 3; ++d) X(v, d) += 1e-3 * model->size() * 0.01 * nd(rng);
    model->ApplyConstraints(k.c, &X);
    EquilibriumLinearization lin;
    std::string why;
    ASSERT_TRUE(lin.Setup(*model, X, k.c, &why, 1)) << why;
    for (int trial = 0; trial < 2; ++trial) {
      Eigen::MatrixX3d dX(X.rows(), 3);
      for (int v = 0; v < X.rows(); ++v)
        for (int d = 0; d < 3; ++d) dX(v, d) = nd(rng);
      Eigen::VectorXd dc(k.c.size());
      for (int a = 0; a < dc.size(); ++a) dc[a] = trial == 0 ? 0.0 : nd(rng);
      Eigen::MatrixX3d dB;
      lin.ApplyRhsDerivative(dX, dc, &dB);
      // Mooney-Rivlin: R_omega(eps) is piecewise linear (knots 0.01-0.03 of strain apart). A step
      // of 1e-6 of the size carries a few elements across a knot, and the error that adds falls
      // only in proportion to the step (2e-5, 5e-6 and 3e-9 at 1e-6, 1e-7 and 1e-8).
      const bool curve = k.mooney_rivlin || k.robot == "twisting_robot";
      const double h =
          (curve ? 1e-8 : 1e-6) * model->size() / dX.norm() * std::sqrt(double(X.rows()));
      const Eigen::MatrixX3d fd = (LocalGlobalRhs(*model, X + h * dX, k.c + h * dc) -
                                   LocalGlobalRhs(*model, X - h * dX, k.c - h * dc)) /
                                  (2 * h);
      const double rel = (dB - fd).norm() / fd.norm();
      EXPECT_LT(rel, 1e-6) << "trial " << trial << ": |dB| " << dB.norm() << " |fd| " << fd.norm();
      EXPECT_GT(fd.norm(), 0.0);
      ++checked;
    }
  }
  EXPECT_EQ(checked, 18);
}

// dX/dc at a tightly converged equilibrium equals central differences of tightly converged forward
// solves over the whole mesh (pneumatic with a rigid or a hyperelastic body, and motion actuators
// with a blended body).
TEST(EquilibriumJacobian, MatchesDifferencesOfForwardSolves) {
  const std::vector<Case> cases = {
      {"three_chamber", 3, {}, Vec({1.8, 1.2, 1.1})},
      {"bimaterial_bar", 2, {{"r_omega_b", 0.5}}, Vec({20.0, 5.0})},
      {"three_chamber", 3, {}, Vec({1.8, 1.2, 1.1}), true},
  };
  for (const Case& k : cases) {
    SCOPED_TRACE(k.robot + (k.mooney_rivlin ? " (Mooney-Rivlin)" : ""));
    const Scene s = CaseScene(k);
    auto model = std::make_shared<const Model>(s);
    auto solver = MakeFkSolver(model, Opts(1e-11, 1e-11));
    const FkResult r = solver->Solve(k.c);
    ASSERT_EQ(r.status, FkStatus::Converged) << r.message;
    const EquilibriumJacobianResult jr = ComputeEquilibriumJacobian(*model, r.positions, k.c);
    ASSERT_TRUE(jr.ok) << jr.message;
    ASSERT_EQ(jr.dXdc.cols(), k.c.size());
    for (int a = 0; a < k.c.size(); ++a) {
      const Actuator& act = s.actuators[a];
      const double h = 1e-4 * (act.max - act.min);
      Eigen::VectorXd cp = k.c, cm = k.c;
      cp[a] += h;
      cm[a] -= h;
      const FkResult rp = solver->Solve(cp, &r.positions), rm = solver->Solve(cm, &r.positions);
      ASSERT_EQ(rp.status, FkStatus::Converged);
      ASSERT_EQ(rm.status, FkStatus::Converged);
      const Eigen::MatrixX3d d = (rp.positions - rm.positions) / (2 * h);
      Eigen::VectorXd fd(3 * d.rows());
      for (int v = 0; v < d.rows(); ++v)
        for (int q = 0; q < 3; ++q) fd[3 * v + q] = d(v, q);
      const double rel = (jr.dXdc.col(a) - fd).norm() / fd.norm();
      EXPECT_LT(rel, 1e-4) << act.name << ": " << jr.iterations[a] << " GMRES iterations";
      EXPECT_LT(jr.residuals[a], 1e-6);  // unpreconditioned; GMRES stops at 1e-8 preconditioned
      EXPECT_GT(fd.norm(), 0.0);
    }
  }
}

// The lockstep solve (one batched product per round for every column) computes the same Krylov
// iterates as the column-by-column solve, and the batched right-hand-side derivative equals the
// single-direction one block by block. BiCGSTAB reaches the same dX/dc to its tolerance.
TEST(EquilibriumJacobian, LockstepEqualsColumnByColumn) {
  const Scene s = MakeRobot("three_chamber", 3);
  auto model = std::make_shared<const Model>(s);
  const Eigen::VectorXd c = Vec({1.7, 1.3, 1.1});
  const FkResult r = MakeFkSolver(model, Opts(1e-8, 1e-9))->Solve(c);
  ASSERT_EQ(r.status, FkStatus::Converged) << r.message;
  EquilibriumJacobianOptions o;
  o.threads = 1;
  o.lockstep = true;
  const auto a = ComputeEquilibriumJacobian(*model, r.positions, c, {}, o);
  o.lockstep = false;
  const auto b = ComputeEquilibriumJacobian(*model, r.positions, c, {}, o);
  o.krylov = KrylovMethod::kBicgstab;
  const auto k = ComputeEquilibriumJacobian(*model, r.positions, c, {}, o);
  ASSERT_TRUE(a.ok) << a.message;
  ASSERT_TRUE(b.ok) << b.message;
  ASSERT_TRUE(k.ok) << k.message;
  EXPECT_LT((a.dXdc - b.dXdc).norm(), 1e-10 * b.dXdc.norm());
  EXPECT_EQ(a.iterations, b.iterations);
  int sum = 0, most = 0;
  for (int its : b.iterations) {
    sum += its;
    most = std::max(most, its);
  }
  EXPECT_EQ(b.rounds, sum);   // one product per round, column after column
  EXPECT_EQ(a.rounds, most);  // every column in each round until the slowest is done
  EXPECT_LT((k.dXdc - b.dXdc).norm(), 1e-5 * b.dXdc.norm());

  // Batched against single-direction derivatives of B, with a nonzero actuation direction.
  EquilibriumLinearization lin;
  std::string why;
  ASSERT_TRUE(lin.Setup(*model, r.positions, c, &why, 1)) << why;
  std::mt19937 rng(3);
  std::normal_distribution<double> nd;
  const int nv = model->num_vertices(), m = 3;
  Eigen::MatrixXd dX(nv, 3 * m), dc(3, m), dB;
  for (int i = 0; i < dX.size(); ++i) dX.data()[i] = nd(rng);
  for (int i = 0; i < dc.size(); ++i) dc.data()[i] = nd(rng);
  lin.ApplyRhsDerivativeBatch(dX, dc, &dB);
  for (int j = 0; j < m; ++j) {
    Eigen::MatrixX3d one;
    lin.ApplyRhsDerivative(dX.middleCols(3 * j, 3), dc.col(j), &one);
    EXPECT_LT((dB.middleCols(3 * j, 3) - one).norm(), 1e-12 * one.norm()) << "direction " << j;
  }
}

// Starting the Krylov solves from a nearby Jacobian (the previous waypoint's) gives the same dX/dc
// to the solver's tolerance with fewer products; the exact answer as the guess costs one product
// per column (the residual check) and is returned as it is.
TEST(EquilibriumJacobian, InitialGuessSavesProductsNotAccuracy) {
  const Scene s = MakeRobot("three_chamber", 3);
  auto model = std::make_shared<const Model>(s);
  auto solver = MakeFkSolver(model, Opts(1e-9, 1e-10));
  const Eigen::VectorXd c0 = Vec({1.6, 1.3, 1.1}), c1 = Vec({1.65, 1.32, 1.1});
  const FkResult r0 = solver->Solve(c0);
  const FkResult r1 = solver->Solve(c1, &r0.positions);
  ASSERT_EQ(r1.status, FkStatus::Converged);
  EquilibriumJacobianOptions o;
  o.threads = 1;
  const auto j0 = ComputeEquilibriumJacobian(*model, r0.positions, c0, {}, o);
  ASSERT_TRUE(j0.ok) << j0.message;
  const auto cold = ComputeEquilibriumJacobian(*model, r1.positions, c1, {}, o);
  const auto warm = ComputeEquilibriumJacobian(*model, r1.positions, c1, {}, o, &j0.dXdc);
  ASSERT_TRUE(cold.ok) << cold.message;
  ASSERT_TRUE(warm.ok) << warm.message;
  EXPECT_LT((warm.dXdc - cold.dXdc).norm(), 1e-6 * cold.dXdc.norm());
  int pc = 0, pw = 0;
  for (size_t j = 0; j < cold.iterations.size(); ++j) {
    pc += cold.iterations[j];
    pw += warm.iterations[j];
  }
  EXPECT_LT(pw, pc);
  const auto same = ComputeEquilibriumJacobian(*model, r1.positions, c1, {}, o, &cold.dXdc);
  ASSERT_TRUE(same.ok) << same.message;
  EXPECT_EQ(same.dXdc, cold.dXdc);
  for (int its : same.iterations) EXPECT_EQ(its, 1);
  // A guess of the wrong shape is ignored (the solve starts from 0).
  const Eigen::MatrixXd wrong = Eigen::MatrixXd::Ones(5, 3);
  const auto ignored = ComputeEquilibriumJacobian(*model, r1.positions, c1, {}, o, &wrong);
  ASSERT_TRUE(ignored.ok);
  EXPECT_EQ(ignored.iterations, cold.iterations);
}

// K_local (the per-element blocks of K) is K itself where no group couples elements: on the
// bimaterial bar (blended bodies, motion actuators, no actuation groups) K_local v equals the
// matrix-free derivative of B along v. On three_chamber the two differ only by the groups'
// rank-one terms, so along a direction that moves no chamber element they agree too. There the
// matrix-free product takes the closed form of rigid bodies and K_local the general one
// (ElementTargetDerivative), so this also checks the one against the other.
TEST(EquilibriumJacobian, LocalStiffnessIsKWithoutTheGroupCoupling) {
  std::mt19937 rng(11);
  std::normal_distribution<double> nd;
  for (const Case& k : {Case{"bimaterial_bar", 2, {{"r_omega_b", 0.4}}, Vec({30.0, 10.0})},
                        Case{"three_chamber", 3, {}, Vec({1.8, 1.2, 1.1})}}) {
    SCOPED_TRACE(k.robot);
    const Scene s = MakeRobot(k.robot, k.res, k.params);
    auto model = std::make_shared<const Model>(s);
    const FkResult r = MakeFkSolver(model, Opts(1e-6, 1e-7))->Solve(k.c);
    ASSERT_EQ(r.status, FkStatus::Converged) << r.message;
    EquilibriumLinearization lin;
    std::string why;
    ASSERT_TRUE(lin.Setup(*model, r.positions, k.c, &why, 1)) << why;
    const Eigen::SparseMatrix<double> K = lin.LocalStiffness();
    const int nv = model->num_vertices();
    ASSERT_EQ(K.rows(), 3 * nv);
    Eigen::MatrixX3d dX(nv, 3);
    for (int i = 0; i < dX.size(); ++i) dX.data()[i] = nd(rng);
    if (k.robot == "three_chamber") {  // keep every vertex of a chamber element still
      for (const ModelElement& e : model->elements())
        if (e.role != ElementRole::Body)
          for (int q = 0; q < e.k; ++q) dX.row(e.v[q]).setZero();
    }
    Eigen::MatrixX3d dB;
    lin.ApplyRhsDerivative(dX, Eigen::VectorXd::Zero(k.c.size()), &dB);
    Eigen::VectorXd v(3 * nv), Kv_ref(3 * nv);
    for (int i = 0; i < nv; ++i)
      for (int d = 0; d < 3; ++d) {
        v[3 * i + d] = dX(i, d);
        Kv_ref[3 * i + d] = dB(i, d);
      }
    const Eigen::VectorXd Kv = K * v;
    EXPECT_LT((Kv - Kv_ref).norm(), 1e-10 * Kv_ref.norm());
    EXPECT_GT(Kv_ref.norm(), 0.0);
  }
}

// The "local" preconditioner (A_ff - sym(K_local), factored) gives the same dX/dc as A_ff to the
// solver's tolerance in fewer products; with a workspace, a Jacobian at a nearby state reuses the
// factor (no new factorisation) and still agrees. On cable_finger A_ff - sym(K_local) is
// indefinite at a bent state; the per-element |eigenvalue| projection is used instead.
TEST(EquilibriumJacobian, LocalPreconditionerSameAnswerFewerProducts) {
  for (const Case& k : {Case{"three_chamber", 3, {}, Vec({1.8, 1.2, 1.1})},
                        Case{"cable_finger", 5, {}, Vec({0.8, 0.7, 0.8})}}) {
    SCOPED_TRACE(k.robot);
    const Scene s = MakeRobot(k.robot, k.res, k.params);
    auto model = std::make_shared<const Model>(s);
    auto solver = MakeFkSolver(model, Opts(1e-9, 1e-10));
    const FkResult r0 = solver->Solve(k.c);
    ASSERT_EQ(r0.status, FkStatus::Converged) << r0.message;
    EquilibriumJacobianOptions a, l;
    a.threads = l.threads = 1;
    a.preconditioner = JacobianPreconditioner::kAff;
    l.preconditioner = JacobianPreconditioner::kLocal;
    const auto ja = ComputeEquilibriumJacobian(*model, r0.positions, k.c, {}, a);
    EquilibriumJacobianWorkspace ws;
    const auto jl = ComputeEquilibriumJacobian(*model, r0.positions, k.c, {}, l, nullptr, &ws);
    ASSERT_TRUE(ja.ok) << ja.message;
    ASSERT_TRUE(jl.ok) << jl.message;
    EXPECT_EQ(ja.preconditioner, "A_ff");
    EXPECT_EQ(jl.preconditioner.rfind("local", 0), 0u) << jl.preconditioner;
    if (k.robot == "cable_finger") {
      EXPECT_EQ(jl.preconditioner, "local, projected");
    }
    EXPECT_LT((jl.dXdc - ja.dXdc).norm(), 1e-4 * ja.dXdc.norm());
    int pa = 0, pl = 0;
    for (size_t j = 0; j < ja.iterations.size(); ++j) {
      pa += ja.iterations[j];
      pl += jl.iterations[j];
    }
    EXPECT_LT(2 * pl, pa) << "A_ff " << pa << " products, local " << pl;
    const int factored = ws.factorizations();
    EXPECT_GE(factored, 1);
    // A nearby state: the factor is reused.
    Eigen::VectorXd c1 = k.c;
    c1[0] += 0.01 * (s.actuators[0].max - s.actuators[0].min);
    const FkResult r1 = solver->Solve(c1, &r0.positions);
    ASSERT_EQ(r1.status, FkStatus::Converged) << r1.message;
    const auto jr = ComputeEquilibriumJacobian(*model, r1.positions, c1, {}, l, nullptr, &ws);
    const auto jr_ref = ComputeEquilibriumJacobian(*model, r1.positions, c1, {}, a);
    ASSERT_TRUE(jr.ok) << jr.message;
    EXPECT_EQ(jr.preconditioner.rfind("local (reused)", 0), 0u) << jr.preconditioner;
    EXPECT_EQ(ws.factorizations(), factored);
    EXPECT_LT((jr.dXdc - jr_ref.dXdc).norm(), 1e-4 * jr_ref.dXdc.norm());
  }
  // Names are checked where they are read.
  try {
    (void)JacobianPreconditionerFromString("ilu");
    ADD_FAILURE() << "no exception for 'ilu'";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("'ilu'; expected one of: A_ff, local"), std::string::npos)
        << e.what();
  }
  EXPECT_EQ(JacobianPreconditionerFromString("local"), JacobianPreconditioner::kLocal);
  EXPECT_EQ(ToString(KrylovMethodFromString("bicgstab")), "bicgstab");
  EXPECT_THROW(KrylovMethodFromString("cg"), std::invalid_argument);
}

// The parts of the hyperelastic target's derivative that a state near an equilibrium seldom
// reaches: elements squashed below the blend-volume floor (kMinBlendVolume), where the blend
// weight t follows the floor instead of R_omega(eps), and strains beyond the curve's last knot.
TEST(EquilibriumJacobian, HyperelasticDerivativeOnTheVolumeFloorMatchesDifferences) {
  const Case k{"three_chamber", 3, {}, Vec({1.0, 1.0, 1.0}), true};
  const Scene s = CaseScene(k);
  const Model model(s);
  // Squash the body along z by 0.05 about its middle and shear it: every body element keeps its
  // orientation, its volume falls to 5 % (below the floor) and its strain is large.
  Eigen::MatrixX3d X = model.rest_positions();
  const double zmid = 0.5 * (X.col(2).minCoeff() + X.col(2).maxCoeff());
  for (int v = 0; v < X.rows(); ++v) {
    X(v, 2) = zmid + 0.05 * (X(v, 2) - zmid);
    X(v, 0) += 0.3 * X(v, 1);
  }
  std::mt19937 rng(11);
  std::normal_distribution<double> nd;
  for (int v = 0; v < X.rows(); ++v)
    for (int d = 0; d < 3; ++d) X(v, d) += 1e-3 * model.size() * 0.01 * nd(rng);
  int on_floor = 0;
  for (const ModelElement& e : model.elements()) {
    if (!e.curve) continue;
    ElemRows D;
    for (int j = 0; j < e.k; ++j) D.row(j) = X.row(e.v[j]);
    CenterRows(D, e.k);
    ElemRows T;
    ElementTarget(e, D, 1.0, &T);
    const double eps = EquivalentStrain(DeformationGradient(e, D));
    if (std::abs(RowsVolume(T, e.k) - e.rest_volume) < 1e-9 * e.rest_volume &&
        RowsVolume(D, e.k) < 0.1 * e.rest_volume)
      ++on_floor;
    EXPECT_GT(eps, 0.0);
  }
  EXPECT_GT(on_floor, 100);
  EquilibriumLinearization lin;
  std::string why;
  ASSERT_TRUE(lin.Setup(model, X, k.c, &why, 1)) << why;
  for (int trial = 0; trial < 2; ++trial) {
    Eigen::MatrixX3d dX(X.rows(), 3);
    for (int v = 0; v < X.rows(); ++v)
      for (int d = 0; d < 3; ++d) dX(v, d) = nd(rng);
    const Eigen::VectorXd dc = Eigen::VectorXd::Zero(k.c.size());
    Eigen::MatrixX3d dB;
    lin.ApplyRhsDerivative(dX, dc, &dB);
    const double h = 1e-7 * model.size() / dX.norm() * std::sqrt(double(X.rows()));
    const Eigen::MatrixX3d fd =
        (LocalGlobalRhs(model, X + h * dX, k.c) - LocalGlobalRhs(model, X - h * dX, k.c)) / (2 * h);
    EXPECT_LT((dB - fd).norm() / fd.norm(), 1e-6) << "trial " << trial;
  }
}

TEST(EquilibriumJacobian, GmresBudgetExhaustedFailsNamingTheActuator) {
  const Scene s = MakeRobot("three_chamber", 3);
  auto model = std::make_shared<const Model>(s);
  const Eigen::VectorXd c = Vec({2.0, 1.0, 1.0});
  const FkResult r = MakeFkSolver(model, Opts())->Solve(c);
  EquilibriumJacobianOptions o;
  o.max_iterations = 1;
  o.tolerance = 1e-14;
  const auto jr = ComputeEquilibriumJacobian(*model, r.positions, c, {0}, o);
  EXPECT_FALSE(jr.ok);
  EXPECT_NE(jr.message.find("'c1'"), std::string::npos) << jr.message;
  EXPECT_EQ(jr.dXdc.size(), 0);
  std::string why;
  o.restart = 0;
  EXPECT_FALSE(o.IsValid(&why));
  EXPECT_NE(why.find("restart"), std::string::npos);
}

}  // namespace
}  // namespace softkin
