#pragma once
/// \file scene_json.hpp
/// The scene JSON: a user's robot described by a mesh file plus region roles, fixed vertices,
/// markers and solver options. Every key has a type, a default and a doc line (SceneSchema());
/// unknown keys and wrong types throw std::invalid_argument naming the key path (e.g.
/// "scene.json: regions[2].r_omega: expected a number in [0, 1], got \"abc\"").
#include "softkin/solver/scene/scene.hpp"

#include <string>

namespace softkin {

/// Loads a scene JSON; relative paths inside it are relative to the JSON's folder.
Scene LoadSceneJson(const std::string& path);
/// Parses scene JSON text; `source` names it in messages, `base_dir` resolves relative paths.
Scene ParseSceneJson(const std::string& text, const std::string& source,
                     const std::string& base_dir);
/// A scene whose mesh is already in memory (built from arrays, as the Python module does): `text`
/// is a scene JSON without the "mesh" key, read as ParseSceneJson reads it. `mesh` must have been
/// checked by ValidateAndOrient; `report` is what that returned, so that vertex indices in `text`
/// are positions in the arrays (before unused vertices were dropped).
Scene ParseSceneJsonWithMesh(const std::string& text, const std::string& source, Mesh mesh,
                             const MeshReport& report);
/// Human-readable schema: every key with its type, default and doc line.
std::string SceneSchema();

}  // namespace softkin
