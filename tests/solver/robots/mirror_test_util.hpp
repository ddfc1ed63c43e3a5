#pragma once
/// \file mirror_test_util.hpp
/// Mirror symmetry of a mesh, shared by the robot tests (test_robot_symmetry.cpp,
/// test_robots_grid.cpp).
#include "softkin/solver/mesh/mesh.hpp"

#include <array>
#include <cmath>
#include <map>
#include <set>
#include <utility>

namespace softkin {
namespace test {

/// A position rounded to 1e-6 mm, to find coincident vertices.
using PositionKey = std::array<long, 3>;
inline PositionKey KeyOf(const Eigen::Vector3d& p) {
  return {std::lround(p.x() * 1e6), std::lround(p.y() * 1e6), std::lround(p.z() * 1e6)};
}

/// Each vertex by its position (KeyOf).
inline std::map<PositionKey, int> VerticesByPosition(const Mesh& mesh) {
  std::map<PositionKey, int> at;
  for (int v = 0; v < mesh.num_vertices(); ++v) at[KeyOf(mesh.vertices.row(v).transpose())] = v;
  return at;
}

/// The mirror image of p about the plane x_axis = plane.
inline Eigen::Vector3d Mirrored(Eigen::Vector3d p, int axis, double plane) {
  p[axis] = 2 * plane - p[axis];
  return p;
}

/// Vertices without a mirror image about the plane y = plane_y (to 1e-6 mm).
inline int UnmatchedMirrorVertices(const Mesh& mesh, double plane_y) {
  const auto at = VerticesByPosition(mesh);
  int unmatched = 0;
  for (int v = 0; v < mesh.num_vertices(); ++v)
    unmatched += !at.count(KeyOf(Mirrored(mesh.vertices.row(v).transpose(), 1, plane_y)));
  return unmatched;
}

/// Elements whose mirror image about the plane x_axis = plane (axis 0, 1 or 2; to 1e-6 mm) is not
/// an element of the mesh (regions are not compared: a mirror may swap a robot's left and right
/// chambers). A mesh can have every vertex mirrored and still not be symmetric: its tets'
/// diagonals may all lean one way. Elements with a vertex that has no mirror image count.
inline int UnmatchedMirrorElements(const Mesh& mesh, int axis, double plane) {
  const auto at = VerticesByPosition(mesh);
  auto sorted_ids = [](const Element& e) {  // the vertex ids in increasing order, then -1s
    std::array<int, 6> ids = e.v;
    for (int a = 1; a < e.k(); ++a)
      for (int b = a; b > 0 && ids[b - 1] > ids[b]; --b) std::swap(ids[b - 1], ids[b]);
    return ids;
  };
  std::set<std::array<int, 6>> elements;
  for (const Element& e : mesh.elements) elements.insert(sorted_ids(e));
  int unmatched = 0;
  for (const Element& e : mesh.elements) {
    Element m = e;
    bool found = true;
    for (int q = 0; q < e.k() && found; ++q) {
      const auto it = at.find(KeyOf(Mirrored(mesh.vertices.row(e.v[q]).transpose(), axis, plane)));
      found = it != at.end();
      if (found) m.v[q] = it->second;
    }
    unmatched += !(found && elements.count(sorted_ids(m)));
  }
  return unmatched;
}

}  // namespace test
}  // namespace softkin
