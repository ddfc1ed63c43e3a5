/// \file cable_finger.cpp
/// cable_finger (thesis Fig. 2.8, Fig. 4.1): a four-tooth finger closed by three tendons.
#include "softkin/solver/robots/robot_parts.hpp"

#include "softkin/solver/mesh/mesh_gen.hpp"

#include <Eigen/Core>

#include <cmath>
#include <stdexcept>
#include <string>
#include <vector>

namespace softkin {
namespace robots_detail {
namespace {

// ================================================================================================
// cable_finger (thesis Fig. 2.8, Fig. 4.1): a 120 x 25 x 25 mm finger of four teeth on a
// continuous base, with three knuckles (the gaps between teeth) each pulled by its own tendon.
//
// Axes: x = long axis (x = 0 fixed, tip face x = 120), y = width [0, 25], z = height [0, 25];
// motion is planar in x-z. Layout (mm): base z in [0, 5] along the whole length (body); teeth
// z in [5, 25] at x in [0, 15], [25, 50], [60, 85], [95, 120] (body); knuckle k (k = 1, 2, 3) is
// the gap x in [15, 25], [50, 60], [85, 95]. In each gap the cable bridge z in [17.5, 25], full
// width, holds the cable's actuation elements (region k, actuator "t<k>"); the rest of the gap
// is empty, so the thin base under it is the flexure that bends.
// How a tendon is tied to the mesh: tendon k runs straight along x through its bridge, at the
// bridge's mid-height, from one tooth to the next (the segment anchored in the two teeth), so its
// path lies entirely in its actuation elements: L = sum l_i = 10 mm and L_R = 0. Shortening it to
// s L shortens the bridge along x, pulls the teeth's tops together and closes the knuckle: the
// shortened top side becomes the concave one and the tip curls up, towards +z. Range s in
// [0.5, 1] (rest 1): up to 50 % shortening.
// Resolution: cells across the 25 mm width (cell size 25/res); features snap to the cells whose
// centres they contain. With design_grid = 1 the grid lines sit on the design's dimensions
// instead (the teeth, gaps, base and bridge floor), each part cut into cells of about 25/res mm
// and an even number across the width, so the knuckles, bridges and base are the same at every
// res and the mesh is mirror-symmetric about y = 12.5.
// ================================================================================================

constexpr int kCableMinRes = 5, kCableMaxRes = 30, kCableDefaultRes = 10;
constexpr double kCableLength = 120.0, kCableWidth = 25.0, kCableHeight = 25.0;
constexpr double kCableBase = 5.0, kCableBridgeFloor = 17.5;
constexpr double kCableGaps[3][2] = {{15.0, 25.0}, {50.0, 60.0}, {85.0, 95.0}};
constexpr double kCableMinShortening = 0.5;

/// Region of the cell whose centre is (x, z): the base and teeth 0, bridge k + 1, else empty.
int CableCell(double x, double z) {
  if (z < kCableBase) return 0;
  for (int k = 0; k < 3; ++k)
    if (x > kCableGaps[k][0] && x < kCableGaps[k][1]) return z > kCableBridgeFloor ? k + 1 : -1;
  return 0;
}

Scene MakeCableFinger(int res, const RobotParams& P) {
  const double h = kCableWidth / res;
  Scene s;
  s.name = "cable_finger";
  if (DesignGridFlag("cable_finger", P)) {
    std::vector<double> bx = {0.0};
    for (const auto& gap : kCableGaps) bx.insert(bx.end(), {gap[0], gap[1]});
    bx.push_back(kCableLength);
    s.mesh = RectilinearTetMesh(
        DesignLines(bx, h), DesignLines({0.0, kCableWidth}, h, {true}),
        DesignLines({0.0, kCableBase, kCableBridgeFloor, kCableHeight}, h),
        [](const Eigen::Vector3d& c, const Eigen::Vector3i&) { return CableCell(c.x(), c.z()); });
  } else {
    const int nx = static_cast<int>(std::lround(kCableLength / h));
    const int nz = static_cast<int>(std::lround(kCableHeight / h));
    s.mesh = SymmetricVoxelTetMesh(Eigen::Vector3d::Zero(), h, Eigen::Vector3i(nx, res, nz),
                                   {false, true, false},
                                   [&](const Eigen::Vector3d&, const Eigen::Vector3i& c) {
                                     return CableCell((c[0] + 0.5) * h, (c[2] + 0.5) * h);
                                   });
  }
  s.body[0] = Material{"body", 1.0, 1.0};
  // The mesh as built (snapped, or on the design lines) decides the far faces and each bridge's
  // box; the tendon spans its bridge along x at the bridge's mid-height.
  Eigen::Array3d lo[3], hi[3];
  for (int k = 0; k < 3; ++k) lo[k].setConstant(kInf), hi[k].setConstant(-kInf);
  for (const Element& e : s.mesh.elements)
    if (e.region > 0)
      for (int j = 0; j < e.k(); ++j) {
        const Eigen::Array3d v = s.mesh.vertices.row(e.v[j]).transpose().array();
        lo[e.region - 1] = lo[e.region - 1].min(v);
        hi[e.region - 1] = hi[e.region - 1].max(v);
      }
  for (int k = 0; k < 3; ++k) {
    if (!(hi[k].x() > lo[k].x()))
      throw std::invalid_argument("cable_finger: knuckle " + std::to_string(k + 1) +
                                  " vanished at res " + std::to_string(res));
    const double zmid = 0.5 * (lo[k].z() + hi[k].z());
    Actuator a;
    a.name = "t" + std::to_string(k + 1);
    a.type = ActuatorType::Cable;
    a.regions = {k + 1};
    a.rest = 1.0;
    a.min = kCableMinShortening;
    a.max = 1.0;
    a.path = {Eigen::Vector3d(lo[k].x(), 0.5 * kCableWidth, zmid),
              Eigen::Vector3d(hi[k].x(), 0.5 * kCableWidth, zmid)};
    s.actuators.push_back(a);
  }
  const double eps = 1e-6 * h;
  s.fixed = VerticesOnPlane(s.mesh, Eigen::Vector3d::Zero(), Eigen::Vector3d::UnitX(), eps);
  AddDistalFaceMarkers(s.mesh.vertices.col(0).maxCoeff(), s.mesh.vertices.col(2).maxCoeff(), eps,
                       &s);
  s.validate();
  return s;
}

}  // namespace

RobotEntry CableFingerEntry() {
  const RobotInfo info = {
      "cable_finger",
      "Cable-driven finger (thesis Fig. 2.8, Fig. 4.1): 120 x 25 x 25 mm, four teeth on a 5 mm "
      "base; x = long axis (x = 0 fixed), z = height, planar motion in x-z. Three knuckles (gaps "
      "x in [15, 25], [50, 60], [85, 95]) each bridged at the top (z >= 17.5) by the actuation "
      "elements of its own tendon t1, t2, t3 (cable, shortening ratio in [0.5, 1]; regions 1-3; "
      "each tendon's path runs along x through its bridge). Markers: tip (face x = 120), tip_top / "
      "tip_bottom (top / bottom quarter of that face).",
      kCableDefaultRes,
      "cells across the 25 mm width (cell size 25/res mm), integer in [5, 30]; features snap "
      "to whole cells unless design_grid = 1",
      {{"design_grid", 0.0, 0.0, 1.0,
        "0: teeth, gaps, base and bridges snap to whole cells of 25/res mm (their sizes change "
        "with res); 1: grid lines on the nominal dimensions (5 mm base, 10 mm gaps, bridges from "
        "z = 17.5) at every res, mirror-symmetric about y = 12.5"}}};
  return {info, kCableMinRes, kCableMaxRes, &MakeCableFinger};
}

}  // namespace robots_detail
}  // namespace softkin
