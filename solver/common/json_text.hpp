#pragma once
/// \file json_text.hpp
/// JSON text read strictly, for every JSON a user writes (scenes, experiment configs): syntax
/// errors as "<source>:<line>:<column>: invalid JSON: ...", a key given twice in one object as an
/// error naming its path, and a number beyond double's range naming its key.
#include <nlohmann/json.hpp>

#include <string>

namespace softkin {

/// Parses `text`; `source` (a file name) starts every message. Throws std::invalid_argument.
nlohmann::json ParseJsonText(const std::string& text, const std::string& source);

}  // namespace softkin
