#pragma once
/// \file cli_tessellate.hpp
/// `softkin tessellate`: the volume tessellation T(S_c, S_b) of a closed body surface with a
/// closed chamber surface inside it (thesis Sec. 3.2.1; docs/remeshing.md), written as .vtu, .vtk,
/// .msh or TetGen .node/.ele.
#include "softkin/solver/remesh/tessellation.hpp"

#include <CLI/CLI.hpp>

#include <string>

namespace softkin {

/// The values of `softkin tessellate`'s options, filled in by CLI11.
struct TessellateCommandArgs {
  std::string body, chamber, out, json_out;
  TessellationOptions options;  ///< cell_size, facet_size, facet_distance, feature_angle, seed
};

/// Adds the `tessellate` subcommand to `app`, bound to *args; returns it.
CLI::App* AddTessellateCommand(CLI::App* app, TessellateCommandArgs* args);

/// Runs `softkin tessellate`. Throws std::invalid_argument for bad input (naming the option) and
/// std::runtime_error when meshing or writing fails; returns the exit code (0).
int RunTessellateCommand(const TessellateCommandArgs& args);

}  // namespace softkin
