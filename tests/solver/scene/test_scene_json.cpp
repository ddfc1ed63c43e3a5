// Tests of the scene JSON reader (solver/scene/scene_json.hpp): the repository's real-mesh scene,
// every selector on a tiny generated mesh, and every error message. The schema text and the FK
// option table are tested in test_scene_schema.cpp.
#include "softkin/solver/scene/scene_json.hpp"

#include "softkin/solver/mesh/io/mesh_io.hpp"
#include "tests/solver/scene/scene_json_test_util.hpp"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <string>
#include <vector>

namespace softkin {
namespace {

using namespace scene_test;

// ------------------------------------------------------------------------------------------------
// The repository's scene on the real finger mesh
// ------------------------------------------------------------------------------------------------

TEST(SceneJsonRealMesh, FingerChamber1Loads) {
  const Scene s = LoadSceneJson(std::string(SOFTKIN_SOURCE_DIR) + "/scenes/finger_chamber1.json");
  EXPECT_EQ(s.name, "finger_chamber1");
  ASSERT_EQ(s.mesh.num_vertices(), 18014);
  ASSERT_EQ(s.mesh.num_elements(), 94240);

  ASSERT_EQ(s.num_actuators(), 1);
  const int c = s.actuator_index("chamber");
  ASSERT_EQ(c, 0);
  EXPECT_EQ(s.actuators[c].type, ActuatorType::Pneumatic);
  EXPECT_EQ(s.actuators[c].regions, std::vector<int>{1});
  EXPECT_DOUBLE_EQ(s.actuators[c].min, 1.0);
  EXPECT_DOUBLE_EQ(s.actuators[c].max, 3.0);
  EXPECT_DOUBLE_EQ(s.actuators[c].rest, 1.0);
  int chamber_elements = 0;
  for (const auto& e : s.mesh.elements) chamber_elements += (e.region == 1);
  EXPECT_EQ(chamber_elements, 27702);
  ASSERT_EQ(s.body.count(0), 1u);
  EXPECT_DOUBLE_EQ(s.body.at(0).r_omega, 1.0);
  EXPECT_DOUBLE_EQ(s.body.at(0).weight, 1.0);

  // The long axis is y: the base is the flat end at y max, the tip the far end at y min.
  const Eigen::RowVector3d lo = s.mesh.vertices.colwise().minCoeff();
  const Eigen::RowVector3d hi = s.mesh.vertices.colwise().maxCoeff();
  ASSERT_GT(s.fixed.size(), 100u);
  EXPECT_TRUE(std::is_sorted(s.fixed.begin(), s.fixed.end()));
  for (int v : s.fixed) EXPECT_GT(s.mesh.vertices(v, 1), hi.y() - 1.0) << "fixed vertex " << v;

  const int tip = s.marker_index("tip");
  ASSERT_GE(tip, 0);
  EXPECT_GE(s.markers[tip].vertices.size(), 10u);
  const Eigen::MatrixX3d P = s.marker_positions(s.mesh.vertices);
  EXPECT_LT(P(tip, 1), lo.y() + 2.0);
  EXPECT_GT(P(tip, 1), lo.y());
  EXPECT_GT(hi.y() - lo.y(), 60.0);

  std::string why;
  EXPECT_TRUE(s.solver.IsValid(&why)) << why;
  EXPECT_EQ(s.solver.solver, FkSolverType::kLgAa);  // the scene file names it
}

// ------------------------------------------------------------------------------------------------
// Selectors, scale, defaults and merging on a tiny generated mesh
// ------------------------------------------------------------------------------------------------

TEST(SceneJsonTiny, EverySelectorScaleAndMergedActuator) {
  TempDir dir;
  WriteTinyMesh(dir.path());
  const Scene s = LoadFrom(dir.path(), TinyScene());
  EXPECT_EQ(s.name, "tiny");
  ASSERT_EQ(s.mesh.num_vertices(), 6);
  ASSERT_EQ(s.mesh.num_elements(), 3);
  // scale 2
  EXPECT_DOUBLE_EQ(s.mesh.vertices.maxCoeff(), 2.0);
  EXPECT_DOUBLE_EQ(s.mesh.vertices(4, 0), 2.0);
  EXPECT_DOUBLE_EQ(s.mesh.vertices(4, 1), 2.0);

  // body region
  ASSERT_EQ(s.body.size(), 1u);
  EXPECT_EQ(s.body.at(0).name, "soft");
  EXPECT_DOUBLE_EQ(s.body.at(0).r_omega, 0.5);
  EXPECT_DOUBLE_EQ(s.body.at(0).weight, 2.0);

  // regions 1 and 2 merged into one actuator; keys given once apply to the whole actuator
  ASSERT_EQ(s.num_actuators(), 1);
  const Actuator& a = s.actuators[0];
  EXPECT_EQ(a.name, "chamber");
  EXPECT_EQ(a.type, ActuatorType::Pneumatic);
  EXPECT_EQ(a.regions, (std::vector<int>{1, 2}));
  EXPECT_DOUBLE_EQ(a.min, 1.0);
  EXPECT_DOUBLE_EQ(a.max, 3.0);
  EXPECT_DOUBLE_EQ(a.rest, Actuator{}.rest);
  EXPECT_DOUBLE_EQ(a.weight, 4.0);

  // plane y = 0 -> {0, 1, 2}; box x >= 1.5, z <= 0.5 -> {1, 4}; file (1-based "6") -> {5}
  EXPECT_EQ(s.fixed, (std::vector<int>{0, 1, 2, 4, 5}));

  ASSERT_EQ(s.markers.size(), 3u);
  EXPECT_EQ(s.markers[0].name, "a");
  EXPECT_EQ(s.markers[0].vertices, std::vector<int>{3});
  EXPECT_EQ(s.markers[1].vertices, std::vector<int>{4});
  EXPECT_EQ(s.markers[2].vertices, (std::vector<int>{3, 4, 5}));
  const Eigen::MatrixX3d P = s.marker_positions(s.mesh.vertices);
  EXPECT_NEAR(P(2, 0), 2.0 / 3.0, 1e-12);
  EXPECT_NEAR(P(2, 1), 2.0, 1e-12);
  EXPECT_NEAR(P(2, 2), 2.0 / 3.0, 1e-12);

  EXPECT_EQ(s.solver.solver, FkSolverType::kLg);
  EXPECT_EQ(s.solver.max_iterations, 50);
  EXPECT_DOUBLE_EQ(s.solver.tolerance, 1e-4);
  EXPECT_DOUBLE_EQ(s.solver.gradient_tolerance, 0.01);
  EXPECT_EQ(s.solver.anderson_window, 3);
  EXPECT_EQ(s.solver.continuation_steps, 2);
  EXPECT_EQ(s.solver.threads, 1);
}

TEST(SceneJsonTiny, RegionSelectorAndZeroBasedFile) {
  TempDir dir;
  WriteTinyMesh(dir.path());
  WriteFile(dir.path() / "zero.txt", "5 4\r\n5  # repeated, CRLF\n");
  json j = TinyScene();
  j["fixed"] = json::parse(R"([{"region": 0}, {"file": "zero.txt"}])");
  const Scene s = LoadFrom(dir.path(), j);
  EXPECT_EQ(s.fixed, (std::vector<int>{0, 1, 2, 3, 4, 5}));
  j["fixed"] = json::parse(R"([{"region": 0}])");
  EXPECT_EQ(LoadFrom(dir.path(), j).fixed, (std::vector<int>{0, 1, 2, 3}));
}

// A mesh file with an unused vertex: the reader drops it, and the indices written in the scene
// (index files, markers[].vertex) still mean positions in the file.
TEST(SceneJsonTiny, IndicesAreFilePositionsWhenUnusedVerticesAreDropped) {
  TempDir dir;
  WriteTinyMesh(dir.path());
  // The tiny mesh with an unused vertex inserted at file position 2.
  WriteFile(dir.path() / "tiny.tet",
            "7 vertices\n3 tets\n0 0 0\n1 0 0\n9 9 9\n0 0 1\n0 1 0\n1 1 0\n0 1 1\n"
            "4 0 3 1 4\n4 1 4 3 5\n4 3 5 4 6\n");
  WriteFile(dir.path() / "fixed.txt", "3 7\n");  // 1-based: the unused vertex and the last one
  json j = TinyScene();
  j["fixed"] = json::parse(R"([{"file": "fixed.txt", "base": 1}])");
  j["markers"] = json::parse(R"([{"name": "a", "vertex": 4}])");
  const Scene s = LoadFrom(dir.path(), j);
  ASSERT_EQ(s.mesh.num_vertices(), 6);
  EXPECT_EQ(s.mesh_source_vertex, (std::vector<int>{0, 1, 3, 4, 5, 6}));
  EXPECT_EQ(s.fixed, std::vector<int>{5});                // file vertex 6
  EXPECT_EQ(s.markers[0].vertices, std::vector<int>{3});  // file vertex 4
  EXPECT_DOUBLE_EQ(s.mesh.vertices(3, 1), 2.0);           // (0, 1, 0) scaled by 2
  j["markers"] = json::parse(R"([{"name": "a", "vertex": 2}])");
  ExpectError([&] { LoadFrom(dir.path(), j); },
              {"markers[0].vertex: vertex 2 of the mesh file is used by no element"});
  WriteFile(dir.path() / "fixed.txt", "3\n");
  j["markers"] = json::parse(R"([{"name": "a", "vertex": 4}])");
  ExpectError([&] { LoadFrom(dir.path(), j); },
              {"fixed[0].file", "lists no vertex index of a vertex used by an element"});
}

TEST(SceneJsonTiny, MeshGivenInMemoryIsReadLikeAFile) {
  // The tiny mesh with an unused vertex at position 2, given as arrays (the Python module's
  // scene from arrays): the same checks as a file, and indices are positions in the arrays.
  Mesh m;
  m.vertices.resize(7, 3);
  m.vertices << 0, 0, 0, 1, 0, 0, 9, 9, 9, 0, 0, 1, 0, 1, 0, 1, 1, 0, 0, 1, 1;
  const int tets[3][4] = {{0, 3, 1, 4}, {1, 4, 3, 5}, {3, 5, 4, 6}};
  for (int i = 0; i < 3; ++i) {
    Element e;
    e.v = {{tets[i][0], tets[i][1], tets[i][2], tets[i][3], -1, -1}};
    e.region = i;
    m.elements.push_back(e);
  }
  Mesh checked = m;
  const MeshReport report = ValidateAndOrient(checked, "arrays");
  EXPECT_EQ(report.unused_vertices, 1);
  json j = TinyScene();
  j.erase("mesh");
  j["fixed"] = json::parse(R"([{"plane": {"point": [0, 0, 0], "normal": [0, 1, 0]}}])");
  j["markers"] = json::parse(R"([{"name": "a", "vertex": 4}])");
  const Scene s = ParseSceneJsonWithMesh(j.dump(), "arrays", checked, report);
  EXPECT_EQ(s.name, "tiny");
  ASSERT_EQ(s.mesh.num_vertices(), 6);
  EXPECT_EQ(s.fixed, (std::vector<int>{0, 1, 2}));        // y = 0: array rows 0, 1, 3
  EXPECT_EQ(s.markers[0].vertices, std::vector<int>{3});  // array row 4
  ASSERT_EQ(s.num_actuators(), 1);
  EXPECT_EQ(s.actuators[0].regions, (std::vector<int>{1, 2}));
  j["markers"] = json::parse(R"([{"name": "a", "vertex": 2}])");
  ExpectError([&] { ParseSceneJsonWithMesh(j.dump(), "arrays", checked, report); },
              {"arrays: markers[0].vertex: vertex 2 of the mesh file is used by no element"});
  j["mesh"] = json::parse(R"({"file": "tiny.tet"})");
  ExpectError([&] { ParseSceneJsonWithMesh(j.dump(), "arrays", checked, report); },
              {"arrays: mesh: leave this key out"});
}

TEST(SceneJsonTiny, CableAndDeaRolesAndDefaults) {
  TempDir dir;
  WriteTinyMesh(dir.path());
  json j = json::parse(R"({
    "mesh": {"file": "tiny.tet", "labels": "tiny_labels.txt"},
    "regions": [
      {"tag": 0, "role": "body"},
      {"tag": 1, "role": "cable", "name": "tendon", "path": [[0, 0, 0], [1, 0, 0], [1, 1, 0]]},
      {"tag": 2, "role": "dea", "name": "skin", "max": 1.5}
    ],
    "fixed": [{"box": {"min": [-1, -1, -1], "max": [2, 0, 2]}}]
  })");
  // The tiny mesh is all tets: a DEA region needs prisms (Sec. 2.3.3).
  try {
    LoadFrom(dir.path(), j);
    ADD_FAILURE() << "a DEA region of tets was accepted";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("DEA actuator 'skin': element 2 is a tet; expected prism "
                                         "elements"),
              std::string::npos)
        << e.what();
  }
  j["regions"][2] = json::parse(R"({"tag": 2, "role": "pneumatic", "name": "skin", "max": 1.5})");
  const Scene s = LoadFrom(dir.path(), j);
  EXPECT_EQ(s.name, "scene");  // default: the JSON file's stem
  ASSERT_EQ(s.num_actuators(), 2);
  EXPECT_EQ(s.actuators[0].name, "tendon");
  EXPECT_EQ(s.actuators[0].type, ActuatorType::Cable);
  EXPECT_EQ(s.actuators[1].name, "skin");
  EXPECT_EQ(s.actuators[1].type, ActuatorType::Pneumatic);
  ASSERT_EQ(s.actuators[0].path.size(), 3u);
  EXPECT_EQ(s.actuators[0].path[2], Eigen::Vector3d(1, 1, 0));
  EXPECT_TRUE(s.actuators[1].path.empty());
  const Actuator def;
  EXPECT_DOUBLE_EQ(s.actuators[0].min, def.min);
  EXPECT_DOUBLE_EQ(s.actuators[0].max, def.max);
  EXPECT_DOUBLE_EQ(s.actuators[0].rest, def.rest);
  EXPECT_DOUBLE_EQ(s.actuators[0].weight, def.weight);
  EXPECT_DOUBLE_EQ(s.actuators[1].max, 1.5);
  const Material mat;
  EXPECT_EQ(s.body.at(0).name, mat.name);
  EXPECT_DOUBLE_EQ(s.body.at(0).r_omega, mat.r_omega);
  EXPECT_DOUBLE_EQ(s.body.at(0).weight, mat.weight);
  EXPECT_TRUE(s.markers.empty());
  const FkOptions fk;
  EXPECT_EQ(s.solver.solver, fk.solver);
  EXPECT_EQ(s.solver.max_iterations, fk.max_iterations);
  EXPECT_DOUBLE_EQ(s.solver.tolerance, fk.tolerance);
  EXPECT_DOUBLE_EQ(s.solver.gradient_tolerance, fk.gradient_tolerance);
  EXPECT_EQ(s.solver.anderson_window, fk.anderson_window);
  EXPECT_EQ(s.solver.continuation_steps, fk.continuation_steps);
  EXPECT_EQ(s.solver.threads, fk.threads);
  EXPECT_EQ(s.fixed, (std::vector<int>{0, 1, 2}));
}

TEST(SceneJsonTiny, OtherMeshFormats) {
  TempDir dir;
  WriteTinyMesh(dir.path());
  const Mesh tiny =
      ReadTet((dir.path() / "tiny.tet").string(), (dir.path() / "tiny_labels.txt").string());
  WriteGmsh((dir.path() / "tiny.msh").string(), tiny);
  WriteTetGen((dir.path() / "tiny_tg").string(), tiny);
  // Legacy VTK by hand, with two integer cell arrays: the tags are in the second one.
  WriteFile(dir.path() / "tiny.vtk",
            "# vtk DataFile Version 3.0\ntiny\nASCII\nDATASET UNSTRUCTURED_GRID\nPOINTS 6 double\n"
            "0 0 0\n1 0 0\n0 0 1\n0 1 0\n1 1 0\n0 1 1\n"
            "CELLS 3 15\n4 0 2 1 3\n4 1 3 2 4\n4 2 4 3 5\nCELL_TYPES 3\n10\n10\n10\n"
            "CELL_DATA 3\nSCALARS other int 1\nLOOKUP_TABLE default\n7\n7\n7\n"
            "SCALARS part int 1\nLOOKUP_TABLE default\n0\n1\n2\n");
  const std::vector<json> meshes = {
      {{"file", "tiny.msh"}, {"scale", 2}},
      {{"file", "tiny.msh"}, {"format", "gmsh"}, {"scale", 2}},
      {{"file", "tiny_tg.node"}, {"scale", 2}},
      {{"file", "tiny_tg.ele"}, {"scale", 2}},
      {{"file", "tiny_tg"}, {"scale", 2}},
      {{"file", "tiny.vtk"}, {"tag_array", "part"}, {"scale", 2}},
  };
  for (const auto& m : meshes) {
    SCOPED_TRACE(m.dump());
    json j = TinyScene();
    j["mesh"] = m;
    const Scene s = LoadFrom(dir.path(), j);
    EXPECT_EQ(s.mesh.num_vertices(), 6);
    EXPECT_EQ(s.mesh.regions(), (std::vector<int>{0, 1, 2}));
    EXPECT_EQ(s.fixed, (std::vector<int>{0, 1, 2, 4, 5}));
    EXPECT_EQ(s.actuators.at(0).regions, (std::vector<int>{1, 2}));
  }
  // Without tag_array the VTK reader takes the first integer array ("other": every cell 7).
  json j = TinyScene();
  j["mesh"] = {{"file", "tiny.vtk"}};
  ExpectError(
      [&] { LoadFrom(dir.path(), j); },
      {"scene.json: regions[0].tag: no element of the mesh has region tag 0 (the mesh's tags: 7)"});
  j["mesh"] = {{"file", "tiny_tg.node"}, {"tag_array", "part"}};
  ExpectError([&] { LoadFrom(dir.path(), j); }, {"scene.json: mesh.tag_array: only used by the vtk "
                                                 "and vtu formats (the mesh is read as tetgen)"});
  j["mesh"] = {{"file", "missing_tg.node"}};
  ExpectError([&] { LoadFrom(dir.path(), j); }, {"scene.json: mesh.file: file not found: '" +
                                                 (dir.path() / "missing_tg.node").string()});
}

TEST(SceneJsonTiny, ParseSceneJsonUsesBaseDirAndSource) {
  TempDir dir;
  WriteTinyMesh(dir.path());
  const Scene s = ParseSceneJson(TinyScene().dump(), "inline.json", dir.path().string());
  EXPECT_EQ(s.mesh.num_vertices(), 6);
  json j = TinyScene();
  j.erase("name");
  EXPECT_EQ(ParseSceneJson(j.dump(), "inline.json", dir.path().string()).name, "inline");
}

// ------------------------------------------------------------------------------------------------
// Errors: source file, key path and what was expected
// ------------------------------------------------------------------------------------------------

TEST(SceneJsonErrors, WrongTypeAndRange) {
  json j = TinyScene();
  j["regions"][0]["r_omega"] = "abc";
  ExpectSceneError(j, {"regions[0].r_omega: expected a number in [0, 1], got \"abc\""});
  j["regions"][0]["r_omega"] = 1.5;
  ExpectSceneError(j, {"regions[0].r_omega: expected a number in [0, 1], got 1.5"});

  j = TinyScene();
  j["regions"][0]["tag"] = 0.5;
  ExpectSceneError(j, {"regions[0].tag: expected an integer", "got 0.5"});
  j["regions"][0]["tag"] = json::parse("18446744073709551615");  // does not wrap to -1
  ExpectSceneError(j, {"regions[0].tag: expected an integer", "got 18446744073709551615"});
  j = TinyScene();
  j["regions"][0]["role"] = "muscle";
  ExpectSceneError(j,
                   {"regions[0].role: expected one of: body, pneumatic, cable, dea", "\"muscle\""});
  j = TinyScene();
  j["fixed"][1]["box"]["min"] = {1, 2};
  ExpectSceneError(j, {"fixed[1].box.min: expected an array of 3 numbers"});
  j = TinyScene();
  j["mesh"]["scale"] = 0;
  ExpectSceneError(j, {"mesh.scale: expected a number > 0, got 0"});
  // A valid number whose product with the coordinates overflows (or underflows the size).
  j = TinyScene();
  j["mesh"]["scale"] = 1e308;
  ExpectSceneError(j, {"mesh.scale: 1e+308 makes the mesh infinitely across", "[1e-30, 1e30]"});
  j = TinyScene();
  j["mesh"]["scale"] = 1e-200;
  ExpectSceneError(j, {"mesh.scale: 1e-200 makes the mesh", "expected a scale"});
  j = TinyScene();
  j["regions"] = json::object();
  ExpectSceneError(j, {"regions: expected an array of objects"});
  j = TinyScene();
  j["regions"][1] = 3;
  ExpectSceneError(j, {"regions[1]: expected an object, got 3"});
  j = TinyScene();
  j["fixed"][2]["base"] = 2;
  ExpectSceneError(j, {"fixed[2].base: expected an integer in [0, 1], got 2"});
}

TEST(SceneJsonTiny, MooneyRivlinMaterials) {
  TempDir dir;
  WriteTinyMesh(dir.path());
  json j = TinyScene();
  j["regions"][0] = {
      {"tag", 0}, {"role", "body"}, {"material", "dragon-skin-20"}, {"law", "mooney-rivlin"}};
  Scene s = LoadFrom(dir.path(), j);
  EXPECT_TRUE(s.body.at(0).hyperelastic());
  EXPECT_DOUBLE_EQ(s.body.at(0).c1, 0.119);
  EXPECT_DOUBLE_EQ(s.body.at(0).c2, 0.023);
  j["regions"][0]["c2"] = 0.05;  // an explicit value overrides the named one
  s = LoadFrom(dir.path(), j);
  EXPECT_DOUBLE_EQ(s.body.at(0).c1, 0.119);
  EXPECT_DOUBLE_EQ(s.body.at(0).c2, 0.05);
  j["regions"][0] = {
      {"tag", 0}, {"role", "body"}, {"law", "mooney-rivlin"}, {"c1", 0.2}, {"c2", 0}};
  s = LoadFrom(dir.path(), j);
  EXPECT_DOUBLE_EQ(s.body.at(0).c1, 0.2);
  // Errors: no constants, constants without the law, negative constants, unknown law.
  j["regions"][0] = {
      {"tag", 0}, {"role", "body"}, {"material", "rubber"}, {"law", "mooney-rivlin"}};
  ExpectSceneError(
      j, {"regions[0]: law mooney-rivlin needs c1 and c2", "ecoflex-00-30", "\"rubber\""});
  j["regions"][0] = {{"tag", 0}, {"role", "body"}, {"c1", 0.1}, {"c2", 0.1}};
  ExpectSceneError(j, {"regions[0]: c1 / c2 are given but law is \"blend\""});
  j["regions"][0] = {
      {"tag", 0}, {"role", "body"}, {"law", "mooney-rivlin"}, {"c1", -0.1}, {"c2", 0.1}};
  ExpectSceneError(j, {"regions[0].c1: expected a number >= 0, got -0.1"});
  j["regions"][0] = {{"tag", 0}, {"role", "body"}, {"law", "ogden"}};
  ExpectSceneError(j, {"regions[0].law: expected one of: blend, mooney-rivlin", "\"ogden\""});
  j["regions"][0] = {{"tag", 0}, {"role", "body"}, {"law", "mooney-rivlin"}, {"c1", 0}, {"c2", 0}};
  ExpectSceneError(j, {"regions[0]: expected c1 + c2 > 0"});
}

TEST(SceneJsonErrors, UnknownKeysAnywhere) {
  json j = TinyScene();
  j["fixed"][0] = json::parse(R"({"bx": {"min": [0, 0, 0], "max": [1, 1, 1]}})");
  ExpectSceneError(j, {"fixed[0]: unknown key 'bx'", "did you mean 'box'?",
                       "expected one of: region, box, plane, file"});

  struct Case {
    json::json_pointer where;
    std::string message;
  };
  const std::vector<Case> cases = {
      {json::json_pointer("/mesh_file"), "unknown key 'mesh_file'"},
      {json::json_pointer("/mesh/scal"), "mesh: unknown key 'scal'"},
      {json::json_pointer("/regions/1/colour"), "regions[1]: unknown key 'colour'"},
      {json::json_pointer("/fixed/0/plane/tol"), "fixed[0].plane: unknown key 'tol'"},
      {json::json_pointer("/fixed/1/box/centre"), "fixed[1].box: unknown key 'centre'"},
      {json::json_pointer("/markers/2/box/mn"), "markers[2].box: unknown key 'mn'"},
      {json::json_pointer("/markers/0/nam"), "markers[0]: unknown key 'nam'"},
      {json::json_pointer("/solver/tol"), "solver: unknown key 'tol'"},
  };
  // A key path is not a key: {"mesh.file": ...} at the top level is unknown.
  j = TinyScene();
  j["mesh.file"] = "tiny.tet";
  ExpectSceneError(j, {"unknown key 'mesh.file'"});
  j = TinyScene();
  j["fixed"][1]["box.min"] = {0, 0, 0};
  ExpectSceneError(j, {"fixed[1]: unknown key 'box.min'"});

  for (const auto& c : cases) {
    SCOPED_TRACE(c.where.to_string());
    json k = TinyScene();
    k[c.where] = 1;
    ExpectSceneError(k, {c.message, "expected one of:"});
  }
}

TEST(SceneJsonErrors, KeyNotAllowedForRoleOrSelector) {
  json j = TinyScene();
  j["regions"][0]["min"] = 1.0;
  ExpectSceneError(j, {"regions[0].min: not allowed for role 'body'", "pneumatic, cable, dea"});
  j = TinyScene();
  j["regions"][1]["r_omega"] = 1.0;
  ExpectSceneError(j,
                   {"regions[1].r_omega: not allowed for role 'pneumatic'", "only for role body"});
  j = TinyScene();
  j["fixed"][1]["base"] = 1;
  ExpectSceneError(j, {"fixed[1].base: only allowed together with 'file'"});
}

TEST(SceneJsonErrors, SelectorsNeedExactlyOne) {
  json j = TinyScene();
  j["fixed"][0] = json::object();
  ExpectSceneError(j, {"fixed[0]: expected exactly one of: region, box, plane, file, got none"});
  j = TinyScene();
  j["fixed"][1]["plane"] = j["fixed"][0]["plane"];
  ExpectSceneError(j, {"fixed[1]: expected exactly one of", "got both 'box' and 'plane'"});
  j = TinyScene();
  j["markers"][0]["nearest"] = {0, 0, 0};
  ExpectSceneError(j, {"markers[0]: expected exactly one of: vertex, nearest, box"});
}

TEST(SceneJsonErrors, SelectionsThatSelectNothing) {
  json j = TinyScene();
  j["markers"][2]["box"] = json::parse(R"({"min": [10, 10, 10], "max": [11, 11, 11]})");
  ExpectSceneError(j,
                   {"markers[2].box selects no vertex", "the mesh spans [0, 0, 0] to [2, 2, 2]"});
  j = TinyScene();
  j["fixed"][1]["box"] = json::parse(R"({"min": [10, 10, 10], "max": [11, 11, 11]})");
  ExpectSceneError(j, {"fixed[1].box selects no vertex"});
  j = TinyScene();
  j["fixed"][0]["plane"]["point"] = {0, 0.5, 0};
  ExpectSceneError(j, {"fixed[0].plane selects no vertex"});
  j = TinyScene();
  j["fixed"][0]["plane"]["normal"] = {0, 0, 0};
  ExpectSceneError(j, {"fixed[0].plane.normal: expected a non-zero vector"});
  j = TinyScene();
  j["fixed"][0] = {{"region", 7}};
  ExpectSceneError(j, {"fixed[0].region: no element of the mesh has region tag 7", "0, 1, 2"});
  j = TinyScene();
  j["fixed"][1]["box"]["min"] = {4, 0, 0};
  ExpectSceneError(j, {"fixed[1].box: expected min <= max"});
}

TEST(SceneJsonErrors, SyntaxErrorHasLineAndColumn) {
  TempDir dir;
  WriteTinyMesh(dir.path());
  // The stray comma is on line 3, column 11.
  WriteFile(dir.path() / "scene.json", "{\n  \"name\": \"x\",\n  \"mesh\": ,\n}\n");
  ExpectError([&] { LoadSceneJson((dir.path() / "scene.json").string()); },
              {"scene.json:3:11: invalid JSON", "unexpected ','"});
  // Unterminated object: reported at the end of the text.
  ExpectError([] { ParseSceneJson("{\n\"name\": \"x\"\n", "inline.json", "."); },
              {"inline.json:3:1: invalid JSON"});
  ExpectError([] { ParseSceneJson("[1, 2]", "inline.json", "."); },
              {"inline.json: expected a JSON object at the top level, got [1,2]"});
}

TEST(SceneJsonErrors, DuplicateKeys) {
  ExpectError([] { ParseSceneJson(R"({"name": "a", "name": "b"})", "dup.json", "."); },
              {"dup.json: duplicate key 'name'"});
  ExpectError(
      [] {
        ParseSceneJson(R"({"regions": [{"tag": 0}, {"tag": 1, "role": "body", "tag": 2}]})",
                       "dup.json", ".");
      },
      {"dup.json: regions[1]: duplicate key 'tag'"});
}

TEST(SceneJsonErrors, MissingRequiredKeys) {
  json j = TinyScene();
  j.erase("mesh");
  ExpectSceneError(j, {"missing required key 'mesh' (expected an object)"});
  j = TinyScene();
  j.erase("fixed");
  ExpectSceneError(j, {"missing required key 'fixed'"});
  j = TinyScene();
  j["mesh"].erase("file");
  ExpectSceneError(j, {"mesh: missing required key 'file' (expected a string)"});
  j = TinyScene();
  j["regions"][1].erase("tag");
  ExpectSceneError(j, {"regions[1]: missing required key 'tag' (expected an integer)"});
  j = TinyScene();
  j["regions"][1].erase("role");
  ExpectSceneError(j, {"regions[1]: missing required key 'role' (expected one of: body"});
  j = TinyScene();
  j["regions"][2].erase("name");
  ExpectSceneError(j, {"regions[2]: missing required key 'name'"});
  j = TinyScene();
  j["fixed"][1]["box"].erase("max");
  ExpectSceneError(j, {"fixed[1].box: missing required key 'max' (expected an array of 3 numbers"});
  j = TinyScene();
  j["markers"][1].erase("name");
  ExpectSceneError(j, {"markers[1]: missing required key 'name'"});
}

TEST(SceneJsonErrors, MissingFiles) {
  TempDir dir;
  WriteTinyMesh(dir.path());
  json j = TinyScene();
  j["mesh"]["file"] = "nope.tet";
  ExpectError([&] { LoadFrom(dir.path(), j); }, {"scene.json: mesh.file: file not found: '" +
                                                 (dir.path() / "nope.tet").string() + "'"});
  j = TinyScene();
  j["mesh"]["labels"] = "sub/nope.txt";
  ExpectError([&] { LoadFrom(dir.path(), j); }, {"scene.json: mesh.labels: file not found: '" +
                                                 (dir.path() / "sub/nope.txt").string()});
  j = TinyScene();
  j["fixed"][2]["file"] = "none.txt";
  ExpectError([&] { LoadFrom(dir.path(), j); },
              {"scene.json: fixed[2].file: cannot open '" + (dir.path() / "none.txt").string()});
  ExpectError([&] { LoadSceneJson((dir.path() / "absent.json").string()); },
              {"absent.json: cannot open the scene file"});
}

TEST(SceneJsonErrors, MeshFormatKeys) {
  TempDir dir;
  WriteTinyMesh(dir.path());
  WriteFile(dir.path() / "tiny.obj", "v 0 0 0\n");
  json j = TinyScene();
  j["mesh"]["file"] = "tiny.obj";
  ExpectError([&] { LoadFrom(dir.path(), j); },
              {"scene.json: mesh.format: cannot tell the mesh format", "tiny.obj", ".tet, .node"});
  j = TinyScene();
  j["mesh"]["format"] = "gmsh";
  ExpectError([&] { LoadFrom(dir.path(), j); },
              {"scene.json: mesh.labels: only used by the tet format"});
  j = TinyScene();
  j["mesh"]["format"] = "stl";
  ExpectError(
      [&] { LoadFrom(dir.path(), j); },
      {"scene.json: mesh.format: expected one of: auto, tet, tetgen, gmsh, vtk, vtu, got \"stl\""});
}

TEST(SceneJsonErrors, IndexFileBadLineAndOutOfRange) {
  TempDir dir;
  WriteTinyMesh(dir.path());
  WriteFile(dir.path() / "fixed.txt", "6\nseven\n");
  ExpectError([&] { LoadFrom(dir.path(), TinyScene()); },
              {"scene.json: fixed[2].file: ",
               "fixed.txt:2: expected an integer vertex index, got 'seven'"});
  WriteFile(dir.path() / "fixed.txt", "# base 1\n1 2\n7\n");
  ExpectError([&] { LoadFrom(dir.path(), TinyScene()); },
              {"scene.json: fixed[2].file: ",
               "fixed.txt:3: vertex index 7 is out of range; expected 1 to 6"});
  WriteFile(dir.path() / "fixed.txt", "0\n");
  ExpectError([&] { LoadFrom(dir.path(), TinyScene()); },
              {"fixed.txt:1: vertex index 0 is out of range"});
  WriteFile(dir.path() / "fixed.txt", "# nothing\n");
  ExpectError([&] { LoadFrom(dir.path(), TinyScene()); },
              {"fixed[2].file: ", "lists no vertex index"});
}

TEST(SceneJsonErrors, MarkerVertexOutOfRangeAndDuplicateNames) {
  json j = TinyScene();
  j["markers"][0]["vertex"] = 99;
  ExpectSceneError(j, {"markers[0].vertex: expected a vertex index in [0, 5], got 99"});
  j["markers"][0]["vertex"] = -1;
  ExpectSceneError(j, {"markers[0].vertex: expected a vertex index in [0, 5], got -1"});
  j = TinyScene();
  j["markers"][2]["name"] = "a";
  ExpectSceneError(j, {"markers[2].name: marker 'a' is already defined by markers[0]"});
}

TEST(SceneJsonErrors, ActuatorRegionsMustAgree) {
  json j = TinyScene();
  j["regions"][2]["max"] = 4;
  ExpectSceneError(
      j, {"regions[2].max: actuator 'chamber' already has max 3 from regions[1].max, got 4"});
  j = TinyScene();
  j["regions"][2]["role"] = "cable";
  j["regions"][2]["path"] = json::parse("[[0, 0, 0], [1, 0, 0]]");
  ExpectSceneError(
      j, {"regions[2].role: actuator 'chamber' is pneumatic in regions[1].role", "got \"cable\""});
  // A cable's path: at least two finite points, and the same path in every region of the cable.
  j = TinyScene();
  j["regions"][1] =
      json::parse(R"({"tag": 1, "role": "cable", "name": "tendon", "path": [[0, 0, 0]]})");
  ExpectSceneError(j, {"regions[1].path", "expected an array of >= 2 points [[x, y, z], ...]"});
  j = TinyScene();
  j["regions"][1] = json::parse(R"({"tag": 1, "role": "cable", "name": "tendon"})");
  ExpectSceneError(j, {"regions[1]", "path"});
  j = TinyScene();
  j["regions"][1] =
      json::parse(R"({"tag": 1, "role": "cable", "name": "t", "path": [[0, 0, 0], [1, 0, 0]]})");
  j["regions"][2] =
      json::parse(R"({"tag": 2, "role": "cable", "name": "t", "path": [[0, 0, 0], [2, 0, 0]]})");
  ExpectSceneError(j, {"regions[2].path: cable 't' already has a different path"});
  j = TinyScene();
  j["regions"][1]["path"] = json::parse("[[0, 0, 0], [1, 0, 0]]");
  ExpectSceneError(j, {"regions[1].path"});
  j = TinyScene();
  j["regions"][1]["rest"] = 3.5;
  ExpectSceneError(j, {"regions[1]: actuator 'chamber': expected min <= rest <= max",
                       "rest 3.5 (regions[1].rest)", "max 3 (regions[1].max)"});
}

TEST(SceneJsonTiny, SignedActuatorAxesAndMotions) {
  TempDir dir;
  WriteTinyMesh(dir.path());
  const Scene s = LoadFrom(dir.path(), SignedMotionScene());
  ASSERT_EQ(s.num_actuators(), 3);
  const Actuator& a = s.actuators[0];
  EXPECT_EQ(a.name, "s");
  EXPECT_TRUE(a.is_signed());
  EXPECT_EQ(a.regions, std::vector<int>{1});
  EXPECT_EQ(a.negative_regions, std::vector<int>{2});
  EXPECT_DOUBLE_EQ(a.gain, 1.5);
  EXPECT_DOUBLE_EQ(a.min, -2);
  EXPECT_DOUBLE_EQ(a.max, 3);
  EXPECT_DOUBLE_EQ(a.rest, 0);
  EXPECT_DOUBLE_EQ(a.SideRatio(-1, -2), 4.0);  // 1 + 1.5 * 2
  EXPECT_DOUBLE_EQ(a.SideRatio(+1, -2), 1.0);
  // Motions follow the region actuators, in file order; the axis is normalised.
  EXPECT_EQ(s.actuators[1].name, "lift");
  EXPECT_EQ(s.actuators[1].type, ActuatorType::Displacement);
  EXPECT_EQ(s.actuators[1].vertices, std::vector<int>{4});
  EXPECT_EQ(s.actuators[1].axis, Eigen::Vector3d(0, 0, 1));
  EXPECT_DOUBLE_EQ(s.actuators[1].rest, 0);
  EXPECT_EQ(s.actuators[2].type, ActuatorType::Twist);
  EXPECT_EQ(s.actuators[2].vertices, std::vector<int>{3});
  EXPECT_EQ(s.actuators[2].centre, Eigen::Vector3d(1, 0, 1));
  EXPECT_DOUBLE_EQ(s.actuators[2].min, -90);
  // Vertex 3 (0,2,0) turned 90 degrees about the y line through (1,0,1): (0,2,2).
  EXPECT_LT((s.actuators[2].Move(s.mesh.vertices.row(3).transpose(), 90) - Eigen::Vector3d(0, 2, 2))
                .norm(),
            1e-12);
  EXPECT_EQ(s.rest_actuation(), Eigen::Vector3d(0, 0, 0));
  EXPECT_EQ(s.fixed, (std::vector<int>{0, 1, 2}));
  EXPECT_EQ(s.fixed_axis[0], std::vector<int>{5});
  EXPECT_TRUE(s.fixed_axis[1].empty());
  EXPECT_EQ(s.fixed_axis[2], std::vector<int>{5});
  EXPECT_TRUE(s.is_constrained(5, 2));
  EXPECT_FALSE(s.is_constrained(5, 1));
  EXPECT_TRUE(s.is_constrained(4, 1));  // moved
  // A per-axis hold on a fully fixed vertex adds nothing.
  json j = SignedMotionScene();
  j["fixed"][1] =
      json::parse(R"({"plane": {"point": [0, 0, 0], "normal": [0, 1, 0]}, "axes": "y"})");
  const Scene t = LoadFrom(dir.path(), j);
  for (int d = 0; d < 3; ++d) EXPECT_TRUE(t.fixed_axis[d].empty());
}

TEST(SceneJsonErrors, SignedActuatorBadValues) {
  json j = SignedMotionScene();
  j["regions"][1].erase("min");
  ExpectSceneError(
      j, {"regions[1]: signed actuator 's' (negative side from regions[2].side) needs 'min'",
          "expected min <= 0 <= max"});
  j = SignedMotionScene();
  j["regions"][2]["rest"] = 1;
  ExpectSceneError(j, {"regions[2].rest: signed actuator 's': expected rest 0, got 1"});
  j = SignedMotionScene();
  j["regions"][1]["min"] = 0.5;
  ExpectSceneError(j, {"regions[1].min: signed actuator 's': expected min <= 0, got 0.5"});
  j = SignedMotionScene();
  j["regions"][1]["max"] = -0.5;
  ExpectSceneError(j, {"regions[1].max: signed actuator 's': expected max >= 0, got -0.5"});
  j = SignedMotionScene();
  j["regions"][1]["side"] = "negative";
  ExpectSceneError(j, {"regions[1]: signed actuator 's' has only negative-side regions"});
  j = SignedMotionScene();
  j["regions"][2]["side"] = "left";
  ExpectSceneError(j, {"regions[2].side: expected one of: positive, negative", "\"left\""});
  j = SignedMotionScene();
  j["regions"][1]["gain"] = 0;
  ExpectSceneError(j, {"regions[1].gain: expected a number > 0, got 0"});
  j = SignedMotionScene();
  j["regions"][2]["gain"] = 2;
  ExpectSceneError(
      j, {"regions[2].gain: actuator 's' already has gain 1.5 from regions[1].gain, got 2"});
  j = SignedMotionScene();
  j["regions"][0]["side"] = "negative";
  ExpectSceneError(j, {"regions[0].side: not allowed for role 'body'"});
  // Unsigned actuators: gain has no meaning, and the values are ratios.
  j = TinyScene();
  j["regions"][1]["gain"] = 2;
  ExpectSceneError(j, {"regions[1].gain: actuator 'chamber' is not signed"});
  j = TinyScene();
  j["regions"][1]["min"] = 0;
  ExpectSceneError(j, {"regions[1].min: actuator 'chamber': expected a ratio > 0, got 0"});
  j = TinyScene();
  j["regions"][1]["min"] = -1;
  ExpectSceneError(j, {"regions[1].min: actuator 'chamber': expected a ratio > 0, got -1"});
}

TEST(SceneJsonErrors, FixedAxesBadValues) {
  for (const char* bad : {"xx", "w", "", "X", "x y"}) {
    json j = SignedMotionScene();
    j["fixed"][1]["axes"] = bad;
    ExpectSceneError(j, {"fixed[1].axes: expected some of the letters x, y, z"});
  }
  json j = SignedMotionScene();
  j["fixed"][1]["axes"] = 3;
  ExpectSceneError(j, {"fixed[1].axes: expected a string, got 3"});
}

TEST(SceneJsonErrors, ObstaclesAndCollisionOptions) {
  auto with_obstacle = [](const json& o) {
    json j = SignedMotionScene();
    j["obstacles"] = json::array({o});
    return j;
  };
  ExpectSceneError(
      with_obstacle(json::parse(R"({"type": "box", "min": [0, 0, 0], "max": [0, 1, 1]})")),
      {"obstacles[0]: box obstacle: expected min < max on every axis"});
  ExpectSceneError(with_obstacle(json::parse(R"({"type": "box", "min": [0, 0, 0]})")),
                   {"obstacles[0]: missing required key 'max'"});
  ExpectSceneError(
      with_obstacle(json::parse(R"({"type": "cylinder", "min": [0, 0, 0], "base": [0, 0, 0],
                                                 "axis": [0, 0, 1], "radius": 1, "height": 1})")),
      {"obstacles[0].min: not allowed for type 'cylinder'"});
  ExpectSceneError(
      with_obstacle(json::parse(R"({"type": "cylinder", "base": [0, 0, 0], "axis": [0, 0, 1],
                                                 "radius": -1, "height": 1})")),
      {"obstacles[0].radius: expected a number > 0"});
  ExpectSceneError(with_obstacle(json::parse(R"({"type": "file", "file": "no_such_surface.obj"})")),
                   {"obstacles[0].file: file not found", "no_such_surface.obj"});
  ExpectSceneError(with_obstacle(json::parse(R"({"type": "sphere"})")),
                   {"obstacles[0].type: expected one of: box, cylinder, file"});
  // A polygon of 1e9 sides would allocate gigabytes: the key's range says where the limit is.
  ExpectSceneError(with_obstacle(json::parse(R"({"type": "cylinder", "base": [9, 0, 0],
      "axis": [0, 0, 1], "radius": 1, "height": 2, "segments": 1e9})")),
                   {"obstacles[0].segments: expected an integer in [3, 100000]"});
  json j = SignedMotionScene();
  j["solver"]["collision"] = json::parse(R"({"self": "yes"})");
  ExpectSceneError(j, {"solver.collision.self: expected a boolean (true or false)"});
  j["solver"]["collision"] = json::parse(R"({"update": "magic"})");
  ExpectSceneError(j, {"solver.collision.update: expected one of: updown, refactor"});
  j["solver"]["collision"] = json::parse(R"({"check_interval": 0})");
  ExpectSceneError(j, {"solver.collision.check_interval: expected an integer >= 1"});
  // And a good one: both kinds of obstacle and every collision option are read.
  json ok = SignedMotionScene();
  ok["obstacles"] = json::parse(R"([{"type": "box", "min": [5, 5, 5], "max": [6, 7, 8]},
      {"type": "cylinder", "base": [9, 0, 0], "axis": [0, 0, 2], "radius": 1.5, "height": 4, "segments": 12}])");
  ok["solver"]["collision"] = json::parse(R"({"self": true, "obstacles": false, "epsilon": 0.1,
      "stiffness": 5, "check_interval": 3, "update": "refactor"})");
  TempDir dir;
  WriteTinyMesh(dir.path());
  const Scene s = LoadFrom(dir.path(), ok);
  ASSERT_EQ(s.obstacles.size(), 2u);
  EXPECT_EQ(s.obstacles[0].faces.rows(), 12);
  EXPECT_NEAR(s.obstacles[0].vertices.col(2).maxCoeff(), 8.0, 1e-12);
  EXPECT_EQ(s.obstacles[1].faces.rows(), 4 * 12);
  EXPECT_NE(s.obstacles[1].source.find("obstacles[1]"), std::string::npos);
  EXPECT_TRUE(s.solver.collision.self);
  EXPECT_FALSE(s.solver.collision.obstacles);
  EXPECT_EQ(s.solver.collision.epsilon, 0.1);
  EXPECT_EQ(s.solver.collision.stiffness, 5.0);
  EXPECT_EQ(s.solver.collision.check_interval, 3);
  EXPECT_EQ(s.solver.collision.update, SpringUpdate::kRefactor);
}

TEST(SceneJsonErrors, MotionBadValues) {
  auto with = [](const std::string& key, const json& v) {
    json j = SignedMotionScene();
    j["motions"][1][key] = v;
    return j;
  };
  auto without = [](const std::string& key) {
    json j = SignedMotionScene();
    j["motions"][1].erase(key);
    return j;
  };
  ExpectSceneError(without("axis"), {"motions[1]: missing required key 'axis'"});
  ExpectSceneError(without("min"), {"motions[1]: missing required key 'min'"});
  ExpectSceneError(without("type"), {"motions[1]: missing required key 'type'"});
  ExpectSceneError(without("box"),
                   {"motions[1]: expected exactly one of: region, box, plane, file, got none"});
  ExpectSceneError(with("region", 0), {"motions[1]: expected exactly one of", "got both"});
  ExpectSceneError(with("type", "spin"), {"motions[1].type: expected one of: displacement, twist"});
  ExpectSceneError(with("axis", json::parse("[0, 0, 0]")),
                   {"motions[1].axis: expected a non-zero vector"});
  ExpectSceneError(with("axis", json::parse("[0, 1]")), {"motions[1].axis: expected"});
  ExpectSceneError(with("min", 5), {"motions[1].min: expected a number <= 0 (rest is 0), got 5"});
  ExpectSceneError(with("max", -5), {"motions[1].max: expected a number >= 0 (rest is 0), got -5"});
  ExpectSceneError(with("name", "s"),
                   {"motions[1].name: actuator 's' is already defined in regions"});
  ExpectSceneError(with("name", "lift"),
                   {"motions[1].name: actuator 'lift' is already defined by motions[0]"});
  ExpectSceneError(with("box", json::parse(R"({"min": [9, 9, 9], "max": [10, 10, 10]})")),
                   {"motions[1].box selects no vertex"});
  ExpectSceneError(with("box", json::parse(R"({"min": [-1, -1, -1], "max": [0.5, 0.5, 0.5]})")),
                   {"motions[1]: vertex 0", "is also in `fixed`"});
  ExpectSceneError(with("box", json::parse(R"({"min": [-1, 1.9, 1.9], "max": [0.5, 2.1, 2.1]})")),
                   {"motions[1]: vertex 5", "is also held on axis x by `fixed`"});
  json j = SignedMotionScene();
  j["motions"][0]["centre"] = json::parse("[0, 0, 0]");
  ExpectSceneError(j, {"motions[0].centre: not allowed for type 'displacement'"});
  j = SignedMotionScene();
  j["motions"][0]["speed"] = 1;
  ExpectSceneError(j, {"motions[0]: unknown key 'speed'"});
  j = SignedMotionScene();
  j["motions"] = json::parse("{}");
  ExpectSceneError(j, {"motions: expected"});
}

TEST(SceneJsonErrors, RegionTags) {
  json j = TinyScene();
  j["regions"][2]["tag"] = 9;
  ExpectSceneError(
      j, {"regions[2].tag: no element of the mesh has region tag 9 (the mesh's tags: 0, 1, 2)"});
  j = TinyScene();
  j["regions"][2]["tag"] = 1;
  ExpectSceneError(j, {"regions[2].tag: region 1 is already described by regions[1]"});
}

TEST(SceneJsonErrors, ValidateMessagePassesThrough) {
  json j = TinyScene();
  j["regions"].erase(2);
  ExpectSceneError(j, {"region 2 has elements but no role"});
}

TEST(SceneJsonErrors, SolverOptions) {
  json j = TinyScene();
  j["solver"]["solver"] = "newtonian";
  ExpectSceneError(j,
                   {"solver.solver: expected one of: lg, lg-aa, newton, auto, ceres, ipopt-lbfgs, "
                    "ipopt-newton, ipopt-hard, calculix-linear, calculix-nonlinear, got "
                    "\"newtonian\""});
  j = TinyScene();
  j["solver"]["anderson_window"] = 0;
  ExpectSceneError(j, {"solver.anderson_window: expected an integer in [1, 50], got 0"});
  j = TinyScene();
  j["solver"]["tolerance"] = -1;
  ExpectSceneError(j, {"solver.tolerance: expected a number in (0, 0.01], got -1"});
  // A stopping test looser than its meaning would call a far-off state converged.
  j = TinyScene();
  j["solver"]["gradient_tolerance"] = 2;
  ExpectSceneError(j, {"solver.gradient_tolerance: expected a number in (0, 0.1], got 2"});
}

TEST(SceneJsonErrors, MeshReaderErrorPassesThrough) {
  TempDir dir;
  WriteTinyMesh(dir.path());
  std::string bad = kTinyTet;
  bad.replace(bad.rfind("4 2 4 3 5"), 9, "4 2 4 3 99");  // line 11: vertex index out of range
  WriteFile(dir.path() / "bad.tet", bad);
  json j = TinyScene();
  j["mesh"]["file"] = "bad.tet";
  ExpectError([&] { LoadFrom(dir.path(), j); },
              {"scene.json: mesh.file: cannot read the tet mesh: ", "bad.tet:11"});
  // A label file with too few labels: the reader names the label file and its line.
  WriteFile(dir.path() / "short_labels.txt", "0\n1\n");
  j = TinyScene();
  j["mesh"]["labels"] = "short_labels.txt";
  ExpectError([&] { LoadFrom(dir.path(), j); },
              {"scene.json: mesh.labels: cannot read the tet mesh: ", "short_labels.txt:"});
}

// time_limit_s is a scene key as it is a config key.
TEST(SceneJsonTiny, SolverTimeLimitIsAKey) {
  TempDir dir;
  WriteTinyMesh(dir.path());
  json j = TinyScene();
  j["solver"] = {{"time_limit_s", 30}, {"collision", {{"stiffness", 4}}}};
  const Scene s = ParseSceneJson(j.dump(), "inline.json", dir.path().string());
  EXPECT_DOUBLE_EQ(s.solver.time_limit_s, 30.0);
  EXPECT_DOUBLE_EQ(s.solver.collision.stiffness, 4.0);
  EXPECT_EQ(s.solver.max_iterations, FkOptions().max_iterations);
}

}  // namespace
}  // namespace softkin
