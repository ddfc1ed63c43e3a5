#pragma once
/// \file mirror_test_util.hpp
/// Mirror symmetry of a mesh, shared by the robot tests (test_robot_symmetry.cpp,
/// test_robots_grid.cpp).
#include "softkin/solver/mesh/mesh.hpp"

#include <array>
#include <cmath>
#include <map>

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

}  // namespace test
}  // namespace softkin
