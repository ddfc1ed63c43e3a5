// Google Benchmark suite for collision response (solver/collision/spring_system.hpp,
// solver/collision/collision_response.hpp; thesis Sec. 3.2.3 and Table 3.1's "Col. Resp." column).
//
// Mesh: pneumatic_finger at resolution `res` (27 res^3 tets; res 12 = 46,656 tets).
//   BM_SpringUpdate/res/n/method   one change of the spring set that adds n springs and releases
//                                  n others (2n rank-one modifications), then one 3-column solve:
//                                  method 0 = CHOLMOD update/downdate, 1 = numeric refactorisation.
//                                  Counter vs_refactor: this time over the refactorisation's at
//                                  the same (res, n, pair), measured in the same run. pair = 1:
//                                  vertex-face springs (each top-face vertex against its three
//                                  nearest other vertices: 4 entries per column, and a refactor
//                                  that must analyse A_ff + K afresh), pair = 0: unit springs.
//   BM_CollisionResponseUpdate/res/plane
//                                  one CollisionResponse::Update (detection + spring rule +
//                                  factor update) from an empty spring set on the finger pressed
//                                  into a box obstacle (springs on ~ every vertex under the tip),
//                                  res 6/9/12; plane 0 = "point" obstacle springs (unit columns
//                                  in the factor), 1 = "plane" (one cached solve per contact
//                                  vertex and the m x m capacitance matrix; vs_point: this time
//                                  over point's at the same res). solve_ms: one global solve with
//                                  the springs; solve_vs_axis: over the per-axis solve without
//                                  the plane springs' Woodbury correction.
//   BM_SelfTargetRule/res/rule     one CollisionResponse::Update on the membrane (thesis Fig. 3.13)
//                                  with its membrane pushed 1 mm into the chamber roofs (every
//                                  membrane-bottom vertex above a roof is a contact): rule 0 =
//                                  self_target "walk" (ray walk along -n(v) through the tets),
//                                  1 = "auto" (between bodies: closest facing point on the other
//                                  body's surface, MovingSurface's CGAL AABB tree rebuilt per
//                                  check, BodyTarget). Counter vs_walk: this time over the walk's
//                                  at the same res, measured in the same run.
// Wall-clock times (UseRealTime). See docs/benchmarks.md, "Collision response", and
// docs/collision_response.md.
#include "softkin/solver/collision/collision_response.hpp"
#include "softkin/solver/fk/fk_solver.hpp"
#include "softkin/solver/robots/robots.hpp"
#include "softkin/solver/collision/spring_system.hpp"
#include "softkin/solver/common/stopwatch.hpp"

#include <benchmark/benchmark.h>

#include <algorithm>
#include <array>
#include <chrono>
#include <map>
#include <memory>
#include <random>
#include <vector>

namespace softkin {
namespace {

std::shared_ptr<const Model> FingerModel(int res) {
  static std::map<int, std::shared_ptr<const Model>> cache;
  auto& m = cache[res];
  if (!m) m = std::make_shared<const Model>(MakeRobot("pneumatic_finger", res));
  return m;
}

std::map<std::array<int, 3>, double>& RefactorTimes() {
  static std::map<std::array<int, 3>, double> t;
  return t;
}

void BM_SpringUpdate(benchmark::State& state) {
  const int res = static_cast<int>(state.range(0));
  const int n = static_cast<int>(state.range(1));
  const bool refactor = state.range(2) != 0;
  const bool pair = state.range(3) != 0;
  auto model = FingerModel(res);
  SpringSystem sys(*model,
                   refactor ? SpringSystem::Method::kRefactor : SpringSystem::Method::kUpdown);
  sys.set_refactor_after(0);
  const double k = 20.0 * model->A().diagonal().mean();
  // Boundary-ish candidates: vertices of the top face (z = max), as contacts would be.
  std::vector<int> cand;
  const double zmax = model->rest_positions().col(2).maxCoeff();
  for (int v = 0; v < model->num_vertices(); ++v)
    if (model->rest_positions()(v, 2) > zmax - 1e-9) cand.push_back(v);
  std::mt19937 rng(3);
  std::shuffle(cand.begin(), cand.end(), rng);
  // Two disjoint sets of n springs: each iteration swaps one for the other.
  const Eigen::MatrixX3d& P = model->rest_positions();
  auto spring = [&](int v) {
    if (!pair) return SpringStencil::Unit(v);
    std::vector<std::pair<double, int>> d;
    for (int u = 0; u < model->num_vertices(); ++u)
      if (u != v) d.push_back({(P.row(u) - P.row(v)).squaredNorm(), u});
    std::partial_sort(d.begin(), d.begin() + 3, d.end());
    return SpringStencil::VertexFace(v, {d[0].second, d[1].second, d[2].second},
                                     Eigen::Vector3d(0.5, 0.3, 0.2));
  };
  std::vector<SpringStencil> a, b;
  for (int i = 0; i < n; ++i) {
    a.push_back(spring(cand[i]));
    b.push_back(spring(cand[n + i]));
  }
  sys.SetSprings(a, k);
  Eigen::VectorXd rhs = Eigen::VectorXd::Ones(model->num_free_dofs());
  bool flip = false;
  const auto t0 = std::chrono::steady_clock::now();
  for (auto _ : state) {
    sys.SetSprings(flip ? a : b, k);
    flip = !flip;
    benchmark::DoNotOptimize(sys.Solve(rhs));
  }
  const double per = SecondsSince(t0) / std::max<double>(1, state.iterations());
  auto& ref = RefactorTimes();
  const std::array<int, 3> key = {res, n, pair ? 1 : 0};
  if (refactor) ref[key] = per;
  if (!refactor && ref.count(key)) state.counters["vs_refactor"] = per / ref[key];
  state.counters["tets"] = model->mesh().num_elements();
  state.counters["springs_changed"] = 2 * n;
}

void BM_CollisionResponseUpdate(benchmark::State& state) {
  const int res = static_cast<int>(state.range(0));
  const bool plane = state.range(1) != 0;
  Scene s = MakeRobot("pneumatic_finger", res);
  s.obstacles.push_back(
      MakeBoxSurface(Eigen::Vector3d(100, -10, -10), Eigen::Vector3d(140, 30, 2)));
  s.solver.collision.obstacle_spring = plane ? ObstacleSpring::kPlane : ObstacleSpring::kPoint;
  const Model model(s);
  CollisionResponse resp(model, s.solver.collision);
  // The tip end of the finger moved 2 mm down into the box's top (z <= 2).
  Eigen::MatrixX3d X = model.rest_positions();
  for (int v = 0; v < X.rows(); ++v)
    if (X(v, 0) > 100) X(v, 2) -= 2.0;
  const auto t0 = std::chrono::steady_clock::now();
  for (auto _ : state) {
    resp.Reset();
    benchmark::DoNotOptimize(resp.Update(X));
  }
  const double per = SecondsSince(t0) / std::max<double>(1, state.iterations());
  static std::map<int, double> point;
  if (!plane) point[res] = per;
  if (plane && point.count(res)) state.counters["vs_point"] = per / point[res];
  // One global solve with the springs in place (what every iteration pays), against the
  // per-axis solve without the plane springs' Woodbury correction.
  Eigen::VectorXd rhs = Eigen::VectorXd::Ones(model.num_free_dofs());
  auto time_solves = [&](auto&& solve) {
    const int reps = 5;
    const auto t1 = std::chrono::steady_clock::now();
    for (int i = 0; i < reps; ++i) benchmark::DoNotOptimize(solve(rhs));
    return SecondsSince(t1) / reps;
  };
  const double solve_s = time_solves([&](const Eigen::VectorXd& b) { return resp.Solve(b); });
  const double base_s =
      time_solves([&](const Eigen::VectorXd& b) { return resp.system().Solve(b); });
  state.counters["tets"] = model.mesh().num_elements();
  state.counters["springs"] = static_cast<double>(resp.springs().size());
  state.counters["check_ms"] = 1e3 * resp.stats().check_s / std::max(1, resp.stats().checks);
  state.counters["response_ms"] = 1e3 * resp.stats().response_s / std::max(1, resp.stats().checks);
  state.counters["solve_ms"] = 1e3 * solve_s;
  state.counters["solve_vs_axis"] = solve_s / base_s;
}

void BM_SelfTargetRule(benchmark::State& state) {
  const int res = static_cast<int>(state.range(0));
  const bool body_rule = state.range(1) != 0;
  Scene s = MakeRobot("membrane", res);
  s.solver.collision.self_target = body_rule ? SelfTarget::kAuto : SelfTarget::kWalk;
  const Model model(s);
  CollisionResponse resp(model, s.solver.collision);
  // The membrane (every vertex above the roofs' 2 mm air gap; its top is one cell above the roofs)
  // lowered by 3 mm: 1 mm into the roofs.
  const double z_roof = model.rest_positions().col(2).maxCoeff() - 250.0 / res;
  Eigen::MatrixX3d X = model.rest_positions();
  for (int v = 0; v < X.rows(); ++v)
    if (X(v, 2) > z_roof + 1.0) X(v, 2) -= 3.0;
  const auto t0 = std::chrono::steady_clock::now();
  for (auto _ : state) {
    resp.Reset();
    benchmark::DoNotOptimize(resp.Update(X));
  }
  const double per = SecondsSince(t0) / std::max<double>(1, state.iterations());
  static std::map<int, double> walk;
  if (!body_rule) walk[res] = per;
  if (body_rule && walk.count(res)) state.counters["vs_walk"] = per / walk[res];
  state.counters["tets"] = model.mesh().num_elements();
  state.counters["springs"] = static_cast<double>(resp.springs().size());
  state.counters["unresolved"] = resp.stats().unresolved;
  state.counters["check_ms"] = 1e3 * resp.stats().check_s / std::max(1, resp.stats().checks);
  state.counters["response_ms"] = 1e3 * resp.stats().response_s / std::max(1, resp.stats().checks);
}

}  // namespace

BENCHMARK(BM_SelfTargetRule)
    ->ArgNames({"res", "rule"})
    ->ArgsProduct({{12, 24}, {0, 1}})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();
BENCHMARK(BM_SpringUpdate)
    ->ArgNames({"res", "n", "refactor", "pair"})
    ->ArgsProduct({{6, 12}, {8, 64}, {1, 0}, {0, 1}})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();
BENCHMARK(BM_CollisionResponseUpdate)
    ->ArgNames({"res", "plane"})
    ->ArgsProduct({{6, 9, 12}, {0, 1}})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();

}  // namespace softkin

BENCHMARK_MAIN();
