/// \file scene_json_regions.cpp
/// Scene JSON: the regions[] section. Each region tag is a body material (blend or
/// Mooney-Rivlin, hyperelastic.hpp) or part of an actuator; regions sharing an actuator name form
/// one actuator, signed if one of its pneumatic regions is on the negative side.
#include "softkin/solver/materials/hyperelastic.hpp"
#include "softkin/solver/scene/scene_parser.hpp"

#include <algorithm>
#include <map>
#include <string>
#include <vector>

namespace softkin {
namespace scene_json_detail {

struct SceneParser::ActuatorEntry {
  struct Given {
    double value;
    std::string path;
  };
  int index;  ///< in scene->actuators
  std::string role, role_path;
  std::string negative_path;           ///< the first region with side "negative" (signed actuator)
  std::map<std::string, Given> given;  ///< range keys given by the entries, with where from
};

void SceneParser::ReadRegions(const json& regions, Scene* scene) const {
  if (regions.empty()) Fail("regions: expected at least one region entry, got []");
  const std::vector<int> mesh_tags = scene->mesh.regions();
  std::map<int, std::string> tag_path;
  ActuatorEntries acts;

  for (size_t i = 0; i < regions.size(); ++i) {
    const std::string path = "regions[" + std::to_string(i) + "]";
    const json& r = regions[i];
    if (!r.is_object()) Fail(path + ": expected an object, got " + Got(r));
    CheckKey(r, "regions[]", path, "role");
    const std::string role = r.at("role").get<std::string>();
    CheckObject(r, "regions[]", path, role);

    const int tag = AsInt(r.at("tag"));
    if (auto it = tag_path.find(tag); it != tag_path.end())
      Fail(path + ".tag: region " + std::to_string(tag) + " is already described by " + it->second +
           "; expected each tag once");
    tag_path[tag] = path;
    if (!std::binary_search(mesh_tags.begin(), mesh_tags.end(), tag))
      Fail(path + ".tag: no element of the mesh has region tag " + std::to_string(tag) +
           " (the mesh's tags: " + IntListText(mesh_tags) + ")");

    if (role == "body") {
      scene->body[tag] = ReadBodyMaterial(r, path, role);
      continue;
    }
    ReadActuatorRegion(r, path, role, tag, &acts, scene);
  }
  for (const auto& [name, info] : acts) FinishActuator(name, info, &scene->actuators[info.index]);
}

Material SceneParser::ReadBodyMaterial(const json& r, const std::string& path,
                                       const std::string& role) const {
  Material mat;
  mat.name = Get(r, "regions[]", "material", role).get<std::string>();
  mat.r_omega = Get(r, "regions[]", "r_omega", role).get<double>();
  mat.weight = Get(r, "regions[]", "weight", role).get<double>();
  mat.law = MaterialLawFromString(Get(r, "regions[]", "law", role).get<std::string>());
  const bool has_c = r.contains("c1") || r.contains("c2");
  if (has_c && !mat.hyperelastic())
    Fail(path + ": c1 / c2 are given but law is \"" + ToString(mat.law) +
         "\"; expected law \"mooney-rivlin\" with them");
  if (mat.hyperelastic()) {
    MooneyRivlin mr;
    const bool named = NamedMooneyRivlin(mat.name, &mr);
    if (!named && !(r.contains("c1") && r.contains("c2"))) {
      std::string names;
      for (const auto& n : NamedMooneyRivlinNames()) names += (names.empty() ? "" : ", ") + n;
      Fail(path + ": law mooney-rivlin needs c1 and c2 (MPa), or 'material' naming one of " +
           names + "; got material \"" + mat.name + "\"");
    }
    mat.c1 = r.contains("c1") ? r.at("c1").get<double>() : mr.c1;
    mat.c2 = r.contains("c2") ? r.at("c2").get<double>() : mr.c2;
    if (!(mat.c1 + mat.c2 > 0)) Fail(path + ": expected c1 + c2 > 0 for law mooney-rivlin");
    if (!(mat.r_omega > 0))
      Fail(path + ".r_omega: expected a zero-strain R_omega > 0 for law mooney-rivlin");
  }
  return mat;
}

void SceneParser::ReadActuatorRegion(const json& r, const std::string& path,
                                     const std::string& role, int tag, ActuatorEntries* acts,
                                     Scene* scene) const {
  const std::string name = r.at("name").get<std::string>();
  if (name.empty()) Fail(path + ".name: expected a non-empty actuator name, got \"\"");
  auto it = acts->find(name);
  if (it == acts->end()) {
    Actuator a;
    a.name = name;
    if (!ActuatorTypeFromString(role, &a.type))
      throw std::logic_error("scene_json: role '" + role + "' is not an actuator type");
    scene->actuators.push_back(a);
    const ActuatorEntry entry{scene->num_actuators() - 1, role, path + ".role", "", {}};
    it = acts->emplace(name, entry).first;
  } else if (it->second.role != role) {
    Fail(path + ".role: actuator '" + name + "' is " + it->second.role + " in " +
         it->second.role_path + ", got \"" + role +
         "\"; regions sharing an actuator name must have the same role");
  }
  const bool negative =
      role == "pneumatic" && Get(r, "regions[]", "side", role).get<std::string>() == "negative";
  if (negative) {
    scene->actuators[it->second.index].negative_regions.push_back(tag);
    if (it->second.negative_path.empty()) it->second.negative_path = path + ".side";
  } else {
    scene->actuators[it->second.index].regions.push_back(tag);
  }
  if (role == "cable") {
    std::vector<Eigen::Vector3d> pts;
    for (const auto& p : r.at("path")) pts.push_back(AsVec(p));
    auto& a = scene->actuators[it->second.index];
    if (a.path.empty())
      a.path = pts;
    else if (a.path != pts)
      Fail(path + ".path: cable '" + name +
           "' already has a different path; regions sharing a cable name must give the same "
           "path");
  }
  for (const char* key : {"min", "max", "rest", "weight", "gain"}) {
    if (!r.contains(key)) continue;
    const double v = r.at(key).get<double>();
    const std::string kp = path + "." + key;
    auto g = it->second.given.find(key);
    if (g == it->second.given.end())
      it->second.given[key] = ActuatorEntry::Given{v, kp};
    else if (g->second.value != v)
      Fail(kp + ": actuator '" + name + "' already has " + key + " " + Num(g->second.value) +
           " from " + g->second.path + ", got " + Num(v) +
           "; regions sharing an actuator name must agree");
  }
}

void SceneParser::FinishActuator(const std::string& name, const ActuatorEntry& info,
                                 Actuator* out) const {
  Actuator& a = *out;
  auto value = [&](const char* key) {
    auto g = info.given.find(key);
    return g != info.given.end() ? g->second.value
                                 : Spec("regions[]", key, info.role)->def.get<double>();
  };
  const std::string entry = info.role_path.substr(0, info.role_path.size() - 5);
  auto where = [&](const char* key) {
    auto g = info.given.find(key);
    return g != info.given.end() ? g->second.path : std::string("default");
  };
  a.weight = value("weight");
  if (info.role == "pneumatic") a.gain = value("gain");
  if (!info.negative_path.empty()) {
    // Signed pneumatic actuator: rest 0, an explicit range around it.
    for (const char* key : {"min", "max"})
      if (!info.given.count(key))
        Fail(entry + ": signed actuator '" + name + "' (negative side from " + info.negative_path +
             ") needs '" + key + "'; expected min <= 0 <= max");
    a.min = value("min");
    a.max = value("max");
    a.rest = info.given.count("rest") ? value("rest") : 0.0;
    if (a.rest != 0.0)
      Fail(where("rest") + ": signed actuator '" + name + "': expected rest 0, got " + Num(a.rest));
    if (!(a.min <= 0.0))
      Fail(where("min") + ": signed actuator '" + name + "': expected min <= 0, got " + Num(a.min));
    if (!(a.max >= 0.0))
      Fail(where("max") + ": signed actuator '" + name + "': expected max >= 0, got " + Num(a.max));
    if (a.regions.empty())
      Fail(entry + ": signed actuator '" + name +
           "' has only negative-side regions; expected at least one region with side \"positive\"");
    return;
  }
  if (info.given.count("gain"))
    Fail(where("gain") + ": actuator '" + name +
         "' is not signed (no region with side \"negative\"); gain applies to signed actuators "
         "only");
  a.min = value("min");
  a.max = value("max");
  a.rest = value("rest");
  for (const char* key : {"min", "max", "rest"})
    if (!(value(key) > 0.0))
      Fail(where(key) + ": actuator '" + name + "': expected a ratio > 0, got " + Num(value(key)));
  if (!(a.min <= a.rest && a.rest <= a.max)) {
    Fail(entry + ": actuator '" + name + "': expected min <= rest <= max, got min " + Num(a.min) +
         " (" + where("min") + "), rest " + Num(a.rest) + " (" + where("rest") + "), max " +
         Num(a.max) + " (" + where("max") + ")");
  }
}

}  // namespace scene_json_detail
}  // namespace softkin
