#pragma once
/// \file cli_fk.hpp
/// `softkin fk`: forward kinematics of an embedded robot or a scene file for one actuation; the
/// result (status, energy, markers, the final collision check) as JSON, the deformed mesh as .vtu
/// or .obj.
#include "softkin/experiments/cli_args.hpp"
#include "softkin/solver/fk/fk_options.hpp"

#include <CLI/CLI.hpp>

#include <string>
#include <vector>

namespace softkin {

/// The values of `softkin fk`'s options, filled in by CLI11.
struct FkCommandArgs {
  std::string robot, scene;
  int res = 0;
  std::vector<std::string> params;
  std::string actuation;
  /// One flag per solver option (--solver, --max-iterations, --collision-self, ...; cli_args.hpp),
  /// overriding the scene's options when given.
  FkOptionFlags options;
  /// --set KEY=VALUE: any solver option by its scene-schema key (solver.* without the prefix),
  /// applied after the flags above.
  std::vector<std::string> set;
  // Outputs.
  std::string json_out, vtu_out, obj_out;
};

/// Adds the `fk` subcommand to `app`, bound to *args; returns it.
CLI::App* AddFkCommand(CLI::App* app, FkCommandArgs* args);

/// The solver options of `softkin fk`: `base` (the scene's) with the option flags, then --set,
/// applied and validated. Throws std::invalid_argument naming the flag and what was expected.
FkOptions FkOptionsFromArgs(const FkCommandArgs& args, const FkOptions& base);

/// Runs `softkin fk`. Throws std::invalid_argument for bad input (naming the option) and
/// std::runtime_error when a file cannot be written; returns the exit code (0: converged, 1: not).
int RunFkCommand(const FkCommandArgs& args);

}  // namespace softkin
