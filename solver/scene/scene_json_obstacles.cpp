/// \file scene_json_obstacles.cpp
/// Scene JSON: the obstacles (boxes, cylinders and surface files, collision.hpp).
#include "softkin/solver/mesh/surface.hpp"
#include "softkin/solver/scene/scene_parser.hpp"

#include <filesystem>
#include <string>
#include <vector>

namespace softkin {
namespace scene_json_detail {

namespace fs = std::filesystem;

std::vector<TriangleSurface> SceneParser::ReadObstacles(const json& obstacles) const {
  std::vector<TriangleSurface> out;
  for (size_t i = 0; i < obstacles.size(); ++i) {
    const std::string path = "obstacles[" + std::to_string(i) + "]";
    const json& o = obstacles[i];
    if (!o.is_object()) Fail(path + ": expected an object, got " + Got(o));
    CheckKey(o, "obstacles[]", path, "type");
    const std::string type = o.at("type").get<std::string>();
    CheckObject(o, "obstacles[]", path, type);
    fs::path file;
    if (type == "file") {
      file = Resolve(o.at("file").get<std::string>());
      if (!fs::is_regular_file(file))
        Fail(path + ".file: file not found: '" + file.string() + "' (relative to '" +
             (base_.empty() ? std::string(".") : base_) + "')");
    }
    TriangleSurface s;
    try {
      if (type == "box") {
        s = MakeBoxSurface(AsVec(o.at("min")), AsVec(o.at("max")));
      } else if (type == "cylinder") {
        s = MakeCylinderSurface(AsVec(o.at("base")), AsVec(o.at("axis")),
                                o.at("radius").get<double>(), o.at("height").get<double>(),
                                AsInt(Get(o, "obstacles[]", "segments", type)));
      } else {
        s = ReadSurfaceMesh(file.string());
      }
      CheckClosedSurface(&s);
    } catch (const std::invalid_argument& e) {
      Fail(path + ": " + e.what());
    }
    s.source = path + " (" + (s.source.empty() ? type : s.source) + ")";
    out.push_back(std::move(s));
  }
  return out;
}

}  // namespace scene_json_detail
}  // namespace softkin
