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

}  // namespace
}  // namespace softkin
