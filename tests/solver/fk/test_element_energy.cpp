// Tests of the element energy's weighting (Scene::element_energy, scene.hpp): "shape" is Eq. 2.10
// as the thesis writes it, whose term for the same strain grows with the element's size squared;
// "strain" divides each term by its element's rest size and does not depend on it.
#include "softkin/solver/factory/fk_factory.hpp"
#include "softkin/solver/fk/energy.hpp"
#include "softkin/solver/fk/model.hpp"
#include "softkin/solver/mesh/mesh_gen.hpp"
#include "softkin/solver/robots/robots.hpp"
#include "softkin/solver/scene/scene_json.hpp"
#include "tests/solver/scene/scene_json_test_util.hpp"

#include <gtest/gtest.h>

#include <Eigen/Geometry>

#include <cmath>
#include <memory>

namespace softkin {
namespace {

/// A 4 mm cube cut into n^3 cubic cells (every tet similar to every other), one body region,
/// the face x = 0 fixed, with the given element energy.
Scene Cube(int n, ElementEnergy energy) {
  Scene s;
  s.name = "cube";
  const double h = 4.0 / n;
  s.mesh = VoxelTetMesh(Eigen::Vector3d::Zero(), h, Eigen::Vector3i(n, n, n),
                        [](const Eigen::Vector3d&, const Eigen::Vector3i&) { return 0; });
  s.body[0] = Material{"body", 1.0, 1.0};
  for (int v = 0; v < s.mesh.num_vertices(); ++v)
    if (s.mesh.vertices(v, 0) < 1e-9) s.fixed.push_back(v);
  s.element_energy = energy;
  s.validate();
  return s;
}

/// The rest shape under x -> F x + t.
Eigen::MatrixX3d Affine(const Eigen::MatrixX3d& X, const Eigen::Matrix3d& F,
                        const Eigen::RowVector3d& t) {
  Eigen::MatrixX3d Y = X * F.transpose();
  Y.rowwise() += t;
  return Y;
}

Eigen::Matrix3d SomeStretch() {
  Eigen::Matrix3d F;
  F << 1.2, 0.1, 0.0,  //
      0.0, 0.9, 0.05,  //
      0.02, 0.0, 1.1;
  return F;
}

// Under one affine deformation every element of a cube has the same deformation gradient. The
// strain form's energy is then the same for 2^3 cells and for 4^3 cells (the same mix of the
// grid's tet orientations, each half the size); Eq. 2.10's falls by 4, the square of the element
// size, when the cells are halved.
TEST(ElementEnergy, StrainFormDoesNotDependOnTheElementSize) {
  const Eigen::VectorXd rest(0);
  for (ElementEnergy form : {ElementEnergy::kShape, ElementEnergy::kStrain}) {
    SCOPED_TRACE(ToString(form));
    const Model coarse(Cube(2, form)), fine(Cube(4, form));
    EXPECT_NEAR(Energy(coarse, coarse.rest_positions(), rest), 0.0, 1e-12);
    EXPECT_NEAR(Energy(fine, fine.rest_positions(), rest), 0.0, 1e-12);
    const Eigen::RowVector3d t(3.0, -1.0, 2.0);
    const double ec = Energy(coarse, Affine(coarse.rest_positions(), SomeStretch(), t), rest);
    const double ef = Energy(fine, Affine(fine.rest_positions(), SomeStretch(), t), rest);
    ASSERT_GT(ec, 1e-3);
    EXPECT_NEAR(ef / ec, form == ElementEnergy::kStrain ? 1.0 : 0.25, 1e-10);
  }
}

// The strain form keeps the identities of the energy: invariant under a rigid motion, and under
// a scaling of the mesh by s it scales as the volume, s^3 (Eq. 2.10's as s^5).
TEST(ElementEnergy, StrainFormIsInvariantUnderRigidMotionAndScalesAsTheVolume) {
  const Eigen::VectorXd rest(0);
  const Model m(Cube(2, ElementEnergy::kStrain));
  const Eigen::MatrixX3d X = Affine(m.rest_positions(), SomeStretch(), Eigen::RowVector3d::Zero());
  const double e = Energy(m, X, rest);
  const Eigen::Matrix3d R =
      Eigen::AngleAxisd(0.7, Eigen::Vector3d(1.0, -2.0, 0.5).normalized()).toRotationMatrix();
  EXPECT_NEAR(Energy(m, Affine(X, R, Eigen::RowVector3d(5.0, 1.0, -3.0)), rest), e, 1e-10 * e);

  Scene big = Cube(2, ElementEnergy::kStrain);
  big.mesh.vertices *= 3.0;
  const Model mb(big);
  EXPECT_NEAR(Energy(mb, 3.0 * X, rest) / e, 27.0, 1e-9);
}

// On a mesh whose elements are all congruent (cubic cells) the two forms differ by one constant
// factor, so they give the same state: bimaterial_bar res 6 (2 mm cubes: its grid lines every
// 20 mm along the bar divide into whole cells), stretched and twisted.
TEST(ElementEnergy, SameStateOnAMeshOfCongruentElements) {
  FkOptions o;
  o.solver = FkSolverType::kLgAa;
  o.tolerance = 1e-9;
  o.gradient_tolerance = 1e-10;
  o.max_iterations = 100000;
  const Eigen::VectorXd c = Eigen::Vector2d(40.0, 10.0);
  auto shape = std::make_shared<const Model>(MakeRobot("bimaterial_bar", 6));
  auto strain =
      std::make_shared<const Model>(MakeRobot("bimaterial_bar", 6, {{"element_energy", 1.0}}));
  EXPECT_EQ(strain->scene().element_energy, ElementEnergy::kStrain);
  EXPECT_EQ(shape->scene().element_energy, ElementEnergy::kShape);
  const FkResult a = MakeFkSolver(shape, o)->Solve(c);
  const FkResult b = MakeFkSolver(strain, o)->Solve(c);
  ASSERT_EQ(a.status, FkStatus::Converged) << a.BriefReport();
  ASSERT_EQ(b.status, FkStatus::Converged) << b.BriefReport();
  ASSERT_GT(a.energy, 1.0);
  EXPECT_LT((a.positions - b.positions).rowwise().norm().maxCoeff(), 1e-6 * shape->size());
  // The constant: a tet of a cube of side h (three edges along the axes) has |N V^t|^2 = 2.5 h^2,
  // so the strain form divides by 2.5 h^2 / 3 = 10/3 mm^2 at h = 2 mm.
  EXPECT_NEAR(a.energy / b.energy, 2.5 * 4.0 / 3.0, 1e-6 * 10.0 / 3.0);
}

// A 40 x 4 x 4 mm bar of one material whose cells are 2 x 1 x 1 mm for x < 20 and 1 mm cubes
// beyond (grid lines are shared, so the halves differ in element size and shape), stretched by
// 8 mm at x = 40 with x = 0 fixed. The continuum answer stretches both halves alike, 4 mm each.
// Eq. 2.10 makes the long cells about 4x stiffer along x than the cubes (|N V^t|^2 along x is 4x
// larger): the coarse half takes under 1.6 mm. The strain form removes the size factor and keeps
// the aspect-ratio one, which its isotropic size measure cannot see (docs/fidelity.md): the long
// cells stay about 2x stiffer along x, and the coarse half takes 2-3 mm.
TEST(ElementEnergy, StrainFormRemovesTheSizeBiasOfABarWithTwoElementSizes) {
  std::vector<double> xs, yz;
  for (double x = 0.0; x < 20.0 - 1e-9; x += 2.0) xs.push_back(x);
  for (double x = 20.0; x <= 40.0 + 1e-9; x += 1.0) xs.push_back(x);
  for (double y = 0.0; y <= 4.0 + 1e-9; y += 1.0) yz.push_back(y);
  double mid_shape = 0.0, mid_strain = 0.0;
  for (ElementEnergy form : {ElementEnergy::kShape, ElementEnergy::kStrain}) {
    Scene s;
    s.name = "graded_bar";
    s.mesh = RectilinearTetMesh(xs, yz, yz,
                                [](const Eigen::Vector3d&, const Eigen::Vector3i&) { return 0; });
    s.body[0] = Material{"body", 1.0, 1.0};
    std::vector<int> end, mid;
    for (int v = 0; v < s.mesh.num_vertices(); ++v) {
      const double x = s.mesh.vertices(v, 0);
      if (x < 1e-9) s.fixed.push_back(v);
      if (x > 40.0 - 1e-9) end.push_back(v);
      if (std::abs(x - 20.0) < 1e-9) mid.push_back(v);
    }
    Actuator st;
    st.name = "stretch";
    st.type = ActuatorType::Displacement;
    st.vertices = end;
    st.axis = Eigen::Vector3d::UnitX();
    st.rest = 0.0;
    st.min = 0.0;
    st.max = 10.0;
    s.actuators = {st};
    s.markers.push_back({"mid", mid});
    s.element_energy = form;
    s.validate();
    auto model = std::make_shared<const Model>(s);
    FkOptions o;
    o.solver = FkSolverType::kLgAa;
    o.max_iterations = 100000;
    const FkResult r = MakeFkSolver(model, o)->Solve(Eigen::VectorXd::Constant(1, 8.0));
    ASSERT_EQ(r.status, FkStatus::Converged) << r.BriefReport();
    const double mid_x = s.marker_positions(r.positions)(0, 0);
    (form == ElementEnergy::kShape ? mid_shape : mid_strain) = mid_x - 20.0;
  }
  // Stiffness of the coarse half against the fine half along x: (8 - m) / m.
  const double k_shape = (8.0 - mid_shape) / mid_shape, k_strain = (8.0 - mid_strain) / mid_strain;
  EXPECT_GT(k_shape, 3.5);
  EXPECT_GT(k_strain, 1.5);
  EXPECT_LT(k_strain, 3.0);
}

// The option's two entry points: the scene key and the robot parameter, with their errors.
TEST(ElementEnergy, SceneKeyAndRobotParameter) {
  using namespace scene_test;
  TempDir dir;
  WriteTinyMesh(dir.path());
  json j = TinyScene();
  EXPECT_EQ(LoadFrom(dir.path(), j).element_energy, ElementEnergy::kShape);
  j["element_energy"] = "strain";
  EXPECT_EQ(LoadFrom(dir.path(), j).element_energy, ElementEnergy::kStrain);
  j["element_energy"] = "volume";
  ExpectSceneError(j, {"element_energy", "shape", "strain"});
  ExpectError(
      [] {
        MakeRobot("three_chamber", 3, {{"element_energy", 0.5}});
      },
      {"three_chamber", "element_energy", "0 (shape", "1 (strain)", "0.5"});
  for (const RobotInfo& info : ListRobots()) {
    bool listed = false;
    for (const RobotParam& p : info.params) listed |= p.name == "element_energy";
    EXPECT_TRUE(listed) << info.name;
  }
}

}  // namespace
}  // namespace softkin
