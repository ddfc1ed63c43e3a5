// One IK waypoint per method (Table 5.1's "time per waypoint"), on the analytical PCC finger: the
// IK overhead itself, since each model evaluation costs well under a microsecond. Two starts: cold
// (the middle of the box, as after the configuration-space sample) and warm (the previous
// waypoint of a smooth path, 1.6 mm away). Counters: evaluations, Jacobian evaluations and the
// final error per waypoint. Simulator-backed cases (ik/simulator_kinematics.hpp) belong here too.
#include "ik/ik_solver.hpp"
#include "ik/pcc_kinematics.hpp"

#include <benchmark/benchmark.h>

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

}  // namespace
}  // namespace softkin

BENCHMARK_MAIN();
