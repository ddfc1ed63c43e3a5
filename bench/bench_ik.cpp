// One IK waypoint per method (Table 5.1's "time per waypoint"), on the analytical PCC finger: the
// IK overhead itself, since each model evaluation costs well under a microsecond. Two starts: cold
// (the middle of the box, as after the configuration-space sample) and warm (the previous
// waypoint of a smooth path, 1.6 mm away). Counters: evaluations, Jacobian evaluations and the
// final error per waypoint.
//
// BM_SimulatorWaypoint: one waypoint with the simulator in the loop (SimulatorKinematics, implicit
// Jacobian, lg-aa with gradient tolerance 1e-4 as `softkin ik --gradient-tolerance 1e-4`) on
// three_chamber, lambda = 0.2 mm. The target is the tip at c_true = (1.78, 1.26, 1); the waypoint
// starts from the previous waypoint's solution c_prev = (1.66, 1.22, 1) (4.5 mm away), with the
// kinematics' state at c_prev, as in trajectory following (Algorithm 4). Before each timed solve
// the kinematics replays the previous waypoint (untimed): J at c_pp = (1.54, 1.18, 1), then p at
// c_prev, so its warm state, prediction and Jacobian guess are those a path would leave; broyden
// is handed the J taken at c_pp, as FollowTrajectory hands on the previous waypoint's.
// range(0): method (enum order), range(1): resolution (7 is the robot's default). Counters:
// fk_solves, rejected_predictions (first-order starts kept out by the guard), evaluations,
// jac_evals, err_mm.
#include "softkin/ik/ik_solver.hpp"
#include "softkin/ik/pcc_kinematics.hpp"
#include "softkin/ik/simulator_kinematics.hpp"
#include "softkin/solver/robots/robots.hpp"
#include "softkin/solver/common/stopwatch.hpp"

#include <benchmark/benchmark.h>

#include <chrono>
#include <map>
#include <memory>

namespace softkin {
namespace {

// state.range(0): method (enum order), state.range(1): 0 cold start, 1 warm start.
void BM_IkWaypoint(benchmark::State& state) {
  const IkMethod method = AllIkMethods()[state.range(0)];
  const bool warm = state.range(1) == 1;
  PccKinematics pcc;
  const Eigen::Vector3d c_true(6, 11, 4);
  const Eigen::Vector3d target = pcc.Evaluate(c_true, false).p.row(0).transpose();
  Eigen::VectorXd c0 = Eigen::Vector3d(10, 10, 10);
  if (warm) {  // the solution of a waypoint ~1.6 mm away
    const Eigen::Vector3d prev = target + Eigen::Vector3d(1.6, 0, 0);
    IkOptions o;
    o.method = IkMethod::kGaussNewton;
    o.lambda = 1e-10;
    c0 = SolveIk(pcc, PointTrackingObjective(pcc.point_names(), "tip", prev), c0, o).c;
  }
  const PointTrackingObjective objective(pcc.point_names(), "tip", target);
  IkOptions opt;
  opt.method = method;
  opt.max_iterations = 300;
  opt.max_evaluations = 5000;
  IkResult r;
  for (auto _ : state) {
    r = SolveIk(pcc, objective, c0, opt);
    benchmark::DoNotOptimize(r.c.data());
  }
  state.SetLabel(IkMethodToString(method) + (warm ? " warm" : " cold") + " " +
                 IkTerminationToString(r.summary.termination));
  state.counters["evals"] = r.summary.evaluations;
  state.counters["jac_evals"] = r.summary.jacobian_evaluations;
  state.counters["err_mm"] = std::sqrt(r.objective);
}

void AllMethods(benchmark::internal::Benchmark* b) {
  for (int m = 0; m < static_cast<int>(AllIkMethods().size()); ++m)
    for (int warm : {0, 1}) b->Args({m, warm});
}

BENCHMARK(BM_IkWaypoint)->Apply(AllMethods)->Unit(benchmark::kMicrosecond);

struct SimFixture {
  std::unique_ptr<SimulatorKinematics> kin;
  Eigen::VectorXd c_pp, c_prev;
  Eigen::Vector3d target;
};

SimFixture& GetSimFixture(int res) {
  static std::map<int, std::unique_ptr<SimFixture>> cache;
  auto it = cache.find(res);
  if (it != cache.end()) return *it->second;
  auto f = std::make_unique<SimFixture>();
  const Scene scene = MakeRobot("three_chamber", res);
  FkOptions fk = scene.solver;
  fk.gradient_tolerance = 1e-4;
  SimulatorKinematicsOptions o;
  o.jacobian = JacobianMode::kImplicit;
  o.points = {"tip"};
  f->kin = std::make_unique<SimulatorKinematics>(scene, o, &fk);
  f->c_pp = Eigen::Vector3d(1.54, 1.18, 1.0);
  f->c_prev = Eigen::Vector3d(1.66, 1.22, 1.0);
  const KinematicsEval e = f->kin->Evaluate(Eigen::Vector3d(1.78, 1.26, 1.0), false);
  f->target = e.ok ? Eigen::Vector3d(e.p.row(0).transpose()) : Eigen::Vector3d::Zero();
  return *cache.emplace(res, std::move(f)).first->second;
}

void BM_SimulatorWaypoint(benchmark::State& state) {
  const IkMethod method = AllIkMethods()[state.range(0)];
  SimFixture& f = GetSimFixture(static_cast<int>(state.range(1)));
  const PointTrackingObjective objective(f.kin->point_names(), "tip", f.target);
  IkOptions opt;
  opt.method = method;
  opt.lambda = 0.04;  // (0.2 mm)^2
  IkResult r;
  long long solves = 0, rejected = 0;
  for (auto _ : state) {
    // The previous waypoint, untimed: J where it started, p where it ended. broyden gets that J
    // handed over (as FollowTrajectory does with the previous waypoint's).
    const KinematicsEval pp = f.kin->Evaluate(f.c_pp, true);
    if (!pp.ok || !f.kin->Evaluate(f.c_prev, false).ok) {
      state.SkipWithError("forward solve or Jacobian of the previous waypoint failed");
      return;
    }
    if (method == IkMethod::kBroyden) opt.initial_jacobian = pp.J;
    const long long before = f.kin->total_fk_solves();
    const long long rejected_before = f.kin->rejected_predictions();
    const auto t0 = std::chrono::steady_clock::now();
    r = SolveIk(*f.kin, objective, f.c_prev, opt);
    state.SetIterationTime(SecondsSince(t0));
    solves = f.kin->total_fk_solves() - before;
    rejected = f.kin->rejected_predictions() - rejected_before;
  }
  state.SetLabel(IkMethodToString(method) + " res " + std::to_string(state.range(1)) + " " +
                 IkTerminationToString(r.summary.termination));
  state.counters["fk_solves"] = static_cast<double>(solves);
  state.counters["rejected_predictions"] = static_cast<double>(rejected);
  state.counters["evals"] = r.summary.evaluations;
  state.counters["jac_evals"] = r.summary.jacobian_evaluations;
  state.counters["err_mm"] = std::sqrt(r.objective);
}

void SimulatorCases(benchmark::internal::Benchmark* b) {
  const auto& all = AllIkMethods();
  auto index = [&](IkMethod m) {
    for (size_t i = 0; i < all.size(); ++i)
      if (all[i] == m) return static_cast<int>(i);
    return 0;
  };
  for (IkMethod m : {IkMethod::kSoftLineSearch, IkMethod::kNloptSlsqp, IkMethod::kGaussNewton,
                     IkMethod::kBroyden})
    b->Args({index(m), 4});
  b->Args({index(IkMethod::kGaussNewton), 7});
  b->Args({index(IkMethod::kBroyden), 7});
}

BENCHMARK(BM_SimulatorWaypoint)
    ->Apply(SimulatorCases)
    ->Iterations(2)
    ->UseManualTime()
    ->Unit(benchmark::kMillisecond);

}  // namespace
}  // namespace softkin

BENCHMARK_MAIN();
