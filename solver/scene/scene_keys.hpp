#pragma once
/// \file scene_keys.hpp
/// The scene JSON's key table, private to solver/scene (not public API; scene_json.hpp is). One
/// table (KeyTable()) drives both the validator (scene_parser.hpp) and SceneSchema(): every key
/// path, its type, range or allowed values, default, role condition and doc line live there, and
/// the parser takes its defaults from it, so the documentation cannot drift from the code. The
/// `solver` object's entries are generated from the FK option table (solver_options_json.hpp).
/// Also the value checks against a key's spec and the text helpers of the reader's messages.
#include <Eigen/Core>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <limits>
#include <string>
#include <vector>

namespace softkin {
namespace scene_json_detail {

using json = nlohmann::json;

constexpr double kInf = std::numeric_limits<double>::infinity();

enum class Type { Object, ObjectArray, String, Number, Integer, Vec3, Polyline, Bool };
/// Required: must be present. Optional: has a default. Selector: each object of that kind needs
/// exactly one key of its selector group (e.g. fixed[]: region | box | plane | file).
enum class Need { Required, Optional, Selector };

struct KeySpec {
  std::string path;  ///< "a.b" = key b of object a; "a[]" = each element of array a
  Type type = Type::String;
  Need need = Need::Optional;
  json def;                          ///< default value of an Optional key
  std::string def_text;              ///< shown in the schema instead of def.dump() when non-empty
  std::vector<std::string> roles;    ///< regions[] keys: roles allowing the key (empty: every role)
  std::string with;                  ///< sibling key this key needs (empty: none)
  double lo = -kInf, hi = kInf;      ///< numeric range
  bool lo_open = false;              ///< lo excluded
  std::vector<std::string> choices;  ///< allowed string values (empty: any)
  std::string doc;

  KeySpec& Def(json v) {
    def = std::move(v);
    return *this;
  }
  KeySpec& DefText(std::string t) {
    def_text = std::move(t);
    return *this;
  }
  KeySpec& Roles(std::vector<std::string> r) {
    roles = std::move(r);
    return *this;
  }
  KeySpec& With(std::string w) {
    with = std::move(w);
    return *this;
  }
  KeySpec& AtLeast(double v) {
    lo = v;
    lo_open = false;
    return *this;
  }
  KeySpec& Above(double v) {
    lo = v;
    lo_open = true;
    return *this;
  }
  KeySpec& AtMost(double v) {
    hi = v;
    return *this;
  }
  KeySpec& In(double a, double b) {
    lo = a;
    hi = b;
    lo_open = false;
    return *this;
  }
  KeySpec& Choices(std::vector<std::string> c) {
    choices = std::move(c);
    return *this;
  }

  bool allows_role(const std::string& role) const {
    return roles.empty() || std::find(roles.begin(), roles.end(), role) != roles.end();
  }
};

/// Every key of the scene JSON, in schema order (parents before their children).
const std::vector<KeySpec>& KeyTable();

/// The `solver` object's keys: generated from the FK option table (solver_options_json.cpp).
std::vector<KeySpec> SolverKeySpecs();

/// "a.b.c" -> "a.b"; "a" -> "".
std::string ParentOf(const std::string& path);
/// "a.b.c" -> "c"; "a" -> "a".
std::string LeafOf(const std::string& path);
/// ("a", "b") -> "a.b"; ("", "b") -> "b".
std::string Join(const std::string& parent, const std::string& key);

// ---- Formatting ----

/// v with 10 significant digits (%.10g).
std::string Num(double v);
/// "[x, y, z]".
std::string VecText(const Eigen::Vector3d& v);
/// "a, b, c".
std::string ListText(const std::vector<std::string>& v);
/// "1, 2, 3", or "none" for an empty list.
std::string IntListText(const std::vector<int>& v);
/// The type, e.g. "number in [0, 1]"; with_article: "a number in [0, 1]" (for "expected ...").
std::string TypeText(const KeySpec& k, bool with_article);
/// A value as JSON text, shortened to 60 characters.
std::string Got(const json& v);
/// Levenshtein distance (for "did you mean" hints).
int EditDistance(const std::string& a, const std::string& b);

// ---- Value checks ----

/// Whether v is an integer that fits an int (an integral float counts).
bool IsInt(const json& v);
/// v as an int; v must pass IsInt.
int AsInt(const json& v);
/// Whether v has k's type and lies in its range or choices.
bool ValueOk(const KeySpec& k, const json& v);
/// A Vec3 value (checked by ValueOk) as a vector.
Eigen::Vector3d AsVec(const json& v);

}  // namespace scene_json_detail
}  // namespace softkin
