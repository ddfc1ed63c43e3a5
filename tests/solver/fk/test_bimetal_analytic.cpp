// An analytic reference: the bilayer strip (robot bilayer_strip) at small strain against
// Timoshenko's bimetal formula (1925), and what SoftKin's actuation model changes in it.
//
// At small strain the element energy w Vol |F - R|^2 is linear elasticity with shear modulus w
// and no volumetric term (Poisson's ratio 0, Young's modulus 2w), and an inflated actuation layer
// is a layer with the isotropic eigenstrain eps = cbrt(alpha) - 1. For two layers of equal
// thickness t, modulus ratio n = E_top / E_bottom and own bending stiffnesses E_i t^3 / 12,
// Timoshenko's curvature is
//     kappa_T = eps / (t (1 + (1 + n)^2 / (12 n))).
// (With Poisson's ratio 0 the bending along the strip does not couple to its width, so the
// plate's curvature along x is the beam's.)
//
// SoftKin's actuation layer is not such a layer: its elements share one volume target (Eq. 2.8),
// handed out in proportion to their current volumes, so the layer resists its total volume but
// not how the volume is spread through its thickness. It pulls on the body with its full axial
// stiffness and has no bending stiffness of its own; the same beam balance with E_top I_top = 0
// gives
//     kappa_0 = eps / (t (1 + (1 + n) / (12 n))),
// 1.45 kappa_T at n = 5. The test checks that SoftKin's curvature lies between the two formulas
// and approaches kappa_0 under refinement (the coarsest mesh, one cell per layer, locks in
// bending and stays below both).
#include "softkin/solver/factory/fk_factory.hpp"
#include "softkin/solver/fk/fk_solver.hpp"
#include "softkin/solver/robots/robots.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>

namespace softkin {
namespace {

struct BimetalResult {
  double kappa = 0, timoshenko = 0, no_layer_bending = 0;
};

BimetalResult SolveBimetal(int res) {
  const Scene s = MakeRobot("bilayer_strip", res, {});
  const double alpha = 1.003, eps = std::cbrt(alpha) - 1.0;
  const double n = s.actuators[0].weight / s.body.at(0).weight;
  const double t = s.mesh.vertices.col(2).maxCoeff() / 2.0;
  const double width = s.mesh.vertices.col(1).maxCoeff();
  BimetalResult out;
  out.timoshenko = eps / (t * (1.0 + (1.0 + n) * (1.0 + n) / (12.0 * n)));
  out.no_layer_bending = eps / (t * (1.0 + (1.0 + n) / (12.0 * n)));
  FkOptions o;
  o.solver = FkSolverType::kNewton;
  o.gradient_tolerance = 1e-9;
  o.tolerance = 1e-9;
  auto model = std::make_shared<const Model>(s);
  const FkResult r = MakeFkSolver(model, o)->Solve(Eigen::VectorXd::Constant(1, alpha));
  EXPECT_EQ(r.status, FkStatus::Converged) << r.message;
  // Least squares w(x, y) = a + b x + kappa x^2 / 2 + c y + d y^2 on the interface z = t, x in
  // [0.3 L, L] (away from the clamp; the y terms take the bending across the width).
  const double L = s.mesh.vertices.col(0).maxCoeff();
  Eigen::MatrixXd A(0, 5);
  Eigen::VectorXd w(0);
  for (int v = 0; v < s.mesh.num_vertices(); ++v) {
    const Eigen::Vector3d X = s.mesh.vertices.row(v);
    if (std::abs(X.z() - t) > 1e-9 || X.x() < 0.3 * L) continue;
    A.conservativeResize(A.rows() + 1, 5);
    w.conservativeResize(w.size() + 1);
    const double y = X.y() - width / 2;
    A.row(A.rows() - 1) << 1.0, X.x(), 0.5 * X.x() * X.x(), y, y * y;
    w[w.size() - 1] = r.positions(v, 2) - X.z();
  }
  EXPECT_GE(A.rows(), 10);
  const Eigen::VectorXd coef = A.colPivHouseholderQr().solve(w);
  out.kappa = -coef[2];  // the strip curls towards -z
  return out;
}

TEST(BimetalAnalytic, SmallStrainCurvatureLiesBetweenTimoshenkoAndTheNoLayerBendingLimit) {
  const BimetalResult r1 = SolveBimetal(1), r2 = SolveBimetal(2), r3 = SolveBimetal(3);
  const double kt = r1.timoshenko, k0 = r1.no_layer_bending;
  std::printf(
      "kappa (1/mm): Timoshenko %.5g, no own bending of the actuated layer %.5g; "
      "SoftKin res 1 / 2 / 3: %.5g / %.5g / %.5g (%+.1f / %+.1f / %+.1f %% of "
      "Timoshenko)\n",
      kt, k0, r1.kappa, r2.kappa, r3.kappa, 100 * (r1.kappa / kt - 1), 100 * (r2.kappa / kt - 1),
      100 * (r3.kappa / kt - 1));
  EXPECT_GT(r1.kappa, 0);
  EXPECT_LT(r1.kappa, r2.kappa);  // one cell per layer locks
  EXPECT_GT(r2.kappa, kt);
  EXPECT_LT(r2.kappa, r3.kappa);
  EXPECT_LT(r3.kappa, k0);
  EXPECT_LT(std::abs(r3.kappa / k0 - 1), 0.08);
}

}  // namespace
}  // namespace softkin
