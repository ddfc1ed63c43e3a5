// The learned-network kernels (issue 7 targets): one forward pass (one input, and a batch), the
// input Jacobian, one Levenberg-Marquardt epoch, and the time the Ceres peer needs to reach the
// loss the in-house trainer reaches. Networks have the thesis's three_chamber architecture
// (3 -> 35 -> 35 -> n_out, h = 2, b = 35, §5.3.4); data come from the analytical PCC finger
// (3 actuators): n_out = 3 is N_fk (tip position), 9 the tip Jacobian (N_J), 27 the Jacobian of
// three tracked points. Training sets have 4096 x 0.7 = 2867 samples (16^3 grid, 70 % split).
// BM_DatasetShard times the simulator dataset those networks learn from (issue 33's target: the
// 16^3 three_chamber res 4 grid with implicit Jacobians in <= 5 minutes).
#include "softkin/ik/ik_solver.hpp"
#include "softkin/ik/objectives.hpp"
#include "softkin/ik/pcc_chamber_kinematics.hpp"
#include "softkin/ik/pcc_kinematics.hpp"
#include "softkin/ik/simulator_kinematics.hpp"
#include "softkin/ik/trajectory.hpp"
#include "softkin/learn/net_kinematics.hpp"
#include "softkin/learn/train_nets.hpp"
#include "softkin/learn/ceres_trainer.hpp"
#include "softkin/learn/dataset.hpp"
#include "softkin/learn/lm_trainer.hpp"

#include "softkin/solver/robots/robots.hpp"

#include <benchmark/benchmark.h>

#include <cstdio>
#include <filesystem>
#include <random>
#include <string>

namespace softkin {
namespace {

// `n` random actuations and the PCC outputs: tip (n_out = 3) or the first n_out / 3 rows of J.
SampleSet PccData(int n, int n_out, unsigned seed) {
  PccKinematics pcc;
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> u(0.0, pcc.params().max_pull);
  SampleSet s;
  s.X.resize(n, 3);
  s.Y.resize(n, n_out);
  for (int i = 0; i < n; ++i) {
    const Eigen::Vector3d c(u(rng), u(rng), u(rng));
    const KinematicsEval e = pcc.Evaluate(c, n_out > 3);
    s.X.row(i) = c.transpose();
    if (n_out == 3) {
      s.Y.row(i) = e.p.row(0);
    } else {
      const Eigen::MatrixXd Jr = e.J.topRows(n_out / 3);  // (n_out/3) x 3, flattened row by row
      for (int r = 0; r < Jr.rows(); ++r) s.Y.block(i, 3 * r, 1, 3) = Jr.row(r);
    }
  }
  return s;
}

Fnn ThreeChamberNet(const SampleSet& data, int n_out) {
  Fnn net({3, 35, 35, n_out});
  net.FitNormalization(data.X, data.Y);
  net.InitializeNguyenWidrow(1);
  return net;
}

void BM_FnnForwardOne(benchmark::State& state) {
  const SampleSet data = PccData(64, 3, 1);
  const Fnn net = ThreeChamberNet(data, 3);
  FnnWorkspace ws;
  Eigen::VectorXd y(3);
  Eigen::VectorXd x = data.X.row(5).transpose();
  for (auto _ : state) {
    net.Forward(x, ws, y);
    benchmark::DoNotOptimize(y.data());
  }
}
BENCHMARK(BM_FnnForwardOne)->Unit(benchmark::kMicrosecond);

void BM_FnnForwardBatch(benchmark::State& state) {
  const int n = static_cast<int>(state.range(0));
  const SampleSet data = PccData(n, 3, 2);
  const Fnn net = ThreeChamberNet(data, 3);
  for (auto _ : state) {
    Eigen::MatrixXd Y = net.ForwardBatch(data.X);
    benchmark::DoNotOptimize(Y.data());
  }
  state.SetItemsProcessed(state.iterations() * n);
}
BENCHMARK(BM_FnnForwardBatch)->Arg(4096)->Unit(benchmark::kMicrosecond);

void BM_FnnInputJacobian(benchmark::State& state) {
  const int n_out = static_cast<int>(state.range(0));
  const SampleSet data = PccData(64, n_out, 3);
  const Fnn net = ThreeChamberNet(data, n_out);
  FnnWorkspace ws;
  Eigen::VectorXd y(n_out);
  Eigen::MatrixXd J(n_out, 3);
  const Eigen::VectorXd x = data.X.row(7).transpose();
  for (auto _ : state) {
    net.InputJacobian(x, ws, y, J);
    benchmark::DoNotOptimize(J.data());
  }
}
BENCHMARK(BM_FnnInputJacobian)->Arg(3)->Arg(9)->Unit(benchmark::kMicrosecond);

// One LM epoch (accumulate J^T J and J^T e, then as many Cholesky solves as mu needs) after the
// initial loss evaluation. Args: n_out, threads.
void BM_LmEpoch(benchmark::State& state) {
  const int n_out = static_cast<int>(state.range(0));
  const int threads = static_cast<int>(state.range(1));
  const SampleSet data = PccData(2867, n_out, 4);
  LmOptions o;
  o.max_epochs = 1;
  o.num_threads = threads;
  LmSummary s;
  for (auto _ : state) {
    Fnn net({3, 35, 35, n_out});
    s = TrainLevenbergMarquardt(net, data, nullptr, o);
    benchmark::DoNotOptimize(s.train_mse.data());
  }
  state.counters["W"] = s.num_parameters;
  state.counters["solves"] = s.accepted_steps + s.rejected_steps;
  state.counters["threads"] = s.num_threads;
  state.SetLabel("3-35-35-" + std::to_string(n_out) + ", 2867 samples");
}
BENCHMARK(BM_LmEpoch)
    ->Args({3, 1})
    ->Args({3, 2})
    ->Args({9, 2})
    ->Args({27, 2})
    ->Unit(benchmark::kMillisecond)
    ->Iterations(2);

// Time to the same training loss: the in-house trainer runs `epochs` epochs (range 0) on N_fk
// data; Ceres (dense normal Cholesky, 2 threads) starts from the same network and stops at the
// loss LM reached. Counters: both times (set-up included), their ratio, the losses.
void BM_PeerTimeToLoss(benchmark::State& state) {
  const int epochs = static_cast<int>(state.range(0));
  const SampleSet data = PccData(2867, 3, 5);
  for (auto _ : state) {
    Fnn lm_net({3, 35, 35, 3});
    LmOptions lo;
    lo.max_epochs = epochs;
    lo.num_threads = 2;
    lo.min_grad = 0.0;
    const LmSummary ls = TrainLevenbergMarquardt(lm_net, data, nullptr, lo);
    Fnn ceres_net({3, 35, 35, 3});
    CeresFitOptions co;
    co.target_mse = ls.final_train_mse;
    co.max_iterations = 20 * epochs;
    co.num_threads = 2;
    const CeresFitSummary cs = FitFnnWithCeres(ceres_net, data, co);
    state.counters["lm_s"] = ls.total_time_s;
    state.counters["ceres_s"] = cs.reached_target ? cs.time_to_target_s : cs.total_time_s;
    state.counters["ratio"] = state.counters["ceres_s"] / ls.total_time_s;
    state.counters["lm_mse"] = ls.final_train_mse;
    state.counters["ceres_mse"] = cs.final_mse;
    state.counters["ceres_iters"] = cs.iterations;
    state.counters["reached"] = cs.reached_target ? 1 : 0;
  }
}
BENCHMARK(BM_PeerTimeToLoss)->Arg(20)->Unit(benchmark::kSecond)->Iterations(1);

// One learned-IK waypoint (Table 5.1's "learned Jacobian", Eq. 5.4-5.6): damped Gauss-Newton on
// N_fk (h = 2, b = 35) and N_J (h = 2, b = 30) trained on 8^3 samples of the three_chamber PCC
// model (setup, not timed), from the closest of 5^3 network samples to a target off the grid,
// stopping at 0.01 % of the workspace width. Arg 1: with the sim-to-real layer (Eq. 5.4).
void BM_LearnedIkWaypoint(benchmark::State& state) {
  static LearnedNets nets = [] {
    PccChamberKinematics pcc;
    Dataset d;
    d.point_names = {"tip"};
    d.num_actuators = 3;
    const int N = 8;
    d.inputs.resize(N * N * N, 3);
    d.positions.resize(N * N * N, 3);
    d.jacobians.resize(N * N * N, 9);
    for (int i = 0; i < N * N * N; ++i) {
      const Eigen::Vector3d c(1 + 2.0 * (i % N) / (N - 1), 1 + 2.0 * (i / N % N) / (N - 1),
                              1 + 2.0 * (i / (N * N)) / (N - 1));
      const KinematicsEval e = pcc.Evaluate(c, true);
      d.inputs.row(i) = c.transpose();
      d.positions.row(i) = e.p.row(0);
      for (int r = 0; r < 3; ++r) d.jacobians.block(i, 3 * r, 1, 3) = e.J.row(r);
    }
    NetsFromDatasetOptions o;
    o.ik = false;
    o.jac_options.hidden = {30, 30};
    o.fk_options.lm.max_epochs = o.jac_options.lm.max_epochs = 100;
    LearnedNets n = TrainNetsFromDataset(d, "pcc-chamber-8^3", o);
    // An s2r layer from a "hardware" PCC with another gain and offset (for Arg 1).
    PccChamberParams hw;
    hw.gain = 0.27;
    hw.offset = 14.0;
    Dataset t = d;
    t.jacobians.resize(t.inputs.rows(), 0);
    for (int i = 0; i < t.inputs.rows(); ++i)
      t.positions.row(i) = PccChamberKinematics::Tip(hw, t.inputs.row(i).transpose()).transpose();
    LmOptions lm;
    lm.max_epochs = 100;
    TrainS2r(n, t, "pcc-hardware", 0.25, lm);
    return n;
  }();
  NetKinematics kin(nets, JacobianSource::kNetwork, state.range(0) != 0);
  SamplingOptions so;
  so.samples_per_axis = 5;
  const ConfigurationSamples samples = SampleConfigurationSpace(kin, "tip", so);
  const double width = nets.info["dataset"]["workspace_width_mm"].get<double>();
  IkOptions io;
  io.method = IkMethod::kGaussNewton;
  io.lambda = std::pow(1e-4 * width, 2);
  const Eigen::Vector3d target =
      kin.Evaluate(Eigen::Vector3d(2.37, 1.42, 1.11), false).p.row(0).transpose();
  const Eigen::VectorXd c0 = samples.c.row(ClosestSample(samples, target)).transpose();
  PointTrackingObjective obj(kin.point_names(), "tip", target);
  double err = 0;
  for (auto _ : state) {
    const IkResult r = SolveIk(kin, obj, c0, io);
    err = std::sqrt(r.objective);
    benchmark::DoNotOptimize(r.c.data());
  }
  state.counters["err_mm"] = err;
}
BENCHMARK(BM_LearnedIkWaypoint)->Arg(0)->Arg(1)->Unit(benchmark::kMillisecond);

// One shard of the thesis-size dataset, as `softkin dataset --robot three_chamber --res 4 --grid 16
// --jacobian implicit --gradient-tolerance 1e-5 --shard 7/16` computes it: 256 samples (four
// warm-start blocks of 64) from the middle of the serpentine order, each a forward solve and an
// implicit Jacobian, one thread. Counters: ms_per_sample, and the whole 16^3 grid projected from
// it, in one process (dataset_16cubed_s, 4096 samples) and as two MPI ranks on two cores
// (dataset_16cubed_2ranks_s, half of it: the ranks share the samples; docs/cluster.md).
void BM_DatasetShard(benchmark::State& state) {
  const Scene scene = MakeRobot("three_chamber", 4);
  FkOptions fk = scene.solver;
  fk.gradient_tolerance = 1e-5;
  fk.threads = 1;
  SimulatorKinematicsOptions ko;
  ko.jacobian = JacobianMode::kImplicit;
  ko.implicit.threads = 1;
  SimulatorKinematics kin(scene, ko, &fk);
  DatasetSampling sampling;
  sampling.grid = 16;
  const std::string out =
      (std::filesystem::temp_directory_path() / "softkin_bench_dataset_shard.csv").string();
  DatasetRunOptions run;
  run.out = out;
  run.jacobian = true;
  run.shard = 7;
  run.shards = 16;
  run.progress = false;
  run.reset = [&kin] { kin.Reset(); };
  DatasetRunSummary sum;
  for (auto _ : state) {
    std::remove(out.c_str());
    std::remove((out + ".json").c_str());
    sum = GenerateDataset(kin, sampling, run);
  }
  std::remove(out.c_str());
  std::remove((out + ".json").c_str());
  if (sum.written != sum.count || sum.failed > 0) {
    state.SkipWithError("a sample failed or was not written");
    return;
  }
  const double per_sample = sum.time_s / static_cast<double>(sum.count);
  state.counters["samples"] = static_cast<double>(sum.count);
  state.counters["ms_per_sample"] = 1e3 * per_sample;
  state.counters["dataset_16cubed_s"] = 4096 * per_sample;
  state.counters["dataset_16cubed_2ranks_s"] = 2048 * per_sample;
}
BENCHMARK(BM_DatasetShard)->Unit(benchmark::kSecond)->Iterations(1)->UseRealTime();

}  // namespace
}  // namespace softkin

BENCHMARK_MAIN();
