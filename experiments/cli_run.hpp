#pragma once
/// \file cli_run.hpp
/// `softkin run CONFIG`: runs an experiment config (experiments/runner.hpp).
#include "softkin/experiments/runner.hpp"

#include <CLI/CLI.hpp>

#include <string>

namespace softkin {

/// The values of `softkin run`'s options, filled in by CLI11.
struct RunCommandArgs {
  std::string config;
  RunOptions options;    ///< quick and results_root from the command line
  bool no_plot = false;  ///< sets options.plot to false
};

/// Adds the `run` subcommand to `app`, bound to *args; returns it.
CLI::App* AddRunCommand(CLI::App* app, RunCommandArgs* args);

/// Runs `softkin run`. Throws std::invalid_argument for a bad config and std::runtime_error when
/// the experiment fails; returns the exit code (0).
int RunRunCommand(const RunCommandArgs& args);

}  // namespace softkin
