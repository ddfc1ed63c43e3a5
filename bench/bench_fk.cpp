// Google Benchmark suite for the forward-kinematics solver (local-global + Anderson acceleration).
//
// Every benchmark except BM_FullBend sweeps the pneumatic_finger resolution (the `res` argument:
// cells across the 20 mm width, 27 res^3 tets for the 120 x 20 x 15 mm finger) and reports the
// counters
//   tets, vertices, free      mesh size (elements, vertices, non-fixed vertices)
//   per_vertex                wall time per vertex (per iteration of the benchmark)
//   per_tet                   wall time per element (element loops only)
// All timings are wall-clock (UseRealTime): the local step and the passes run with OpenMP.
//
// See docs/benchmarks.md for what each benchmark measures and how to run them.
#include "softkin/solver/fk/anderson.hpp"
#include "softkin/solver/factory/fk_factory.hpp"
#include "softkin/solver/fk/fk_solver.hpp"
#include "softkin/solver/fk/local_global.hpp"
#include "softkin/solver/fk/model.hpp"
#include "softkin/solver/robots/robots.hpp"
#include "softkin/solver/fk/rotation.hpp"
#include "softkin/solver/fk/targets.hpp"
#include "softkin/solver/mesh/io/mesh_io.hpp"
#include "softkin/solver/common/stopwatch.hpp"

#include <benchmark/benchmark.h>
#include <omp.h>

#include <algorithm>
#include <cmath>
#include <chrono>
#include <cstdio>
#include <functional>
#include <map>
#include <memory>
#include <random>
#include <string>
#include <vector>

namespace softkin {
namespace {

using Clock = std::chrono::steady_clock;
constexpr const char* kRobot = "pneumatic_finger";
/// Resolutions of the sweep: 6.5k, 13.8k, 28.8k, 46.7k, 77.6k and 163k tets.
const std::vector<int> kResolutions = {6, 8, 10, 12, 14, 18};
/// Actuation (chamber volume ratio) of the deformed configuration used by the per-step benchmarks.
constexpr double kAlpha = 3.0;
/// Local-global iterations (lg-aa, from rest) used to reach that deformed configuration.
constexpr int kSetupIterations = 40;

/// Everything a per-step benchmark needs for one resolution, built once and cached.
struct Fixture {
  int res = 0;
  std::shared_ptr<const Model> model;
  Eigen::VectorXd c;               ///< actuation of the deformed configuration
  Eigen::MatrixX3d X;              ///< deformed positions (#V x 3), a partly converged lg-aa solve
  Eigen::VectorXd rhs_free;        ///< B_f - A_fc X_c at X: the right-hand side of the global step
  std::vector<Eigen::Matrix3d> M;  ///< per-element cross-covariance D^T P at X
  int tets = 0, vertices = 0, free = 0;
};

const Fixture& GetFixture(int res) {
  static std::map<int, std::unique_ptr<Fixture>> cache;
  auto it = cache.find(res);
  if (it != cache.end()) return *it->second;

  auto f = std::make_unique<Fixture>();
  f->res = res;
  f->model = std::make_shared<const Model>(MakeRobot(kRobot, res));
  const Model& m = *f->model;
  f->tets = static_cast<int>(m.elements().size());
  f->vertices = m.num_vertices();
  f->free = m.num_free();

  f->c = m.scene().rest_actuation();
  f->c[0] = kAlpha;
  FkOptions opts = m.scene().solver;
  opts.solver = FkSolverType::kLgAa;
  opts.max_iterations = kSetupIterations;
  opts.continuation_steps = 1;
  auto solver = MakeFkSolver(f->model, opts);
  const FkResult r = solver->Solve(f->c);
  f->X = r.positions;

  // Right-hand side of the global step at X (as in LocalGlobalSolver).
  std::vector<double> ratios;
  std::vector<ElemRows> weighted;
  Eigen::MatrixX3d B;
  ComputeLocalRatios(m, f->X, f->c, &ratios);
  LocalStep(m, f->X, ratios, &weighted);
  AssembleRhs(m, weighted, &B);
  Eigen::MatrixX3d Xc = Eigen::MatrixX3d::Zero(m.num_vertices(), 3);
  m.ApplyConstraints(f->c, &Xc);
  Eigen::VectorXd Cfix;
  m.GatherFree(m.A() * Xc, &Cfix);
  m.GatherFree(B, &f->rhs_free);
  f->rhs_free -= Cfix;

  // Cross-covariances M_i = D_i^T P_i (current centred rows vs rest centred rows), as in the
  // local step.
  f->M.resize(m.elements().size());
  for (size_t i = 0; i < m.elements().size(); ++i) {
    const ModelElement& e = m.elements()[i];
    ElemRows D;
    for (int j = 0; j < e.k; ++j) D.row(j) = f->X.row(e.v[j]);
    CenterRows(D, e.k);
    f->M[i] = D.topRows(e.k).transpose() * e.rest.topRows(e.k);
  }
  std::fprintf(stderr, "[fixture] res %d: %d tets, %d vertices (%d free); setup solve %s\n", res,
               f->tets, f->vertices, f->free, r.BriefReport().c_str());
  return *cache.emplace(res, std::move(f)).first->second;
}

void SizeCounters(benchmark::State& state, const Fixture& f, bool per_tet, bool per_vertex = true) {
  state.counters["tets"] = f.tets;
  state.counters["vertices"] = f.vertices;
  state.counters["free"] = f.free;
  // Rate counters with kInvert: seconds per vertex / per tet of one benchmark iteration.
  if (per_vertex)
    state.counters["per_vertex"] = benchmark::Counter(
        f.vertices, benchmark::Counter::kIsIterationInvariantRate | benchmark::Counter::kInvert);
  if (per_tet)
    state.counters["per_tet"] = benchmark::Counter(
        f.tets, benchmark::Counter::kIsIterationInvariantRate | benchmark::Counter::kInvert);
}

/// One pass of a 3x3 rotation fit over all cross-covariances, parallelised like the local step
/// (threads = 0: OpenMP default). Returns a checksum so the work cannot be optimised away.
template <class Fit>
double RotationPass(const std::vector<Eigen::Matrix3d>& M, int threads, Fit fit) {
  const int n = static_cast<int>(M.size());
  const int nt = threads > 0 ? threads : omp_get_max_threads();
  double sink = 0.0;
#pragma omp parallel for schedule(static) reduction(+ : sink) num_threads(nt)
  for (int i = 0; i < n; ++i) {
    const Eigen::Matrix3d R = fit(M[i]);
    sink += R(0, 0) + R(1, 1) + R(2, 2);
  }
  return sink;
}
double SvdPass(const std::vector<Eigen::Matrix3d>& M, int threads) {
  return RotationPass(M, threads, [](const Eigen::Matrix3d& A) { return BestRotationSvd(A); });
}
double PolarPass(const std::vector<Eigen::Matrix3d>& M, int threads) {
  return RotationPass(M, threads, [](const Eigen::Matrix3d& A) { return BestRotation(A); });
}
double PolarBatchPass(const std::vector<Eigen::Matrix3d>& M, int threads) {
  const int n = static_cast<int>(M.size());
  const int nt = threads > 0 ? threads : omp_get_max_threads();
  const int nb = (n + kRotationBatch - 1) / kRotationBatch;
  double sink = 0.0;
#pragma omp parallel for schedule(static) reduction(+ : sink) num_threads(nt)
  for (int b = 0; b < nb; ++b) {
    Eigen::Matrix3d R[kRotationBatch];
    const int i0 = b * kRotationBatch, m = std::min(kRotationBatch, n - i0);
    BestRotations(M.data() + i0, m, R);
    for (int l = 0; l < m; ++l) sink += R[l](0, 0) + R[l](1, 1) + R[l](2, 2);
  }
  return sink;
}
double PolarEigenPass(const std::vector<Eigen::Matrix3d>& M, int threads) {
  return RotationPass(M, threads, [](const Eigen::Matrix3d& A) { return BestRotationEigen(A); });
}

double Median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  const size_t n = v.size();
  return n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

/// Baseline of one iteration: the bare global solve (3 RHS) + the bare SVD pass (default threads),
/// and, for the stricter ratio against the solver's own rotation fit, the batched polar pass
/// (BestRotations, as in the local step). `iteration`
/// (optional) times one sample of the iteration being compared; it is interleaved with the
/// baseline passes so that load changes on a shared machine hit both sides alike. Medians of
/// `reps` repetitions after one warm-up.
struct Baseline {
  double solve_s = 0, svd_s = 0, polar_s = 0, iter_s = 0;
  double total() const { return solve_s + svd_s; }
  double total_polar() const { return solve_s + polar_s; }
};
Baseline MeasureBaseline(const Fixture& f, const std::function<double()>& iteration, int reps = 7) {
  std::vector<double> ts, tv, tp, ti;
  benchmark::DoNotOptimize(f.model->SolveFree(f.rhs_free));
  benchmark::DoNotOptimize(SvdPass(f.M, 0));
  benchmark::DoNotOptimize(PolarBatchPass(f.M, 0));
  if (iteration) iteration();
  for (int k = 0; k < reps; ++k) {
    auto t0 = Clock::now();
    Eigen::VectorXd Y = f.model->SolveFree(f.rhs_free);
    benchmark::DoNotOptimize(Y.data());
    ts.push_back(SecondsSince(t0));
    t0 = Clock::now();
    double s = SvdPass(f.M, 0);
    benchmark::DoNotOptimize(s);
    tv.push_back(SecondsSince(t0));
    t0 = Clock::now();
    s = PolarBatchPass(f.M, 0);
    benchmark::DoNotOptimize(s);
    tp.push_back(SecondsSince(t0));
    if (iteration) ti.push_back(iteration());
  }
  return {Median(ts), Median(tv), Median(tp), ti.empty() ? 0.0 : Median(ti)};
}

void BaselineCounters(benchmark::State& state, const Baseline& b) {
  state.counters["base_solve_ms"] = 1e3 * b.solve_s;
  state.counters["base_svd_ms"] = 1e3 * b.svd_s;
  state.counters["base_polar_ms"] = 1e3 * b.polar_s;
  state.counters["iter_ms"] = 1e3 * b.iter_s;
  state.counters["ratio_to_baseline"] = b.iter_s / b.total();
  state.counters["ratio_to_polar_base"] = b.iter_s / b.total_polar();
}

FkOptions OneIterationOptions(const Model& m, int max_iterations) {
  FkOptions o = m.scene().solver;
  o.solver = FkSolverType::kLgAa;
  o.max_iterations = max_iterations;
  o.tolerance = 1e-300;  // never converge: every call runs exactly max_iterations iterations
  o.gradient_tolerance = 1e-300;
  o.continuation_steps = 1;
  o.threads = 0;
  return o;
}

void ResolutionSweep(benchmark::internal::Benchmark* b) {
  b->ArgName("res");
  for (int r : kResolutions) b->Arg(r);
}
void ResolutionThreadSweep(benchmark::internal::Benchmark* b) {
  b->ArgNames({"res", "threads"});
  for (int r : kResolutions)
    for (int t : {1, 0}) b->Args({r, t});
}

// ---- benchmarks --------------------------------------------------------------------------------

/// Model construction: element constants, assembly of A, A_ff, A_fc, CHOLMOD analyse + factor.
/// Reading the thesis group's real finger mesh (data/thesis/finger_chamber1.tet, 94,240 tets, with
/// its region labels): parsing, orientation and the topology checks (folds, cracks, duplicates).
void BM_ReadTetFingerChamber(benchmark::State& state) {
  const std::string dir = SOFTKIN_THESIS_DATA;
  for (auto _ : state) {
    const Mesh m = ReadTet(dir + "/finger_chamber1.tet", dir + "/finger_chamber1_labels.txt");
    benchmark::DoNotOptimize(m.elements.data());
  }
}
BENCHMARK(BM_ReadTetFingerChamber)->Unit(benchmark::kMillisecond)->UseRealTime();

void BM_Factorization(benchmark::State& state) {
  const Fixture& f = GetFixture(static_cast<int>(state.range(0)));
  const Scene scene = f.model->scene();
  double factor_s = 0.0;
  for (auto _ : state) {
    Model m(scene);
    factor_s += m.factor_time_s();
    benchmark::DoNotOptimize(&m);
  }
  SizeCounters(state, f, false);
  state.counters["factor_s"] = benchmark::Counter(factor_s, benchmark::Counter::kAvgIterations);
  state.counters["nnz_Aff"] = static_cast<double>(f.model->A_ff().nonZeros());
}
BENCHMARK(BM_Factorization)->Apply(ResolutionSweep)->Unit(benchmark::kMillisecond)->UseRealTime();

/// Local step: per-element local ratios, then targets (best rotation + blending) and energy.
void BM_LocalStep(benchmark::State& state) {
  const Fixture& f = GetFixture(static_cast<int>(state.range(0)));
  const Model& m = *f.model;
  std::vector<double> ratios;
  std::vector<ElemRows> weighted;
  ComputeLocalRatios(m, f.X, f.c, &ratios);
  LocalStep(m, f.X, ratios, &weighted);  // allocate outside the loop
  for (auto _ : state) {
    ComputeLocalRatios(m, f.X, f.c, &ratios);
    double E = LocalStep(m, f.X, ratios, &weighted);
    benchmark::DoNotOptimize(E);
  }
  SizeCounters(state, f, true);
}
BENCHMARK(BM_LocalStep)->Apply(ResolutionSweep)->Unit(benchmark::kMillisecond)->UseRealTime();

/// The local step with the finger's body as Ch. 2 blend (law 0) or hyperelastic Ecoflex 00-30
/// (law 1, Eq. 3.6-3.7: a deformation gradient, its strain and a volume rescale per element), at
/// the same deformed positions. Counter law_cost: time over the blend's, measured in this run.
void BM_LocalStepLaw(benchmark::State& state) {
  const Fixture& f = GetFixture(static_cast<int>(state.range(0)));
  static std::map<int, std::shared_ptr<const Model>> hyper;
  auto& hm = hyper[f.res];
  if (!hm) {
    Scene s = f.model->scene();
    for (auto& [tag, mat] : s.body)
      mat = Material{"ecoflex-00-30", 1.0, mat.weight, MaterialLaw::kMooneyRivlin, 0.0418, 0.0106};
    hm = std::make_shared<const Model>(s);
  }
  static std::map<int, double> blend_time;
  const Model& m = state.range(1) ? *hm : *f.model;
  std::vector<double> ratios;
  std::vector<ElemRows> weighted;
  ComputeLocalRatios(m, f.X, f.c, &ratios);
  LocalStep(m, f.X, ratios, &weighted);
  const auto t0 = Clock::now();
  int64_t n = 0;
  for (auto _ : state) {
    double E = LocalStep(m, f.X, ratios, &weighted);
    benchmark::DoNotOptimize(E);
    ++n;
  }
  const double per = SecondsSince(t0) / std::max<int64_t>(n, 1);
  if (!state.range(1)) blend_time[f.res] = per;
  if (state.range(1) && blend_time.count(f.res))
    state.counters["law_cost"] = per / blend_time[f.res];
  SizeCounters(state, f, true);
}
BENCHMARK(BM_LocalStepLaw)
    ->ArgNames({"res", "law"})
    ->Args({12, 0})
    ->Args({12, 1})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();

/// The hyperelastic target's volume guard (HyperelasticBlendWeight, Eq. 3.6-3.7) on inverted
/// tets, where it searches for the blend weight that lifts the blend's volume to the floor.
/// method 0: the library's (the volume sampled four times, then Newton's method on that cubic,
/// kept inside [rho, 1]); method 1: the former method, a bisection that re-blends the element and
/// takes its volume at every halving. Counter over_cubic: method 1's time over method 0's in
/// this run; max_dt: the largest difference of the two weights.
void BM_HyperelasticGuard(benchmark::State& state) {
  constexpr int kTets = 4096;
  static std::vector<ElemRows> Rr, D;
  static std::vector<double> rest;
  if (Rr.empty()) {
    std::mt19937 rng(7);
    std::uniform_real_distribution<double> u(-1.0, 1.0), depth(0.9, 2.5);
    for (int i = 0; i < kTets; ++i) {
      ElemRows P = ElemRows::Zero();
      P.row(1) = Eigen::RowVector3d(10, 0, 0);
      P.row(2) = Eigen::RowVector3d(0, 10, 0);
      P.row(3) = Eigen::RowVector3d(0, 0, 10);
      for (int j = 0; j < 4; ++j) P.row(j) += 0.5 * Eigen::RowVector3d(u(rng), u(rng), u(rng));
      CenterRows(P, 4);
      // The current shape: vertex 0 pushed through the opposite face (flat to fully inverted).
      ElemRows X = P;
      const Eigen::RowVector3d f = (X.row(1) + X.row(2) + X.row(3)) / 3.0;
      X.row(0) = f + (1.0 - depth(rng)) * (X.row(0) - f);
      CenterRows(X, 4);
      Rr.push_back(P);  // its rotated rest shape (any rotation: the guard only blends)
      D.push_back(X);
      rest.push_back(RowsVolume(P, 4));
    }
  }
  const double rho = 0.1;
  auto reference = [&](int i) {
    auto volume = [&](double t) {
      ElemRows B = ElemRows::Zero();
      B.topRows(4) = t * Rr[i].topRows(4) + (1.0 - t) * D[i].topRows(4);
      return RowsVolume(B, 4);
    };
    const double floor = kMinBlendVolume * rest[i];
    if (volume(rho) >= floor) return rho;
    double lo = rho, hi = 1.0;
    for (int it = 0; it < 50; ++it) {
      const double mid = 0.5 * (lo + hi);
      (volume(mid) < floor ? lo : hi) = mid;
    }
    return hi;
  };
  const bool ref = state.range(0) == 1;
  static double cubic_time = 0;
  const auto t0 = Clock::now();
  int64_t n = 0;
  for (auto _ : state) {
    double sum = 0;
    for (int i = 0; i < kTets; ++i)
      sum += ref ? reference(i) : HyperelasticBlendWeight(Rr[i], D[i], 4, rho, rest[i]);
    benchmark::DoNotOptimize(sum);
    ++n;
  }
  const double per = SecondsSince(t0) / std::max<int64_t>(n, 1);
  if (!ref) cubic_time = per;
  if (ref && cubic_time > 0) state.counters["over_cubic"] = per / cubic_time;
  double max_dt = 0;
  for (int i = 0; i < kTets; ++i)
    max_dt = std::max(
        max_dt, std::abs(reference(i) - HyperelasticBlendWeight(Rr[i], D[i], 4, rho, rest[i])));
  state.counters["max_dt"] = max_dt;
  state.counters["ns_per_tet"] = 1e9 * per / kTets;
}
BENCHMARK(BM_HyperelasticGuard)
    ->ArgNames({"method"})
    ->Arg(0)
    ->Arg(1)
    ->Unit(benchmark::kMicrosecond)
    ->UseRealTime();

/// Right-hand side gather sum_i w_i Vol_i S_i^T T_i (#V x 3).
void BM_AssembleRhs(benchmark::State& state) {
  const Fixture& f = GetFixture(static_cast<int>(state.range(0)));
  const Model& m = *f.model;
  std::vector<double> ratios;
  std::vector<ElemRows> weighted;
  ComputeLocalRatios(m, f.X, f.c, &ratios);
  LocalStep(m, f.X, ratios, &weighted);
  Eigen::MatrixX3d B(m.num_vertices(), 3);
  for (auto _ : state) {
    AssembleRhs(m, weighted, &B);
    benchmark::DoNotOptimize(B.data());
    benchmark::ClobberMemory();
  }
  SizeCounters(state, f, false);
}
BENCHMARK(BM_AssembleRhs)->Apply(ResolutionSweep)->Unit(benchmark::kMicrosecond)->UseRealTime();

/// Global step: the prefactored CHOLMOD solve A_ff Y = rhs with #free x 3 right-hand sides.
void BM_GlobalSolve(benchmark::State& state) {
  const Fixture& f = GetFixture(static_cast<int>(state.range(0)));
  for (auto _ : state) {
    Eigen::VectorXd Y = f.model->SolveFree(f.rhs_free);
    benchmark::DoNotOptimize(Y.data());
  }
  SizeCounters(state, f, false);
}
BENCHMARK(BM_GlobalSolve)->Apply(ResolutionSweep)->Unit(benchmark::kMillisecond)->UseRealTime();

/// Bare SVD pass: BestRotationSvd (3x3 JacobiSVD) over every element's precomputed D^T P.
/// threads = 1: serial; threads = 0: OpenMP default (what the local step uses).
void BM_SvdPass(benchmark::State& state) {
  const Fixture& f = GetFixture(static_cast<int>(state.range(0)));
  const int threads = static_cast<int>(state.range(1));
  for (auto _ : state) benchmark::DoNotOptimize(SvdPass(f.M, threads));
  SizeCounters(state, f, true);
}
BENCHMARK(BM_SvdPass)->Apply(ResolutionThreadSweep)->Unit(benchmark::kMillisecond)->UseRealTime();

/// The same pass with BestRotation (closed-form polar factor used by the solver).
void BM_PolarPass(benchmark::State& state) {
  const Fixture& f = GetFixture(static_cast<int>(state.range(0)));
  const int threads = static_cast<int>(state.range(1));
  for (auto _ : state) benchmark::DoNotOptimize(PolarPass(f.M, threads));
  SizeCounters(state, f, true);
}
BENCHMARK(BM_PolarPass)->Apply(ResolutionThreadSweep)->Unit(benchmark::kMillisecond)->UseRealTime();

/// The same pass with BestRotations, the batched polar iteration the local step uses. Counters
/// (medians of 7 alternating repetitions in one process): single_vs_batch = BestRotation one
/// matrix at a time / this pass, eigen_vs_batch = BestRotationEigen (the closed-form
/// eigen-decomposition of M^T M, BestRotation's fallback for inverted elements) / this pass.
void BM_PolarPassBatch(benchmark::State& state) {
  const Fixture& f = GetFixture(static_cast<int>(state.range(0)));
  const int threads = static_cast<int>(state.range(1));
  for (auto _ : state) benchmark::DoNotOptimize(PolarBatchPass(f.M, threads));
  std::vector<double> tb, ts, te;
  for (int r = 0; r < 7; ++r) {
    const auto t0 = Clock::now();
    benchmark::DoNotOptimize(PolarBatchPass(f.M, threads));
    const auto t1 = Clock::now();
    benchmark::DoNotOptimize(PolarPass(f.M, threads));
    const auto t2 = Clock::now();
    benchmark::DoNotOptimize(PolarEigenPass(f.M, threads));
    const auto t3 = Clock::now();
    tb.push_back(Seconds(t0, t1));
    ts.push_back(Seconds(t1, t2));
    te.push_back(Seconds(t2, t3));
  }
  state.counters["single_vs_batch"] = Median(ts) / Median(tb);
  state.counters["eigen_vs_batch"] = Median(te) / Median(tb);
  SizeCounters(state, f, true);
}
BENCHMARK(BM_PolarPassBatch)
    ->Apply(ResolutionThreadSweep)
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();

/// One full local-global iteration through the public solver API: LocalGlobalSolver::Solve with
/// max_iterations = 1 from a warm start (nothing subtracted, so the per-call overhead of Solve is
/// included). ratio_to_baseline = iteration time / (bare global solve + bare SVD pass), all medians
/// of 7 interleaved repetitions timed in the same process just before the benchmark loop.
void BM_Iteration(benchmark::State& state) {
  const Fixture& f = GetFixture(static_cast<int>(state.range(0)));
  LocalGlobalSolver solver(f.model, OneIterationOptions(*f.model, 1));
  int bad = 0;
  auto one_iteration = [&]() {
    const auto t0 = Clock::now();
    FkResult r = solver.Solve(f.c, &f.X);
    const double t = SecondsSince(t0);
    benchmark::DoNotOptimize(r.energy);
    if (r.iterations != 1) ++bad;
    return t;
  };
  const Baseline base = MeasureBaseline(f, one_iteration);
  double local_s = 0, global_s = 0;
  for (auto _ : state) {
    FkResult r = solver.Solve(f.c, &f.X);
    benchmark::DoNotOptimize(r.energy);
    local_s += r.local_time_s;
    global_s += r.global_time_s;
    if (r.iterations != 1) ++bad;
  }
  SizeCounters(state, f, false);
  BaselineCounters(state, base);
  // Solver-internal split (the local part includes the reference-residual local step at rest).
  state.counters["local_ms"] =
      benchmark::Counter(1e3 * local_s, benchmark::Counter::kAvgIterations);
  state.counters["global_ms"] =
      benchmark::Counter(1e3 * global_s, benchmark::Counter::kAvgIterations);
  if (bad) state.SkipWithError("Solve did not run exactly one iteration");
}
BENCHMARK(BM_Iteration)->Apply(ResolutionSweep)->Unit(benchmark::kMillisecond)->UseRealTime();

/// Marginal cost of one iteration inside a Solve: (t(Solve, 1 + K iterations) - t(Solve, 1)) / K,
/// i.e. BM_Iteration without the per-call setup (reference residual, final energy, copies).
/// Includes Anderson and any safeguard re-evaluations (aa_rejected counts them). Same ratio
/// counters as BM_Iteration.
void BM_IterationMarginal(benchmark::State& state) {
  constexpr int K = 5;
  const Fixture& f = GetFixture(static_cast<int>(state.range(0)));
  LocalGlobalSolver one(f.model, OneIterationOptions(*f.model, 1));
  LocalGlobalSolver many(f.model, OneIterationOptions(*f.model, 1 + K));
  int rejected = 0, accepted = 0, samples = 0;
  auto marginal = [&]() {
    auto t0 = Clock::now();
    FkResult r1 = one.Solve(f.c, &f.X);
    const double t1 = SecondsSince(t0);
    t0 = Clock::now();
    FkResult rk = many.Solve(f.c, &f.X);
    const double tk = SecondsSince(t0);
    benchmark::DoNotOptimize(r1.energy + rk.energy);
    rejected += rk.aa_rejected;
    accepted += rk.aa_accepted;
    ++samples;
    return std::max(0.0, (tk - t1) / K);
  };
  const Baseline base = MeasureBaseline(f, marginal);
  for (auto _ : state) state.SetIterationTime(marginal());
  SizeCounters(state, f, false);
  BaselineCounters(state, base);
  state.counters["aa_rejected"] = double(rejected) / samples;  // per Solve of 1 + K iterations
  state.counters["aa_accepted"] = double(accepted) / samples;
}
BENCHMARK(BM_IterationMarginal)
    ->Apply(ResolutionSweep)
    ->Unit(benchmark::kMillisecond)
    ->UseManualTime();

/// Anderson::Compute on vectors of size 3 * #free with window 6, history full (steady state).
void BM_AndersonOverhead(benchmark::State& state) {
  const Fixture& f = GetFixture(static_cast<int>(state.range(0)));
  const int dim = 3 * f.free;
  constexpr int kWindow = 6, kPool = 9;
  std::mt19937 rng(7);
  std::normal_distribution<double> nd;
  std::vector<Eigen::VectorXd> G(kPool), F(kPool);
  for (int k = 0; k < kPool; ++k) {
    G[k] = Eigen::VectorXd::NullaryExpr(dim, [&]() { return nd(rng); });
    F[k] = Eigen::VectorXd::NullaryExpr(dim, [&]() { return nd(rng); });
  }
  Anderson aa(dim, kWindow);
  int k = 0;
  for (; k < kWindow + 2; ++k) aa.Compute(G[k % kPool], F[k % kPool]);  // fill the history
  for (auto _ : state) {
    const Eigen::VectorXd& x = aa.Compute(G[k % kPool], F[k % kPool]);
    benchmark::DoNotOptimize(x.data());
    ++k;
  }
  SizeCounters(state, f, false);
  state.counters["dim"] = dim;
}
BENCHMARK(BM_AndersonOverhead)
    ->Apply(ResolutionSweep)
    ->Unit(benchmark::kMicrosecond)
    ->UseRealTime();

/// The full bend of the default finger (res 12): alpha from 1 to the actuator max in 12 equal
/// steps with lg-aa, the scene's default tolerances and Anderson window state.range(1), each
/// step started from the secant predictor X_k + (X_k - X_{k-1}), as the fig2_11 experiment does.
void BM_FullBend(benchmark::State& state) {
  constexpr int kSteps = 12;
  const Fixture& f = GetFixture(static_cast<int>(state.range(0)));
  const Model& m = *f.model;
  FkOptions opts = m.scene().solver;
  opts.solver = FkSolverType::kLgAa;
  opts.anderson_window = static_cast<int>(state.range(1));
  auto solver = MakeFkSolver(f.model, opts);
  const Actuator& act = m.scene().actuators[0];
  double total = 0, solver_s = 0, local_s = 0, global_s = 0;
  int iters = 0, not_converged = 0, max_iters = 0;
  double final_ratio = 0;
  for (auto _ : state) {
    Eigen::VectorXd c = m.scene().rest_actuation();
    Eigen::MatrixX3d X = m.rest_positions(), X_prev = X, guess;
    const auto t0 = Clock::now();
    for (int s = 1; s <= kSteps; ++s) {
      c[0] = act.rest + (act.max - act.rest) * double(s) / kSteps;
      guess = s > 1 ? Eigen::MatrixX3d(2.0 * X - X_prev) : X;
      FkResult r = solver->Solve(c, &guess);
      X_prev = X;
      X = r.positions;
      iters += r.iterations;
      max_iters = std::max(max_iters, r.iterations);
      solver_s += r.time_s;
      local_s += r.local_time_s;
      global_s += r.global_time_s;
      if (r.status != FkStatus::Converged) ++not_converged;
      final_ratio = r.volume_ratios.empty() ? 0.0 : r.volume_ratios[0];
      std::fprintf(stderr, "[full bend] step %2d alpha %.3f: %s (aa %d/%d accepted/rejected)\n", s,
                   c[0], r.BriefReport().c_str(), r.aa_accepted, r.aa_rejected);
    }
    total += SecondsSince(t0);
  }
  SizeCounters(state, f, false, false);
  using C = benchmark::Counter;
  state.counters["total_s"] = C(total, C::kAvgIterations);
  state.counters["solver_s"] = C(solver_s, C::kAvgIterations);
  state.counters["local_s"] = C(local_s, C::kAvgIterations);
  state.counters["global_s"] = C(global_s, C::kAvgIterations);
  state.counters["iterations"] = C(iters, C::kAvgIterations);
  state.counters["max_step_iters"] = max_iters;
  state.counters["not_converged"] = C(not_converged, C::kAvgIterations);
  state.counters["ms_per_iter"] = iters > 0 ? 1e3 * total / iters : 0.0;
  state.counters["final_vol_ratio"] = final_ratio;
}
BENCHMARK(BM_FullBend)
    ->Args({12, 6})
    ->Args({12, 15})
    ->ArgNames({"res", "window"})
    ->Iterations(1)
    ->Unit(benchmark::kSecond)
    ->UseRealTime();

/// Every embedded robot at its default resolution: one cold solve (lg-aa, the scene's defaults)
/// from the mesh to every actuator at the end of its range farther from the mesh's own state
/// (ratio 1 for chambers, cables and DEA, 0 for signed and motion actuators; so the crawler is
/// solved at its released state 0.7, not at the flat 1), with a
/// pure per-iteration time measured separately: 20 iterations of the local step, the right-hand
/// side and the global solve at the solution. Counters: iterations, ms_per_iter (solve time /
/// iterations, Anderson included), iter_ms (the bare iteration), elements, vertices.
void BM_RobotSolve(benchmark::State& state) {
  const RobotInfo info = ListRobots()[state.range(0)];
  auto model = std::make_shared<const Model>(MakeRobot(info.name));
  const Scene& sc = model->scene();
  Eigen::VectorXd c = sc.rest_actuation();
  for (int a = 0; a < sc.num_actuators(); ++a) {
    const Actuator& act = sc.actuators[a];
    const double neutral = (act.is_signed() || act.is_motion()) ? 0.0 : 1.0;
    c[a] = std::abs(act.max - neutral) >= std::abs(act.min - neutral) ? act.max : act.min;
  }
  FkOptions opts = sc.solver;
  opts.solver = FkSolverType::kLgAa;
  FkResult r;
  for (auto _ : state) {
    auto solver = MakeFkSolver(model, opts);
    r = solver->Solve(c);
  }
  // Bare iteration at the solution.
  std::vector<double> ratios;
  std::vector<ElemRows> weighted;
  Eigen::MatrixX3d B;
  Eigen::VectorXd Bf;
  const auto t0 = Clock::now();
  constexpr int kReps = 20;
  for (int k = 0; k < kReps; ++k) {
    ComputeLocalRatios(*model, r.positions, c, &ratios);
    LocalStep(*model, r.positions, ratios, &weighted);
    AssembleRhs(*model, weighted, &B);
    model->GatherFree(B, &Bf);
    benchmark::DoNotOptimize(model->SolveFree(Bf).data());
  }
  const double iter_s = SecondsSince(t0) / kReps;
  state.SetLabel(info.name + " (" + FkStatusToString(r.status) + ")");
  state.counters["elements"] = sc.mesh.num_elements();
  state.counters["vertices"] = sc.mesh.num_vertices();
  state.counters["iterations"] = r.iterations;
  state.counters["solve_s"] = r.time_s;
  state.counters["ms_per_iter"] = r.iterations > 0 ? 1e3 * r.time_s / r.iterations : 0.0;
  state.counters["iter_ms"] = 1e3 * iter_s;
}
BENCHMARK(BM_RobotSolve)
    ->DenseRange(0, static_cast<int>(ListRobots().size()) - 1)
    ->ArgName("robot")
    ->Iterations(1)
    ->Unit(benchmark::kSecond)
    ->UseRealTime();

/// The FK methods of table2_2 on one cold solve each, on a small mesh (three_chamber res 3, 2754
/// tets, actuation (2, 1, 1)) and a medium one (pneumatic_finger res 5, 3600 tets, volume ratio
/// 2.5), same stopping rule, 120 s wall-clock limit per solve. Counters: iterations, solve_s,
/// ms_per_iter, converged (1/0), energy, and time_vs_lg_aa (this method's time over lg-aa's on
/// the same case, measured in the same run).
void BM_SolverCompare(benchmark::State& state) {
  static const std::vector<std::string> kSolvers = {"lg-aa", "lg", "ceres", "ipopt-lbfgs",
                                                    "ipopt-newton"};
  static std::map<int, double> lg_aa_time;  // per case, from the lg-aa run (registered first)
  const std::string name = kSolvers[state.range(1)];
  const int which = static_cast<int>(state.range(0));
  auto model = std::make_shared<const Model>(which == 0 ? MakeRobot("three_chamber", 3)
                                                        : MakeRobot("pneumatic_finger", 5));
  Eigen::VectorXd c = model->scene().rest_actuation();
  c[0] = which == 0 ? 2.0 : 2.5;
  FkOptions opts = model->scene().solver;
  opts.solver = FkSolverTypeFromString(name);
  opts.time_limit_s = 120;
  opts.max_iterations = 100000;
  FkResult r;
  for (auto _ : state) {
    auto solver = MakeFkSolver(model, opts);
    r = solver->Solve(c);
  }
  if (name == "lg-aa") lg_aa_time[which] = r.time_s;
  state.SetLabel(std::string(which == 0 ? "three_chamber res 3" : "pneumatic_finger res 5") + ", " +
                 name + " (" + FkStatusToString(r.status) + ")");
  state.counters["elements"] = model->mesh().num_elements();
  state.counters["iterations"] = r.iterations;
  state.counters["solve_s"] = r.time_s;
  state.counters["ms_per_iter"] = r.iterations > 0 ? 1e3 * r.time_s / r.iterations : 0.0;
  state.counters["converged"] = r.status == FkStatus::Converged ? 1 : 0;
  state.counters["energy"] = r.energy;
  if (lg_aa_time.count(which) && lg_aa_time[which] > 0)
    state.counters["time_vs_lg_aa"] = r.time_s / lg_aa_time[which];
}
BENCHMARK(BM_SolverCompare)
    ->ArgsProduct({{0, 1}, {0, 1, 2, 3, 4}})
    ->ArgNames({"mesh", "solver"})
    ->Iterations(1)
    ->Unit(benchmark::kSecond)
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
