// Google Benchmark suite for mesh generation (thesis Table 3.1, first column): the volume
// tessellation T(S_c, S_b) of the twisting robot (solver/remesh/tessellation.hpp) and a progressive
// remesh of its chamber (solver/remesh/remesh.hpp, Algorithm 2).
//
// Robot: twisting_robot with the Ch. 2 shape-blending body (hyperelastic = 0), at resolution `res`
// (cell size 8/res mm; res 4 has 29,156 tets, like the thesis's 28,198). Benchmarks:
//   BM_Tessellate      T(S_c, S_b) from the robot's generated surfaces, seeded (the robot's build
//                      without its scene setup)
//   BM_ChamberRemesh   RemeshChamber (auto: chamber-only, else whole) of the state solved at
//                      alpha = 4 from rest (the first state of Algorithm 2's ladder, where the
//                      remeshing test fires), for each chamber rest (range 1: 0 remeshed, the
//                      default; 1 original, pulled back)
// Counters: tets (input), tets_after, chamber_tets_after, whole (1 if the whole robot was
// re-tessellated), vs_remeshed (BM_ChamberRemesh: time over that of the remeshed rest at the same
// size in this run, registered first), and thesis_over_ours: Table 3.1's 2.81 s of mesh generation
// per step at 28,198 tets over the time of one call (res 4 only).
//
// See docs/benchmarks.md (section "Mesh generation") for how to run them and results.
#include "softkin/solver/factory/fk_factory.hpp"
#include "softkin/solver/fk/fk_solver.hpp"
#include "softkin/solver/fk/model.hpp"
#include "softkin/solver/remesh/remesh.hpp"
#include "softkin/solver/robots/robot_twisting.hpp"
#include "softkin/solver/robots/robots.hpp"
#include "softkin/solver/remesh/tessellation.hpp"
#include "softkin/solver/common/stopwatch.hpp"

#include <benchmark/benchmark.h>

#include <chrono>
#include <cstdint>
#include <cstdio>
#include <map>
#include <memory>
#include <string>
#include <vector>

namespace softkin {
namespace {

const RobotParams kParams = {{"hyperelastic", 0.0}};
/// Resolutions of the sweep: 6.2k, 10.8k and 29.2k tets.
const std::vector<int64_t> kResolutions = {1, 2, 4};
constexpr double kAlpha = 4.0;
/// Table 3.1, twisting robot: mesh generation per step, s, at 28,198 tets.
constexpr double kThesisMeshGenS = 2.81;
constexpr int kThesisRes = 4;

/// The robot and its state at alpha = 4, built once per resolution.
struct Fixture {
  Scene scene;
  Eigen::MatrixX3d X;
};

const Fixture& GetFixture(int res) {
  static std::map<int, std::unique_ptr<Fixture>> cache;
  auto it = cache.find(res);
  if (it != cache.end()) return *it->second;
  auto f = std::make_unique<Fixture>();
  f->scene = MakeRobot("twisting_robot", res, kParams);
  Eigen::VectorXd c = f->scene.rest_actuation();
  c[0] = kAlpha;
  const FkResult r =
      MakeFkSolver(std::make_shared<const Model>(f->scene), f->scene.solver)->Solve(c);
  f->X = r.positions;
  const RemeshCheck chk =
      CheckRemesh(f->scene.mesh, f->scene.mesh.vertices, f->X, f->scene.actuators[0].regions);
  std::fprintf(stderr,
               "[fixture] res %d: %d tets; alpha %g: %s; remesh test %s (volume ratio %.2f, "
               "distortion %.2f)\n",
               res, f->scene.mesh.num_tets(), kAlpha, r.BriefReport().c_str(),
               chk.needed ? "fires" : "quiet", chk.max_volume_ratio, chk.max_distortion);
  return *cache.emplace(res, std::move(f)).first->second;
}

void BM_Tessellate(benchmark::State& state) {
  const int res = static_cast<int>(state.range(0));
  TriangleSurface chamber, body;
  TwistingRobotSurfaces(kParams, &chamber, &body);
  TessellationOptions opt = TwistingRobotTessellation(res, kParams);
  opt.seed = 1;
  int tets = 0;
  double seconds = 0;
  int64_t n = 0;
  for (auto _ : state) {
    const auto t0 = std::chrono::steady_clock::now();
    const Mesh m = Tessellate(chamber, body, opt);
    seconds += SecondsSince(t0);
    tets = m.num_tets();
    ++n;
  }
  state.counters["tets"] = tets;
  if (res == kThesisRes && n > 0)
    state.counters["thesis_over_ours"] = kThesisMeshGenS / (seconds / n);
}
BENCHMARK(BM_Tessellate)
    ->ArgsProduct({kResolutions})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime()
    ->Iterations(2);

void BM_ChamberRemesh(benchmark::State& state) {
  const int res = static_cast<int>(state.range(0));
  const ChamberRest rest = state.range(1) == 0 ? ChamberRest::Remeshed : ChamberRest::Original;
  const Fixture& f = GetFixture(res);
  ChamberRemeshOptions opt;
  opt.rest = rest;
  opt.region.seed = 1;
  opt.tessellation = TwistingRobotTessellation(res, kParams);
  opt.tessellation.seed = 1;
  static std::map<int, double> remeshed_time;
  ChamberRemesh last;
  double seconds = 0;
  int64_t n = 0;
  for (auto _ : state) {
    try {
      last = RemeshChamber(f.scene, f.X, opt);
    } catch (const std::runtime_error& e) {
      state.SkipWithError(e.what());
      return;
    }
    seconds += last.seconds;
    ++n;
  }
  n = std::max<int64_t>(n, 1);
  state.SetLabel(ChamberRestToString(rest));
  state.counters["tets"] = f.scene.mesh.num_tets();
  state.counters["tets_after"] = last.scene.mesh.num_tets();
  state.counters["chamber_tets_after"] = last.chamber_tets_after;
  state.counters["whole"] = last.method == RemeshMethod::Whole ? 1 : 0;
  if (rest == ChamberRest::Remeshed) remeshed_time[res] = seconds / n;
  if (remeshed_time.count(res)) state.counters["vs_remeshed"] = (seconds / n) / remeshed_time[res];
  if (res == kThesisRes) state.counters["thesis_over_ours"] = kThesisMeshGenS / (seconds / n);
}
BENCHMARK(BM_ChamberRemesh)
    ->ArgsProduct({kResolutions, {0, 1}})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime()
    ->Iterations(2);

}  // namespace
}  // namespace softkin

BENCHMARK_MAIN();
