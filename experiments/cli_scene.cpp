#include "softkin/experiments/cli_scene.hpp"

#include "softkin/solver/factory/fk_factory.hpp"
#include "softkin/solver/fk/model.hpp"
#include "softkin/solver/scene/scene_json.hpp"

#include <iostream>
#include <stdexcept>

namespace softkin {

CLI::App* AddSceneCommand(CLI::App* app, SceneCommandArgs* a) {
  auto* scene = app->add_subcommand("scene", "Check a scene JSON, or print its schema");
  scene->add_flag("--schema", a->schema, "Print every key with its type, default and doc");
  scene->add_option("file", a->file,
                    "Scene JSON to check as `softkin fk` does before it solves (the scene, the "
                    "model it builds: cable paths, held parts, the factor of its matrix; and the "
                    "solver options), and summarise");
  return scene;
}

int RunSceneCommand(const SceneCommandArgs& a) {
  if (a.schema) {
    std::cout << SceneSchema();
    return 0;
  }
  if (a.file.empty()) throw std::invalid_argument("scene: give a scene JSON file or --schema");
  const Scene s = LoadSceneJson(a.file);
  // What fk checks before its first iteration: the model (cable paths through their elements,
  // every part held, the global matrix's factor) and the solver with the scene's options.
  try {
    auto model = std::make_shared<const Model>(s);
    MakeFkSolver(model, s.solver);
  } catch (const std::exception& e) {
    throw std::invalid_argument(a.file + ": " + e.what());
  }
  std::cout << a.file << ": " << s.mesh.num_vertices() << " vertices, " << s.mesh.num_elements()
            << " elements, " << s.num_actuators() << " actuator(s), " << s.fixed.size()
            << " fixed vertices, " << s.markers.size() << " marker(s)\n";
  return 0;
}

}  // namespace softkin
