#include "softkin/experiments/runner.hpp"

#include "softkin/solver/robots/robots.hpp"

#include "softkin/experiments/mpi_job.hpp"
#include "softkin/experiments/results.hpp"
#include "softkin/solver/common/output_file.hpp"
#include "softkin/solver/common/stopwatch.hpp"

#include <algorithm>
#include <chrono>
#include <cstdlib>
#include <filesystem>
#include <iostream>
#include <stdexcept>

namespace softkin {

namespace fs = std::filesystem;

// Declared here rather than in runner.hpp: experiments/exp_remesh.cpp (Fig. 3.7).
nlohmann::json RunTwistingRemesh(const Config& cfg, const std::string& dir, bool verbose);

namespace {
struct Entry {
  const char* type;
  ExperimentFn fn;
  /// A sweep of independent units (experiments/sweep.hpp) that `mpirun -n N softkin run` shares
  /// out over the ranks; the others run in one process.
  bool mpi = false;
};
const Entry kExperiments[] = {
    {"pneumatic_bending", &RunPneumaticBending},
    {"resolution_sweep", &RunResolutionSweep},
    {"refinement", &RunRefinement, true},
    {"fidelity_fem", &RunFidelityFem},
    {"solver_scaling", &RunSolverScaling},
    {"marker_sweep", &RunMarkerSweep},
    {"solver_comparison", &RunSolverComparison},
    {"calibration", &RunCalibration},
    {"hyperelastic_fit", &RunHyperelasticFit},
    {"collision_sweep", &RunCollisionSweep},
    {"collision_costs", &RunCollisionCosts},
    {"aa_ablation", &RunAaAblation},
    {"actuation_paths", &RunActuationPaths},
    {"twisting_remesh", &RunTwistingRemesh},
    {"ik_initial_guess", &RunIkInitialGuess},
    {"ik_trajectory", &RunIkTrajectory},
    {"ik_methods", &RunIkMethods, true},
    {"ik_pick_and_place", &RunIkPickAndPlace},
    {"learn_architecture", &RunLearnArchitecture, true},
    {"learn_ik_methods", &RunLearnIkMethods},
    {"learn_data_source", &RunLearnDataSource},
    {"learn_s2r_sweep", &RunLearnS2rSweep},
    {"learn_s2r_paths", &RunLearnS2rPaths},
    {"learn_redundant_path", &RunLearnRedundantPath},
};
}  // namespace

std::vector<std::string> ExperimentTypes() {
  std::vector<std::string> v;
  for (const auto& e : kExperiments) v.push_back(e.type);
  return v;
}

Scene ConfigRobot(const Config& cfg, const std::string& robot, int res) {
  const auto params = cfg.NumberMap("robot_params");
  try {
    return MakeRobot(robot, res, params);
  } catch (const std::invalid_argument& e) {
    throw std::invalid_argument(cfg.path() + ": robot '" + robot + "' (keys robot, res, " +
                                "robot_params): " + e.what());
  }
}

ExperimentFn FindExperiment(const std::string& type) {
  for (const auto& e : kExperiments)
    if (type == e.type) return e.fn;
  return nullptr;
}

std::vector<std::string> MpiExperimentTypes() {
  std::vector<std::string> v;
  for (const auto& e : kExperiments)
    if (e.mpi) v.push_back(e.type);
  return v;
}

nlohmann::json RunExperiment(const std::string& config_path, const RunOptions& opt) {
  Config cfg = Config::Load(config_path, opt.quick);
  ExperimentFn fn = FindExperiment(cfg.type());
  if (!fn) {
    std::string known;
    for (const auto& t : ExperimentTypes()) known += (known.empty() ? "" : ", ") + t;
    cfg.Fail("experiment", "one of " + known);
  }
  if (opt.quick && cfg.has_quick()) {
    // The full settings, which the quick overrides hide, are checked too (reading only).
    Config full = Config::Load(config_path, false);
    full.set_check_only(true);
    try {
      fn(full, std::string(), false);
    } catch (const std::invalid_argument& e) {
      throw std::invalid_argument(std::string("--quick: the full settings (without the quick "
                                              "overrides) are invalid: ") +
                                  e.what());
    }
  }
  // Under mpirun: only the sweeps share their units over the ranks; rank 0 writes the results.
  const std::string what = "run " + cfg.name();
  RequireMpiIfLaunched(what);
  if (LaunchedMpiSize() > 1) {
    const auto mpi_types = MpiExperimentTypes();
    if (std::find(mpi_types.begin(), mpi_types.end(), cfg.type()) == mpi_types.end()) {
      std::string list;
      for (const auto& t : mpi_types) list += (list.empty() ? "" : ", ") + t;
      throw std::invalid_argument(what + ": started by an MPI launcher with " +
                                  std::to_string(LaunchedMpiSize()) + " processes, but '" +
                                  cfg.type() +
                                  "' is not a sweep of independent units; run it as one process "
                                  "(the sweeps that MPI shares out: " +
                                  list + ")");
    }
  }
  const MpiPlace& job = MpiJob();
  const bool root = job.root();
  const std::string dir = ResultDir(opt.results_root, cfg.name());
  // The run writes the config it used to RESULTS/<name>/config.json: never over the input.
  CheckDistinctPaths({{"config", config_path}},
                     {{"the run's copy of its config", dir + "/config.json"}});
  if (root) WriteJson(dir + "/config.json", cfg.json());
  nlohmann::json run;
  run["config_path"] = config_path;
  run["quick"] = opt.quick;
  run["git_commit"] = GitCommit();
  run["machine"] = MachineInfo();
  run["seed"] = cfg.seed();
  const auto t0 = std::chrono::steady_clock::now();
  if (opt.verbose && root)
    std::cerr << "softkin: running " << cfg.name() << (opt.quick ? " (quick)" : "")
              << (job.active() ? " on " + std::to_string(job.size) + " MPI ranks" : "") << "\n";
  nlohmann::json summary = fn(cfg, dir, opt.verbose && root);
  if (!root) return {};  // the other ranks computed units; rank 0 writes the results
  run["mpi_ranks"] = job.size;
  const double wall = SecondsSince(t0);
  run["wall_time_s"] = wall;
  summary["name"] = cfg.name();
  summary["experiment"] = cfg.type();
  summary["quick"] = opt.quick;
  summary["seed"] = cfg.seed();
  summary["git_commit"] = run["git_commit"];
  summary["machine"] = run["machine"];
  summary["config"] = cfg.json();
  summary["wall_time_s"] = wall;
  WriteJson(dir + "/summary.json", summary);
  WriteJson(dir + "/run.json", run);
  if (opt.verbose) std::cerr << "softkin: wrote " << dir << "/summary.json (" << wall << " s)\n";

  if (opt.plot) {
    const fs::path script = fs::path(SOFTKIN_SOURCE_DIR) / "paper_figs" / (cfg.name() + ".py");
    if (fs::exists(script)) {
      const std::string cmd = "/usr/bin/python3 '" + script.string() + "' '" + dir + "'";
      if (opt.verbose) std::cerr << "softkin: plotting: " << cmd << "\n";
      const int rc = std::system(cmd.c_str());
      if (rc != 0)
        throw std::runtime_error("the plot script " + script.string() + " failed (exit " +
                                 std::to_string(rc) + "); results are in " + dir +
                                 "; is python3-matplotlib installed?");
    } else if (opt.verbose) {
      std::cerr << "softkin: no plot script " << script.string() << "\n";
    }
  }
  return summary;
}

}  // namespace softkin
