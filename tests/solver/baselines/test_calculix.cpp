// The CalculiX baseline (solver/baselines/calculix.hpp): the .inp export parsed back and checked,
// the .dat reader on good and bad files, and a tiny ccx run (the set-up installs calculix-ccx)
// whose displacement field bends the bar the way lg-aa does.
#include "softkin/solver/baselines/calculix.hpp"

#include "softkin/solver/factory/fk_factory.hpp"
#include "softkin/solver/fk/fk_solver.hpp"
#include "softkin/solver/robots/robots.hpp"
#include "tests/solver/test_util.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>
#include <string>
#include <vector>

#include <unistd.h>

namespace softkin {
namespace {

namespace fs = std::filesystem;

/// A 6 x 2 x 2 bar of 2 mm cells with a chamber in the upper half of cells 1..4 (region 1) and a
/// stiff bottom layer (region 2, weight 20): inflating it bends the bar towards -z.
Scene BendingBar() {
  Actuator a = test::Pneumatic("chamber", {1}, 5.0, 1.0, 3.0);
  return test::VoxelScene(
      Eigen::Vector3i(6, 2, 2), 2.0,
      [](const Eigen::Vector3i& c) {
        if (c.z() == 0) return 2;
        return (c.x() >= 1 && c.x() <= 4) ? 1 : 0;
      },
      {{0, Material{"body", 1.0, 1.0}}, {2, Material{"layer", 1.0, 20.0}}}, {a}, "bending_bar");
}

fs::path TempFile(const std::string& name) {
  return fs::temp_directory_path() /
         ("softkin_test_ccx_" + std::to_string(::getpid()) + "_" + name);
}

TEST(Calculix, InpExportParsesBack) {
  const Scene s = BendingBar();
  const Model model(s);
  const Eigen::VectorXd c = Eigen::VectorXd::Constant(1, 2.0);
  CalculixOptions opt;
  opt.increments = 4;
  const fs::path p = TempFile("export.inp");
  WriteCalculixInput(model, c, opt, p.string());
  std::ifstream in(p);
  ASSERT_TRUE(in);
  std::string line, section, elset, material;
  int nodes = 0, elements = 0;
  std::map<std::string, int> set_size;
  std::map<std::string, double> expansion, young;
  std::vector<int> fixed;
  bool in_fixed = false, nlgeom = false;
  while (std::getline(in, line)) {
    if (line.rfind("**", 0) == 0) continue;
    if (line[0] == '*') {
      section = line.substr(0, line.find(','));
      in_fixed = line.find("NSET=FIXED") != std::string::npos;
      if (section == "*ELEMENT") {
        EXPECT_NE(line.find("TYPE=C3D4"), std::string::npos) << line;
        elset = line.substr(line.find("ELSET=") + 6);
      }
      if (section == "*MATERIAL") material = line.substr(line.find("NAME=") + 5);
      if (section == "*STEP") nlgeom = line.find("NLGEOM") != std::string::npos;
      continue;
    }
    if (section == "*BOUNDARY" || section == "*INITIAL CONDITIONS" || section == "*TEMPERATURE" ||
        section == "*NODE PRINT")
      continue;  // set names, not numbers
    std::stringstream ss(line);
    std::vector<double> v;
    std::string tok;
    while (std::getline(ss, tok, ',')) v.push_back(std::stod(tok));
    if (section == "*NODE") {
      ASSERT_EQ(v.size(), 4u);
      const int id = static_cast<int>(v[0]) - 1;
      ASSERT_EQ(id, nodes);
      for (int d = 0; d < 3; ++d) EXPECT_DOUBLE_EQ(v[1 + d], s.mesh.vertices(id, d));
      ++nodes;
    } else if (section == "*ELEMENT") {
      ASSERT_EQ(v.size(), 5u);
      const auto& e = s.mesh.elements[static_cast<int>(v[0]) - 1];
      for (int j = 0; j < 4; ++j) EXPECT_EQ(static_cast<int>(v[1 + j]) - 1, e.v[j]);
      ++elements;
      ++set_size[elset];
    } else if (section == "*NSET" && in_fixed) {
      for (double x : v) fixed.push_back(static_cast<int>(x) - 1);
    } else if (section == "*ELASTIC") {
      young[material] = v[0];
      EXPECT_DOUBLE_EQ(v[1], opt.poisson);
    } else if (section == "*EXPANSION") {
      expansion[material] = v[0];
    }
  }
  EXPECT_EQ(nodes, s.mesh.num_vertices());
  EXPECT_EQ(elements, s.mesh.num_elements());
  EXPECT_TRUE(nlgeom);
  EXPECT_EQ(fixed, s.fixed);
  // The chamber group: free volume ratio (1 + a)^3 = alpha; stiffness 5 E0. Body: no expansion,
  // E = weight * E0.
  ASSERT_TRUE(expansion.count("MG0"));
  EXPECT_NEAR(std::pow(1.0 + expansion["MG0"], 3), 2.0, 1e-12);
  EXPECT_DOUBLE_EQ(young["MG0"], 5.0);
  EXPECT_DOUBLE_EQ(expansion["MR0"], 0.0);
  EXPECT_DOUBLE_EQ(young["MR2"], 20.0);
  EXPECT_EQ(set_size["G0"], static_cast<int>(model.group_elements(0).size()));
  fs::remove(p);

  // Unsupported scenes are refused with the reason.
  const Scene crawler = MakeRobot("dea_crawler", 4);
  const Model cm(crawler);
  try {
    WriteCalculixInput(cm, Eigen::VectorXd::Constant(1, 0.8), opt, p.string());
    ADD_FAILURE() << "a prism mesh was exported";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("tets only"), std::string::npos) << e.what();
  }
  // So is a scene whose regions have their own rest shapes (a remeshed chamber): here the bar's
  // pneumatic region rests in a uniformly grown copy of the mesh.
  Scene own = s;
  own.region_rest.regions = {own.actuators[0].regions[0]};
  own.region_rest.positions = 1.1 * own.mesh.vertices;
  const Model om(own);
  try {
    WriteCalculixInput(om, c, opt, p.string());
    ADD_FAILURE() << "a scene with region_rest was exported";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("own rest shape"), std::string::npos) << e.what();
  }
}

TEST(Calculix, DatReaderAcceptsIncrementsAndRejectsBadFiles) {
  const fs::path p = TempFile("job.dat");
  {
    std::ofstream o(p);
    o << "\n displacements (vx,vy,vz) for set NALL and time  0.5000000E+00\n\n"
         "         1  0.0  0.0  0.0\n         2  1.0E-01 -2.0E-01  3.0E-01\n\n"
         " displacements (vx,vy,vz) for set NALL and time  0.1000000E+01\n\n"
         "         2  2.0 0.0 0.0\n         1  0.0  0.0  1.5\n";
  }
  const auto blocks = ReadCalculixDisplacements(p.string(), 2);
  ASSERT_EQ(blocks.size(), 2u);
  EXPECT_DOUBLE_EQ(blocks[0].first, 0.5);
  EXPECT_DOUBLE_EQ(blocks[0].second(1, 2), 0.3);
  EXPECT_DOUBLE_EQ(blocks[1].first, 1.0);
  EXPECT_DOUBLE_EQ(blocks[1].second(0, 2), 1.5);
  // A missing node, a node out of range, a short line: errors naming the file.
  auto expect_error = [&](const std::string& text, const std::string& part) {
    {
      std::ofstream o(p);
      o << text;
    }
    try {
      ReadCalculixDisplacements(p.string(), 2);
      ADD_FAILURE() << "accepted: " << text;
    } catch (const std::runtime_error& e) {
      EXPECT_NE(std::string(e.what()).find(part), std::string::npos) << e.what();
      EXPECT_NE(std::string(e.what()).find(p.string()), std::string::npos) << e.what();
    }
  };
  expect_error(" displacements (vx,vy,vz) for set NALL and time 1.0\n 1 0 0 0\n", "lacks node 2");
  expect_error(" displacements (vx,vy,vz) for set NALL and time 1.0\n 3 0 0 0\n",
               ":2: node 3 out of range");
  expect_error(" displacements (vx,vy,vz) for set NALL and time 1.0\n 1 0 0\n",
               ":2: expected node ux uy uz");
  fs::remove(p);
}

TEST(Calculix, StaCounterSkipsCutBackAttempts) {
  const fs::path p = TempFile("job.sta");
  EXPECT_EQ(CountConvergedIncrements(p.string()), 0);  // not written yet
  {
    std::ofstream o(p);
    o << "SUMMARY OF JOB INFORMATION\n"
         "  STEP      INC     ATT  ITRS     TOT TIME     STEP TIME      INC TIME\n"
         "     1          1     1U   11  0.000000E+00  0.000000E+00  0.833333E-01\n"
         "     1          1     2    10  0.416667E-01  0.416667E-01  0.416667E-01\n"
         "     1          2     1     5  0.833333E-01  0.833333E-01  0.416667E-01\n"
         "     1          3     1U    9  0.833333E-01  0.833333E-01  0.416667E-01\n";
  }
  EXPECT_EQ(CountConvergedIncrements(p.string()), 2);
  fs::remove(p);
}

TEST(Calculix, TinyRunBendsTheWayLgAaDoes) {
  const Scene s = BendingBar();
  const Eigen::VectorXd c = Eigen::VectorXd::Constant(1, 2.0);
  FkOptions aa = s.solver;
  const FkResult ref = SolveFk(s, c, &aa);
  ASSERT_EQ(ref.status, FkStatus::Converged) << ref.BriefReport();
  const int tip = s.marker_index("tip");
  const Eigen::Vector3d t0 = s.marker_positions(s.mesh.vertices).row(tip).transpose();
  const Eigen::Vector3d d_ref = s.marker_positions(ref.positions).row(tip).transpose() - t0;
  ASSERT_LT(d_ref.z(), -0.5) << "the test bar should bend towards -z";
  if (FindCcx().empty())
    GTEST_SKIP() << "ccx is not installed (scripts/setup.sh installs calculix-ccx)";
  for (const char* name : {"calculix-linear", "calculix-nonlinear"}) {
    FkOptions o = s.solver;
    o.solver = FkSolverTypeFromString(name);
    o.time_limit_s = 120;
    const FkResult r = SolveFk(s, c, &o);
    ASSERT_EQ(r.status, FkStatus::Converged) << r.BriefReport();
    const Eigen::Vector3d d = s.marker_positions(r.positions).row(tip).transpose() - t0;
    std::printf("  %s: tip moved (%.3f, %.3f, %.3f) mm, lg-aa (%.3f, %.3f, %.3f); %s\n", name,
                d.x(), d.y(), d.z(), d_ref.x(), d_ref.y(), d_ref.z(), r.BriefReport().c_str());
    EXPECT_GT(d.dot(d_ref), 0.7 * d.norm() * d_ref.norm()) << name;
    EXPECT_LT(d.z(), 0.0) << name;
    // The fixed face does not move; the chamber has grown.
    for (int v : s.fixed) EXPECT_LT((r.positions.row(v) - s.mesh.vertices.row(v)).norm(), 1e-9);
    EXPECT_GT(r.volume_ratios[0], 1.2) << name;
    // Five increments (continuation_steps), each time-stamped as ccx reported it: loads rise to 1,
    // wall-clock times rise and stay within the run, the last increment is the result.
    o.continuation_steps = 5;
    auto model = std::make_shared<const Model>(s);
    auto solver = MakeFkSolver(model, o);
    const FkResult r5 = solver->Solve(c);
    ASSERT_EQ(r5.status, FkStatus::Converged) << r5.BriefReport();
    const auto& incs = dynamic_cast<const CalculixSolver&>(*solver).increments();
    ASSERT_GE(incs.size(), 5u) << name;
    for (size_t k = 1; k < incs.size(); ++k) {
      EXPECT_GT(incs[k].load, incs[k - 1].load);
      EXPECT_GE(incs[k].wall_s, incs[k - 1].wall_s);
    }
    EXPECT_NEAR(incs[0].load, 0.2, 1e-9) << "the first increment is 1/5 of the load";
    EXPECT_DOUBLE_EQ(incs.back().load, 1.0);
    // The chamber ratio a load stands for: the expansion coefficient ramps with it.
    EXPECT_DOUBLE_EQ(CalculixRatioAtLoad(2.0, 1.0), 2.0);
    EXPECT_NEAR(CalculixRatioAtLoad(8.0, 0.5), 1.5 * 1.5 * 1.5, 1e-12);
    EXPECT_GT(incs.front().wall_s, 0.0);
    EXPECT_LE(incs.back().wall_s, r5.time_s);
    EXPECT_EQ((incs.back().positions - r5.positions).norm(), 0.0);
  }
}

}  // namespace
}  // namespace softkin
