#pragma once
/// \file cli_ik.hpp
/// `softkin ik`: simulation-in-the-loop inverse kinematics of an embedded robot or a scene file for
/// one target point or a waypoint file (thesis Algorithm 4), one CSV row per waypoint as it
/// finishes, resumable (docs/ik.md, "The softkin ik command").
#include "softkin/experiments/cli_args.hpp"

#include <CLI/CLI.hpp>

#include <string>
#include <vector>

namespace softkin {

/// The values of `softkin ik`'s options, filled in by CLI11.
struct IkCommandArgs {
  std::string robot, scene;
  int res = 0;
  std::vector<std::string> params;
  std::string target, trajectory;
  std::string point = "tip";
  std::string method = "softls";
  std::string jacobian = "implicit";
  double lambda_mm = 0.2;
  int max_iterations = 30;
  int max_evaluations = 300;
  int samples = 5;
  int first_starts = 3;
  double max_time_s = 600;
  FkOptionFlags fk_options;  ///< --gradient-tolerance: over the scene's FK options (cli_args.hpp)
  std::string cache;
  std::string out;
  bool resume = false;
  bool quiet = false;
  bool trace_fk = false;
  // ---- learned kinematics (thesis Ch. 5; docs/learning.md) ----
  std::string nets;                         ///< network directory from `softkin train`
  std::string jacobian_source = "network";  ///< network (N_J) or fk-derivative (dN_fk/dc)
  bool s2r = false;                         ///< drive the sim-to-real corrected kinematics
  bool interactive = false;                 ///< targets from stdin, rows to stdout (Fig. 5.13)
};

/// Adds the `ik` subcommand to `app`, bound to *args; returns it.
CLI::App* AddIkCommand(CLI::App* app, IkCommandArgs* args);

/// Runs `softkin ik`. Throws std::invalid_argument for bad input (the message names the option, or
/// the file and line) and std::runtime_error when a file cannot be written; returns the exit code
/// (0: every waypoint was solved, converged or not; 1: the kinematics failed at some waypoint).
int RunIkCommand(const IkCommandArgs& args);

}  // namespace softkin
