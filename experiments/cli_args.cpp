#include "softkin/experiments/cli_args.hpp"

#include "softkin/solver/common/input_file.hpp"
#include "softkin/solver/scene/solver_options_json.hpp"

#include <CLI/CLI.hpp>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <stdexcept>

namespace softkin {

Eigen::VectorXd ParseNumberList(const std::string& text, const std::string& option) {
  std::vector<double> v;
  std::stringstream ss(text);
  std::string item;
  while (std::getline(ss, item, ',')) {
    size_t pos = 0;
    double x = 0;
    try {
      x = std::stod(item, &pos);
    } catch (const std::exception&) {
      pos = 0;
    }
    while (pos < item.size() && isspace(static_cast<unsigned char>(item[pos]))) ++pos;
    if (item.empty() || pos != item.size() || !std::isfinite(x))
      throw std::invalid_argument(option + ": expected comma-separated finite numbers, got '" +
                                  text + "'");
    v.push_back(x);
  }
  if (!text.empty() && text.back() == ',')
    throw std::invalid_argument(option + ": expected comma-separated finite numbers, got '" + text +
                                "'");
  if (v.empty()) throw std::invalid_argument(option + ": expected at least one number");
  return Eigen::Map<Eigen::VectorXd>(v.data(), static_cast<Eigen::Index>(v.size()));
}

RobotParams ParseRobotParams(const std::vector<std::string>& items) {
  RobotParams params;
  for (const auto& text : items) {
    const auto eq = text.find('=');
    char* end = nullptr;
    const std::string value = eq == std::string::npos ? "" : text.substr(eq + 1);
    const double v = value.empty() ? 0.0 : std::strtod(value.c_str(), &end);
    if (eq == std::string::npos || eq == 0 || value.empty() ||
        end != value.c_str() + value.size() || !std::isfinite(v))
      throw std::invalid_argument("--param: expected NAME=VALUE with a finite number, got '" +
                                  text + "'");
    if (!params.emplace(text.substr(0, eq), v).second)
      throw std::invalid_argument("--param: expected each parameter once, got '" +
                                  text.substr(0, eq) + "' twice");
  }
  return params;
}

namespace {

/// The value name a flag shows in help texts ("--tolerance NUMBER"), by the option's type.
std::string ValueName(const nlohmann::json& default_value) {
  if (default_value.is_boolean()) return "BOOL";
  if (default_value.is_number_integer()) return "INT";
  if (default_value.is_number()) return "NUMBER";
  return "NAME";
}

}  // namespace

nlohmann::json CommandLineValue(const std::string& text) {
  nlohmann::json v = nlohmann::json::parse(text, nullptr, false);
  if (v.is_discarded()) v = text;
  return v;
}

std::string FkOptionFlagName(const std::string& key) {
  std::string name = "--" + key;
  std::replace(name.begin(), name.end(), '_', '-');
  std::replace(name.begin(), name.end(), '.', '-');
  return name;
}

std::vector<CLI::Option*> AddFkOptionFlags(CLI::App* cmd, FkOptionFlags* flags,
                                           const std::vector<std::string>& keys,
                                           const std::map<std::string, std::string>& aliases) {
  std::vector<CLI::Option*> added;
  for (const SolverOptionDoc& o : SolverOptionDocs()) {
    if (!keys.empty() && std::find(keys.begin(), keys.end(), o.key) == keys.end()) continue;
    std::string names = FkOptionFlagName(o.key);
    if (aliases.count(o.key)) names += "," + aliases.at(o.key);
    const std::string key = o.key;
    const std::string help = o.doc + " [" + o.value + "; default: the scene's solver." + key + "]";
    CLI::Option* flag = cmd->add_option_function<std::string>(
        names, [flags, key](const std::string& v) { flags->given[key] = v; }, help);
    flag->type_name(ValueName(o.default_value));
    added.push_back(flag);
  }
  return added;
}

FkOptions ApplyFkOptionFlags(const FkOptionFlags& flags, const FkOptions& base) {
  FkOptions o = base;
  for (const std::string& key : SolverOptionKeys()) {
    const auto it = flags.given.find(key);
    if (it == flags.given.end()) continue;
    // {"max_iterations": 5} or {"collision": {"self": true}}: the reader's layout.
    nlohmann::json j;
    const auto dot = key.find('.');
    if (dot == std::string::npos)
      j[key] = CommandLineValue(it->second);
    else
      j[key.substr(0, dot)][key.substr(dot + 1)] = CommandLineValue(it->second);
    o = ReadSolverOptionsJson(j, FkOptionFlagName(key) + ": solver", o);
  }
  return o;
}

std::vector<NamedPath> SceneInputs(const std::string& scene, const std::string& option) {
  std::vector<NamedPath> in;
  if (scene.empty()) return in;
  in.push_back({option, scene});
  CheckInputFile(scene, "a scene file (.json)");
  nlohmann::json j;
  try {
    std::ifstream f(scene, std::ios::binary);
    j = nlohmann::json::parse(f, nullptr, /*allow_exceptions=*/false);
  } catch (const std::exception&) {  // unreadable: the scene reader says why
    return in;
  }
  if (!j.is_object()) return in;
  const std::filesystem::path dir = std::filesystem::path(scene).parent_path();
  auto add = [&](const nlohmann::json& v, const std::string& key) {
    if (v.is_string()) in.push_back({option + " " + key, (dir / v.get<std::string>()).string()});
  };
  if (j.contains("mesh") && j["mesh"].is_object()) {
    if (j["mesh"].contains("file")) add(j["mesh"]["file"], "mesh.file");
    if (j["mesh"].contains("labels")) add(j["mesh"]["labels"], "mesh.labels");
  }
  if (j.contains("obstacles") && j["obstacles"].is_array())
    for (const auto& o : j["obstacles"])
      if (o.is_object() && o.contains("file")) add(o["file"], "obstacles[].file");
  return in;
}

void CheckCommandPaths(const std::vector<NamedPath>& inputs,
                       const std::vector<NamedPath>& outputs) {
  CheckDistinctPaths(inputs, outputs);
  for (const NamedPath& o : outputs)
    if (!o.path.empty()) CheckOutputPath(o);
}

}  // namespace softkin
