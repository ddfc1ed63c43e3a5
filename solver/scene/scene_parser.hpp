#pragma once
/// \file scene_parser.hpp
/// The scene JSON reader's builder, private to solver/scene (not public API; scene_json.hpp is).
/// SceneParser validates each object against the key table (scene_keys.hpp) before reading it and
/// throws std::invalid_argument("<source>: <key path>: ...") on the first problem. Its sections
/// are read in scene_json_mesh.cpp (mesh), scene_json_regions.cpp (materials and actuators),
/// scene_json_vertices.cpp (vertex selections: fixed, motions, markers), scene_json_obstacles.cpp
/// and scene_json.cpp (the validator, the solver options and the whole scene).
#include "softkin/solver/scene/scene.hpp"
#include "softkin/solver/scene/scene_keys.hpp"

#include <Eigen/Core>

#include <filesystem>
#include <map>
#include <stdexcept>
#include <string>
#include <vector>

namespace softkin {
namespace scene_json_detail {

class SceneParser {
 public:
  SceneParser(std::string source, std::string base_dir)
      : src_(std::move(source)), base_(std::move(base_dir)) {}

  /// The scene of `root`. With `given` (a mesh already in memory, checked by ValidateAndOrient,
  /// and its report), `root` has no "mesh" key and its vertex indices are positions in the
  /// arrays the mesh came from.
  Scene Build(const json& root, const Mesh* given = nullptr,
              const MeshReport* given_report = nullptr);

 private:
  /// What the regions[] entries sharing one actuator name gave (ReadRegions).
  struct ActuatorEntry;
  using ActuatorEntries = std::map<std::string, ActuatorEntry>;

  [[noreturn]] void Fail(const std::string& msg) const {
    throw std::invalid_argument(src_ + ": " + msg);
  }
  static std::string At(const std::string& path) {
    return path.empty() ? std::string() : path + ": ";
  }

  // ---- Validation against the key table (scene_json.cpp) ----

  /// Specs of the keys of objects at `pattern` (e.g. "fixed[]") that apply to `role`.
  std::vector<const KeySpec*> Children(const std::string& pattern, const std::string& role) const;
  const KeySpec* Spec(const std::string& pattern, const std::string& key,
                      const std::string& role) const;
  /// Value of key (or its default); the key must have been checked by CheckObject.
  json Get(const json& obj, const std::string& pattern, const std::string& key,
           const std::string& role = "") const;
  void CheckValue(const KeySpec& k, const json& v, const std::string& path) const;
  /// Checks one key of `obj` (presence if required, type, range) before the rest of the object.
  void CheckKey(const json& obj, const std::string& pattern, const std::string& path,
                const std::string& key) const;
  /// Validates object `obj` found at `path` against the keys of `pattern`: unknown keys, keys not
  /// allowed for `role`, types and ranges, required keys and the selector group.
  void CheckObject(const json& obj, const std::string& pattern, const std::string& path,
                   const std::string& role = "") const;

  std::filesystem::path Resolve(const std::string& file) const {
    std::filesystem::path p(file);
    if (p.is_relative() && !base_.empty()) p = std::filesystem::path(base_) / p;
    return p.lexically_normal();
  }

  // ---- The sections, in the order Build reads them ----

  /// mesh (scene_json_mesh.cpp); sets file_to_mesh_.
  void ReadMeshSection(const json& m, Scene* scene);
  /// Sets file_to_mesh_ from a reader's report on a mesh of `num_vertices` kept vertices.
  void MapFileVertices(const MeshReport& report, int num_vertices);
  /// regions[]: body materials and actuators (scene_json_regions.cpp).
  void ReadRegions(const json& regions, Scene* scene) const;
  /// fixed[], motions[], markers[] (scene_json_vertices.cpp).
  void ReadFixed(const json& fixed, Scene* scene) const;
  void ReadMotions(const json& motions, Scene* scene) const;
  std::vector<Marker> ReadMarkers(const json& markers, const Mesh& mesh) const;
  /// The mesh vertex of 0-based file position `v` (an index written in the scene): -1 if the
  /// reader dropped it (no element uses it), -2 if v is out of the file's range.
  int MeshVertexOfFile(long long v) const;
  /// obstacles[] (scene_json_obstacles.cpp).
  std::vector<TriangleSurface> ReadObstacles(const json& obstacles) const;
  /// solver (scene_json.cpp).
  void ReadSolverOptions(const json& solver, FkOptions* o) const;

  // ---- Regions (scene_json_regions.cpp) ----

  /// The body material of region entry `r` at `path` (role "body").
  Material ReadBodyMaterial(const json& r, const std::string& path, const std::string& role) const;
  /// Adds region entry `r` (tag `tag`, an actuator role) to its actuator, creating the actuator
  /// in `scene` at the first entry of its name; records the range keys the entry gives.
  void ReadActuatorRegion(const json& r, const std::string& path, const std::string& role, int tag,
                          ActuatorEntries* acts, Scene* scene) const;
  /// Sets the weight, gain and range of actuator `name` from its entries' keys or the defaults,
  /// and checks them.
  void FinishActuator(const std::string& name, const ActuatorEntry& info, Actuator* out) const;

  // ---- Vertex selections (scene_json_vertices.cpp) ----

  /// The vertices chosen by the selector key (region | box | plane | file) of an object at
  /// `pattern` ("fixed[]" or "motions[]"), already checked by CheckObject.
  std::vector<int> ReadSelection(const json& entry, const std::string& pattern,
                                 const std::string& path, const Mesh& mesh) const;
  /// Indices of an index file: file positions (see Scene::mesh_source_vertex) mapped to mesh
  /// vertices; those of dropped (unused) vertices are left out.
  std::vector<int> ReadIndexFile(const json& entry, const std::string& pattern,
                                 const std::string& path) const;
  void ReadBox(const json& box, const std::string& pattern, const std::string& path,
               Eigen::Vector3d* lo, Eigen::Vector3d* hi) const;
  std::string BoundsText(const Mesh& mesh) const {
    if (mesh.num_vertices() == 0) return "the mesh has no vertices";
    return "the mesh spans " + VecText(mesh.vertices.colwise().minCoeff().transpose()) + " to " +
           VecText(mesh.vertices.colwise().maxCoeff().transpose());
  }

  std::string src_;
  std::string base_;
  /// File position -> mesh vertex (-1: dropped as unused), one entry per vertex of the mesh file.
  std::vector<int> file_to_mesh_;
};

}  // namespace scene_json_detail
}  // namespace softkin
