// Algorithm 3: the soft line search never accepts an increase and never leaves the box, on the
// nonlinear bounded PCC model, with reachable and unreachable targets, the raw and the
// range-normalised gradient, and evaluations that fail.
#include "softkin/ik/pcc_kinematics.hpp"
#include "softkin/ik/soft_line_search.hpp"

#include "ik_test_models.hpp"

#include <gtest/gtest.h>

namespace softkin {
namespace {

void ExpectAllInBox(const test::RecordingKinematics& rec, const Kinematics& k) {
  ASSERT_FALSE(rec.calls.empty());
  for (size_t i = 0; i < rec.calls.size(); ++i) {
    EXPECT_TRUE((rec.calls[i].array() >= k.lower().array()).all() &&
                (rec.calls[i].array() <= k.upper().array()).all())
        << "call " << i << ": " << rec.calls[i].transpose();
  }
}

void ExpectStrictlyDecreasing(const IkSummary& s) {
  ASSERT_GE(s.history.size(), 1u);
  EXPECT_EQ(s.history.size(), static_cast<size_t>(s.iterations) + 1);
  for (size_t i = 1; i < s.history.size(); ++i)
    EXPECT_LT(s.history[i], s.history[i - 1]) << "iteration " << i;
}

TEST(SoftLineSearch, NeverIncreasesAndStaysInTheBox) {
  PccKinematics pcc;
  const std::vector<Eigen::Vector3d> targets = {
      Eigen::Vector3d(20, 10, 90),   // reachable
      Eigen::Vector3d(-30, 25, 70),  // reachable, far from rest
      Eigen::Vector3d(200, 0, 0),    // unreachable: the search ends at the box / a minimum
      Eigen::Vector3d(0, 0, 150)};   // unreachable above the rest tip
  int runs = 0;
  for (bool normalize : {true, false})
    for (const Eigen::Vector3d& t : targets) {
      test::RecordingKinematics rec(pcc);
      PointTrackingObjective o(rec.point_names(), "tip", t);
      IkOptions opt;
      opt.normalize_by_range = normalize;
      opt.max_iterations = 40;
      const IkResult r = SolveIk(rec, o, rec.rest(), opt);
      SCOPED_TRACE(r.summary.BriefReport());
      ExpectStrictlyDecreasing(r.summary);
      ExpectAllInBox(rec, pcc);
      EXPECT_NEAR(r.objective, r.summary.history.back(), 1e-12);
      EXPECT_LE(r.objective, r.summary.history.front());
      ++runs;
    }
  EXPECT_EQ(runs, 8);
}

TEST(SoftLineSearch, ReachesAReachableTargetFromRest) {
  PccKinematics pcc;
  const Eigen::Vector3d c_true(3, 12, 6);
  const Eigen::Vector3d target = pcc.Evaluate(c_true, false).p.row(0).transpose();
  PointTrackingObjective o(pcc.point_names(), "tip", target);
  IkOptions opt;
  opt.max_iterations = 200;
  opt.max_evaluations = 5000;
  const IkResult r = SolveIk(pcc, o, pcc.rest(), opt);
  EXPECT_TRUE(r.summary.converged()) << r.summary.BriefReport();
  EXPECT_LE((r.p.row(0).transpose() - target).norm(), 0.2);
}

TEST(SoftLineSearch, UnreachableTargetEndsOnTheBoxWithoutNaN) {
  PccKinematics pcc;
  PointTrackingObjective o(pcc.point_names(), "tip", Eigen::Vector3d(500, 0, 0));
  IkOptions opt;
  opt.max_iterations = 100;
  const IkResult r = SolveIk(pcc, o, pcc.rest(), opt);
  EXPECT_FALSE(r.summary.converged());
  EXPECT_TRUE(r.c.allFinite() && r.p.allFinite());
  EXPECT_NEAR(r.c[0], 20.0, 1e-9) << r.c.transpose();  // cable 0 fully pulled (bends towards +x)
  EXPECT_FALSE(r.summary.message.empty());
}

TEST(SoftLineSearch, FailedTrialsAreTreatedAsNoDecrease) {
  PccKinematics pcc;
  test::RecordingKinematics rec(pcc);
  rec.fail_if = [](const Eigen::VectorXd& c) { return c[1] > 8.0; };  // the "simulator" fails there
  PointTrackingObjective o(rec.point_names(), "tip",
                           pcc.Evaluate(Eigen::Vector3d(2, 12, 2), false).p.row(0).transpose());
  IkOptions opt;
  opt.max_iterations = 50;
  const IkResult r = SolveIk(rec, o, rec.rest(), opt);
  ExpectStrictlyDecreasing(r.summary);
  EXPECT_LE(r.c[1], 8.0);
  int failed = 0;
  for (const auto& c : rec.calls) failed += c[1] > 8.0;
  EXPECT_GT(failed, 0);  // the guarded case really happened
}

// With no descent along -grad the shrinking stops at steps of parameter_tolerance (of the
// ranges), not after max_shrinks: each smaller trial would be a forward solve spent on noise.
TEST(SoftLineSearch, ShrinkingStopsBelowTheParameterTolerance) {
  PccKinematics pcc;
  test::RecordingKinematics rec(pcc);
  rec.alter = [](KinematicsEval* e) {  // J negated: -grad points uphill everywhere
    if (e->ok && e->J.size() > 0) e->J = -e->J;
  };
  const Eigen::VectorXd c0 = (pcc.lower() + pcc.upper()) / 2;
  PointTrackingObjective o(rec.point_names(), "tip",
                           pcc.Evaluate(pcc.upper() * 0.9, false).p.row(0).transpose());
  IkOptions opt;
  opt.parameter_tolerance = 1e-6;
  const IkResult r = SolveIk(rec, o, c0, opt);
  EXPECT_EQ(r.summary.termination, IkTermination::kNoProgress);
  EXPECT_NE(r.summary.message.find("below parameter_tolerance"), std::string::npos)
      << r.summary.message;
  ASSERT_GE(rec.calls.size(), 3u);
  EXPECT_LT(rec.calls.size(), 1u + opt.max_shrinks);
  const Eigen::VectorXd range = pcc.upper() - pcc.lower();
  for (size_t i = 1; i < rec.calls.size(); ++i)  // every trial moved by more than the tolerance
    EXPECT_GT((rec.calls[i] - c0).cwiseAbs().cwiseQuotient(range).maxCoeff(),
              opt.parameter_tolerance)
        << "trial " << i;
  EXPECT_EQ(r.c, c0);
}

TEST(SoftLineSearch, AFailureAtTheStartIsReportedWithItsMessage) {
  PccKinematics pcc;
  test::RecordingKinematics rec(pcc);
  rec.fail_if = [](const Eigen::VectorXd&) { return true; };
  PointTrackingObjective o(rec.point_names(), "tip", Eigen::Vector3d(0, 0, 90));
  const IkResult r = SolveIk(rec, o, rec.rest(), IkOptions());
  EXPECT_EQ(r.summary.termination, IkTermination::kKinematicsFailure);
  EXPECT_NE(r.summary.message.find("injected failure"), std::string::npos) << r.summary.message;
  EXPECT_EQ(r.c, rec.rest());
}

TEST(SoftLineSearch, StopsAtLambdaAndAtIMax) {
  PccKinematics pcc;
  PointTrackingObjective o(pcc.point_names(), "tip", Eigen::Vector3d(30, 30, 60));
  IkOptions opt;
  opt.max_iterations = 3;
  opt.lambda = 0.0;
  const IkResult r = SolveIk(pcc, o, pcc.rest(), opt);
  EXPECT_EQ(r.summary.termination, IkTermination::kMaxIterations);
  EXPECT_EQ(r.summary.iterations, 3);
  opt.lambda = 1e9;  // already satisfied at c0
  const IkResult r0 = SolveIk(pcc, o, pcc.rest(), opt);
  EXPECT_TRUE(r0.summary.converged());
  EXPECT_EQ(r0.summary.iterations, 0);
  EXPECT_EQ(r0.summary.evaluations, 1);
}

}  // namespace
}  // namespace softkin
