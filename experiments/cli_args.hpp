#pragma once
/// \file cli_args.hpp
/// Parsing of `softkin` option values shared by several commands. Every error is a
/// std::invalid_argument that names the option and says what was expected.
#include "softkin/solver/common/output_file.hpp"
#include "softkin/solver/fk/fk_options.hpp"
#include "softkin/solver/robots/robots.hpp"

#include <Eigen/Core>
#include <nlohmann/json.hpp>

#include <map>
#include <string>
#include <vector>

namespace CLI {
class App;
class Option;
}  // namespace CLI

namespace softkin {

/// "v1,v2,..." -> numbers (finite, at least one). `option` names the flag in errors.
Eigen::VectorXd ParseNumberList(const std::string& text, const std::string& option);

/// Repeated "--param NAME=VALUE" values -> robot design parameters (finite numbers).
RobotParams ParseRobotParams(const std::vector<std::string>& items);

/// A command-line value as JSON: the JSON value if the text is one (a number, true, false), else
/// the text as a string.
nlohmann::json CommandLineValue(const std::string& text);

/// Flags of FK solver options, generated from the option table (solver/scene/
/// solver_options_json.hpp): option KEY is the flag --KEY with '_' and '.' as '-'
/// (max_iterations: --max-iterations, collision.self: --collision-self). Each takes one value
/// (CommandLineValue).
struct FkOptionFlags {
  std::map<std::string, std::string> given;  ///< option key -> the value given on the command line
};

/// The flag of option `key`: "max_iterations" -> "--max-iterations".
std::string FkOptionFlagName(const std::string& key);

/// Adds to `cmd` the flags of the options `keys` (empty: every option of the table), bound to
/// *flags; returns them in table order. `aliases` gives some options one more flag name (key ->
/// "--name"), e.g. the short names of older command lines. Help: the option's doc line and its
/// values, which override the scene's.
std::vector<CLI::Option*> AddFkOptionFlags(CLI::App* cmd, FkOptionFlags* flags,
                                           const std::vector<std::string>& keys = {},
                                           const std::map<std::string, std::string>& aliases = {});

/// `base` with the given flags applied (in table order), each read by ReadSolverOptionsJson, so an
/// error names the flag, the option and what was expected, e.g. "--max-iterations:
/// solver.max_iterations: expected an integer >= 1, got 0".
FkOptions ApplyFkOptionFlags(const FkOptionFlags& flags, const FkOptions& base);

/// The files a scene JSON reads: the scene itself (as `option`), its mesh.file and mesh.labels
/// and its obstacles' files, resolved as the scene reader resolves them. Empty `scene`: none. An
/// unreadable or malformed scene gives just the scene (its reader reports the error later).
std::vector<NamedPath> SceneInputs(const std::string& scene, const std::string& option = "--scene");

/// Before any work: refuses an output that is an input or another output, and an output that
/// cannot be written (CheckDistinctPaths, CheckOutputPath; empty paths are skipped).
void CheckCommandPaths(const std::vector<NamedPath>& inputs, const std::vector<NamedPath>& outputs);

}  // namespace softkin
