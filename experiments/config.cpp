#include "softkin/experiments/config.hpp"
#include "softkin/solver/common/input_file.hpp"

#include "softkin/solver/common/json_text.hpp"

#include "softkin/solver/scene/solver_options_json.hpp"

#include <fstream>
#include <sstream>
#include <stdexcept>

namespace softkin {

namespace {
std::string Dump(const nlohmann::json& v) {
  std::string s = v.dump();
  return s.size() > 60 ? s.substr(0, 57) + "..." : s;
}
/// The JSON kind of a value, in a config's words.
std::string Kind(const nlohmann::json& v) {
  if (v.is_boolean()) return "a boolean";
  if (v.is_number()) return "a number";
  if (v.is_string()) return "a string";
  if (v.is_array()) return "an array";
  if (v.is_object()) return "an object";
  return "null";
}

/// Empty if `over` (a quick override) has the kind of `full`, the value it replaces: the same JSON
/// kind, and for non-empty arrays the same kind of elements; else the kind expected.
std::string OverrideMismatch(const nlohmann::json& full, const nlohmann::json& over) {
  if (Kind(full) != Kind(over)) return Kind(full);
  if (full.is_array() && !full.empty() && !over.empty()) {
    const std::string a = Kind(full.front());
    for (const auto& x : over)
      if (Kind(x) != a) return "an array of " + a.substr(a.find(' ') + 1) + "s";
  }
  return "";
}

}  // namespace

Config Config::Load(const std::string& path, bool quick) {
  Config c;
  c.path_ = path;
  c.quick_ = quick;
  CheckInputFile(path, "an experiment config (.json)");
  std::ifstream f(path);
  if (!f) throw std::invalid_argument(path + ": cannot open experiment config");
  std::stringstream ss;
  ss << f.rdbuf();
  const std::string text = ss.str();
  // Syntax errors by line and column, duplicate keys and out-of-range numbers by key, as scenes.
  c.j_ = ParseJsonText(text, path);
  if (!c.j_.is_object()) throw std::invalid_argument(path + ": expected a JSON object at the top");
  if (c.j_.contains("quick")) {
    if (!c.j_["quick"].is_object()) c.Fail("quick", "an object of overrides");
    c.has_quick_ = true;
    nlohmann::json q = c.j_["quick"];
    // Checked in both modes, so that a full run's validation (the experiment's getters) also
    // covers the kind of every value a quick run puts in its place, and the other way round.
    for (auto it = q.begin(); it != q.end(); ++it) {
      if (!c.j_.contains(it.key()))
        throw std::invalid_argument(path + ": quick." + it.key() +
                                    ": overrides a key that the config does not have");
      const std::string why = OverrideMismatch(c.j_[it.key()], it.value());
      if (!why.empty())
        throw std::invalid_argument(path + ": quick." + it.key() + ": expected " + why +
                                    ", as the config's '" + it.key() + "' (" +
                                    Dump(c.j_[it.key()]) + "), got " + Dump(it.value()));
      if (quick) c.j_[it.key()] = it.value();
    }
    c.j_.erase("quick");
  }
  c.name_ = c.String("name", "");
  if (c.name_.empty()) c.Fail("name", "a non-empty string");
  for (char ch : c.name_)
    if (!(isalnum(static_cast<unsigned char>(ch)) || ch == '_' || ch == '-'))
      c.Fail("name", "letters, digits, '_' or '-' only");
  c.type_ = c.String("experiment", "");
  if (!c.j_.contains("seed")) c.Fail("seed", "an integer seed (every config carries its seed)");
  c.seed_ = static_cast<unsigned>(c.Int("seed", 0));
  c.String("description", "");
  return c;
}

namespace {
/// The value at a nested config key such as "robots[0].robot_params.a", or nullptr.
const nlohmann::json* FindNested(const nlohmann::json& root, const std::string& key) {
  const nlohmann::json* at = &root;
  size_t i = 0;
  while (i < key.size()) {
    if (key[i] == '.') {
      ++i;
      continue;
    }
    if (key[i] == '[') {
      const size_t close = key.find(']', i);
      if (close == std::string::npos || !at->is_array()) return nullptr;
      size_t idx = 0;
      try {
        idx = std::stoul(key.substr(i + 1, close - i - 1));
      } catch (const std::exception&) {
        return nullptr;
      }
      if (idx >= at->size()) return nullptr;
      at = &(*at)[idx];
      i = close + 1;
      continue;
    }
    const size_t end = key.find_first_of(".[", i);
    const std::string name = key.substr(i, end == std::string::npos ? std::string::npos : end - i);
    if (!at->is_object() || !at->contains(name)) return nullptr;
    at = &(*at)[name];
    i = end == std::string::npos ? key.size() : end;
  }
  return at;
}
}  // namespace

void Config::Fail(const std::string& key, const std::string& expected) const {
  const nlohmann::json* v = j_.contains(key) ? &j_.at(key) : FindNested(j_, key);
  std::string got = v ? ", got " + Dump(*v) : " (missing)";
  throw std::invalid_argument(path_ + ": " + key + ": expected " + expected + got);
}

std::string Config::String(const std::string& key, const std::string& def) const {
  used_.insert(key);
  if (!j_.contains(key)) return def;
  if (!j_[key].is_string()) Fail(key, "a string");
  return j_[key].get<std::string>();
}

double Config::Number(const std::string& key, double def) const {
  used_.insert(key);
  if (!j_.contains(key)) return def;
  if (!j_[key].is_number()) Fail(key, "a number");
  return j_[key].get<double>();
}

int Config::Int(const std::string& key, int def) const {
  used_.insert(key);
  if (!j_.contains(key)) return def;
  if (!j_[key].is_number_integer()) Fail(key, "an integer");
  return j_[key].get<int>();
}

bool Config::Bool(const std::string& key, bool def) const {
  used_.insert(key);
  if (!j_.contains(key)) return def;
  if (!j_[key].is_boolean()) Fail(key, "true or false");
  return j_[key].get<bool>();
}

std::vector<int> Config::IntList(const std::string& key, const std::vector<int>& def) const {
  used_.insert(key);
  if (!j_.contains(key)) return def;
  const auto& v = j_[key];
  if (!v.is_array()) Fail(key, "an array of integers");
  std::vector<int> out;
  for (const auto& x : v) {
    if (!x.is_number_integer()) Fail(key, "an array of integers");
    out.push_back(x.get<int>());
  }
  return out;
}

std::vector<double> Config::NumberList(const std::string& key,
                                       const std::vector<double>& def) const {
  used_.insert(key);
  if (!j_.contains(key)) return def;
  const auto& v = j_[key];
  if (!v.is_array()) Fail(key, "an array of numbers");
  std::vector<double> out;
  for (const auto& x : v) {
    if (!x.is_number()) Fail(key, "an array of numbers");
    out.push_back(x.get<double>());
  }
  return out;
}

nlohmann::json Config::Raw(const std::string& key) const {
  used_.insert(key);
  return j_.contains(key) ? j_.at(key) : nlohmann::json();
}

std::map<std::string, double> Config::NumberMap(const std::string& key) const {
  used_.insert(key);
  if (!j_.contains(key)) return {};
  return NumberObject(j_[key], key);
}

std::map<std::string, double> Config::NumberObject(const nlohmann::json& v,
                                                   const std::string& key) const {
  std::map<std::string, double> out;
  if (!v.is_object()) Fail(key, "an object of numbers, e.g. {\"name\": 1.5}");
  for (const auto& [k, x] : v.items()) {
    if (!x.is_number()) Fail(key, "a number for every entry (entry '" + k + "' is not)");
    out[k] = x.get<double>();
  }
  return out;
}

std::vector<std::string> Config::StringList(const std::string& key,
                                            const std::vector<std::string>& def) const {
  used_.insert(key);
  if (!j_.contains(key)) return def;
  const auto& v = j_[key];
  if (!v.is_array()) Fail(key, "an array of strings");
  std::vector<std::string> out;
  for (const auto& x : v) {
    if (!x.is_string()) Fail(key, "an array of strings");
    out.push_back(x.get<std::string>());
  }
  return out;
}

void ApplySolverJson(const nlohmann::json& j, const std::string& where, FkOptions* o) {
  *o = ReadSolverOptionsJson(j, where, *o);  // the scene JSON's reader and schema
}

FkOptions Config::Solver(const FkOptions& base) const {
  used_.insert("solver");
  FkOptions o = base;
  if (j_.contains("solver")) ApplySolverJson(j_["solver"], path_ + ": solver", &o);
  return o;
}

void Config::CheckNoUnknownKeys() const {
  for (auto it = j_.begin(); it != j_.end(); ++it)
    if (!used_.count(it.key()))
      throw std::invalid_argument(path_ + ": " + it.key() + ": unknown key for experiment '" +
                                  type_ + "'");
}

}  // namespace softkin
