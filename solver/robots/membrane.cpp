/// \file membrane.cpp
/// membrane (thesis Sec. 3.4.3, Fig. 3.13): a membrane shaped through contact by four chambers.
#include "softkin/solver/robots/robot_parts.hpp"

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
// membrane (thesis Sec. 3.4.3, Fig. 3.13): a 250 x 250 mm Dragon Skin 20 membrane shaped by four
// pneumatic chambers below it, which touch it only through contact (collision response between
// separate bodies of one mesh).
//
// Axes: membrane in x, y in [0, 250], z up. Cells of h = 250 / res mm. The membrane is one cell
// thick (region 0), its rim (x or y at 0 or 250) fixed. Below it, a 2 x 2 array of closed boxes
// (walls region 1, one cell thick; cavities regions 2..5 = actuators c1..c4, volume ratio in
// [1, 4]), each about 40 mm tall, chamber_gap cells apart (default 2: with 1, neighbouring
// chambers' swelling side walls press on each other) and one cell in from the rim, standing on
// the fixed plane z = 0, with a 2 mm air gap between their roofs and the membrane (the mesh is
// cut there, CutSlit). Chamber k sits under quadrant k: c1 (x < 125, y < 125), c2 (x > 125,
// y < 125), c3 (x < 125, y > 125), c4 (x > 125, y > 125). Material: Mooney-Rivlin Dragon Skin 20
// (Eq. 3.6-3.7) for membrane and walls. Markers: tip (the membrane's top centre) and q1..q4
// (membrane top above each chamber's centre). Self-collision response is on in the scene's solver
// options.
// ================================================================================================

constexpr int kMemMinRes = 10, kMemMaxRes = 60, kMemDefaultRes = 20;
constexpr double kMemSide = 250.0, kMemChamberHeight = 40.0, kMemGap = 2.0, kMemMaxAlpha = 4.0;

Scene MakeMembrane(int res, const RobotParams& P) {
  // An even count of cells across: the voxel split is mirrored cell by cell, so it is symmetric
  // about the mid-planes x, y = 125 only then (an odd res takes res + 1 cells).
  const int n = res + (res & 1);
  const double h = kMemSide / n;
  const int gap = static_cast<int>(std::lround(P.at("chamber_gap")));
  if (std::abs(P.at("chamber_gap") - gap) > 1e-9)
    throw std::invalid_argument("membrane: chamber_gap: expected an integer number of cells, got " +
                                std::to_string(P.at("chamber_gap")));
  // Chamber width in cells: 1 margin + nc + gap + nc + (the rest) margin. An odd gap leaves one
  // more cell of margin on the far sides: that layout is off-centre by half a cell.
  const int nc = (n - 2 - gap) / 2;
  if (nc < 3)
    throw std::invalid_argument("membrane: chamber_gap = " + std::to_string(gap) +
                                " leaves chambers " + std::to_string(nc) + " cells wide at res " +
                                std::to_string(res) +
                                "; expected at least 3 (raise res or lower chamber_gap)");
  const int hc = std::max(3, static_cast<int>(std::lround(kMemChamberHeight / h)));
  const int zm = hc;  // membrane cell layer, on the roofs (then lifted by the slit)
  const int x0[2] = {1, 1 + nc + gap};
  auto cell = [&](const Eigen::Vector3d&, const Eigen::Vector3i& c) {
    const int i = c[0], j = c[1], k = c[2];
    if (k == zm) return 0;
    if (k >= hc) return -1;
    for (int q = 0; q < 4; ++q) {
      const int ox = x0[q % 2], oy = x0[q / 2];
      if (i < ox || i >= ox + nc || j < oy || j >= oy + nc) continue;
      const bool interior =
          i > ox && i < ox + nc - 1 && j > oy && j < oy + nc - 1 && k > 0 && k < hc - 1;
      return interior ? 2 + q : 1;
    }
    return -1;
  };
  Scene s;
  s.name = "membrane";
  s.mesh = VoxelTetMesh(Eigen::Vector3d::Zero(), h, Eigen::Vector3i(n, n, zm + 1), cell);
  // The membrane is a separate body: lift it off the roofs by kMemGap.
  const double z_roof = zm * h;
  CutSlit(
      &s.mesh, [&](const Eigen::Vector3d& p) { return std::abs(p.z() - z_roof) < 1e-6 * h; },
      [&](const Eigen::Vector3d& c) { return c.z() > z_roof; }, Eigen::Vector3d(0, 0, kMemGap));
  s.body[0] = MooneyRivlinMaterial("membrane", "dragon-skin-20", 1.0);
  s.body[1] = MooneyRivlinMaterial("chamber_wall", "dragon-skin-20", 1.0);
  for (int q = 0; q < 4; ++q) {
    Actuator a;
    a.name = "c" + std::to_string(q + 1);
    a.type = ActuatorType::Pneumatic;
    a.regions = {2 + q};
    a.rest = a.min = 1.0;
    a.max = kMemMaxAlpha;
    s.actuators.push_back(a);
  }
  const double eps = 1e-6 * h, side = n * h, zlo = zm * h + kMemGap;
  std::vector<int> fixed =
      VerticesOnPlane(s.mesh, Eigen::Vector3d::Zero(), Eigen::Vector3d::UnitZ(), eps);
  for (int v = 0; v < s.mesh.num_vertices(); ++v) {
    const Eigen::Vector3d p = s.mesh.vertices.row(v);
    const bool rim = p.x() < eps || p.y() < eps || p.x() > side - eps || p.y() > side - eps;
    if (rim && p.z() > zlo - eps) fixed.push_back(v);
  }
  std::sort(fixed.begin(), fixed.end());
  fixed.erase(std::unique(fixed.begin(), fixed.end()), fixed.end());
  s.fixed = fixed;
  const double ztop = zlo + h;
  s.markers.push_back(
      {"tip", {NearestVertex(s.mesh, Eigen::Vector3d(0.5 * side, 0.5 * side, ztop))}});
  for (int q = 0; q < 4; ++q) {
    const double cx = (x0[q % 2] + 0.5 * nc) * h, cy = (x0[q / 2] + 0.5 * nc) * h;
    s.markers.push_back(
        {"q" + std::to_string(q + 1), {NearestVertex(s.mesh, Eigen::Vector3d(cx, cy, ztop))}});
  }
  s.solver.collision.self = true;
  s.validate();
  return s;
}

}  // namespace

RobotEntry MembraneEntry() {
  const RobotInfo info = {
      "membrane",
      "250 x 250 mm Dragon Skin 20 membrane (rim fixed) shaped by four pneumatic chambers below "
      "it through contact only (thesis Sec. 3.4.3, Fig. 3.13). Actuators c1..c4 (volume ratio in "
      "[1, 4]) under quadrants (x<125,y<125), (x>125,y<125), (x<125,y>125), (x>125,y>125). "
      "Self-collision response on. Markers: tip (membrane top centre), q1..q4 (membrane top above "
      "each chamber).",
      kMemDefaultRes,
      "cells across the 250 mm side (cell size 250/res mm; an odd res takes res + 1, so that the "
      "mesh is mirror-symmetric about x = 125 and y = 125), integer in [10, 60]",
      {{"chamber_gap", 2.0, 1.0, 10.0,
        "cells between neighbouring chambers (integer). With 1 the swelling chambers' side walls "
        "press on each other and the contact response breaks down at res 24 "
        "(docs/collision_response.md). An odd gap leaves the far margins one cell wider than the "
        "near ones, so the layout is off-centre by half a cell"}}};
  return {info, kMemMinRes, kMemMaxRes, &MakeMembrane};
}

}  // namespace robots_detail
}  // namespace softkin
