#include "softkin/experiments/cli_dataset.hpp"

#include "softkin/experiments/cli_args.hpp"
#include "softkin/experiments/dataset_mpi.hpp"
#include "softkin/experiments/mpi_job.hpp"
#include "softkin/experiments/results.hpp"
#include "softkin/ik/simulator_kinematics.hpp"
#include "softkin/learn/dataset.hpp"
#include "softkin/learn/twin.hpp"
#include "softkin/solver/robots/robots.hpp"

#include <cmath>
#include <cstdio>
#include <iostream>
#include <memory>
#include <sstream>
#include <stdexcept>

namespace softkin {

CLI::App* AddDatasetCommand(CLI::App* app, DatasetCommandArgs* a) {
  auto* ds = app->add_subcommand(
      "dataset",
      "Generate a learning dataset (thesis Sec. 5.3.2): evaluate a robot's simulator, or a "
      "'hardware' twin, on a grid of N^m actuations visited in serpentine order (each sample one "
      "grid step from the previous, so the simulator warm-starts next to its answer) or on seeded "
      "random actuations. Writes a CSV (index, status, c0.., <point>_x/_y/_z, "
      "J_<point>_<coord>_c<a> "
      "with --jacobian, message), one line per sample as it is computed, and a sidecar FILE.json "
      "(robot, res, params, points, sampling, git commit; twin label). Running the same command "
      "again on a partial file resumes it; --shard k/n computes the k-th of n contiguous slices; "
      "--merge joins the shards; under mpirun (-n N) the ranks share the samples "
      "(docs/cluster.md; " +
          MpiSupportNote() +
          "). "
          "Exit 0 when every sample succeeded, 1 when some were recorded as "
          "failed, 2 for bad input. Units: mm. See docs/datasets.md");
  auto* o_robot = ds->add_option("--robot", a->robot, "Embedded robot name (see `softkin robots`)");
  auto* o_twin = ds->add_option(
      "--twin", a->twin, "A 'hardware' twin (docs/twins.md): " + [] {
        std::string s;
        for (const auto& n : TwinNames()) s += (s.empty() ? "" : ", ") + n;
        return s;
      }());
  o_robot->excludes(o_twin);
  ds->add_option("--res", a->res, "Robot resolution (default: the robot's own)")
      ->check(CLI::Range(1, 1 << 20));
  ds->add_option("--param", a->params,
                 "Robot design parameter NAME=VALUE (repeatable; see `softkin robots`)")
      ->needs(o_robot);
  auto* o_grid =
      ds->add_option("--grid", a->grid, "N samples per actuator: a grid of N^m (default 16)")
          ->check(CLI::Range(1, 1 << 20));
  auto* o_random = ds->add_option("--random", a->random, "Number of uniform random samples")
                       ->check(CLI::Range(1, 1 << 30));
  o_grid->excludes(o_random);
  ds->add_option("--seed", a->seed, "Seed of --random (required with it)")->needs(o_random);
  ds->add_option("--block", a->block,
                 "Warm-start block: the simulator restarts from rest every this many samples, so "
                 "a resumed or sharded run equals an uninterrupted one bit for bit (default 64)");
  ds->add_option(
      "--points", a->points,
      "Tracked points, comma-separated markers (or marker[i]) of the robot (default tip)");
  ds->add_option("--jacobian", a->jacobian,
                 "Record J = dp/dc too: none (default), implicit (exact, cheapest), fd, fd-warm "
                 "(a twin has none)");
  ds->add_option("--shard", a->shard,
                 "Compute shard k of n (k = 0..n-1): a contiguous slice of "
                 "the serpentine order, into its own --out file");
  AddFkOptionFlags(ds, &a->fk_options, {"solver", "gradient_tolerance"});
  ds->add_option("--merge", a->merge, "Merge these complete shard files (all n of them) into --out")
      ->expected(1, -1);
  ds->add_option("--out", a->out, "Output CSV (its sidecar is FILE.json)")->required();
  ds->add_flag("--quiet", a->quiet, "No progress on stderr");
  ds->add_flag("--dry-run", a->dry_run,
               "Print the plan as JSON on stdout (samples, warm-start units of --block, the "
               "shard's slice) and exit without computing or writing anything");
  return ds;
}

namespace {

std::vector<std::string> SplitComma(const std::string& s, const std::string& option) {
  std::vector<std::string> out;
  std::stringstream ss(s);
  std::string item;
  while (std::getline(ss, item, ','))
    if (item.empty())
      throw std::invalid_argument(option + ": empty item in '" + s + "'");
    else
      out.push_back(item);
  if (out.empty() || s.back() == ',')
    throw std::invalid_argument(option + ": expected comma-separated names, got '" + s + "'");
  return out;
}

int DefaultResolution(const std::string& robot) {
  for (const auto& r : ListRobots())
    if (r.name == robot) return r.default_resolution;
  return 0;
}

/// --merge: joins complete shard files into --out.
int MergeCommand(const DatasetCommandArgs& a) {
  if (!a.robot.empty() || !a.twin.empty() || !a.shard.empty())
    throw std::invalid_argument("--merge: give only the shard files and --out");
  const long long n = MergeDatasets(a.merge, a.out);
  if (!a.quiet)
    std::cerr << "softkin dataset: merged " << a.merge.size() << " shard(s), " << n
              << " samples, into " << a.out << "\n";
  return 0;
}

/// --grid or --random (with --seed), and --block.
DatasetSampling SamplingFromArgs(const DatasetCommandArgs& a) {
  DatasetSampling sampling;
  if (a.random != 0) {
    if (a.random < 1)
      throw std::invalid_argument("--random: expected a number of samples >= 1, got " +
                                  std::to_string(a.random));
    if (a.seed < 0)
      throw std::invalid_argument(
          "--seed: required with --random: expected an integer >= 0" +
          (a.seed == -1 ? std::string() : ", got " + std::to_string(a.seed)));
    sampling.kind = DatasetSampling::Kind::kRandom;
    sampling.random = a.random;
    sampling.seed = static_cast<std::uint64_t>(a.seed);
  } else {
    sampling.grid = a.grid == 0 ? 16 : a.grid;
    if (sampling.grid < 2 || sampling.grid > 1000)
      throw std::invalid_argument("--grid: expected N in [2, 1000] samples per actuator, got " +
                                  std::to_string(sampling.grid));
  }
  if (a.block < 1)
    throw std::invalid_argument("--block: expected an integer >= 1, got " +
                                std::to_string(a.block));
  sampling.block = a.block;
  return sampling;
}

/// The kinematics a dataset samples, and the "source" object of its sidecar.
struct DatasetSource {
  std::unique_ptr<Kinematics> kin;
  nlohmann::json json;
};

/// --robot: the robot's simulator tracking `points` (ko: the Jacobian mode); sets run->reset.
DatasetSource RobotSource(const DatasetCommandArgs& a, SimulatorKinematicsOptions ko,
                          const std::vector<std::string>& points, DatasetRunOptions* run) {
  const bool with_j = a.jacobian != "none";
  const RobotParams params = ParseRobotParams(a.params);
  const Scene scene = MakeRobot(a.robot, a.res, params);
  FkOptions fk = ApplyFkOptionFlags(a.fk_options, scene.solver);
  ko.points = points;
  std::unique_ptr<SimulatorKinematics> sim;
  try {
    sim = std::make_unique<SimulatorKinematics>(scene, ko, &fk);
  } catch (const std::invalid_argument& e) {
    throw std::invalid_argument(std::string("--points / --jacobian: ") + e.what());
  }
  SimulatorKinematics* raw = sim.get();
  run->reset = [raw] { raw->Reset(); };
  nlohmann::json pj = nlohmann::json::object();
  for (const auto& [k, v] : params) pj[k] = v;
  DatasetSource out;
  out.json = {{"kind", "robot"},
              {"robot", a.robot},
              {"res", a.res > 0 ? a.res : DefaultResolution(a.robot)},
              {"params", pj},
              {"fk_solver", ToString(fk.solver)},
              {"gradient_tolerance", fk.gradient_tolerance},
              {"jacobian_mode", with_j ? a.jacobian : "none"}};
  out.kin = std::move(sim);
  return out;
}

/// --twin: the 'hardware' twin tracking `points`; sets run->reset.
DatasetSource TwinSource(const DatasetCommandArgs& a, const std::vector<std::string>& points,
                         DatasetRunOptions* run) {
  TwinSpec spec;
  try {
    spec = GetTwinSpec(a.twin);
  } catch (const std::invalid_argument& e) {
    throw std::invalid_argument(std::string("--twin: ") + e.what());
  }
  TwinOptions to;
  to.res = a.res;
  to.points = points;
  // --gradient-tolerance, checked by the option reader; 0 (not given): the robot's own.
  if (a.fk_options.given.count("gradient_tolerance"))
    to.gradient_tolerance = ApplyFkOptionFlags(a.fk_options, FkOptions()).gradient_tolerance;
  std::unique_ptr<TwinKinematics> twin;
  try {
    twin = std::make_unique<TwinKinematics>(spec, to);
  } catch (const std::invalid_argument& e) {
    throw std::invalid_argument(std::string("--twin / --points: ") + e.what());
  }
  TwinKinematics* raw = twin.get();
  run->reset = [raw] { raw->Reset(); };
  DatasetSource out;
  out.json = {{"kind", "twin"},
              {"twin", "twin:" + spec.name},
              {"robot", spec.robot},
              {"res", a.res > 0 ? a.res : DefaultResolution(spec.robot)},
              {"twin_doc", spec.doc},
              {"noise_sigma_mm", spec.noise_sigma_mm},
              {"gradient_tolerance", twin->simulator().fk_options().gradient_tolerance},
              {"noise_seed", spec.noise_seed}};
  out.kin = std::move(twin);
  return out;
}

/// The run's counts and times on stderr.
void ReportSummary(const DatasetRunSummary& s) {
  char line[300];
  std::snprintf(line, sizeof line,
                "softkin dataset: samples [%lld, %lld): %lld already in the file, %lld written "
                "(%lld failed, %lld with inverted elements) in %.1f s (%.1f ms/sample, %lld "
                "forward solves)\n",
                s.first, s.first + s.count, s.already, s.written, s.failed, s.inverted, s.time_s,
                s.written > 0 ? 1e3 * s.time_s / s.written : 0.0, s.fk_solves);
  std::cerr << line;
  if (s.inverted > 0)
    std::cerr << "softkin dataset: WARNING: " << s.inverted
              << " sample(s) solved to states with inverted body elements: marked 'inverted' "
                 "in the status column and left out of training\n";
}

}  // namespace

int RunDatasetCommand(const DatasetCommandArgs& a) {
  // Before any work: --out and its sidecar are not inputs (shards) and can be written.
  std::vector<NamedPath> shards;
  for (const std::string& m : a.merge) {
    shards.push_back({"--merge", m});
    shards.push_back({"--merge sidecar", m + ".json"});
  }
  CheckCommandPaths(shards, {{"--out", a.out}, {"--out's sidecar", a.out + ".json"}});
  if (!a.merge.empty()) return MergeCommand(a);
  if (a.robot.empty() == a.twin.empty())
    throw std::invalid_argument("dataset: give exactly one of --robot NAME or --twin NAME");
  if (a.res < 0) throw std::invalid_argument("--res: expected a positive integer");
  const DatasetSampling sampling = SamplingFromArgs(a);
  const bool with_j = a.jacobian != "none";
  SimulatorKinematicsOptions ko;
  if (with_j && !JacobianModeFromString(a.jacobian, &ko.jacobian))
    throw std::invalid_argument("--jacobian: unknown mode '" + a.jacobian + "' (expected none, " +
                                JacobianModeNames() + ")");
  if (!a.twin.empty() && with_j)
    throw std::invalid_argument(
        "--jacobian: a twin gives positions only (hardware has no "
        "Jacobian); use --jacobian none with --twin");
  DatasetRunOptions run;
  run.out = a.out;
  run.jacobian = with_j;
  run.progress = !a.quiet;
  if (!a.shard.empty()) {
    int k = -1, n = -1;
    char tail = 0;
    if (std::sscanf(a.shard.c_str(), "%d/%d%c", &k, &n, &tail) != 2 || n < 1 || k < 0 || k >= n)
      throw std::invalid_argument("--shard: expected k/n with integers 0 <= k < n, got '" +
                                  a.shard + "'");
    run.shard = k;
    run.shards = n;
  }
  const std::vector<std::string> points = SplitComma(a.points, "--points");
  for (size_t i = 0; i < points.size(); ++i)
    for (size_t j = 0; j < i; ++j)
      if (points[i] == points[j])
        throw std::invalid_argument("--points: expected each point once, got '" + points[i] +
                                    "' twice");
  DatasetSource source =
      a.robot.empty() ? TwinSource(a, points, &run) : RobotSource(a, ko, points, &run);
  run.source = source.json;
  run.provenance = {{"git_commit", GitCommit()}, {"command", a.command_line}};

  const long long total = DatasetSize(sampling, source.kin->num_actuators());
  if (a.dry_run) {
    const ShardRange slice = DatasetShard(total, sampling.block, run.shard, run.shards);
    std::cout << nlohmann::json{{"samples", total},
                                {"block", sampling.block},
                                {"units", (total + sampling.block - 1) / sampling.block},
                                {"shard", {{"k", run.shard}, {"n", run.shards}}},
                                {"first", slice.first},
                                {"count", slice.count},
                                {"out", a.out}}
                     .dump()
              << "\n";
    return 0;
  }
  RequireMpiIfLaunched("dataset --out " + a.out);
  const int ranks = LaunchedMpiSize();
  if (ranks > 1) {
    if (!a.shard.empty())
      throw std::invalid_argument("--shard: not under mpirun, where the ranks share the samples");
    const bool root = LaunchedMpiRank() == 0;
    run.progress = run.progress && root;
    if (run.progress)
      std::cerr << "softkin dataset: " << source.kin->name() << " of "
                << (a.robot.empty() ? a.twin : a.robot) << ", " << total << " samples on " << ranks
                << " MPI ranks, points " << a.points << ", jacobian " << a.jacobian << " -> "
                << a.out << "\n";
    const DatasetRunSummary s = GenerateDatasetMpi(*source.kin, sampling, run);
    if (run.progress) ReportSummary(s);
    return s.failed > 0 ? 1 : 0;
  }
  if (!a.quiet)
    std::cerr << "softkin dataset: " << source.kin->name() << " of "
              << (a.robot.empty() ? a.twin : a.robot) << ", " << total << " samples"
              << (run.shards > 1 ? " (shard " + a.shard + ")" : "") << ", points " << a.points
              << ", jacobian " << a.jacobian << " -> " << a.out << "\n";
  const DatasetRunSummary s = GenerateDataset(*source.kin, sampling, run);
  if (!a.quiet) ReportSummary(s);
  return s.failed > 0 ? 1 : 0;
}

}  // namespace softkin
