#include "softkin/solver/scene/solver_options_json.hpp"

#include "softkin/solver/scene/scene_keys.hpp"

#include <algorithm>
#include <functional>
#include <stdexcept>
#include <type_traits>

namespace softkin {

namespace {

using json = nlohmann::json;
using scene_json_detail::KeySpec;

/// One option: its key below `solver.` and how to read and write it on FkOptions.
struct Field {
  std::string key;
  std::function<json(const FkOptions&)> get;
  std::function<void(const json&, FkOptions*)> set;
};

template <class T>
void Assign(const json& v, T* out) {
  if constexpr (std::is_same_v<T, int>)
    *out = scene_json_detail::AsInt(v);  // an integral float counts, as in the scene validator
  else
    *out = v.get<T>();
}

template <class T>
Field Top(const char* key, T FkOptions::*m) {
  return {key, [m](const FkOptions& o) { return json(o.*m); },
          [m](const json& v, FkOptions* o) { Assign(v, &(o->*m)); }};
}

template <class T>
Field Col(const char* key, T CollisionOptions::*m) {
  return {std::string("collision.") + key, [m](const FkOptions& o) { return json(o.collision.*m); },
          [m](const json& v, FkOptions* o) { Assign(v, &(o->collision.*m)); }};
}

/// Every option, in schema order. A test checks that it matches the schema's solver.* keys.
const std::vector<Field>& Fields() {
  static const std::vector<Field> fields = {
      Top("solver", &FkOptions::solver),
      Top("max_iterations", &FkOptions::max_iterations),
      Top("tolerance", &FkOptions::tolerance),
      Top("gradient_tolerance", &FkOptions::gradient_tolerance),
      Top("anderson_window", &FkOptions::anderson_window),
      Top("anderson_safeguard", &FkOptions::anderson_safeguard),
      Top("continuation_steps", &FkOptions::continuation_steps),
      Top("threads", &FkOptions::threads),
      Top("time_limit_s", &FkOptions::time_limit_s),
      Col("self", &CollisionOptions::self),
      Col("obstacles", &CollisionOptions::obstacles),
      Col("epsilon", &CollisionOptions::epsilon),
      Col("stiffness", &CollisionOptions::stiffness),
      Col("check_interval", &CollisionOptions::check_interval),
      Col("update", &CollisionOptions::update),
      Col("self_target", &CollisionOptions::self_target),
      Col("self_spring", &CollisionOptions::self_spring),
      Col("obstacle_spring", &CollisionOptions::obstacle_spring),
  };
  return fields;
}

const KeySpec& SchemaEntry(const std::string& key) {
  for (const KeySpec& k : scene_json_detail::KeyTable())
    if (k.path == "solver." + key) return k;
  throw std::logic_error("solver option '" + key + "' has no scene schema entry");
}

/// The known keys below `prefix` ("" or "collision."), for messages.
std::string KnownKeys(const std::string& prefix) {
  std::vector<std::string> keys;
  for (const Field& f : Fields()) {
    if (f.key.compare(0, prefix.size(), prefix) != 0) continue;
    const std::string rest = f.key.substr(prefix.size());
    const std::string head = rest.substr(0, rest.find('.'));
    if (std::find(keys.begin(), keys.end(), head) == keys.end()) keys.push_back(head);
  }
  return scene_json_detail::ListText(keys);
}

void ReadObject(const json& j, const std::string& where, const std::string& prefix, FkOptions* o) {
  for (auto it = j.begin(); it != j.end(); ++it) {
    const std::string key = prefix + it.key();
    const json& v = it.value();
    if (prefix.empty() && it.key() == "collision") {
      if (!v.is_object())
        throw std::invalid_argument(where +
                                    ".collision: expected an object of collision "
                                    "options, got " +
                                    scene_json_detail::Got(v));
      ReadObject(v, where, "collision.", o);
      continue;
    }
    const auto f = std::find_if(Fields().begin(), Fields().end(),
                                [&](const Field& x) { return x.key == key; });
    if (f == Fields().end())
      throw std::invalid_argument(where + "." + key + ": unknown key (expected one of " +
                                  KnownKeys(prefix) + ")");
    const KeySpec& spec = SchemaEntry(key);
    if (!scene_json_detail::ValueOk(spec, v))
      throw std::invalid_argument(where + "." + key + ": expected " +
                                  scene_json_detail::TypeText(spec, true) + ", got " +
                                  scene_json_detail::Got(v));
    f->set(v, o);
  }
}

}  // namespace

FkOptions ReadSolverOptionsJson(const json& j, const std::string& where, const FkOptions& base) {
  if (!j.is_object())
    throw std::invalid_argument(where + ": expected an object of solver options, got " +
                                scene_json_detail::Got(j));
  FkOptions o = base;
  ReadObject(j, where, "", &o);
  std::string why;
  if (!o.IsValid(&why)) throw std::invalid_argument(where + "." + why);
  return o;
}

json SolverOptionsToJson(const FkOptions& o) {
  json j = json::object();
  for (const Field& f : Fields()) {
    if (f.key.compare(0, 10, "collision.") == 0)
      j["collision"][f.key.substr(10)] = f.get(o);
    else
      j[f.key] = f.get(o);
  }
  return j;
}

std::vector<std::string> SolverOptionKeys() {
  std::vector<std::string> keys;
  for (const Field& f : Fields()) keys.push_back(f.key);
  return keys;
}

}  // namespace softkin
