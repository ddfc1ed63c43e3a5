/// \file scene_json.cpp
/// Scene JSON reader: the JSON text, the validator of every object against the key table
/// (scene_keys.hpp), the solver options and the whole scene. The other sections are read in
/// scene_json_{mesh,regions,vertices,obstacles}.cpp (scene_parser.hpp).
#include "softkin/solver/scene/scene_json.hpp"
#include "softkin/solver/common/input_file.hpp"

#include "softkin/solver/common/json_text.hpp"
#include "softkin/solver/scene/scene_keys.hpp"
#include "softkin/solver/scene/scene_parser.hpp"
#include "softkin/solver/scene/solver_options_json.hpp"

#include <nlohmann/json.hpp>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <set>
#include <sstream>
#include <stdexcept>

namespace softkin {
namespace {

namespace fs = std::filesystem;

}  // namespace

namespace scene_json_detail {
namespace {}  // namespace

// ------------------------------------------------------------------------------------------------
// Validation against the key table
// ------------------------------------------------------------------------------------------------

std::vector<const KeySpec*> SceneParser::Children(const std::string& pattern,
                                                  const std::string& role) const {
  std::vector<const KeySpec*> out;
  for (const auto& k : KeyTable())
    if (ParentOf(k.path) == pattern && k.allows_role(role)) out.push_back(&k);
  return out;
}

const KeySpec* SceneParser::Spec(const std::string& pattern, const std::string& key,
                                 const std::string& role) const {
  if (key.find_first_of(".[]") != std::string::npos) return nullptr;  // "mesh.file" is no key
  for (const auto& k : KeyTable())
    if (k.path == Join(pattern, key) && k.allows_role(role)) return &k;
  return nullptr;
}

json SceneParser::Get(const json& obj, const std::string& pattern, const std::string& key,
                      const std::string& role) const {
  if (obj.contains(key)) return obj.at(key);
  const KeySpec* k = Spec(pattern, key, role);
  if (!k) throw std::logic_error("scene_json: no key " + Join(pattern, key) + " in the key table");
  return k->def;
}

void SceneParser::CheckValue(const KeySpec& k, const json& v, const std::string& path) const {
  if (!ValueOk(k, v)) Fail(path + ": expected " + TypeText(k, true) + ", got " + Got(v));
}

void SceneParser::CheckKey(const json& obj, const std::string& pattern, const std::string& path,
                           const std::string& key) const {
  const KeySpec* k = Spec(pattern, key, "");
  if (!obj.contains(key)) {
    if (k->need == Need::Required)
      Fail(At(path) + "missing required key '" + key + "' (expected " + TypeText(*k, true) + ")");
    return;
  }
  CheckValue(*k, obj.at(key), Join(path, key));
}

void SceneParser::CheckObject(const json& obj, const std::string& pattern, const std::string& path,
                              const std::string& role) const {
  if (!obj.is_object())
    Fail(path.empty() ? "expected a JSON object at the top level, got " + Got(obj)
                      : path + ": expected an object, got " + Got(obj));
  const auto kids = Children(pattern, role);
  std::vector<std::string> allowed;
  for (const KeySpec* k : kids)
    if (std::find(allowed.begin(), allowed.end(), LeafOf(k->path)) == allowed.end())
      allowed.push_back(LeafOf(k->path));
  for (const auto& [key, value] : obj.items()) {
    const KeySpec* k = Spec(pattern, key, role);
    if (!k) {
      const KeySpec* any_role = Spec(pattern, key, "");
      bool known = false;
      std::vector<std::string> roles;
      for (const auto& s : KeyTable())
        if (s.path == Join(pattern, key) && key.find_first_of(".[]") == std::string::npos) {
          known = true;
          roles.insert(roles.end(), s.roles.begin(), s.roles.end());
        }
      if (known && !any_role) {
        const std::string word =
            (pattern == "motions[]" || pattern == "obstacles[]") ? "type" : "role";
        Fail(Join(path, key) + ": not allowed for " + word + " '" + role + "' (only for " + word +
             " " + ListText(roles) + "; expected one of: " + ListText(allowed) + ")");
      }
      std::string hint;
      for (const auto& a : allowed)
        if (EditDistance(key, a) <= 2) {
          hint = "did you mean '" + a + "'? ";
          break;
        }
      Fail(At(path) + "unknown key '" + key + "' (" + hint +
           "expected one of: " + ListText(allowed) + ")");
    }
    if (!k->with.empty() && !obj.contains(k->with))
      Fail(Join(path, key) + ": only allowed together with '" + k->with + "'");
    CheckValue(*k, value, Join(path, key));
  }
  std::vector<std::string> selectors, present;
  for (const KeySpec* k : kids) {
    const std::string leaf = LeafOf(k->path);
    if (k->need == Need::Required && !obj.contains(leaf))
      Fail(At(path) + "missing required key '" + leaf + "' (expected " + TypeText(*k, true) + ")");
    if (k->need == Need::Selector) {
      selectors.push_back(leaf);
      if (obj.contains(leaf)) present.push_back(leaf);
    }
  }
  if (!selectors.empty() && present.size() != 1)
    Fail(At(path) + "expected exactly one of: " + ListText(selectors) +
         (present.empty() ? std::string(", got none")
                          : ", got both '" + present[0] + "' and '" + present[1] + "'"));
}

// ------------------------------------------------------------------------------------------------
// The solver options and the whole scene
// ------------------------------------------------------------------------------------------------

void SceneParser::ReadSolverOptions(const json& solver, FkOptions* o) const {
  CheckObject(solver, "solver", "solver");
  try {
    *o = ReadSolverOptionsJson(solver, "solver", FkOptions());  // defaults as in the schema
  } catch (const std::invalid_argument& e) {
    Fail(e.what());
  }
}

Scene SceneParser::Build(const json& given_root, const Mesh* given,
                         const MeshReport* given_report) {
  json with_mesh;
  if (given && given_root.is_object()) {
    if (given_root.contains("mesh"))
      Fail("mesh: leave this key out: the mesh is given as arrays (vertices, elements, tags)");
    with_mesh = given_root;
    with_mesh["mesh"] = {{"file", "(arrays)"}};  // the key table requires a mesh object
  }
  const json& root = with_mesh.is_null() ? given_root : with_mesh;
  CheckObject(root, "", "");
  Scene scene;
  scene.name = Get(root, "", "name").get<std::string>();
  if (scene.name.empty()) scene.name = fs::path(src_).stem().string();

  if (given) {
    scene.mesh = *given;
    if (given_report) scene.mesh_source_vertex = given_report->source_vertex;
    MapFileVertices(given_report ? *given_report : MeshReport(), scene.mesh.num_vertices());
  } else {
    ReadMeshSection(root.at("mesh"), &scene);
  }
  scene.element_energy =
      ElementEnergyFromString(Get(root, "", "element_energy").get<std::string>());
  ReadRegions(root.at("regions"), &scene);
  ReadFixed(root.at("fixed"), &scene);
  ReadMotions(Get(root, "", "motions"), &scene);
  scene.markers = ReadMarkers(Get(root, "", "markers"), scene.mesh);
  scene.obstacles = ReadObstacles(Get(root, "", "obstacles"));
  ReadSolverOptions(Get(root, "", "solver"), &scene.solver);

  try {
    scene.validate();
  } catch (const std::invalid_argument& e) {
    Fail(e.what());
  }
  return scene;
}

}  // namespace scene_json_detail

Scene ParseSceneJson(const std::string& text, const std::string& source,
                     const std::string& base_dir) {
  const scene_json_detail::json root = ParseJsonText(text, source);
  return scene_json_detail::SceneParser(source, base_dir).Build(root);
}

Scene ParseSceneJsonWithMesh(const std::string& text, const std::string& source, Mesh mesh,
                             const MeshReport& report) {
  const scene_json_detail::json root = ParseJsonText(text, source);
  return scene_json_detail::SceneParser(source, ".").Build(root, &mesh, &report);
}

Scene LoadSceneJson(const std::string& path) {
  CheckInputFile(path, "a scene file (.json)");
  std::ifstream in(path, std::ios::binary);
  if (!in)
    throw std::invalid_argument(path + ": cannot open the scene file (resolved: '" +
                                fs::absolute(path).lexically_normal().string() + "')");
  std::ostringstream ss;
  ss << in.rdbuf();
  fs::path dir = fs::path(path).parent_path();
  return ParseSceneJson(ss.str(), path, dir.empty() ? std::string(".") : dir.string());
}

}  // namespace softkin
