// Experiment configs (experiments/config.hpp): errors name the file and the key, with the value
// found there, also for nested keys.
#include "softkin/experiments/config.hpp"
#include "softkin/experiments/runner.hpp"

#include <gtest/gtest.h>

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <string>

namespace softkin {
namespace {

std::string WriteTemp(const std::string& name, const std::string& text) {
  const std::string path = ::testing::TempDir() + name;
  std::ofstream(path) << text;
  return path;
}

TEST(Config, FailNamesNestedKeysWithTheValueFoundThere) {
  const std::string path = WriteTemp("softkin_config_nested.json",
                                     R"({"name": "x", "experiment": "collision_costs", "seed": 1,
          "robots": [{"robot": "membrane", "robot_params": {"a": "b"}}]})");
  const Config cfg = Config::Load(path, false);
  auto message = [&](const std::string& key) {
    try {
      cfg.Fail(key, "a number");
    } catch (const std::invalid_argument& e) {
      return std::string(e.what());
    }
    return std::string("no exception");
  };
  EXPECT_EQ(message("robots[0].robot_params.a"),
            path + ": robots[0].robot_params.a: expected a number, got \"b\"");
  EXPECT_EQ(message("robots[0].robot"),
            path + ": robots[0].robot: expected a number, got \"membrane\"");
  // Keys that lead nowhere are reported as missing.
  EXPECT_EQ(message("robots[3].robot"), path + ": robots[3].robot: expected a number (missing)");
  EXPECT_EQ(message("robots[0].res"), path + ": robots[0].res: expected a number (missing)");
  EXPECT_EQ(message("seed.x"), path + ": seed.x: expected a number (missing)");
  EXPECT_EQ(message("robots[x]"), path + ": robots[x]: expected a number (missing)");
  std::remove(path.c_str());
}

// A quick override must have the kind of the value it replaces, in either mode: a quick run must
// not pass with a value a full run would reject as the wrong kind, or the other way round.
TEST(Config, QuickOverridesKeepTheKindOfTheirKey) {
  auto message = [](const std::string& text, bool quick) {
    const std::string path = WriteTemp("softkin_config_quick.json", text);
    try {
      Config::Load(path, quick);
    } catch (const std::invalid_argument& e) {
      std::remove(path.c_str());
      return std::string(e.what());
    }
    std::remove(path.c_str());
    return std::string();
  };
  const std::string head = R"({"name": "q", "experiment": "resolution_sweep", "seed": 1, )";
  for (bool quick : {false, true}) {
    EXPECT_EQ(message(head + R"("res": 12, "quick": {"res": 6}})", quick), "");
    EXPECT_EQ(message(head + R"("steps": [1, 2], "quick": {"steps": [3]}})", quick), "");
    const std::string m1 = message(head + R"("res": 12, "quick": {"res": "6"}})", quick);
    EXPECT_NE(m1.find("quick.res: expected a number, as the config's 'res' (12), got \"6\""),
              std::string::npos)
        << m1;
    const std::string m2 =
        message(head + R"("resolutions": [4, 5], "quick": {"resolutions": [3, "4"]}})", quick);
    EXPECT_NE(m2.find("quick.resolutions: expected an array of numbers"), std::string::npos) << m2;
    const std::string m3 =
        message(head + R"("solver": {"solver": "lg"}, "quick": {"solver": "lg"}})", quick);
    EXPECT_NE(m3.find("quick.solver: expected an object"), std::string::npos) << m3;
  }
}

// Every config shipped in experiments/ loads (full and quick), is named after its file, names an
// experiment type the runner knows, and has the plot script that regenerates its figure.
TEST(Config, EveryShippedConfigLoadsAndHasAPlotScript) {
  namespace fs = std::filesystem;
  const fs::path root(SOFTKIN_SOURCE_DIR);
  int checked = 0;
  for (const auto& entry : fs::directory_iterator(root / "experiments" / "configs")) {
    if (entry.path().extension() != ".json") continue;
    SCOPED_TRACE(entry.path().string());
    for (bool quick : {false, true}) {
      const Config cfg = Config::Load(entry.path().string(), quick);
      EXPECT_EQ(cfg.name(), entry.path().stem().string());
      EXPECT_NE(FindExperiment(cfg.type()), nullptr) << cfg.type();
    }
    EXPECT_TRUE(fs::exists(root / "paper_figs" / (entry.path().stem().string() + ".py")));
    ++checked;
  }
  EXPECT_GE(checked, 30);
}

// A --quick run also checks the full settings its overrides hide, before any work: a bad full
// value fails the quick (CI) run at once, not hours into the full one. The quick run itself still
// runs when both are valid.
TEST(Config, QuickRunsCheckTheFullSettingsToo) {
  const std::string root = ::testing::TempDir() + "/softkin_quick_full";
  std::filesystem::remove_all(root);
  auto run = [&](const std::string& steps) -> std::string {
    const std::string path = WriteTemp("softkin_config_quick_full.json",
                                       R"({"name": "quick_full", "experiment": "pneumatic_bending",
        "seed": 1, "robot": "three_chamber", "res": 3, "actuators": ["c1"], "steps": )" +
                                           steps + R"(, "quick": {"steps": 2}})");
    RunOptions o;
    o.quick = true;
    o.plot = false;
    o.verbose = false;
    o.results_root = root;
    try {
      RunExperiment(path, o);
    } catch (const std::invalid_argument& e) {
      return e.what();
    }
    return "";
  };
  const std::string bad = run("0");
  EXPECT_NE(bad.find("--quick: the full settings (without the quick overrides) are invalid"),
            std::string::npos)
      << bad;
  EXPECT_NE(bad.find("steps: expected an integer >= 1"), std::string::npos) << bad;
  EXPECT_FALSE(std::filesystem::exists(root + "/quick_full/summary.json"));
  EXPECT_EQ(run("40"), "");
  EXPECT_TRUE(std::filesystem::exists(root + "/quick_full/summary.json"));
  std::filesystem::remove_all(root);
}

}  // namespace
}  // namespace softkin
