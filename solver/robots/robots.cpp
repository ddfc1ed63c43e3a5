#include "softkin/solver/robots/robots.hpp"
#include "softkin/solver/common/text_format.hpp"

#include "softkin/solver/materials/hyperelastic.hpp"

#include "softkin/solver/mesh/mesh_gen.hpp"
#include "softkin/solver/robots/robot_twisting.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <functional>
#include <limits>
#include <map>
#include <stdexcept>
#include <string>

namespace softkin {

namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();

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

constexpr int kFingerMinRes = 5, kFingerMaxRes = 40, kFingerDefaultRes = 12;
constexpr double kFingerLength = 120.0, kFingerWidth = 20.0, kFingerHeight = 15.0;
constexpr double kFingerBase = 1.5, kFingerFloor = 1.5, kFingerWall = 1.5, kFingerCavity = 5.0;
constexpr double kFingerProximal = 8.0;
/// Weight of the inextensible layer relative to the body: it resists stretching; being one cell
/// thin it still bends.
constexpr double kFingerLayerWeight = 20.0;
constexpr double kFingerBodyROmega = 1.0;
constexpr double kFingerMaxAlpha = 10.0;

/// The finger's layout in cells.
struct FingerLayout {
  double h = 1.0;        // cell size, mm
  int nx = 0, ny = 0, nz = 0;
  int base = 0;          // base layer thickness (cells)
  int floor = 0;         // solid floor between the base layer and the cavities
  int wall = 0;          // walls: between cavities (x), sides (y), roof (z)
  int cavity = 0;        // cavity length (x)
  int chambers = 0;      // number of cavities
  int proximal = 0;      // proximal solid block length
};

int Cells(double mm, double h) { return std::max(1, static_cast<int>(std::lround(mm / h))); }

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

/// Markers of a finger whose distal face is the plane x = xmax: "tip" (the face's centroid),
/// "tip_top" / "tip_bottom" (its top and bottom quarters in z, used for the bend angle).
void AddDistalFaceMarkers(double xmax, double zmax, double eps, Scene* s) {
  const Mesh& m = s->mesh;
  s->markers.push_back({"tip", VerticesInBox(m, Eigen::Vector3d(xmax - eps, -kInf, -kInf),
                                             Eigen::Vector3d(xmax + eps, kInf, kInf))});
  s->markers.push_back(
      {"tip_top", VerticesInBox(m, Eigen::Vector3d(xmax - eps, -kInf, 0.75 * zmax - eps),
                                Eigen::Vector3d(xmax + eps, kInf, kInf))});
  s->markers.push_back(
      {"tip_bottom", VerticesInBox(m, Eigen::Vector3d(xmax - eps, -kInf, -kInf),
                                   Eigen::Vector3d(xmax + eps, kInf, 0.25 * zmax + eps))});
}

Scene MakePneumaticFinger(int res) {
  const FingerLayout L = MakeFingerLayout(res);
  Scene s;
  s.name = "pneumatic_finger";
  s.mesh = VoxelTetMesh(Eigen::Vector3d::Zero(), L.h, Eigen::Vector3i(L.nx, L.ny, L.nz),
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
  s.actuators.push_back(a);

  const double eps = 1e-6 * L.h;
  const double xmax = L.nx * L.h, zmax = L.nz * L.h;
  s.fixed = VerticesOnPlane(s.mesh, Eigen::Vector3d::Zero(), Eigen::Vector3d::UnitX(), eps);
  AddDistalFaceMarkers(xmax, zmax, eps, &s);
  s.validate();
  return s;
}

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
// canonical (sector-0) copy of every tet, so the tagging is exactly 3-fold symmetric.
// ================================================================================================

constexpr int kThreeMinRes = 3, kThreeMaxRes = 16, kThreeDefaultRes = 7;
constexpr double kThreeRadius = 24.0, kThreeLength = 136.0;
constexpr double kChamberRadius = 7.0, kChamberOffset = 13.0, kChamberY0 = 8.0, kChamberY1 = 128.0;
constexpr double kChamberAngle0 = 180.0;  // degrees, chamber 0 (c1)

Scene MakeThreeChamber(int res, double chamber_radius) {
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
// centres they contain.
// ================================================================================================

constexpr int kCableMinRes = 5, kCableMaxRes = 30, kCableDefaultRes = 10;
constexpr double kCableLength = 120.0, kCableWidth = 25.0, kCableHeight = 25.0;
constexpr double kCableBase = 5.0, kCableBridgeFloor = 17.5;
constexpr double kCableGaps[3][2] = {{15.0, 25.0}, {50.0, 60.0}, {85.0, 95.0}};
constexpr double kCableMinShortening = 0.5;

Scene MakeCableFinger(int res) {
  const double h = kCableWidth / res;
  const int nx = static_cast<int>(std::lround(kCableLength / h));
  const int nz = static_cast<int>(std::lround(kCableHeight / h));
  auto cell = [&](const Eigen::Vector3d&, const Eigen::Vector3i& c) {
    const double x = (c[0] + 0.5) * h, z = (c[2] + 0.5) * h;
    if (z < kCableBase) return 0;
    for (int k = 0; k < 3; ++k)
      if (x > kCableGaps[k][0] && x < kCableGaps[k][1]) return z > kCableBridgeFloor ? k + 1 : -1;
    return 0;
  };
  Scene s;
  s.name = "cable_finger";
  s.mesh = VoxelTetMesh(Eigen::Vector3d::Zero(), h, Eigen::Vector3i(nx, res, nz), cell);
  s.body[0] = Material{"body", 1.0, 1.0};
  // Bridge cells actually present (snapped): the path spans them at their mid-height.
  const double zmax = nz * h;
  const double zmid = 0.5 * (std::ceil(kCableBridgeFloor / h - 0.5) * h + zmax);
  for (int k = 0; k < 3; ++k) {
    double x0 = kInf, x1 = -kInf;
    for (int i = 0; i < nx; ++i) {
      const double x = (i + 0.5) * h;
      if (x > kCableGaps[k][0] && x < kCableGaps[k][1]) {
        x0 = std::min(x0, i * h);
        x1 = std::max(x1, (i + 1) * h);
      }
    }
    if (!(x1 > x0))
      throw std::invalid_argument("cable_finger: knuckle " + std::to_string(k + 1) +
                                  " vanished at res " + std::to_string(res));
    Actuator a;
    a.name = "t" + std::to_string(k + 1);
    a.type = ActuatorType::Cable;
    a.regions = {k + 1};
    a.rest = 1.0;
    a.min = kCableMinShortening;
    a.max = 1.0;
    a.path = {Eigen::Vector3d(x0, 0.5 * kCableWidth, zmid), Eigen::Vector3d(x1, 0.5 * kCableWidth, zmid)};
    s.actuators.push_back(a);
  }
  const double eps = 1e-6 * h, xmax = nx * h;
  s.fixed = VerticesOnPlane(s.mesh, Eigen::Vector3d::Zero(), Eigen::Vector3d::UnitX(), eps);
  AddDistalFaceMarkers(xmax, zmax, eps, &s);
  s.validate();
  return s;
}

// ================================================================================================
// Chamber rows shared by the multi-segment robots: along x, a solid proximal part, then cavities
// of `cavity` cells between walls of `wall` cells, the last wall closing the segment.
// ================================================================================================

struct ChamberRow {
  int x0 = 0, x1 = 0;        // the segment's cells [x0, x1)
  int wall = 1, cavity = 1;  // cells
  int first = 0;             // first cavity wall cell (after the solid proximal part)
  int chambers = 0;
};

ChamberRow MakeChamberRow(int x0, int x1, int wall, int cavity, int min_solid) {
  ChamberRow r{x0, x1, wall, cavity, 0, 0};
  const int pitch = wall + cavity;
  r.chambers = std::max(0, (x1 - x0 - min_solid - wall) / pitch);
  r.first = x1 - r.chambers * pitch - wall;
  return r;
}

/// Whether cell column i lies in a cavity of the row.
bool InCavity(const ChamberRow& r, int i) {
  const int u = i - r.first;
  if (u < 0 || u >= r.chambers * (r.wall + r.cavity)) return false;
  return u % (r.wall + r.cavity) >= r.wall;
}

Actuator PneumaticActuator(const std::string& name, std::vector<int> regions, double max) {
  Actuator a;
  a.name = name;
  a.type = ActuatorType::Pneumatic;
  a.regions = std::move(regions);
  a.rest = a.min = 1.0;
  a.max = max;
  return a;
}

std::vector<int> VerticesInXRange(const Mesh& m, double x0, double x1, double zmax_incl) {
  return VerticesInBox(m, Eigen::Vector3d(x0, -kInf, -kInf), Eigen::Vector3d(x1, kInf, zmax_incl));
}

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
// At the defaults (gain 4, chamber weight 20) section 1 turns at v = 3 by 43 / 73 / 95 degrees
// at res 6 / 8 / 12: walls snap to whole cells (3.3 / 2.5 / 1.7 mm for the 1.5 mm design), and
// thinner walls let the chambers grow more (at res 8 they reach volume ratio 9.8 of the 13
// asked: the actuation elements are soft constraints, Eq. 2.10, held back by the rigid walls,
// floor and roof). With the thesis's weight 5 and gain 2 it is 38 degrees at res 8. A
// PneuNet-style variant with gaps between the chamber boxes did not bend more (50). The mesh is mirror-symmetric about y = 10 (res is even), so v and -v give
// mirror images. Markers: tip (distal face x = L), j1, j2 (the connectors' distal faces: the
// ends of sections 1 and 2).
// ================================================================================================

constexpr int kManipMinRes = 6, kManipMaxRes = 24, kManipDefaultRes = 8;
constexpr double kManipWidth = 20.0, kManipThick = 12.0, kManipBase = 6.0, kManipSection = 40.0,
                 kManipJoint = 6.0, kManipCap = 3.0, kManipWall = 1.5, kManipCavity = 4.0,
                 kManipSpine = 3.0, kManipGain = 4.0, kManipRange = 3.0,
                 kManipChamberWeight = 20.0;

Scene MakeFingerManipulator(int res, const RobotParams& P) {
  if (res % 2 != 0)
    throw std::invalid_argument("finger_manipulator: --res must be even (mirror symmetry about "
                                "the mid-plane y = 10), got " + std::to_string(res));
  const double h = kManipWidth / res;
  const int ny = res, nz = static_cast<int>(std::lround(kManipThick / h));
  const int wall = Cells(kManipWall, h), cav = Cells(kManipCavity, h);
  const int side_cav = std::max(1, (ny - 2 * wall - Cells(kManipSpine, h)) / 2);
  const int base = Cells(kManipBase, h), sec = Cells(kManipSection, h), joint = Cells(kManipJoint, h),
            cap = Cells(kManipCap, h);
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
        if (j >= wall && j < wall + side_cav) return 2 + 2 * q;           // -y side
        if (j >= ny - wall - side_cav && j < ny - wall) return 1 + 2 * q;  // +y side
      }
      if (j >= wall + side_cav && j < ny - wall - side_cav && i >= r.first) return 7;  // spine
      return 0;
    }
    return 0;
  };
  Scene s;
  s.name = "finger_manipulator";
  s.mesh = VoxelTetMesh(Eigen::Vector3d::Zero(), h, Eigen::Vector3i(nx, ny, nz), cell);
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
  const double eps = 1e-6 * h, xmax = nx * h;
  s.fixed = VerticesOnPlane(s.mesh, Eigen::Vector3d::Zero(), Eigen::Vector3d::UnitX(), eps);
  s.markers.push_back({"tip", VerticesOnPlane(s.mesh, Eigen::Vector3d(xmax, 0, 0),
                                              Eigen::Vector3d::UnitX(), eps)});
  for (int q = 0; q < 2; ++q)
    s.markers.push_back({"j" + std::to_string(q + 1),
                         VerticesOnPlane(s.mesh, Eigen::Vector3d(joints[q].second * h, 0, 0),
                                         Eigen::Vector3d::UnitX(), eps)});
  s.validate();
  return s;
}

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

Scene MakeMultiSegmentGripper(int res, const RobotParams&) {
  const double h = kGripWidth / res;
  const int ny = res, nz = static_cast<int>(std::lround(kGripHeight / h));
  const int wall = Cells(kGripWall, h), cav = Cells(kGripCavity, h), layer = Cells(kGripLayer, h);
  const int base = Cells(kGripBase, h), seg = Cells(kGripSegment, h), joint = Cells(kGripJoint, h);
  const int nx = base + 3 * seg + 2 * joint;
  if (nz < layer + 2 * wall + 1)
    throw std::invalid_argument("multi_segment_gripper: res " + std::to_string(res) + " too coarse");
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
  s.name = "multi_segment_gripper";
  s.mesh = VoxelTetMesh(Eigen::Vector3d::Zero(), h, Eigen::Vector3i(nx, ny, nz), cell);
  s.body[0] = Material{"body", 1.0, 1.0};
  s.body[4] = Material{"inextensible", 1.0, 20.0};
  s.body[5] = Material{"connector", 1.0, 20.0};
  for (int k = 0; k < 3; ++k)
    s.actuators.push_back(PneumaticActuator("c" + std::to_string(k + 1), {k + 1}, kGripMaxAlpha));
  const double eps = 1e-6 * h, xmax = nx * h, zmax = nz * h;
  s.fixed = VerticesOnPlane(s.mesh, Eigen::Vector3d::Zero(), Eigen::Vector3d::UnitX(), eps);
  AddDistalFaceMarkers(xmax, zmax, eps, &s);
  s.markers.push_back({"P0", VerticesOnPlane(s.mesh, Eigen::Vector3d(joints[1].second * h, 0, 0),
                                             Eigen::Vector3d::UnitX(), eps)});
  s.markers.push_back({"grip_layer", VerticesInXRange(s.mesh, rows[2].x0 * h - eps,
                                                      rows[2].x1 * h + eps, layer * h + eps)});
  s.validate();
  return s;
}

// ================================================================================================
// dea_crawler (thesis Fig. 2.10, after [83]): a thin strip of prism elements, a DEA membrane under a
// bendable frame, with a leg under each end.
//
// Axes: x = long axis [0, 60], y = width [0, 20], z = up. Prism layers (mm): legs z in [0, 5] under
// x in [0, 5] and [55, 60] (region 3, weight 20: rigid); the membrane layer z in [5, 5.5], whose
// part x in [10, 50] is the DEA actuator "dea" (region 1) and the rest passive elastomer
// (region 2); the frame layer z in [5.5, 6.5] over the whole strip (region 0, R_omega 1).
// The mesh is the flat, pre-stretched state of fabrication (area ratio 1). Releasing the stretch
// gives the robot's rest state, lambda_init = 0.7: the membrane shrinks, the bilayer arches up and
// the legs are pulled together. A voltage relaxes the membrane (lambda towards 1), flattening the
// arch and spreading the legs. Range lambda in [0.7, 1], rest 0.7.
// Supports: the legs stay on the x-y plane (thesis): the bottom of the rear leg (x in [0, 5]) is
// pinned (the stance foot), the bottom of the front leg has only z held (it slides on the
// ground). Markers: tip (front face x = 60), rear_foot / front_foot (centroids of the leg
// bottoms), apex (the frame's top surface at x = 30). The leg spacing is front_foot - rear_foot.
// Resolution: prisms per 20 mm of width (in-plane cell 20 / res mm).
// ================================================================================================

constexpr int kCrawlMinRes = 4, kCrawlMaxRes = 40, kCrawlDefaultRes = 8;
constexpr double kCrawlLength = 60.0, kCrawlWidth = 20.0, kCrawlLeg = 5.0, kCrawlLegHeight = 5.0,
                 kCrawlMembrane = 0.5, kCrawlFrame = 1.0, kCrawlDea0 = 10.0, kCrawlDea1 = 50.0,
                 kCrawlInit = 0.7;

Scene MakeDeaCrawler(int res, const RobotParams& P) {
  const double h = kCrawlWidth / res;
  const int nx = static_cast<int>(std::lround(kCrawlLength / h)), ny = res;
  // Layers: legs split into cells of about h, then the membrane and the frame.
  const int leg_layers = std::max(1, static_cast<int>(std::lround(kCrawlLegHeight / h)));
  std::vector<double> z;
  for (int l = 0; l <= leg_layers; ++l) z.push_back(kCrawlLegHeight * l / leg_layers);
  z.push_back(kCrawlLegHeight + kCrawlMembrane);
  z.push_back(kCrawlLegHeight + kCrawlMembrane + P.at("frame_thickness"));
  auto cell = [&](const Eigen::Vector3d& ctr, const Eigen::Vector3i& c) {
    const double xc = ctr.x();
    if (c[2] < leg_layers) return (xc < kCrawlLeg || xc > kCrawlLength - kCrawlLeg) ? 3 : -1;
    if (c[2] == leg_layers) return (xc > kCrawlDea0 && xc < kCrawlDea1) ? 1 : 2;
    return 0;
  };
  Scene s;
  s.name = "dea_crawler";
  s.mesh = PrismGridMesh(Eigen::Vector3d::Zero(), h, h, Eigen::Vector2i(nx, ny), z, cell);
  s.body[0] = Material{"frame", 1.0, P.at("frame_weight")};
  s.body[2] = Material{"elastomer", 1.0, 1.0};
  s.body[3] = Material{"leg", 1.0, 20.0};
  Actuator a;
  a.name = "dea";
  a.type = ActuatorType::Dea;
  a.regions = {1};
  a.min = a.rest = kCrawlInit;
  a.max = 1.0;
  s.actuators.push_back(a);
  const double eps = 1e-6 * h, xmax = nx * h;
  const std::vector<int> rear = VerticesInBox(s.mesh, Eigen::Vector3d(-kInf, -kInf, -eps),
                                              Eigen::Vector3d(kCrawlLeg + eps, kInf, eps));
  const std::vector<int> front = VerticesInBox(s.mesh, Eigen::Vector3d(xmax - kCrawlLeg - eps, -kInf, -eps),
                                               Eigen::Vector3d(kInf, kInf, eps));
  s.fixed = rear;
  s.fixed_axis[2] = front;
  s.markers.push_back({"tip", VerticesOnPlane(s.mesh, Eigen::Vector3d(xmax, 0, 0),
                                              Eigen::Vector3d::UnitX(), eps)});
  s.markers.push_back({"rear_foot", rear});
  s.markers.push_back({"front_foot", front});
  const double ztop = z.back();
  const int mid = NearestVertex(s.mesh, Eigen::Vector3d(0.5 * xmax, 0, ztop));
  const double xmid = s.mesh.vertices(mid, 0);
  s.markers.push_back({"apex", VerticesInBox(s.mesh, Eigen::Vector3d(xmid - eps, -kInf, ztop - eps),
                                             Eigen::Vector3d(xmid + eps, kInf, kInf))});
  s.validate();
  return s;
}

// ================================================================================================
// bimaterial_bar (thesis Fig. 2.6): the two-material specimen of the elongation and twisting
// tests used to calibrate R_omega.
//
// Axes: x = long axis [0, 80], cross-section y, z in [0, 12] x [0, 12]. Material A (region 0) for
// x < interface * 80, material B (region 1) beyond; the x = 0 face is fixed. The x = 80 face is
// moved by two motion actuators, composed in this order: "twist" (degrees about the bar's axis
// y = z = 6, range [-180, 180]) and "stretch" (mm along +x, range [0, 40]). Each material's
// R_omega and weight are parameters. Markers: tip (end face), interface (the cells' face nearest
// the interface plane), a_mid / b_mid (the cross-sections midway through each material).
// Resolution: cells across the 12 mm side (cell 12 / res mm); the interface snaps to a cell face.
// ================================================================================================

constexpr int kBarMinRes = 2, kBarMaxRes = 24, kBarDefaultRes = 4;
constexpr double kBarLength = 80.0, kBarSide = 12.0;

Scene MakeBimaterialBar(int res, const RobotParams& P) {
  const double h = kBarSide / res;
  const int nx = static_cast<int>(std::lround(kBarLength / h));
  const int ni = std::clamp(static_cast<int>(std::lround(P.at("interface") * nx)), 1, nx - 1);
  auto cell = [&](const Eigen::Vector3d&, const Eigen::Vector3i& c) { return c[0] < ni ? 0 : 1; };
  Scene s;
  s.name = "bimaterial_bar";
  s.mesh = VoxelTetMesh(Eigen::Vector3d::Zero(), h, Eigen::Vector3i(nx, res, res), cell);
  s.body[0] = Material{"A", P.at("r_omega_a"), P.at("weight_a")};
  s.body[1] = Material{"B", P.at("r_omega_b"), P.at("weight_b")};
  const double eps = 1e-6 * h, xmax = nx * h;
  const std::vector<int> end =
      VerticesOnPlane(s.mesh, Eigen::Vector3d(xmax, 0, 0), Eigen::Vector3d::UnitX(), eps);
  Actuator tw;
  tw.name = "twist";
  tw.type = ActuatorType::Twist;
  tw.vertices = end;
  tw.axis = Eigen::Vector3d::UnitX();
  tw.centre = Eigen::Vector3d(0, 0.5 * kBarSide, 0.5 * kBarSide);
  tw.rest = 0.0;
  tw.min = -180.0;
  tw.max = 180.0;
  Actuator st = tw;
  st.name = "stretch";
  st.type = ActuatorType::Displacement;
  st.min = 0.0;
  st.max = 40.0;
  s.actuators = {tw, st};
  s.fixed = VerticesOnPlane(s.mesh, Eigen::Vector3d::Zero(), Eigen::Vector3d::UnitX(), eps);
  auto plane = [&](int i) {
    return VerticesOnPlane(s.mesh, Eigen::Vector3d(i * h, 0, 0), Eigen::Vector3d::UnitX(), eps);
  };
  s.markers.push_back({"tip", end});
  s.markers.push_back({"interface", plane(ni)});
  s.markers.push_back({"a_mid", plane(ni / 2)});
  s.markers.push_back({"b_mid", plane((ni + nx) / 2)});
  s.validate();
  return s;
}

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
  const int nx = static_cast<int>(std::lround(kCgLength / h)), nz = static_cast<int>(std::lround(kCgHeight / h));
  auto cell = [&](const Eigen::Vector3d& c, const Eigen::Vector3i&) {
    if (c.z() > kCgChannel && c.x() > kCgStart) return 1;
    const double u = std::fmod(c.x(), kCgLink + kCgJoint);
    return u < kCgLink ? 0 : 2;
  };
  Scene s;
  s.name = "cable_gripper";
  s.mesh = VoxelTetMesh(Eigen::Vector3d::Zero(), h, Eigen::Vector3i(nx, res, nz), cell);
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
  s.markers.push_back({"tip", VerticesOnPlane(s.mesh, Eigen::Vector3d(xmax, 0, 0),
                                              Eigen::Vector3d::UnitX(), eps)});
  for (int q = 0; q < 3; ++q) {
    const double xm = std::min(xmax, 40.0 + 30.0 * q);
    s.markers.push_back({"m" + std::to_string(q + 1),
                         {NearestVertex(s.mesh, Eigen::Vector3d(xm, 0.5 * kCgWidth, 0.0))}});
  }
  s.validate();
  return s;
}

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
// Snapped to cells of h = 20 / res mm (every feature >= 1 cell).
// ================================================================================================

constexpr int kScfMinRes = 5, kScfMaxRes = 32, kScfDefaultRes = 8;
constexpr double kScfGap = 0.2, kScfCavity = 5.0, kScfMaxAlpha = 6.0;

Material MooneyRivlinMaterial(const std::string& name, const std::string& named, double weight) {
  MooneyRivlin mr;
  if (!NamedMooneyRivlin(named, &mr))
    throw std::logic_error("unknown built-in material '" + named + "'");
  Material m{name, 1.0, weight};
  m.law = "mooney-rivlin";
  m.c1 = mr.c1;
  m.c2 = mr.c2;
  return m;
}

/// Initial shear modulus 2 (c1 + c2) of a named Mooney-Rivlin material, MPa.
double ShearModulus(const std::string& named) {
  MooneyRivlin mr;
  if (!NamedMooneyRivlin(named, &mr))
    throw std::logic_error("unknown built-in material '" + named + "'");
  return 2.0 * (mr.c1 + mr.c2);
}

/// Cuts a slit through a tet mesh along a set of vertices: every vertex with on_cut(position)
/// that is used by tets on both sides (far_side(tet centroid) true and false) is doubled, and
/// the far-side tets take the copy; a vertex used by far-side tets only is simply moved. The
/// far side's vertices of the cut are then moved by `shift` (mm), opening the slit.
void CutSlit(Mesh* mesh, const std::function<bool(const Eigen::Vector3d&)>& on_cut,
             const std::function<bool(const Eigen::Vector3d&)>& far_side,
             const Eigen::Vector3d& shift) {
  const int n0 = mesh->num_vertices();
  std::vector<char> near(n0, 0), far(n0, 0);
  std::vector<char> tet_far(mesh->elements.size(), 0);
  for (size_t t = 0; t < mesh->elements.size(); ++t) {
    const auto& e = mesh->elements[t];
    Eigen::Vector3d c = Eigen::Vector3d::Zero();
    for (int a = 0; a < e.k(); ++a) c += mesh->vertices.row(e.v[a]).transpose() / e.k();
    tet_far[t] = far_side(c);
    for (int a = 0; a < e.k(); ++a) (tet_far[t] ? far : near)[e.v[a]] = 1;
  }
  std::vector<int> copy(n0, -1);
  int next = n0;
  for (int v = 0; v < n0; ++v)
    if (far[v] && on_cut(mesh->vertices.row(v).transpose())) copy[v] = near[v] ? next++ : v;
  mesh->vertices.conservativeResize(next, 3);
  for (int v = 0; v < n0; ++v) {
    if (copy[v] < 0) continue;
    mesh->vertices.row(copy[v]) = mesh->vertices.row(v) + shift.transpose();
  }
  for (size_t t = 0; t < mesh->elements.size(); ++t) {
    if (!tet_far[t]) continue;
    auto& e = mesh->elements[t];
    for (int a = 0; a < e.k(); ++a)
      if (copy[e.v[a]] >= 0) e.v[a] = copy[e.v[a]];
  }
}

Scene MakeSelfCollisionFinger(int res, const RobotParams& P) {
  const double h = kFingerWidth / res;
  const int ny = res, nz = static_cast<int>(std::lround(kFingerHeight / h));
  const int base = Cells(kFingerBase, h), floor = Cells(kFingerFloor, h), wall = Cells(P.at("wall"), h);
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
    const bool inside = w >= wall && w < wall + cavity && j >= wall && j < ny - wall && k < nz - wall;
    return inside ? 1 : 0;
  };
  Mesh mesh = VoxelTetMesh(Eigen::Vector3d::Zero(), h, Eigen::Vector3i(nx, ny, nz), cell);
  // Cut the slits: above the floor, the vertices on the plane between two chambers are doubled,
  // the copies taken by the tets on the distal side and moved kScfGap along +x.
  const double z_floor = (base + floor) * h, tol = 1e-6 * h;
  for (int q = chambers - 1; q >= 1; --q) {
    const double xs = (proximal + q * pitch) * h;
    CutSlit(&mesh,
            [&](const Eigen::Vector3d& p) { return std::abs(p.x() - xs) < tol && p.z() > z_floor + tol; },
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
  AddDistalFaceMarkers(nx * h, nz * h, eps, &s);
  s.solver.collision.self = true;
  s.validate();
  return s;
}

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
// y < 125), c3 (x < 125, y > 125), c4 (x > 125, y > 125). Material: Mooney-Rivlin Dragon Skin 20 (Eq. 3.6-3.7) for membrane and walls.
// Markers: tip (the membrane's top centre) and q1..q4 (membrane top above each chamber's
// centre). Self-collision response is on in the scene's solver options.
// ================================================================================================

constexpr int kMemMinRes = 10, kMemMaxRes = 60, kMemDefaultRes = 20;
constexpr double kMemSide = 250.0, kMemChamberHeight = 40.0, kMemGap = 2.0, kMemMaxAlpha = 4.0;

Scene MakeMembrane(int res, const RobotParams& P) {
  const double h = kMemSide / res;
  const int n = res;
  const int gap = static_cast<int>(std::lround(P.at("chamber_gap")));
  if (std::abs(P.at("chamber_gap") - gap) > 1e-9)
    throw std::invalid_argument("membrane: chamber_gap: expected an integer number of cells, got " +
                                std::to_string(P.at("chamber_gap")));
  // Chamber width in cells: 1 margin + nc + gap + nc + (the rest) margin.
  const int nc = (n - 2 - gap) / 2;
  if (nc < 3)
    throw std::invalid_argument("membrane: chamber_gap = " + std::to_string(gap) + " leaves chambers " +
                                std::to_string(nc) + " cells wide at res " + std::to_string(res) +
                                "; expected at least 3 (raise res or lower chamber_gap)");
  const int hc = std::max(3, static_cast<int>(std::lround(kMemChamberHeight / h)));
  const int zm = hc;           // membrane cell layer, on the roofs (then lifted by the slit)
  const int x0[2] = {1, 1 + nc + gap};
  auto cell = [&](const Eigen::Vector3d&, const Eigen::Vector3i& c) {
    const int i = c[0], j = c[1], k = c[2];
    if (k == zm) return 0;
    if (k >= hc) return -1;
    for (int q = 0; q < 4; ++q) {
      const int ox = x0[q % 2], oy = x0[q / 2];
      if (i < ox || i >= ox + nc || j < oy || j >= oy + nc) continue;
      const bool interior = i > ox && i < ox + nc - 1 && j > oy && j < oy + nc - 1 && k > 0 && k < hc - 1;
      return interior ? 2 + q : 1;
    }
    return -1;
  };
  Scene s;
  s.name = "membrane";
  s.mesh = VoxelTetMesh(Eigen::Vector3d::Zero(), h, Eigen::Vector3i(n, n, zm + 1), cell);
  // The membrane is a separate body: lift it off the roofs by kMemGap.
  const double z_roof = zm * h;
  CutSlit(&s.mesh, [&](const Eigen::Vector3d& p) { return std::abs(p.z() - z_roof) < 1e-6 * h; },
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
  std::vector<int> fixed = VerticesOnPlane(s.mesh, Eigen::Vector3d::Zero(), Eigen::Vector3d::UnitZ(), eps);
  for (int v = 0; v < s.mesh.num_vertices(); ++v) {
    const Eigen::Vector3d p = s.mesh.vertices.row(v);
    const bool rim = p.x() < eps || p.y() < eps || p.x() > side - eps || p.y() > side - eps;
    if (rim && p.z() > zlo - eps) fixed.push_back(v);
  }
  std::sort(fixed.begin(), fixed.end());
  fixed.erase(std::unique(fixed.begin(), fixed.end()), fixed.end());
  s.fixed = fixed;
  const double ztop = zlo + h;
  s.markers.push_back({"tip", {NearestVertex(s.mesh, Eigen::Vector3d(0.5 * side, 0.5 * side, ztop))}});
  for (int q = 0; q < 4; ++q) {
    const double cx = (x0[q % 2] + 0.5 * nc) * h, cy = (x0[q / 2] + 0.5 * nc) * h;
    s.markers.push_back({"q" + std::to_string(q + 1), {NearestVertex(s.mesh, Eigen::Vector3d(cx, cy, ztop))}});
  }
  s.solver.collision.self = true;
  s.validate();
  return s;
}

struct RobotEntry {
  RobotInfo info;
  int min_res, max_res;
  Scene (*make)(int, const RobotParams&);
};

Scene MakePneumaticFingerP(int res, const RobotParams&) { return MakePneumaticFinger(res); }
Scene MakeThreeChamberP(int res, const RobotParams& P) {
  return MakeThreeChamber(res, P.at("chamber_radius"));
}
Scene MakeCableFingerP(int res, const RobotParams&) { return MakeCableFinger(res); }

const std::vector<RobotEntry>& Registry() {
  static const std::vector<RobotEntry> kRobots = {
      {{"pneumatic_finger",
        "PneuNet-style pneumatic bending finger (thesis Fig. 2.11), voxel tet mesh. x = long axis "
        "[0, 120] mm (x = 0 fixed), y = width [0, 20], z = height [0, 15]; inextensible base layer "
        "z in [0, 1.5] (region 2, weight 20), a 1.5 mm floor, a solid proximal block and a row of "
        "5 mm cavities between single 1.5 mm walls (region 0); the filled cavities (region 1) form "
        "one pneumatic actuator 'chamber' (volume ratio in [1, 10]; ~260 degrees of bend at 10). "
        "Markers: tip (distal face x = 120), tip_top / tip_bottom (top / bottom quarter of the "
        "distal face).",
        kFingerDefaultRes,
        "cells across the 20 mm width (cell size 20/res mm), integer in [5, 40]; 27 res^3 tets; "
        "features snap to whole cells (16 chambers at res 12)", {}},
       kFingerMinRes, kFingerMaxRes, &MakePneumaticFingerP},
      {{"three_chamber",
        "Three-chamber pneumatic actuator (thesis Fig. 2.12, Chapter 5): 48 x 48 x 136 mm cylinder. "
        "y = long axis (y = 0 fixed, tip face y = 136); angles phi = atan2(z, x) in the x-z plane. "
        "Chambers c1, c2, c3 (regions 1-3, pneumatic, volume ratio in [1, 3]): radius 7 mm, 13 mm "
        "from the axis at phi = 180, 300, 60 degrees, y in [8, 128]; body region 0. The mesh is "
        "exactly invariant under rotation by 120 degrees about y (c1 -> c2 -> c3). Marker: tip "
        "(top face y = 136).",
        kThreeDefaultRes,
        "number of concentric rings of the cross-section disk (radial spacing 24/res mm; layers "
        "along y of about the same size), integer in [3, 16]; ~102 res^3 tets",
        {{"chamber_radius", kChamberRadius, 5.0, 9.0,
          "chamber radius, mm (the outer wall is 24 - 13 - radius thick: 4 mm at the default 7); "
          "chamber elements are the tets whose centroid lies within it"}}},
       kThreeMinRes, kThreeMaxRes, &MakeThreeChamberP},
      {{"cable_finger",
        "Cable-driven finger (thesis Fig. 2.8, Fig. 4.1): 120 x 25 x 25 mm, four teeth on a 5 mm "
        "base; x = long axis (x = 0 fixed), z = height, planar motion in x-z. Three knuckles (gaps "
        "x in [15, 25], [50, 60], [85, 95]) each bridged at the top (z >= 17.5) by the actuation "
        "elements of its own tendon t1, t2, t3 (cable, shortening ratio in [0.5, 1]; regions 1-3; "
        "each tendon's path runs along x through its bridge). Markers: tip (face x = 120), tip_top / "
        "tip_bottom (top / bottom quarter of that face).",
        kCableDefaultRes, "cells across the 25 mm width (cell size 25/res mm), integer in [5, 30]", {}},
       kCableMinRes, kCableMaxRes, &MakeCableFingerP},
      {{"finger_manipulator",
        "Planar finger manipulator (thesis Sec. 5.3.1): three 40 mm finger sections joined by rigid "
        "6 mm connectors; x = long axis (x = 0 fixed), y = width [0, 20], z = thickness [0, 12]; "
        "planar motion in x-y. Each section has a row of chambers on each side of a central "
        "inextensible spine; its signed pneumatic actuator s1, s2, s3 takes a value in [-3, 3]: "
        "v > 0 inflates the +y chambers to volume ratio 1 + gain v (bending towards -y), v < 0 the "
        "-y chambers. Redundant: m = 3, n = 2. Markers: tip, j1, j2 (ends of sections 1 and 2).",
        kManipDefaultRes,
        "cells across the 20 mm width (cell size 20/res mm), even integer in [6, 24]",
        {{"gain", kManipGain, 0.1, 10.0,
          "volume ratio per unit of actuation: a chamber side reaches 1 + gain |v|"},
         {"spine_weight", 20.0, 0.01, 100.0, "element weight of the central spine"},
         {"chamber_weight", kManipChamberWeight, 0.01, 100.0,
          "element weight of the chambers' actuation elements"},
         {"body_r_omega", 1.0, 0.0, 1.0, "R_omega of the body material (walls, floor, roof)"}}},
       kManipMinRes, kManipMaxRes, &MakeFingerManipulator},
      {{"multi_segment_gripper",
        "Three-segment pneumatic manipulator-gripper (thesis Fig. 4.7): three 50 mm bending "
        "segments on a common inextensible layer (z in [0, 1.5], weight 20) joined by 5 mm "
        "connectors; x = long axis (x = 0 fixed), y = width [0, 20], z = height [0, 15]; planar "
        "motion in x-z. Pneumatic actuators c1, c2, c3 (volume ratio in [1, 8]). Markers: tip, "
        "tip_top, tip_bottom, P0 (end of the second segment), grip_layer (the third segment's "
        "inextensible layer).",
        kGripDefaultRes, "cells across the 20 mm width (cell size 20/res mm), integer in [6, 24]", {}},
       kGripMinRes, kGripMaxRes, &MakeMultiSegmentGripper},
      {{"dea_crawler",
        "DEA crawling robot (thesis Fig. 2.10): a 60 x 20 mm strip of prism elements, a 0.5 mm DEA "
        "membrane (actuator 'dea', area ratio in [0.7, 1], rest 0.7 = the released pre-stretch "
        "lambda_init) under a bendable frame, with a 5 mm leg under each end. The mesh is the flat "
        "pre-stretched state. The rear foot is pinned, the front foot slides on the x-y plane (z "
        "held). Markers: tip, rear_foot, front_foot, apex (top of the frame at mid-length).",
        kCrawlDefaultRes, "prisms across the 20 mm width (in-plane cell 20/res mm), integer in [4, 40]",
        {{"frame_thickness", kCrawlFrame, 0.2, 5.0, "thickness of the frame layer, mm"},
         {"frame_weight", 1.0, 0.01, 100.0, "element weight of the frame (membrane: 1, DEA: 5)"}}},
       kCrawlMinRes, kCrawlMaxRes, &MakeDeaCrawler},
      {{"bimaterial_bar",
        "Two-material specimen of the elongation and twisting tests (thesis Fig. 2.6): an "
        "80 x 12 x 12 mm bar, material A (region 0) up to the interface and B (region 1) beyond; "
        "x = 0 fixed; the x = 80 face is driven by the motion actuators 'twist' (degrees about the "
        "bar's axis, [-180, 180]) and 'stretch' (mm along +x, [0, 40]). Markers: tip, interface, "
        "a_mid, b_mid.",
        kBarDefaultRes, "cells across the 12 mm side (cell size 12/res mm), integer in [2, 24]",
        {{"interface", 0.5, 0.05, 0.95, "interface position as a fraction of the length (snapped to a cell face)"},
         {"r_omega_a", 1.0, 0.0, 1.0, "R_omega of material A"},
         {"r_omega_b", 1.0, 0.0, 1.0, "R_omega of material B"},
         {"weight_a", 1.0, 1e-3, 1e3, "element weight of material A"},
         {"weight_b", 1.0, 1e-3, 1e3, "element weight of material B"}}},
       kBarMinRes, kBarMaxRes, &MakeBimaterialBar},
      {{"cable_gripper",
        "Cable-driven gripper finger of two materials (thesis Fig. 2.9): 100 x 20 x 20 mm, x = long "
        "axis (x = 0 fixed), planar motion in x-z; a cable channel along the top (z >= 16, cable "
        "'cable', shortening ratio in [0.5, 1]) over a body of alternating 10 mm links (region 0) "
        "and 5 mm joints (region 2). Markers: tip, m1, m2, m3 (bottom face at x = 40, 70, 100).",
        kCgDefaultRes, "cells across the 20 mm width (cell size 20/res mm), integer in [4, 24]",
        {{"link_weight", 1.0, 1e-3, 1e3, "element weight of the links"},
         {"joint_weight", 1.0, 1e-3, 1e3, "element weight of the joints"},
         {"link_r_omega", 1.0, 0.0, 1.0, "R_omega of the links"},
         {"joint_r_omega", 1.0, 0.0, 1.0, "R_omega of the joints"}}},
       kCgMinRes, kCgMaxRes, &MakeCableGripper},
      {{"selfcollision_finger",
        "PneuNet finger with 0.2 mm slits between its chambers, whose walls press on each other as they swell "
        "(thesis Sec. 3.4.2, Fig. 3.9-3.10): 120 x 20 x 15 mm, x = long axis (x = 0 fixed), "
        "inextensible base layer (region 2), Mooney-Rivlin body (region 0; material 0 = Ecoflex "
        "00-30, 1 = Dragon Skin 20, weighted by shear modulus), cavities (region 1) = pneumatic "
        "actuator 'chamber' (volume ratio in [1, 6]). Self-collision response on. Markers: tip, "
        "tip_top, tip_bottom.",
        kScfDefaultRes, "cells across the 20 mm width (cell size 20/res mm), integer in [5, 32]",
        {{"material", 0.0, 0.0, 1.0, "0: Ecoflex 00-30, 1: Dragon Skin 20 (rounded)"},
         {"wall", kFingerWall, 1.0, 5.0,
          "chamber wall thickness, mm, snapped to whole cells (at least one): one tet layer at the "
          "default 1.5 mm, whose walls invert under contact on fine meshes (docs/collision_response.md)"}}},
       kScfMinRes, kScfMaxRes, &MakeSelfCollisionFinger},
      {{"membrane",
        "250 x 250 mm Dragon Skin 20 membrane (rim fixed) shaped by four pneumatic chambers below "
        "it through contact only (thesis Sec. 3.4.3, Fig. 3.13). Actuators c1..c4 (volume ratio in "
        "[1, 4]) under quadrants (x<125,y<125), (x>125,y<125), (x<125,y>125), (x>125,y>125). "
        "Self-collision response on. Markers: tip (membrane top centre), q1..q4 (membrane top above "
        "each chamber).",
        kMemDefaultRes, "cells across the 250 mm side (cell size 250/res mm), integer in [10, 60]",
        {{"chamber_gap", 2.0, 1.0, 10.0,
          "cells between neighbouring chambers (integer). With 1 the swelling chambers' side walls "
          "press on each other and the contact response breaks down at res 24 (docs/collision_response.md)"}}},
       kMemMinRes, kMemMaxRes, &MakeMembrane},
      {{"twisting_robot",
        "Plant-inspired twisting robot (thesis Sec. 3.4.1, Fig. 3.7-3.8): a 100 mm long cylinder of "
        "radius 10 mm (z = long axis, z = 0 fixed, tip face z = 100) of Ecoflex 00-30 (Mooney-Rivlin "
        "c1 = 0.0418, c2 = 0.0106 MPa; region 0) with a spiral tube chamber (region 1, pneumatic "
        "actuator 'chamber', volume ratio in [1, 120]) around the helix of radius helix_radius from "
        "z = 8 to 92, meshed by CGAL Mesh_3 from generated surfaces, T(S_c, S_b) "
        "(solver/remesh/tessellation.hpp). For large ratios use progressive remeshing (solver/remesh/remesh.hpp). "
        "Markers: tip (face z = 100), tip_rim (its vertex nearest (10, 0, 100)).",
        kTwistDefaultRes,
        "Mesh_3 cell size 8/res mm (facet size the same, facet distance 0.05 of it), integer in "
        "[1, 6]; 6.2k / 10.8k / 18.0k / 29.2k tets at res 1 / 2 / 3 / 4 (docs/remeshing.md)",
        {{"helix_radius", 5.0, 2.0, 7.0, "radius of the chamber's helical centreline, mm"},
         {"tube_radius", 2.5, 1.0, 4.0, "radius of the chamber tube, mm (helix_radius + tube_radius <= 9)"},
         {"turns", kTwistDefaultTurns, 1.0, 8.0, "turns of the helix between z = 8 and z = 92"},
         {"hyperelastic", 1.0, 0.0, 1.0,
          "1: Ecoflex 00-30 Mooney-Rivlin body (Eq. 3.6-3.7); 0: Ch. 2 shape blending with R_omega = 1"},
         {"strip", 0.0, 0.0, 6.0,
          "thickness (mm, from the +x side) of a strain-limiting strip along the body (region 2); 0: none. "
          "With a strip the robot bends toward +x as it twists, and coils (Fig. 3.8)"},
         {"strip_weight", 20.0, 1.0, 1000.0, "the strip's element weight, relative to the body's"}}},
       kTwistMinRes, kTwistMaxRes, &MakeTwistingRobot},
  };
  return kRobots;
}

}  // namespace

std::vector<RobotInfo> ListRobots() {
  std::vector<RobotInfo> out;
  for (const auto& r : Registry()) out.push_back(r.info);
  return out;
}

Scene MakeRobot(const std::string& name, int res, const RobotParams& params) {
  for (const auto& r : Registry()) {
    if (r.info.name != name) continue;
    if (res <= 0) res = r.info.default_resolution;
    if (res < r.min_res || res > r.max_res)
      throw std::invalid_argument(name + ": --res must be an integer in [" +
                                  std::to_string(r.min_res) + ", " + std::to_string(r.max_res) +
                                  "], got " + std::to_string(res));
    RobotParams full;
    for (const auto& p : r.info.params) full[p.name] = p.def;
    for (const auto& [key, value] : params) {
      auto it = std::find_if(r.info.params.begin(), r.info.params.end(),
                             [&](const RobotParam& p) { return p.name == key; });
      if (it == r.info.params.end()) {
        std::string known;
        for (const auto& p : r.info.params) known += (known.empty() ? "" : ", ") + p.name;
        throw std::invalid_argument(name + ": unknown parameter '" + key + "'; its parameters: " +
                                    (known.empty() ? std::string("none") : known));
      }
      if (!(value >= it->lo && value <= it->hi))
        throw std::invalid_argument(name + ": parameter '" + key + "' must be in [" +
                                    FormatNumber(it->lo) + ", " + FormatNumber(it->hi) +
                                    "], got " + FormatNumber(value));
      full[key] = value;
    }
    return r.make(res, full);
  }
  std::string known;
  for (const auto& r : Registry()) known += (known.empty() ? "" : ", ") + r.info.name;
  throw std::invalid_argument("unknown robot '" + name + "'; known robots: " + known);
}

}  // namespace softkin
