#include "solver/robots.hpp"

#include "solver/mesh_gen.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
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

Scene MakeThreeChamber(int res) {
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
  auto region = [&centre](const DiskElementInfo& e) {
    const Eigen::Vector3d& c = e.canonical_centroid;
    if (c.y() < kChamberY0 || c.y() > kChamberY1) return 0;
    for (int k = 0; k < 3; ++k)
      if ((Eigen::Vector2d(c.x(), c.z()) - centre[k]).norm() <= kChamberRadius)
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

struct RobotEntry {
  RobotInfo info;
  int min_res, max_res;
  Scene (*make)(int);
};

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
        "features snap to whole cells (16 chambers at res 12)"},
       kFingerMinRes, kFingerMaxRes, &MakePneumaticFinger},
      {{"three_chamber",
        "Three-chamber pneumatic actuator (thesis Fig. 2.12, Chapter 5): 48 x 48 x 136 mm cylinder. "
        "y = long axis (y = 0 fixed, tip face y = 136); angles phi = atan2(z, x) in the x-z plane. "
        "Chambers c1, c2, c3 (regions 1-3, pneumatic, volume ratio in [1, 3]): radius 7 mm, 13 mm "
        "from the axis at phi = 180, 300, 60 degrees, y in [8, 128]; body region 0. The mesh is "
        "exactly invariant under rotation by 120 degrees about y (c1 -> c2 -> c3). Marker: tip "
        "(top face y = 136).",
        kThreeDefaultRes,
        "number of concentric rings of the cross-section disk (radial spacing 24/res mm; layers "
        "along y of about the same size), integer in [3, 16]; ~102 res^3 tets"},
       kThreeMinRes, kThreeMaxRes, &MakeThreeChamber},
      {{"cable_finger",
        "Cable-driven finger (thesis Fig. 2.8, Fig. 4.1): 120 x 25 x 25 mm, four teeth on a 5 mm "
        "base; x = long axis (x = 0 fixed), z = height, planar motion in x-z. Three knuckles (gaps "
        "x in [15, 25], [50, 60], [85, 95]) each bridged at the top (z >= 17.5) by the actuation "
        "elements of its own tendon t1, t2, t3 (cable, shortening ratio in [0.5, 1]; regions 1-3; "
        "each tendon's path runs along x through its bridge). Markers: tip (face x = 120), tip_top / "
        "tip_bottom (top / bottom quarter of that face).",
        kCableDefaultRes, "cells across the 25 mm width (cell size 25/res mm), integer in [5, 30]"},
       kCableMinRes, kCableMaxRes, &MakeCableFinger},
  };
  return kRobots;
}

}  // namespace

std::vector<RobotInfo> ListRobots() {
  std::vector<RobotInfo> out;
  for (const auto& r : Registry()) out.push_back(r.info);
  return out;
}

Scene MakeRobot(const std::string& name, int res) {
  for (const auto& r : Registry()) {
    if (r.info.name != name) continue;
    if (res <= 0) res = r.info.default_resolution;
    if (res < r.min_res || res > r.max_res)
      throw std::invalid_argument(name + ": --res must be an integer in [" +
                                  std::to_string(r.min_res) + ", " + std::to_string(r.max_res) +
                                  "], got " + std::to_string(res));
    return r.make(res);
  }
  std::string known;
  for (const auto& r : Registry()) known += (known.empty() ? "" : ", ") + r.info.name;
  throw std::invalid_argument("unknown robot '" + name + "'; known robots: " + known);
}

}  // namespace softkin
