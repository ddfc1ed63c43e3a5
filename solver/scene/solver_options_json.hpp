#pragma once
/// \file solver_options_json.hpp
/// The FK solver options' one table and the one reader and writer of the `solver` object. Each
/// option of FkOptions is defined once, in solver_options_json.cpp: its key, doc line, type and
/// range or allowed values (an enum's names), default (a default-constructed FkOptions') and how to
/// read and write it. From that table come
///  - the scene schema's `solver.*` entries (softkin scene --schema; scene_keys.hpp),
///  - the reader of the scene JSON's `solver` object (scene_json.hpp) and of experiment configs
///    (experiments/config.hpp), which checks each value against its entry,
///  - the command-line flags of `softkin fk` and the FK flags of other commands
///    (experiments/cli_args.hpp), whose values go through the same reader.
#include "softkin/solver/fk/fk_options.hpp"

#include <nlohmann/json.hpp>

#include <string>
#include <vector>

namespace softkin {

/// Reads the options present in `j` (a JSON object such as {"solver": "lg", "collision": {"self":
/// true}}) over `base`: keys left out keep base's values. Throws std::invalid_argument naming
/// `where`.key and what was expected for a value of the wrong type or out of range, an unknown
/// key (listing the known ones), or options that fail FkOptions::IsValid.
FkOptions ReadSolverOptionsJson(const nlohmann::json& j, const std::string& where,
                                const FkOptions& base);

/// Every option of `o` as JSON, in the layout ReadSolverOptionsJson reads (collision options in
/// the nested "collision" object); enum options as their names.
nlohmann::json SolverOptionsToJson(const FkOptions& o);

/// One option of the table as help texts show it.
struct SolverOptionDoc {
  std::string key;               ///< below `solver.`; collision options as "collision.<key>"
  std::string value;             ///< what a value must be, e.g. "an integer >= 1", "one of: a, b"
  std::string doc;               ///< the schema's doc line
  nlohmann::json default_value;  ///< a default-constructed FkOptions' value
};

/// Every option of the table, in schema order.
std::vector<SolverOptionDoc> SolverOptionDocs();

/// The option keys, with the collision options as "collision.<key>", in schema order.
std::vector<std::string> SolverOptionKeys();

}  // namespace softkin
