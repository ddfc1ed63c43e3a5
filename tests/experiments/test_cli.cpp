// Tests of the `softkin` command line: the contract later issues and users rely on.
#include "softkin/experiments/cli_args.hpp"
#include "softkin/experiments/cli_dataset.hpp"
#include "softkin/experiments/cli_fk.hpp"
#include "softkin/experiments/cli_ik.hpp"
#include "softkin/solver/scene/solver_options_json.hpp"
#include "tests/experiments/cli_test_util.hpp"
#include "tests/solver/fk/fk_test_util.hpp"
#include "tests/solver/scene/scene_json_test_util.hpp"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <array>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

using namespace softkin::cli_test;  // NOLINT: the helpers of every test here

namespace {

// An output that is also an input (or another output), or that cannot be written, is refused
// before any solve, and the input is left as it was; a failed write is an error, not exit 0.
TEST(Cli, BadOutputsAndValuesAreRefusedBeforeAnyWork) {
  const std::string dir = TempDir("outputs");
  const std::string scene = dir + "/s.json", path = dir + "/p.txt";
  {
    std::ofstream(scene) << R"({"robot": {"name": "three_chamber", "res": 3}})";
    std::ofstream(path) << "0 0 50\n";
    std::ofstream(dir + "/cfg.json") << R"({"name": "t", "experiment": "aa_ablation", "seed": 1,
      "robots": ["three_chamber"], "resolutions": [3], "levels": [1.0]})";
  }
  const std::string scene_text = ReadAll(scene), path_text = ReadAll(path);
  struct Case {
    std::string args, expect;
  };
  const std::string fk = "fk --robot three_chamber --res 3 --actuation 1.2,1,1 ";
  for (const Case& c : std::vector<Case>{
           {"fk --scene " + scene + " --actuation 1.2,1,1 --json " + scene,
            "same file as the input --scene"},
           {fk + "--json " + dir + "/o --vtu " + dir + "/./o", "same file as the output --json"},
           {fk + "--vtu " + dir + "/nodir/o.vtu", "does not exist"},
           {fk + "--json " + dir, "is a folder"},
           {"ik --robot three_chamber --res 3 --trajectory " + path + " --out " + path,
            "same file as the input --trajectory"},
           {"ik --robot three_chamber --res 3 --trajectory " + path + " --out " + dir +
                "/x.csv --cache " + dir + "/x.csv",
            "--cache"},
           {"dataset --robot three_chamber --res 3 --grid 2 --out " + dir + "/nodir/d.csv",
            "does not exist"},
           // Thread counts beyond the cap (100000 crashed libgomp).
           {fk + "--threads 100000", "solver.threads: expected an integer in [0, 256]"},
           {"train --dataset " + dir + "/d.csv --out " + dir + "/nets --threads 100000",
            "--threads: expected an integer in [0, 256]"},
           // 0 is no longer a silent "default".
           {"fk --robot three_chamber --res 0 --actuation 1,1,1", "--res: Value 0 not in range"},
           {"dataset --robot three_chamber --grid 0 --out " + dir + "/d.csv",
            "--grid: Value 0 not in range"},
           {"dataset --robot three_chamber --random 0 --seed 1 --out " + dir + "/d.csv",
            "--random: Value 0 not in range"},
           {"calibrate --rm 2 --res 0", "--res: Value 0 not in range"},
           // Networks are inputs of ik and outputs of train; a TetGen .node brings its .ele.
           {"ik --robot three_chamber --nets " + dir +
                "/nets --method learned --target 10,136,0 "
                "--out " +
                dir + "/nets/fk.fnn",
            "same file as the input --nets"},
           {"train --dataset " + dir + "/nets/nets.json --out " + dir + "/nets",
            "same file as the input --dataset"},
           {"tessellate --body " + dir + "/b.obj --chamber " + dir + "/c.obj --out " + dir +
                "/m.node --json " + dir + "/m.ele",
            "same file as the output --out's .ele"},
           // Stopping tests looser than their meaning (a fraction of the model size, of the
           // first gradient) would call a far-off state converged.
           {fk + "--tolerance 10", "solver.tolerance: expected a number in (0, 0.01], got 10"},
           {fk + "--gradient-tolerance 0.5",
            "solver.gradient_tolerance: expected a number in (0, 0.1], got 0.5"},
           {"run " + dir + "/cfg.json --results " + path, "is a file; expected a folder"},
           {"dataset --robot three_chamber --random 5 --seed -5 --out " + dir + "/d.csv",
            "--seed: required with --random: expected an integer >= 0, got -5"},
           {"dataset --robot three_chamber --grid 2 --points tip,tip --out " + dir + "/d.csv",
            "--points: expected each point once, got 'tip' twice"},
           // An empty value (an unset shell variable) is not "no file".
           {fk + "--vtu \"\"", "--vtu: expected a value, got an empty string"},
           // One value per option: no repeat silently wins.
           {fk + "--set tolerance=1e-3 --tolerance 1e-5",
            "--set tolerance: the option is also given as --tolerance"},
           {fk + "--set tolerance=1e-3 --set tolerance=1e-4",
            "--set: expected each option once, got 'tolerance' twice"},
           {"fk --robot pneumatic_finger --res 4 --actuation 1.2 --param design_grid=0 "
            "--param design_grid=1",
            "--param: expected each parameter once, got 'design_grid' twice"}}) {
    const CliRun r = Cli(c.args);
    EXPECT_EQ(r.code, 2) << c.args << "\n" << r.out;
    EXPECT_NE(r.out.find(c.expect), std::string::npos) << c.args << "\n" << r.out;
    EXPECT_EQ(r.out.find("converged"), std::string::npos) << "solved before the check: " << r.out;
  }
  EXPECT_EQ(ReadAll(scene), scene_text);
  EXPECT_EQ(ReadAll(path), path_text);
  if (std::filesystem::exists("/dev/full")) {
    const CliRun r = Cli(fk + "--json /dev/full");
    EXPECT_NE(r.code, 0) << r.out;
    EXPECT_NE(r.out.find("/dev/full: write error"), std::string::npos) << r.out;
  }
}

TEST(Cli, HelpOnEveryCommand) {
  for (const char* c : {"--help", "robots --help", "fk --help", "run --help", "scene --help",
                        "calibrate --help", "train --help", "dataset --help", "ik --help"}) {
    const CliRun r = Cli(c);
    EXPECT_EQ(r.code, 0) << c << "\n" << r.out;
    EXPECT_NE(r.out.find("Usage"), std::string::npos) << c;
  }
}

TEST(Cli, RobotsJsonListsActuatorsAndMarkers) {
  const CliRun r = Cli("robots --json");
  ASSERT_EQ(r.code, 0) << r.out;
  const auto j = nlohmann::json::parse(r.out);
  ASSERT_GE(j.size(), 2u);
  for (const auto& robot : j) {
    // Default meshes: thousands of tets, or a thin shell of prisms (dea_crawler).
    EXPECT_GT(robot["n_tets"].get<int>() + robot["n_prisms"].get<int>(), 500) << robot["name"];
    EXPECT_FALSE(robot["actuators"].empty());
    EXPECT_TRUE(robot["params"].is_array()) << robot["name"];
    for (const auto& p : robot["params"]) {
      EXPECT_LE(p["range"][0].get<double>(), p["default"].get<double>()) << p["name"];
      EXPECT_LE(p["default"].get<double>(), p["range"][1].get<double>()) << p["name"];
    }
    bool has_tip = false;
    for (const auto& m : robot["markers"]) has_tip = has_tip || m == "tip";
    EXPECT_TRUE(has_tip) << robot["name"];
  }
}

TEST(Cli, FkWritesTheDocumentedJson) {
  const std::string dir = TempDir("fk");
  const CliRun r = Cli("fk --robot three_chamber --res 3 --actuation 1.3,1,1 --json " + dir +
                       "/fk.json --vtu " + dir + "/fk.vtu");
  ASSERT_EQ(r.code, 0) << r.out;
  std::ifstream f(dir + "/fk.json");
  const auto j = nlohmann::json::parse(f);
  for (const char* k : {"status", "iterations", "energy", "time_s", "n_vertices", "n_elements",
                        "actuation", "markers"})
    EXPECT_TRUE(j.contains(k)) << k;
  EXPECT_EQ(j["status"], "converged");
  EXPECT_EQ(j["actuation"].size(), 3u);
  ASSERT_TRUE(j["markers"].contains("tip"));
  // Inflating c1 (at phi = 180 deg, on -x) bends the tip towards +x.
  EXPECT_GT(j["markers"]["tip"][0].get<double>(), 0.5);
  EXPECT_TRUE(std::filesystem::exists(dir + "/fk.vtu"));
}

// With collision handling on, the JSON carries the exact check of the final state; without it,
// no collision object.
TEST(Cli, FkJsonCarriesTheCollisionCheck) {
  const std::string dir = TempDir("fk_collision");
  const CliRun r =
      Cli("fk --robot selfcollision_finger --res 5 --actuation 1.5 --json " + dir + "/fk.json");
  ASSERT_EQ(r.code, 0) << r.out;
  std::ifstream f(dir + "/fk.json");
  const auto j = nlohmann::json::parse(f);
  ASSERT_TRUE(j.contains("collision")) << j.dump();
  const auto& c = j["collision"];
  for (const char* k :
       {"collision_free", "self_contacts", "obstacle_contacts", "max_penetration_mm",
        "inverted_elements", "inverted_body_elements", "tangled_contacts", "springs",
        "unresolved_contacts", "check_s", "response_s"})
    EXPECT_TRUE(c.contains(k)) << k;
  // The finger's walls press on each other at this inflation: springs hold them apart, and the
  // final state passes the exact check.
  EXPECT_TRUE(c["collision_free"].get<bool>());
  EXPECT_EQ(c["self_contacts"].get<int>(), 0);
  EXPECT_GT(c["springs"].get<int>(), 0);
  EXPECT_GT(c["check_s"].get<double>(), 0.0);

  const CliRun plain =
      Cli("fk --robot three_chamber --res 3 --actuation 1.3,1,1 --json " + dir + "/plain.json");
  ASSERT_EQ(plain.code, 0) << plain.out;
  std::ifstream g(dir + "/plain.json");
  EXPECT_FALSE(nlohmann::json::parse(g).contains("collision"));
}

// --set reaches every solver option through the scene JSON's reader, and names a bad one.
TEST(Cli, FkSetsAnySolverOption) {
  const std::string dir = TempDir("fk_set");
  const CliRun capped =
      Cli("fk --robot three_chamber --res 3 --actuation 1.3,1,1 --set max_iterations=3 "
          "--set collision.stiffness=5 --json " +
          dir + "/fk.json");
  EXPECT_EQ(capped.code, 1) << capped.out;  // not converged in 3 iterations
  std::ifstream f(dir + "/fk.json");
  const nlohmann::json j = nlohmann::json::parse(f);
  EXPECT_EQ(j["status"], "iteration_cap");
  EXPECT_EQ(j["iterations"].get<int>(), 3);
  const CliRun typo = Cli("fk --robot three_chamber --res 3 --actuation 1.3,1,1 --set tolerence=1");
  EXPECT_NE(typo.code, 0);
  EXPECT_NE(typo.out.find("--set: solver.tolerence: unknown key (expected one of solver, "),
            std::string::npos)
      << typo.out;
  const CliRun bad = Cli("fk --robot three_chamber --res 3 --actuation 1.3,1,1 --set threads=x");
  EXPECT_NE(bad.code, 0);
  EXPECT_NE(bad.out.find("--set: solver.threads: expected an integer in [0, 256], got \"x\""),
            std::string::npos)
      << bad.out;
}

// Every option of the FK option table has a `softkin fk` flag, and each flag's value reaches
// FkOptions through the option reader (in process: the flags CLI11 parses, then
// FkOptionsFromArgs).
TEST(Cli, FkHasAFlagForEveryOptionThatReachesFkOptions) {
  using namespace softkin;
  // A value other than the default for every option.
  const FkOptions want = test::NonDefaultFkOptions();
  const nlohmann::json wj = SolverOptionsToJson(want), dj = SolverOptionsToJson(FkOptions());

  CLI::App app;
  FkCommandArgs args;
  CLI::App* fk = AddFkCommand(&app, &args);
  std::string line = "fk --robot three_chamber --actuation 1";
  for (const std::string& key : SolverOptionKeys()) {
    const std::string flag = FkOptionFlagName(key);
    EXPECT_NE(fk->get_option_no_throw(flag), nullptr) << key << ": no flag " << flag;
    const auto dot = key.find('.');
    const nlohmann::json& v =
        dot == std::string::npos ? wj.at(key) : wj.at(key.substr(0, dot)).at(key.substr(dot + 1));
    const nlohmann::json& d =
        dot == std::string::npos ? dj.at(key) : dj.at(key.substr(0, dot)).at(key.substr(dot + 1));
    EXPECT_NE(v, d) << key << ": the test value is the default";
    line += " " + flag + " " + (v.is_string() ? v.get<std::string>() : v.dump());
  }
  app.parse(line, false);
  EXPECT_EQ(SolverOptionsToJson(FkOptionsFromArgs(args, FkOptions())), wj) << line;

  // --max-iterations 5 alone; the short names of older command lines; --set after the flags.
  CLI::App app2;
  FkCommandArgs args2;
  AddFkCommand(&app2, &args2);
  app2.parse(
      "fk --robot three_chamber --actuation 1 --max-iterations 5 --continuation 3 "
      "--aa-safeguard none --set tolerance=1e-3",
      false);
  const FkOptions o = FkOptionsFromArgs(args2, FkOptions());
  EXPECT_EQ(o.max_iterations, 5);
  EXPECT_EQ(o.continuation_steps, 3);
  EXPECT_EQ(o.anderson_safeguard, AndersonSafeguard::kNone);
  EXPECT_DOUBLE_EQ(o.tolerance, 1e-3);
  EXPECT_EQ(o.solver, FkOptions().solver);  // not given: the base's

  // A bad value names the flag, the option and what was expected.
  CLI::App app3;
  FkCommandArgs args3;
  AddFkCommand(&app3, &args3);
  app3.parse("fk --robot three_chamber --actuation 1 --max-iterations 0", false);
  try {
    (void)FkOptionsFromArgs(args3, FkOptions());
    ADD_FAILURE() << "no exception for --max-iterations 0";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("--max-iterations: solver.max_iterations: expected an "
                                         "integer >= 1, got 0"),
              std::string::npos)
        << e.what();
  }

  // ik and dataset take the FK option they use by the same generated flag.
  CLI::App app4;
  IkCommandArgs ik;
  DatasetCommandArgs ds;
  EXPECT_NE(AddIkCommand(&app4, &ik)->get_option_no_throw("--gradient-tolerance"), nullptr);
  EXPECT_NE(AddDatasetCommand(&app4, &ds)->get_option_no_throw("--gradient-tolerance"), nullptr);
  app4.parse("ik --robot cable_finger --target 1,2,3 --gradient-tolerance 1e-4", false);
  EXPECT_DOUBLE_EQ(ApplyFkOptionFlags(ik.fk_options, FkOptions()).gradient_tolerance, 1e-4);
}

TEST(Cli, FkReportsEachContinuationStep) {
  const std::string dir = TempDir("fk_steps");
  const CliRun r =
      Cli("fk --robot three_chamber --res 3 --actuation 1.3,1,1 --continuation 3 --json " + dir +
          "/fk.json");
  ASSERT_EQ(r.code, 0) << r.out;
  for (const char* line :
       {"fk: step 1/3: converged", "fk: step 2/3: converged", "fk: step 3/3: converged"})
    EXPECT_NE(r.out.find(line), std::string::npos) << r.out;
  EXPECT_EQ(r.out.find("step 4/3"), std::string::npos) << r.out;
  // Without continuation there is one step and no step report.
  const CliRun one =
      Cli("fk --robot three_chamber --res 3 --actuation 1.3,1,1 --json " + dir + "/fk1.json");
  ASSERT_EQ(one.code, 0) << one.out;
  EXPECT_EQ(one.out.find("fk: step"), std::string::npos) << one.out;
}

TEST(Cli, BadValuesNameTheOptionAndWhatWasExpected) {
  CliRun r = Cli("fk --robot three_chamber --res 3 --actuation 1.3,abc,1");
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.out.find("--actuation"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("expected"), std::string::npos) << r.out;
  r = Cli("fk --robot three_chamber --res 3 --actuation 9,1,1");
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.out.find("c1"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("[1, 3]"), std::string::npos) << r.out;
  r = Cli("fk --robot no_such_robot --actuation 1");
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.out.find("known robots"), std::string::npos) << r.out;
  r = Cli("fk --robot three_chamber --res 1 --actuation 1,1,1");
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.out.find("res"), std::string::npos) << r.out;
  r = Cli("fk --robot three_chamber --res 3 --actuation 1,1,1 --solver magic");
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.out.find("lg-aa"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("calculix-nonlinear"), std::string::npos) << r.out;
  // A scene the chosen solver cannot express is the solver's error, not the actuation's.
  r = Cli("fk --robot dea_crawler --res 4 --actuation 0.8 --solver calculix-linear");
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.out.find("--solver calculix-linear: calculix: element 0 is a prism"),
            std::string::npos)
      << r.out;
}

TEST(Cli, CalibratePrintsTheRatioAndRejectsBadValues) {
  CliRun r = Cli("calibrate --rm 3.75 --res 2");
  ASSERT_EQ(r.code, 0) << r.out;
  EXPECT_NE(r.out.find("R_omega^A / R_omega^B = 6.09"), std::string::npos) << r.out;
  r = Cli("calibrate --rm -1 --res 2");
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.out.find("rm = -1, expected a finite elasticity ratio > 0"), std::string::npos)
      << r.out;
  r = Cli("calibrate --rm 3 --interface 2");
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.out.find("interface = 2, expected a fraction of the length in [0.05, 0.95]"),
            std::string::npos)
      << r.out;
}

TEST(Cli, SceneSchemaPrintsKeys) {
  const CliRun r = Cli("scene --schema");
  ASSERT_EQ(r.code, 0);
  for (const char* k : {"mesh.file", "regions", "fixed", "markers", "solver"})
    EXPECT_NE(r.out.find(k), std::string::npos) << k;
}

// `softkin scene` runs what fk checks before it solves: a cable whose path misses its elements
// loads as JSON but cannot be modelled, and the check says so, naming the file.
TEST(Cli, SceneCheckBuildsTheModelAsFkDoes) {
  const std::string dir = TempDir("scene_check");
  softkin::scene_test::WriteTinyMesh(dir);
  nlohmann::json good = softkin::scene_test::TinyScene();
  std::ofstream(dir + "/good.json") << good.dump(2);
  CliRun r = Cli("scene " + dir + "/good.json");
  EXPECT_EQ(r.code, 0) << r.out;
  nlohmann::json bad = good;
  bad["regions"][1] = {
      {"tag", 1}, {"role", "cable"}, {"name", "tendon"}, {"path", {{10, 10, 10}, {11, 10, 10}}}};
  bad["regions"][2] = {{"tag", 2}, {"role", "body"}};
  std::ofstream(dir + "/bad.json") << bad.dump(2);
  r = Cli("scene " + dir + "/bad.json");
  EXPECT_NE(r.code, 0) << r.out;
  EXPECT_NE(r.out.find(dir + "/bad.json: cable 'tendon': its path does not pass through its "
                             "actuation elements"),
            std::string::npos)
      << r.out;
}

/// An axis-aligned box [lo, hi]^3 as a Wavefront OBJ (outward triangles).
void WriteBoxObj(const std::string& path, double lo, double hi) {
  std::ofstream f(path);
  for (int i = 0; i < 8; ++i)
    f << "v " << (i & 1 ? hi : lo) << " " << (i & 2 ? hi : lo) << " " << (i & 4 ? hi : lo) << "\n";
  const int t[12][3] = {{0, 2, 1}, {1, 2, 3}, {4, 5, 6}, {5, 7, 6}, {0, 1, 4}, {1, 5, 4},
                        {2, 6, 3}, {3, 6, 7}, {0, 4, 2}, {2, 4, 6}, {1, 3, 5}, {3, 7, 5}};
  for (const auto& tri : t)
    f << "f " << tri[0] + 1 << " " << tri[1] + 1 << " " << tri[2] + 1 << "\n";
}

TEST(Cli, TessellateMeshesABoxChamberInABoxBody) {
  const std::string dir = TempDir("tessellate");
  WriteBoxObj(dir + "/body.obj", -3, 3);
  WriteBoxObj(dir + "/chamber.obj", -1, 1);
  CliRun r = Cli("tessellate --help");
  EXPECT_EQ(r.code, 0) << r.out;
  EXPECT_NE(r.out.find("--chamber"), std::string::npos) << r.out;
  r = Cli("tessellate --body " + dir + "/body.obj --chamber " + dir +
          "/chamber.obj --size 1 --out " + dir + "/mesh.vtk --json " + dir + "/report.json");
  ASSERT_EQ(r.code, 0) << r.out;
  std::ifstream f(dir + "/report.json");
  const auto j = nlohmann::json::parse(f);
  EXPECT_GT(j["body_tets"].get<int>(), 50);
  EXPECT_GT(j["chamber_tets"].get<int>(), 5);
  EXPECT_NEAR(j["body_volume"].get<double>(), 208.0, 0.2);
  EXPECT_NEAR(j["chamber_volume"].get<double>(), 8.0, 0.01);
  // The VTK file holds both regions.
  std::ifstream vtk(dir + "/mesh.vtk");
  const std::string text((std::istreambuf_iterator<char>(vtk)), std::istreambuf_iterator<char>());
  EXPECT_NE(text.find("CELL_TYPES"), std::string::npos);
  // A chamber that sticks out of the body is rejected, naming the file.
  WriteBoxObj(dir + "/big.obj", -2, 4);
  r = Cli("tessellate --body " + dir + "/body.obj --chamber " + dir + "/big.obj --out " + dir +
          "/bad.vtk");
  EXPECT_EQ(r.code, 2) << r.out;
  EXPECT_NE(r.out.find("big.obj"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("strictly inside"), std::string::npos) << r.out;
  // A size whose mesh cannot fit in memory (~1e9 tets here) is refused before meshing.
  r = Cli("tessellate --body " + dir + "/body.obj --chamber " + dir +
          "/chamber.obj --size 0.01 --out " + dir + "/fine.vtk");
  EXPECT_EQ(r.code, 2) << r.out;
  EXPECT_NE(r.out.find("--size 0.01: needs an estimated"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("use a larger --size"), std::string::npos) << r.out;
  EXPECT_FALSE(std::filesystem::exists(dir + "/fine.vtk"));
  // Bad sizes and output formats name the flag.
  r = Cli("tessellate --body " + dir + "/body.obj --chamber " + dir +
          "/chamber.obj --size -1 --out " + dir + "/m.vtk");
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.out.find("--size"), std::string::npos) << r.out;
  r = Cli("tessellate --body " + dir + "/body.obj --chamber " + dir + "/chamber.obj --out " + dir +
          "/m.xyz");
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.out.find("--out"), std::string::npos) << r.out;
}

}  // namespace

// ---- softkin ik ----------------------------------------------------------------------------

TEST(Cli, IkHelpDocumentsEveryOption) {
  const CliRun r = Cli("ik --help");
  ASSERT_EQ(r.code, 0) << r.out;
  for (const char* k : {"--robot", "--scene", "--target", "--trajectory", "--point", "--method",
                        "--jacobian", "--lambda", "--max-iterations", "--samples", "--cache",
                        "--out", "--resume", "nlopt-bobyqa", "fd-warm"})
    EXPECT_NE(r.out.find(k), std::string::npos) << k;
}

TEST(Cli, IkBadInputExitsWithCode2AndNamesTheOptionOrFileLine) {
  const std::string dir = TempDir("ik_bad");
  const std::string out = " --out " + dir + "/out.csv";
  const std::string base = "ik --robot cable_finger --res 5";
  struct Case {
    std::string args;
    std::vector<std::string> expect;
  };
  std::ofstream(dir + "/two_columns.txt") << "100 12.5 20\n100 12.5\n";
  std::ofstream(dir + "/nan.txt") << "# x y z\n100 12.5 20\n\n100 nan 20\n";
  std::ofstream(dir + "/word.txt") << "x y z\n100 12.5 20\n100 12.5 2O\n";
  const std::vector<Case> cases = {
      {"ik --robot no_such_robot --target 1,2,3" + out, {"known robots"}},
      {base + " --target 1,2,3 --point nose" + out, {"--point", "nose", "tip_top"}},
      {base + " --target 1,2,3 --method magic" + out,
       {"--method", "magic", "softls", "gauss-newton"}},
      {base + " --target 1,2,3 --jacobian exact" + out, {"--jacobian", "fd-warm"}},
      {base + " --target 1,2" + out, {"--target", "x,y,z"}},
      {base + " --target 1,abc,3" + out, {"--target", "expected"}},
      {base + " --target 1,2,3 --lambda -1" + out, {"--lambda"}},
      {base + " --target 1,2,3 --samples 1" + out, {"--samples"}},
      {base + out, {"--target", "--trajectory"}},
      {base + " --target 1,2,3 --trajectory " + dir + "/nan.txt" + out, {"excludes"}},
      {base + " --trajectory " + dir + "/two_columns.txt" + out, {"two_columns.txt:2", "3 values"}},
      {base + " --trajectory " + dir + "/nan.txt" + out, {"nan.txt:4", "finite"}},
      {base + " --trajectory " + dir + "/word.txt" + out, {"word.txt:3", "2O"}},
      {base + " --trajectory " + dir + "/missing.txt" + out, {"missing.txt"}},
      {base + " --target 1,2,3", {"--out"}},
  };
  for (const auto& c : cases) {
    const CliRun r = Cli(c.args);
    EXPECT_EQ(r.code, 2) << c.args << "\n" << r.out;
    for (const auto& e : c.expect)
      EXPECT_NE(r.out.find(e), std::string::npos) << c.args << "\n" << r.out;
  }
}

TEST(Cli, IkReachesAForwardSolvedTargetAndResumesATrajectory) {
  const std::string dir = TempDir("ik_run");
  // A reachable target: where the tip goes at a known actuation.
  // Loose forward solves (gradient ratio 1e-3) keep this test short; the tip moves by ~0.05 mm.
  CliRun r =
      Cli("fk --robot cable_finger --res 5 --actuation 0.9,0.85,0.95 --gradient-tolerance 1e-3 "
          "--json " +
          dir + "/fk.json");
  ASSERT_EQ(r.code, 0) << r.out;
  std::ifstream f(dir + "/fk.json");
  const auto tip = nlohmann::json::parse(f)["markers"]["tip"];
  std::ostringstream target;
  target << tip[0].get<double>() << "," << tip[1].get<double>() << "," << tip[2].get<double>();
  r = Cli("ik --robot cable_finger --res 5 --target " + target.str() +
          " --samples 2 --gradient-tolerance 1e-3 --method gauss-newton --out " + dir + "/one.csv");
  ASSERT_EQ(r.code, 0) << r.out;
  EXPECT_NE(r.out.find("[1/1]"), std::string::npos) << r.out;  // progress on stderr
  std::string text = ReadAll(dir + "/one.csv");
  ASSERT_EQ(CountLines(text), 2) << text;
  EXPECT_EQ(text.rfind("index,target_x,target_y,target_z,c0,c1,c2,reached_x", 0), 0u) << text;
  // error_mm is column 11 (after index, target x3, c0..c2, reached x3): within lambda = 0.2 mm.
  {
    std::stringstream row(text.substr(text.find('\n') + 1));
    std::string cell;
    for (int i = 0; i < 11; ++i) std::getline(row, cell, ',');
    EXPECT_LE(std::stod(cell), 0.2) << text;
  }

  // A three-waypoint path near that target; interrupt it after one row (plus half a row) and
  // resume.
  const double x = tip[0].get<double>(), y = tip[1].get<double>(), z = tip[2].get<double>();
  std::ofstream(dir + "/path.txt") << x << " " << y << " " << z << "\n"
                                   << x << " " << y << " " << z + 1 << "\n"
                                   << x - 1 << " " << y << " " << z + 1 << "\n";
  const std::string run =
      "ik --robot cable_finger --res 5 --trajectory " + dir +
      "/path.txt --samples 2 "
      "--gradient-tolerance 1e-3 --method gauss-newton --jacobian implicit --cache " +
      dir + "/samples.csv --out " + dir + "/path.csv";
  r = Cli(run);
  ASSERT_EQ(r.code, 0) << r.out;
  const std::string full = ReadAll(dir + "/path.csv");
  ASSERT_EQ(CountLines(full), 4) << full;
  EXPECT_TRUE(std::filesystem::exists(dir + "/samples.csv"));
  const size_t second_row = full.find('\n', full.find('\n') + 1) + 1;
  std::ofstream(dir + "/path.csv", std::ios::trunc) << full.substr(0, second_row) << "1,123.4";
  r = Cli(run + " --resume");
  ASSERT_EQ(r.code, 0) << r.out;
  EXPECT_NE(r.out.find("resuming"), std::string::npos) << r.out;
  const std::string resumed = ReadAll(dir + "/path.csv");
  ASSERT_EQ(CountLines(resumed), 4) << resumed;
  EXPECT_EQ(resumed.substr(0, second_row), full.substr(0, second_row));
  EXPECT_EQ(resumed.substr(second_row, 2), "1,") << resumed;
  // Nothing left to do.
  r = Cli(run + " --resume");
  ASSERT_EQ(r.code, 0) << r.out;
  EXPECT_NE(r.out.find("nothing to do"), std::string::npos) << r.out;
  // Resuming against another path is refused with the CSV line.
  std::ofstream(dir + "/other.txt") << x + 5 << " " << y << " " << z << "\n"
                                    << x << " " << y << " " << z << "\n";
  r = Cli("ik --robot cable_finger --res 5 --trajectory " + dir + "/other.txt --samples 2 --out " +
          dir + "/path.csv --resume");
  EXPECT_EQ(r.code, 2) << r.out;
  EXPECT_NE(r.out.find("path.csv:2"), std::string::npos) << r.out;
}

TEST(Cli, IkExperimentsRunTinyConfigsAndRejectBadPaths) {
  const std::string dir = TempDir("ik_exp");
  const std::string cfg = dir + "/tiny.json";
  // Two waypoints near the rest tip of the coarse finger, loose forward solves (fast).
  std::ofstream(cfg) << R"({"name": "tiny_traj", "experiment": "ik_trajectory", "seed": 2,
    "robot": "cable_finger", "res": 5, "solver": {"gradient_tolerance": 1e-3},
    "method": "gauss-newton", "samples_per_axis": 2,
    "paths": [{"name": "seg", "type": "polyline", "n": 2,
               "vertices": [[119.5, 12.5, 16.0], [119.0, 12.5, 18.0]], "thesis": {"total_time_s": 1}}]})";
  CliRun r = Cli("run " + cfg + " --no-plot --results " + dir);
  ASSERT_EQ(r.code, 0) << r.out;
  {
    std::ifstream f(dir + "/tiny_traj/summary.json");
    const auto j = nlohmann::json::parse(f);
    ASSERT_EQ(j["paths"].size(), 1u);
    const auto& p = j["paths"][0];
    EXPECT_EQ(p["waypoints"], 2);
    EXPECT_EQ(p["thesis"]["total_time_s"], 1);
    for (const char* k : {"mean_error_mm", "max_error_mm", "total_time_s", "max_jump",
                          "max_reached_step_mm", "fk_solves", "beyond_lambda"})
      EXPECT_TRUE(p.contains(k)) << k;
    EXPECT_EQ(j["samples"]["n"], 8);
    EXPECT_TRUE(std::filesystem::exists(dir + "/tiny_traj/path_seg.csv"));
    EXPECT_TRUE(std::filesystem::exists(dir + "/tiny_traj/samples.csv"));
  }
  // ik_methods journals each method x Jacobian row; a rerun reuses it.
  std::ofstream(cfg) << R"({"name": "tiny_methods", "experiment": "ik_methods", "seed": 2,
    "robot": "cable_finger", "res": 5, "solver": {"gradient_tolerance": 1e-3}, "samples_per_axis": 2,
    "methods": ["gauss-newton"], "jacobians": ["implicit"], "max_evaluations": 6,
    "path": {"name": "seg", "type": "polyline", "n": 2, "vertices": [[119.5, 12.5, 16.0], [119.0, 12.5, 18.0]]}})";
  for (int run = 0; run < 2; ++run) {
    r = Cli("run " + cfg + " --no-plot --results " + dir);
    ASSERT_EQ(r.code, 0) << r.out;
    std::ifstream f(dir + "/tiny_methods/summary.json");
    const auto j = nlohmann::json::parse(f);
    ASSERT_EQ(j["rows"].size(), 1u);
    EXPECT_EQ(j["rows"][0]["method"], "gauss-newton");
    EXPECT_EQ(j["rows"][0]["waypoints"], 2);
    EXPECT_EQ(j["resumed_rows"], run) << "run " << run;
  }
  // A path of an unknown type, a file path with a bad stride, a bad method: exit 2 with the key.
  std::ofstream(cfg) << R"({"name": "tiny_traj", "experiment": "ik_trajectory", "seed": 2,
    "robot": "cable_finger", "res": 5, "samples_per_axis": 2, "solver": {"gradient_tolerance": 1e-3},
    "paths": [{"name": "seg", "type": "spiral"}]})";
  r = Cli("run " + cfg + " --no-plot --results " + dir);
  EXPECT_EQ(r.code, 2) << r.out;
  EXPECT_NE(r.out.find("paths[0].type"), std::string::npos) << r.out;
  // A waypoint file that is not there is named with its key and where it was looked for.
  std::ofstream(cfg) << R"({"name": "tiny_traj", "experiment": "ik_trajectory", "seed": 2,
    "robot": "cable_finger", "res": 5, "samples_per_axis": 2, "solver": {"gradient_tolerance": 1e-3},
    "paths": [{"name": "seg", "type": "file", "file": "no/such/waypoints.txt"}]})";
  r = Cli("run " + cfg + " --no-plot --results " + dir);
  EXPECT_EQ(r.code, 2) << r.out;
  EXPECT_NE(r.out.find("paths[0].file: "), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("no/such/waypoints.txt: cannot open the waypoint file (a relative file is "
                       "read from the source tree"),
            std::string::npos)
      << r.out;
  std::ofstream(cfg) << R"({"name": "tiny_m", "experiment": "ik_methods", "seed": 2,
    "robot": "cable_finger", "res": 5, "methods": ["softls", "newton"], "path": {}})";
  r = Cli("run " + cfg + " --no-plot --results " + dir);
  EXPECT_EQ(r.code, 2) << r.out;
  EXPECT_NE(r.out.find("methods"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("newton"), std::string::npos) << r.out;
  std::ofstream(cfg) << R"({"name": "tiny_pp", "experiment": "ik_pick_and_place", "seed": 2,
    "robot": "multi_segment_gripper", "res": 6, "pick_design_actuation": [2, 2]})";
  r = Cli("run " + cfg + " --no-plot --results " + dir);
  EXPECT_EQ(r.code, 2) << r.out;
  EXPECT_NE(r.out.find("place_offset"), std::string::npos) << r.out;
}

namespace {

// train takes the networks' bounds and provenance from the dataset's sidecar: without one, or with
// one that does not describe the CSV (another dataset's points, bounds that exclude its samples),
// it refuses before training and names the sidecar's key.
TEST(Cli, TrainRefusesAMissingOrForeignSidecar) {
  const std::string dir = TempDir("train_sidecar");
  CliRun r =
      Cli("dataset --robot three_chamber --res 3 --grid 3 --gradient-tolerance 1e-3 "
          "--quiet --out " +
          dir + "/d.csv");
  ASSERT_EQ(r.code, 0) << r.out;
  const std::string csv = ReadAll(dir + "/d.csv");
  const auto side = nlohmann::json::parse(ReadAll(dir + "/d.csv.json"));
  auto train = [&](const std::string& name) {
    return Cli("train --dataset " + dir + "/" + name + " --out " + dir + "/nets_" + name +
               " --hidden 4 --epochs 2 --what fk --threads 1 --quiet");
  };
  std::ofstream(dir + "/none.csv") << csv;
  r = train("none.csv");
  EXPECT_EQ(r.code, 2) << r.out;
  EXPECT_NE(r.out.find(dir + "/none.csv.json: not found"), std::string::npos) << r.out;
  std::ofstream(dir + "/points.csv") << csv;
  nlohmann::json other = side;
  other["config"]["points"] = {"fingertip"};
  std::ofstream(dir + "/points.csv.json") << other.dump(2);
  r = train("points.csv");
  EXPECT_EQ(r.code, 2) << r.out;
  EXPECT_NE(r.out.find("points.csv.json: config.points: expected the CSV's points"),
            std::string::npos)
      << r.out;
  std::ofstream(dir + "/bounds.csv") << csv;
  nlohmann::json narrow = side;
  narrow["config"]["actuator_bounds"][1] = {1.0, 1.2};
  std::ofstream(dir + "/bounds.csv.json") << narrow.dump(2);
  r = train("bounds.csv");
  EXPECT_EQ(r.code, 2) << r.out;
  EXPECT_NE(r.out.find("bounds.csv.json: config.actuator_bounds[1]: [1, 1.2] does not hold"),
            std::string::npos)
      << r.out;
  EXPECT_FALSE(std::filesystem::exists(dir + "/nets_bounds.csv/nets.json"));
  r = train("d.csv");  // its own sidecar
  EXPECT_EQ(r.code, 0) << r.out;
  // A network whose Levenberg-Marquardt matrices cannot fit is refused with the option and the
  // estimate, before any network of the job is trained.
  r = Cli("train --dataset " + dir + "/d.csv --out " + dir +
          "/wide --hidden 10000,10000 --what fk --quiet");
  EXPECT_EQ(r.code, 2) << r.out;
  EXPECT_NE(r.out.find("N_fk (--hidden): network 3-10000-10000-3: needs an estimated"),
            std::string::npos)
      << r.out;
  r = Cli("train --dataset " + dir + "/d.csv --out " + dir +
          "/wide_ik --hidden 4 --hidden-ik 10000,10000 --what fk,ik --quiet");
  EXPECT_EQ(r.code, 2) << r.out;
  EXPECT_NE(r.out.find("N_ik (--hidden-ik)"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("use fewer hidden neurons"), std::string::npos) << r.out;
  EXPECT_FALSE(std::filesystem::exists(dir + "/wide_ik/fk.fnn"));
}

TEST(Cli, TrainAndLearnedIkFromADataset) {
  const std::string dir = TempDir("learn");
  // 27 samples of the coarse three_chamber with implicit Jacobians, loose forward solves.
  CliRun r =
      Cli("dataset --robot three_chamber --res 3 --grid 3 --jacobian implicit --gradient-tolerance "
          "1e-3 --quiet --out " +
          dir + "/d.csv");
  ASSERT_EQ(r.code, 0) << r.out;
  r = Cli("train --dataset " + dir + "/d.csv --out " + dir +
          "/nets --hidden 6 --hidden-jac 6 --hidden-ik 6 --epochs 40 --threads 1 --quiet");
  ASSERT_EQ(r.code, 0) << r.out;
  EXPECT_NE(r.out.find("% of the"), std::string::npos)
      << r.out;  // N_fk error as % of the workspace
  for (const char* f : {"nets.json", "fk.fnn", "jac.fnn", "ik.fnn"})
    EXPECT_TRUE(std::filesystem::exists(dir + "/nets/" + f)) << f;
  std::ifstream nj(dir + "/nets/nets.json");
  const auto info = nlohmann::json::parse(nj);
  EXPECT_EQ(info["format"], "softkin-nets");
  EXPECT_EQ(info["info"]["dataset"]["samples"], 27);
  EXPECT_EQ(info["rest"], nlohmann::json::array({1.0, 1.0, 1.0}));

  // One target (the rest tip region), learned and direct.
  for (const char* method : {"learned", "direct"}) {
    r = Cli(std::string("ik --nets ") + dir + "/nets --method " + method +
            " --target 0,136,0 --quiet --out " + dir + "/ik.csv");
    ASSERT_EQ(r.code, 0) << method << "\n" << r.out;
    const std::string text = ReadAll(dir + "/ik.csv");
    EXPECT_EQ(CountLines(text), 2) << text;
    EXPECT_EQ(text.find("nan"), std::string::npos) << text;
  }
  // A target 1 m away: the direct answer is far from it, and every output says it missed
  // (the CSV's converged and termination columns, and the count on stderr).
  r = Cli("ik --nets " + dir + "/nets --method direct --target 0,136,1000 --out " + dir +
          "/far.csv");
  ASSERT_EQ(r.code, 0) << r.out;
  EXPECT_NE(r.out.find("0 of 1 waypoint(s) within lambda"), std::string::npos) << r.out;
  {
    std::istringstream csv(ReadAll(dir + "/far.csv"));
    std::string header, row, cell;
    std::getline(csv, header);
    std::getline(csv, row);
    std::vector<std::string> names, values;
    for (std::istringstream h(header); std::getline(h, cell, ',');) names.push_back(cell);
    for (std::istringstream v(row); std::getline(v, cell, ',');) values.push_back(cell);
    ASSERT_EQ(names.size(), values.size()) << header << "\n" << row;
    EXPECT_EQ(std::count(names.begin(), names.end(), "converged") +
                  std::count(names.begin(), names.end(), "termination"),
              2)
        << header;
    for (size_t k = 0; k < names.size(); ++k) {
      if (names[k] == "converged") {
        EXPECT_EQ(values[k], "0") << row;
      }
      if (names[k] == "termination") {
        EXPECT_EQ(values[k], "no-progress") << row;
      }
    }
  }
  // Interactive: rows on stdout for good lines, a message naming the line for a bad one, 'quit'
  // stops.
  std::ofstream(dir + "/in.txt") << "2 140 -3\nnot a point\n-4,138,2\nquit\n5 5 5\n";
  r = Cli("ik --nets " + dir + "/nets --method learned --interactive --quiet < " + dir + "/in.txt");
  ASSERT_EQ(r.code, 0) << r.out;
  EXPECT_NE(r.out.find("stdin:2: expected a target"), std::string::npos) << r.out;
  EXPECT_EQ(r.out.find("\n2,"), std::string::npos) << r.out;  // nothing after 'quit'
  EXPECT_NE(r.out.find("\n0,2,140,-3,"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("\n1,-4,138,2,"), std::string::npos) << r.out;

  // Bad input: exit 2 with the option named.
  r = Cli("ik --nets " + dir + "/missing --method learned --target 0,136,0 --out " + dir +
          "/x.csv");
  EXPECT_EQ(r.code, 2) << r.out;
  EXPECT_NE(r.out.find("--nets"), std::string::npos) << r.out;
  r = Cli("ik --nets " + dir + "/nets --method learned --s2r --target 0,136,0 --out " + dir +
          "/x.csv");
  EXPECT_EQ(r.code, 2) << r.out;
  EXPECT_NE(r.out.find("no s2r network"), std::string::npos) << r.out;
  r = Cli("ik --method learned --target 0,136,0 --out " + dir + "/x.csv");
  EXPECT_EQ(r.code, 2) << r.out;
  r = Cli("train --dataset " + dir + "/d.csv --out " + dir + "/n2 --what fk,xyz");
  EXPECT_EQ(r.code, 2) << r.out;
  EXPECT_NE(r.out.find("--what"), std::string::npos) << r.out;
  r = Cli("train --s2r " + dir + "/d.csv --out " + dir + "/none");
  EXPECT_EQ(r.code, 2) << r.out;
  EXPECT_NE(r.out.find("nets.json"), std::string::npos) << r.out;
}

TEST(Cli, ArchitectureSweepResumesFinishedNetworks) {
  const std::string dir = TempDir("arch");
  const std::string cfg = dir + "/arch.json";
  std::ofstream(cfg) << R"({"name": "tiny_arch", "experiment": "learn_architecture", "seed": 3,
    "datasets": [{"robot": "three_chamber", "res": 3, "grid": 3, "gradient_tolerance": 1e-3}],
    "layers": [1], "neurons": [3, 5], "jacobian_network": false, "epochs": 15, "threads": 1})";
  CliRun r = Cli("run " + cfg + " --no-plot --results " + dir);
  ASSERT_EQ(r.code, 0) << r.out;
  auto summary = [&] {
    std::ifstream f(dir + "/tiny_arch/summary.json");
    return nlohmann::json::parse(f);
  };
  const auto first = summary();
  ASSERT_EQ(first["rows"].size(), 2u);
  EXPECT_EQ(first["resumed_rows"], 0);
  // A rerun trains nothing and reports the same rows.
  r = Cli("run " + cfg + " --no-plot --results " + dir);
  ASSERT_EQ(r.code, 0) << r.out;
  const auto second = summary();
  EXPECT_EQ(second["resumed_rows"], 2);
  EXPECT_EQ(second["rows"], first["rows"]);
  // An interrupted journal (the last record cut mid-write) and a changed setting: the cut record
  // and the rows of other settings are trained again, the intact record is reused.
  std::string journal = ReadAll(dir + "/tiny_arch/architecture.jsonl");
  ASSERT_EQ(CountLines(journal), 2) << journal;
  const size_t second_line = journal.find('\n') + 1;
  std::ofstream(dir + "/tiny_arch/architecture.jsonl") << journal.substr(0, second_line + 20);
  r = Cli("run " + cfg + " --no-plot --results " + dir);
  ASSERT_EQ(r.code, 0) << r.out;
  EXPECT_NE(r.out.find("architecture.jsonl:2: not a complete JSON record"), std::string::npos)
      << r.out;
  const auto third = summary();
  EXPECT_EQ(third["resumed_rows"], 1);
  EXPECT_EQ(third["rows"][0], first["rows"][0]);
  EXPECT_EQ(third["rows"][1]["b"], 5);
  std::ofstream(cfg) << R"({"name": "tiny_arch", "experiment": "learn_architecture", "seed": 3,
    "datasets": [{"robot": "three_chamber", "res": 3, "grid": 3, "gradient_tolerance": 1e-3}],
    "layers": [1], "neurons": [3, 5], "jacobian_network": false, "epochs": 16, "threads": 1})";
  r = Cli("run " + cfg + " --no-plot --results " + dir);
  ASSERT_EQ(r.code, 0) << r.out;
  EXPECT_EQ(summary()["resumed_rows"], 0);
}

}  // namespace
