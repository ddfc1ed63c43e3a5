#pragma once
/// \file collision.hpp
/// Collision detection (thesis Sec. 3.2.2) with CGAL AABB trees.
///  - Obstacles are closed, consistently oriented triangle surfaces (read from OBJ or STL, or
///    built as a box or a cylinder). Each gets a CGAL AABB tree over its triangles, for the
///    closest point on its surface and, through CGAL::Side_of_triangle_mesh, for inside tests.
///    An obstacle does not move, so its tree is built once.
///  - Self-collision: a boundary vertex of the robot lying inside (or on the boundary of) a
///    tetrahedron that is not incident to it (Eq. 3.3). On a conforming mesh a vertex touches
///    only its own tets, so the rest shape reports nothing; a vertex that crossed into the body
///    is found even where it lies on a face shared by two tets. The broad phase is a uniform grid
///    over the tets' boxes (default), CGAL::box_intersection_d or a CGAL AABB tree over the tets
///    (SelfCollisionDetector); the answer is exact in every case (CGAL's exact predicates).
/// Robot-obstacle contact (Eq. 3.4): a robot vertex strictly inside an obstacle.
#include "softkin/solver/mesh/mesh.hpp"
#include "softkin/solver/mesh/surface.hpp"

#include <Eigen/Dense>

#include <memory>
#include <array>
#include <string>
#include <vector>

namespace softkin {

/// A static obstacle with its CGAL trees.
class Obstacle {
 public:
  explicit Obstacle(TriangleSurface surface);  ///< checks it (CheckClosedSurface)
  ~Obstacle();
  Obstacle(Obstacle&&) noexcept;
  Obstacle& operator=(Obstacle&&) noexcept;
  /// True if p (mm) lies strictly inside (on the surface is outside). A point outside the
  /// bounding box is rejected without the ray-casting test.
  bool Contains(const Eigen::Vector3d& p) const;
  /// Corners of the surface's axis-aligned bounding box (mm).
  const Eigen::Vector3d& box_min() const { return box_min_; }
  const Eigen::Vector3d& box_max() const { return box_max_; }
  /// Closest point on the surface to p, and the outward unit normal of its triangle.
  Eigen::Vector3d ClosestPoint(const Eigen::Vector3d& p, Eigen::Vector3d* normal = nullptr) const;
  const TriangleSurface& surface() const { return surface_; }

 private:
  struct Impl;
  TriangleSurface surface_;
  Eigen::Vector3d box_min_, box_max_;
  std::unique_ptr<Impl> impl_;
};

/// Closest-point queries on a set of triangles whose corners move with a mesh (for example, the
/// boundary faces of one body of a robot), through a CGAL AABB tree over the triangles at the
/// positions of the last Update(). CGAL's tree has no refit, so Update() rebuilds it (linear in the
/// number of triangles, plus the distance-query acceleration).
class MovingSurface {
 public:
  /// `faces`: vertex indices into the positions that Update() takes (each triangle once). Throws
  /// std::invalid_argument if it is empty or holds a negative index.
  explicit MovingSurface(std::vector<std::array<int, 3>> faces);
  ~MovingSurface();
  MovingSurface(MovingSurface&&) noexcept;
  MovingSurface& operator=(MovingSurface&&) noexcept;
  /// Takes positions X (#V x 3, mm) and rebuilds the tree. Throws std::invalid_argument if a
  /// face refers to a row that X does not have.
  void Update(const Eigen::Ref<const Eigen::MatrixX3d>& X);
  /// The closest point to p on the triangles at the last Update()'s positions, and the index
  /// (into `faces()`) of a triangle it lies on. Update() must have been called.
  Eigen::Vector3d ClosestPoint(const Eigen::Vector3d& p, int* face = nullptr) const;
  /// The closest point to p among the triangles that face against `n`: those whose normal
  /// (x1 - x0) x (x2 - x0) has a negative dot product with n. Box queries of the tree, doubled
  /// from the unrestricted distance until they hold the answer. Returns false (and leaves the
  /// outputs alone) if no triangle faces against n.
  bool ClosestFacing(const Eigen::Vector3d& p, const Eigen::Vector3d& n, Eigen::Vector3d* closest,
                     int* face = nullptr) const;
  const std::vector<std::array<int, 3>>& faces() const { return faces_; }

 private:
  struct Impl;
  std::vector<std::array<int, 3>> faces_;
  std::unique_ptr<Impl> impl_;
};

/// A boundary vertex inside or on a tetrahedron that is not incident to it.
struct SelfContact {
  int vertex = -1;
  int tet = -1;
};

/// A robot vertex inside an obstacle: the closest surface point and the outward normal there.
struct ObstacleContact {
  int vertex = -1;
  int obstacle = -1;
  Eigen::Vector3d closest = Eigen::Vector3d::Zero();
  Eigen::Vector3d normal = Eigen::Vector3d::Zero();
  double depth = 0;  ///< distance from the vertex to `closest`
};

/// Self-collision detection over a tet mesh (prism elements are not supported: it throws
/// std::invalid_argument). Three broad phases, one exact answer (the same contacts, tested):
///  - kGrid (default, the fastest): a uniform grid over the tets' boxes at the current
///    positions, rebuilt by Update() in linear time (counting sort into flat arrays, buffers kept
///    across calls). Each boundary vertex scans the tets listed in its cell. A floating-point
///    orientation test with a rigorous error margin decides the clear cases; only the ambiguous
///    ones (the vertex within a relative 1e-12 of a face plane, or a nearly flat tet) go to
///    CGAL's exact orientation predicate.
///  - kBoxIntersection: CGAL::box_intersection_d between the boundary vertices' point boxes and
///    the tets' boxes; every candidate goes to CGAL's exact point-in-tetrahedron test.
///  - kAabbTree: a CGAL AABB tree over the tets, rebuilt by Update() (CGAL's tree has no refit),
///    queried per boundary vertex; the same exact test as kBoxIntersection.
/// Update() and Detect() use OpenMP (kGrid: from 16384 tets for the build and 1024 boundary
/// vertices for the query; one thread below); the result does not depend on the number of
/// threads.
/// Not thread-safe: one detector per thread (Detect() stores its timings and counts).
class SelfCollisionDetector {
 public:
  enum class Method { kBoxIntersection, kAabbTree, kGrid };
  /// Precomputes the boundary vertices and the incidence of `mesh` (a tet mesh, rest positions
  /// #V x 3 in mm) and calls Update(mesh.vertices).
  explicit SelfCollisionDetector(const Mesh& mesh, Method method = Method::kGrid);
  ~SelfCollisionDetector();
  /// Takes positions X (#V x 3, mm, the mesh's vertex order; throws std::invalid_argument if
  /// the row count differs or a coordinate is not finite). kGrid rebuilds its grid and kAabbTree
  /// its tree. Seconds spent: last_build_s().
  void Update(const Eigen::Ref<const Eigen::MatrixX3d>& X);
  /// Boundary vertices inside (or on) a non-incident tet at the positions of the last Update
  /// (each vertex once, with the lowest such tet id; sorted by vertex). Seconds spent are in
  /// last_query_s().
  std::vector<SelfContact> Detect() const;
  /// The boundary vertices (on faces that belong to one tet only), sorted.
  const std::vector<int>& boundary_vertices() const { return boundary_; }
  Method method() const { return method_; }
  /// Wall-clock seconds of the last Update() (grid or tree build; for kBoxIntersection only
  /// the copy of the positions).
  double last_build_s() const { return build_s_; }
  /// Wall-clock seconds of the last Detect() (broad phase and exact tests).
  double last_query_s() const { return query_s_; }
  /// Candidate (vertex, tet) pairs of the last Detect() that reached the point-in-tet test.
  /// kGrid and kBoxIntersection: the tet's box contains the vertex and the tet is not incident
  /// to it (kGrid stops a vertex's search at its first hit in ascending tet order,
  /// kBoxIntersection tests all of its pairs). kAabbTree: the tree's traversal has already
  /// tested the tets themselves, so only non-incident tets that contain the vertex are counted.
  long long last_narrow_tests() const { return narrow_tests_; }
  /// How many of those were decided by CGAL's exact predicates (kGrid: the ambiguous ones;
  /// the CGAL methods: all of them).
  long long last_exact_tests() const { return exact_tests_; }
  /// kGrid: tets of the last Update() whose box spans more than 64 grid cells (a vertex thrown
  /// far away); they are kept out of the cells, in one list that every vertex scans. 0 for the
  /// other methods.
  int grid_large_tets() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
  Method method_;
  std::vector<int> boundary_;
  double build_s_ = 0;
  mutable double query_s_ = 0;
  mutable long long narrow_tests_ = 0;
  mutable long long exact_tests_ = 0;
};

/// "box_intersection", "aabb_tree", "grid".
const char* SelfCollisionMethodToString(SelfCollisionDetector::Method m);
/// Inverse of SelfCollisionMethodToString; throws std::invalid_argument naming the value and
/// the accepted names.
SelfCollisionDetector::Method SelfCollisionMethodFromString(const std::string& name);

/// True if p lies inside or on the boundary of the tetrahedron (a, b, c, d) (any orientation;
/// a flat tet contains nothing), decided exactly: a floating-point orientation filter with a
/// rigorous margin, CGAL's exact orientation predicate where the filter cannot tell. Points in
/// mm (any unit). If `exact_used` is given, it is set to whether the exact predicate ran.
bool TetContainsPoint(const Eigen::Vector3d& a, const Eigen::Vector3d& b, const Eigen::Vector3d& c,
                      const Eigen::Vector3d& d, const Eigen::Vector3d& p,
                      bool* exact_used = nullptr);

/// Vertices of `vertices` (all robot vertices if empty; ids into the rows of X, #V x 3 in mm)
/// strictly inside any of the obstacles (the first one, in obstacle order), in the order of
/// `vertices`. A vertex outside an obstacle's bounding box is rejected without the CGAL inside
/// test, so the cost is small when few vertices are near an obstacle.
std::vector<ObstacleContact> DetectObstacleContacts(const std::vector<Obstacle>& obstacles,
                                                    const Eigen::Ref<const Eigen::MatrixX3d>& X,
                                                    const std::vector<int>& vertices = {});

}  // namespace softkin
