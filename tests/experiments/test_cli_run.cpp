// Tests of `softkin run`: experiment configs are checked before any work, and tiny runs write
// the summaries, CSVs and headline figures their experiments promise.
#include "softkin/solver/baselines/ccx_run.hpp"
#include "tests/experiments/cli_test_util.hpp"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

using namespace softkin::cli_test;  // NOLINT: the helpers of every test here

TEST(Cli, RunWritesSummaryWithConfigCommitAndMachine) {
  const std::string dir = TempDir("run");
  const std::string cfg = dir + "/tiny.json";
  // three_chamber has no tip_top/tip_bottom: the bending experiment must say so.
  CliRun r = RunConfig(cfg, R"({"name": "tiny_bend", "experiment": "pneumatic_bending", "seed": 3,
    "robot": "three_chamber", "res": 3, "actuator": "c1", "steps": 3,
    "milestones_deg": [5], "end_value": 1.6})",
                       dir);
  EXPECT_NE(r.code, 0);
  EXPECT_NE(r.out.find("tip_top"), std::string::npos) << r.out;

  // actuation_paths (Fig. 2.12): a group naming an unknown actuator is rejected with the key.
  EXPECT_TRUE(RefusedWith(
      RunConfig(cfg, R"({"name": "tiny_paths", "experiment": "actuation_paths", "seed": 3,
    "robot": "three_chamber", "res": 3, "paths": ["c1", "c1+c9"], "steps": 2})",
                dir),
      {"paths", "c1+c9"}));
  r = RunConfig(cfg, R"({"name": "tiny_paths", "experiment": "actuation_paths", "seed": 3,
    "robot": "three_chamber", "res": 3, "paths": ["c1", "c1+c2+c3"], "steps": 2, "end_value": 1.5})",
                dir);
  ASSERT_EQ(r.code, 0) << r.out;
  {
    std::ifstream pf(dir + "/tiny_paths/summary.json");
    const auto pj = nlohmann::json::parse(pf);
    ASSERT_EQ(pj["paths"].size(), 2u);
    EXPECT_EQ(pj["non_converged_steps"], 0);
    // Equal inflation of all three chambers keeps the tip on the axis (x = z = 0).
    const auto& tip = pj["paths"][1]["tips"][1];
    EXPECT_NEAR(tip[0].get<double>(), 0.0, 1e-6);
    EXPECT_NEAR(tip[2].get<double>(), 0.0, 1e-6);
  }

  r = RunConfig(cfg, R"({"name": "tiny_aa", "experiment": "aa_ablation", "seed": 3,
    "robots": ["three_chamber"], "resolutions": [3], "levels": [0.5, 1.0], "solvers": ["newton"]})",
                dir);
  ASSERT_EQ(r.code, 0) << r.out;
  std::ifstream f(dir + "/tiny_aa/summary.json");
  const auto j = nlohmann::json::parse(f);
  EXPECT_EQ(j["seed"], 3);
  // The whole other solver runs beside the Anderson variants, compared by time.
  const auto& full = j["cases"][1];
  EXPECT_EQ(full["newton"]["status"], "converged");
  EXPECT_GT(full["newton"]["linear_iterations"].get<int>(), 0);
  EXPECT_FALSE(full["newton"].contains("aa_accepted"));
  EXPECT_NEAR(full["newton"]["energy"].get<double>(),
              full["lg-aa m=6 hybrid"]["energy"].get<double>(),
              1e-4 * full["lg-aa m=6 hybrid"]["energy"].get<double>());
  EXPECT_GT(j["time_ratio_full_actuation_by_solver"]["newton"]["min"].get<double>(), 0.0);
  EXPECT_TRUE(j.contains("git_commit"));
  EXPECT_TRUE(j["machine"].contains("hardware_threads"));
  EXPECT_EQ(j["config"]["robots"][0], "three_chamber");
  EXPECT_TRUE(std::filesystem::exists(dir + "/tiny_aa/aa_ablation.csv"));

  // Rerunning the copy a run wrote (RESULTS/<name>/config.json) into the same results would
  // write over it (with the quick overrides resolved): refused, the file left as it was.
  const std::string copy = dir + "/tiny_aa/config.json", copy_text = ReadAll(copy);
  EXPECT_TRUE(RefusedWith(Cli("run " + copy + " --no-plot --results " + dir),
                          {"is the same file as the input config"}));
  EXPECT_EQ(ReadAll(copy), copy_text);

  EXPECT_TRUE(RefusedWith(
      RunConfig(cfg, R"({"name": "tiny_aa", "experiment": "aa_ablation", "seed": 3, "robts": []})",
                dir),
      {"robts"}));
  for (const std::string bad : {R"(["lg-aa"])", R"(["newtn"])"}) {
    const std::string text =
        R"({"name": "tiny_aa", "experiment": "aa_ablation", "seed": 3, "solvers": )" + bad + "}";
    EXPECT_TRUE(RefusedWith(RunConfig(cfg, text, dir), {"solvers"})) << bad;
  }
  EXPECT_TRUE(
      RefusedWith(RunConfig(cfg, R"({"name": "x", "experiment": "aa_ablation"})", dir), {"seed"}));
}

// Fig. 2.11 and Table 2.2 carry the pressure-driven FEM (calculix_pressure.hpp) beside SoftKin:
// its keys are checked before any work, and a tiny ramp is measured as a bending trajectory that
// inflates the cavity and bends the finger the way SoftKin does.
TEST(Cli, BendingAndSolverComparisonRunThePressureFem) {
  const std::string dir = TempDir("pressure_fem");
  const std::string cfg = dir + "/bend.json";
  const std::string bend_base =
      R"("name": "tiny_fem", "experiment": "pneumatic_bending", "seed": 1,
         "robot": "pneumatic_finger", "res": 5, "steps": 2, "end_value": 1.4)";
  EXPECT_TRUE(RefusedWith(
      RunConfig(cfg, "{" + bend_base + R"(, "fem_laws": ["rubber"], "fem_pressure_mpa": 0.02})",
                dir),
      {"fem_laws[0]", "neo-hooke"}));
  EXPECT_TRUE(RefusedWith(RunConfig(cfg, "{" + bend_base + R"(, "fem_laws": ["linear"]})", dir),
                          {"fem_pressure_mpa"}));
  EXPECT_TRUE(RefusedWith(RunConfig(cfg, "{" + bend_base + R"(, "fem_laws": ["linear"],
    "fem_pressure_mpa": 0.02, "fem_element": "C3D8"})",
                                    dir),
                          {"fem_element"}));
  if (softkin::FindCcx().empty()) GTEST_SKIP() << softkin::CcxMissingMessage();

  CliRun r = RunConfig(cfg, "{" + bend_base + R"(, "fem_laws": ["neo-hooke"],
    "fem_pressure_mpa": 0.03, "fem_element": "C3D4", "max_increment": 0.5})",
                       dir);
  ASSERT_EQ(r.code, 0) << r.out;
  {
    std::ifstream f(dir + "/tiny_fem/summary.json");
    const auto j = nlohmann::json::parse(f);
    const auto& fem = j["fem"]["neo-hooke"];
    ASSERT_GE(fem["increments"].get<int>(), 1) << fem.dump();
    EXPECT_GT(fem["end_cavity_ratio"].get<double>(), 1.0);
    // Inflating the chamber bends the finger the same way as SoftKin's sweep (positive angle).
    EXPECT_GT(fem["max_bend_deg"].get<double>(), 0.1);
    EXPECT_GT(j["max_bend_deg"].get<double>(), 0.1);
    EXPECT_EQ(j["fem"]["element"], "C3D4");
    std::ifstream csv(dir + "/tiny_fem/fem_trajectory.csv");
    std::string header, row;
    std::getline(csv, header);
    EXPECT_EQ(header.rfind("law,increment,load,pressure_mpa,cavity_ratio,bend_deg", 0), 0u);
    int rows = 0;
    while (std::getline(csv, row)) rows += !row.empty();
    EXPECT_EQ(rows, fem["increments"].get<int>() + 1);  // the rest state, then each increment
  }

  r = RunConfig(cfg, R"({"name": "tiny_table", "experiment": "solver_comparison", "seed": 1,
    "robot": "pneumatic_finger", "res": 5, "steps": 2, "end_value": 1.4, "time_limit_s": 60,
    "methods": ["lg-aa", "calculix-pressure-nonlinear"], "fem_pressure_mpa": 0.03,
    "fem_element": "C3D4", "max_increment": 0.5})",
                dir);
  ASSERT_EQ(r.code, 0) << r.out;
  std::ifstream f(dir + "/tiny_table/summary.json");
  const auto j = nlohmann::json::parse(f);
  const auto& row = j["methods"]["calculix_pressure_nonlinear"];
  EXPECT_TRUE(row["status"] == "reached_end" || row["status"] == "stopped") << row.dump();
  EXPECT_GE(row["iterations"].get<int>(), 1);
  EXPECT_GT(row["end_cavity_ratio"].get<double>(), 1.0);
  EXPECT_TRUE(row["energy"].is_null());  // the FEM's chambers are hollow: no Eq. 2.10 energy
  EXPECT_TRUE(j.contains("speedup_vs_calculix_pressure_nonlinear"));
}

// Table 2.2's headline against Ceres / Ipopt holds when lg-aa's last steps end with inverted
// elements (the full-size finger's do): those steps met the tolerance and count as completed, so
// the optimiser that ran out of time in step 1 still gives a lower bound (it was silently null).
TEST(Cli, SolverComparisonBoundsTheOptimisersWhenLgAaEndsInverted) {
  const std::string dir = TempDir("table_inverted");
  const std::string cfg = dir + "/table.json";
  const CliRun r =
      RunConfig(cfg, R"({"name": "tiny_inverted", "experiment": "solver_comparison", "seed": 1,
    "robot": "pneumatic_finger", "res": 6, "steps": 2, "end_value": 10, "time_limit_s": 8,
    "methods": ["lg-aa", "ceres"]})",
                dir);
  ASSERT_EQ(r.code, 0) << r.out;
  std::ifstream f(dir + "/tiny_inverted/summary.json");
  const auto j = nlohmann::json::parse(f);
  const auto& aa = j["methods"]["lg_aa"];
  ASSERT_EQ(aa["status"], "inverted") << aa.dump();  // the case this test is about
  EXPECT_EQ(aa["steps_done"], 2);
  const auto& ceres = j["methods"]["ceres"];
  ASSERT_EQ(ceres["status"], "time_limit") << ceres.dump();
  ASSERT_TRUE(j["speedup_vs_best_nlp"].is_number()) << j.dump();
  EXPECT_EQ(j["speedup_vs_best_nlp_method"], "ceres");
  EXPECT_TRUE(j["speedup_vs_best_nlp_lower_bound"].get<bool>());
  EXPECT_GT(j["speedup_vs_best_nlp"].get<double>(), 1.0);
  EXPECT_FALSE(j.contains("speedup_vs_best_nlp_reason"));
}

// Table 3.1's cost experiment checks every robot's keys before it runs the first, including the
// progressive remeshing object of a robot driven as Algorithm 2 does.
TEST(Cli, CollisionCostsRejectsABadRemeshKeyBeforeRunningAny) {
  const std::string dir = TempDir("collision_costs_bad_remesh");
  const std::string cfg = dir + "/bad.json";
  for (const auto& [remesh, message] : std::vector<std::pair<std::string, std::string>>{
           {R"({"alpha_max": "four"})", "robots[1].remesh.alpha_max: expected a finite number"},
           {R"({"alpha": 4})", "robots[1].remesh.alpha: expected one of alpha_max, d_max, method"},
           {R"({"method": "all"})", "robots[1].remesh.method: expected auto, chamber or whole"},
           {R"({"chamber_rest": "deformed"})",
            "robots[1].remesh.chamber_rest: expected remeshed or original"},
           {R"({"d_max": 0.5})", "robots[1].remesh.d_max: expected"},
           {R"([4])", "robots[1].remesh: expected an object"}}) {
    SCOPED_TRACE(remesh);
    const CliRun r = RunConfig(cfg,
                               R"({"name": "bad_costs", "experiment": "collision_costs", "seed": 1,
      "robots": [{"robot": "selfcollision_finger", "res": 5, "steps": 1, "actuation": {"chamber": 1.5}},
                 {"robot": "twisting_robot", "res": 1, "steps": 2, "actuation": {"chamber": 3.0},
                  "remesh": )" + remesh +
                                   "}]}",
                               dir);
    EXPECT_TRUE(RefusedWith(r, {cfg + ": " + message}));
    EXPECT_EQ(r.out.find("[selfcollision_finger 1/1]"), std::string::npos)
        << r.out;  // robot 0 never ran
  }
  // A robot's own collision options are checked up front too.
  const CliRun r =
      RunConfig(cfg, R"({"name": "bad_costs", "experiment": "collision_costs", "seed": 1,
    "robots": [{"robot": "selfcollision_finger", "res": 5, "steps": 1, "actuation": {"chamber": 1.5}},
               {"robot": "membrane", "res": 10, "steps": 1, "actuation": {"c1": 1.5},
                "collision": {"stiffness": "soft"}}]})",
                dir);
  EXPECT_TRUE(RefusedWith(
      r, {cfg + ": robots[1].collision.stiffness: expected a number > 0, got \"soft\""}));
  EXPECT_EQ(r.out.find("[selfcollision_finger 1/1]"), std::string::npos) << r.out;
}

// A collision sweep reads every variant before it runs the first: a bad key in the last one
// fails at once, naming the file and the key, and no variant's output is written.
TEST(Cli, CollisionSweepRejectsABadVariantBeforeRunningAny) {
  const std::string dir = TempDir("collision_bad_variant");
  const std::string cfg = dir + "/bad.json";
  const CliRun r =
      RunConfig(cfg, R"({"name": "bad_sweep", "experiment": "collision_sweep", "seed": 1,
    "robot": "selfcollision_finger", "res": 5, "steps": 1, "actuation": {"chamber": 1.5},
    "variants": [{"name": "ok", "collision": {"self": true}},
                 {"name": "bad", "collision": {"self": true, "self_spring": "glue"}}]})",
                dir);
  EXPECT_TRUE(RefusedWith(
      r,
      {cfg + ": variants[1].collision.self_spring: expected one of: target, pair, got \"glue\""}));
  EXPECT_EQ(r.out.find("[ok 1/1]"), std::string::npos) << r.out;  // variant 0 never ran
  EXPECT_FALSE(std::filesystem::exists(dir + "/bad_sweep/steps.csv"));
}

// fidelity_fem: a case may run the FEM with its own element and increment (the thesis mesh is
// out of reach of C3D10) and may be left out of the comparison with the fitted parameters; the
// keys are checked before any FEM runs.
TEST(Cli, FidelityCasesTakeTheirOwnFemElementAndMayStayUncalibrated) {
  const std::string dir = TempDir("fidelity_cases");
  const std::string cfg = dir + "/fid.json";
  const std::string head = R"({"name": "tiny_fid", "experiment": "fidelity_fem", "seed": 1,
    "fem_element": "C3D4", "max_increment": 0.25, "fractions": [1.0], "calibrate_on": "a",)";
  EXPECT_TRUE(RefusedWith(RunConfig(cfg, head + R"( "cases": [
    {"label": "a", "robot": "three_chamber", "res": 3, "pressure": [0.01, 0, 0]},
    {"label": "b", "robot": "three_chamber", "res": 3, "pressure": [0.01, 0, 0],
     "fem_element": "C3D8"}]})",
                                    dir),
                          {cfg + ": cases[1].fem_element: expected C3D10 or C3D4"}));
  EXPECT_TRUE(RefusedWith(RunConfig(cfg, head + R"( "cases": [
    {"label": "a", "robot": "three_chamber", "res": 3, "pressure": [0.01, 0, 0],
     "calibrated": false}]})",
                                    dir),
                          {"cases[0].calibrated: expected true (or absent) for the case that "
                           "calibrate_on fits"}));
  EXPECT_FALSE(std::filesystem::exists(dir + "/tiny_fid/summary.json"));
  if (softkin::FindCcx().empty()) GTEST_SKIP() << softkin::CcxMissingMessage();

  CliRun r = RunConfig(cfg, head + R"( "cases": [
    {"label": "a", "robot": "three_chamber", "res": 3, "pressure": [0.01, 0, 0]},
    {"label": "b", "robot": "three_chamber", "res": 3, "pressure": [0.01, 0, 0],
     "fem_element": "C3D10", "max_increment": 1.0, "calibrated": false}]})",
                       dir);
  ASSERT_EQ(r.code, 0) << r.out;
  std::ifstream f(dir + "/tiny_fid/summary.json");
  const auto j = nlohmann::json::parse(f);
  const auto& a = j["cases"][0];
  const auto& b = j["cases"][1];
  EXPECT_EQ(a["fem_element"], "C3D4");
  EXPECT_EQ(b["fem_element"], "C3D10");
  // The same mesh as quadratic tets: every edge gains a midpoint node.
  EXPECT_GT(b["fem_nodes"].get<int>(), 2 * a["fem_nodes"].get<int>()) << b.dump();
  // The whole ramp in one increment (the config's a quarter of it).
  EXPECT_EQ(b["fem_increments"].get<int>(), 1) << b.dump();
  EXPECT_GT(a["fem_increments"].get<int>(), 1) << a.dump();
  EXPECT_EQ(a["role"], "calibration");
  EXPECT_EQ(b["role"], "default parameters only");
  EXPECT_TRUE(a.contains("calibrated") && a.contains("default")) << a.dump();
  EXPECT_TRUE(b.contains("default")) << b.dump();
  EXPECT_FALSE(b.contains("calibrated")) << b.dump();
}

// A solver scaling study reads every case before it solves: a bad solver name in the last case
// fails at once with the key. A tiny valid one writes one converged row per (res, solver) and the
// growth of the iteration count per solver.
TEST(Cli, SolverScalingChecksEveryCaseAndReportsTheGrowth) {
  const std::string dir = TempDir("solver_scaling");
  const std::string bad = dir + "/bad.json";
  CliRun r = RunConfig(bad, R"({"name": "bad_scaling", "experiment": "solver_scaling", "seed": 1,
    "cases": [{"robot": "three_chamber", "resolutions": [3], "actuation": [1.2, 1, 1],
               "solvers": ["newton"]},
              {"robot": "three_chamber", "resolutions": [3], "actuation": [1.2, 1, 1],
               "solvers": ["newtonn"]}]})",
                       dir);
  EXPECT_TRUE(RefusedWith(r, {bad + ": cases[1].solvers: expected FK solver names"}));
  EXPECT_EQ(r.out.find("res 3 ("), std::string::npos) << r.out;  // nothing was solved
  const std::string good = dir + "/good.json";
  r = RunConfig(good, R"({"name": "tiny_scaling", "experiment": "solver_scaling", "seed": 1,
    "cases": [{"robot": "three_chamber", "resolutions": [3, 4], "actuation": [1.2, 1, 1],
               "solvers": ["newton", "lg-aa"]}]})",
                dir);
  ASSERT_EQ(r.code, 0) << r.out;
  const std::string csv = ReadAll(dir + "/tiny_scaling/scaling.csv");
  EXPECT_EQ(CountLines(csv), 5) << csv;  // header + 2 res x 2 solvers
  const auto j = nlohmann::json::parse(ReadAll(dir + "/tiny_scaling/summary.json"));
  for (const char* solver : {"newton", "lg-aa"}) {
    const auto& g = j["growth"]["three_chamber"][solver];
    EXPECT_TRUE(g["all_converged"].get<bool>()) << g;
    EXPECT_GT(g["iteration_growth"].get<double>(), 0.0) << g;
  }
  for (const auto& row : j["rows"]) {
    EXPECT_EQ(row["status"], "converged") << row;
    EXPECT_LT(row["residual_ratio"].get<double>(), 1e-6) << row;
  }
}

TEST(Cli, RefinementCanCompareAtEqualChamberVolume) {
  const std::string dir = TempDir("refinement_volume");
  const std::string bad = dir + "/bad.json";
  // A volume target needs pneumatic actuators; a case gives actuation or volume_ratio, not both.
  EXPECT_TRUE(RefusedWith(
      RunConfig(bad, R"({"name": "bad_ref", "experiment": "refinement", "seed": 1,
    "cases": [{"label": "c", "robot": "cable_finger", "volume_ratio": [1.1, 1.1, 1.1],
               "resolutions": [5, 6, 7, 8]}]})",
                dir),
      {bad + ": cases[0].volume_ratio: expected a robot whose actuators are all unsigned "
             "pneumatic ones ('cable_finger' has cable actuator 't1')"}));
  // A signed actuator inflates one of two chambers: no single volume ratio to match.
  EXPECT_TRUE(RefusedWith(
      RunConfig(bad, R"({"name": "bad_ref", "experiment": "refinement", "seed": 1,
    "cases": [{"label": "m", "robot": "finger_manipulator", "volume_ratio": [1.5, 1, 1],
               "resolutions": [6, 7, 8, 9]}]})",
                dir),
      {"cases[0].volume_ratio: expected a robot whose actuators are all unsigned pneumatic ones "
       "('finger_manipulator' has signed pneumatic actuator 's1')"}));
  EXPECT_TRUE(
      RefusedWith(RunConfig(bad, R"({"name": "bad_ref", "experiment": "refinement", "seed": 1,
    "cases": [{"label": "t", "robot": "three_chamber", "volume_ratio": [1.3, 1, 1],
               "actuation": [1.3, 1, 1], "resolutions": [3, 4, 5, 6]}]})",
                            dir),
                  {"cases[0].actuation: expected exactly one of actuation and volume_ratio"}));

  const std::string good = dir + "/good.json";
  CliRun r = RunConfig(good, R"({"name": "tiny_ref", "experiment": "refinement", "seed": 1,
    "cases": [{"label": "t", "robot": "three_chamber", "volume_ratio": [1.3, 1, 1],
               "resolutions": [3, 4, 5, 6]}]})",
                       dir);
  ASSERT_EQ(r.code, 0) << r.out;
  const auto j = nlohmann::json::parse(ReadAll(dir + "/tiny_ref/summary.json"));
  const auto& c = j["cases"][0];
  EXPECT_TRUE(c["all_converged"].get<bool>()) << c;
  EXPECT_EQ(c["tip_changes_mm"].size(), 3u);
  // Every row reached the chamber volume, each at its own actuation (the body resists the
  // chamber, so the actuation must exceed the volume ratio it reaches).
  const std::string csv = ReadAll(dir + "/tiny_ref/refinement.csv");
  std::istringstream lines(csv);
  std::string line, header;
  std::getline(lines, header);
  EXPECT_NE(header.find(",actuation,volume_ratio,volume_matched"), std::string::npos) << header;
  int rows = 0;
  while (std::getline(lines, line)) {
    ++rows;
    std::vector<std::string> f;
    std::stringstream ls(line);
    for (std::string x; std::getline(ls, x, ',');) f.push_back(x);
    ASSERT_EQ(f.size(), 18u) << line;
    EXPECT_EQ(f[9], "") << line;  // twist_deg: this case measures no twist
    EXPECT_EQ(f[17], "true") << line;
    std::istringstream ratios(f[16]), actuation(f[15]);
    double v1 = 0, c1 = 0;
    ratios >> v1;
    actuation >> c1;
    EXPECT_NEAR(v1, 1.3, 1.3e-3) << line;  // the others, at rest, follow their neighbour
    EXPECT_GT(c1, 1.3 + 1e-3) << line;
  }
  EXPECT_EQ(rows, 4);
  EXPECT_EQ(j["resumed_rows"], 0);

  // Each resolution is journaled as it finishes: the same command again solves nothing, and a
  // run killed after two resolutions solves only the other two, to the same rows (all but the
  // recomputed rows' times).
  const std::string journal = dir + "/tiny_ref/refinement.jsonl";
  r = Cli("run " + good + " --no-plot --results " + dir);
  ASSERT_EQ(r.code, 0) << r.out;
  EXPECT_EQ(nlohmann::json::parse(ReadAll(dir + "/tiny_ref/summary.json"))["resumed_rows"], 4);
  EXPECT_EQ(ReadAll(dir + "/tiny_ref/refinement.csv"), csv);
  const std::string records = ReadAll(journal);
  ASSERT_EQ(CountLines(records), 4) << records;
  size_t cut = 0;
  for (int k = 0; k < 2; ++k) cut = records.find('\n', cut) + 1;
  std::ofstream(journal, std::ios::trunc) << records.substr(0, cut);
  r = Cli("run " + good + " --no-plot --results " + dir);
  ASSERT_EQ(r.code, 0) << r.out;
  EXPECT_EQ(nlohmann::json::parse(ReadAll(dir + "/tiny_ref/summary.json"))["resumed_rows"], 2);
  auto without_times = [](const std::string& text) {
    std::istringstream in(text);
    std::string out;
    for (std::string l; std::getline(in, l);) {
      std::vector<std::string> f;
      std::stringstream ls(l);
      for (std::string x; std::getline(ls, x, ',');) f.push_back(x);
      f.at(12).clear();  // solve_s
      for (const auto& x : f) out += x + ",";
      out += "\n";
    }
    return out;
  };
  EXPECT_EQ(without_times(ReadAll(dir + "/tiny_ref/refinement.csv")), without_times(csv));
}

TEST(Cli, RefinementRecordsTheTwistAboutAnAxis) {
  const std::string dir = TempDir("refinement_twist");
  const std::string bad = dir + "/bad.json";
  EXPECT_TRUE(
      RefusedWith(RunConfig(bad, R"({"name": "bad_twist", "experiment": "refinement", "seed": 1,
    "cases": [{"label": "b", "robot": "bimaterial_bar", "actuation": [30, 0],
               "twist_axis": [0, 0, 0], "resolutions": [2, 3, 4, 6]}]})",
                            dir),
                  {bad + ": cases[0].twist_axis: expected an array of 3 numbers, not all zero"}));
  // One vertex has no twist.
  EXPECT_TRUE(RefusedWith(
      RunConfig(bad, R"({"name": "bad_twist", "experiment": "refinement", "seed": 1,
    "cases": [{"label": "w", "robot": "twisting_robot", "marker": "tip_rim", "actuation": [2],
               "twist_axis": [0, 0, 1], "resolutions": [1, 2, 3, 4]}]})",
                dir),
      {"cases[0].twist_axis: expected a marker of 3 or more vertices to measure a twist "
       "('tip_rim' has 1)"}));

  // The bar's end face is turned by the motion actuator 'twist' (degrees about +x): the recorded
  // twist of marker 'tip' is that angle at every resolution, and about -x its negative.
  const std::string good = dir + "/good.json";
  CliRun r = RunConfig(good, R"({"name": "tiny_twist", "experiment": "refinement", "seed": 1,
    "cases": [{"label": "x", "robot": "bimaterial_bar", "actuation": [30, 0],
               "twist_axis": [2, 0, 0], "resolutions": [2, 3, 4, 6]},
              {"label": "minus x", "robot": "bimaterial_bar", "actuation": [30, 0],
               "twist_axis": [-1, 0, 0], "resolutions": [2, 3, 4, 6]},
              {"label": "interface", "robot": "bimaterial_bar", "marker": "interface",
               "actuation": [30, 0], "twist_axis": [1, 0, 0], "resolutions": [2, 3, 4, 6]}]})",
                       dir);
  ASSERT_EQ(r.code, 0) << r.out;
  const auto j = nlohmann::json::parse(ReadAll(dir + "/tiny_twist/summary.json"));
  ASSERT_EQ(j["cases"].size(), 3u);
  for (int k = 0; k < 2; ++k) {
    const auto& t = j["cases"][k]["twist_deg"];
    ASSERT_EQ(t.size(), 4u) << j;
    for (const auto& deg : t) EXPECT_NEAR(deg.get<double>(), k == 0 ? 30.0 : -30.0, 1e-6) << j;
  }
  // The interface of two equal halves turns part of the way, the same way.
  for (const auto& deg : j["cases"][2]["twist_deg"]) {
    EXPECT_GT(deg.get<double>(), 1.0) << j;
    EXPECT_LT(deg.get<double>(), 29.0) << j;
  }
  const std::string csv = ReadAll(dir + "/tiny_twist/refinement.csv");
  EXPECT_NE(csv.find("change_mm,to_finest_mm,twist_deg,energy"), std::string::npos) << csv;
}
