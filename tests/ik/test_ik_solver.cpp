// SolveIk across methods: string converters, options validation, recovery of a known actuation to
// lambda from its own forward result (every method, both gradient sources, linear and PCC models),
// budgets, and failures reported rather than thrown.
#include "softkin/ik/ik_solver.hpp"
#include "softkin/ik/pcc_kinematics.hpp"

#include "ik_test_models.hpp"

#include <gtest/gtest.h>

namespace softkin {
namespace {

TEST(IkSolver, EnumStringsRoundTrip) {
  int n = 0;
  for (IkMethod m : AllIkMethods()) {
    IkMethod back = IkMethod::kGaussNewton;
    ASSERT_TRUE(StringToIkMethod(IkMethodToString(m), &back)) << IkMethodToString(m);
    EXPECT_EQ(back, m);
    ++n;
  }
  EXPECT_EQ(n, 8);
  IkMethod m = IkMethod::kNloptMma;
  EXPECT_FALSE(StringToIkMethod("bfgs", &m));
  EXPECT_EQ(m, IkMethod::kNloptMma);
  EXPECT_EQ(IkMethodNames(),
            "softls, nlopt-mma, nlopt-lbfgs, nlopt-slsqp, nlopt-ccsaq, nlopt-bobyqa, gauss-newton, "
            "broyden");
  for (IkTermination t :
       {IkTermination::kConverged, IkTermination::kNoProgress, IkTermination::kMaxIterations,
        IkTermination::kMaxEvaluations, IkTermination::kMaxTime, IkTermination::kKinematicsFailure,
        IkTermination::kObjectiveFailure, IkTermination::kSolverFailure}) {
    IkTermination back = IkTermination::kConverged;
    ASSERT_TRUE(StringToIkTermination(IkTerminationToString(t), &back));
    EXPECT_EQ(back, t);
  }
  IkGradient g = IkGradient::kJacobian;
  EXPECT_TRUE(StringToIkGradient("central-difference", &g));
  EXPECT_EQ(g, IkGradient::kCentralDifference);
  EXPECT_FALSE(StringToIkGradient("fd", &g));
}

TEST(IkSolver, OptionsValidationNamesTheField) {
  std::string why;
  EXPECT_TRUE(IkOptions().IsValid(&why)) << why;
  IkOptions o;
  o.tau = 1.0;
  EXPECT_FALSE(o.IsValid(&why));
  EXPECT_NE(why.find("tau"), std::string::npos);
  o = IkOptions();
  o.lambda = -1;
  EXPECT_FALSE(o.IsValid(&why));
  EXPECT_NE(why.find("lambda"), std::string::npos);
  o = IkOptions();
  o.max_iterations = 0;
  EXPECT_FALSE(o.IsValid(&why));
  EXPECT_NE(why.find("max_iterations"), std::string::npos);
  o = IkOptions();
  o.fd_step = std::nan("");
  EXPECT_FALSE(o.IsValid(&why));
  EXPECT_NE(why.find("fd_step"), std::string::npos);
}

TEST(IkSolver, BadInputsThrowInvalidArgument) {
  PccKinematics pcc;
  PointTrackingObjective o(pcc.point_names(), "tip", Eigen::Vector3d(0, 0, 90));
  EXPECT_THROW(SolveIk(pcc, o, Eigen::Vector3d(0, 0, 30), IkOptions()), std::invalid_argument);
  EXPECT_THROW(SolveIk(pcc, o, Eigen::Vector2d(0, 0), IkOptions()), std::invalid_argument);
  IkOptions bad;
  bad.max_time_s = 0;
  EXPECT_THROW(SolveIk(pcc, o, pcc.rest(), bad), std::invalid_argument);
  auto lin = test::LinearKinematics::Random(2, 1);
  EXPECT_THROW(SolveIk(lin, o, lin.rest(), IkOptions()), std::invalid_argument);
}

struct Case {
  IkMethod method;
  IkGradient gradient;
};

std::vector<Case> AllCases() {
  std::vector<Case> out;
  for (IkMethod m : AllIkMethods()) {
    out.push_back({m, IkGradient::kJacobian});
    if (m != IkMethod::kNloptBobyqa && m != IkMethod::kGaussNewton && m != IkMethod::kBroyden)
      out.push_back({m, IkGradient::kCentralDifference});
  }
  return out;
}

TEST(IkSolver, EveryMethodRecoversAKnownActuationOnTheLinearModel) {
  int solved = 0;
  for (const Case& cs : AllCases()) {
    auto lin = test::LinearKinematics::Random(3, 42);
    const Eigen::Vector3d c_true(2.5, 7.0, 4.0);
    const Eigen::Vector3d target = lin.Evaluate(c_true, false).p.row(0).transpose();
    PointTrackingObjective o(lin.point_names(), "tip", target);
    IkOptions opt;
    opt.method = cs.method;
    opt.gradient = cs.gradient;
    opt.max_iterations = 500;
    opt.max_evaluations = 5000;
    const IkResult r = SolveIk(lin, o, lin.rest(), opt);
    SCOPED_TRACE(r.summary.BriefReport());
    EXPECT_TRUE(r.summary.converged());
    EXPECT_LE(r.objective, opt.lambda);
    EXPECT_LE((r.p.row(0).transpose() - target).norm(), 0.2);
    EXPECT_LE(r.summary.evaluations, opt.max_evaluations);
    ++solved;
  }
  EXPECT_EQ(solved, 13);
}

TEST(IkSolver, EveryMethodRecoversKnownActuationsOnThePccModel) {
  int solved = 0;
  const std::vector<Eigen::Vector3d> truths = {Eigen::Vector3d(3, 12, 6), Eigen::Vector3d(15, 1, 8),
                                               Eigen::Vector3d(4, 4, 18)};
  for (const Case& cs : AllCases())
    for (const Eigen::Vector3d& c_true : truths) {
      PccKinematics pcc;
      const Eigen::Vector3d target = pcc.Evaluate(c_true, false).p.row(0).transpose();
      PointTrackingObjective o(pcc.point_names(), "tip", target);
      IkOptions opt;
      opt.method = cs.method;
      opt.gradient = cs.gradient;
      opt.max_iterations = 300;
      opt.max_evaluations = 5000;
      // From the middle of the box (what the trajectory's sampled guess gives on average).
      const IkResult r = SolveIk(pcc, o, Eigen::Vector3d(10, 10, 10), opt);
      SCOPED_TRACE(r.summary.BriefReport() + " for c = " + std::to_string(c_true[0]) + "," +
                   std::to_string(c_true[1]) + "," + std::to_string(c_true[2]));
      EXPECT_TRUE(r.summary.converged());
      EXPECT_LE((r.p.row(0).transpose() - target).norm(), 0.2);
      EXPECT_TRUE((r.c.array() >= 0).all() && (r.c.array() <= 20).all());
      ++solved;
    }
  EXPECT_EQ(solved, 39);
}

TEST(IkSolver, ShapeMatchingRecoversTheWholeShape) {
  // Sec. 4.2: the configuration-space objective pins down c itself (the shape is injective in c).
  for (IkMethod m : {IkMethod::kSoftLineSearch, IkMethod::kGaussNewton, IkMethod::kNloptSlsqp}) {
    PccKinematics pcc;
    const Eigen::Vector3d c_true(6, 14, 2);
    const Eigen::MatrixX3d shape = pcc.Evaluate(c_true, false).p.bottomRows(8);
    const ShapeMatchingObjective o =
        ShapeMatchingObjective::ForGroup(pcc.point_names(), "backbone", shape);
    IkOptions opt;
    opt.method = m;
    opt.lambda = 1e-8;
    opt.max_iterations = 500;
    opt.max_evaluations = 5000;
    const IkResult r = SolveIk(pcc, o, Eigen::Vector3d(10, 10, 10), opt);
    EXPECT_TRUE(r.summary.converged()) << r.summary.BriefReport();
    EXPECT_LT((r.c - c_true).norm(), 1e-2) << IkMethodToString(m) << ": " << r.c.transpose();
  }
}

TEST(IkSolver, BudgetsAreRespected) {
  for (IkMethod m : AllIkMethods()) {
    PccKinematics pcc;
    PointTrackingObjective o(pcc.point_names(), "tip", Eigen::Vector3d(-20, 30, 70));
    IkOptions opt;
    opt.method = m;
    opt.lambda = 0.0;
    opt.max_iterations = 1000;
    opt.max_evaluations = 7;
    opt.function_tolerance = 0;
    opt.parameter_tolerance = 0;
    const IkResult r = SolveIk(pcc, o, Eigen::Vector3d(10, 10, 10), opt);
    EXPECT_LE(r.summary.evaluations, 7) << IkMethodToString(m);
    EXPECT_FALSE(r.summary.converged());
    EXPECT_TRUE(r.c.allFinite());
  }
}

TEST(IkSolver, AFailingKinematicsStopsEveryMethodWithItsMessage) {
  for (IkMethod m : AllIkMethods()) {
    PccKinematics pcc;
    test::RecordingKinematics rec(pcc);
    int calls = 0;
    rec.fail_if = [&](const Eigen::VectorXd&) { return ++calls > 3; };  // after 3 good evaluations
    PointTrackingObjective o(rec.point_names(), "tip", Eigen::Vector3d(-20, 30, 70));
    IkOptions opt;
    opt.method = m;
    IkResult r;
    ASSERT_NO_THROW(r = SolveIk(rec, o, Eigen::Vector3d(10, 10, 10), opt)) << IkMethodToString(m);
    EXPECT_TRUE(r.c.allFinite());
    if (m == IkMethod::kSoftLineSearch || m == IkMethod::kGaussNewton || m == IkMethod::kBroyden) {
      // Failed trials count as no decrease; the solve ends one way or another, never above O(c0).
      EXPECT_LE(r.objective, r.summary.history.front());
      continue;
    }
    EXPECT_EQ(r.summary.termination, IkTermination::kKinematicsFailure) << r.summary.BriefReport();
    EXPECT_NE(r.summary.message.find("injected failure"), std::string::npos) << r.summary.message;
  }
}

// Gauss-Newton takes J only where it will step from: at c0 and at each accepted point it goes on
// from, never at the point where it stops (on the simulator a Jacobian costs about a forward
// solve). The evaluations are then one per iteration with J plus the trials.
TEST(IkSolver, GaussNewtonTakesNoJacobianWhereItStops) {
  PccKinematics pcc;
  for (const Eigen::Vector3d& c_true : {Eigen::Vector3d(5, 5, 9), Eigen::Vector3d(12, 3, 7)}) {
    PointTrackingObjective o(pcc.point_names(), "tip",
                             pcc.Evaluate(c_true, false).p.row(0).transpose());
    IkOptions opt;
    opt.method = IkMethod::kGaussNewton;
    const IkResult r = SolveIk(pcc, o, pcc.rest(), opt);
    ASSERT_TRUE(r.summary.converged()) << r.summary.BriefReport();
    ASSERT_GT(r.summary.iterations, 0);
    EXPECT_EQ(r.summary.jacobian_evaluations, r.summary.iterations);
    EXPECT_EQ(r.summary.history.size(), static_cast<size_t>(r.summary.iterations) + 1);
    EXPECT_LE(r.objective, opt.lambda);
    EXPECT_EQ(r.objective, r.summary.history.back());
  }
}

// broyden on a linear model: the secant update keeps an exact J exact (J dc = dp on every step),
// so with J handed over it never evaluates one, and it converges like gauss-newton.
TEST(IkSolver, BroydenWithAnExactJacobianEvaluatesNone) {
  auto lin = test::LinearKinematics::Random(3, 7);
  const Eigen::Vector3d c_true(2.5, 7.0, 4.0);
  const Eigen::Vector3d target = lin.Evaluate(c_true, false).p.row(0).transpose();
  PointTrackingObjective o(lin.point_names(), "tip", target);
  IkOptions opt;
  opt.method = IkMethod::kBroyden;
  opt.lambda = 1e-10;
  opt.initial_jacobian = lin.Evaluate(lin.rest(), true).J;
  const IkResult r = SolveIk(lin, o, lin.rest(), opt);
  ASSERT_TRUE(r.summary.converged()) << r.summary.BriefReport();
  EXPECT_EQ(r.summary.jacobian_evaluations, 0);
  EXPECT_EQ(r.summary.secant_updates, r.summary.iterations);
  EXPECT_GT(r.summary.iterations, 0);
  EXPECT_LT((r.c - c_true).norm(), 1e-4);
  // The J it hands back is still the model's (constant) Jacobian.
  EXPECT_TRUE(test::NearMatrix(r.J, opt.initial_jacobian, 1e-9, 1e-9));
  EXPECT_NE(r.summary.BriefReport().find("secant updates"), std::string::npos);
}

// A wrong Jacobian handed over (here the negated true one, so its first step goes uphill) costs
// one evaluated J and nothing else: broyden never accepts an increase, evaluates J where the step
// failed, and converges. A J of the wrong size is rejected up front.
TEST(IkSolver, BroydenRecoversFromAWrongJacobian) {
  PccKinematics pcc;
  const Eigen::Vector3d c0(10, 10, 10);
  for (const Eigen::Vector3d& c_true : {Eigen::Vector3d(5, 5, 9), Eigen::Vector3d(12, 3, 7)}) {
    PointTrackingObjective o(pcc.point_names(), "tip",
                             pcc.Evaluate(c_true, false).p.row(0).transpose());
    IkOptions opt;
    opt.method = IkMethod::kBroyden;
    opt.initial_jacobian = -pcc.Evaluate(c0, true).J;
    const IkResult r = SolveIk(pcc, o, c0, opt);
    ASSERT_TRUE(r.summary.converged()) << r.summary.BriefReport();
    EXPECT_GE(r.summary.jacobian_evaluations, 1);
    for (size_t i = 1; i < r.summary.history.size(); ++i)
      EXPECT_LE(r.summary.history[i], r.summary.history[i - 1]);
    EXPECT_EQ(r.J.rows(), 3 * pcc.num_points());
    EXPECT_EQ(r.J.cols(), 3);
    EXPECT_TRUE(r.J.allFinite());
  }
  PointTrackingObjective o(pcc.point_names(), "tip", Eigen::Vector3d(0, 0, 90));
  IkOptions bad;
  bad.method = IkMethod::kBroyden;
  bad.initial_jacobian = Eigen::MatrixXd::Zero(2, 3);
  EXPECT_THROW(SolveIk(pcc, o, c0, bad), std::invalid_argument);
  bad.initial_jacobian = Eigen::MatrixXd::Constant(3, 3, std::nan(""));
  EXPECT_THROW(SolveIk(pcc, o, c0, bad), std::invalid_argument);
}

TEST(IkSolver, BriefReportSaysWhatHappened) {
  PccKinematics pcc;
  PointTrackingObjective o(pcc.point_names(), "tip",
                           pcc.Evaluate(Eigen::Vector3d(5, 5, 9), false).p.row(0).transpose());
  IkOptions opt;
  opt.method = IkMethod::kGaussNewton;
  const IkResult r = SolveIk(pcc, o, pcc.rest(), opt);
  const std::string s = r.summary.BriefReport();
  EXPECT_NE(s.find("gauss-newton"), std::string::npos) << s;
  EXPECT_NE(s.find("converged"), std::string::npos) << s;
  EXPECT_GT(r.summary.fk_solves, 0);
  EXPECT_EQ(r.summary.fk_solves, r.summary.evaluations);  // one model evaluation each
}

}  // namespace
}  // namespace softkin
