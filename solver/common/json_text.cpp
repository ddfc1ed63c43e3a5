/// \file json_text.cpp
/// ParseJsonText (json_text.hpp): nlohmann's parser with a callback that tracks the key path.
#include "softkin/solver/common/json_text.hpp"

#include <algorithm>
#include <set>
#include <stdexcept>
#include <vector>

namespace softkin {

nlohmann::json ParseJsonText(const std::string& text, const std::string& source) {
  using json = nlohmann::json;
  struct Frame {
    bool array = false;
    std::set<std::string> keys;
    std::string key;
    int index = 0;
  };
  std::vector<Frame> stack;
  auto path_of = [&](size_t n) {
    std::string p;
    for (size_t i = 0; i < n; ++i) {
      if (stack[i].array)
        p += "[" + std::to_string(stack[i].index) + "]";
      else
        p += (p.empty() ? "" : ".") + stack[i].key;
    }
    return p;
  };
  json::parser_callback_t cb = [&](int, json::parse_event_t ev, json& parsed) {
    switch (ev) {
      case json::parse_event_t::object_start:
        stack.push_back(Frame{});
        break;
      case json::parse_event_t::array_start: {
        Frame f;
        f.array = true;
        stack.push_back(std::move(f));
        break;
      }
      case json::parse_event_t::key: {
        const std::string k = parsed.get<std::string>();
        Frame& f = stack.back();
        if (!f.keys.insert(k).second) {
          const std::string p = path_of(stack.size() - 1);
          throw std::invalid_argument(source + ": " + (p.empty() ? "" : p + ": ") +
                                      "duplicate key '" + k + "'; expected each key once");
        }
        f.key = k;
        break;
      }
      case json::parse_event_t::object_end:
      case json::parse_event_t::array_end:
        stack.pop_back();
        if (!stack.empty() && stack.back().array) ++stack.back().index;
        break;
      case json::parse_event_t::value:
        if (!stack.empty() && stack.back().array) ++stack.back().index;
        break;
    }
    return true;
  };
  try {
    return json::parse(text, cb);
  } catch (const json::out_of_range& e) {         // a number beyond double's range (1e400)
    const std::string p = path_of(stack.size());  // the innermost key is the number's
    std::string what = e.what();
    const auto bracket = what.find("] ");
    if (bracket != std::string::npos) what = what.substr(bracket + 2);
    throw std::invalid_argument(source + ": " + (p.empty() ? "" : p + ": ") + what +
                                "; expected a number within +-1.8e308");
  } catch (const json::parse_error& e) {
    // e.byte counts the characters read, the offending one included; turn it into line:column.
    size_t at = e.byte == 0 ? 0 : e.byte - 1;
    at = std::min(at, text.size());
    int line = 1;
    size_t line_start = 0;
    for (size_t i = 0; i < at; ++i)
      if (text[i] == '\n') {
        ++line;
        line_start = i + 1;
      }
    const size_t column = at - line_start + 1;
    std::string what = e.what();
    const auto pe = what.find("parse error");
    if (pe != std::string::npos) {
      const auto colon = what.find(": ", pe);
      if (colon != std::string::npos) what = what.substr(colon + 2);
    }
    throw std::invalid_argument(source + ":" + std::to_string(line) + ":" + std::to_string(column) +
                                ": invalid JSON: " + what);
  }
}

}  // namespace softkin
