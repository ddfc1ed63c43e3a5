/// \file bilayer_strip.cpp
/// bilayer_strip: a thin clamped two-layer strip whose top layer is one pneumatic actuator. The
/// hard case of the FK benchmarks: long, thin and bending-dominated.
#include "softkin/solver/robots/robot_parts.hpp"

#include "softkin/solver/common/text_format.hpp"
#include "softkin/solver/materials/hyperelastic.hpp"
#include "softkin/solver/mesh/mesh_gen.hpp"

#include <Eigen/Core>

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>
#include <vector>

namespace softkin {
namespace robots_detail {
namespace {

// ================================================================================================
// bilayer_strip: a strip of length L (x, default 100 mm), width W (y, default 10 mm) and two
// layers of thickness t each (z, default 2 mm). The bottom layer z in [0, t] is the body (region
// 0, R_omega 1, weight 1); the top layer z in [t, 2t] is the pneumatic actuation elements of the
// single actuator "top" (region 1, weight 1, volume ratio alpha in [1, 2]). The face x = 0 is
// clamped. Inflating the top layer lengthens it, so the strip curls towards -z. Both layers are
// solid: the strip is a bending beam whose curvature grows with alpha (a bimetal).
// Resolution: cells across one layer (cell size t / res in x and z). Across the width the cell
// count is the even number nearest W / h (cells of W / ny, up to h / (W / h) from cubic), so the
// mesh is mirror-symmetric about y = W / 2 and a curl stays in that plane: the voxel split is
// mirrored cell by cell, which is symmetric only over an even count. res 1 gives
// 6 * 50 * 6 * 2 = 3,600 tets at the defaults, res 2 24,000, res 3 86,400 and res 4 192,000.
// cell_length > 0 sets the cells' length along x instead (rounded to a whole number of cells):
// res 2 with cell_length 2 is the 50 x 10 x 4-cell, 12,000-tet strip of issue #33.
// hyperelastic = 1 makes the body Ecoflex 00-30 (Mooney-Rivlin, Eq. 3.6-3.7) instead.
// Markers: tip (the x = L face), tip_top / tip_bottom (its top and bottom quarters in z).
// ================================================================================================

constexpr int kStripMinRes = 1, kStripMaxRes = 8, kStripDefaultRes = 2;
constexpr double kStripMinCellLength = 0.25;  // mm: the cubic cells of the thinnest layers at res 1

Scene MakeBilayerStrip(int res, const RobotParams& P) {
  const double t = P.at("layer"), h = t / res;
  const double width = P.at("width");
  const double cell_length = P.at("cell_length"), length = P.at("length");
  // Shorter cells than the thinnest layer's cubic ones would give millions of tets.
  if (cell_length != 0.0 && cell_length < kStripMinCellLength)
    throw std::invalid_argument("bilayer_strip: cell_length must be 0 (cubic cells) or at least " +
                                FormatNumber(kStripMinCellLength) + " mm, got " +
                                FormatNumber(cell_length));
  const int nx = Cells(length, cell_length > 0.0 ? cell_length : h), nz = 2 * res;
  const double dx = length / nx;
  const int ny = 2 * std::max(1, static_cast<int>(std::lround(width / (2 * h))));
  auto lines = [](int n, double step) {
    std::vector<double> v(n + 1);
    for (int i = 0; i <= n; ++i) v[i] = i * step;
    return v;
  };
  Scene s;
  s.name = "bilayer_strip";
  s.mesh = RectilinearTetMesh(
      lines(nx, dx), lines(ny, width / ny), lines(nz, h),
      [res](const Eigen::Vector3d&, const Eigen::Vector3i& c) { return c[2] < res ? 0 : 1; });
  if (FlagParam("bilayer_strip", P, "hyperelastic", "Ch. 2 shape blending, R_omega 1",
                "Ecoflex 00-30 Mooney-Rivlin")) {
    MooneyRivlin eco;
    NamedMooneyRivlin("ecoflex-00-30", &eco);
    s.body[0] = Material{"ecoflex-00-30", 1.0, 1.0, MaterialLaw::kMooneyRivlin, eco.c1, eco.c2};
  } else {
    s.body[0] = Material{"body", 1.0, 1.0};
  }
  Actuator a;
  a.name = "top";
  a.type = ActuatorType::Pneumatic;
  a.regions = {1};
  a.rest = 1.0;
  a.min = 1.0;
  a.max = 2.0;
  s.actuators.push_back(a);
  const double eps = 1e-6 * h;
  s.fixed = VerticesOnPlane(s.mesh, Eigen::Vector3d::Zero(), Eigen::Vector3d::UnitX(), eps);
  AddDistalFaceMarkers(nx * dx, nz * h, eps, &s);
  // The robot's own solver: newton, 7-45x faster than lg-aa here (bench_newton, docs/newton.md);
  // --solver or the scene's solver object still choose another.
  s.solver.solver = FkSolverType::kNewton;
  s.validate();
  return s;
}

}  // namespace

RobotEntry BilayerStripEntry() {
  const RobotInfo info = {
      "bilayer_strip",
      "Thin clamped two-layer strip (the hard case of the FK benchmarks): x = length [0, 100] "
      "mm (x = 0 clamped), y = width [0, 10], z = two 2 mm layers; the bottom layer is the body "
      "(region 0, R_omega 1), the top layer the pneumatic actuator 'top' (region 1, alpha in "
      "[1, 2]), so inflation curls the strip towards -z. Markers: tip, tip_top, tip_bottom. "
      "Solved by newton unless --solver says otherwise (lg-aa needs thousands of iterations). "
      "hyperelastic = 1 makes the body Ecoflex 00-30 (Mooney-Rivlin).",
      kStripDefaultRes,
      "cells across one layer (cell size layer/res mm; an even count across the width, so "
      "the mesh is mirror-symmetric), integer in [1, 8]; res 1: 3,600 tets, res 2: 24,000",
      {{"length", 100.0, 10.0, 500.0, "strip length, mm"},
       {"width", 10.0, 1.0, 100.0, "strip width, mm"},
       {"layer", 2.0, 0.25, 20.0, "thickness of each layer, mm"},
       {"cell_length", 0.0, 0.0, 50.0,
        "cell size along the length, mm (0: layer/res, cubic cells; else at least 0.25); res 2 "
        "with cell_length 2 gives 12,000 tets"},
       {"hyperelastic", 0.0, 0.0, 1.0,
        "0: the body is Ch. 2 shape blending with R_omega 1; 1: Ecoflex 00-30 Mooney-Rivlin "
        "(Eq. 3.6-3.7)"}}};
  return {info, kStripMinRes, kStripMaxRes, &MakeBilayerStrip};
}

}  // namespace robots_detail
}  // namespace softkin
