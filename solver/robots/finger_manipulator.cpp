/// \file finger_manipulator.cpp
/// finger_manipulator (thesis Sec. 5.3.1, Fig. 5.3b): three finger sections with signed pneumatic
/// actuators.
#include "softkin/solver/robots/robot_parts.hpp"

#include "softkin/solver/mesh/mesh_gen.hpp"

#include <Eigen/Core>

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

namespace softkin {
namespace robots_detail {
namespace {

// ================================================================================================
// finger_manipulator (thesis Sec. 5.3.1, Fig. 5.3b): three finger sections joined rigidly, each
// with two opposite rows of chambers; one signed actuation value per section.
//
// Axes: x = long axis (x = 0 fixed), y = width [0, 20], z = thickness [0, 12]; the motion is planar
// in x-y. Layout (mm, snapped to cells of h = 20 / res): a 6 mm base block; then three 40 mm
// sections, the first two followed by a 6 mm connector (region 8, weight 20: rigid joints); a
// 3 mm tip cap. In each section, a central spine along x (region 7, inextensible, weight 20; the
// cells between the two cavity rows) and two rows of 4 mm cavities between 1.5 mm walls, one on
// the +y side (region 1 + 2 s), one on the -y side (region 2 + 2 s), 1.5 mm side walls, floor and
// roof (region 0). Section s is the signed pneumatic actuator "s<s+1>": value v in [-3, 3]
// (the thesis's pressure in bar, its sign picking the side); v > 0 drives the +y chambers to
// volume ratio 1 + gain v and bends the section towards -y, v < 0 the -y chambers and bends it
// towards +y. The thesis's sections bend up to 120 degrees; this geometric model reaches less.
// At the defaults (gain 4, chamber weight 20) section 1 turns at v = 3 by 43 / 75 / 97 degrees
// at res 6 / 8 / 12: walls snap to whole cells (3.3 / 2.5 / 1.7 mm for the 1.5 mm design), and
// thinner walls let the chambers grow more (at res 8 they reach volume ratio 9.9 of the 13
// asked: the actuation elements are soft constraints, Eq. 2.10, held back by the rigid walls,
// floor and roof). With the thesis's weight 5 and gain 2 it is 41 degrees at res 8. A
// PneuNet-style variant with gaps between the chamber boxes did not bend more (50). The mesh is
// mirror-symmetric about y = 10, so v and -v give mirror images, and about its mid-thickness, so
// the motion stays in x-y (an odd count of cells across either plane is cut into one more).
// Markers: tip (distal face x = L), j1, j2 (the connectors' distal faces: the ends of sections 1
// and 2). With design_grid = 1 the grid lines sit on the nominal dimensions instead, at any res
// (DesignGridManipulatorMesh; docs/fidelity.md has what it changes, and that it still does not
// converge under refinement).
// ================================================================================================

constexpr int kManipMinRes = 6, kManipMaxRes = 24, kManipDefaultRes = 8;
constexpr double kManipWidth = 20.0, kManipThick = 12.0, kManipBase = 6.0, kManipSection = 40.0,
                 kManipJoint = 6.0, kManipCap = 3.0, kManipWall = 1.5, kManipCavity = 4.0,
                 kManipSpine = 3.0, kManipGain = 4.0, kManipRange = 3.0, kManipChamberWeight = 20.0;

/// The scene around a manipulator mesh (regions as in the layout above): materials, the three
/// signed actuators, the fixed base face and the markers (tip; j1, j2 at x = joint_end[q]).
Scene FinishManipulator(const RobotParams& P, Mesh mesh, const double joint_end[2]) {
  Scene s;
  s.name = "finger_manipulator";
  s.mesh = std::move(mesh);
  s.body[0] = Material{"body", P.at("body_r_omega"), 1.0};
  s.body[7] = Material{"spine", 1.0, P.at("spine_weight")};
  s.body[8] = Material{"joint", 1.0, 20.0};
  const double gain = P.at("gain");
  for (int q = 0; q < 3; ++q) {
    Actuator a;
    a.name = "s" + std::to_string(q + 1);
    a.type = ActuatorType::Pneumatic;
    a.regions = {1 + 2 * q};
    a.negative_regions = {2 + 2 * q};
    a.gain = gain;
    a.weight = P.at("chamber_weight");
    a.rest = 0.0;
    a.min = -kManipRange;
    a.max = kManipRange;
    s.actuators.push_back(a);
  }
  const double xmax = s.mesh.vertices.col(0).maxCoeff(), eps = 1e-9 * xmax;
  s.fixed = VerticesOnPlane(s.mesh, Eigen::Vector3d::Zero(), Eigen::Vector3d::UnitX(), eps);
  s.markers.push_back(
      {"tip", VerticesOnPlane(s.mesh, Eigen::Vector3d(xmax, 0, 0), Eigen::Vector3d::UnitX(), eps)});
  for (int q = 0; q < 2; ++q)
    s.markers.push_back(
        {"j" + std::to_string(q + 1), VerticesOnPlane(s.mesh, Eigen::Vector3d(joint_end[q], 0, 0),
                                                      Eigen::Vector3d::UnitX(), eps)});
  s.validate();
  return s;
}

/// The design's dimensions along x (mm): the base block, then per section its solid proximal part
/// and chamber row, then the connector; the cap. Section q spans [x0[q], x0[q] + 40); its row
/// holds as many 4 mm cavities between 1.5 mm walls as fit after a solid part of one wall, ending
/// in a wall (6 cavities, from x0 + 5.5), as MakeChamberRow does in cells.
struct ManipDesign {
  double x0[3], first[3], joint_end[2];  // mm; joint_end: the connectors' distal faces
  int chambers = 0;
  double length = 0.0;
};
ManipDesign MakeManipDesign() {
  ManipDesign d;
  const double pitch = kManipWall + kManipCavity;
  d.chambers = static_cast<int>(std::floor((kManipSection - 2 * kManipWall) / pitch + 1e-9));
  double x = kManipBase;
  for (int q = 0; q < 3; ++q) {
    d.x0[q] = x;
    d.first[q] = x + kManipSection - d.chambers * pitch - kManipWall;
    x += kManipSection;
    if (q < 2) {
      x += kManipJoint;
      d.joint_end[q] = x;
    }
  }
  d.length = x + kManipCap;
  return d;
}

/// The manipulator with its nominal dimensions at every resolution (grid lines on each of them,
/// parts cut into cells of about 20 / res mm; an even count across the spine, so y = 10 is a
/// grid line and the mesh is mirror-symmetric about it, and an even count between the floor and
/// the roof, so it is mirror-symmetric about z = 6 too): 1.5 mm walls, floor and roof, 4 mm
/// cavities, 7 mm wide chamber rows beside a 3 mm spine.
Mesh DesignGridManipulatorMesh(int res, const ManipDesign& d) {
  const double h = kManipWidth / res, pitch = kManipWall + kManipCavity;
  const double side = 0.5 * (kManipWidth - 2 * kManipWall - kManipSpine);
  const double y1 = kManipWall, y2 = kManipWall + side, y3 = y2 + kManipSpine, y4 = y3 + side;
  std::vector<double> bx = {0.0};
  for (int q = 0; q < 3; ++q) {
    bx.push_back(d.x0[q]);
    for (int c = 0; c < d.chambers; ++c) {
      bx.push_back(d.first[q] + c * pitch);
      bx.push_back(d.first[q] + c * pitch + kManipWall);
    }
    bx.push_back(d.first[q] + d.chambers * pitch);
    bx.push_back(d.x0[q] + kManipSection);
  }
  bx.push_back(d.length);
  bx.erase(
      std::unique(bx.begin(), bx.end(), [](double a, double b) { return std::abs(a - b) < 1e-9; }),
      bx.end());
  const auto xs = DesignLines(bx, h);
  const auto ys = DesignLines({0.0, y1, y2, y3, y4, kManipWidth}, h, {false, false, true});
  // An even count between the floor and the roof: the mirrored voxel split (mesh_gen.hpp) is then
  // symmetric about the mid-thickness z = 6, so the motion stays in its plane (with an odd
  // count every tet leans one way and the tip left the plane by up to 1.6 mm).
  const auto zs = DesignLines({0.0, kManipWall, kManipThick - kManipWall, kManipThick}, h,
                              {false, true, false});
  return RectilinearTetMesh(xs, ys, zs, [&](const Eigen::Vector3d& c, const Eigen::Vector3i&) {
    for (int q = 0; q < 2; ++q)
      if (c.x() > d.joint_end[q] - kManipJoint && c.x() < d.joint_end[q]) return 8;
    for (int q = 0; q < 3; ++q) {
      if (c.x() < d.x0[q] || c.x() > d.x0[q] + kManipSection) continue;
      const double u = c.x() - d.first[q];
      const bool cavity = u > 0 && u < d.chambers * pitch && std::fmod(u, pitch) > kManipWall &&
                          c.z() > kManipWall && c.z() < kManipThick - kManipWall;
      if (cavity && c.y() > y1 && c.y() < y2) return 2 + 2 * q;  // -y side
      if (cavity && c.y() > y3 && c.y() < y4) return 1 + 2 * q;  // +y side
      if (c.y() > y2 && c.y() < y3 && u > 0) return 7;           // spine
      return 0;
    }
    return 0;
  });
}

Scene MakeFingerManipulator(int res, const RobotParams& P) {
  if (DesignGridFlag("finger_manipulator", P)) {
    const ManipDesign d = MakeManipDesign();
    return FinishManipulator(P, DesignGridManipulatorMesh(res, d), d.joint_end);
  }
  const double h = kManipWidth / res;
  const int ny = res, nz = static_cast<int>(std::lround(kManipThick / h));
  const int wall = Cells(kManipWall, h), cav = Cells(kManipCavity, h);
  const int side_cav = std::max(1, (ny - 2 * wall - Cells(kManipSpine, h)) / 2);
  const int base = Cells(kManipBase, h), sec = Cells(kManipSection, h),
            joint = Cells(kManipJoint, h), cap = Cells(kManipCap, h);
  const int nx = base + 3 * sec + 2 * joint + cap;
  if (nz < 2 * wall + 1 || ny < 2 * wall + 2 * side_cav + 1)
    throw std::invalid_argument("finger_manipulator: res " + std::to_string(res) + " too coarse");
  std::vector<ChamberRow> rows;
  std::vector<std::pair<int, int>> joints;
  int x = base;
  for (int q = 0; q < 3; ++q) {
    rows.push_back(MakeChamberRow(x, x + sec, wall, cav, wall));
    x += sec;
    if (q < 2) {
      joints.emplace_back(x, x + joint);
      x += joint;
    }
  }
  auto cell = [&](const Eigen::Vector3d&, const Eigen::Vector3i& c) {
    const int i = c[0], j = c[1], k = c[2];
    for (const auto& jt : joints)
      if (i >= jt.first && i < jt.second) return 8;
    for (int q = 0; q < 3; ++q) {
      const ChamberRow& r = rows[q];
      if (i < r.x0 || i >= r.x1) continue;
      const bool zin = k >= wall && k < nz - wall;
      if (InCavity(r, i) && zin) {
        if (j >= wall && j < wall + side_cav) return 2 + 2 * q;            // -y side
        if (j >= ny - wall - side_cav && j < ny - wall) return 1 + 2 * q;  // +y side
      }
      if (j >= wall + side_cav && j < ny - wall - side_cav && i >= r.first) return 7;  // spine
      return 0;
    }
    return 0;
  };
  const double joint_end[2] = {joints[0].second * h, joints[1].second * h};
  // Mirror-symmetric about y = 10 and about the mid-thickness: an odd count of cells across either
  // plane (res across the width at odd res; 5 layers through the thickness at the default res 8,
  // 7 at res 12) is cut into one more, of equal size (SymmetricVoxelTetMesh). With the odd count
  // every tet leaned one way and the tip left its plane (2.6 mm at s1 = 0.5 at res 8, 5.6 mm at s1
  // = 3). Cutting only the middle layer in two was measured too: its half-height tets folded, 72
  // inverted elements at s1 = 3 with the thesis's weight 5 and gain 2, where the equal layers have
  // none.
  return FinishManipulator(
      P,
      SymmetricVoxelTetMesh(Eigen::Vector3d::Zero(), h, Eigen::Vector3i(nx, ny, nz),
                            {false, true, true}, cell),
      joint_end);
}

}  // namespace

RobotEntry FingerManipulatorEntry() {
  const RobotInfo info = {
      "finger_manipulator",
      "Planar finger manipulator (thesis Sec. 5.3.1): three 40 mm finger sections joined by rigid "
      "6 mm connectors; x = long axis (x = 0 fixed), y = width [0, 20], z = thickness [0, 12]; "
      "planar motion in x-y. Each section has a row of chambers on each side of a central "
      "inextensible spine; its signed pneumatic actuator s1, s2, s3 takes a value in [-3, 3]: "
      "v > 0 inflates the +y chambers to volume ratio 1 + gain v (bending towards -y), v < 0 the "
      "-y chambers. Redundant: m = 3, n = 2. Markers: tip, j1, j2 (ends of sections 1 and 2).",
      kManipDefaultRes,
      "cells across the 20 mm width (cell size 20/res mm), integer in [6, 24]",
      {{"gain", kManipGain, 0.1, 10.0,
        "volume ratio per unit of actuation: a chamber side reaches 1 + gain |v|"},
       {"spine_weight", 20.0, 0.01, 100.0, "element weight of the central spine"},
       {"chamber_weight", kManipChamberWeight, 0.01, 100.0,
        "element weight of the chambers' actuation elements"},
       {"body_r_omega", 1.0, 0.0, 1.0, "R_omega of the body material (walls, floor, roof)"},
       {"design_grid", 0.0, 0.0, 1.0,
        "0: features snap to whole cells of 20/res mm (walls and cavities change with res; an odd "
        "count of cells across a mirror plane is cut into one more); 1: grid lines on the nominal "
        "dimensions (1.5 mm walls, floor and roof, six 4 mm "
        "cavities per section, 3 mm spine) at every res, mirror-symmetric about y = 10 and z = "
        "6"}}};
  return {info, kManipMinRes, kManipMaxRes, &MakeFingerManipulator};
}

}  // namespace robots_detail
}  // namespace softkin
