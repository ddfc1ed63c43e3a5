#include "softkin/solver/mesh/mesh.hpp"
#include "softkin/solver/common/text_format.hpp"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <numeric>
#include <stdexcept>
#include <string>

namespace softkin {

const char* ElementTypeToString(ElementType t) {
  switch (t) {
    case ElementType::Tet:
      return "tet";
    case ElementType::Prism:
      return "prism";
  }
  return "unknown";
}

int Mesh::num_tets() const {
  return static_cast<int>(std::count_if(elements.begin(), elements.end(), [](const Element& e) {
    return e.type == ElementType::Tet;
  }));
}

int Mesh::num_prisms() const {
  return static_cast<int>(std::count_if(elements.begin(), elements.end(), [](const Element& e) {
    return e.type == ElementType::Prism;
  }));
}

std::vector<int> Mesh::regions() const {
  std::vector<int> r;
  r.reserve(elements.size());
  for (const auto& e : elements) r.push_back(e.region);
  std::sort(r.begin(), r.end());
  r.erase(std::unique(r.begin(), r.end()), r.end());
  return r;
}

double Mesh::size() const {
  if (vertices.rows() == 0) return 0.0;
  return (vertices.colwise().maxCoeff() - vertices.colwise().minCoeff()).norm();
}

namespace {

inline double TetVolume6(const Eigen::Ref<const Eigen::MatrixX3d>& X, int a, int b, int c, int d) {
  const Eigen::RowVector3d p = X.row(a);
  const Eigen::RowVector3d u = X.row(b) - p, v = X.row(c) - p, w = X.row(d) - p;
  return u.cross(v).dot(w);
}

std::string Where(const std::string& source, const std::vector<int>& lines, int i,
                  const char* kind) {
  if (i >= 0 && i < static_cast<int>(lines.size()) && lines[i] > 0)
    return source + ":" + std::to_string(lines[i]);
  return source + ": " + kind + " " + std::to_string(i);
}

[[noreturn]] void Throw(const std::string& where, const std::string& what,
                        const std::string& expected) {
  throw std::runtime_error(where + ": " + what + "; expected " + expected);
}

struct UnionFind {
  std::vector<int> parent;
  explicit UnionFind(int n) : parent(n) { std::iota(parent.begin(), parent.end(), 0); }
  int Find(int x) {
    while (parent[x] != x) {
      parent[x] = parent[parent[x]];
      x = parent[x];
    }
    return x;
  }
  void Unite(int a, int b) {
    a = Find(a);
    b = Find(b);
    if (a != b) parent[std::max(a, b)] = std::min(a, b);
  }
};

}  // namespace

double SignedVolume(const Element& e, const Eigen::Ref<const Eigen::MatrixX3d>& X) {
  const auto& v = e.v;
  if (e.type == ElementType::Tet) return TetVolume6(X, v[0], v[1], v[2], v[3]) / 6.0;
  // Prism split into (0,1,2,3), (1,2,3,4), (2,3,4,5): all positive for a positively oriented
  // prism; the outer faces of the split triangulate the quads, so the sum is exact when the quad
  // faces are planar.
  return (TetVolume6(X, v[0], v[1], v[2], v[3]) + TetVolume6(X, v[1], v[2], v[3], v[4]) +
          TetVolume6(X, v[2], v[3], v[4], v[5])) /
         6.0;
}

int CountInvertedElements(const Mesh& mesh, const Eigen::Ref<const Eigen::MatrixX3d>& X) {
  if (X.rows() != mesh.num_vertices())
    throw std::invalid_argument("CountInvertedElements: " + std::to_string(X.rows()) +
                                " positions for a mesh of " + std::to_string(mesh.num_vertices()) +
                                " vertices");
  int n = 0;
  for (const auto& e : mesh.elements) n += SignedVolume(e, X) > 0 ? 0 : 1;
  return n;
}

void FlipElement(Element& e) {
  if (e.type == ElementType::Tet) {
    std::swap(e.v[1], e.v[2]);
  } else {
    std::swap(e.v[1], e.v[2]);
    std::swap(e.v[4], e.v[5]);
  }
}

std::vector<int> ElementComponents(const Mesh& mesh, int* count) {
  const int nv = mesh.num_vertices();
  UnionFind uf(nv);
  for (const auto& e : mesh.elements) {
    const int k = e.k();
    for (int j = 1; j < k; ++j) {
      if (e.v[0] >= 0 && e.v[0] < nv && e.v[j] >= 0 && e.v[j] < nv) uf.Unite(e.v[0], e.v[j]);
    }
  }
  std::vector<int> label(nv, -1);
  std::vector<int> comp(mesh.elements.size(), -1);
  int n = 0;
  for (std::size_t i = 0; i < mesh.elements.size(); ++i) {
    const int a = mesh.elements[i].v[0];
    if (a < 0 || a >= nv) continue;
    const int root = uf.Find(a);
    if (label[root] < 0) label[root] = n++;
    comp[i] = label[root];
  }
  if (count) *count = n;
  return comp;
}

MeshReport ValidateAndOrient(Mesh& mesh, const std::string& source,
                             const std::vector<int>& element_lines,
                             const std::vector<int>& vertex_lines) {
  MeshReport rep;
  const int nv = mesh.num_vertices();
  const int ne = mesh.num_elements();
  if (ne == 0) Throw(source, "the mesh has no elements", "at least one tetrahedron or prism");

  // Coordinates must be finite.
  for (int j = 0; j < nv; ++j) {
    for (int c = 0; c < 3; ++c) {
      const double x = mesh.vertices(j, c);
      if (!std::isfinite(x)) {
        Throw(Where(source, vertex_lines, j, "vertex"),
              "vertex " + std::to_string(j) + " has a non-finite coordinate (" +
                  (std::isnan(x) ? std::string("NaN") : std::string(x > 0 ? "+Inf" : "-Inf")) + ")",
              "finite numbers");
      }
    }
  }

  // Connectivity: element kind, index range, no repeated vertex.
  std::vector<char> used(nv, 0);
  for (int i = 0; i < ne; ++i) {
    const Element& e = mesh.elements[i];
    if (e.type != ElementType::Tet && e.type != ElementType::Prism)
      Throw(Where(source, element_lines, i, "element"),
            "element " + std::to_string(i) + " has unknown type " + std::to_string(e.k()),
            "a tet (4 vertices) or a prism (6 vertices)");
    const int k = e.k();
    for (int a = 0; a < k; ++a) {
      const int va = e.v[a];
      if (va < 0 || va >= nv)
        Throw(Where(source, element_lines, i, "element"),
              "element " + std::to_string(i) + " refers to vertex " + std::to_string(va) +
                  ", which is out of range",
              "a vertex index in [0, " + std::to_string(nv) + ")");
      for (int b = 0; b < a; ++b)
        if (e.v[b] == va)
          Throw(Where(source, element_lines, i, "element"),
                "element " + std::to_string(i) + " uses vertex " + std::to_string(va) + " twice",
                std::to_string(k) + " distinct vertices");
      used[va] = 1;
    }
  }

  // Orientation and degeneracy. |vol| is compared, so a consistently negatively oriented mesh is
  // flipped rather than rejected.
  const double h = mesh.size();
  const double tol = 1e-12 * h * h * h;
  for (int i = 0; i < ne; ++i) {
    Element& e = mesh.elements[i];
    double vol = SignedVolume(e, mesh.vertices);
    if (!(std::abs(vol) > tol)) {
      Throw(Where(source, element_lines, i, "element"),
            "element " + std::to_string(i) + " (" + ElementTypeToString(e.type) +
                ") is degenerate: signed volume " + FormatNumber(vol) + " mm^3",
            "|volume| > 1e-12 * size^3 = " + FormatNumber(tol) + " mm^3");
    }
    if (vol < 0) {
      FlipElement(e);
      ++rep.flipped;
    }
  }
  if (rep.flipped > 0)
    rep.notes.push_back(source + ": flipped " + std::to_string(rep.flipped) + " of " +
                        std::to_string(ne) + " elements (negatively oriented)");

  // Unused vertices.
  int first_unused = -1;
  for (int j = 0; j < nv; ++j) {
    if (!used[j]) {
      if (first_unused < 0) first_unused = j;
      ++rep.unused_vertices;
    }
  }
  if (rep.unused_vertices > 0)
    rep.warnings.push_back(source + ": " + std::to_string(rep.unused_vertices) + " of " +
                           std::to_string(nv) +
                           " vertices are not used by any element (first: vertex " +
                           std::to_string(first_unused) + ")");

  // Connected parts.
  ElementComponents(mesh, &rep.components);
  if (rep.components > 1)
    rep.warnings.push_back(source + ": the mesh has " + std::to_string(rep.components) +
                           " disconnected parts (groups of elements sharing no vertex)");
  return rep;
}

}  // namespace softkin
