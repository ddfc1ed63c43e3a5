#include "softkin/solver/collision/collision.hpp"
#include "softkin/solver/common/stopwatch.hpp"

#include <CGAL/AABB_face_graph_triangle_primitive.h>
#include <CGAL/AABB_traits.h>
#include <CGAL/AABB_tree.h>
#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Box_intersection_d/Box_with_info_d.h>
#include <CGAL/Side_of_triangle_mesh.h>
#include <CGAL/box_intersection_d.h>
#include <CGAL/Surface_mesh.h>

#include <algorithm>
#include <array>
#include <cassert>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <fstream>
#include <limits>
#include <map>
#include <sstream>
#include <stdexcept>

#include <omp.h>

namespace softkin {

namespace {

using K = CGAL::Exact_predicates_inexact_constructions_kernel;
using CPoint = K::Point_3;
using SurfaceMesh = CGAL::Surface_mesh<CPoint>;
using FacePrimitive = CGAL::AABB_face_graph_triangle_primitive<SurfaceMesh>;
using FaceTree = CGAL::AABB_tree<CGAL::AABB_traits<K, FacePrimitive>>;
using Inside = CGAL::Side_of_triangle_mesh<SurfaceMesh, K>;
using Clock = std::chrono::steady_clock;

[[noreturn]] void Fail(const std::string& where, const std::string& what) {
  throw std::invalid_argument(where + ": " + what);
}

Eigen::Vector3d FaceNormal(const TriangleSurface& s, int f) {
  const Eigen::Vector3d a = s.vertices.row(s.faces(f, 0)), b = s.vertices.row(s.faces(f, 1)),
                        c = s.vertices.row(s.faces(f, 2));
  return (b - a).cross(c - a).normalized();
}

CPoint P(const Eigen::Ref<const Eigen::MatrixX3d>& X, int v) {
  return CPoint(X(v, 0), X(v, 1), X(v, 2));
}

}  // namespace

// ---- Obstacle ----------------------------------------------------------------------------------

struct Obstacle::Impl {
  SurfaceMesh mesh;
  FaceTree tree;
  std::unique_ptr<Inside> inside;
};

Obstacle::Obstacle(TriangleSurface surface)
    : surface_(std::move(surface)), impl_(std::make_unique<Impl>()) {
  CheckClosedSurface(&surface_);
  box_min_ = surface_.vertices.colwise().minCoeff().transpose();
  box_max_ = surface_.vertices.colwise().maxCoeff().transpose();
  auto& m = impl_->mesh;
  std::vector<SurfaceMesh::Vertex_index> vi;
  for (int i = 0; i < surface_.vertices.rows(); ++i)
    vi.push_back(m.add_vertex(P(surface_.vertices, i)));
  for (int f = 0; f < surface_.faces.rows(); ++f)
    if (m.add_face(vi[surface_.faces(f, 0)], vi[surface_.faces(f, 1)], vi[surface_.faces(f, 2)]) ==
        SurfaceMesh::null_face())
      Fail(surface_.source,
           "triangle " + std::to_string(f) + " cannot be added to a manifold surface");
  impl_->tree.rebuild(faces(m).first, faces(m).second, m);
  impl_->tree.accelerate_distance_queries();
  impl_->inside = std::make_unique<Inside>(impl_->tree);
  // Build the lazily constructed search structures now, so that queries may run in parallel.
  (*impl_->inside)(P(surface_.vertices, 0));
  impl_->tree.closest_point(P(surface_.vertices, 0));
}

Obstacle::~Obstacle() = default;
Obstacle::Obstacle(Obstacle&&) noexcept = default;
Obstacle& Obstacle::operator=(Obstacle&&) noexcept = default;

bool Obstacle::Contains(const Eigen::Vector3d& p) const {
  // A point strictly inside the closed surface lies in its (closed) bounding box; the box test
  // is exact, so it only saves the ray casting.
  if ((p.array() < box_min_.array()).any() || (p.array() > box_max_.array()).any()) return false;
  return (*impl_->inside)(CPoint(p.x(), p.y(), p.z())) == CGAL::ON_BOUNDED_SIDE;
}

Eigen::Vector3d Obstacle::ClosestPoint(const Eigen::Vector3d& p, Eigen::Vector3d* normal) const {
  const auto cp = impl_->tree.closest_point_and_primitive(CPoint(p.x(), p.y(), p.z()));
  if (normal) *normal = FaceNormal(surface_, static_cast<int>(cp.second.idx()));
  return Eigen::Vector3d(cp.first.x(), cp.first.y(), cp.first.z());
}

// ---- self-collision ----------------------------------------------------------------------------

namespace {

/// Positions stored row by row, so that one vertex's coordinates are contiguous.
using RowX3 = Eigen::Matrix<double, Eigen::Dynamic, 3, Eigen::RowMajor>;

CPoint P(const RowX3& X, int v) { return CPoint(X(v, 0), X(v, 1), X(v, 2)); }

/// Cells with N corners (tets, triangles) indexing into positions that move (shared data).
template <int N>
struct CellData {
  const RowX3* X = nullptr;
  const std::vector<std::array<int, N>>* cells = nullptr;
};

/// One cell (a tet of the robot, a triangle of a moving surface), read from the current positions
/// in the shared data, for CGAL's tree. Datum: the CGAL object built from the N corners.
template <int N, class DatumT>
class CellPrimitive {
 public:
  using Id = int;
  using Point = CPoint;
  using Datum = DatumT;
  using Shared_data = CellData<N>;
  CellPrimitive() = default;
  template <class Iterator>
  CellPrimitive(Iterator it, const Shared_data&) : id_(*it) {}
  Id id() const { return id_; }
  Datum datum(const Shared_data& d) const {
    const auto& c = (*d.cells)[id_];
    if constexpr (N == 4)
      return Datum(P(*d.X, c[0]), P(*d.X, c[1]), P(*d.X, c[2]), P(*d.X, c[3]));
    else
      return Datum(P(*d.X, c[0]), P(*d.X, c[1]), P(*d.X, c[2]));
  }
  Point reference_point(const Shared_data& d) const { return P(*d.X, (*d.cells)[id_][0]); }
  static Shared_data construct_shared_data(const Shared_data& d) { return d; }

 private:
  int id_ = -1;
};

using TetData = CellData<4>;
using TetTree = CGAL::AABB_tree<CGAL::AABB_traits<K, CellPrimitive<4, K::Tetrahedron_3>>>;
using TriData = CellData<3>;
using TriTree = CGAL::AABB_tree<CGAL::AABB_traits<K, CellPrimitive<3, K::Triangle_3>>>;

// -- the point-in-tet test ------------------------------------------------------------------------
//
// With D = orient(a, b, c, d) and D_i the same determinant with vertex i replaced by p, the
// barycentric coordinates of p are D_i / D (Cramer). So p lies in the closed tet iff D != 0 and
// no D_i has the sign opposite to D. This is what CGAL's Tetrahedron_3::has_on_unbounded_side
// decides (after is_degenerate), and what the exact fallback computes with CGAL::orientation.

/// Margin of the floating-point filter, relative to the permanent of the determinant (the same
/// sum with absolute values). Evaluated in double as below, the error of det[b-a, c-a, d-a] is
/// below 7.8e-16 times that permanent (the bound of Shewchuk's orient3d filter, without
/// underflow); 1e-12 leaves a factor of ~1000 on top.
constexpr double kRelMargin = 1e-12;
/// Covers underflow in the products (the relative bound assumes none).
constexpr double kAbsMargin = 1e-280;

/// Sign of det[b - a, c - a, d - a], i.e. of CGAL::orientation(a, b, c, d), when the double
/// evaluation certifies it; 0 when it cannot (within the margin, overflow, NaN).
inline int FilteredOrientation(const double* a, const double* b, const double* c, const double* d) {
  const double bx = b[0] - a[0], by = b[1] - a[1], bz = b[2] - a[2];
  const double cx = c[0] - a[0], cy = c[1] - a[1], cz = c[2] - a[2];
  const double dx = d[0] - a[0], dy = d[1] - a[1], dz = d[2] - a[2];
  const double m1 = cy * dz, m2 = cz * dy, m3 = cz * dx, m4 = cx * dz, m5 = cx * dy, m6 = cy * dx;
  const double det = bx * (m1 - m2) + by * (m3 - m4) + bz * (m5 - m6);
  const double perm = std::abs(bx) * (std::abs(m1) + std::abs(m2)) +
                      std::abs(by) * (std::abs(m3) + std::abs(m4)) +
                      std::abs(bz) * (std::abs(m5) + std::abs(m6));
  const double margin = kRelMargin * perm + kAbsMargin;
  if (det > margin) return 1;
  if (det < -margin) return -1;
  return 0;
}

/// The exact test with CGAL's filtered exact orientation predicate (Epick).
bool ContainsExact(const double* a, const double* b, const double* c, const double* d,
                   const double* p) {
  const CPoint q[5] = {CPoint(a[0], a[1], a[2]), CPoint(b[0], b[1], b[2]), CPoint(c[0], c[1], c[2]),
                       CPoint(d[0], d[1], d[2]), CPoint(p[0], p[1], p[2])};
  const int o = static_cast<int>(CGAL::orientation(q[0], q[1], q[2], q[3]));
  if (o == 0) return false;  // a flat tet contains nothing (CGAL: is_degenerate)
  for (int i = 0; i < 4; ++i) {
    const CPoint& r0 = i == 0 ? q[4] : q[0];
    const CPoint& r1 = i == 1 ? q[4] : q[1];
    const CPoint& r2 = i == 2 ? q[4] : q[2];
    const CPoint& r3 = i == 3 ? q[4] : q[3];
    if (static_cast<int>(CGAL::orientation(r0, r1, r2, r3)) == -o) return false;
  }
  return true;
}

/// p in the closed tet (a, b, c, d): the filter decides when every sign it needs is certain
/// (one face certainly on the wrong side: outside; all certainly on the right side: inside),
/// the exact test otherwise. *exact tells which.
inline bool ContainsFiltered(const double* a, const double* b, const double* c, const double* d,
                             const double* p, bool* exact) {
  *exact = false;
  const int o = FilteredOrientation(a, b, c, d);
  if (o != 0) {
    const int s0 = FilteredOrientation(p, b, c, d);
    if (s0 == -o) return false;
    const int s1 = FilteredOrientation(a, p, c, d);
    if (s1 == -o) return false;
    const int s2 = FilteredOrientation(a, b, p, d);
    if (s2 == -o) return false;
    const int s3 = FilteredOrientation(a, b, c, p);
    if (s3 == -o) return false;
    if (s0 != 0 && s1 != 0 && s2 != 0 && s3 != 0) return true;
  }
  *exact = true;
  return ContainsExact(a, b, c, d, p);
}

/// Grid cells per axis are capped so that a wildly spread-out configuration cannot ask for
/// unbounded memory: at most kMaxCellsPerTet * #tets + kMinCellCap cells in all (the cells grow).
constexpr long long kMaxCellsPerTet = 2;
constexpr long long kMinCellCap = 4096;
/// Below these sizes the grid's build (#tets) and query (#boundary vertices) run on one thread:
/// on 2 cores the parallel passes gain nothing there (res 6, 6.5k tets), and every parallel
/// region costs a wake-up, a scheduler time slice when the machine is loaded.
constexpr int kParallelTets = 16384;
constexpr int kParallelVertices = 1024;
/// A tet whose box spans more cells than this is kept out of the cells, in a list that every
/// vertex scans: a few huge tets (a vertex thrown far away) cannot blow up the cell lists.
constexpr long long kLargeTetCells = 64;
/// Cell edge as a multiple of the mean edge of the tets' boxes (measured: 1.0 to 2.0 are within
/// 10% of each other on pneumatic_finger; see docs/collision.md).
constexpr double kCellScale = 1.5;

}  // namespace

bool TetContainsPoint(const Eigen::Vector3d& a, const Eigen::Vector3d& b, const Eigen::Vector3d& c,
                      const Eigen::Vector3d& d, const Eigen::Vector3d& p, bool* exact_used) {
  if (!a.allFinite() || !b.allFinite() || !c.allFinite() || !d.allFinite() || !p.allFinite())
    throw std::invalid_argument("TetContainsPoint: expected finite coordinates");
  bool exact = false;
  const bool in = ContainsFiltered(a.data(), b.data(), c.data(), d.data(), p.data(), &exact);
  if (exact_used) *exact_used = exact;
  return in;
}

const char* SelfCollisionMethodToString(SelfCollisionDetector::Method m) {
  switch (m) {
    case SelfCollisionDetector::Method::kBoxIntersection:
      return "box_intersection";
    case SelfCollisionDetector::Method::kAabbTree:
      return "aabb_tree";
    case SelfCollisionDetector::Method::kGrid:
      return "grid";
  }
  return "unknown";
}

SelfCollisionDetector::Method SelfCollisionMethodFromString(const std::string& name) {
  for (auto m : {SelfCollisionDetector::Method::kBoxIntersection,
                 SelfCollisionDetector::Method::kAabbTree, SelfCollisionDetector::Method::kGrid})
    if (name == SelfCollisionMethodToString(m)) return m;
  throw std::invalid_argument("self-collision method '" + name +
                              "': expected one of box_intersection, aabb_tree, grid");
}

/// The uniform grid of kGrid: cell (i, j, k) is [origin + h (i, j, k), origin + h (i+1, j+1, k+1));
/// the first and last cells of each axis extend to infinity (coordinates are clamped). Cell
/// c = (k n_y + j) n_x + i lists the tets whose box overlaps it in cell_tets[start[c] ..
/// start[c+1]), ascending. Since the cell of a coordinate is a monotone function of it, a point
/// inside a tet's closed box lies in a cell that lists the tet.
struct UniformTetGrid {
  std::array<double, 3> origin{{0, 0, 0}};
  double inv_h = 1;
  std::array<int, 3> n{{1, 1, 1}};
  std::vector<double> box;     ///< 6 per tet: min x, y, z, max x, y, z (mm)
  std::vector<int> start;      ///< #cells + 1
  std::vector<int> cell_tets;  ///< tet ids, grouped by cell
  std::vector<int> large;      ///< ascending ids of the tets spanning > kLargeTetCells cells
  /// Per tet: first cell of its box and the box's span in cells per axis (bytes 0, 1, 2); the
  /// first cell is -1 for a large tet.
  std::vector<std::array<int, 2>> range;
  std::vector<int> cursor;  ///< #threads x #cells: counts, then write positions

  int Coord(double x, int axis) const {
    const double t =
        std::min(std::max((x - origin[axis]) * inv_h, 0.0), static_cast<double>(n[axis] - 1));
    return static_cast<int>(t);
  }
  int Cell(const double* p) const {
    return (Coord(p[2], 2) * n[1] + Coord(p[1], 1)) * n[0] + Coord(p[0], 0);
  }

  /// Rebuilds the grid over the tets at positions X (row-major #V x 3, mm).
  void Build(const RowX3& X, const std::vector<std::array<int, 4>>& tets);
};

void UniformTetGrid::Build(const RowX3& X, const std::vector<std::array<int, 4>>& tets) {
  const int nt = static_cast<int>(tets.size());
  box.resize(6 * static_cast<size_t>(nt));
  double lx = std::numeric_limits<double>::infinity(), ly = lx, lz = lx;
  double hx = -lx, hy = -lx, hz = -lx, sum = 0;
  const bool parallel = nt >= kParallelTets;
#pragma omp parallel for schedule(static) reduction(min : lx, ly, lz) reduction(max : hx, hy, hz) \
    reduction(+ : sum) if (parallel)
  for (int t = 0; t < nt; ++t) {
    const auto& tt = tets[t];
    const double* p = &X(tt[0], 0);
    double b[6] = {p[0], p[1], p[2], p[0], p[1], p[2]};
    for (int k = 1; k < 4; ++k) {
      const double* q = &X(tt[k], 0);
      for (int a = 0; a < 3; ++a) {
        b[a] = std::min(b[a], q[a]);
        b[3 + a] = std::max(b[3 + a], q[a]);
      }
    }
    std::copy(b, b + 6, &box[6 * static_cast<size_t>(t)]);
    lx = std::min(lx, b[0]), ly = std::min(ly, b[1]), lz = std::min(lz, b[2]);
    hx = std::max(hx, b[3]), hy = std::max(hy, b[4]), hz = std::max(hz, b[5]);
    sum += (b[3] - b[0]) + (b[4] - b[1]) + (b[5] - b[2]);
  }
  large.clear();
  if (nt == 0) {
    n = {1, 1, 1};
    start.assign(2, 0);
    cell_tets.clear();
    return;
  }
  range.resize(nt);
  origin = {lx, ly, lz};
  const double extent[3] = {hx - lx, hy - ly, hz - lz};
  double h = kCellScale * sum / (3.0 * nt);
  if (!(h > 0)) h = std::max({extent[0], extent[1], extent[2], std::numeric_limits<double>::min()});
  const long long cap = kMaxCellsPerTet * nt + kMinCellCap;
  long long cells = 0;
  for (int grow = 0;; ++grow) {
    cells = 1;
    for (int a = 0; a < 3; ++a) {
      n[a] = static_cast<int>(std::min(extent[a] / h, 1e6)) + 1;
      cells *= n[a];
    }
    if (cells <= cap) break;
    assert(grow < 64);
    h *= 1.01 * std::cbrt(static_cast<double>(cells) / static_cast<double>(cap));
  }
  inv_h = 1.0 / h;
  const int nc = static_cast<int>(cells);
  start.resize(nc + 1);
  // Counting sort, parallel over contiguous chunks of tets: each thread counts its chunk's
  // entries per cell; the prefix sum over (cell, thread) gives every thread its own write
  // positions, so each cell lists its tets in ascending order.
  const int threads = parallel ? omp_get_max_threads() : 1;
  cursor.assign(static_cast<size_t>(threads) * nc, 0);
#pragma omp parallel num_threads(threads) if (parallel)
  {
    const int tid = omp_get_thread_num(), nth = omp_get_num_threads();
    const int begin = static_cast<int>(static_cast<long long>(nt) * tid / nth);
    const int end = static_cast<int>(static_cast<long long>(nt) * (tid + 1) / nth);
    int* cur = cursor.data() + static_cast<size_t>(tid) * nc;
    // Calls f(cell) for every cell of tet t's box, in ascending order.
    auto for_cells = [&](int t, auto&& f) {
      const int base = range[t][0], span = range[t][1];
      const int si = span & 0xff, sj = (span >> 8) & 0xff, sk = (span >> 16) & 0xff;
      for (int k = 0; k < sk; ++k)
        for (int j = 0; j < sj; ++j) {
          const int row = base + (k * n[1] + j) * n[0];
          for (int i = 0; i < si; ++i) f(row + i);
        }
    };
    for (int t = begin; t < end; ++t) {
      const double* b = &box[6 * static_cast<size_t>(t)];
      const int i0 = Coord(b[0], 0), j0 = Coord(b[1], 1), k0 = Coord(b[2], 2);
      const int si = Coord(b[3], 0) - i0 + 1, sj = Coord(b[4], 1) - j0 + 1,
                sk = Coord(b[5], 2) - k0 + 1;
      if (static_cast<long long>(si) * sj * sk > kLargeTetCells) {
        range[t] = {-1, 0};
        continue;
      }
      range[t] = {(k0 * n[1] + j0) * n[0] + i0, si | (sj << 8) | (sk << 16)};
      for_cells(t, [&](int c) { ++cur[c]; });
    }
#pragma omp barrier
#pragma omp single
    {
      for (int t = 0; t < nt; ++t)
        if (range[t][0] < 0) large.push_back(t);
      int run = 0;
      for (int c = 0; c < nc; ++c) {
        start[c] = run;
        for (int th = 0; th < nth; ++th) {
          int& slot = cursor[static_cast<size_t>(th) * nc + c];
          const int count = slot;
          slot = run;
          run += count;
        }
      }
      start[nc] = run;
      cell_tets.resize(run);
    }  // implicit barrier
    for (int t = begin; t < end; ++t)
      if (range[t][0] >= 0) for_cells(t, [&](int c) { cell_tets[cur[c]++] = t; });
  }
}

struct SelfCollisionDetector::Impl {
  int num_vertices = 0;
  std::vector<std::array<int, 4>> tets;
  std::vector<int> ids;
  std::vector<std::vector<int>> incident;  // per vertex, sorted tet ids (the CGAL methods)
  RowX3 X;
  TetTree tree;
  UniformTetGrid grid;
};

SelfCollisionDetector::SelfCollisionDetector(const Mesh& mesh, Method method)
    : impl_(std::make_unique<Impl>()), method_(method) {
  if (method != Method::kBoxIntersection && method != Method::kAabbTree && method != Method::kGrid)
    throw std::invalid_argument("self-collision detection: unknown method " +
                                std::to_string(static_cast<int>(method)));
  const int ne = mesh.num_elements();
  auto& I = *impl_;
  I.num_vertices = mesh.num_vertices();
  I.incident.assign(mesh.num_vertices(), {});
  std::map<std::array<int, 3>, int> face_count;
  for (int i = 0; i < ne; ++i) {
    const Element& e = mesh.elements[i];
    if (e.k() != 4)
      throw std::invalid_argument("self-collision detection: element " + std::to_string(i) +
                                  " is a prism; expected a tet mesh");
    I.tets.push_back({e.v[0], e.v[1], e.v[2], e.v[3]});
    I.ids.push_back(i);
    for (int k = 0; k < 4; ++k) I.incident[e.v[k]].push_back(i);
    for (int skip = 0; skip < 4; ++skip) {
      std::array<int, 3> f;
      int q = 0;
      for (int k = 0; k < 4; ++k)
        if (k != skip) f[q++] = e.v[k];
      std::sort(f.begin(), f.end());
      ++face_count[f];
    }
  }
  std::vector<char> on(mesh.num_vertices(), 0);
  for (const auto& [f, n] : face_count)
    if (n == 1)
      for (int v : f) on[v] = 1;
  for (int v = 0; v < mesh.num_vertices(); ++v)
    if (on[v]) boundary_.push_back(v);
  Update(mesh.vertices);
}

SelfCollisionDetector::~SelfCollisionDetector() = default;

int SelfCollisionDetector::grid_large_tets() const {
  return method_ == Method::kGrid ? static_cast<int>(impl_->grid.large.size()) : 0;
}

void SelfCollisionDetector::Update(const Eigen::Ref<const Eigen::MatrixX3d>& X) {
  const auto t0 = Clock::now();
  auto& I = *impl_;
  if (X.rows() != I.num_vertices)
    throw std::invalid_argument("SelfCollisionDetector::Update: expected positions for " +
                                std::to_string(I.num_vertices) + " vertices, got " +
                                std::to_string(X.rows()) + " rows");
  I.X = X;
  if (!I.X.allFinite()) {
    int v = 0;
    while (I.X.row(v).allFinite()) ++v;
    throw std::invalid_argument("SelfCollisionDetector::Update: vertex " + std::to_string(v) +
                                " has a non-finite coordinate");
  }
  if (method_ == Method::kAabbTree) {
    I.tree.clear();
    I.tree.rebuild(I.ids.begin(), I.ids.end(), TetData{&I.X, &I.tets});
    I.tree.build();
  } else if (method_ == Method::kGrid) {
    I.grid.Build(I.X, I.tets);
  }
  build_s_ = SecondsSince(t0);
}

namespace {

using TetList = std::vector<std::array<int, 4>>;

/// The exact test of the CGAL methods: whether vertex v is in the closed tet t, which is not
/// incident to it. Returns -1 for an incident tet (no test), else 0 or 1.
int InsideNonIncident(const std::vector<std::vector<int>>& incident, const TetList& tets,
                      const RowX3& X, int v, int t) {
  if (std::binary_search(incident[v].begin(), incident[v].end(), t)) return -1;
  const auto& tt = tets[t];
  const K::Tetrahedron_3 tet(P(X, tt[0]), P(X, tt[1]), P(X, tt[2]), P(X, tt[3]));
  return !tet.is_degenerate() && !tet.has_on_unbounded_side(P(X, v)) ? 1 : 0;
}

/// kGrid: hit[q] = the lowest id of a tet containing boundary vertex q (box, incidence, then the
/// filtered exact test), or -1. Adds the narrow-phase and exact tests to *narrow_out, *exact_out.
void DetectInGrid(const UniformTetGrid& G, const TetList& tets, const RowX3& X,
                  const std::vector<int>& boundary, std::vector<int>* hit_out,
                  long long* narrow_out, long long* exact_out) {
  const int nb = static_cast<int>(boundary.size());
  std::vector<int>& hit = *hit_out;
  long long narrow = 0, exact = 0;
#pragma omp parallel for schedule(dynamic, 64) reduction(+ : narrow, exact) if (nb >= kParallelVertices)
  for (int q = 0; q < nb; ++q) {
    const int v = boundary[q];
    const double* p = &X(v, 0);
    long long my_narrow = 0, my_exact = 0;
    // Does tet t contain p (box, incidence, then the filtered exact test)?
    auto test = [&](int t) {
      const double* b = &G.box[6 * static_cast<size_t>(t)];
      if (p[0] < b[0] || p[1] < b[1] || p[2] < b[2] || p[0] > b[3] || p[1] > b[4] || p[2] > b[5])
        return false;
      const auto& tt = tets[t];
      if (tt[0] == v || tt[1] == v || tt[2] == v || tt[3] == v) return false;
      ++my_narrow;
      bool ex = false;
      const bool in =
          ContainsFiltered(&X(tt[0], 0), &X(tt[1], 0), &X(tt[2], 0), &X(tt[3], 0), p, &ex);
      my_exact += ex;
      return in;
    };
    // Both lists are ascending: the first hit of each, the lower of the two, is the lowest id.
    int best = -1;
    const int c = G.Cell(p);
    for (int k = G.start[c]; k < G.start[c + 1]; ++k)
      if (test(G.cell_tets[k])) {
        best = G.cell_tets[k];
        break;
      }
    for (int t : G.large) {
      if (best >= 0 && t > best) break;
      if (test(t)) {
        best = t;
        break;
      }
    }
    hit[q] = best;
    narrow += my_narrow;
    exact += my_exact;
  }
  *narrow_out += narrow;
  *exact_out += exact;
}

/// kAabbTree: hit[q] = the lowest id of a non-incident tet of the tree containing boundary
/// vertex q, or -1. Adds the tests to *narrow_out, *exact_out.
void DetectInAabbTree(const TetTree& tree, const std::vector<std::vector<int>>& incident,
                      const TetList& tets, const RowX3& X, const std::vector<int>& boundary,
                      std::vector<int>* hit_out, long long* narrow_out, long long* exact_out) {
  const int nb = static_cast<int>(boundary.size());
  std::vector<int>& hit = *hit_out;
  long long narrow = 0, exact = 0;
#pragma omp parallel for schedule(dynamic, 64) reduction(+ : narrow, exact)
  for (int q = 0; q < nb; ++q) {
    const int v = boundary[q];
    std::vector<int> cand;
    tree.all_intersected_primitives(P(X, v), std::back_inserter(cand));
    std::sort(cand.begin(), cand.end());
    for (int t : cand) {
      const int in = InsideNonIncident(incident, tets, X, v, t);
      if (in < 0) continue;
      ++narrow;
      ++exact;
      if (in) {
        hit[q] = t;
        break;
      }
    }
  }
  *narrow_out += narrow;
  *exact_out += exact;
}

/// kBoxIntersection: hit[q] = the lowest id of a non-incident tet containing boundary vertex q,
/// or -1, by CGAL's box intersection of the vertices' points with the tets' boxes. Adds the tests
/// to *narrow_out, *exact_out.
void DetectByBoxIntersection(const std::vector<std::vector<int>>& incident, const TetList& tets,
                             const RowX3& X, const std::vector<int>& boundary,
                             std::vector<int>* hit_out, long long* narrow_out,
                             long long* exact_out) {
  const int nb = static_cast<int>(boundary.size());
  std::vector<int>& hit = *hit_out;
  long long narrow = 0;
  // Broad phase: boxes of the boundary vertices (points) against boxes of the tets.
  using Box =
      CGAL::Box_intersection_d::Box_with_info_d<double, 3, int,
                                                CGAL::Box_intersection_d::ID_FROM_BOX_ADDRESS>;
  std::vector<Box> vb, tb;
  vb.reserve(nb);
  for (int q = 0; q < nb; ++q) {
    const int v = boundary[q];
    vb.emplace_back(CGAL::Bbox_3(X(v, 0), X(v, 1), X(v, 2), X(v, 0), X(v, 1), X(v, 2)), q);
  }
  tb.reserve(tets.size());
  for (int t = 0; t < static_cast<int>(tets.size()); ++t) {
    const auto& tt = tets[t];
    Eigen::Vector3d lo = X.row(tt[0]).transpose(), hi = lo;
    for (int k = 1; k < 4; ++k) {
      lo = lo.cwiseMin(X.row(tt[k]).transpose());
      hi = hi.cwiseMax(X.row(tt[k]).transpose());
    }
    tb.emplace_back(CGAL::Bbox_3(lo.x(), lo.y(), lo.z(), hi.x(), hi.y(), hi.z()), t);
  }
  std::vector<std::pair<int, int>> pairs;  // (boundary index, tet)
  CGAL::box_intersection_d(
      vb.begin(), vb.end(), tb.begin(), tb.end(),
      [&](const Box& a, const Box& b) { pairs.emplace_back(a.info(), b.info()); });
  std::sort(pairs.begin(), pairs.end());
  const int np = static_cast<int>(pairs.size());
  std::vector<signed char> ok(np, 0);
#pragma omp parallel for schedule(static) reduction(+ : narrow)
  for (int k = 0; k < np; ++k) {
    ok[k] = static_cast<signed char>(
        InsideNonIncident(incident, tets, X, boundary[pairs[k].first], pairs[k].second));
    narrow += ok[k] >= 0;
  }
  for (int k = 0; k < np; ++k)
    if (ok[k] > 0 && hit[pairs[k].first] < 0) hit[pairs[k].first] = pairs[k].second;
  *narrow_out += narrow;
  *exact_out += narrow;
}

}  // namespace

std::vector<SelfContact> SelfCollisionDetector::Detect() const {
  const auto t0 = Clock::now();
  const auto& I = *impl_;
  const int nb = static_cast<int>(boundary_.size());
  long long narrow = 0, exact = 0;
  std::vector<int> hit(nb, -1);
  if (method_ == Method::kGrid)
    DetectInGrid(I.grid, I.tets, I.X, boundary_, &hit, &narrow, &exact);
  else if (method_ == Method::kAabbTree)
    DetectInAabbTree(I.tree, I.incident, I.tets, I.X, boundary_, &hit, &narrow, &exact);
  else
    DetectByBoxIntersection(I.incident, I.tets, I.X, boundary_, &hit, &narrow, &exact);
  std::vector<SelfContact> out;
  for (int q = 0; q < nb; ++q)
    if (hit[q] >= 0) out.push_back({boundary_[q], hit[q]});
  narrow_tests_ = narrow;
  exact_tests_ = exact;
  query_s_ = SecondsSince(t0);
  return out;
}

std::vector<ObstacleContact> DetectObstacleContacts(const std::vector<Obstacle>& obstacles,
                                                    const Eigen::Ref<const Eigen::MatrixX3d>& X,
                                                    const std::vector<int>& vertices) {
  const int n = vertices.empty() ? static_cast<int>(X.rows()) : static_cast<int>(vertices.size());
  for (int v : vertices)
    if (v < 0 || v >= X.rows())
      throw std::invalid_argument("DetectObstacleContacts: vertex id " + std::to_string(v) +
                                  " is not in 0.." + std::to_string(X.rows() - 1));
  const int no = static_cast<int>(obstacles.size());
  if (no == 0 || n == 0) return {};
  // Serial pass: the vertices inside the union of the obstacles' boxes (a vertex outside it
  // touches no obstacle). A few comparisons per vertex; no parallel region when few are near.
  Eigen::Vector3d lo = obstacles[0].box_min(), hi = obstacles[0].box_max();
  for (const auto& o : obstacles) {
    lo = lo.cwiseMin(o.box_min());
    hi = hi.cwiseMax(o.box_max());
  }
  std::vector<int> near;
  for (int q = 0; q < n; ++q) {
    const int v = vertices.empty() ? q : vertices[q];
    if (X(v, 0) >= lo.x() && X(v, 1) >= lo.y() && X(v, 2) >= lo.z() && X(v, 0) <= hi.x() &&
        X(v, 1) <= hi.y() && X(v, 2) <= hi.z())
      near.push_back(v);
  }
  // The CGAL inside test (after each obstacle's own box) and, for contained vertices, the
  // closest point; in parallel when there are enough of them to pay for it.
  const int nn = static_cast<int>(near.size());
  std::vector<ObstacleContact> found(nn);
#pragma omp parallel for schedule(dynamic, 64) if (nn > 256)
  for (int k = 0; k < nn; ++k) {
    const int v = near[k];
    const Eigen::Vector3d p(X(v, 0), X(v, 1), X(v, 2));
    for (int o = 0; o < no; ++o)
      if (obstacles[o].Contains(p)) {
        ObstacleContact& c = found[k];
        c.vertex = v;
        c.obstacle = o;
        c.closest = obstacles[o].ClosestPoint(p, &c.normal);
        c.depth = (c.closest - p).norm();
        break;
      }
  }
  std::vector<ObstacleContact> out;
  for (const auto& c : found)
    if (c.vertex >= 0) out.push_back(c);
  return out;
}

// ---- MovingSurface -----------------------------------------------------------------------------

struct MovingSurface::Impl {
  RowX3 X;
  std::vector<int> ids;
  TriTree tree;
  bool built = false;
};

MovingSurface::MovingSurface(std::vector<std::array<int, 3>> faces)
    : faces_(std::move(faces)), impl_(std::make_unique<Impl>()) {
  if (faces_.empty()) throw std::invalid_argument("MovingSurface: no triangles");
  for (const auto& f : faces_)
    for (int v : f)
      if (v < 0)
        throw std::invalid_argument("MovingSurface: negative vertex index " + std::to_string(v));
  impl_->ids.resize(faces_.size());
  for (size_t i = 0; i < faces_.size(); ++i) impl_->ids[i] = static_cast<int>(i);
}

MovingSurface::~MovingSurface() = default;
MovingSurface::MovingSurface(MovingSurface&&) noexcept = default;
MovingSurface& MovingSurface::operator=(MovingSurface&&) noexcept = default;

void MovingSurface::Update(const Eigen::Ref<const Eigen::MatrixX3d>& X) {
  for (const auto& f : faces_)
    for (int v : f)
      if (v >= X.rows())
        throw std::invalid_argument("MovingSurface: a triangle refers to vertex " +
                                    std::to_string(v) + " but the positions have " +
                                    std::to_string(X.rows()) + " rows");
  impl_->X = X;
  impl_->tree.rebuild(impl_->ids.begin(), impl_->ids.end(), TriData{&impl_->X, &faces_});
  impl_->tree.accelerate_distance_queries();
  impl_->built = true;
}

Eigen::Vector3d MovingSurface::ClosestPoint(const Eigen::Vector3d& p, int* face) const {
  if (!impl_->built) throw std::logic_error("MovingSurface::ClosestPoint before Update");
  const auto cp = impl_->tree.closest_point_and_primitive(CPoint(p.x(), p.y(), p.z()));
  if (face) *face = cp.second;
  return Eigen::Vector3d(cp.first.x(), cp.first.y(), cp.first.z());
}

bool MovingSurface::ClosestFacing(const Eigen::Vector3d& p, const Eigen::Vector3d& n,
                                  Eigen::Vector3d* closest, int* face) const {
  if (!impl_->built) throw std::logic_error("MovingSurface::ClosestFacing before Update");
  const auto& I = *impl_;
  const CGAL::Bbox_3 all = I.tree.bbox();
  const double span =
      std::max({all.xmax() - all.xmin(), all.ymax() - all.ymin(), all.zmax() - all.zmin()});
  // Start from the unrestricted distance: no facing triangle is closer.
  double r = std::max((ClosestPoint(p) - p).norm(), 1e-9 * span);
  const CPoint cp(p.x(), p.y(), p.z());
  std::vector<int> cand;
  for (;;) {
    cand.clear();
    const CGAL::Bbox_3 box(p.x() - r, p.y() - r, p.z() - r, p.x() + r, p.y() + r, p.z() + r);
    I.tree.all_intersected_primitives(box, std::back_inserter(cand));
    double best = std::numeric_limits<double>::infinity();
    int best_f = -1;
    Eigen::Vector3d best_c;
    for (int f : cand) {
      const auto& t = faces_[f];
      const Eigen::Vector3d a = I.X.row(t[0]), b = I.X.row(t[1]), c = I.X.row(t[2]);
      if (!((b - a).cross(c - a).dot(n) < 0)) continue;
      const CPoint cq = K().construct_projected_point_3_object()(
          K::Triangle_3(P(I.X, t[0]), P(I.X, t[1]), P(I.X, t[2])), cp);
      const Eigen::Vector3d q(cq.x(), cq.y(), cq.z());
      const double d = (q - p).norm();
      if (d < best || (d == best && f < best_f)) {
        best = d;
        best_f = f;
        best_c = q;
      }
    }
    // Every triangle within distance r meets the box, so an answer within r is final; so is
    // the best one once the box holds the whole surface.
    const bool covers = box.xmin() <= all.xmin() && box.ymin() <= all.ymin() &&
                        box.zmin() <= all.zmin() && box.xmax() >= all.xmax() &&
                        box.ymax() >= all.ymax() && box.zmax() >= all.zmax();
    if (best <= r || covers) {
      if (best_f < 0) return false;
      *closest = best_c;
      if (face) *face = best_f;
      return true;
    }
    r *= 2.0;
  }
}

}  // namespace softkin
