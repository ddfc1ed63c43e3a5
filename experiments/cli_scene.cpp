#include "softkin/experiments/cli_scene.hpp"

#include "softkin/solver/scene/scene_json.hpp"

#include <iostream>
#include <stdexcept>

namespace softkin {

CLI::App* AddSceneCommand(CLI::App* app, SceneCommandArgs* a) {
  auto* scene = app->add_subcommand("scene", "Check a scene JSON, or print its schema");
  scene->add_flag("--schema", a->schema, "Print every key with its type, default and doc");
  scene->add_option("file", a->file, "Scene JSON to load and summarise");
  return scene;
}

int RunSceneCommand(const SceneCommandArgs& a) {
  if (a.schema) {
    std::cout << SceneSchema();
    return 0;
  }
  if (a.file.empty()) throw std::invalid_argument("scene: give a scene JSON file or --schema");
  const Scene s = LoadSceneJson(a.file);
  std::cout << a.file << ": " << s.mesh.num_vertices() << " vertices, " << s.mesh.num_elements()
            << " elements, " << s.num_actuators() << " actuator(s), " << s.fixed.size()
            << " fixed vertices, " << s.markers.size() << " marker(s)\n";
  return 0;
}

}  // namespace softkin
