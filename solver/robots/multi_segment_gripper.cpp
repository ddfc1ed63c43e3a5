/// \file multi_segment_gripper.cpp
/// multi_segment_gripper (thesis Fig. 4.7): three pneumatic bending segments, the last a gripper.
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
// multi_segment_gripper (thesis Fig. 4.7): three pneumatic bending segments in a row on a common
// inextensible layer; the third segment is the gripper that wraps an object.
//
// Axes: x = long axis (x = 0 fixed), y = width [0, 20], z = height [0, 15]; planar motion in x-z
// (the segments curl towards -z, as pneumatic_finger). Layout (mm, cells of h = 20 / res): an
// 8 mm base block, three 50 mm segments separated by 5 mm connectors (region 5, weight 20); the
// inextensible layer z in [0, 1.5] over the whole length (region 4, weight 20); in segment k, a row
// of 5 mm cavities between 1.5 mm walls over a 1.5 mm floor, with 1.5 mm side walls and roof
// (region 0); its filled cavities are the pneumatic actuator "c<k>" (region k, volume ratio in
// [1, 8]). Markers: tip (distal face), tip_top / tip_bottom, P0 (the distal face of the second
// segment's connector: where the gripper segment starts), grip_layer (the vertices of the third
// segment's inextensible layer, the surface that closes on the object).
// ================================================================================================

constexpr int kGripMinRes = 6, kGripMaxRes = 24, kGripDefaultRes = 8;
constexpr double kGripWidth = 20.0, kGripHeight = 15.0, kGripBase = 8.0, kGripSegment = 50.0,
                 kGripJoint = 5.0, kGripLayer = 1.5, kGripWall = 1.5, kGripCavity = 5.0,
                 kGripMaxAlpha = 8.0;

Actuator PneumaticActuator(const std::string& name, std::vector<int> regions, double max,
                           double weight) {
  Actuator a;
  a.name = name;
  a.type = ActuatorType::Pneumatic;
  a.regions = std::move(regions);
  a.rest = a.min = 1.0;
  a.max = max;
  a.weight = weight;
  return a;
}

std::vector<int> VerticesInXRange(const Mesh& m, double x0, double x1, double zmax_incl) {
  return VerticesInBox(m, Eigen::Vector3d(x0, -kInf, -kInf), Eigen::Vector3d(x1, kInf, zmax_incl));
}

/// Materials, actuators, the fixed face and the markers of a gripper mesh whose third segment
/// (the gripper) starts at x = third_x0: P0 is that plane, grip_layer the layer (z <= layer_z)
/// of the segment, x in [third_x0, xmax].
void FinishGripper(int res, double third_x0, double xmax, double layer_z, double chamber_weight,
                   Scene* s) {
  s->name = "multi_segment_gripper";
  s->body[0] = Material{"body", 1.0, 1.0};
  s->body[4] = Material{"inextensible", 1.0, 20.0};
  s->body[5] = Material{"connector", 1.0, 20.0};
  for (int k = 0; k < 3; ++k)
    s->actuators.push_back(
        PneumaticActuator("c" + std::to_string(k + 1), {k + 1}, kGripMaxAlpha, chamber_weight));
  const double eps = 1e-6 * kGripWidth / res, zmax = s->mesh.vertices.col(2).maxCoeff();
  s->fixed = VerticesOnPlane(s->mesh, Eigen::Vector3d::Zero(), Eigen::Vector3d::UnitX(), eps);
  AddDistalFaceMarkers(xmax, zmax, eps, s);
  s->markers.push_back({"P0", VerticesOnPlane(s->mesh, Eigen::Vector3d(third_x0, 0, 0),
                                              Eigen::Vector3d::UnitX(), eps)});
  s->markers.push_back(
      {"grip_layer", VerticesInXRange(s->mesh, third_x0 - eps, xmax + eps, layer_z + eps)});
  s->validate();
}

/// Chambers per segment with design_grid = 1 (the count the snapped grid has at res 12).
constexpr int kGripDesignChambers = 7;

/// The gripper's x breakpoints and the cell classifier with its nominal dimensions whatever the
/// resolution (design_grid = 1): the 8 mm base block; per segment a 2 mm solid proximal part and
/// 7 cavities of 5 mm between 1.5 mm walls, the last wall closing the segment at 50 mm; 5 mm
/// connectors. Grid lines on every one of these, each part cut into cells of about 20 / res mm,
/// an even number across the cavities' width (mirror-symmetric about y = 10).
Mesh DesignGridGripperMesh(int res) {
  const double h = kGripWidth / res, pitch = kGripWall + kGripCavity;
  const double solid = kGripSegment - kGripDesignChambers * pitch - kGripWall;
  std::vector<double> bx = {0.0}, first;
  for (int k = 0; k < 3; ++k) {
    const double x0 = kGripBase + k * (kGripSegment + kGripJoint);
    bx.push_back(x0);
    first.push_back(x0 + solid);
    for (int c = 0; c < kGripDesignChambers; ++c) {
      bx.push_back(first.back() + c * pitch);
      bx.push_back(first.back() + c * pitch + kGripWall);
    }
    bx.push_back(first.back() + kGripDesignChambers * pitch);  // the closing wall
    bx.push_back(x0 + kGripSegment);
  }
  const double z0 = kGripLayer + kGripWall, z1 = kGripHeight - kGripWall;
  const auto xs = DesignLines(bx, h);
  const auto ys =
      DesignLines({0.0, kGripWall, kGripWidth - kGripWall, kGripWidth}, h, {false, true, false});
  const auto zs = DesignLines({0.0, kGripLayer, z0, z1, kGripHeight}, h);
  return RectilinearTetMesh(xs, ys, zs, [&](const Eigen::Vector3d& c, const Eigen::Vector3i&) {
    if (c.z() < kGripLayer) return 4;
    for (int k = 0; k < 3; ++k) {
      const double x0 = kGripBase + k * (kGripSegment + kGripJoint), x1 = x0 + kGripSegment;
      if (c.x() > x1 && c.x() < x1 + kGripJoint) return 5;
      if (c.x() < x0 || c.x() > x1) continue;
      const double u = c.x() - first[k];
      const bool cavity = u > 0 && u < kGripDesignChambers * pitch &&
                          std::fmod(u, pitch) > kGripWall && c.y() > kGripWall &&
                          c.y() < kGripWidth - kGripWall && c.z() > z0 && c.z() < z1;
      return cavity ? k + 1 : 0;
    }
    return 0;
  });
}

Scene MakeMultiSegmentGripper(int res, const RobotParams& P) {
  if (DesignGridFlag("multi_segment_gripper", P)) {
    // The third segment (the gripper) starts after two segments and their connectors.
    const double third = kGripBase + 2 * (kGripSegment + kGripJoint);
    Scene s;
    s.mesh = DesignGridGripperMesh(res);
    FinishGripper(res, third, s.mesh.vertices.col(0).maxCoeff(), kGripLayer, P.at("chamber_weight"),
                  &s);
    return s;
  }
  const double h = kGripWidth / res;
  const int ny = res, nz = static_cast<int>(std::lround(kGripHeight / h));
  const int wall = Cells(kGripWall, h), cav = Cells(kGripCavity, h), layer = Cells(kGripLayer, h);
  const int base = Cells(kGripBase, h), seg = Cells(kGripSegment, h), joint = Cells(kGripJoint, h);
  const int nx = base + 3 * seg + 2 * joint;
  if (nz < layer + 2 * wall + 1)
    throw std::invalid_argument("multi_segment_gripper: res " + std::to_string(res) +
                                " too coarse");
  std::vector<ChamberRow> rows;
  std::vector<std::pair<int, int>> joints;
  int x = base;
  for (int k = 0; k < 3; ++k) {
    rows.push_back(MakeChamberRow(x, x + seg, wall, cav, wall));
    x += seg;
    if (k < 2) {
      joints.emplace_back(x, x + joint);
      x += joint;
    }
  }
  auto cell = [&](const Eigen::Vector3d&, const Eigen::Vector3i& c) {
    const int i = c[0], j = c[1], kz = c[2];
    if (kz < layer) return 4;
    for (const auto& jt : joints)
      if (i >= jt.first && i < jt.second) return 5;
    for (int k = 0; k < 3; ++k) {
      const ChamberRow& r = rows[k];
      if (i < r.x0 || i >= r.x1) continue;
      if (InCavity(r, i) && j >= wall && j < ny - wall && kz >= layer + wall && kz < nz - wall)
        return k + 1;
      return 0;
    }
    return 0;
  };
  Scene s;
  s.mesh = SymmetricVoxelTetMesh(Eigen::Vector3d::Zero(), h, Eigen::Vector3i(nx, ny, nz),
                                 {false, true, false}, cell);
  FinishGripper(res, rows[2].x0 * h, nx * h, layer * h, P.at("chamber_weight"), &s);
  return s;
}

}  // namespace

RobotEntry MultiSegmentGripperEntry() {
  const RobotInfo info = {
      "multi_segment_gripper",
      "Three-segment pneumatic manipulator-gripper (thesis Fig. 4.7): three 50 mm bending "
      "segments on a common inextensible layer (z in [0, 1.5], weight 20) joined by 5 mm "
      "connectors; x = long axis (x = 0 fixed), y = width [0, 20], z = height [0, 15]; planar "
      "motion in x-z. Pneumatic actuators c1, c2, c3 (volume ratio in [1, 8]). Markers: tip, "
      "tip_top, tip_bottom, P0 (end of the second segment), grip_layer (the third segment's "
      "inextensible layer).",
      kGripDefaultRes,
      "cells across the 20 mm width (cell size 20/res mm), integer in [6, 24]; features snap to "
      "whole cells unless design_grid = 1",
      {{"design_grid", 0.0, 0.0, 1.0,
        "0: features snap to whole cells of 20/res mm (walls, cavities and their count change "
        "with res: 4, 6, 5, 7 chambers per segment at res 6, 8, 10, 12); 1: grid lines on the "
        "nominal dimensions (7 cavities of 5 mm per segment between 1.5 mm walls, 1.5 mm floor, "
        "side walls, roof and layer) at every res, mirror-symmetric about y = 10"},
       ChamberWeightParam()}};
  return {info, kGripMinRes, kGripMaxRes, &MakeMultiSegmentGripper};
}

}  // namespace robots_detail
}  // namespace softkin
