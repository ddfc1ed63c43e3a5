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
///    is found even where it lies on a face shared by two tets. The broad phase is
///    CGAL::box_intersection_d (default) or a CGAL AABB tree over the tets (SelfCollisionDetector).
/// Robot-obstacle contact (Eq. 3.4): a robot vertex strictly inside an obstacle.
#include "solver/mesh.hpp"

#include <Eigen/Dense>

#include <memory>
#include <string>
#include <vector>

namespace softkin {

/// A triangle surface: #V x 3 vertices (mm), #F x 3 vertex indices (counter-clockwise seen from
/// outside), and where it came from (for messages).
struct TriangleSurface {
  Eigen::MatrixX3d vertices;
  Eigen::MatrixX3i faces;
  std::string source;
};

/// Reads an obstacle surface from Wavefront OBJ (`v` and `f` lines; polygons are split into
/// fans; `f 1/2/3` forms and negative indices accepted; other lines ignored) or STL (ASCII or
/// binary; duplicate corner points are merged exactly), by extension (.obj, .stl). Then checks it
/// with CheckClosedSurface. Throws std::invalid_argument naming the file (and line, for text
/// formats) and what was expected.
TriangleSurface ReadSurfaceMesh(const std::string& path);

/// Checks a surface for use as an obstacle: finite coordinates, indices in range, no degenerate
/// triangle, every edge shared by exactly two triangles with opposite directions (closed and
/// consistently oriented), and positive enclosed volume (outward normals; an inside-out surface
/// is flipped). Throws std::invalid_argument naming `s.source` and the first offending element.
void CheckClosedSurface(TriangleSurface* s);

/// An axis-aligned box obstacle [lo, hi] (12 triangles).
TriangleSurface MakeBoxSurface(const Eigen::Vector3d& lo, const Eigen::Vector3d& hi);
/// A closed cylinder obstacle: axis from `base` along unit `axis` for `height`, with `segments`
/// sides (>= 3).
TriangleSurface MakeCylinderSurface(const Eigen::Vector3d& base, const Eigen::Vector3d& axis,
                                    double radius, double height, int segments = 48);

/// A static obstacle with its CGAL trees.
class Obstacle {
 public:
  explicit Obstacle(TriangleSurface surface);  ///< checks it (CheckClosedSurface)
  ~Obstacle();
  Obstacle(Obstacle&&) noexcept;
  Obstacle& operator=(Obstacle&&) noexcept;
  /// True if p lies strictly inside (on the surface is outside).
  bool Contains(const Eigen::Vector3d& p) const;
  /// Closest point on the surface to p, and the outward unit normal of its triangle.
  Eigen::Vector3d ClosestPoint(const Eigen::Vector3d& p, Eigen::Vector3d* normal = nullptr) const;
  const TriangleSurface& surface() const { return surface_; }

 private:
  struct Impl;
  TriangleSurface surface_;
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
/// std::invalid_argument). Two broad phases, same exact test and same answer:
///  - kBoxIntersection (default): CGAL::box_intersection_d between the boundary vertices' point
///    boxes and the tets' boxes at the current positions; no hierarchy to keep up to date.
///  - kAabbTree: a CGAL AABB tree over the tets, rebuilt by Update() (CGAL's tree has no refit),
///    queried per boundary vertex.
class SelfCollisionDetector {
 public:
  enum class Method { kBoxIntersection, kAabbTree };
  explicit SelfCollisionDetector(const Mesh& mesh, Method method = Method::kBoxIntersection);
  ~SelfCollisionDetector();
  /// Takes positions X (#V x 3); kAabbTree rebuilds its tree. Seconds spent: last_build_s().
  void Update(const Eigen::Ref<const Eigen::MatrixX3d>& X);
  /// Boundary vertices inside (or on) a non-incident tet at the positions of the last Update
  /// (each vertex once, with the lowest such tet id). Seconds spent are in last_query_s().
  std::vector<SelfContact> Detect() const;
  /// The boundary vertices (on faces that belong to one tet only), sorted.
  const std::vector<int>& boundary_vertices() const { return boundary_; }
  double last_build_s() const { return build_s_; }
  double last_query_s() const { return query_s_; }

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
  Method method_;
  std::vector<int> boundary_;
  double build_s_ = 0;
  mutable double query_s_ = 0;
};

/// Vertices of `vertices` (all robot vertices if empty) strictly inside any of the obstacles.
std::vector<ObstacleContact> DetectObstacleContacts(const std::vector<Obstacle>& obstacles,
                                                    const Eigen::Ref<const Eigen::MatrixX3d>& X,
                                                    const std::vector<int>& vertices = {});

}  // namespace softkin
