#pragma once
/// \file cli_scene.hpp
/// `softkin scene`: load a scene JSON and print its sizes, or print the scene schema.
#include <CLI/CLI.hpp>

#include <string>

namespace softkin {

/// The values of `softkin scene`'s options, filled in by CLI11.
struct SceneCommandArgs {
  bool schema = false;  ///< print the schema instead of checking a file
  std::string file;     ///< the scene JSON to check
};

/// Adds the `scene` subcommand to `app`, bound to *args; returns it.
CLI::App* AddSceneCommand(CLI::App* app, SceneCommandArgs* args);

/// Runs `softkin scene`. Throws std::invalid_argument for a missing file argument or a bad scene;
/// returns the exit code (0).
int RunSceneCommand(const SceneCommandArgs& args);

}  // namespace softkin
