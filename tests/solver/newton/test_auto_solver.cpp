/// \file test_auto_solver.cpp
/// The "auto" FK solver (solver/newton/auto_solver.hpp): lg-aa's answer where lg-aa converges
/// within its first 500 iterations or is near the tolerance then, newton's from the same start
/// where it is not, lg-aa again when newton runs over its time budget, the user's cap, scenes
/// with collision response, and bad limits.
#include "softkin/solver/factory/fk_factory.hpp"
#include "softkin/solver/fk/contact_term.hpp"
#include "softkin/solver/newton/auto_solver.hpp"
#include "softkin/solver/robots/robots.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <memory>
#include <string>

namespace softkin {
namespace {

FkOptions Options(const std::string& solver) {
  FkOptions o;
  o.solver = FkSolverTypeFromString(solver);
  o.threads = 1;
  return o;
}

double MaxDistance(const Eigen::MatrixX3d& a, const Eigen::MatrixX3d& b) {
  return (a - b).rowwise().norm().maxCoeff();
}

// Where lg-aa converges before the checkpoint, auto is lg-aa: the same state, iterations, no note.
TEST(AutoSolver, IsLgAaWhereLgAaConvergesBeforeTheCheckpoint) {
  auto model = std::make_shared<const Model>(MakeRobot("three_chamber", 3));
  const Eigen::Vector3d c(1.6, 1.0, 1.2);
  const FkResult lg = MakeFkSolver(model, Options("lg-aa"))->Solve(c);
  auto solver = MakeFkSolver(model, Options("auto"));
  EXPECT_EQ(solver->name(), "auto");
  const FkResult au = solver->Solve(c);
  ASSERT_EQ(lg.status, FkStatus::Converged) << lg.BriefReport();
  ASSERT_LT(lg.iterations, AutoSolver::Limits().lg_iterations);
  EXPECT_EQ(au.status, FkStatus::Converged) << au.BriefReport();
  EXPECT_EQ(au.solver, "auto");
  EXPECT_EQ(au.iterations, lg.iterations);
  EXPECT_EQ(au.message, "");
  EXPECT_EQ(MaxDistance(au.positions, lg.positions), 0.0);
  // A warm start too.
  const Eigen::Vector3d c2(1.7, 1.0, 1.2);
  const FkResult lg2 = MakeFkSolver(model, Options("lg-aa"))->Solve(c2, &lg.positions);
  const FkResult au2 = solver->Solve(c2, &au.positions);
  EXPECT_EQ(au2.iterations, lg2.iterations);
  EXPECT_EQ(MaxDistance(au2.positions, lg2.positions), 0.0);
}

// On the thin strip lg-aa needs about 4,000 iterations at alpha 1.1 (docs/newton.md): auto stops
// it at the checkpoint and returns newton's answer from the rest shape, and says so.
TEST(AutoSolver, SwitchesToNewtonWhereLgAaCrawls) {
  auto model = std::make_shared<const Model>(MakeRobot("bilayer_strip", 1));
  const Eigen::VectorXd c = Eigen::VectorXd::Constant(1, 1.1);
  const FkResult nw = MakeFkSolver(model, Options("newton"))->Solve(c);
  AutoSolver solver(model, Options("auto"));
  AutoSolver::Limits limits;
  limits.newton_time_factor = 1e6;  // no budget: the test must not depend on the machine's speed
  solver.set_limits(limits);
  const FkResult au = solver.Solve(c);
  ASSERT_EQ(nw.status, FkStatus::Converged) << nw.BriefReport();
  EXPECT_EQ(au.status, FkStatus::Converged) << au.BriefReport();
  EXPECT_NE(au.message.find("auto: lg-aa was at residual ratio "), std::string::npos) << au.message;
  EXPECT_NE(au.message.find("newton from the rest shape solved it"), std::string::npos)
      << au.message;
  // lg-aa's iterations up to the checkpoint (500, or the next checked iterate), then newton's.
  EXPECT_GE(au.iterations - nw.iterations, 500);
  EXPECT_LT(au.iterations - nw.iterations, 520);
  EXPECT_EQ(au.linear_iterations, nw.linear_iterations);
  EXPECT_LT(MaxDistance(au.positions, nw.positions), 1e-9 * model->size());
  EXPECT_LE(au.gradient_ratio, 1e-6);
}

// With continuation steps the checkpoint counts all of them, and a stop there ends the solve
// (not only its stage): auto then switches as without them.
TEST(AutoSolver, CheckpointStopsASolveWithContinuationSteps) {
  auto model = std::make_shared<const Model>(MakeRobot("bilayer_strip", 1));
  const Eigen::VectorXd c = Eigen::VectorXd::Constant(1, 1.1);
  FkOptions o = Options("auto");
  o.continuation_steps = 2;
  AutoSolver solver(model, o);
  AutoSolver::Limits limits;
  limits.newton_time_factor = 1e6;
  solver.set_limits(limits);
  const FkResult au = solver.Solve(c);
  EXPECT_EQ(au.status, FkStatus::Converged) << au.BriefReport();
  EXPECT_NE(au.message.find("newton from the rest shape solved it"), std::string::npos)
      << au.message;
  EXPECT_GT(au.linear_iterations, 0);
}

// lg-aa near the tolerance at the checkpoint goes on, and its iterates are lg-aa's own; far from
// it, newton takes over.
TEST(AutoSolver, LgAaNearTheToleranceAtTheCheckpointGoesOn) {
  auto model = std::make_shared<const Model>(MakeRobot("three_chamber", 3));
  const Eigen::Vector3d c(1.6, 1.0, 1.2);
  const FkResult lg = MakeFkSolver(model, Options("lg-aa"))->Solve(c);
  ASSERT_EQ(lg.status, FkStatus::Converged) << lg.BriefReport();
  ASSERT_GT(lg.iterations, 10);
  AutoSolver::Limits limits;
  limits.lg_iterations = lg.iterations - 3;  // the checkpoint 3 iterations before the end
  limits.near_factor = 1e12;                 // any ratio counts as near
  AutoSolver near(model, Options("auto"));
  near.set_limits(limits);
  const FkResult a = near.Solve(c);
  EXPECT_EQ(a.status, FkStatus::Converged) << a.BriefReport();
  EXPECT_EQ(a.message, "");
  EXPECT_EQ(a.iterations, lg.iterations);
  EXPECT_EQ(a.linear_iterations, 0);  // no Newton products
  EXPECT_EQ(MaxDistance(a.positions, lg.positions), 0.0);

  limits.near_factor = 1.0;  // never near: newton takes over
  limits.newton_time_factor = 1e6;
  AutoSolver far(model, Options("auto"));
  far.set_limits(limits);
  const FkResult b = far.Solve(c);
  EXPECT_EQ(b.status, FkStatus::Converged) << b.BriefReport();
  EXPECT_NE(b.message.find("solved it"), std::string::npos) << b.message;
  EXPECT_GT(b.linear_iterations, 0);
  EXPECT_LT(MaxDistance(b.positions, lg.positions), 1e-3 * model->size());
}

// newton gets a time budget (a multiple of lg-aa's time so far); past it lg-aa continues from
// where it stopped, and the message says so.
TEST(AutoSolver, NewtonOverItsBudgetHandsBackToLgAa) {
  auto model = std::make_shared<const Model>(MakeRobot("three_chamber", 3));
  const Eigen::Vector3d c(1.6, 1.0, 1.2);
  const FkResult lg = MakeFkSolver(model, Options("lg-aa"))->Solve(c);
  ASSERT_EQ(lg.status, FkStatus::Converged) << lg.BriefReport();
  AutoSolver::Limits limits;
  limits.lg_iterations = lg.iterations / 2;
  limits.near_factor = 1.0;
  limits.newton_time_factor = 1e-9;  // newton's time is up at once
  AutoSolver solver(model, Options("auto"));
  solver.set_limits(limits);
  const FkResult au = solver.Solve(c);
  EXPECT_EQ(au.status, FkStatus::Converged) << au.BriefReport();
  EXPECT_NE(au.message.find("had not converged after"), std::string::npos) << au.message;
  EXPECT_NE(au.message.find("continued with lg-aa from where it stopped"), std::string::npos)
      << au.message;
  EXPECT_GT(au.iterations, limits.lg_iterations);
  EXPECT_LT(MaxDistance(au.positions, lg.positions), 1e-3 * model->size());
}

// When the user's time limit runs out during newton, the answer is lg-aa's state at the
// checkpoint (newton's may belong to an intermediate load step).
TEST(AutoSolver, UsersTimeLimitDuringNewtonReturnsLgAasState) {
  auto model = std::make_shared<const Model>(MakeRobot("bilayer_strip", 1));
  const Eigen::VectorXd c = Eigen::VectorXd::Constant(1, 1.5);
  FkOptions o = Options("auto");
  o.time_limit_s = 0.3;  // newton needs about 15 iterations and 0.7 s here (docs/newton.md)
  AutoSolver solver(model, o);
  AutoSolver::Limits limits;
  limits.lg_iterations = 5;
  limits.near_factor = 1.0;
  limits.newton_time_factor = 1e6;
  solver.set_limits(limits);
  const FkResult au = solver.Solve(c);
  FkOptions capped = Options("lg-aa");
  capped.max_iterations = 5;
  const FkResult lg = MakeFkSolver(model, capped)->Solve(c);
  EXPECT_EQ(au.status, FkStatus::TimeLimit) << au.BriefReport();
  EXPECT_NE(au.message.find("when the time limit ran out"), std::string::npos) << au.message;
  EXPECT_NE(au.message.find("returned lg-aa's state"), std::string::npos) << au.message;
  EXPECT_EQ(MaxDistance(au.positions, lg.positions), 0.0);
  EXPECT_EQ(au.gradient_ratio, lg.gradient_ratio);
  EXPECT_GT(au.iterations, 5);  // lg-aa's and newton's
}

// A user's cap at or below the checkpoint is lg-aa's cap: no switch.
TEST(AutoSolver, UsersCapBelowTheCheckpointIsLgAasCap) {
  auto model = std::make_shared<const Model>(MakeRobot("bilayer_strip", 1));
  const Eigen::VectorXd c = Eigen::VectorXd::Constant(1, 1.1);
  FkOptions o = Options("auto");
  o.max_iterations = 200;
  const FkResult au = MakeFkSolver(model, o)->Solve(c);
  EXPECT_EQ(au.status, FkStatus::IterationCap) << au.BriefReport();
  EXPECT_EQ(au.iterations, 200);
  EXPECT_EQ(au.linear_iterations, 0);
  EXPECT_EQ(au.message.find("newton"), std::string::npos) << au.message;
}

// A scene with an active collision response switches only when solved from the rest shape;
// a warm-started solve is lg-aa's with its full cap.
TEST(AutoSolver, ContactScenesSwitchFromRestOnlyAndKeepTheQuasiStaticPath) {
  // selfcollision_finger res 5 at alpha 2.5: lg-aa's one call from rest ends 6 mm from the
  // quasi-static path (tip z -7.2 mm against -13.5), newton's load steps on it (docs/newton.md).
  const Scene s = MakeRobot("selfcollision_finger", 5);
  auto model = std::make_shared<const Model>(s);
  const Eigen::VectorXd c = Eigen::VectorXd::Constant(1, 2.5);
  FkOptions oa = Options("auto"), ol = Options("lg-aa"), on = Options("newton");
  oa.collision = ol.collision = on.collision = s.solver.collision;
  ASSERT_TRUE(ContactHandlingActive(s, oa.collision));
  const int tip = s.marker_index("tip");
  auto tip_z = [&](const FkResult& r) { return s.marker_positions(r.positions)(tip, 2); };

  // From rest lg-aa is far from the tolerance at its checkpoint, so auto solves with newton.
  auto built = MakeFkSolver(model, oa);  // the factory gives the solver its contact term
  auto* solver = dynamic_cast<AutoSolver*>(built.get());
  ASSERT_NE(solver, nullptr);
  const FkResult au = solver->Solve(c);
  ASSERT_EQ(au.status, FkStatus::Converged) << au.BriefReport();
  EXPECT_NE(au.message.find("newton from the rest shape solved it"), std::string::npos)
      << au.message;
  EXPECT_TRUE(au.collision.collision_free()) << au.BriefReport();
  const FkResult nw = MakeFkSolver(model, on)->Solve(c);
  ASSERT_EQ(nw.status, FkStatus::Converged) << nw.BriefReport();
  EXPECT_LT(MaxDistance(au.positions, nw.positions), 0.05);
  const FkResult lg = MakeFkSolver(model, ol)->Solve(c);
  ASSERT_EQ(lg.status, FkStatus::Converged) << lg.BriefReport();
  EXPECT_LT(tip_z(au), tip_z(lg) - 3.0) << "auto's tip is not past lg-aa's one-call tip";

  // A warm-started contact solve is lg-aa's however early the checkpoint: a sweep keeps one
  // solver's path.
  AutoSolver::Limits limits;
  limits.lg_iterations = 5;
  solver->set_limits(limits);
  const Eigen::VectorXd c2 = Eigen::VectorXd::Constant(1, 2.6);
  const FkResult aw = solver->Solve(c2, &au.positions);
  const FkResult lw = MakeFkSolver(model, ol)->Solve(c2, &au.positions);
  ASSERT_EQ(lw.status, FkStatus::Converged) << lw.BriefReport();
  ASSERT_GT(lw.iterations, 5);
  EXPECT_EQ(aw.status, FkStatus::Converged) << aw.BriefReport();
  EXPECT_EQ(aw.iterations, lw.iterations);
  EXPECT_EQ(aw.linear_iterations, 0);
  EXPECT_EQ(MaxDistance(aw.positions, lw.positions), 0.0);

  // From rest, when newton does not converge within its budget, lg-aa solves again from the rest
  // shape, whole: its checkpoint state may belong to an intermediate stage, without the springs.
  AutoSolver::Limits no_time;
  no_time.newton_time_factor = 1e-9;  // newton's time is up at once
  solver->set_limits(no_time);
  const FkResult ag = solver->Solve(c);
  EXPECT_NE(ag.message.find("solved again with lg-aa from the rest shape"), std::string::npos)
      << ag.message;
  EXPECT_EQ(ag.status, lg.status) << ag.BriefReport();
  EXPECT_GT(ag.iterations, lg.iterations);
  EXPECT_EQ(MaxDistance(ag.positions, lg.positions), 0.0);
}

TEST(AutoSolver, BadLimitsNameTheFieldAndTheRange) {
  auto model = std::make_shared<const Model>(MakeRobot("three_chamber", 3));
  AutoSolver solver(model, Options("auto"));
  auto error = [&](const AutoSolver::Limits& l) {
    try {
      solver.set_limits(l);
    } catch (const std::invalid_argument& e) {
      return std::string(e.what());
    }
    return std::string();
  };
  AutoSolver::Limits l;
  l.lg_iterations = 0;
  EXPECT_NE(error(l).find("lg_iterations must be an integer >= 1, got 0"), std::string::npos)
      << error(l);
  l = {};
  l.near_factor = std::nan("");
  EXPECT_NE(error(l).find("near_factor must be a number >= 1, got nan"), std::string::npos)
      << error(l);
  l = {};
  l.newton_time_factor = 0.0;
  EXPECT_NE(error(l).find("newton_time_factor must be a number > 0, got 0"), std::string::npos)
      << error(l);
  EXPECT_EQ(error({}), "");
  EXPECT_EQ(FkSolverTypeFromString("auto"), FkSolverType::kAuto);
}

}  // namespace
}  // namespace softkin
