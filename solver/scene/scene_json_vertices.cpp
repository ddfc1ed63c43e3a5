/// \file scene_json_vertices.cpp
/// Scene JSON: vertex selections (region, box, plane or index file) and the sections made of
/// them: fixed vertices, motion actuators and markers.
#include "softkin/solver/scene/scene_parser.hpp"

#include <algorithm>
#include <array>
#include <charconv>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <map>
#include <sstream>
#include <string>
#include <vector>

namespace softkin {
namespace scene_json_detail {

namespace fs = std::filesystem;

void SceneParser::ReadBox(const json& box, const std::string& pattern, const std::string& path,
                          Eigen::Vector3d* lo, Eigen::Vector3d* hi) const {
  CheckObject(box, pattern, path);
  *lo = AsVec(box.at("min"));
  *hi = AsVec(box.at("max"));
  if (!((lo->array() <= hi->array()).all()))
    Fail(path + ": expected min <= max in every coordinate, got min " + VecText(*lo) + ", max " +
         VecText(*hi));
}

std::vector<int> SceneParser::ReadIndexFile(const json& entry, const std::string& pattern,
                                            const std::string& path) const {
  const std::string name = entry.at("file").get<std::string>();
  const int base = AsInt(Get(entry, pattern, "base"));
  const fs::path file = Resolve(name);
  std::ifstream in(file);
  if (!in) Fail(path + ".file: cannot open '" + file.string() + "' (from \"" + name + "\")");
  const int n = static_cast<int>(file_to_mesh_.size());
  std::vector<int> out;
  int dropped = 0;
  std::string line;
  int line_no = 0;
  while (std::getline(in, line)) {
    ++line_no;
    const auto hash = line.find('#');
    if (hash != std::string::npos) line.resize(hash);
    std::istringstream tokens(line);
    std::string tok;
    while (tokens >> tok) {
      long long v = 0;
      const auto [ptr, ec] = std::from_chars(tok.data(), tok.data() + tok.size(), v);
      const std::string where =
          path + ".file: " + file.string() + ":" + std::to_string(line_no) + ": ";
      if (ec != std::errc() || ptr != tok.data() + tok.size())
        Fail(where + "expected an integer vertex index, got '" + tok + "'");
      const int mv = MeshVertexOfFile(v - base);
      if (mv == -2)
        Fail(where + "vertex index " + tok + " is out of range; expected " + std::to_string(base) +
             " to " + std::to_string(n - 1 + base) + " (" + std::to_string(n) +
             " vertices in the mesh file, base " + std::to_string(base) + ")");
      if (mv < 0)
        ++dropped;  // used by no element: dropped by the reader, nothing to hold or move
      else
        out.push_back(mv);
    }
  }
  if (in.bad()) Fail(path + ".file: error while reading '" + file.string() + "'");
  if (out.empty())
    Fail(path + ".file: '" + file.string() + "' lists no vertex index" +
         (dropped ? " of a vertex used by an element (the " + std::to_string(dropped) +
                        " listed are used by none and were dropped with the mesh file's unused "
                        "vertices)"
                  : std::string()));
  return out;
}

int SceneParser::MeshVertexOfFile(long long v) const {
  if (v < 0 || v >= static_cast<long long>(file_to_mesh_.size())) return -2;
  return file_to_mesh_[static_cast<std::size_t>(v)];
}

std::vector<int> SceneParser::ReadSelection(const json& f, const std::string& pattern,
                                            const std::string& path, const Mesh& mesh) const {
  std::vector<int> sel;
  if (f.contains("region")) {
    const int tag = AsInt(f.at("region"));
    sel = VerticesOfRegions(mesh, {tag});
    if (sel.empty())
      Fail(path + ".region: no element of the mesh has region tag " + std::to_string(tag) +
           " (the mesh's tags: " + IntListText(mesh.regions()) + ")");
  } else if (f.contains("box")) {
    Eigen::Vector3d lo, hi;
    ReadBox(f.at("box"), pattern + ".box", path + ".box", &lo, &hi);
    sel = VerticesInBox(mesh, lo, hi);
    if (sel.empty()) Fail(path + ".box selects no vertex (" + BoundsText(mesh) + ")");
  } else if (f.contains("plane")) {
    const json& p = f.at("plane");
    CheckObject(p, pattern + ".plane", path + ".plane");
    const Eigen::Vector3d point = AsVec(p.at("point")), normal = AsVec(p.at("normal"));
    if (!(normal.norm() > 0.0))
      Fail(path + ".plane.normal: expected a non-zero vector, got " + VecText(normal));
    const double tol = Get(p, pattern + ".plane", "tolerance").get<double>();
    sel = VerticesOnPlane(mesh, point, normal, tol);
    if (sel.empty())
      Fail(path + ".plane selects no vertex (tolerance " + Num(tol) + "; " + BoundsText(mesh) +
           ")");
  } else {
    sel = ReadIndexFile(f, pattern, path);
  }
  std::sort(sel.begin(), sel.end());
  sel.erase(std::unique(sel.begin(), sel.end()), sel.end());
  return sel;
}

void SceneParser::ReadFixed(const json& fixed, Scene* scene) const {
  if (fixed.empty()) Fail("fixed: expected at least one selection, got []");
  std::vector<int> all;
  std::array<std::vector<int>, 3> axis;
  for (size_t i = 0; i < fixed.size(); ++i) {
    const std::string path = "fixed[" + std::to_string(i) + "]";
    const json& f = fixed[i];
    CheckObject(f, "fixed[]", path);
    const std::string axes = Get(f, "fixed[]", "axes").get<std::string>();
    std::array<bool, 3> held = {false, false, false};
    for (char c : axes) {
      const int d = c == 'x' ? 0 : c == 'y' ? 1 : c == 'z' ? 2 : -1;
      if (d < 0 || held[d])
        Fail(path +
             ".axes: expected some of the letters x, y, z, each at most once (e.g. \"xyz\", "
             "\"z\"), got \"" +
             axes + "\"");
      held[d] = true;
    }
    if (axes.empty())
      Fail(path + ".axes: expected some of the letters x, y, z, each at most once, got \"\"");
    const std::vector<int> sel = ReadSelection(f, "fixed[]", path, scene->mesh);
    if (held[0] && held[1] && held[2]) {
      all.insert(all.end(), sel.begin(), sel.end());
    } else {
      for (int d = 0; d < 3; ++d)
        if (held[d]) axis[d].insert(axis[d].end(), sel.begin(), sel.end());
    }
  }
  auto sort_unique = [](std::vector<int>* v) {
    std::sort(v->begin(), v->end());
    v->erase(std::unique(v->begin(), v->end()), v->end());
  };
  sort_unique(&all);
  scene->fixed = all;
  for (int d = 0; d < 3; ++d) {
    sort_unique(&axis[d]);
    // A fully fixed vertex needs no per-axis entry.
    std::vector<int> only;
    std::set_difference(axis[d].begin(), axis[d].end(), all.begin(), all.end(),
                        std::back_inserter(only));
    scene->fixed_axis[d] = only;
  }
}

void SceneParser::ReadMotions(const json& motions, Scene* scene) const {
  std::map<std::string, std::string> name_path;
  for (size_t i = 0; i < motions.size(); ++i) {
    const std::string path = "motions[" + std::to_string(i) + "]";
    const json& m = motions[i];
    if (!m.is_object()) Fail(path + ": expected an object, got " + Got(m));
    CheckKey(m, "motions[]", path, "type");
    const std::string type = m.at("type").get<std::string>();
    CheckObject(m, "motions[]", path, type);
    Actuator a;
    a.name = m.at("name").get<std::string>();
    if (a.name.empty()) Fail(path + ".name: expected a non-empty actuator name, got \"\"");
    if (scene->actuator_index(a.name) >= 0)
      Fail(path + ".name: actuator '" + a.name + "' is already defined" +
           (name_path.count(a.name) ? " by " + name_path[a.name] : std::string(" in regions")) +
           "; expected unique actuator names");
    name_path[a.name] = path;
    if (!ActuatorTypeFromString(type, &a.type))
      throw std::logic_error("scene_json: motion type '" + type + "' is not an actuator type");
    a.vertices = ReadSelection(m, "motions[]", path, scene->mesh);
    a.axis = AsVec(m.at("axis"));
    if (!(a.axis.norm() > 0.0))
      Fail(path + ".axis: expected a non-zero vector, got " + VecText(a.axis));
    a.axis.normalize();
    if (a.type == ActuatorType::Twist) a.centre = AsVec(Get(m, "motions[]", "centre", type));
    a.min = m.at("min").get<double>();
    a.max = m.at("max").get<double>();
    a.rest = 0.0;
    if (!(a.min <= 0.0)) Fail(path + ".min: expected a number <= 0 (rest is 0), got " + Num(a.min));
    if (!(a.max >= 0.0)) Fail(path + ".max: expected a number >= 0 (rest is 0), got " + Num(a.max));
    for (int v : a.vertices)
      if (std::binary_search(scene->fixed.begin(), scene->fixed.end(), v))
        Fail(path + ": vertex " + std::to_string(v) + " (at " +
             VecText(scene->mesh.vertices.row(v).transpose()) +
             ") is also in `fixed`; expected moved vertices not to be fixed");
    for (int d = 0; d < 3; ++d)
      for (int v : a.vertices)
        if (std::binary_search(scene->fixed_axis[d].begin(), scene->fixed_axis[d].end(), v))
          Fail(path + ": vertex " + std::to_string(v) + " (at " +
               VecText(scene->mesh.vertices.row(v).transpose()) + ") is also held on axis " +
               "xyz"[d] + " by `fixed`; expected moved vertices not to be held");
    scene->actuators.push_back(std::move(a));
  }
}

std::vector<Marker> SceneParser::ReadMarkers(const json& markers, const Mesh& mesh) const {
  std::vector<Marker> out;
  std::map<std::string, std::string> name_path;
  for (size_t i = 0; i < markers.size(); ++i) {
    const std::string path = "markers[" + std::to_string(i) + "]";
    const json& m = markers[i];
    CheckObject(m, "markers[]", path);
    Marker mk;
    mk.name = m.at("name").get<std::string>();
    if (mk.name.empty()) Fail(path + ".name: expected a non-empty marker name, got \"\"");
    if (auto it = name_path.find(mk.name); it != name_path.end())
      Fail(path + ".name: marker '" + mk.name + "' is already defined by " + it->second +
           "; expected unique names");
    name_path[mk.name] = path;
    if (m.contains("vertex")) {
      const int v = AsInt(m.at("vertex"));
      const int mv = MeshVertexOfFile(v);
      if (mv == -2)
        Fail(path + ".vertex: expected a vertex index in [0, " +
             std::to_string(file_to_mesh_.size() - 1) + "], got " + std::to_string(v));
      if (mv < 0)
        Fail(path + ".vertex: vertex " + std::to_string(v) +
             " of the mesh file is used by no element (the reader dropped it); expected a "
             "vertex of the mesh's elements");
      mk.vertices = {mv};
    } else if (m.contains("nearest")) {
      if (mesh.num_vertices() == 0) Fail(path + ".nearest: the mesh has no vertices");
      mk.vertices = {NearestVertex(mesh, AsVec(m.at("nearest")))};
    } else {
      Eigen::Vector3d lo, hi;
      ReadBox(m.at("box"), "markers[].box", path + ".box", &lo, &hi);
      mk.vertices = VerticesInBox(mesh, lo, hi);
      if (mk.vertices.empty()) Fail(path + ".box selects no vertex (" + BoundsText(mesh) + ")");
    }
    out.push_back(std::move(mk));
  }
  return out;
}

}  // namespace scene_json_detail
}  // namespace softkin
