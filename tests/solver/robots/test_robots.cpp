// Tests of the structured mesh generators (solver/mesh/mesh_gen.hpp) and the embedded robots
// (solver/robots/robots.hpp). The mesh checks here are self-contained (own volume, face and
// component code) so they test the generators independently of mesh.cpp.
#include "softkin/solver/mesh/mesh_gen.hpp"
#include "softkin/solver/robots/robots.hpp"
#include "tests/solver/robots/mirror_test_util.hpp"

#include <Eigen/Geometry>
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <map>
#include <numeric>
#include <set>
#include <stdexcept>
#include <string>
#include <unordered_map>
#include <vector>

namespace softkin {
namespace {

// ---------------------------------------------------------------------------------------------
// Helpers
// ---------------------------------------------------------------------------------------------

double TetVol(const Mesh& m, const Element& e) {
  const Eigen::Vector3d a = m.vertices.row(e.v[0]).transpose();
  const Eigen::Vector3d b = m.vertices.row(e.v[1]).transpose() - a;
  const Eigen::Vector3d c = m.vertices.row(e.v[2]).transpose() - a;
  const Eigen::Vector3d d = m.vertices.row(e.v[3]).transpose() - a;
  return b.cross(c).dot(d) / 6.0;
}

double TotalVolume(const Mesh& m, int region = -1) {
  double v = 0.0;
  for (const auto& e : m.elements)
    if (region < 0 || e.region == region) v += TetVol(m, e);
  return v;
}

struct FaceStats {
  int boundary = 0;  // faces used by one tet
  int interior = 0;  // faces used by two tets
  int bad = 0;       // faces used by more than two tets
  std::vector<std::pair<std::array<int, 3>, int>> boundary_faces;  // (face, element)
};

// Triangle-face usage of a tet mesh.
FaceStats Faces(const Mesh& m) {
  struct F {
    std::array<int, 3> v;
    int elem;
  };
  std::vector<F> faces;
  faces.reserve(4 * m.elements.size());
  static const int kFace[4][3] = {{1, 2, 3}, {0, 2, 3}, {0, 1, 3}, {0, 1, 2}};
  for (int i = 0; i < m.num_elements(); ++i) {
    const auto& e = m.elements[i];
    for (const auto& f : kFace) {
      std::array<int, 3> t = {e.v[f[0]], e.v[f[1]], e.v[f[2]]};
      std::sort(t.begin(), t.end());
      faces.push_back({t, i});
    }
  }
  std::sort(faces.begin(), faces.end(), [](const F& a, const F& b) { return a.v < b.v; });
  FaceStats s;
  for (size_t i = 0; i < faces.size();) {
    size_t j = i;
    while (j < faces.size() && faces[j].v == faces[i].v) ++j;
    const size_t n = j - i;
    if (n == 1) {
      ++s.boundary;
      s.boundary_faces.push_back({faces[i].v, faces[i].elem});
    } else if (n == 2) {
      ++s.interior;
    } else {
      ++s.bad;
    }
    i = j;
  }
  return s;
}

struct UnionFind {
  std::vector<int> p;
  explicit UnionFind(int n) : p(n) { std::iota(p.begin(), p.end(), 0); }
  int find(int x) {
    while (p[x] != x) x = p[x] = p[p[x]];
    return x;
  }
  void unite(int a, int b) { p[find(a)] = find(b); }
};

// Connected components (vertex sharing) of the tets accepted by `keep`.
template <class Keep>
int Components(const Mesh& m, Keep keep) {
  UnionFind uf(m.num_vertices());
  std::vector<char> used(m.num_vertices(), 0);
  for (const auto& e : m.elements) {
    if (!keep(e)) continue;
    for (int j = 0; j < 4; ++j) used[e.v[j]] = 1;
    for (int j = 1; j < 4; ++j) uf.unite(e.v[0], e.v[j]);
  }
  std::set<int> roots;
  for (int v = 0; v < m.num_vertices(); ++v)
    if (used[v]) roots.insert(uf.find(v));
  return static_cast<int>(roots.size());
}
int Components(const Mesh& m) {
  return Components(m, [](const Element&) { return true; });
}

int UnusedVertices(const Mesh& m) {
  std::vector<char> used(m.num_vertices(), 0);
  for (const auto& e : m.elements)
    for (int j = 0; j < e.k(); ++j) used[e.v[j]] = 1;
  return static_cast<int>(std::count(used.begin(), used.end(), 0));
}

// Common structural checks for a generated tet mesh.
void ExpectWellFormed(const Mesh& m, const std::string& what) {
  SCOPED_TRACE(what);
  ASSERT_GT(m.num_elements(), 0);
  int nonpos = 0, nontet = 0, range = 0;
  double minvol = 1e300;
  for (const auto& e : m.elements) {
    if (e.type != ElementType::Tet) ++nontet;
    for (int j = 0; j < 4; ++j)
      if (e.v[j] < 0 || e.v[j] >= m.num_vertices()) ++range;
    if (range) continue;
    const double v = TetVol(m, e);
    minvol = std::min(minvol, v);
    if (!(v > 0.0)) ++nonpos;
  }
  EXPECT_EQ(nontet, 0);
  ASSERT_EQ(range, 0);
  EXPECT_EQ(nonpos, 0) << "non-positively oriented tets (min volume " << minvol << ")";
  const FaceStats f = Faces(m);
  EXPECT_EQ(f.bad, 0) << "faces shared by more than two tets";
  EXPECT_EQ(f.boundary + 2 * f.interior, 4 * m.num_elements());
  // One connected body, except the membrane: the membrane and its four chambers are separate
  // bodies of one mesh that meet through contact (Fig. 3.13).
  EXPECT_EQ(Components(m), what == "membrane" ? 5 : 1);
  EXPECT_EQ(UnusedVertices(m), 0);
}

// Exact equality of two meshes.
bool SameMesh(const Mesh& a, const Mesh& b) {
  if (a.vertices.rows() != b.vertices.rows() || a.elements.size() != b.elements.size())
    return false;
  if (!(a.vertices.array() == b.vertices.array()).all()) return false;
  for (size_t i = 0; i < a.elements.size(); ++i)
    if (a.elements[i].v != b.elements[i].v || a.elements[i].region != b.elements[i].region ||
        a.elements[i].type != b.elements[i].type)
      return false;
  return true;
}

// Maps every vertex x to the vertex at f(x) (within tol); -1 where there is none.
template <class F>
std::vector<int> VertexMap(const Mesh& m, F f, double tol) {
  const double q = 1e-3;
  auto cell = [q](const Eigen::Vector3d& x) {
    return std::array<std::int64_t, 3>{std::int64_t(std::floor(x[0] / q)),
                                       std::int64_t(std::floor(x[1] / q)),
                                       std::int64_t(std::floor(x[2] / q))};
  };
  std::map<std::array<std::int64_t, 3>, std::vector<int>> grid;
  for (int v = 0; v < m.num_vertices(); ++v) grid[cell(m.vertices.row(v).transpose())].push_back(v);
  std::vector<int> out(m.num_vertices(), -1);
  for (int v = 0; v < m.num_vertices(); ++v) {
    const Eigen::Vector3d y = f(Eigen::Vector3d(m.vertices.row(v).transpose()));
    const auto c = cell(y);
    for (int dx = -1; dx <= 1 && out[v] < 0; ++dx)
      for (int dy = -1; dy <= 1 && out[v] < 0; ++dy)
        for (int dz = -1; dz <= 1 && out[v] < 0; ++dz) {
          auto it = grid.find({c[0] + dx, c[1] + dy, c[2] + dz});
          if (it == grid.end()) continue;
          for (int w : it->second)
            if ((m.vertices.row(w).transpose() - y).norm() <= tol) {
              out[v] = w;
              break;
            }
        }
  }
  return out;
}

// Rotation by +120 degrees in the plane of coordinates (a, b), angle from axis a towards axis b.
Eigen::Vector3d Rot120(const Eigen::Vector3d& x, int a, int b) {
  const double c = -0.5, s = std::sqrt(3.0) / 2.0;
  Eigen::Vector3d y = x;
  y[a] = c * x[a] - s * x[b];
  y[b] = s * x[a] + c * x[b];
  return y;
}

std::array<int, 4> SortedTet(const Element& e, const std::vector<int>& map) {
  std::array<int, 4> t = {map[e.v[0]], map[e.v[1]], map[e.v[2]], map[e.v[3]]};
  std::sort(t.begin(), t.end());
  return t;
}

// Reflection across the plane x_b = 0 (in the plane of coordinates (a, b): across axis a).
Eigen::Vector3d Reflect(const Eigen::Vector3d& x, int b) {
  Eigen::Vector3d y = x;
  y[b] = -x[b];
  return y;
}

// Checks that the isometry f maps the vertex set onto itself and every tet with region r onto a
// tet with region region_map(r).
template <class F, class RegionMap>
void ExpectMapsOntoItself(const Mesh& m, F f, RegionMap region_map) {
  const std::vector<int> map = VertexMap(m, f, 1e-9);
  const int missing = static_cast<int>(std::count(map.begin(), map.end(), -1));
  ASSERT_EQ(missing, 0) << "vertices without an image";
  std::vector<int> sorted = map;
  std::sort(sorted.begin(), sorted.end());
  EXPECT_TRUE(std::adjacent_find(sorted.begin(), sorted.end()) == sorted.end())
      << "the rotation is not a bijection";
  std::map<std::array<int, 4>, int> tets;
  std::vector<int> identity(m.num_vertices());
  std::iota(identity.begin(), identity.end(), 0);
  for (const auto& e : m.elements) tets[SortedTet(e, identity)] = e.region;
  int unmatched = 0, wrong_region = 0;
  for (const auto& e : m.elements) {
    auto it = tets.find(SortedTet(e, map));
    if (it == tets.end()) {
      ++unmatched;
    } else if (it->second != region_map(e.region)) {
      ++wrong_region;
    }
  }
  EXPECT_EQ(unmatched, 0);
  EXPECT_EQ(wrong_region, 0);
}

// Rotation by 120 degrees in the plane of coordinates (a, b).
template <class RegionMap>
void ExpectThreeFold(const Mesh& m, int a, int b, RegionMap region_map) {
  ExpectMapsOntoItself(
      m, [&](const Eigen::Vector3d& x) { return Rot120(x, a, b); }, region_map);
}

Eigen::Vector3d Centroid(const Mesh& m, const std::vector<int>& vs) {
  Eigen::Vector3d c = Eigen::Vector3d::Zero();
  for (int v : vs) c += m.vertices.row(v).transpose();
  return c / std::max<size_t>(1, vs.size());
}

int CountRegion(const Mesh& m, int r) {
  return static_cast<int>(std::count_if(m.elements.begin(), m.elements.end(),
                                        [r](const Element& e) { return e.region == r; }));
}

// Tets of the given regions that have a face on the mesh boundary.
int RegionTetsOnBoundary(const Mesh& m, const std::set<int>& regions) {
  const FaceStats f = Faces(m);
  int n = 0;
  for (const auto& bf : f.boundary_faces)
    if (regions.count(m.elements[bf.second].region)) ++n;
  return n;
}

// ---------------------------------------------------------------------------------------------
// MeshGen: VoxelTetMesh
// ---------------------------------------------------------------------------------------------

TEST(MeshGenVoxel, SingleCellIsSixPositiveTetsSharingTheDiagonal) {
  const double h = 2.5;
  const Mesh m = VoxelTetMesh(Eigen::Vector3d(1, 2, 3), h, Eigen::Vector3i(1, 1, 1),
                              [](const Eigen::Vector3d&, const Eigen::Vector3i&) { return 7; });
  ASSERT_EQ(m.num_vertices(), 8);
  ASSERT_EQ(m.num_elements(), 6);
  for (const auto& e : m.elements) {
    EXPECT_EQ(e.region, 7);
    EXPECT_NEAR(TetVol(m, e), h * h * h / 6.0, 1e-12);
    // Every tet contains the main diagonal: vertices (1,2,3) and (3.5,4.5,5.5).
    EXPECT_TRUE((m.vertices.row(e.v[0]) - Eigen::RowVector3d(1, 2, 3)).norm() < 1e-12);
    EXPECT_TRUE((m.vertices.row(e.v[3]) - Eigen::RowVector3d(3.5, 4.5, 5.5)).norm() < 1e-12);
  }
  ExpectWellFormed(m, "single cell");
}

TEST(MeshGenVoxel, ConformingCompactedAndCountsExposedFaces) {
  const Eigen::Vector3i n(5, 4, 6);
  // A deterministic pattern of kept cells, kept connected through the full bottom layer.
  auto keep = [](const Eigen::Vector3i& c) {
    if (c[2] == 0) return true;
    const unsigned hsh =
        unsigned(c[0] * 73856093) ^ unsigned(c[1] * 19349663) ^ unsigned(c[2] * 83492791);
    return (hsh % 3) != 0 || c[0] == 0;
  };
  std::vector<char> kept(n.prod(), 0);
  auto idx = [&](int i, int j, int k) { return i + n[0] * (j + n[1] * k); };
  int ncells = 0;
  for (int k = 0; k < n[2]; ++k)
    for (int j = 0; j < n[1]; ++j)
      for (int i = 0; i < n[0]; ++i)
        if (keep(Eigen::Vector3i(i, j, k))) kept[idx(i, j, k)] = 1, ++ncells;
  const double h = 0.7;
  const Mesh m = VoxelTetMesh(Eigen::Vector3d::Zero(), h, n,
                              [&](const Eigen::Vector3d& centre, const Eigen::Vector3i& c) {
                                // The centre is consistent with the index.
                                EXPECT_NEAR(centre[0], (c[0] + 0.5) * h, 1e-12);
                                return keep(c) ? c[2] % 2 : -1;
                              });
  EXPECT_EQ(m.num_elements(), 6 * ncells);
  EXPECT_NEAR(TotalVolume(m), ncells * h * h * h, 1e-9);
  ExpectWellFormed(m, "voxel pattern");
  // Each exposed square cell face is two boundary triangles.
  int exposed = 0;
  for (int k = 0; k < n[2]; ++k)
    for (int j = 0; j < n[1]; ++j)
      for (int i = 0; i < n[0]; ++i) {
        if (!kept[idx(i, j, k)]) continue;
        const int nb[6][3] = {{i - 1, j, k}, {i + 1, j, k}, {i, j - 1, k},
                              {i, j + 1, k}, {i, j, k - 1}, {i, j, k + 1}};
        for (const auto& q : nb) {
          const bool in =
              q[0] >= 0 && q[0] < n[0] && q[1] >= 0 && q[1] < n[1] && q[2] >= 0 && q[2] < n[2];
          if (!in || !kept[idx(q[0], q[1], q[2])]) ++exposed;
        }
      }
  EXPECT_EQ(Faces(m).boundary, 2 * exposed);
}

TEST(MeshGenVoxel, RejectsBadArguments) {
  auto all = [](const Eigen::Vector3d&, const Eigen::Vector3i&) { return 0; };
  EXPECT_THROW(VoxelTetMesh(Eigen::Vector3d::Zero(), 0.0, Eigen::Vector3i(1, 1, 1), all),
               std::invalid_argument);
  EXPECT_THROW(VoxelTetMesh(Eigen::Vector3d::Zero(), 1.0, Eigen::Vector3i(1, 0, 1), all),
               std::invalid_argument);
  EXPECT_THROW(VoxelTetMesh(Eigen::Vector3d::Zero(), 1.0, Eigen::Vector3i(1, 1, 1), nullptr),
               std::invalid_argument);
  // All cells empty: an empty mesh, not an error.
  const Mesh m = VoxelTetMesh(Eigen::Vector3d::Zero(), 1.0, Eigen::Vector3i(2, 2, 2),
                              [](const Eigen::Vector3d&, const Eigen::Vector3i&) { return -1; });
  EXPECT_EQ(m.num_vertices(), 0);
  EXPECT_EQ(m.num_elements(), 0);
}

// SymmetricVoxelTetMesh: an even count is VoxelTetMesh's grid exactly; an odd count across a
// mirror axis becomes one more cell of equal size over the same box, each new cell tagged as the
// original cell holding its centre; the tets are then mirror images about the mid-plane, which
// the plain split over an odd count is not (every one of its tets leans the same way).
TEST(MeshGenVoxel, SymmetricGridCutsAnOddCountIntoOneMoreCell) {
  const double h = 1.5;
  const Eigen::Vector3d o(1, -2, 0.5);
  // A design symmetric in y over 5 cells: walls j = 0 and 4 (tag 0), a cavity j = 1..3 (tag 1).
  auto design = [&](const Eigen::Vector3d& centre, const Eigen::Vector3i& c) {
    EXPECT_NEAR(centre[1], o[1] + (c[1] + 0.5) * h, 1e-12);  // the original cell's centre
    EXPECT_GE(c[1], 0);
    EXPECT_LT(c[1], 5);
    return c[1] == 0 || c[1] == 4 ? 0 : 1;
  };
  const Eigen::Vector3i n(4, 5, 3);
  const Mesh plain = VoxelTetMesh(o, h, n, design);
  const Mesh sym = SymmetricVoxelTetMesh(o, h, n, {false, true, false}, design);
  const double mid = o[1] + 2.5 * h;
  EXPECT_EQ(test::UnmatchedMirrorElements(plain, 1, mid), plain.num_elements());
  EXPECT_EQ(test::UnmatchedMirrorElements(sym, 1, mid), 0);
  EXPECT_EQ(sym.num_elements(), 6 * 4 * 6 * 3);  // 6 cells across y instead of 5
  ExpectWellFormed(sym, "symmetric grid");
  // The same box, the same total volume; the walls are one of six equal cells each.
  EXPECT_LT((sym.vertices.colwise().minCoeff() - plain.vertices.colwise().minCoeff()).norm(),
            1e-12);
  EXPECT_LT((sym.vertices.colwise().maxCoeff() - plain.vertices.colwise().maxCoeff()).norm(),
            1e-12);
  EXPECT_NEAR(TotalVolume(sym), TotalVolume(plain), 1e-9);
  double wall = 0;
  for (const auto& e : sym.elements)
    if (e.region == 0) wall += TetVol(sym, e);
  EXPECT_NEAR(wall, 2 * (5 * h / 6) * 4 * h * 3 * h, 1e-9);
  // Even counts, and axes not asked for, keep VoxelTetMesh's mesh bit for bit.
  const Mesh even = SymmetricVoxelTetMesh(
      o, h, Eigen::Vector3i(4, 4, 5), {true, true, false},
      [](const Eigen::Vector3d& c, const Eigen::Vector3i& k) { return (c.x() > 2.0) + k[2] % 2; });
  const Mesh ref = VoxelTetMesh(
      o, h, Eigen::Vector3i(4, 4, 5),
      [](const Eigen::Vector3d& c, const Eigen::Vector3i& k) { return (c.x() > 2.0) + k[2] % 2; });
  ASSERT_EQ(even.num_elements(), ref.num_elements());
  EXPECT_EQ(even.vertices, ref.vertices);
  for (int e = 0; e < ref.num_elements(); ++e) {
    EXPECT_EQ(even.elements[e].v, ref.elements[e].v);
    EXPECT_EQ(even.elements[e].region, ref.elements[e].region);
  }
  EXPECT_THROW(SymmetricVoxelTetMesh(o, 0.0, n, {true, true, true}, design), std::invalid_argument);
  EXPECT_THROW(SymmetricVoxelTetMesh(o, h, Eigen::Vector3i(1, 0, 1), {true, true, true}, design),
               std::invalid_argument);
  EXPECT_THROW(SymmetricVoxelTetMesh(o, h, n, {true, true, true}, nullptr), std::invalid_argument);
}

// ---------------------------------------------------------------------------------------------
// MeshGen: concentric disk and its extrusion
// ---------------------------------------------------------------------------------------------

TEST(MeshGenDisk, RingsCountsAreaAndCounterClockwise) {
  for (int nr : {1, 2, 3, 7}) {
    SCOPED_TRACE(nr);
    const double R = 3.0;
    const ConcentricDisk d = MakeConcentricDisk(R, nr);
    ASSERT_EQ(d.num_points(), 1 + 3 * nr * (nr + 1));
    ASSERT_EQ(static_cast<int>(d.triangles.size()), 6 * nr * nr);
    double area = 0.0;
    int cw = 0;
    std::set<std::array<int, 3>> seen;
    for (const auto& t : d.triangles) {
      const Eigen::Vector2d a = d.points.row(t[0]).transpose();
      const Eigen::Vector2d u = d.points.row(t[1]).transpose() - a;
      const Eigen::Vector2d v = d.points.row(t[2]).transpose() - a;
      const double A = 0.5 * (u.x() * v.y() - u.y() * v.x());
      if (!(A > 0.0)) ++cw;
      area += A;
      std::array<int, 3> s = t;
      std::sort(s.begin(), s.end());
      EXPECT_TRUE(seen.insert(s).second) << "duplicate triangle";
      // Keys are distinct within a triangle.
      EXPECT_NE(d.key(t[0]), d.key(t[1]));
      EXPECT_NE(d.key(t[1]), d.key(t[2]));
      EXPECT_NE(d.key(t[0]), d.key(t[2]));
    }
    EXPECT_EQ(cw, 0);
    const int n = 6 * nr;
    const double pi = std::acos(-1.0);
    EXPECT_NEAR(area, 0.5 * n * R * R * std::sin(2 * pi / n), 1e-12);
    for (int p = 0; p < d.num_points(); ++p) {
      const double r = d.points.row(p).norm();
      EXPECT_NEAR(r, R * d.ring[p] / nr, 1e-12);
      EXPECT_EQ(d.id(d.ring[p], d.index[p]), p);
      EXPECT_EQ(d.key(d.rotated(p, 1)), d.key(p));
      EXPECT_EQ(d.rotated(d.rotated(p, 1), -1), p);
    }
  }
}

TEST(MeshGenDisk, ExtrusionIsConformingPositiveAndHasTheExpectedFaces) {
  for (int axis : {0, 1, 2}) {
    SCOPED_TRACE(axis);
    DiskExtrusion p;
    p.radius = 5.0;
    p.rings = 4;
    p.length = 12.0;
    p.layers = 5;
    p.axis = axis;
    p.base = -1.0;
    const Mesh m = ExtrudedDiskTetMesh(p);
    const int T = 6 * p.rings * p.rings, np = 1 + 3 * p.rings * (p.rings + 1);
    ASSERT_EQ(m.num_elements(), 3 * T * p.layers);
    ASSERT_EQ(m.num_vertices(), np * (p.layers + 1));
    ExpectWellFormed(m, "extruded disk");
    const FaceStats f = Faces(m);
    // Boundary: top and bottom disks (T triangles each) + side quads (6 rings per layer, 2 each).
    EXPECT_EQ(f.boundary, 2 * T + 2 * 6 * p.rings * p.layers);
    EXPECT_EQ(f.interior, (4 * m.num_elements() - f.boundary) / 2);
    const int n = 6 * p.rings;
    const double pi = std::acos(-1.0);
    const double area = 0.5 * n * p.radius * p.radius * std::sin(2 * pi / n);
    EXPECT_NEAR(TotalVolume(m), area * p.length, 1e-9);
    for (int v = 0; v < m.num_vertices(); ++v) {
      EXPECT_GE(m.vertices(v, axis), p.base - 1e-12);
      EXPECT_LE(m.vertices(v, axis), p.base + p.length + 1e-12);
    }
  }
}

TEST(MeshGenDisk, ExtrusionIsExactlyThreeFoldSymmetric) {
  for (int axis : {0, 1, 2}) {
    SCOPED_TRACE(axis);
    DiskExtrusion p;
    p.radius = 10.0;
    p.rings = 5;
    p.length = 8.0;
    p.layers = 3;
    p.axis = axis;
    const std::array<int, 2> pl = DiskPlaneAxes(axis);
    int checked = 0;
    // Tag by sector: the rotation must map sector s onto s+1; and the canonical centroid rotated
    // by the sector must be the centroid.
    const Mesh m = ExtrudedDiskTetMesh(p, [&](const DiskElementInfo& e) {
      Eigen::Vector3d c = e.canonical_centroid;
      for (int s = 0; s < e.sector; ++s) c = Rot120(c, pl[0], pl[1]);
      EXPECT_LT((c - e.centroid).norm(), 1e-12);
      ++checked;
      return e.sector;
    });
    EXPECT_EQ(checked, m.num_elements());
    ExpectThreeFold(m, pl[0], pl[1], [](int r) { return (r + 1) % 3; });
    // And the reflection across the first in-plane axis.
    const Mesh plain = ExtrudedDiskTetMesh(p);
    ExpectMapsOntoItself(
        plain, [&](const Eigen::Vector3d& x) { return Reflect(x, pl[1]); },
        [](int r) { return r; });
  }
}

TEST(MeshGenDisk, RejectsBadArguments) {
  EXPECT_THROW(MakeConcentricDisk(0.0, 3), std::invalid_argument);
  EXPECT_THROW(MakeConcentricDisk(1.0, 0), std::invalid_argument);
  DiskExtrusion p;
  p.layers = 0;
  EXPECT_THROW(ExtrudedDiskTetMesh(p), std::invalid_argument);
  p.layers = 2;
  p.axis = 3;
  EXPECT_THROW(ExtrudedDiskTetMesh(p), std::invalid_argument);
  p.axis = 2;
  EXPECT_THROW(ExtrudedDiskTetMesh(p, [](const DiskElementInfo&) { return -1; }),
               std::invalid_argument);
}

// ---------------------------------------------------------------------------------------------
// Robots
// ---------------------------------------------------------------------------------------------

TEST(Robots, ListsEveryRobotAndRejectsBadInput) {
  const std::vector<RobotInfo> list = ListRobots();
  const std::vector<std::string> names = {
      "pneumatic_finger",      "three_chamber", "cable_finger",   "finger_manipulator",
      "multi_segment_gripper", "dea_crawler",   "bimaterial_bar", "cable_gripper",
      "selfcollision_finger",  "membrane",      "twisting_robot", "bilayer_strip"};
  ASSERT_EQ(list.size(), names.size());
  for (size_t i = 0; i < names.size(); ++i) EXPECT_EQ(list[i].name, names[i]);
  for (const auto& r : list) {
    EXPECT_GT(r.default_resolution, 0);
    EXPECT_FALSE(r.description.empty());
    EXPECT_FALSE(r.resolution_doc.empty());
  }
  try {
    MakeRobot("x");
    FAIL() << "no exception";
  } catch (const std::invalid_argument& e) {
    EXPECT_EQ(
        std::string(e.what()),
        "unknown robot 'x'; known robots: pneumatic_finger, three_chamber, cable_finger, "
        "finger_manipulator, multi_segment_gripper, dea_crawler, bimaterial_bar, cable_gripper, "
        "selfcollision_finger, membrane, twisting_robot, bilayer_strip");
  }
  try {
    MakeRobot("pneumatic_finger", 2);
    FAIL() << "no exception";
  } catch (const std::invalid_argument& e) {
    EXPECT_EQ(std::string(e.what()),
              "pneumatic_finger: --res must be an integer in [5, 40], got 2");
  }
  EXPECT_THROW(MakeRobot("pneumatic_finger", 41), std::invalid_argument);
  EXPECT_THROW(MakeRobot("three_chamber", 2), std::invalid_argument);
  EXPECT_THROW(MakeRobot("three_chamber", 17), std::invalid_argument);
}

TEST(Robots, EveryRobotIsValidWellFormedAndDeterministic) {
  for (const auto& info : ListRobots()) {
    SCOPED_TRACE(info.name);
    const Scene a = MakeRobot(info.name);
    const Scene b = MakeRobot(info.name, info.default_resolution);
    EXPECT_NO_THROW(a.validate());
    EXPECT_EQ(a.name, info.name);
    if (a.mesh.num_prisms() == 0) {
      ExpectWellFormed(a.mesh, info.name);
    } else {
      // Prism meshes (PrismGridMesh, tested in test_constraints.cpp): oriented, no unused vertex.
      for (const auto& e : a.mesh.elements) EXPECT_GT(SignedVolume(e, a.mesh.vertices), 0.0);
      EXPECT_EQ(UnusedVertices(a.mesh), 0);
    }
    EXPECT_TRUE(SameMesh(a.mesh, b.mesh)) << "two builds differ";
    EXPECT_EQ(a.fixed, b.fixed);
    ASSERT_EQ(a.markers.size(), b.markers.size());
    for (size_t i = 0; i < a.markers.size(); ++i)
      EXPECT_EQ(a.markers[i].vertices, b.markers[i].vertices);
    EXPECT_TRUE(std::is_sorted(a.fixed.begin(), a.fixed.end()));
    EXPECT_TRUE(std::adjacent_find(a.fixed.begin(), a.fixed.end()) == a.fixed.end());
    EXPECT_GE(a.marker_index("tip"), 0);
    for (const auto& act : a.actuators) {
      SCOPED_TRACE(act.name);
      EXPECT_LT(act.min, act.max);
      EXPECT_GE(act.rest, act.min);
      EXPECT_LE(act.rest, act.max);
      if (act.is_motion() || act.is_signed()) {
        // Motion: rest = no motion; signed pneumatic: rest 0 = both sides vented.
        EXPECT_EQ(act.rest, 0.0);
      } else if (act.type == ActuatorType::Pneumatic) {
        // Chambers inflate from ratio 1.
        EXPECT_EQ(act.rest, 1.0);
        EXPECT_EQ(act.min, 1.0);
      } else if (act.type == ActuatorType::Cable) {
        // Cables shorten from ratio 1.
        EXPECT_EQ(act.rest, 1.0);
        EXPECT_EQ(act.max, 1.0);
        EXPECT_GE(act.path.size(), 2u);
      } else {
        // DEA: the crawler rests at its released pre-stretch lambda_init < 1 (the mesh is the
        // stretched state, ratio 1).
        EXPECT_EQ(act.type, ActuatorType::Dea);
        EXPECT_LE(act.rest, 1.0);
      }
    }
  }
}

TEST(Robots, DefaultResolutionScenesHaveTheirSizes) {
  // Each robot at its default resolution: elements, vertices, fixed vertices, actuators and
  // markers. The grid robots' counts follow from integer cell layouts and are exact
  // (pneumatic_finger's are those of its documentation: 27 res^3 tets, 9,490 vertices at res 12);
  // the twisting robot's CGAL Mesh_3 tessellation is held to the 6.2k tets its resolution doc
  // states, within 3 %.
  struct Size {
    const char* name;
    int elements, vertices, fixed, actuators, markers;
  };
  const std::vector<Size> sizes = {
      {"pneumatic_finger", 46656, 9490, 130, 1, 3},
      {"three_chamber", 35280, 6929, 169, 3, 1},
      {"cable_finger", 25200, 5533, 121, 3, 3},
      {"finger_manipulator", 15840, 3528, 63, 3, 3},
      {"multi_segment_gripper", 19296, 4284, 63, 3, 5},
      {"dea_crawler", 896, 783, 27, 1, 4},
      {"bimaterial_bar", 2688, 725, 25, 2, 4},
      {"cable_gripper", 15360, 3321, 81, 1, 4},
      {"selfcollision_finger", 13824, 3447, 63, 1, 3},
      {"membrane", 7008, 2178, 484, 4, 5},
      {"twisting_robot", 6200, -1, -1, 1, 2},  // Mesh_3: elements approximately, the rest unpinned
      {"bilayer_strip", 24000, 5555, 55, 1, 3},
  };
  const std::vector<RobotInfo> list = ListRobots();
  ASSERT_EQ(list.size(), sizes.size());
  for (size_t i = 0; i < sizes.size(); ++i) {
    const Size& z = sizes[i];
    SCOPED_TRACE(z.name);
    ASSERT_EQ(list[i].name, z.name);
    const Scene s = MakeRobot(z.name);
    EXPECT_NO_THROW(s.validate());
    EXPECT_EQ(s.num_actuators(), z.actuators);
    EXPECT_EQ(static_cast<int>(s.markers.size()), z.markers);
    if (z.vertices < 0) {
      EXPECT_NEAR(s.mesh.num_elements(), z.elements, 0.03 * z.elements);
      continue;
    }
    EXPECT_EQ(s.mesh.num_elements(), z.elements);
    EXPECT_EQ(s.mesh.num_vertices(), z.vertices);
    EXPECT_EQ(static_cast<int>(s.fixed.size()), z.fixed);
  }
}

// ---- pneumatic_finger ----

TEST(RobotsPneumaticFinger, DefaultSizeRegionsAndMaterials) {
  const Scene s = MakeRobot("pneumatic_finger");
  const int n = s.mesh.num_elements();
  EXPECT_GE(n, 40500);
  EXPECT_LE(n, 49500);
  ASSERT_EQ(s.num_actuators(), 1);
  EXPECT_EQ(s.actuators[0].name, "chamber");
  EXPECT_EQ(s.actuators[0].regions, std::vector<int>{1});
  ASSERT_EQ(s.body.size(), 2u);
  EXPECT_EQ(s.body.at(0).name, "body");
  EXPECT_EQ(s.body.at(2).name, "inextensible");
  std::set<int> regions;
  for (const auto& e : s.mesh.elements) regions.insert(e.region);
  EXPECT_EQ(regions, (std::set<int>{0, 1, 2}));
  EXPECT_GT(CountRegion(s.mesh, 1), n / 10);
  // Bounding box 120 x 20 x 15 mm (9 cells of 20/12 mm in height).
  const Eigen::RowVector3d lo = s.mesh.vertices.colwise().minCoeff();
  const Eigen::RowVector3d hi = s.mesh.vertices.colwise().maxCoeff();
  EXPECT_LT((lo - Eigen::RowVector3d(0, 0, 0)).norm(), 1e-9);
  EXPECT_LT((hi - Eigen::RowVector3d(120, 20, 15)).norm(), 1e-9);
  // The inextensible layer is the bottom cell layer; it is heavier than the body.
  for (const auto& e : s.mesh.elements) {
    if (e.region != 2) continue;
    for (int j = 0; j < 4; ++j) ASSERT_LE(s.mesh.vertices(e.v[j], 2), 20.0 / 12 + 1e-9);
  }
  EXPECT_GT(s.body.at(2).weight, s.body.at(0).weight);
  EXPECT_EQ(s.actuators[0].min, 1.0);
  EXPECT_EQ(s.actuators[0].max, 10.0);
}

TEST(RobotsPneumaticFinger, FixedBaseAndTipMarkers) {
  const Scene s = MakeRobot("pneumatic_finger");
  const Mesh& m = s.mesh;
  int on_plane = 0;
  for (int v = 0; v < m.num_vertices(); ++v) on_plane += std::abs(m.vertices(v, 0)) < 1e-9;
  EXPECT_EQ(static_cast<int>(s.fixed.size()), on_plane);
  for (int v : s.fixed) EXPECT_NEAR(m.vertices(v, 0), 0.0, 1e-9);
  for (const char* name : {"tip", "tip_top", "tip_bottom"}) {
    const int k = s.marker_index(name);
    ASSERT_GE(k, 0) << name;
    for (int v : s.markers[k].vertices) EXPECT_NEAR(m.vertices(v, 0), 120.0, 1e-9) << name;
  }
  const Eigen::MatrixX3d P = s.marker_positions(m.vertices);
  const Eigen::Vector3d tip = P.row(s.marker_index("tip")).transpose();
  const Eigen::Vector3d top = P.row(s.marker_index("tip_top")).transpose();
  const Eigen::Vector3d bot = P.row(s.marker_index("tip_bottom")).transpose();
  EXPECT_NEAR(tip.x(), 120.0, 1e-9);
  EXPECT_NEAR(tip.y(), 10.0, 1e-9);
  const double height = m.vertices.col(2).maxCoeff();
  EXPECT_NEAR(height, 15.0, 1e-9);
  EXPECT_NEAR(tip.z(), height / 2, 1e-9);
  EXPECT_NEAR(top.y(), 10.0, 1e-9);
  EXPECT_NEAR(bot.y(), 10.0, 1e-9);
  EXPECT_GE(top.z(), 0.75 * height);
  EXPECT_LE(bot.z(), 0.25 * height);
}

TEST(RobotsPneumaticFinger, FeaturesSurviveEveryResolution) {
  // Walls enclose every cavity, single walls separate the chambers, the base layer and the floor
  // exist under every cavity, and the finger keeps its 120 x 20 x 15 mm size.
  for (int res : {5, 6, 7, 8, 9, 10, 12, 15, 16, 20}) {
    SCOPED_TRACE(res);
    const Scene s = MakeRobot("pneumatic_finger", res);
    const Mesh& m = s.mesh;
    const double h = 20.0 / res;
    ExpectWellFormed(m, "finger");
    EXPECT_GT(CountRegion(m, 2), 0);
    EXPECT_EQ(RegionTetsOnBoundary(m, {1}), 0) << "a cavity element lies on the outer surface";
    const int chambers = Components(m, [](const Element& e) { return e.region == 1; });
    const int body_parts = Components(m, [](const Element& e) { return e.region == 0; });
    EXPECT_EQ(body_parts, 1) << "the walls, floor and proximal block form one connected part";
    for (const auto& e : m.elements) {
      if (e.region != 1) continue;  // cavities sit above the base layer and the floor
      for (int j = 0; j < 4; ++j) ASSERT_GE(m.vertices(e.v[j], 2), 2 * h - 1e-9);
    }
    // Chambers: cavities ~5 mm long between ~1.5 mm walls along ~110 mm.
    const int pitch =
        std::max(1, int(std::lround(5.0 / h))) + std::max(1, int(std::lround(1.5 / h)));
    EXPECT_GE(chambers * pitch * h, 95.0);
    EXPECT_GE(chambers, 8);
    const Eigen::RowVector3d hi = m.vertices.colwise().maxCoeff();
    EXPECT_LT((hi.head<2>() - Eigen::RowVector2d(120, 20)).norm(), 1e-9);
    EXPECT_NEAR(hi(2), 15.0, 0.5 * h + 1e-9);
  }
}

TEST(RobotsPneumaticFinger, CellCountScalesAsResCubed) {
  auto tets = [](int res) {
    return double(MakeRobot("pneumatic_finger", res).mesh.num_elements());
  };
  const double n8 = tets(8), n12 = tets(12), n16 = tets(16), n24 = tets(24);
  EXPECT_NEAR(n16 / n8, 8.0, 8.0 * 0.2);
  EXPECT_NEAR(n24 / n12, 8.0, 8.0 * 0.2);
  // tets / res^3 stays roughly constant.
  for (auto [n, r] : {std::pair<double, int>{n8, 8}, {n12, 12}, {n16, 16}, {n24, 24}})
    EXPECT_NEAR(n / (r * r * r), 27.0, 3.0) << "res " << r;
}

// ---- three_chamber ----

TEST(RobotsThreeChamber, DimensionsActuatorsFixedAndTip) {
  const Scene s = MakeRobot("three_chamber");
  const Mesh& m = s.mesh;
  const int n = m.num_elements();
  EXPECT_GE(n, 30000);
  EXPECT_LE(n, 40000);
  const Eigen::RowVector3d lo = m.vertices.colwise().minCoeff();
  const Eigen::RowVector3d hi = m.vertices.colwise().maxCoeff();
  EXPECT_NEAR(lo.y(), 0.0, 1e-12);
  EXPECT_NEAR(hi.y(), 136.0, 1e-9);
  EXPECT_NEAR(hi.x() - lo.x(), 48.0, 1e-9);
  EXPECT_NEAR(hi.z() - lo.z(), 48.0, 0.5);  // polygonal disk: 48 cos(pi / 6 res) in z
  ASSERT_EQ(s.num_actuators(), 3);
  for (int k = 0; k < 3; ++k) {
    EXPECT_EQ(s.actuators[k].name, "c" + std::to_string(k + 1));
    EXPECT_EQ(s.actuators[k].regions, std::vector<int>{k + 1});
    EXPECT_GT(CountRegion(m, k + 1), 0);
  }
  EXPECT_EQ(s.body.size(), 1u);
  EXPECT_EQ(s.body.at(0).name, "body");
  int on_plane = 0;
  for (int v = 0; v < m.num_vertices(); ++v) on_plane += std::abs(m.vertices(v, 1)) < 1e-9;
  EXPECT_EQ(static_cast<int>(s.fixed.size()), on_plane);
  for (int v : s.fixed) EXPECT_NEAR(m.vertices(v, 1), 0.0, 1e-12);
  const int t = s.marker_index("tip");
  ASSERT_GE(t, 0);
  for (int v : s.markers[t].vertices) EXPECT_NEAR(m.vertices(v, 1), 136.0, 1e-9);
  const Eigen::Vector3d tip = Centroid(m, s.markers[t].vertices);
  EXPECT_LT((tip - Eigen::Vector3d(0, 136, 0)).norm(), 1e-9);
  // Chamber c1 is centred on -x (phi = 180 deg), at ~13 mm from the axis.
  Eigen::Vector3d c1 = Eigen::Vector3d::Zero();
  double vol = 0.0;
  for (const auto& e : m.elements) {
    if (e.region != 1) continue;
    const double v = TetVol(m, e);
    Eigen::Vector3d c = Eigen::Vector3d::Zero();
    for (int j = 0; j < 4; ++j) c += m.vertices.row(e.v[j]).transpose() / 4.0;
    c1 += v * c;
    vol += v;
  }
  c1 /= vol;
  EXPECT_NEAR(c1.x(), -13.0, 1.5);
  EXPECT_NEAR(c1.z(), 0.0, 0.05);  // the mesh is 3-fold but not mirror symmetric
  EXPECT_NEAR(c1.y(), 68.0, 2.0);
}

TEST(RobotsThreeChamber, ExactlyThreeFoldAndMirrorSymmetricWithEqualChambers) {
  for (int res : {3, 7}) {
    SCOPED_TRACE(res);
    const Scene s = MakeRobot("three_chamber", res);
    // phi = atan2(z, x): rotate from +x towards +z; chamber k -> k+1, body -> body.
    ExpectThreeFold(s.mesh, 0, 2, [](int r) { return r == 0 ? 0 : 1 + r % 3; });
    // The mirror z -> -z through c1's axis (phi = 180 degrees) keeps c1 and swaps c2 and c3.
    ExpectMapsOntoItself(
        s.mesh, [](const Eigen::Vector3d& x) { return Reflect(x, 2); },
        [](int r) { return r == 2   ? 3
                           : r == 3 ? 2
                                    : r; });
    const double v1 = TotalVolume(s.mesh, 1), v2 = TotalVolume(s.mesh, 2),
                 v3 = TotalVolume(s.mesh, 3);
    EXPECT_GT(v1, 0.0);
    EXPECT_NEAR(v2, v1, 1e-9 * v1);
    EXPECT_NEAR(v3, v1, 1e-9 * v1);
    EXPECT_EQ(CountRegion(s.mesh, 1), CountRegion(s.mesh, 2));
    EXPECT_EQ(CountRegion(s.mesh, 1), CountRegion(s.mesh, 3));
  }
}

TEST(RobotsThreeChamber, ChambersAreEnclosedAndSeparateAtEveryResolution) {
  for (int res = 3; res <= 12; ++res) {
    SCOPED_TRACE(res);
    const Scene s = MakeRobot("three_chamber", res);
    const Mesh& m = s.mesh;
    if (res <= 8) ExpectWellFormed(m, "three_chamber");
    EXPECT_EQ(RegionTetsOnBoundary(m, {1, 2, 3}), 0);
    // No vertex is shared by two different chambers; each chamber is one piece.
    std::vector<int> owner(m.num_vertices(), 0);
    int shared = 0;
    for (const auto& e : m.elements) {
      if (e.region == 0) continue;
      for (int j = 0; j < 4; ++j) {
        int& o = owner[e.v[j]];
        if (o != 0 && o != e.region) ++shared;
        o = e.region;
      }
    }
    EXPECT_EQ(shared, 0);
    for (int r = 1; r <= 3; ++r)
      EXPECT_EQ(Components(m, [r](const Element& e) { return e.region == r; }), 1);
  }
}

}  // namespace
}  // namespace softkin

namespace softkin {
namespace {

// The twisting robot's strain-limiting strip: body tets beyond x = 10 - strip become region 2 with
// strip_weight times the body's weight; without a strip there is no region 2.
TEST(RobotsTwisting, StrainLimitingStripRegion) {
  const Scene plain = MakeRobot("twisting_robot", 1, {{"hyperelastic", 0.0}});
  EXPECT_EQ(plain.body.count(2), 0u);
  const Scene s = MakeRobot("twisting_robot", 1,
                            {{"hyperelastic", 0.0}, {"strip", 3.0}, {"strip_weight", 40.0}});
  ASSERT_EQ(s.body.count(2), 1u);
  EXPECT_DOUBLE_EQ(s.body.at(2).weight, 40.0 * s.body.at(0).weight);
  EXPECT_EQ(s.mesh.num_elements(), plain.mesh.num_elements());
  int strip = 0;
  for (int i = 0; i < s.mesh.num_elements(); ++i) {
    const auto& e = s.mesh.elements[i];
    EXPECT_EQ(e.region == 1, plain.mesh.elements[i].region == 1);  // chamber untouched
    if (e.region != 2) continue;
    ++strip;
    double cx = 0;
    for (int j = 0; j < 4; ++j) cx += s.mesh.vertices(e.v[j], 0) / 4;
    EXPECT_GT(cx, 7.0);
  }
  EXPECT_GT(strip, 50);
}

// The membrane's chambers stand chamber_gap cells apart: the gap between the wall boxes (region 1
// and the cavities) of neighbouring chambers along x and y is exactly that many cells.
TEST(RobotsSelfCollisionFinger, WallParameterSetsTheTetLayersOfTheChamberWalls) {
  // At res 12 (cells of 20/12 mm) the default 1.5 mm wall snaps to one cell; 3.34 mm to two. The
  // side walls are the cells between the cavities (region 1) and the finger's sides y = 0, 20.
  const int res = 12;
  const double h = 20.0 / res;
  for (const auto& [wall, cells] : std::vector<std::pair<double, int>>{{1.5, 1}, {3.34, 2}}) {
    SCOPED_TRACE(wall);
    const Scene s = MakeRobot("selfcollision_finger", res, {{"wall", wall}});
    double ymin = 1e9, ymax = -1e9;
    int cavity = 0;
    for (const auto& e : s.mesh.elements) {
      if (e.region != 1) continue;
      ++cavity;
      for (int j = 0; j < 4; ++j) {
        ymin = std::min(ymin, s.mesh.vertices(e.v[j], 1));
        ymax = std::max(ymax, s.mesh.vertices(e.v[j], 1));
      }
    }
    ASSERT_GT(cavity, 0);
    EXPECT_NEAR(ymin, cells * h, 1e-9);
    EXPECT_NEAR(20.0 - ymax, cells * h, 1e-9);
  }
  try {
    MakeRobot("selfcollision_finger", res, {{"wall", 0.5}});
    FAIL() << "no exception";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("wall"), std::string::npos) << e.what();
  }
}

TEST(RobotsMembrane, ChambersStandChamberGapCellsApart) {
  for (int gap : {1, 2, 3}) {
    const int res = 24;
    const double h = 250.0 / res;
    const Scene s = MakeRobot("membrane", res, {{"chamber_gap", double(gap)}});
    // The x extent of the chamber elements (every region but the membrane's 0) left of and right
    // of the middle, over the rows y < 125.
    double left_max = -1, right_min = 1e9;
    for (int e = 0; e < s.mesh.num_elements(); ++e) {
      if (s.mesh.elements[e].region == 0) continue;
      double cx = 0, cy = 0;
      for (int j = 0; j < 4; ++j) {
        cx += s.mesh.vertices(s.mesh.elements[e].v[j], 0) / 4;
        cy += s.mesh.vertices(s.mesh.elements[e].v[j], 1) / 4;
      }
      if (cy > 125) continue;
      for (int j = 0; j < 4; ++j) {
        const double x = s.mesh.vertices(s.mesh.elements[e].v[j], 0);
        if (cx < 125)
          left_max = std::max(left_max, x);
        else
          right_min = std::min(right_min, x);
      }
    }
    EXPECT_NEAR(right_min - left_max, gap * h, 1e-9) << "chamber_gap " << gap;
  }
  try {
    MakeRobot("membrane", 24, {{"chamber_gap", 1.5}});
    FAIL() << "no exception";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("chamber_gap: expected an integer"), std::string::npos)
        << e.what();
  }
  try {
    MakeRobot("membrane", 10, {{"chamber_gap", 3}});
    FAIL() << "no exception";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("expected at least 3"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace softkin
