/// \file mesh_topology.cpp
/// Checks of a mesh's combinatorics used by ValidateAndOrient: duplicate elements, folds (face
/// neighbours on the same side of their shared face) and cracks (coincident vertices).
#include <algorithm>
#include <array>
#include <climits>
#include <cmath>
#include <tuple>

#include "softkin/solver/mesh/element_faces.hpp"
#include "softkin/solver/mesh/mesh.hpp"

namespace softkin {

namespace {

void AddPair(int a, int b, std::vector<std::pair<int, int>>* out) {
  out->emplace_back(std::min(a, b), std::max(a, b));
}

}  // namespace

std::vector<std::pair<int, int>> FoldedElementPairs(const Mesh& mesh) {
  const std::vector<MeshFace> faces = SortedMeshFaces(mesh);
  std::vector<std::pair<int, int>> out;
  for (std::size_t i = 0; i < faces.size();) {
    std::size_t j = i + 1;
    while (j < faces.size() && faces[j].key == faces[i].key) ++j;
    if (j - i == 2 && faces[i].turn == faces[i + 1].turn) {
      AddPair(faces[i].element, faces[i + 1].element, &out);
    } else if (j - i > 2) {  // three or more elements on one face: some of them overlap
      for (std::size_t q = i + 1; q < j; ++q) AddPair(faces[i].element, faces[q].element, &out);
    }
    i = j;
  }
  std::sort(out.begin(), out.end());
  out.erase(std::unique(out.begin(), out.end()), out.end());
  return out;
}

std::vector<std::pair<int, int>> DuplicateElementPairs(const Mesh& mesh) {
  const int ne = mesh.num_elements();
  std::vector<std::array<int, 6>> keys(static_cast<std::size_t>(ne));
  for (int i = 0; i < ne; ++i) {
    std::array<int, 6> k = mesh.elements[i].v;
    for (int a = mesh.elements[i].k(); a < 6; ++a) k[a] = INT_MAX;
    std::sort(k.begin(), k.end());
    keys[i] = k;
  }
  std::vector<int> order(static_cast<std::size_t>(ne));
  for (int i = 0; i < ne; ++i) order[i] = i;
  std::sort(order.begin(), order.end(),
            [&](int a, int b) { return std::tie(keys[a], a) < std::tie(keys[b], b); });
  std::vector<std::pair<int, int>> out;
  for (int i = 0; i < ne;) {
    int j = i + 1;
    while (j < ne && keys[order[j]] == keys[order[i]]) ++j;
    for (int q = i + 1; q < j; ++q) out.emplace_back(order[i], order[q]);
    i = j;
  }
  std::sort(out.begin(), out.end());
  return out;
}

std::vector<std::pair<int, int>> CoincidentVertexPairs(const Mesh& mesh, double tol) {
  const int nv = mesh.num_vertices();
  std::vector<char> used(static_cast<std::size_t>(nv), 0);
  for (const auto& e : mesh.elements)
    for (int a = 0; a < e.k(); ++a) used[e.v[a]] = 1;
  // Bucket the vertices in cells of side >= tol (large enough for the cell numbers to fit in 64
  // bits); a pair within tol lies in neighbouring cells.
  const double far = nv > 0 ? mesh.vertices.cwiseAbs().maxCoeff() : 0.0;
  const double cell = std::max({tol, far * 1e-15, 1e-300});
  using Cell = std::array<long long, 3>;
  std::vector<std::pair<Cell, int>> grid;
  grid.reserve(static_cast<std::size_t>(nv));
  for (int j = 0; j < nv; ++j) {
    if (!used[j]) continue;
    Cell c;
    for (int d = 0; d < 3; ++d) c[d] = std::llround(std::floor(mesh.vertices(j, d) / cell));
    grid.emplace_back(c, j);
  }
  std::sort(grid.begin(), grid.end());
  std::vector<std::pair<int, int>> out;
  for (const auto& [c, j] : grid) {
    for (int o = 0; o < 27; ++o) {
      const Cell n = {c[0] + o % 3 - 1, c[1] + (o / 3) % 3 - 1, c[2] + o / 9 - 1};
      auto it = std::lower_bound(grid.begin(), grid.end(), std::make_pair(n, INT_MIN));
      for (; it != grid.end() && it->first == n; ++it) {
        if (it->second <= j) continue;
        if ((mesh.vertices.row(it->second) - mesh.vertices.row(j)).norm() <= tol)
          out.emplace_back(j, it->second);
      }
    }
  }
  std::sort(out.begin(), out.end());
  return out;
}

}  // namespace softkin
