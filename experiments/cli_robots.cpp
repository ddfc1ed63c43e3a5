#include "softkin/experiments/cli_robots.hpp"

#include "softkin/solver/robots/robots.hpp"

#include <nlohmann/json.hpp>

#include <iostream>

namespace softkin {

CLI::App* AddRobotsCommand(CLI::App* app, RobotsCommandArgs* a) {
  auto* robots =
      app->add_subcommand("robots", "List the embedded robots: actuators, markers, sizes");
  robots->add_flag("--json", a->json, "Print JSON instead of a table");
  return robots;
}

namespace {

/// Every embedded robot at its default resolution: name, description, design parameters,
/// actuators, markers and mesh sizes.
nlohmann::json RobotsJson() {
  nlohmann::json out = nlohmann::json::array();
  for (const auto& info : ListRobots()) {
    Scene s = MakeRobot(info.name, 0);
    nlohmann::json acts = nlohmann::json::array();
    for (const auto& a : s.actuators)
      acts.push_back({{"name", a.name},
                      {"type", ActuatorTypeToString(a.type)},
                      {"range", {a.min, a.max}},
                      {"rest", a.rest}});
    nlohmann::json markers = nlohmann::json::array();
    for (const auto& m : s.markers) markers.push_back(m.name);
    nlohmann::json params = nlohmann::json::array();
    for (const auto& p : info.params)
      params.push_back(
          {{"name", p.name}, {"default", p.def}, {"range", {p.lo, p.hi}}, {"doc", p.doc}});
    out.push_back({{"name", info.name},
                   {"description", info.description},
                   {"params", params},
                   {"default_resolution", info.default_resolution},
                   {"resolution", info.resolution_doc},
                   {"actuators", acts},
                   {"markers", markers},
                   {"n_vertices", s.mesh.num_vertices()},
                   {"n_tets", s.mesh.num_tets()},
                   {"n_prisms", s.mesh.num_prisms()},
                   {"n_fixed", s.fixed.size()}});
  }
  return out;
}

/// One robot of RobotsJson as a few lines of text.
void PrintRobot(const nlohmann::json& r) {
  std::cout << r["name"].get<std::string>() << ": ";
  if (r["n_tets"].get<int>() > 0) std::cout << r["n_tets"] << " tets, ";
  if (r["n_prisms"].get<int>() > 0) std::cout << r["n_prisms"] << " prisms, ";
  std::cout << r["n_vertices"] << " vertices (default res " << r["default_resolution"] << ")\n  "
            << r["description"].get<std::string>() << "\n  actuators:";
  for (const auto& a : r["actuators"])
    std::cout << " " << a["name"].get<std::string>() << " (" << a["type"].get<std::string>()
              << ", [" << a["range"][0] << ", " << a["range"][1] << "])";
  std::cout << "\n  markers:";
  for (const auto& m : r["markers"]) std::cout << " " << m.get<std::string>();
  for (const auto& p : r["params"])
    std::cout << "\n  param " << p["name"].get<std::string>() << " = " << p["default"] << " in ["
              << p["range"][0] << ", " << p["range"][1] << "]: " << p["doc"].get<std::string>();
  std::cout << "\n";
}

}  // namespace

int RunRobotsCommand(const RobotsCommandArgs& a) {
  const nlohmann::json j = RobotsJson();
  if (a.json) {
    std::cout << j.dump(2) << "\n";
  } else {
    for (const auto& r : j) PrintRobot(r);
  }
  return 0;
}

}  // namespace softkin
