#pragma once
/// \file cli_dataset.hpp
/// `softkin dataset`: generate a learning dataset (thesis Sec. 5.3.2) from an embedded robot's
/// simulator or from a "hardware" twin (learn/twin.hpp), resumable and shardable, or merge shard
/// files (learn/dataset.hpp, docs/datasets.md).
#include "softkin/experiments/cli_args.hpp"

#include <CLI/CLI.hpp>

#include <string>
#include <vector>

namespace softkin {

/// The values of `softkin dataset`'s options, filled in by CLI11.
struct DatasetCommandArgs {
  std::string robot, twin;
  int res = 0;
  std::vector<std::string> params;
  int grid = 0;          ///< 0: not given
  long long random = 0;  ///< 0: not given
  long long seed = -1;   ///< -1: not given
  int block = 64;
  std::string points = "tip";
  std::string jacobian = "none";
  std::string shard;         ///< "k/n", empty: the whole dataset
  FkOptionFlags fk_options;  ///< --gradient-tolerance: over the robot's FK options (cli_args.hpp)
  std::vector<std::string> merge;
  std::string out;
  bool quiet = false;
  bool dry_run = false;      ///< --dry-run: print the plan and exit
  std::string command_line;  ///< the whole command line, for the sidecar (set by RunCli)
};

/// Adds the `dataset` subcommand to `app`, bound to *args; returns it.
CLI::App* AddDatasetCommand(CLI::App* app, DatasetCommandArgs* args);

/// Runs `softkin dataset`. Throws std::invalid_argument for bad input (naming the option, or the
/// file and line) and std::runtime_error when a file cannot be written; returns the exit code
/// (0: every sample evaluated, 1: some samples failed and were recorded as failed).
int RunDatasetCommand(const DatasetCommandArgs& args);

}  // namespace softkin
