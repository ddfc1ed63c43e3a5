#pragma once
/// \file cli_fk.hpp
/// `softkin fk`: forward kinematics of an embedded robot or a scene file for one actuation; the
/// result (status, energy, markers, the final collision check) as JSON, the deformed mesh as .vtu
/// or .obj.
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
  std::string solver;  ///< empty: the scene's
  // Solver settings that override the scene's when given (a given 0 is validated, not ignored).
  int continuation = 0;
  int max_iterations = 0;
  double tolerance = 0;
  double gradient_tolerance = 0;
  std::string safeguard;
  bool continuation_given = false;
  bool max_iterations_given = false;
  bool tolerance_given = false;
  bool gradient_tolerance_given = false;
  bool safeguard_given = false;
  /// --set KEY=VALUE: any solver option by its scene-schema key (solver.* without the prefix),
  /// applied after the flags above.
  std::vector<std::string> set;
  // Outputs.
  std::string json_out, vtu_out, obj_out;
};

/// Adds the `fk` subcommand to `app`, bound to *args; returns it.
CLI::App* AddFkCommand(CLI::App* app, FkCommandArgs* args);

/// Runs `softkin fk`. Throws std::invalid_argument for bad input (naming the option) and
/// std::runtime_error when a file cannot be written; returns the exit code (0: converged, 1: not).
int RunFkCommand(const FkCommandArgs& args);

}  // namespace softkin
