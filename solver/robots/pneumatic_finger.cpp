/// \file pneumatic_finger.cpp
/// pneumatic_finger (thesis Fig. 2.11): a PneuNet-style bending finger on a voxel grid.
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
// pneumatic_finger (thesis Fig. 2.11): PneuNet-style bending actuator on a voxel grid.
//
// Axes: x = long axis (proximal end x = 0, fixed; distal end x = 120), y = width [0, 20],
// z = height [0, 15]. The inextensible layer is at the bottom and the chambers above it, so
// inflation lengthens the upper side and the finger curls towards -z (tip down, then back).
// Nominal geometry (mm), snapped to the grid of cell size h = 20 / res (every feature >= 1 cell):
//   base layer z in [0, 1.5]              region 2 "inextensible" (r_omega 1, weight 20)
//   floor z in [1.5, 3]                    region 0, a thin solid floor under the chambers
//   proximal block x in [0, >= 8]          region 0, its x = 0 face is fixed
//   a row of cavities 5 mm long separated by single 1.5 mm walls (the last wall closes the
//   distal end), with 1.5 mm side walls and roof: region 0 "body" (r_omega 1, weight 1). The
//   cavities are filled with region-1 tets, the pneumatic actuation elements of the single
//   actuator "chamber" (volume ratio alpha in [1, 10]).
// Why this layout: the chamber elements expand isotropically (Eq. 2.8). Thin walls leave the
// expansion to the chambers; the shared end walls carry no bending; the heavy thin base layer
// does not lengthen, so the lengthening upper side curls the finger. (Gaps between chambers, as
// in a moulded PneuNet, give more bend per volume but a far stiffer, slower fixed-point problem;
// a thick solid lower body acts as a stiff beam and caps the bend near 50 degrees.) Measured at
// res 12: 262 degrees at alpha = 10 (fig2_11_pneumatic_bending).
// At the default res 12 (h = 1.667 mm): base, floor, walls 1 cell; cavities 3 cells
// (5 x 16.7 x 10 mm); 16 chambers; proximal block 7 cells; 46,656 tets, 9,490 vertices.
// The grid snaps features to whole cells, so the wall thickness changes with res; the
// resolution study (fig2_13) uses three_chamber, whose geometry does not depend on res.
// ================================================================================================

// The nominal dimensions (kFingerLength, kFingerWall, ...) and kFingerLayerWeight are in
// robot_parts.hpp: selfcollision_finger shares them.
constexpr int kFingerMinRes = 5, kFingerMaxRes = 40, kFingerDefaultRes = 12;
constexpr double kFingerBodyROmega = 1.0;
constexpr double kFingerMaxAlpha = 10.0;

/// The finger's layout in cells.
struct FingerLayout {
  double h = 1.0;  // cell size, mm
  int nx = 0, ny = 0, nz = 0;
  int base = 0;      // base layer thickness (cells)
  int floor = 0;     // solid floor between the base layer and the cavities
  int wall = 0;      // walls: between cavities (x), sides (y), roof (z)
  int cavity = 0;    // cavity length (x)
  int chambers = 0;  // number of cavities
  int proximal = 0;  // proximal solid block length
};

FingerLayout MakeFingerLayout(int res) {
  FingerLayout L;
  L.h = kFingerWidth / res;
  L.ny = res;
  L.nx = static_cast<int>(std::lround(kFingerLength / L.h));  // = 6 res
  L.nz = static_cast<int>(std::lround(kFingerHeight / L.h));
  L.base = Cells(kFingerBase, L.h);
  L.floor = Cells(kFingerFloor, L.h);
  L.wall = Cells(kFingerWall, L.h);
  L.cavity = Cells(kFingerCavity, L.h);
  const int pitch = L.wall + L.cavity;
  L.chambers = (L.nx - Cells(kFingerProximal, L.h) - L.wall) / pitch;
  L.proximal = L.nx - L.chambers * pitch - L.wall;
  return L;
}

/// Region of cell (i, j, k): 2 base layer, 0 body (floor, walls, proximal block), 1 cavity.
int FingerCell(const FingerLayout& L, int i, int j, int k) {
  if (k < L.base) return 2;
  const int u = i - L.proximal;
  if (u < 0 || u >= L.chambers * (L.wall + L.cavity)) return 0;
  const bool cavity = u % (L.wall + L.cavity) >= L.wall && j >= L.wall && j < L.ny - L.wall &&
                      k >= L.base + L.floor && k < L.nz - L.wall;
  return cavity ? 1 : 0;
}

/// The finger with its nominal dimensions whatever the resolution: 16 cavities of 5 mm between
/// 1.5 mm walls (the count at the default res 12), 1.5 mm side walls, roof, floor and base layer,
/// and a 14.5 mm proximal block; grid lines on every one of these dimensions, each part cut into
/// cells of about 20 / res mm, an even number across the cavities' width so that the mid-plane
/// y = 10 is a grid line and the mesh is mirror-symmetric about it.
Mesh DesignGridFingerMesh(int res) {
  const double h = kFingerWidth / res;
  constexpr int kChambers = 16;
  const double pitch = kFingerWall + kFingerCavity;
  const double proximal = kFingerLength - kChambers * pitch - kFingerWall;
  std::vector<double> bx = {0.0, proximal};
  for (int c = 0; c < kChambers; ++c) {
    bx.push_back(proximal + c * pitch + kFingerWall);
    bx.push_back(proximal + (c + 1) * pitch);
  }
  bx.push_back(kFingerLength);
  const double cavity_z0 = kFingerBase + kFingerFloor, cavity_z1 = kFingerHeight - kFingerWall;
  const auto xs = DesignLines(bx, h);
  const auto ys = DesignLines({0.0, kFingerWall, kFingerWidth - kFingerWall, kFingerWidth}, h,
                              {false, true, false});
  const auto zs = DesignLines({0.0, kFingerBase, cavity_z0, cavity_z1, kFingerHeight}, h);
  return RectilinearTetMesh(xs, ys, zs, [&](const Eigen::Vector3d& c, const Eigen::Vector3i&) {
    if (c.z() < kFingerBase) return 2;
    const double u = c.x() - proximal;
    const bool in_row = u > 0 && u < kChambers * pitch;
    const bool cavity = in_row && std::fmod(u, pitch) > kFingerWall && c.y() > kFingerWall &&
                        c.y() < kFingerWidth - kFingerWall && c.z() > cavity_z0 &&
                        c.z() < cavity_z1;
    return cavity ? 1 : 0;
  });
}

Scene MakePneumaticFinger(int res, const RobotParams& P) {
  const FingerLayout L = MakeFingerLayout(res);
  Scene s;
  s.name = "pneumatic_finger";
  s.mesh = DesignGridFlag("pneumatic_finger", P)
               ? DesignGridFingerMesh(res)
               : SymmetricVoxelTetMesh(Eigen::Vector3d::Zero(), L.h,
                                       Eigen::Vector3i(L.nx, L.ny, L.nz), {false, true, false},
                                       [&L](const Eigen::Vector3d&, const Eigen::Vector3i& c) {
                                         return FingerCell(L, c[0], c[1], c[2]);
                                       });
  s.body[0] = Material{"body", kFingerBodyROmega, 1.0};
  s.body[2] = Material{"inextensible", 1.0, kFingerLayerWeight};
  Actuator a;
  a.name = "chamber";
  a.type = ActuatorType::Pneumatic;
  a.regions = {1};
  a.rest = 1.0;
  a.min = 1.0;
  a.max = kFingerMaxAlpha;
  a.weight = P.at("chamber_weight");
  s.actuators.push_back(a);

  const double eps = 1e-6 * L.h;
  const double xmax = s.mesh.vertices.col(0).maxCoeff(), zmax = s.mesh.vertices.col(2).maxCoeff();
  s.fixed = VerticesOnPlane(s.mesh, Eigen::Vector3d::Zero(), Eigen::Vector3d::UnitX(), eps);
  AddDistalFaceMarkers(xmax, zmax, eps, &s);
  s.validate();
  return s;
}

}  // namespace

RobotEntry PneumaticFingerEntry() {
  const RobotInfo info = {
      "pneumatic_finger",
      "PneuNet-style pneumatic bending finger (thesis Fig. 2.11), voxel tet mesh. x = long axis "
      "[0, 120] mm (x = 0 fixed), y = width [0, 20], z = height [0, 15]; inextensible base layer "
      "z in [0, 1.5] (region 2, weight 20), a 1.5 mm floor, a solid proximal block and a row of "
      "5 mm cavities between single 1.5 mm walls (region 0); the filled cavities (region 1) form "
      "one pneumatic actuator 'chamber' (volume ratio in [1, 10]; ~260 degrees of bend at 10). "
      "Markers: tip (distal face x = 120), tip_top / tip_bottom (top / bottom quarter of the "
      "distal face).",
      kFingerDefaultRes,
      "cells across the 20 mm width (cell size 20/res mm), integer in [5, 40]; 27 res^3 tets; "
      "features snap to whole cells (16 chambers at res 12) unless design_grid = 1",
      {{"design_grid", 0.0, 0.0, 1.0,
        "0: features snap to whole cells of 20/res mm (walls, chamber count and proximal block "
        "change with res); 1: grid lines on the nominal dimensions (16 cavities of 5 mm, 1.5 mm "
        "walls, floor and base layer, 14.5 mm proximal block) at every res, mirror-symmetric "
        "about y = 10"},
       ChamberWeightParam()}};
  return {info, kFingerMinRes, kFingerMaxRes, &MakePneumaticFinger};
}

}  // namespace robots_detail
}  // namespace softkin
