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

/// Vertices without a mirror image about the plane y = plane_y (to 1e-6 mm).
inline int UnmatchedMirrorVertices(const Mesh& mesh, double plane_y) {
  auto key = [](double x, double y, double z) {
    return std::array<long, 3>{std::lround(x * 1e6), std::lround(y * 1e6), std::lround(z * 1e6)};
  };
  std::map<std::array<long, 3>, int> at;
  for (int v = 0; v < mesh.num_vertices(); ++v)
    at[key(mesh.vertices(v, 0), mesh.vertices(v, 1), mesh.vertices(v, 2))] = v;
  int unmatched = 0;
  for (int v = 0; v < mesh.num_vertices(); ++v)
    unmatched +=
        !at.count(key(mesh.vertices(v, 0), 2 * plane_y - mesh.vertices(v, 1), mesh.vertices(v, 2)));
  return unmatched;
}

/// Elements whose mirror image about the plane x_axis = plane (axis 0, 1 or 2; to 1e-6 mm) is not
/// an element of the mesh (regions are not compared: a mirror may swap a robot's left and right
/// chambers). A mesh can have every vertex mirrored and still not be symmetric: its tets'
/// diagonals may all lean one way. Elements with a vertex that has no mirror image count.
inline int UnmatchedMirrorElements(const Mesh& mesh, int axis, double plane) {
  auto key = [](Eigen::Vector3d p) {
    return std::array<long, 3>{std::lround(p.x() * 1e6), std::lround(p.y() * 1e6),
                               std::lround(p.z() * 1e6)};
  };
  std::map<std::array<long, 3>, int> at;
  for (int v = 0; v < mesh.num_vertices(); ++v) at[key(mesh.vertices.row(v).transpose())] = v;
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
      Eigen::Vector3d p = mesh.vertices.row(e.v[q]).transpose();
      p[axis] = 2 * plane - p[axis];
      const auto it = at.find(key(p));
      found = it != at.end();
      if (found) m.v[q] = it->second;
    }
    unmatched += !(found && elements.count(sorted_ids(m)));
  }
  return unmatched;
}

}  // namespace test
}  // namespace softkin
