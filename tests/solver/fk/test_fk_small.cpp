// FK on meshes of a few dozen tets and prisms, with only softkin::core (the solvers constructed
// directly, not by name): the solves the sanitizer subset (test_sanitized) runs on every CI build.

#include "../test_util.hpp"
#include "softkin/solver/fk/fk_solver.hpp"
#include "softkin/solver/fk/local_global.hpp"
#include "softkin/solver/fk/model.hpp"
#include "softkin/solver/newton/newton_solver.hpp"

#include <gtest/gtest.h>

#include <memory>

namespace softkin {
namespace {

/// Bar of 1 mm cubes, 6 x 2 x 2 cells, x = 0 fixed: the upper layer is one pneumatic chamber
/// (weight 5), the lower layer body (R_omega 1).
Scene ChamberBar() {
  return test::VoxelScene(
      {6, 2, 2}, 1.0, [](const Eigen::Vector3i& c) { return c.z() >= 1 ? 1 : 0; },
      {{0, Material{"body", 1.0, 1.0}}}, {test::Pneumatic("p", {1}, 5.0, 1.0, 2.0)}, "bar");
}

FkResult SolveWith(FkSolverType type, const Scene& scene, double c) {
  auto model = std::make_shared<const Model>(scene);
  FkOptions o;
  o.solver = type;
  o.threads = 1;
  std::unique_ptr<FkSolver> solver;
  if (type == FkSolverType::kNewton)
    solver = std::make_unique<NewtonSolver>(model, o);
  else
    solver = std::make_unique<LocalGlobalSolver>(model, o);
  return solver->Solve(Eigen::VectorXd::Constant(1, c), nullptr);
}

double MaxDistance(const Eigen::MatrixX3d& a, const Eigen::MatrixX3d& b) {
  return (a - b).rowwise().norm().maxCoeff();
}

TEST(SmallMeshFk, RestActuationLeavesTheBarAtRest) {
  const Scene s = ChamberBar();
  for (FkSolverType type : {FkSolverType::kLgAa, FkSolverType::kNewton}) {
    const FkResult r = SolveWith(type, s, 1.0);
    EXPECT_EQ(r.status, FkStatus::Converged) << ToString(type) << ": " << r.message;
    EXPECT_LT(MaxDistance(r.positions, s.mesh.vertices), 1e-9) << ToString(type);
    EXPECT_NEAR(r.energy, 0.0, 1e-12) << ToString(type);
    EXPECT_EQ(r.inverted_elements, 0);
  }
}

TEST(SmallMeshFk, InflatedChamberBendsTheBarAwayFromIt) {
  // The upper layer grows, the lower one resists: the free end bends down (-z), the chamber
  // grows towards its target but, held by the body, not all the way, and both solvers reach the
  // same state.
  const Scene s = ChamberBar();
  const FkResult lg = SolveWith(FkSolverType::kLgAa, s, 1.6);
  const FkResult nt = SolveWith(FkSolverType::kNewton, s, 1.6);
  ASSERT_EQ(lg.status, FkStatus::Converged) << lg.message;
  ASSERT_EQ(nt.status, FkStatus::Converged) << nt.message;
  const std::vector<int>& tip = s.markers[0].vertices;
  double dz = 0;
  for (int v : tip) dz += lg.positions(v, 2) - s.mesh.vertices(v, 2);
  dz /= static_cast<double>(tip.size());
  EXPECT_LT(dz, -0.3) << "mean tip z motion " << dz << " mm";
  ASSERT_EQ(lg.volume_ratios.size(), 1u);
  EXPECT_GT(lg.volume_ratios[0], 1.1);
  EXPECT_LT(lg.volume_ratios[0], 1.6);
  EXPECT_LT(MaxDistance(lg.positions, nt.positions), 1e-4 * s.mesh.size());
  EXPECT_NEAR(lg.energy, nt.energy, 1e-6 * (1.0 + lg.energy));
  EXPECT_EQ(lg.inverted_elements, 0);
  // The fixed face has not moved.
  for (int v : s.fixed) EXPECT_EQ(lg.positions.row(v), s.mesh.vertices.row(v)) << "vertex " << v;
}

TEST(SmallMeshFk, PrismSlabWithADeaLayerSolves) {
  // Two prism layers, the upper one a DEA that expands in area: the slab curls, with no
  // inverted element, and lg-aa and newton agree.
  Scene s;
  s.name = "dea_slab";
  s.mesh = test::PrismSlab(5, 2, 2, 1.0, [](int, int, int l) { return l == 1 ? 1 : 0; });
  s.body = {{0, Material{"body", 1.0, 1.0}}};
  s.actuators = {test::Dea("d", {1})};
  test::FinishScene(&s);
  const FkResult lg = SolveWith(FkSolverType::kLgAa, s, 1.3);
  const FkResult nt = SolveWith(FkSolverType::kNewton, s, 1.3);
  ASSERT_EQ(lg.status, FkStatus::Converged) << lg.message;
  ASSERT_EQ(nt.status, FkStatus::Converged) << nt.message;
  EXPECT_GT(MaxDistance(lg.positions, s.mesh.vertices), 0.1);
  EXPECT_LT(MaxDistance(lg.positions, nt.positions), 1e-4 * s.mesh.size());
  EXPECT_EQ(lg.inverted_elements, 0);
  EXPECT_FALSE(lg.positions.hasNaN());
}

}  // namespace
}  // namespace softkin
