// The pressure-loaded CalculiX FEM (solver/baselines/calculix_pressure.hpp): the hollow mesh and
// its cavity faces, the .inp deck parsed back (sets, element faces under pressure, the pressure),
// the cavity volume at rest, and tiny ccx runs: no pressure gives the rest shape, pressure
// inflates the cavity and bends the bar the way SoftKin bends it.
#include "softkin/solver/baselines/calculix_pressure.hpp"
#include "softkin/solver/baselines/ccx_run.hpp"

#include "softkin/solver/factory/fk_factory.hpp"
#include "softkin/solver/fk/fk_solver.hpp"
#include "tests/solver/test_util.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cstdio>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <map>
#include <set>
#include <sstream>
#include <string>
#include <vector>

#include <unistd.h>

namespace softkin {
namespace {

namespace fs = std::filesystem;

/// A 10 x 3 x 4 bar of 2 mm cells with a closed chamber (region 1: cells x 2..7, y 1, z 2) inside
/// the body (region 0) above a stiff bottom layer (region 2, weight 20, z = 0): inflating the
/// chamber lengthens the top and bends the bar towards -z.
Scene ClosedChamberBar() {
  Actuator a = test::Pneumatic("chamber", {1}, 5.0, 1.0, 3.0);
  return test::VoxelScene(
      Eigen::Vector3i(10, 3, 4), 2.0,
      [](const Eigen::Vector3i& c) {
        if (c.z() == 0) return 2;
        return (c.x() >= 2 && c.x() <= 7 && c.y() == 1 && c.z() == 2) ? 1 : 0;
      },
      {{0, Material{"body", 1.0, 1.0}}, {2, Material{"layer", 1.0, 20.0}}}, {a},
      "closed_chamber_bar");
}

double ChamberElementVolume(const Model& m, int g) {
  double v = 0;
  for (int i : m.group_elements(g)) v += m.elements()[i].rest_volume;
  return v;
}

fs::path TempFile(const std::string& name) {
  return fs::temp_directory_path() /
         ("softkin_test_ccxp_" + std::to_string(::getpid()) + "_" + name);
}

TEST(PressureFem, HollowMeshDropsTheChamberAndItsCavityHasTheChamberVolume) {
  const Scene s = ClosedChamberBar();
  const Model model(s);
  for (const std::string type : {"C3D4", "C3D10"}) {
    const PressureFemMesh fem = BuildPressureFemMesh(model, type);
    const int chamber = static_cast<int>(model.group_elements(0).size());
    EXPECT_EQ(static_cast<int>(fem.connectivity.size()), s.mesh.num_elements() - chamber) << type;
    for (const auto& conn : fem.connectivity) EXPECT_EQ(conn.size(), type == "C3D4" ? 4u : 10u);
    // 6 cells x 1 x 1: the cavity's boundary is 2 (6 x 1 + 6 x 1 + 1 x 1) squares of 2 x 2 mm,
    // two triangles each.
    EXPECT_EQ(fem.cavities[0].size(), 2u * 2u * (6 + 6 + 1)) << type;
    EXPECT_NEAR(fem.cavity_rest_volume[0], ChamberElementVolume(model, 0), 1e-9) << type;
    EXPECT_NEAR(fem.cavity_rest_volume[0], 6 * 8.0, 1e-9) << type;
    // Every mesh vertex is kept (the 6 x 1 x 1 cell chamber has no interior vertex).
    for (int v = 0; v < s.mesh.num_vertices(); ++v) EXPECT_GE(fem.vertex_node[v], 0);
  }
}

TEST(PressureFem, CavityVolumeIsInvariantUnderRigidMotion) {
  const Model model(ClosedChamberBar());
  const PressureFemMesh fem = BuildPressureFemMesh(model, "C3D10");
  const Eigen::Matrix3d R =
      Eigen::AngleAxisd(0.7, Eigen::Vector3d(1, 2, 3).normalized()).toRotationMatrix();
  Eigen::MatrixX3d X = (fem.rest * R.transpose()).rowwise() + Eigen::RowVector3d(5, -3, 11);
  EXPECT_NEAR(CavityVolume(fem.cavities[0], X), fem.cavity_rest_volume[0], 1e-9);
  // Scaling by s scales it by s^3.
  EXPECT_NEAR(CavityVolume(fem.cavities[0], 1.5 * fem.rest), 3.375 * fem.cavity_rest_volume[0],
              1e-9);
}

TEST(PressureFem, InpExportParsesBack) {
  const Scene s = ClosedChamberBar();
  const Model model(s);
  const PressureFemMesh fem = BuildPressureFemMesh(model, "C3D10");
  PressureFemOptions opt;
  const fs::path p = TempFile("export.inp");
  WritePressureFemInput(model, fem, Eigen::VectorXd::Constant(1, 0.05), opt, p.string());
  std::ifstream in(p);
  ASSERT_TRUE(in);
  std::string line, section, header;
  std::map<int, std::vector<int>> elements;
  std::vector<std::pair<int, std::string>> loads;
  std::vector<double> load_values;
  std::set<int> fixed;
  int nodes = 0;
  bool nlgeom = false;
  std::vector<int> pending;
  int pending_id = -1;
  while (std::getline(in, line)) {
    if (line.rfind("**", 0) == 0) continue;
    if (line[0] == '*') {
      header = line;
      section = line.substr(0, line.find(','));
      if (section == "*ELEMENT") {
        EXPECT_NE(line.find("TYPE=C3D10"), std::string::npos) << line;
      }
      if (section == "*STEP") nlgeom = line.find("NLGEOM") != std::string::npos;
      continue;
    }
    std::stringstream ss(line);
    std::string tok;
    std::vector<std::string> toks;
    while (std::getline(ss, tok, ',')) toks.push_back(tok);
    if (section == "*NODE") {
      ++nodes;
    } else if (section == "*ELEMENT") {
      // 11 numbers, split over two lines after the ninth.
      std::vector<int> v;
      for (const auto& t : toks)
        if (t.find_first_not_of(" ") != std::string::npos) v.push_back(std::stoi(t));
      if (pending_id < 0) {
        pending_id = v[0];
        pending.assign(v.begin() + 1, v.end());
      } else {
        pending.insert(pending.end(), v.begin(), v.end());
      }
      if (pending.size() == 10) {
        elements[pending_id] = pending;
        pending_id = -1;
      }
    } else if (section == "*NSET" && header.find("NSET=FIXED") != std::string::npos) {
      for (const auto& t : toks) fixed.insert(std::stoi(t) - 1);
    } else if (section == "*DLOAD") {
      ASSERT_EQ(toks.size(), 3u) << line;
      std::string label = toks[1];
      label.erase(std::remove(label.begin(), label.end(), ' '), label.end());
      loads.push_back({std::stoi(toks[0]), label});
      load_values.push_back(std::stod(toks[2]));
    }
  }
  EXPECT_TRUE(nlgeom);
  EXPECT_EQ(nodes, fem.rest.rows());
  EXPECT_EQ(elements.size(), fem.connectivity.size());
  // Fixed: the x = 0 vertices.
  EXPECT_EQ(fixed.size(), s.fixed.size());
  for (int v : s.fixed) EXPECT_TRUE(fixed.count(fem.vertex_node[v])) << v;
  // Each loaded face, read with CalculiX's face numbering (1-2-3, 1-4-2, 2-4-3, 3-4-1), is a face
  // of the chamber: its three corners belong to chamber elements.
  ASSERT_EQ(loads.size(), fem.cavities[0].size());
  std::set<int> chamber_vertices;
  for (int i : model.group_elements(0))
    for (int j = 0; j < 4; ++j) chamber_vertices.insert(s.mesh.elements[i].v[j]);
  const int kFaces[4][3] = {{0, 1, 2}, {0, 3, 1}, {1, 3, 2}, {2, 3, 0}};
  std::set<std::set<int>> loaded_faces;
  for (size_t q = 0; q < loads.size(); ++q) {
    EXPECT_DOUBLE_EQ(load_values[q], 0.05);
    ASSERT_TRUE(elements.count(loads[q].first)) << loads[q].first;
    ASSERT_EQ(loads[q].second.size(), 2u);
    const int face = loads[q].second[1] - '0';
    ASSERT_TRUE(loads[q].second[0] == 'P' && face >= 1 && face <= 4) << loads[q].second;
    std::set<int> corners;
    for (int j : kFaces[face - 1]) {
      const int node = elements[loads[q].first][j] - 1;
      corners.insert(node);
      EXPECT_TRUE(chamber_vertices.count(fem.node_vertex[node])) << "element " << loads[q].first;
    }
    loaded_faces.insert(corners);
  }
  EXPECT_EQ(loaded_faces.size(), loads.size());  // no face loaded twice
  fs::remove(p);
}

TEST(PressureFem, OpenOrTouchingChambersAndOtherActuatorsAreRefusedByName) {
  // The chamber reaches the top surface: an open cavity.
  Actuator a = test::Pneumatic("top_chamber", {1}, 5.0, 1.0, 3.0);
  const Scene open =
      test::VoxelScene(Eigen::Vector3i(6, 2, 2), 2.0,
                       [](const Eigen::Vector3i& c) { return (c.z() == 1 && c.x() >= 1) ? 1 : 0; },
                       {{0, Material{"body", 1.0, 1.0}}}, {a});
  try {
    BuildPressureFemMesh(Model(open), "C3D10");
    ADD_FAILURE() << "an open chamber was accepted";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("'top_chamber' is open"), std::string::npos) << e.what();
  }
  // A cable actuator.
  const Scene cable = test::VoxelScene(
      Eigen::Vector3i(6, 2, 2), 2.0, [](const Eigen::Vector3i& c) { return c.z() == 1 ? 1 : 0; },
      {{0, Material{"body", 1.0, 1.0}}},
      {test::Cable("tendon", {1}, {Eigen::Vector3d(0, 2, 3), Eigen::Vector3d(12, 2, 3)})});
  try {
    BuildPressureFemMesh(Model(cable), "C3D10");
    ADD_FAILURE() << "a cable actuator was accepted";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("'tendon' is cable"), std::string::npos) << e.what();
  }
  const Model model(ClosedChamberBar());
  EXPECT_THROW(BuildPressureFemMesh(model, "C3D8"), std::invalid_argument);
  PressureFemOptions bad;
  bad.poisson = 0.5;
  EXPECT_THROW(
      WritePressureFemInput(model, BuildPressureFemMesh(model, "C3D4"),
                            Eigen::VectorXd::Constant(1, 0.1), bad, TempFile("bad.inp").string()),
      std::invalid_argument);
}

TEST(PressureFem, NoPressureKeepsTheRestShape) {
  if (FindCcx().empty()) GTEST_SKIP() << CcxMissingMessage();
  const Scene s = ClosedChamberBar();
  const Model model(s);
  PressureFemOptions opt;
  opt.max_increment = 0.5;
  const PressureFemRun run = RunPressureFem(model, Eigen::VectorXd::Zero(1), opt);
  ASSERT_TRUE(run.ok) << run.message;
  ASSERT_TRUE(run.reached_end) << run.message;
  const auto& last = run.increments.back();
  EXPECT_LT((last.positions - s.mesh.vertices).cwiseAbs().maxCoeff(), 1e-9);
  EXPECT_NEAR(last.cavity_ratio[0], 1.0, 1e-12);
}

TEST(PressureFem, PressureInflatesTheCavityAndBendsTheBarLikeSoftKin) {
  if (FindCcx().empty()) GTEST_SKIP() << CcxMissingMessage();
  const Scene s = ClosedChamberBar();
  auto model = std::make_shared<const Model>(s);
  PressureFemOptions opt;
  opt.max_increment = 0.25;
  const PressureFemRun run = RunPressureFem(*model, Eigen::VectorXd::Constant(1, 0.2), opt);
  ASSERT_TRUE(run.ok) << run.message;
  ASSERT_TRUE(run.reached_end) << run.message;
  ASSERT_GE(run.increments.size(), 4u);
  // The cavity grows with the pressure, and the pressure is the ramp's.
  double prev = 1.0;
  for (const auto& inc : run.increments) {
    EXPECT_GT(inc.cavity_ratio[0], prev) << "load " << inc.load;
    prev = inc.cavity_ratio[0];
    EXPECT_NEAR(inc.pressure[0], 0.2 * inc.load, 1e-12);
    EXPECT_TRUE(inc.positions.allFinite());
  }
  const double ratio = run.increments.back().cavity_ratio[0];
  EXPECT_GT(ratio, 1.05);
  // SoftKin at the chamber volume ratio the FEM reached (its target ratio, so at least as much
  // inflation): both bend the tip down (-z) and keep it near the plane y = 3 (the voxel tets are
  // not mirror-symmetric, so not exactly in it).
  FkOptions fk;
  const FkResult r = MakeFkSolver(model, fk)->Solve(Eigen::VectorXd::Constant(1, ratio));
  ASSERT_EQ(r.status, FkStatus::Converged) << r.message;
  const Eigen::RowVector3d fem_tip =
      s.marker_positions(run.increments.back().positions).row(s.marker_index("tip"));
  const Eigen::RowVector3d sk_tip = s.marker_positions(r.positions).row(s.marker_index("tip"));
  const Eigen::RowVector3d rest_tip =
      s.marker_positions(s.mesh.vertices).row(s.marker_index("tip"));
  EXPECT_LT(fem_tip.z() - rest_tip.z(), -0.2);
  EXPECT_LT(sk_tip.z() - rest_tip.z(), -0.2);
  EXPECT_NEAR(fem_tip.y(), 3.0, 0.05);
  EXPECT_NEAR(sk_tip.y(), 3.0, 0.05);
  std::printf("cavity ratio %.4f; tip moves FEM (%.3f, %.3f, %.3f), SoftKin (%.3f, %.3f, %.3f)\n",
              ratio, fem_tip.x() - rest_tip.x(), fem_tip.y() - rest_tip.y(),
              fem_tip.z() - rest_tip.z(), sk_tip.x() - rest_tip.x(), sk_tip.y() - rest_tip.y(),
              sk_tip.z() - rest_tip.z());
}

}  // namespace
}  // namespace softkin
