// Tests of the scene JSON's schema text (SceneSchema, scene_json.hpp) and of the FK option table
// (solver/scene/solver_options_json.hpp) that generates its solver.* entries: one reader for
// scenes, configs and `softkin fk`, its writer, and the enum options' names.
#include "softkin/solver/scene/scene_json.hpp"
#include "softkin/solver/scene/scene_keys.hpp"
#include "softkin/solver/scene/solver_options_json.hpp"

#include "tests/solver/scene/scene_json_test_util.hpp"

#include "tests/solver/fk/fk_test_util.hpp"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <map>
#include <set>
#include <sstream>
#include <string>
#include <vector>

namespace softkin {
namespace {

using namespace scene_test;

// ------------------------------------------------------------------------------------------------
// Schema text
// ------------------------------------------------------------------------------------------------

// Every key the scene JSON accepts. The schema must list exactly these.
const std::vector<std::string> kAllKeys = {"name",
                                           "mesh",
                                           "mesh.file",
                                           "mesh.format",
                                           "mesh.labels",
                                           "mesh.tag_array",
                                           "mesh.scale",
                                           "element_energy",
                                           "regions",
                                           "regions[].tag",
                                           "regions[].role",
                                           "regions[].material",
                                           "regions[].law",
                                           "regions[].c1",
                                           "regions[].c2",
                                           "regions[].r_omega",
                                           "regions[].weight",
                                           "regions[].name",
                                           "regions[].min",
                                           "regions[].max",
                                           "regions[].rest",
                                           "regions[].path",
                                           "regions[].side",
                                           "regions[].gain",
                                           "fixed[].axes",
                                           "motions",
                                           "motions[].name",
                                           "motions[].type",
                                           "motions[].region",
                                           "motions[].box",
                                           "motions[].box.min",
                                           "motions[].box.max",
                                           "motions[].plane",
                                           "motions[].plane.point",
                                           "motions[].plane.normal",
                                           "motions[].plane.tolerance",
                                           "motions[].file",
                                           "motions[].base",
                                           "motions[].axis",
                                           "motions[].centre",
                                           "motions[].min",
                                           "motions[].max",
                                           "fixed",
                                           "fixed[].region",
                                           "fixed[].box",
                                           "fixed[].box.min",
                                           "fixed[].box.max",
                                           "fixed[].plane",
                                           "fixed[].plane.point",
                                           "fixed[].plane.normal",
                                           "fixed[].plane.tolerance",
                                           "fixed[].file",
                                           "fixed[].base",
                                           "markers",
                                           "markers[].name",
                                           "markers[].vertex",
                                           "markers[].nearest",
                                           "markers[].box",
                                           "markers[].box.min",
                                           "markers[].box.max",
                                           "solver",
                                           "solver.solver",
                                           "solver.max_iterations",
                                           "solver.tolerance",
                                           "solver.gradient_tolerance",
                                           "solver.anderson_window",
                                           "solver.anderson_safeguard",
                                           "solver.continuation_steps",
                                           "solver.threads",
                                           "solver.time_limit_s",
                                           "solver.collision",
                                           "solver.collision.self",
                                           "solver.collision.obstacles",
                                           "solver.collision.epsilon",
                                           "solver.collision.stiffness",
                                           "solver.collision.check_interval",
                                           "solver.collision.update",
                                           "solver.collision.self_target",
                                           "solver.collision.self_spring",
                                           "solver.collision.obstacle_spring",
                                           "obstacles",
                                           "obstacles[].type",
                                           "obstacles[].min",
                                           "obstacles[].max",
                                           "obstacles[].base",
                                           "obstacles[].axis",
                                           "obstacles[].radius",
                                           "obstacles[].height",
                                           "obstacles[].segments",
                                           "obstacles[].file"};

/// Key lines of the schema (after the "Keys:" line, not indented): path -> the rest of the line,
/// plus the doc line that follows.
std::multimap<std::string, std::pair<std::string, std::string>> SchemaLines(
    const std::string& schema) {
  std::multimap<std::string, std::pair<std::string, std::string>> out;
  std::istringstream in(schema);
  std::string line;
  bool keys = false;
  std::string last;
  while (std::getline(in, line)) {
    if (line == "Keys:") {
      keys = true;
      continue;
    }
    if (!keys || line.empty()) continue;
    if (line[0] != ' ') {
      const auto sp = line.find(' ');
      last = line.substr(0, sp);
      out.emplace(last, std::make_pair(line, std::string()));
    } else if (!last.empty()) {
      auto it = out.equal_range(last).second;
      (--it)->second.second = line;
    }
  }
  return out;
}

TEST(SceneJsonSchema, ListsExactlyEveryKeyWithTypeDefaultAndDoc) {
  const std::string schema = SceneSchema();
  const auto lines = SchemaLines(schema);
  std::set<std::string> listed;
  for (const auto& [path, text] : lines) {
    listed.insert(path);
    const std::string& head = text.first;
    EXPECT_TRUE(head.find("default ") != std::string::npos ||
                head.find("required") != std::string::npos ||
                head.find("selector") != std::string::npos)
        << head;
    EXPECT_GT(text.second.size(), 10u) << "no doc line for " << path;
  }
  EXPECT_EQ(listed, std::set<std::string>(kAllKeys.begin(), kAllKeys.end()));
  // regions[].weight has a default per role: 1 for body, 5 for actuators.
  EXPECT_EQ(lines.count("regions[].weight"), 2u);
}

TEST(SceneJsonSchema, DefaultsComeFromTheStructs) {
  const auto lines = SchemaLines(SceneSchema());
  auto head = [&](const std::string& key) {
    auto it = lines.find(key);
    return it == lines.end() ? std::string() : it->second.first;
  };
  const FkOptions fk;
  EXPECT_NE(head("solver.solver").find("default \"" + ToString(fk.solver) + "\""),
            std::string::npos);
  EXPECT_NE(head("solver.max_iterations").find("default " + std::to_string(fk.max_iterations)),
            std::string::npos);
  EXPECT_NE(head("solver.anderson_window").find("integer in [1, 50]"), std::string::npos);
  EXPECT_NE(head("regions[].r_omega").find("number in [0, 1]"), std::string::npos);
  EXPECT_NE(head("regions[].r_omega").find("[role body]"), std::string::npos);
  EXPECT_NE(head("mesh.file").find("required"), std::string::npos);
  EXPECT_NE(head("fixed[].box").find("selector"), std::string::npos);
  EXPECT_NE(head("mesh.format").find("one of: auto, tet, tetgen, gmsh, vtk"), std::string::npos);
}

TEST(SceneJsonSchema, DocsContainTheCurrentSchema) {
  const std::string doc = ReadFile(fs::path(SOFTKIN_SOURCE_DIR) / "docs" / "scene.md");
  ASSERT_FALSE(doc.empty()) << "docs/scene.md missing";
  EXPECT_NE(doc.find(SceneSchema()), std::string::npos)
      << "docs/scene.md does not contain the current SceneSchema() text; regenerate it";
}

// ------------------------------------------------------------------------------------------------
// Solver options: one reader for scenes, configs and `softkin fk --set`
// ------------------------------------------------------------------------------------------------

// Every solver.* leaf of the scene schema is an option the reader knows, and the other way round;
// every schema default is FkOptions' default.
TEST(SolverOptionsJson, EveryOptionHasASchemaEntryWithItsDefault) {
  std::vector<std::string> schema;
  const json defaults = SolverOptionsToJson(FkOptions());
  for (const auto& k : scene_json_detail::KeyTable()) {
    if (k.path.rfind("solver.", 0) != 0 || k.type == scene_json_detail::Type::Object) continue;
    const std::string key = k.path.substr(7);
    schema.push_back(key);
    const auto dot = key.find('.');
    const json& d = dot == std::string::npos
                        ? defaults.at(key)
                        : defaults.at(key.substr(0, dot)).at(key.substr(dot + 1));
    EXPECT_EQ(k.def, d) << key;
  }
  EXPECT_EQ(schema, SolverOptionKeys());
  EXPECT_GE(schema.size(), 18u);
}

TEST(SolverOptionsJson, RoundTripsEveryOption) {
  const FkOptions o = test::NonDefaultFkOptions();
  const json j = SolverOptionsToJson(o);
  const FkOptions back = ReadSolverOptionsJson(j, "test", FkOptions());
  EXPECT_EQ(SolverOptionsToJson(back), j);
  // Every value above differs from its default, so each option is read back, not defaulted.
  const json d = SolverOptionsToJson(FkOptions());
  for (const std::string& key : SolverOptionKeys()) {
    const auto dot = key.find('.');
    const json::json_pointer at(
        "/" + (dot == std::string::npos ? key : key.substr(0, dot) + "/" + key.substr(dot + 1)));
    EXPECT_NE(j.at(at), d.at(at)) << key;
  }
  EXPECT_EQ(j["solver"], "lg");  // enum options as their names
  EXPECT_EQ(j["collision"]["obstacle_spring"], "point");
  // Keys left out keep the base's values.
  const FkOptions partial = ReadSolverOptionsJson(json{{"tolerance", 1e-3}}, "test", o);
  EXPECT_EQ(partial.max_iterations, 123);
  EXPECT_EQ(partial.collision.update, SpringUpdate::kRefactor);
  EXPECT_DOUBLE_EQ(partial.tolerance, 1e-3);
}

// The enum options: every name reads back as itself, an unknown one is refused with the list,
// and the schema's allowed values are the enum's one list of names.
TEST(SolverOptionsJson, EnumNamesAreOneListPerOption) {
  for (const std::string& n : FkSolverTypeNames())
    EXPECT_EQ(ToString(FkSolverTypeFromString(n)), n);
  for (const std::string& n : AndersonSafeguardNames())
    EXPECT_EQ(ToString(AndersonSafeguardFromString(n)), n);
  for (const std::string& n : SpringUpdateNames())
    EXPECT_EQ(ToString(SpringUpdateFromString(n)), n);
  for (const std::string& n : SelfTargetNames()) EXPECT_EQ(ToString(SelfTargetFromString(n)), n);
  for (const std::string& n : SelfSpringNames()) EXPECT_EQ(ToString(SelfSpringFromString(n)), n);
  for (const std::string& n : ObstacleSpringNames())
    EXPECT_EQ(ToString(ObstacleSpringFromString(n)), n);
  for (const std::string& n : MaterialLawNames()) EXPECT_EQ(ToString(MaterialLawFromString(n)), n);
  EXPECT_EQ(FkSolverTypeNames().size(), 10u);
  ExpectError([] { (void)FkSolverTypeFromString("newtonian"); },
              {"unknown FK solver 'newtonian'; expected one of: lg, lg-aa, newton, auto, ceres, "
               "ipopt-lbfgs, "
               "ipopt-newton, ipopt-hard, calculix-linear, calculix-nonlinear"});
  ExpectError([] { (void)MaterialLawFromString("ogden"); }, {"'ogden'", "blend, mooney-rivlin"});
  auto choices = [](const std::string& path) {
    for (const auto& k : scene_json_detail::KeyTable())
      if (k.path == path) return k.choices;
    return std::vector<std::string>{"no key " + path};
  };
  EXPECT_EQ(choices("solver.solver"), FkSolverTypeNames());
  EXPECT_EQ(choices("solver.anderson_safeguard"), AndersonSafeguardNames());
  EXPECT_EQ(choices("solver.collision.update"), SpringUpdateNames());
  EXPECT_EQ(choices("solver.collision.self_target"), SelfTargetNames());
  EXPECT_EQ(choices("solver.collision.self_spring"), SelfSpringNames());
  EXPECT_EQ(choices("solver.collision.obstacle_spring"), ObstacleSpringNames());
  EXPECT_EQ(choices("regions[].law"), MaterialLawNames());
  // As JSON an enum option is its name (to_json / from_json), never its number.
  EXPECT_EQ(json(FkSolverType::kCalculixLinear), "calculix-linear");
  EXPECT_EQ(json("point").get<ObstacleSpring>(), ObstacleSpring::kPoint);
}

TEST(SolverOptionsJson, BadValuesNameTheKeyAndWhatWasExpected) {
  auto read = [](const json& j) {
    (void)ReadSolverOptionsJson(j, "cfg.json: solver", FkOptions());
  };
  ExpectError(
      [&] {
        read(json{{"max_iterations", "many"}});
      },
      {"cfg.json: solver.max_iterations: expected an integer", "got \"many\""});
  ExpectError(
      [&] {
        read(json{{"max_iterations", 0}});
      },
      {"cfg.json: solver.max_iterations: expected an integer >= 1"});
  ExpectError(
      [&] {
        read(json{{"collision", {{"update", "magic"}}}});
      },
      {"cfg.json: solver.collision.update: expected", "updown", "refactor"});
  ExpectError(
      [&] {
        read(json{{"tolerence", 1e-3}});
      },
      {"cfg.json: solver.tolerence: unknown key (expected one of solver, max_iterations"});
  ExpectError(
      [&] {
        read(json{{"collision", {{"selff", true}}}});
      },
      {"cfg.json: solver.collision.selff: unknown key (expected one of self, obstacles"});
  ExpectError(
      [&] {
        read(json{{"collision", true}});
      },
      {"cfg.json: solver.collision: expected an object"});
  ExpectError([&] { read(json::array()); }, {"cfg.json: solver: expected an object"});
}

}  // namespace
}  // namespace softkin
