// Google Benchmark suite for the Newton-Krylov FK solver against lg-aa (docs/newton.md).
//
// Each benchmark solves one actuation from the rest shape with one solver, to the same stopping
// test (tolerance 1e-5, gradient_tolerance 1e-6; lg-aa gets an iteration cap of 10^6 so that it
// converges), and reports the counters
//   tets, vertices      mesh size
//   iterations          Newton iterations (newton) or local-global iterations (lg-aa)
//   krylov              GMRES products (newton)
//   load_steps          converged load steps (newton)
//   residual_ratio      the final residual ratio (both must be below 1e-6)
//   inverted            inverted body elements of the answer (status inverted: the tolerance is
//                       met, at a state whose walls buckle through each other, the same for both)
//   per_vertex          wall time per vertex
// Compare solvers as the ratio of their times within one run (the machine is shared):
//   build/bin/bench_newton --benchmark_filter='Strip'
// Cases: bilayer_strip res 1 and 2 (3.6k and 24k tets), res 1 with an Ecoflex 00-30 Mooney-Rivlin
// body (hyperelastic = 1; StripMR), and the 12k-tet strip of issue #33 (res 2
// with 2 mm cells along the length) and the unstructured Gmsh strip of the same size
// (scenes/bilayer_strip_gmsh.json, 12,397 tets, data/strip/) at alpha 1.1 and 1.5; pneumatic_finger
// res 8 at alpha 5, and res 12 (46.7k tets) from rest to the end of its range, alpha 10;
// three_chamber res 5 at (1.5, 1, 1); finger_manipulator res 8 and 10 at (0.5, 0, 0); cable_finger
// res 8 at (0.8, 0.8, 0.8) (lg-aa and auto only: newton takes about 3 minutes there,
// docs/newton.md). "auto" (the default solver) runs beside both on every case.
#include "softkin/solver/factory/fk_factory.hpp"
#include "softkin/solver/robots/robots.hpp"
#include "softkin/solver/scene/scene_json.hpp"

#include <benchmark/benchmark.h>

#include <map>
#include <memory>
#include <string>
#include <tuple>
#include <vector>

namespace softkin {
namespace {

/// One model per (robot, res, params), built once.
std::shared_ptr<const Model> CachedModel(const std::string& robot, int res,
                                         const RobotParams& params) {
  static std::map<std::tuple<std::string, int, RobotParams>, std::shared_ptr<const Model>> cache;
  auto& m = cache[{robot, res, params}];
  if (!m) m = std::make_shared<const Model>(MakeRobot(robot, res, params));
  return m;
}

/// The scene file's model (relative to the source tree), built once.
std::shared_ptr<const Model> CachedSceneModel(const std::string& scene) {
  static std::map<std::string, std::shared_ptr<const Model>> cache;
  auto& m = cache[scene];
  if (!m)
    m = std::make_shared<const Model>(LoadSceneJson(std::string(SOFTKIN_SOURCE_DIR) + "/" + scene));
  return m;
}

void Solve(benchmark::State& state, const std::shared_ptr<const Model>& model,
           const std::string& solver, const Eigen::VectorXd& c) {
  FkOptions o;
  o.solver = FkSolverTypeFromString(solver);
  o.max_iterations = 1000000;
  FkResult r;
  for (auto _ : state) {
    auto s = MakeFkSolver(model, o);  // a fresh solver: no factor or reference kept between runs
    r = s->Solve(c);
    if (r.status != FkStatus::Converged && r.status != FkStatus::Inverted)
      state.SkipWithError(r.BriefReport().c_str());
  }
  state.counters["tets"] = model->mesh().num_elements();
  state.counters["vertices"] = model->num_vertices();
  state.counters["iterations"] = r.iterations;
  state.counters["krylov"] = r.linear_iterations;
  state.counters["load_steps"] = r.load_steps;
  state.counters["residual_ratio"] = r.gradient_ratio;
  state.counters["inverted"] = r.inverted_elements;
  state.counters["per_vertex"] =
      benchmark::Counter(model->num_vertices(), benchmark::Counter::kIsIterationInvariantRate |
                                                    benchmark::Counter::kInvert);
}

void Solve(benchmark::State& state, const std::string& robot, int res, const std::string& solver,
           const Eigen::VectorXd& c, const RobotParams& params = {}) {
  Solve(state, CachedModel(robot, res, params), solver, c);
}

Eigen::VectorXd One(double v) { return Eigen::VectorXd::Constant(1, v); }

void BM_Strip(benchmark::State& state, int res, double alpha, const char* solver) {
  Solve(state, "bilayer_strip", res, solver, One(alpha));
}
void BM_StripMooneyRivlin(benchmark::State& state, double alpha, const char* solver) {
  Solve(state, "bilayer_strip", 1, solver, One(alpha), {{"hyperelastic", 1.0}});
}
void BM_Strip12k(benchmark::State& state, double alpha, const char* solver) {
  Solve(state, "bilayer_strip", 2, solver, One(alpha), {{"cell_length", 2.0}});
}
void BM_GmshStrip(benchmark::State& state, double alpha, const char* solver) {
  Solve(state, CachedSceneModel("scenes/bilayer_strip_gmsh.json"), solver, One(alpha));
}
void BM_Finger(benchmark::State& state, const char* solver) {
  Solve(state, "pneumatic_finger", 8, solver, One(5.0));
}
void BM_FingerRes12Alpha10(benchmark::State& state, const char* solver) {
  Solve(state, "pneumatic_finger", 12, solver, One(10.0));
}
void BM_ThreeChamber(benchmark::State& state, const char* solver) {
  Solve(state, "three_chamber", 5, solver, Eigen::Vector3d(1.5, 1.0, 1.0));
}
void BM_Manipulator(benchmark::State& state, int res, const char* solver) {
  Solve(state, "finger_manipulator", res, solver, Eigen::Vector3d(0.5, 0.0, 0.0));
}
void BM_Manipulator_r8(benchmark::State& s, const char* solver) { BM_Manipulator(s, 8, solver); }
void BM_Manipulator_r10(benchmark::State& s, const char* solver) { BM_Manipulator(s, 10, solver); }
void BM_CableFinger(benchmark::State& state, const char* solver) {
  Solve(state, "cable_finger", 8, solver, Eigen::Vector3d(0.8, 0.8, 0.8));
}

void BM_Strip_r1_a1_1(benchmark::State& s, const char* solver) { BM_Strip(s, 1, 1.1, solver); }
void BM_Strip_r1_a1_5(benchmark::State& s, const char* solver) { BM_Strip(s, 1, 1.5, solver); }
void BM_Strip_r2_a1_1(benchmark::State& s, const char* solver) { BM_Strip(s, 2, 1.1, solver); }
void BM_Strip_r2_a1_5(benchmark::State& s, const char* solver) { BM_Strip(s, 2, 1.5, solver); }
void BM_StripMR_r1_a1_1(benchmark::State& s, const char* solver) {
  BM_StripMooneyRivlin(s, 1.1, solver);
}
void BM_StripMR_r1_a1_5(benchmark::State& s, const char* solver) {
  BM_StripMooneyRivlin(s, 1.5, solver);
}
void BM_Strip12k_a1_1(benchmark::State& s, const char* solver) { BM_Strip12k(s, 1.1, solver); }
void BM_Strip12k_a1_5(benchmark::State& s, const char* solver) { BM_Strip12k(s, 1.5, solver); }
void BM_GmshStrip_a1_1(benchmark::State& s, const char* solver) { BM_GmshStrip(s, 1.1, solver); }
void BM_GmshStrip_a1_5(benchmark::State& s, const char* solver) { BM_GmshStrip(s, 1.5, solver); }

BENCHMARK_CAPTURE(BM_Strip_r1_a1_1, newton, "newton")
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime()
    ->Iterations(1);
BENCHMARK_CAPTURE(BM_Strip_r1_a1_1, lg_aa, "lg-aa")
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime()
    ->Iterations(1);
BENCHMARK_CAPTURE(BM_Strip_r1_a1_5, newton, "newton")
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime()
    ->Iterations(1);
BENCHMARK_CAPTURE(BM_Strip_r1_a1_5, lg_aa, "lg-aa")
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime()
    ->Iterations(1);
BENCHMARK_CAPTURE(BM_Strip_r2_a1_1, newton, "newton")
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime()
    ->Iterations(1);
BENCHMARK_CAPTURE(BM_Strip_r2_a1_1, lg_aa, "lg-aa")
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime()
    ->Iterations(1);
BENCHMARK_CAPTURE(BM_Strip_r2_a1_5, newton, "newton")
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime()
    ->Iterations(1);
BENCHMARK_CAPTURE(BM_Strip_r2_a1_5, lg_aa, "lg-aa")
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime()
    ->Iterations(1);
BENCHMARK_CAPTURE(BM_StripMR_r1_a1_1, newton, "newton")
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime()
    ->Iterations(1);
BENCHMARK_CAPTURE(BM_StripMR_r1_a1_1, lg_aa, "lg-aa")
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime()
    ->Iterations(1);
BENCHMARK_CAPTURE(BM_StripMR_r1_a1_5, newton, "newton")
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime()
    ->Iterations(1);
BENCHMARK_CAPTURE(BM_StripMR_r1_a1_5, lg_aa, "lg-aa")
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime()
    ->Iterations(1);
BENCHMARK_CAPTURE(BM_Strip12k_a1_1, newton, "newton")
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime()
    ->Iterations(1);
BENCHMARK_CAPTURE(BM_Strip12k_a1_1, lg_aa, "lg-aa")
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime()
    ->Iterations(1);
BENCHMARK_CAPTURE(BM_Strip12k_a1_5, newton, "newton")
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime()
    ->Iterations(1);
BENCHMARK_CAPTURE(BM_Strip12k_a1_5, lg_aa, "lg-aa")
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime()
    ->Iterations(1);
BENCHMARK_CAPTURE(BM_GmshStrip_a1_1, newton, "newton")
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime()
    ->Iterations(1);
BENCHMARK_CAPTURE(BM_GmshStrip_a1_1, lg_aa, "lg-aa")
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime()
    ->Iterations(1);
BENCHMARK_CAPTURE(BM_GmshStrip_a1_5, newton, "newton")
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime()
    ->Iterations(1);
BENCHMARK_CAPTURE(BM_GmshStrip_a1_5, lg_aa, "lg-aa")
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime()
    ->Iterations(1);
BENCHMARK_CAPTURE(BM_Finger, newton, "newton")
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime()
    ->Iterations(1);
BENCHMARK_CAPTURE(BM_Finger, lg_aa, "lg-aa")
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime()
    ->Iterations(1);
BENCHMARK_CAPTURE(BM_FingerRes12Alpha10, newton, "newton")
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime()
    ->Iterations(1);
BENCHMARK_CAPTURE(BM_FingerRes12Alpha10, lg_aa, "lg-aa")
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime()
    ->Iterations(1);
BENCHMARK_CAPTURE(BM_ThreeChamber, newton, "newton")
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime()
    ->Iterations(1);
BENCHMARK_CAPTURE(BM_ThreeChamber, lg_aa, "lg-aa")
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime()
    ->Iterations(1);
BENCHMARK_CAPTURE(BM_Strip12k_a1_1, auto, "auto") -> Unit(benchmark::kMillisecond) -> UseRealTime()
    -> Iterations(1);
BENCHMARK_CAPTURE(BM_Strip12k_a1_5, auto, "auto") -> Unit(benchmark::kMillisecond) -> UseRealTime()
    -> Iterations(1);
BENCHMARK_CAPTURE(BM_Finger, auto, "auto") -> Unit(benchmark::kMillisecond) -> UseRealTime()
    -> Iterations(1);
BENCHMARK_CAPTURE(BM_FingerRes12Alpha10, auto, "auto") -> Unit(benchmark::kMillisecond)
    -> UseRealTime() -> Iterations(1);
BENCHMARK_CAPTURE(BM_ThreeChamber, auto, "auto") -> Unit(benchmark::kMillisecond) -> UseRealTime()
    -> Iterations(1);
BENCHMARK_CAPTURE(BM_Manipulator_r8, newton, "newton")
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime()
    ->Iterations(1);
BENCHMARK_CAPTURE(BM_Manipulator_r8, lg_aa, "lg-aa")
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime()
    ->Iterations(1);
BENCHMARK_CAPTURE(BM_Manipulator_r8, auto, "auto") -> Unit(benchmark::kMillisecond) -> UseRealTime()
    -> Iterations(1);
BENCHMARK_CAPTURE(BM_Manipulator_r10, newton, "newton")
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime()
    ->Iterations(1);
BENCHMARK_CAPTURE(BM_Manipulator_r10, lg_aa, "lg-aa")
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime()
    ->Iterations(1);
BENCHMARK_CAPTURE(BM_Manipulator_r10, auto, "auto") -> Unit(benchmark::kMillisecond)
    -> UseRealTime() -> Iterations(1);
BENCHMARK_CAPTURE(BM_CableFinger, lg_aa, "lg-aa")
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime()
    ->Iterations(1);
BENCHMARK_CAPTURE(BM_CableFinger, auto, "auto") -> Unit(benchmark::kMillisecond) -> UseRealTime()
    -> Iterations(1);

}  // namespace
}  // namespace softkin

BENCHMARK_MAIN();
