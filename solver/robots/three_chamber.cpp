/// \file three_chamber.cpp
/// three_chamber (thesis Fig. 2.12, Chapter 5): a cylinder with three pneumatic chambers.
#include "softkin/solver/robots/robot_parts.hpp"

#include "softkin/solver/mesh/mesh_gen.hpp"

#include <Eigen/Core>

#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

namespace softkin {
namespace robots_detail {
namespace {

// ================================================================================================
// three_chamber (thesis Fig. 2.12, Chapter 5): 48 x 48 x 136 mm cylinder with three chambers.
//
// Axes: y = long axis (base face y = 0, fixed; tip face y = 136), as in the real trajectory data
// (flower_trajectory.txt). The cross-section is the x-z plane; angles phi are measured in it from
// +x towards +z, i.e. phi = atan2(z, x). Chamber k (k = 0, 1, 2; actuator "c<k+1>", region k+1)
// is a cylinder of radius 7 mm around the line at distance 13 mm from the axis at angle
//   phi_k = 180 + 120 k degrees   (c1 on -x, c2 at 300 deg, c3 at 60 deg),
// spanning y in [8, 128]. Rotation by +120 degrees in phi maps chamber k onto chamber k+1.
// Inflating chamber k alone bends the tip away from it, towards phi_k + 180 = 0, 120, 240 deg:
// the three petal directions of the 'flower' trajectory, visited in the order c1, c2, c3.
// Chamber elements are the tets whose centroid lies inside a chamber; tags are assigned on the
// canonical (sector-0) copy of every tet, so the tagging is exactly 3-fold symmetric. The mesh is
// also mirror-symmetric about each chamber's plane (ConcentricDisk), so inflating one chamber, or
// the other two equally, bends the robot in that plane.
// ================================================================================================

constexpr int kThreeMinRes = 3, kThreeMaxRes = 16, kThreeDefaultRes = 7;
constexpr double kThreeRadius = 24.0, kThreeLength = 136.0;
constexpr double kChamberRadius = 7.0, kChamberOffset = 13.0, kChamberY0 = 8.0, kChamberY1 = 128.0;
constexpr double kChamberAngle0 = 180.0;  // degrees, chamber 0 (c1)

/// Two chambers that share a vertex would be one cavity. Where the tagging by centroid puts tets
/// of two chambers on a common vertex (at res 3, on the mirror plane between two chambers), every
/// chamber tet on that vertex stays body: a rule as symmetric as the mesh.
void SeparateChambers(Mesh* mesh) {
  std::vector<int> owner(mesh->num_vertices(), 0);
  std::vector<char> shared(mesh->num_vertices(), 0);
  for (const Element& e : mesh->elements)
    if (e.region != 0)
      for (int j = 0; j < e.k(); ++j) {
        int& o = owner[e.v[j]];
        if (o != 0 && o != e.region) shared[e.v[j]] = 1;
        o = e.region;
      }
  for (Element& e : mesh->elements)
    for (int j = 0; j < e.k() && e.region != 0; ++j)
      if (shared[e.v[j]]) e.region = 0;
}

Scene MakeThreeChamber(int res, const RobotParams& P) {
  const double chamber_radius = P.at("chamber_radius");
  DiskExtrusion p;
  p.radius = kThreeRadius;
  p.rings = res;
  p.length = kThreeLength;
  p.axis = 1;
  p.base = 0.0;
  p.layers = std::max(1, static_cast<int>(std::lround(kThreeLength / (kThreeRadius / res))));
  const double pi = std::acos(-1.0);
  Eigen::Vector2d centre[3];  // (x, z) of each chamber's axis
  for (int k = 0; k < 3; ++k) {
    const double a = (kChamberAngle0 + 120.0 * k) * pi / 180.0;
    centre[k] = kChamberOffset * Eigen::Vector2d(std::cos(a), std::sin(a));
  }
  auto region = [&centre, chamber_radius](const DiskElementInfo& e) {
    const Eigen::Vector3d& c = e.canonical_centroid;
    if (c.y() < kChamberY0 || c.y() > kChamberY1) return 0;
    for (int k = 0; k < 3; ++k)
      if ((Eigen::Vector2d(c.x(), c.z()) - centre[k]).norm() <= chamber_radius)
        return 1 + (k + e.sector) % 3;
    return 0;
  };
  Scene s;
  s.name = "three_chamber";
  s.mesh = ExtrudedDiskTetMesh(p, region);
  SeparateChambers(&s.mesh);
  s.body[0] = Material{"body", 1.0, 1.0};
  for (int k = 0; k < 3; ++k) {
    Actuator a;
    a.name = "c" + std::to_string(k + 1);
    a.type = ActuatorType::Pneumatic;
    a.regions = {k + 1};
    a.rest = 1.0;
    a.min = 1.0;
    a.max = 3.0;
    s.actuators.push_back(a);
  }
  const double eps = 1e-6 * kThreeLength / p.layers;
  s.fixed = VerticesOnPlane(s.mesh, Eigen::Vector3d::Zero(), Eigen::Vector3d::UnitY(), eps);
  s.markers.push_back({"tip", VerticesOnPlane(s.mesh, Eigen::Vector3d(0.0, kThreeLength, 0.0),
                                              Eigen::Vector3d::UnitY(), eps)});
  s.validate();
  return s;
}

}  // namespace

RobotEntry ThreeChamberEntry() {
  const RobotInfo info = {
      "three_chamber",
      "Three-chamber pneumatic actuator (thesis Fig. 2.12, Chapter 5): 48 x 48 x 136 mm cylinder. "
      "y = long axis (y = 0 fixed, tip face y = 136); angles phi = atan2(z, x) in the x-z plane. "
      "Chambers c1, c2, c3 (regions 1-3, pneumatic, volume ratio in [1, 3]): radius 7 mm, 13 mm "
      "from the axis at phi = 180, 300, 60 degrees, y in [8, 128]; body region 0. The mesh is "
      "exactly invariant under rotation by 120 degrees about y (c1 -> c2 -> c3) and under the "
      "mirror z -> -z (c2 <-> c3). Marker: tip "
      "(top face y = 136).",
      kThreeDefaultRes,
      "number of concentric rings of the cross-section disk (radial spacing 24/res mm; layers "
      "along y of about the same size), integer in [3, 16]; ~102 res^3 tets",
      {{"chamber_radius", kChamberRadius, 5.0, 9.0,
        "chamber radius, mm (the outer wall is 24 - 13 - radius thick: 4 mm at the default 7); "
        "chamber elements are the tets whose centroid lies within it"}}};
  return {info, kThreeMinRes, kThreeMaxRes, &MakeThreeChamber};
}

}  // namespace robots_detail
}  // namespace softkin
