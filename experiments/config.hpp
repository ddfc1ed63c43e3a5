#pragma once
/// \file config.hpp
/// Experiment configs: JSON files in experiments/ with a name, an experiment type, a seed, the
/// experiment's parameters and an optional "quick" object whose keys override the top-level ones
/// in --quick mode (for CI). Every key is checked: unknown keys and wrong types are errors that
/// name the config file and the key.
#include "softkin/solver/fk/fk_options.hpp"

#include <nlohmann/json.hpp>

#include <map>
#include <set>
#include <string>
#include <vector>

namespace softkin {

class Config {
 public:
  /// Loads `path`, merges "quick" over the top level if quick is set, and checks the common keys.
  static Config Load(const std::string& path, bool quick);

  const std::string& name() const { return name_; }
  const std::string& type() const { return type_; }
  const std::string& path() const { return path_; }
  unsigned seed() const { return seed_; }
  bool quick() const { return quick_; }
  /// Whether the file has a "quick" object (whose overrides a quick run puts in place).
  bool has_quick() const { return has_quick_; }
  /// Set on a config that is only to be checked: each experiment reads and checks all its
  /// settings, then returns at once when this is set. A --quick run checks the full settings this
  /// way first, so that a value its overrides hide cannot wait to fail in the full run.
  bool check_only() const { return check_only_; }
  void set_check_only(bool on) { check_only_ = on; }
  /// The effective config (after merging quick), as recorded in results.
  const nlohmann::json& json() const { return j_; }

  /// Typed getters; each marks the key as known. Missing keys give the default.
  std::string String(const std::string& key, const std::string& def) const;
  double Number(const std::string& key, double def) const;
  int Int(const std::string& key, int def) const;
  bool Bool(const std::string& key, bool def) const;
  std::vector<int> IntList(const std::string& key, const std::vector<int>& def) const;
  std::vector<double> NumberList(const std::string& key, const std::vector<double>& def) const;
  std::vector<std::string> StringList(const std::string& key,
                                      const std::vector<std::string>& def) const;
  /// The raw JSON value of `key` (null if missing), for structured keys the experiment checks
  /// itself (reporting errors through Fail).
  nlohmann::json Raw(const std::string& key) const;
  /// An object of numbers, e.g. "robot_params": {"interface": 0.3}.
  std::map<std::string, double> NumberMap(const std::string& key) const;
  /// The same check for a value found inside a structured key (e.g. cases[2].robot_params);
  /// errors name `key`.
  std::map<std::string, double> NumberObject(const nlohmann::json& v, const std::string& key) const;
  /// Solver options from the "solver" object on top of `base`.
  FkOptions Solver(const FkOptions& base) const;
  /// Throws if the config has keys that no getter asked for.
  void CheckNoUnknownKeys() const;
  [[noreturn]] void Fail(const std::string& key, const std::string& expected) const;

 private:
  std::string path_, name_, type_;
  unsigned seed_ = 0;
  bool quick_ = false, has_quick_ = false, check_only_ = false;
  nlohmann::json j_;
  mutable std::set<std::string> used_;
};

/// Applies a JSON object of solver options onto opts with ReadSolverOptionsJson (the scene
/// schema's solver.* keys; solver/scene/solver_options_json.hpp); `where` names it in
/// errors (e.g. "config.json: solver"). Unknown keys and wrong types throw std::invalid_argument.
void ApplySolverJson(const nlohmann::json& j, const std::string& where, FkOptions* opts);

}  // namespace softkin
