#pragma once
/// \file cli_robots.hpp
/// `softkin robots`: the embedded robots with their actuators, markers, design parameters and
/// sizes, as a table or as JSON.
#include <CLI/CLI.hpp>

namespace softkin {

/// The values of `softkin robots`'s options, filled in by CLI11.
struct RobotsCommandArgs {
  bool json = false;  ///< print JSON instead of a table
};

/// Adds the `robots` subcommand to `app`, bound to *args; returns it.
CLI::App* AddRobotsCommand(CLI::App* app, RobotsCommandArgs* args);

/// Runs `softkin robots`; returns the exit code (0).
int RunRobotsCommand(const RobotsCommandArgs& args);

}  // namespace softkin
