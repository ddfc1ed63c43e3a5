// Google Benchmark suite for collision detection (solver/collision/collision.hpp, thesis
// Sec. 3.2.2).
//
// The meshes are pneumatic_finger at resolution `res` (cells across the 20 mm width, 27 res^3
// tets). The deformed configuration is the one bench_fk uses: alpha = 3 on the chamber, 40 lg-aa
// iterations from rest (the finger bends but does not touch itself). Benchmarks:
//   BM_SelfCollision             one pass (Update + Detect) per broad phase (method) and size
//   BM_SelfCollisionPenetrating  the same on a state with many contacts (the finger's far half
//                                pushed back 24.5 mm into the near half), res 12
//   BM_ObstacleContacts          DetectObstacleContacts on every vertex, with an obstacle at the
//                                tip and one far away
// Counters: tets, boundary_vertices, build_ms and query_ms (means of last_build_s and
// last_query_s), contacts, narrow_tests and exact_tests (of the last pass), and vs_box: the
// mean pass time over that of the box-intersection method at the same size in this run
// (registered first). All timings are wall-clock (UseRealTime): the passes use OpenMP.
//
// See docs/benchmarks.md (section "Self-collision detection") for how to run them and results.
#include "softkin/solver/collision/collision.hpp"
#include "softkin/solver/factory/fk_factory.hpp"
#include "softkin/solver/fk/fk_solver.hpp"
#include "softkin/solver/fk/model.hpp"
#include "softkin/solver/robots/robots.hpp"

#include <benchmark/benchmark.h>
#include <omp.h>

#include <algorithm>
#include <cstdio>
#include <map>
#include <memory>
#include <string>
#include <vector>

namespace softkin {
namespace {

constexpr const char* kRobot = "pneumatic_finger";
/// Resolutions of the sweep: 5.8k, 19.7k and 46.7k tets.
const std::vector<int> kResolutions = {6, 9, 12};
/// Actuation (chamber volume ratio) and lg-aa iterations of the deformed configuration (as in
/// bench_fk).
constexpr double kAlpha = 3.0;
constexpr int kSetupIterations = 40;

using Method = SelfCollisionDetector::Method;
const Method kMethods[] = {Method::kBoxIntersection, Method::kAabbTree, Method::kGrid};

/// A mesh and its deformed positions, built once per resolution.
struct Fixture {
  int res = 0;
  std::shared_ptr<const Model> model;
  Eigen::MatrixX3d X;  ///< #V x 3 deformed positions (mm)
};

const Fixture& GetFixture(int res) {
  static std::map<int, std::unique_ptr<Fixture>> cache;
  auto it = cache.find(res);
  if (it != cache.end()) return *it->second;
  auto f = std::make_unique<Fixture>();
  f->res = res;
  f->model = std::make_shared<const Model>(MakeRobot(kRobot, res));
  Eigen::VectorXd c = f->model->scene().rest_actuation();
  c[0] = kAlpha;
  FkOptions opts = f->model->scene().solver;
  opts.solver = FkSolverType::kLgAa;
  opts.max_iterations = kSetupIterations;
  opts.continuation_steps = 1;
  const FkResult r = MakeFkSolver(f->model, opts)->Solve(c);
  f->X = r.positions;
  std::fprintf(stderr, "[fixture] res %d: %d tets, %d vertices; setup solve %s\n", res,
               f->model->scene().mesh.num_elements(), f->model->num_vertices(),
               r.BriefReport().c_str());
  return *cache.emplace(res, std::move(f)).first->second;
}

/// Rest positions with every vertex past the middle of the length (x) moved by (-24.5, 0.35,
/// 0.25) mm: the far half overlaps the near half. The offset is not a multiple of the mesh
/// spacing and leaves the y and z planes, so that the contacts are generic (a pure x shift puts
/// boundary vertices exactly on the edges of the stretched tets at the cut: every contact then
/// needs the exact predicate).
Eigen::MatrixX3d PenetratingState(const Mesh& m) {
  Eigen::MatrixX3d X = m.vertices;
  const double lo = X.col(0).minCoeff(), hi = X.col(0).maxCoeff();
  for (int v = 0; v < X.rows(); ++v)
    if (X(v, 0) > 0.5 * (lo + hi)) X.row(v) += Eigen::RowVector3d(-24.5, 0.35, 0.25);
  return X;
}

/// Times Update(X) + Detect() and sets the counters; `key` identifies the size for vs_box.
void RunPasses(benchmark::State& state, const Mesh& mesh, const Eigen::MatrixX3d& X, Method method,
               const std::string& key) {
  SelfCollisionDetector d(mesh, method);
  static std::map<std::string, double> box_time;
  double build = 0, query = 0;
  size_t contacts = 0;
  int64_t n = 0;
  for (auto _ : state) {
    d.Update(X);
    contacts = d.Detect().size();
    build += d.last_build_s();
    query += d.last_query_s();
    ++n;
  }
  n = std::max<int64_t>(n, 1);
  const double pass = (build + query) / n;
  state.SetLabel(SelfCollisionMethodToString(method));
  state.counters["tets"] = mesh.num_elements();
  state.counters["boundary_vertices"] = static_cast<double>(d.boundary_vertices().size());
  state.counters["build_ms"] = 1e3 * build / n;
  state.counters["query_ms"] = 1e3 * query / n;
  state.counters["contacts"] = static_cast<double>(contacts);
  state.counters["narrow_tests"] = static_cast<double>(d.last_narrow_tests());
  state.counters["exact_tests"] = static_cast<double>(d.last_exact_tests());
  if (method == Method::kBoxIntersection) box_time[key] = pass;
  if (box_time.count(key)) state.counters["vs_box"] = pass / box_time[key];
}

/// Self-collision detection at the deformed positions, by each method (range 1: 0 box
/// intersection, 1 AABB tree, 2 grid), same exact answer.
void BM_SelfCollision(benchmark::State& state) {
  const Fixture& f = GetFixture(static_cast<int>(state.range(0)));
  RunPasses(state, f.model->scene().mesh, f.X, kMethods[state.range(1)],
            "res" + std::to_string(f.res));
}

void MethodResolutionSweep(benchmark::internal::Benchmark* b) {
  b->ArgNames({"res", "method"});
  for (int r : kResolutions)
    for (int m = 0; m < 3; ++m) b->Args({r, m});  // box intersection first: the reference of vs_box
}
BENCHMARK(BM_SelfCollision)
    ->Apply(MethodResolutionSweep)
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();

/// The same on a penetrating state (560 contacts at res 12).
void BM_SelfCollisionPenetrating(benchmark::State& state) {
  const Fixture& f = GetFixture(static_cast<int>(state.range(0)));
  const Mesh& mesh = f.model->scene().mesh;
  RunPasses(state, mesh, PenetratingState(mesh), kMethods[state.range(1)],
            "penetrating res" + std::to_string(f.res));
}
BENCHMARK(BM_SelfCollisionPenetrating)
    ->ArgNames({"res", "method"})
    ->Args({12, 0})
    ->Args({12, 1})
    ->Args({12, 2})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();

/// DetectObstacleContacts on every vertex of the deformed finger: a box obstacle over the last
/// 10 mm of the rest length, which the bent tip reaches into (range 1 = 1), or far away
/// (range 1 = 0, every vertex rejected by the bounding box).
void BM_ObstacleContacts(benchmark::State& state) {
  const Fixture& f = GetFixture(static_cast<int>(state.range(0)));
  const Eigen::MatrixX3d& X = f.X;
  const Eigen::Vector3d lo = X.colwise().minCoeff().transpose(),
                        hi = X.colwise().maxCoeff().transpose();
  std::vector<Obstacle> obs;
  if (state.range(1)) {
    const Eigen::Vector3d tip_lo(hi.x() - 10.0, lo.y() - 50.0, lo.z() - 50.0);
    obs.emplace_back(
        MakeBoxSurface(tip_lo, Eigen::Vector3d(hi.x() + 50.0, hi.y() + 50.0, hi.z() + 50.0)));
  } else {
    obs.emplace_back(
        MakeBoxSurface(hi + Eigen::Vector3d(100, 100, 100), hi + Eigen::Vector3d(150, 150, 150)));
  }
  size_t contacts = 0;
  for (auto _ : state) contacts = DetectObstacleContacts(obs, X).size();
  state.counters["vertices"] = static_cast<double>(X.rows());
  state.counters["contacts"] = static_cast<double>(contacts);
}
BENCHMARK(BM_ObstacleContacts)
    ->ArgNames({"res", "near"})
    ->Args({12, 0})
    ->Args({12, 1})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();

}  // namespace
}  // namespace softkin

int main(int argc, char** argv) {
  benchmark::Initialize(&argc, argv);
  if (benchmark::ReportUnrecognizedArguments(argc, argv)) return 1;
  benchmark::AddCustomContext("omp_max_threads", std::to_string(omp_get_max_threads()));
  benchmark::AddCustomContext("robot", softkin::kRobot);
  benchmark::RunSpecifiedBenchmarks();
  benchmark::Shutdown();
  return 0;
}
