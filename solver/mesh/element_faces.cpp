#include "softkin/solver/mesh/element_faces.hpp"

#include <algorithm>
#include <climits>
#include <cstddef>
#include <tuple>

namespace softkin {

const LocalFace* LocalFaces(ElementType t, int* count) {
  const bool tet = t == ElementType::Tet;
  *count = tet ? 4 : 5;
  return tet ? kTetFaces : kPrismFaces;
}

std::vector<MeshFace> SortedMeshFaces(const Mesh& mesh) {
  std::vector<MeshFace> faces;
  faces.reserve(static_cast<std::size_t>(mesh.num_tets()) * 4 +
                static_cast<std::size_t>(mesh.num_prisms()) * 5);
  for (int i = 0; i < mesh.num_elements(); ++i) {
    const Element& e = mesh.elements[i];
    int nf = 0;
    const LocalFace* lf = LocalFaces(e.type, &nf);
    for (int f = 0; f < nf; ++f) {
      std::array<int, 4> cyc = {e.v[lf[f].a], e.v[lf[f].b], e.v[lf[f].c],
                                lf[f].d >= 0 ? e.v[lf[f].d] : INT_MAX};
      const int n = lf[f].d >= 0 ? 4 : 3;
      const int m = static_cast<int>(std::min_element(cyc.begin(), cyc.begin() + n) - cyc.begin());
      const bool turn = cyc[(m + 1) % n] < cyc[(m + n - 1) % n];
      std::sort(cyc.begin(), cyc.end());
      faces.push_back({cyc, i, f, turn});
    }
  }
  std::sort(faces.begin(), faces.end(), [](const MeshFace& a, const MeshFace& b) {
    return std::tie(a.key, a.element, a.local) < std::tie(b.key, b.element, b.local);
  });
  return faces;
}

std::vector<int> BoundaryVertices(const Mesh& mesh) {
  const std::vector<MeshFace> faces = SortedMeshFaces(mesh);
  std::vector<bool> on(mesh.num_vertices(), false);
  for (size_t q = 0; q < faces.size(); ++q) {
    if ((q > 0 && faces[q - 1].key == faces[q].key) ||
        (q + 1 < faces.size() && faces[q + 1].key == faces[q].key))
      continue;  // shared by two elements
    for (int v : faces[q].key)
      if (v >= 0 && v < mesh.num_vertices()) on[v] = true;  // skips a triangle's INT_MAX pad
  }
  std::vector<int> out;
  for (int v = 0; v < mesh.num_vertices(); ++v)
    if (on[v]) out.push_back(v);
  return out;
}

}  // namespace softkin
