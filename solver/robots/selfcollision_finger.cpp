/// \file selfcollision_finger.cpp
/// selfcollision_finger (thesis Sec. 3.4.2, Fig. 3.9-3.10): a PneuNet finger with slits between its
/// chambers, whose walls press on each other as they swell.
#include "softkin/solver/robots/robot_parts.hpp"

#include "softkin/solver/materials/hyperelastic.hpp"
#include "softkin/solver/mesh/mesh_gen.hpp"

#include <Eigen/Core>

#include <cmath>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

namespace softkin {
namespace robots_detail {
namespace {

// ================================================================================================
// selfcollision_finger (thesis Sec. 3.4.2, Fig. 3.9-3.10): a PneuNet finger as it is moulded, with
// an air gap between neighbouring chambers, so that the chamber walls meet as the chambers swell.
//
// Axes as pneumatic_finger: x = long axis [0, 120] (x = 0 fixed), y = width [0, 20], z = height
// [0, 15]; inextensible base layer z in [0, 1.5] (region 2), a 1.5 mm floor (region 0), a solid
// proximal block, then `chambers` units along x, each a closed box of 1.5 mm walls (region 0)
// around a 5 mm cavity (region 1, one pneumatic actuator "chamber", volume ratio in [1, 6]),
// separated above the floor by 0.2 mm slits (the mesh is cut there: the distal side's vertices
// are doubled and moved 0.2 mm), so neighbouring walls press on each other as soon as the
// chambers swell, as in a moulded PneuNet. Body material: first-order
// Mooney-Rivlin (Eq. 3.6-3.7) of Ecoflex 00-30 (parameter material = 0) or Dragon Skin 20
// (material = 1); the element weight is the material's initial shear modulus
// mu = 2 (c1 + c2) relative to Ecoflex 00-30's (Dragon Skin 20: 2.71, "around 3 times stiffer").
// Snapped to cells of h = 20 / res mm (every feature >= 1 cell), or, with design_grid = 1, on grid
// lines at the design's dimensions, so that the walls keep their thickness at every res.
// ================================================================================================

constexpr int kScfMinRes = 5, kScfMaxRes = 32, kScfDefaultRes = 8;
constexpr double kScfGap = 0.2, kScfCavity = 5.0, kScfMaxAlpha = 6.0;

/// Initial shear modulus 2 (c1 + c2) of a named Mooney-Rivlin material, MPa.
double ShearModulus(const std::string& named) {
  MooneyRivlin mr;
  if (!NamedMooneyRivlin(named, &mr))
    throw std::logic_error("unknown built-in material '" + named + "'");
  return 2.0 * (mr.c1 + mr.c2);
}

/// The finger's mesh before its slits are cut, and where they go: the planes x = slits[q] between
/// neighbouring chambers, above z = z_floor.
struct ScfMesh {
  Mesh mesh;
  std::vector<double> slits;
  double z_floor = 0;
};

/// Features snapped to whole cells of h (design_grid = 0): the wall thickness, the chamber count
/// and the proximal block change with res.
ScfMesh SnappedScfMesh(double h, double wall_mm) {
  const int ny = static_cast<int>(std::lround(kFingerWidth / h)),
            nz = static_cast<int>(std::lround(kFingerHeight / h));
  const int base = Cells(kFingerBase, h), floor = Cells(kFingerFloor, h), wall = Cells(wall_mm, h);
  const int cavity = Cells(kScfCavity, h);
  const int pitch = 2 * wall + cavity;
  const int nx = static_cast<int>(std::lround(kFingerLength / h));
  const int chambers = (nx - Cells(kFingerProximal, h)) / pitch;
  const int proximal = nx - chambers * pitch;
  auto cell = [&](const Eigen::Vector3d&, const Eigen::Vector3i& c) {
    const int i = c[0], j = c[1], k = c[2];
    if (k < base) return 2;
    if (k < base + floor || i < proximal) return 0;
    const int w = (i - proximal) % pitch;
    const bool inside =
        w >= wall && w < wall + cavity && j >= wall && j < ny - wall && k < nz - wall;
    return inside ? 1 : 0;
  };
  ScfMesh out;
  out.mesh = SymmetricVoxelTetMesh(Eigen::Vector3d::Zero(), h, Eigen::Vector3i(nx, ny, nz),
                                   {false, true, false}, cell);
  for (int q = 1; q < chambers; ++q) out.slits.push_back((proximal + q * pitch) * h);
  out.z_floor = (base + floor) * h;
  return out;
}

/// Grid lines on the design's dimensions (design_grid = 1): walls of wall_mm, 5 mm cavities, as
/// many chambers as fit after an 8 mm proximal block, the 1.5 mm base layer and floor, each part
/// cut into cells of about h, an even number across the cavities' width (mirror symmetry about
/// y = 10).
ScfMesh DesignGridScfMesh(double h, double wall) {
  const double pitch = 2 * wall + kScfCavity;
  const int chambers = static_cast<int>((kFingerLength - kFingerProximal) / pitch);
  const double proximal = kFingerLength - chambers * pitch;
  std::vector<double> bx = {0.0};
  for (int q = 0; q < chambers; ++q) {
    const double x0 = proximal + q * pitch;
    bx.insert(bx.end(), {x0, x0 + wall, x0 + wall + kScfCavity});
  }
  bx.push_back(kFingerLength);
  const double z_floor = kFingerBase + kFingerFloor, roof = kFingerHeight - wall;
  const auto xs = DesignLines(bx, h);
  const auto ys =
      DesignLines({0.0, wall, kFingerWidth - wall, kFingerWidth}, h, {false, true, false});
  const auto zs = DesignLines({0.0, kFingerBase, z_floor, roof, kFingerHeight}, h);
  ScfMesh out;
  out.mesh = RectilinearTetMesh(xs, ys, zs, [&](const Eigen::Vector3d& c, const Eigen::Vector3i&) {
    if (c.z() < kFingerBase) return 2;
    if (c.z() < z_floor || c.x() < proximal) return 0;
    const double w = std::fmod(c.x() - proximal, pitch);
    const bool inside = w > wall && w < wall + kScfCavity && c.y() > wall &&
                        c.y() < kFingerWidth - wall && c.z() < roof;
    return inside ? 1 : 0;
  });
  for (int q = 1; q < chambers; ++q) out.slits.push_back(proximal + q * pitch);
  out.z_floor = z_floor;
  return out;
}

Scene MakeSelfCollisionFinger(int res, const RobotParams& P) {
  const double h = kFingerWidth / res;
  ScfMesh m = DesignGridFlag("selfcollision_finger", P) ? DesignGridScfMesh(h, P.at("wall"))
                                                        : SnappedScfMesh(h, P.at("wall"));
  Mesh& mesh = m.mesh;
  // Cut the slits: above the floor, the vertices on the plane between two chambers are doubled,
  // the copies taken by the tets on the distal side and moved kScfGap along +x (distal first).
  const double tol = 1e-6 * h;
  for (auto it = m.slits.rbegin(); it != m.slits.rend(); ++it) {
    const double xs = *it;
    CutSlit(
        &mesh,
        [&](const Eigen::Vector3d& p) {
          return std::abs(p.x() - xs) < tol && p.z() > m.z_floor + tol;
        },
        [&](const Eigen::Vector3d& c) { return c.x() > xs; }, Eigen::Vector3d(kScfGap, 0, 0));
  }
  Scene s;
  s.name = "selfcollision_finger";
  s.mesh = std::move(mesh);
  const bool dragon = P.at("material") >= 0.5;
  const std::string named = dragon ? "dragon-skin-20" : "ecoflex-00-30";
  const double weight = ShearModulus(named) / ShearModulus("ecoflex-00-30");
  s.body[0] = MooneyRivlinMaterial(named, named, weight);
  s.body[2] = Material{"inextensible", 1.0, kFingerLayerWeight * weight};
  Actuator a;
  a.name = "chamber";
  a.type = ActuatorType::Pneumatic;
  a.regions = {1};
  a.rest = a.min = 1.0;
  a.max = kScfMaxAlpha;
  s.actuators.push_back(a);
  const double eps = 1e-6 * h;
  s.fixed = VerticesOnPlane(s.mesh, Eigen::Vector3d::Zero(), Eigen::Vector3d::UnitX(), eps);
  AddDistalFaceMarkers(s.mesh.vertices.col(0).maxCoeff(), s.mesh.vertices.col(2).maxCoeff(), eps,
                       &s);
  s.solver.collision.self = true;
  s.validate();
  return s;
}

}  // namespace

RobotEntry SelfCollisionFingerEntry() {
  const RobotInfo info = {
      "selfcollision_finger",
      "PneuNet finger with 0.2 mm slits between its chambers, whose walls press on each other as "
      "they swell "
      "(thesis Sec. 3.4.2, Fig. 3.9-3.10): 120 x 20 x 15 mm, x = long axis (x = 0 fixed), "
      "inextensible base layer (region 2), Mooney-Rivlin body (region 0; material 0 = Ecoflex "
      "00-30, 1 = Dragon Skin 20, weighted by shear modulus), cavities (region 1) = pneumatic "
      "actuator 'chamber' (volume ratio in [1, 6]). Self-collision response on. Markers: tip, "
      "tip_top, tip_bottom.",
      kScfDefaultRes,
      "cells across the 20 mm width (cell size 20/res mm), integer in [5, 32]",
      {{"material", 0.0, 0.0, 1.0, "0: Ecoflex 00-30, 1: Dragon Skin 20 (rounded)"},
       {"wall", kFingerWall, 1.0, 5.0,
        "chamber wall thickness, mm, snapped to whole cells (at least one) unless design_grid = 1: "
        "one tet layer at the default 1.5 mm, whose walls invert under contact on fine meshes "
        "(docs/collision_response.md)"},
       {"design_grid", 0.0, 0.0, 1.0,
        "0: features snap to whole cells of 20/res mm (the walls' thickness and the chamber count "
        "change with res); 1: grid lines on the design's dimensions (walls of `wall` mm, 5 mm "
        "cavities, 1.5 mm base layer and floor) at every res, mirror-symmetric about y = 10"}}};
  return {info, kScfMinRes, kScfMaxRes, &MakeSelfCollisionFinger};
}

}  // namespace robots_detail
}  // namespace softkin
