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
// options. The slit takes the air gap from the membrane's bottom, so the membrane is one cell less
// 2 mm thick. With design_grid = 1 the dimensions are those of the default res 20 (12.5 mm cells:
// a 10.5 mm membrane, 12.5 mm walls and roofs, 100 mm wide and 37.5 mm tall chambers at the
// default gap) at every res, on grid lines; at res 20 the two meshes are the same.
// ================================================================================================

constexpr int kMemMinRes = 10, kMemMaxRes = 60, kMemDefaultRes = 20;
constexpr double kMemSide = 250.0, kMemChamberHeight = 40.0, kMemGap = 2.0, kMemMaxAlpha = 4.0;

/// The setup's dimensions (mm) for cells of h: the rim margin, the walls, the roofs and the
/// membrane are one cell thick; the chambers nc cells wide, gap cells apart and hc cells tall.
struct MembraneLayout {
  double h = 0;
  int nc = 0, gap = 0, hc = 0;
  double x0(int q) const { return (q == 0 ? 1 : 1 + nc + gap) * h; }  // a chamber's near side
  double width() const { return nc * h; }
  double roof() const { return hc * h; }  // the chambers' top, the membrane's bottom at rest
};

MembraneLayout MakeMembraneLayout(int n, int gap) {
  MembraneLayout L;
  L.h = kMemSide / n;
  L.gap = gap;
  // Chamber width in cells: 1 margin + nc + gap + nc + (the rest) margin. An odd gap leaves one
  // more cell of margin on the far sides: that layout is off-centre by half a cell.
  L.nc = (n - 2 - gap) / 2;
  L.hc = std::max(3, static_cast<int>(std::lround(kMemChamberHeight / L.h)));
  return L;
}

/// The region of the cell centred at c: the membrane (0) above the roofs, a chamber's wall (1)
/// or cavity (2 + q), or none (-1).
int MembraneCell(const MembraneLayout& L, const Eigen::Vector3d& c) {
  if (c.z() > L.roof()) return 0;
  for (int q = 0; q < 4; ++q) {
    const double ox = L.x0(q % 2), oy = L.x0(q / 2), w = L.width();
    if (c.x() < ox || c.x() > ox + w || c.y() < oy || c.y() > oy + w) continue;
    const bool interior = c.x() > ox + L.h && c.x() < ox + w - L.h && c.y() > oy + L.h &&
                          c.y() < oy + w - L.h && c.z() > L.h && c.z() < L.roof() - L.h;
    return interior ? 2 + q : 1;
  }
  return -1;
}

/// Grid lines on one horizontal axis at the layout's dimensions, cells of about h; an even count
/// across the gap keeps the mesh symmetric about the mid-plane when the layout is.
std::vector<double> MembraneLines(const MembraneLayout& L, double h) {
  std::vector<double> b = {0.0};
  for (int q = 0; q < 2; ++q)
    for (double x : {L.x0(q), L.x0(q) + L.h, L.x0(q) + L.width() - L.h, L.x0(q) + L.width()})
      b.push_back(x);
  b.push_back(kMemSide);
  return DesignLines(b, h, {false, false, false, false, true});
}

Scene MakeMembrane(int res, const RobotParams& P) {
  // An even count of cells across: the voxel split is mirrored cell by cell, so it is symmetric
  // about the mid-planes x, y = 125 only then (an odd res takes res + 1 cells).
  const int n = res + (res & 1);
  const double h = kMemSide / n;
  const int gap = static_cast<int>(std::lround(P.at("chamber_gap")));
  if (std::abs(P.at("chamber_gap") - gap) > 1e-9)
    throw std::invalid_argument("membrane: chamber_gap: expected an integer number of cells, got " +
                                std::to_string(P.at("chamber_gap")));
  const bool design = DesignGridFlag("membrane", P);
  // On the design grid the dimensions are those of the default res at every res.
  const MembraneLayout L = MakeMembraneLayout(design ? kMemDefaultRes : n, gap);
  if (L.nc < 3)
    throw std::invalid_argument("membrane: chamber_gap = " + std::to_string(gap) +
                                " leaves chambers " + std::to_string(L.nc) + " cells wide at res " +
                                std::to_string(design ? kMemDefaultRes : res) +
                                "; expected at least 3 (raise res or lower chamber_gap)");
  auto cell = [&L](const Eigen::Vector3d& c, const Eigen::Vector3i&) { return MembraneCell(L, c); };
  Scene s;
  s.name = "membrane";
  if (design) {
    const auto xs = MembraneLines(L, h);
    s.mesh = RectilinearTetMesh(
        xs, xs, DesignLines({0.0, L.h, L.roof() - L.h, L.roof(), L.roof() + L.h}, h), cell);
  } else {
    s.mesh = VoxelTetMesh(Eigen::Vector3d::Zero(), h, Eigen::Vector3i(n, n, L.hc + 1), cell);
  }
  // The membrane is a separate body: cut it from the roofs and raise its bottom face by kMemGap
  // (an air gap taken from its thickness).
  const double z_roof = L.roof(), t = L.h;
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
  const double eps = 1e-6 * h, side = kMemSide, zlo = z_roof + kMemGap;
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
  const double ztop = z_roof + t;  // the membrane's top (the slit takes the gap from its bottom)
  s.markers.push_back(
      {"tip", {NearestVertex(s.mesh, Eigen::Vector3d(0.5 * side, 0.5 * side, ztop))}});
  for (int q = 0; q < 4; ++q) {
    const double cx = L.x0(q % 2) + 0.5 * L.width(), cy = L.x0(q / 2) + 0.5 * L.width();
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
        "near ones, so the layout is off-centre by half a cell"},
       {"design_grid", 0.0, 0.0, 1.0,
        "0: every dimension is whole cells of 250/res mm (walls and roofs one cell thick, the "
        "membrane one cell less the 2 mm air gap, the chambers' width, height and gap in cells); "
        "1: the default res's dimensions (10.5 mm membrane, 12.5 mm walls and roofs, chamber_gap "
        "cells of 12.5 mm) on grid lines at every res, mirror-symmetric about x, y = 125 for an "
        "even chamber_gap"}}};
  return {info, kMemMinRes, kMemMaxRes, &MakeMembrane};
}

}  // namespace robots_detail
}  // namespace softkin
