#pragma once
/// \file solver_options_json.hpp
/// FK solver options as JSON: the one reader and writer of the `solver` object, used by the scene
/// JSON (scene_json.hpp) and by experiment configs (experiments/config.hpp). Each key is checked
/// against the scene schema's `solver.*` entry (softkin scene --schema): its type, range and
/// allowed values, so the schema documents exactly what every reader accepts.
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
/// the nested "collision" object).
nlohmann::json SolverOptionsToJson(const FkOptions& o);

/// The option keys, with the collision options as "collision.<key>", in schema order.
std::vector<std::string> SolverOptionKeys();

}  // namespace softkin
