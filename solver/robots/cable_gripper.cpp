/// \file cable_gripper.cpp
/// cable_gripper (thesis Fig. 2.9): a cable-driven gripper finger of two materials.
#include "softkin/solver/robots/robot_parts.hpp"

#include "softkin/solver/mesh/mesh_gen.hpp"

#include <Eigen/Core>

#include <algorithm>
#include <cmath>
#include <string>

namespace softkin {
namespace robots_detail {
namespace {

// ================================================================================================
// cable_gripper (thesis Fig. 2.9): a cable-driven gripper finger whose body alternates two
// materials, links and joints; the two material distributions of Fig. 2.9 are two choices of
// their parameters (uniform vs stiff links with soft joints: experiments/fig2_9_multimaterial).
//
// Axes: x = long axis [0, 100] (x = 0 fixed), y = width [0, 20], z = height [0, 20]; planar motion
// in x-z. The cable channel is the top strip z in [16, 20] for x >= 10 (region 1, the actuation
// elements of cable "cable", shortening ratio in [0.5, 1]); its path runs along x at the strip's
// mid-height from x = 10 to the tip, so L_R = 0. Below it, the body alternates 10 mm links
// (region 0) and 5 mm joints (region 2), starting with a 10 mm link at the fixed end. Parameters:
// each material's weight and R_omega. Markers (Fig. 2.9's three boundary markers): m1, m2, m3 on
// the bottom face (z = 0, mid-width) at x = 40, 70 and 100; tip (distal face).
// ================================================================================================

constexpr int kCgMinRes = 4, kCgMaxRes = 24, kCgDefaultRes = 8;
constexpr double kCgLength = 100.0, kCgWidth = 20.0, kCgHeight = 20.0, kCgChannel = 16.0,
                 kCgStart = 10.0, kCgLink = 10.0, kCgJoint = 5.0;

Scene MakeCableGripper(int res, const RobotParams& P) {
  const double h = kCgWidth / res;
  const int nx = static_cast<int>(std::lround(kCgLength / h)),
            nz = static_cast<int>(std::lround(kCgHeight / h));
  auto cell = [&](const Eigen::Vector3d& c, const Eigen::Vector3i&) {
    if (c.z() > kCgChannel && c.x() > kCgStart) return 1;
    const double u = std::fmod(c.x(), kCgLink + kCgJoint);
    return u < kCgLink ? 0 : 2;
  };
  Scene s;
  s.name = "cable_gripper";
  s.mesh = SymmetricVoxelTetMesh(Eigen::Vector3d::Zero(), h, Eigen::Vector3i(nx, res, nz),
                                 {false, true, false}, cell);
  s.body[0] = Material{"link", P.at("link_r_omega"), P.at("link_weight")};
  s.body[2] = Material{"joint", P.at("joint_r_omega"), P.at("joint_weight")};
  // The channel cells actually present (snapped): the path spans them at their mid-height.
  const double zlo = std::ceil(kCgChannel / h - 0.5) * h, zmax = nz * h, xmax = nx * h;
  const double x0 = std::ceil(kCgStart / h - 0.5) * h;
  Actuator a;
  a.name = "cable";
  a.type = ActuatorType::Cable;
  a.regions = {1};
  a.rest = a.max = 1.0;
  a.min = 0.5;
  a.path = {Eigen::Vector3d(x0, 0.5 * kCgWidth, 0.5 * (zlo + zmax)),
            Eigen::Vector3d(xmax, 0.5 * kCgWidth, 0.5 * (zlo + zmax))};
  s.actuators.push_back(a);
  const double eps = 1e-6 * h;
  s.fixed = VerticesOnPlane(s.mesh, Eigen::Vector3d::Zero(), Eigen::Vector3d::UnitX(), eps);
  s.markers.push_back(
      {"tip", VerticesOnPlane(s.mesh, Eigen::Vector3d(xmax, 0, 0), Eigen::Vector3d::UnitX(), eps)});
  for (int q = 0; q < 3; ++q) {
    const double xm = std::min(xmax, 40.0 + 30.0 * q);
    s.markers.push_back({"m" + std::to_string(q + 1),
                         {NearestVertex(s.mesh, Eigen::Vector3d(xm, 0.5 * kCgWidth, 0.0))}});
  }
  s.validate();
  return s;
}

}  // namespace

RobotEntry CableGripperEntry() {
  const RobotInfo info = {
      "cable_gripper",
      "Cable-driven gripper finger of two materials (thesis Fig. 2.9): 100 x 20 x 20 mm, x = long "
      "axis (x = 0 fixed), planar motion in x-z; a cable channel along the top (z >= 16, cable "
      "'cable', shortening ratio in [0.5, 1]) over a body of alternating 10 mm links (region 0) "
      "and 5 mm joints (region 2). Markers: tip, m1, m2, m3 (bottom face at x = 40, 70, 100).",
      kCgDefaultRes,
      "cells across the 20 mm width (cell size 20/res mm), integer in [4, 24]",
      {{"link_weight", 1.0, 1e-3, 1e3, "element weight of the links"},
       {"joint_weight", 1.0, 1e-3, 1e3, "element weight of the joints"},
       {"link_r_omega", 1.0, 0.0, 1.0, "R_omega of the links"},
       {"joint_r_omega", 1.0, 0.0, 1.0, "R_omega of the joints"}}};
  return {info, kCgMinRes, kCgMaxRes, &MakeCableGripper};
}

}  // namespace robots_detail
}  // namespace softkin
