// Algorithm 4 on the PCC finger: continuity on a smooth path, unreachable waypoints reported with
// their distance, the closest-sample initial guess, the sample cache, streaming and resuming.
#include "softkin/ik/trajectory.hpp"
#include "softkin/ik/trajectory_io.hpp"
#include "softkin/ik/pcc_kinematics.hpp"

#include "ik_test_models.hpp"

#include <gtest/gtest.h>

#include <cstdio>
#include <fstream>
#include <sstream>
#include <unistd.h>

namespace softkin {
namespace {

// A smooth closed path: a circle of radius 15 mm around a reachable point, N waypoints.
Eigen::MatrixX3d CirclePath(PccKinematics& k, int n) {
  const Eigen::Vector3d centre = k.Evaluate(Eigen::Vector3d(8, 8, 8), false).p.row(0).transpose();
  Eigen::MatrixX3d w(n, 3);
  for (int i = 0; i < n; ++i) {
    const double a = 2 * M_PI * i / n;
    w.row(i) = (centre + Eigen::Vector3d(15 * std::cos(a), 15 * std::sin(a), 0)).transpose();
  }
  return w;
}

std::string TempPath(const std::string& name) {
  return ::testing::TempDir() + "/softkin_" + std::to_string(::getpid()) + "_" + name;
}

TEST(Trajectory, SmoothPathGivesContinuousActuation) {
  PccKinematics k;
  const Eigen::MatrixX3d path = CirclePath(k, 60);
  TrajectoryOptions opt;
  opt.ik.max_iterations = 100;
  opt.ik.max_evaluations = 2000;
  int calls = 0;
  const TrajectoryResult r = FollowTrajectory(k, path, opt, [&](const WaypointResult& w) {
    EXPECT_EQ(w.index, calls);
    ++calls;
  });
  ASSERT_EQ(calls, 60);
  EXPECT_EQ(r.converged, 60);
  EXPECT_LE(r.max_error_mm, 0.2);
  // Neighbouring waypoints are 1.6 mm apart; the tip moves ~1-3 mm per mm of cable here, so a
  // continuous solution moves each cable by a few mm at most. A branch switch would jump by ~10.
  EXPECT_LT(r.max_jump, 3.0) << "at waypoint " << r.max_jump_index;
  EXPECT_GE(r.max_jump_index, 1);
  for (const WaypointResult& w : r.waypoints) {
    EXPECT_NEAR(w.error_mm, (w.reached - w.target).norm(), 1e-12);
    EXPECT_NEAR(w.objective, w.error_mm * w.error_mm, 1e-9);
  }
  EXPECT_EQ(r.samples.c.rows(), 125);
  EXPECT_EQ(r.samples.cache_status, "built");
}

// broyden along a smooth path: each waypoint gets the previous one's Jacobian, so J is evaluated
// at the first waypoint and where a secant-updated step failed, not at every waypoint as with
// gauss-newton; the answers are as good.
TEST(Trajectory, BroydenHandsTheJacobianOnAlongThePath) {
  PccKinematics k;
  const Eigen::MatrixX3d path = CirclePath(k, 40);
  int j_gn = 0, j_br = 0;
  for (IkMethod m : {IkMethod::kGaussNewton, IkMethod::kBroyden}) {
    int with_j = 0;
    struct Counting : test::RecordingKinematics {
      using test::RecordingKinematics::RecordingKinematics;
      int* jac = nullptr;
      KinematicsEval Evaluate(const Eigen::Ref<const Eigen::VectorXd>& c,
                              bool with_jacobian) override {
        if (with_jacobian) ++*jac;
        return test::RecordingKinematics::Evaluate(c, with_jacobian);
      }
    } counting(k);
    counting.jac = &with_j;
    TrajectoryOptions opt;
    opt.ik.method = m;
    opt.ik.max_iterations = 100;
    opt.ik.max_evaluations = 2000;
    const TrajectoryResult r = FollowTrajectory(counting, path, opt);
    SCOPED_TRACE(IkMethodToString(m));
    EXPECT_EQ(r.converged, 40);
    EXPECT_LE(r.max_error_mm, 0.2);
    EXPECT_LT(r.max_jump, 3.0);
    (m == IkMethod::kBroyden ? j_br : j_gn) = with_j;  // the sampling takes no J
  }
  EXPECT_GE(j_gn, 40);        // at least one J per waypoint
  EXPECT_LT(j_br, j_gn / 2);  // most waypoints need none
  EXPECT_GE(j_br, 1);
}

// When the first waypoint does not converge from the closest sample (here the kinematics fails
// around it, as a forward solve that does not converge would), the next closest samples are tried
// in order; the kept answer, its start and the summed cost are reported. With one start allowed
// (Algorithm 4 as written) the waypoint fails.
TEST(Trajectory, FirstWaypointTriesTheNextClosestSamples) {
  PccKinematics k;
  const Eigen::MatrixX3d path = CirclePath(k, 3);
  SamplingOptions so;
  const ConfigurationSamples all = SampleConfigurationSpace(k, "tip", so);
  const std::vector<int> order = ClosestSamples(all, path.row(0).transpose(), 125);
  ASSERT_EQ(order.size(), 125u);
  for (size_t i = 1; i < order.size(); ++i)
    EXPECT_LE((all.p.row(order[i - 1]) - path.row(0)).norm(),
              (all.p.row(order[i]) - path.row(0)).norm());
  EXPECT_EQ(order.front(), ClosestSample(all, path.row(0).transpose()));
  const Eigen::VectorXd bad = all.c.row(order[0]).transpose();
  for (int starts : {1, 3}) {
    SCOPED_TRACE(starts);
    test::RecordingKinematics rec(k);
    // The 125 sampling evaluations see no failure; the solve from the closest sample fails at
    // its start.
    rec.fail_if = [&](const Eigen::VectorXd& c) {
      return rec.calls.size() > 125 && (c - bad).norm() < 1e-9;
    };
    TrajectoryOptions opt;
    opt.ik.method = IkMethod::kGaussNewton;
    opt.first_waypoint_starts = starts;
    const TrajectoryResult r = FollowTrajectory(rec, path, opt);
    ASSERT_EQ(r.waypoints.size(), 3u);
    if (starts == 1) {
      EXPECT_FALSE(r.waypoints[0].converged);
      EXPECT_EQ(r.initial_sample, order[0]);
      EXPECT_EQ(r.initial_starts_tried, 1);
      continue;
    }
    EXPECT_TRUE(r.waypoints[0].converged) << r.waypoints[0].message;
    EXPECT_EQ(r.initial_starts_tried, 2);
    EXPECT_EQ(r.initial_sample, order[1]);
    EXPECT_TRUE(r.initial_guess.isApprox(all.c.row(order[1]).transpose()));
    EXPECT_NE(r.waypoints[0].message.find("2 sample(s)"), std::string::npos)
        << r.waypoints[0].message;
    EXPECT_EQ(r.converged, 3);
  }
  TrajectoryOptions zero;
  zero.first_waypoint_starts = 0;
  EXPECT_THROW(FollowTrajectory(k, path, zero), std::invalid_argument);
}

TEST(Trajectory, FirstWaypointStartsFromTheClosestSample) {
  PccKinematics k;
  const Eigen::MatrixX3d path = CirclePath(k, 4);
  const TrajectoryResult r = FollowTrajectory(k, path, TrajectoryOptions());
  ASSERT_GE(r.initial_sample, 0);
  double best = 1e300;
  for (int i = 0; i < r.samples.p.rows(); ++i)
    best = std::min(best, (r.samples.p.row(i) - path.row(0)).norm());
  EXPECT_DOUBLE_EQ((r.samples.p.row(r.initial_sample) - path.row(0)).norm(), best);
  EXPECT_EQ(r.initial_guess, Eigen::VectorXd(r.samples.c.row(r.initial_sample).transpose()));
}

TEST(Trajectory, UnreachableWaypointReportsItsDistanceAndThePathRecovers) {
  PccKinematics k;
  Eigen::MatrixX3d path = CirclePath(k, 12);
  path.row(5) << 0, 0, 140;  // 40 mm above the straight finger's tip: outside the workspace
  TrajectoryOptions opt;
  // Leaving the straight (rest) configuration again takes gradient descent many steps.
  opt.ik.max_iterations = 300;
  opt.ik.max_evaluations = 3000;
  const TrajectoryResult r = FollowTrajectory(k, path, opt);
  const WaypointResult& w = r.waypoints[5];
  EXPECT_FALSE(w.converged);
  EXPECT_NEAR(w.error_mm, 40.0, 1e-6);  // the closest reachable point is the rest tip, z = 100
  EXPECT_TRUE(w.c.isZero(1e-9)) << w.c.transpose();
  EXPECT_NEAR(w.error_mm, (w.reached - w.target).norm(), 1e-12);
  EXPECT_TRUE(w.c.allFinite());
  for (int i = 6; i < 12; ++i) EXPECT_TRUE(r.waypoints[i].converged) << i;
  EXPECT_EQ(r.converged, 11);
}

// The inverted elements of the state behind each answer reach the waypoint, its CSV row and the
// path's count: PCC standing in for a simulator that folds elements when cable 0 exceeds 5 mm.
TEST(Trajectory, InvertedStatesAreCarriedToEveryWaypointAndItsRow) {
  struct Folding : PccKinematics {
    KinematicsEval Evaluate(const Eigen::Ref<const Eigen::VectorXd>& c, bool with_j) override {
      KinematicsEval e = PccKinematics::Evaluate(c, with_j);
      if (c[0] > 5.0) {
        e.inverted_elements = 7;
        e.min_volume_ratio = -0.5;
      }
      return e;
    }
  } k;
  const Eigen::MatrixX3d path = CirclePath(k, 12);
  TrajectoryOptions opt;
  opt.ik.max_iterations = 100;
  opt.ik.max_evaluations = 2000;
  const TrajectoryResult r = FollowTrajectory(k, path, opt);
  int inverted = 0;
  for (const WaypointResult& w : r.waypoints) {
    EXPECT_EQ(w.inverted_elements, w.c[0] > 5.0 ? 7 : 0) << w.index << ": c " << w.c.transpose();
    EXPECT_EQ(w.min_volume_ratio, w.c[0] > 5.0 ? -0.5 : 1.0);
    inverted += w.c[0] > 5.0;
    const std::string row = WaypointCsvRow(w);
    EXPECT_EQ(row.substr(row.rfind(',') + 1), std::to_string(w.inverted_elements)) << row;
  }
  EXPECT_GT(inverted, 0);            // the circle needs cable 0 beyond 5 mm somewhere
  EXPECT_LT(inverted, path.rows());  // and not everywhere
  EXPECT_EQ(r.inverted, inverted);
  // Every waypoint meets the objective, but one in an inverted state is never `converged`.
  EXPECT_EQ(r.converged, 12 - inverted);
  for (const WaypointResult& w : r.waypoints) EXPECT_EQ(w.converged, w.inverted_elements == 0);
  const std::string header = WaypointCsvHeader(3);
  EXPECT_EQ(header.substr(header.rfind(',') + 1), "inverted_elements");
}

TEST(Trajectory, SampleCacheIsReusedAndRejectedWhenBuiltForSomethingElse) {
  PccKinematics k;
  const std::string file = TempPath("samples.csv");
  std::remove(file.c_str());
  SamplingOptions so;
  so.cache_file = file;
  so.cache_key = "pcc default";
  const ConfigurationSamples a = SampleConfigurationSpace(k, "tip", so);
  EXPECT_EQ(a.cache_status, "written");
  const long long before = k.total_fk_solves();
  const ConfigurationSamples b = SampleConfigurationSpace(k, "tip", so);
  EXPECT_EQ(b.cache_status, "loaded");
  EXPECT_EQ(k.total_fk_solves(), before);  // no evaluation
  EXPECT_EQ(a.c, b.c);
  EXPECT_EQ(a.p, b.p);  // 17 digits round-trip exactly
  so.cache_key = "pcc other";
  const ConfigurationSamples c = SampleConfigurationSpace(k, "tip", so);
  EXPECT_NE(c.cache_status.find("rebuilt"), std::string::npos);
  EXPECT_NE(c.cache_status.find("key=pcc default"), std::string::npos) << c.cache_status;
  const ConfigurationSamples d = SampleConfigurationSpace(k, "backbone[3]", so);
  EXPECT_NE(d.cache_status.find("point=tip"), std::string::npos) << d.cache_status;
  {
    std::ofstream f(file, std::ios::app);
    f << "1,2,oops,4,5,6\n";
  }
  so.cache_key = "pcc other";
  const ConfigurationSamples e = SampleConfigurationSpace(k, "backbone[3]", so);
  EXPECT_NE(e.cache_status.find("oops"), std::string::npos) << e.cache_status;
  // A sample outside the actuators' range is not loaded (it would start IK out of range).
  std::string text;
  {
    std::ifstream in(file);
    std::stringstream ss;
    ss << in.rdbuf();
    text = ss.str();
  }
  const size_t last = text.rfind('\n', text.size() - 2) + 1;
  text.replace(last, text.find(',', last) - last, "99");
  { std::ofstream(file, std::ios::trunc) << text; }
  const ConfigurationSamples g = SampleConfigurationSpace(k, "backbone[3]", so);
  EXPECT_NE(g.cache_status.find("c0 = 99 is outside the actuator's range"), std::string::npos)
      << g.cache_status;
  std::remove(file.c_str());
}

TEST(Trajectory, ResumingFromAWaypointGivesTheSameResults) {
  PccKinematics k;
  const Eigen::MatrixX3d path = CirclePath(k, 10);
  const TrajectoryResult full = FollowTrajectory(k, path, TrajectoryOptions());
  TrajectoryOptions opt;
  opt.first_waypoint = 6;
  opt.warm_start = full.waypoints[5].c;
  const TrajectoryResult rest = FollowTrajectory(k, path, opt);
  ASSERT_EQ(rest.waypoints.size(), 4u);
  EXPECT_EQ(rest.initial_sample, -1);
  EXPECT_EQ(rest.samples.c.rows(), 0);
  for (int i = 0; i < 4; ++i) {
    EXPECT_EQ(rest.waypoints[i].index, 6 + i);
    EXPECT_EQ(rest.waypoints[i].c, full.waypoints[6 + i].c);  // deterministic
  }
}

TEST(Trajectory, BadInputsThrow) {
  PccKinematics k;
  Eigen::MatrixX3d path = CirclePath(k, 3);
  TrajectoryOptions opt;
  opt.point = "nose";
  EXPECT_THROW(FollowTrajectory(k, path, opt), std::invalid_argument);
  opt = TrajectoryOptions();
  opt.warm_start = Eigen::Vector3d(0, 0, 99);
  EXPECT_THROW(FollowTrajectory(k, path, opt), std::invalid_argument);
  opt = TrajectoryOptions();
  path(1, 2) = std::nan("");
  EXPECT_THROW(FollowTrajectory(k, path, opt), std::invalid_argument);
  opt.sampling.samples_per_axis = 1;
  std::string why;
  EXPECT_FALSE(opt.IsValid(&why));
  EXPECT_NE(why.find("sampling.samples_per_axis"), std::string::npos) << why;
}

}  // namespace
}  // namespace softkin
