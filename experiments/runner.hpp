#pragma once
/// \file runner.hpp
/// `softkin run CONFIG`: dispatches an experiment config to its experiment, writes
/// results/<name>/{summary.json, config.json, run.json, *.csv} and, unless disabled, runs the
/// matching paper_figs/<name>.py to make the PNG.
#include "softkin/experiments/config.hpp"
#include "softkin/solver/scene/scene.hpp"

#include <nlohmann/json.hpp>

#include <string>
#include <vector>

namespace softkin {

struct RunOptions {
  bool quick = false;
  bool plot = true;
  std::string results_root = "results";
  bool verbose = true;  ///< progress on stderr
};

/// An experiment reads its keys from the config (then CheckNoUnknownKeys), runs, writes CSVs into
/// `dir` and returns its summary (headline numbers).
using ExperimentFn = nlohmann::json (*)(const Config& cfg, const std::string& dir, bool verbose);

/// Registered experiment types ("pneumatic_bending", "resolution_sweep", "aa_ablation").
std::vector<std::string> ExperimentTypes();
ExperimentFn FindExperiment(const std::string& type);
/// The types that `mpirun -n N softkin run CONFIG` shares out over the ranks (sweeps of
/// independent units, experiments/sweep.hpp).
std::vector<std::string> MpiExperimentTypes();

/// Runs one config; returns the summary written. Throws std::invalid_argument for bad configs and
/// std::runtime_error if a step fails (finished CSV rows are kept). Under an MPI launcher, a sweep
/// type shares its units over the ranks and rank 0 writes the results (the others return {}); any
/// other type is refused with std::invalid_argument.
nlohmann::json RunExperiment(const std::string& config_path, const RunOptions& options);

/// The config's robot at resolution `res` with its "robot_params" object (design parameters);
/// errors from the robot generator are reported with the config's path and key.
Scene ConfigRobot(const Config& cfg, const std::string& robot, int res);

// Experiments (each in its own file).
nlohmann::json RunPneumaticBending(const Config& cfg, const std::string& dir, bool verbose);
nlohmann::json RunResolutionSweep(const Config& cfg, const std::string& dir, bool verbose);
/// Convergence under refinement, robot by robot (exp_refinement.cpp).
nlohmann::json RunRefinement(const Config& cfg, const std::string& dir, bool verbose);
/// SoftKin against the pressure-driven CalculiX FEM at equal chamber volume (exp_fidelity_fem.cpp).
nlohmann::json RunFidelityFem(const Config& cfg, const std::string& dir, bool verbose);
nlohmann::json RunSolverScaling(const Config& cfg, const std::string& dir, bool verbose);
nlohmann::json RunAaAblation(const Config& cfg, const std::string& dir, bool verbose);
nlohmann::json RunActuationPaths(const Config& cfg, const std::string& dir, bool verbose);
nlohmann::json RunMarkerSweep(const Config& cfg, const std::string& dir, bool verbose);
nlohmann::json RunSolverComparison(const Config& cfg, const std::string& dir, bool verbose);
nlohmann::json RunCalibration(const Config& cfg, const std::string& dir, bool verbose);
nlohmann::json RunHyperelasticFit(const Config& cfg, const std::string& dir, bool verbose);
nlohmann::json RunCollisionSweep(const Config& cfg, const std::string& dir, bool verbose);
nlohmann::json RunCollisionCosts(const Config& cfg, const std::string& dir, bool verbose);
// Chapter 4 (experiments/exp_ik.cpp, exp_pick_place.cpp).
nlohmann::json RunIkInitialGuess(const Config& cfg, const std::string& dir, bool verbose);
nlohmann::json RunIkTrajectory(const Config& cfg, const std::string& dir, bool verbose);
nlohmann::json RunIkMethods(const Config& cfg, const std::string& dir, bool verbose);
nlohmann::json RunIkPickAndPlace(const Config& cfg, const std::string& dir, bool verbose);
// Chapter 5 (experiments/exp_learn.cpp; the sim-to-real ones in exp_learn_s2r.cpp).
nlohmann::json RunLearnArchitecture(const Config& cfg, const std::string& dir, bool verbose);
nlohmann::json RunLearnIkMethods(const Config& cfg, const std::string& dir, bool verbose);
nlohmann::json RunLearnDataSource(const Config& cfg, const std::string& dir, bool verbose);
nlohmann::json RunLearnS2rSweep(const Config& cfg, const std::string& dir, bool verbose);
nlohmann::json RunLearnS2rPaths(const Config& cfg, const std::string& dir, bool verbose);
nlohmann::json RunLearnRedundantPath(const Config& cfg, const std::string& dir, bool verbose);

}  // namespace softkin
