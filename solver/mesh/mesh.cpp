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

namespace {

/// Names elements and vertices in messages: "<source>:<line>", "<source>: byte offset <n>", or
/// "<source>: element <i>" when the reader gave no location.
class Locator {
 public:
  Locator(const std::string& source, const MeshOrigin& origin) : src_(source), o_(origin) {}
  const std::string& source() const { return src_; }
  std::string Element(int i) const { return At(o_.element_at, i, "element"); }
  /// Vertex by its position in the file (MeshReport::source_vertex).
  std::string Vertex(int j) const { return At(o_.vertex_at, j, "vertex"); }
  /// " (line 12)" / " (byte offset 80)" / "" for element i.
  std::string ElementWhere(int i) const {
    if (!Known(o_.element_at, i)) return "";
    return std::string(o_.bytes ? " (byte offset " : " (line ") + std::to_string(o_.element_at[i]) +
           ")";
  }

 private:
  bool Known(const std::vector<long long>& at, int i) const {
    return i >= 0 && i < static_cast<int>(at.size()) && (o_.bytes ? at[i] >= 0 : at[i] > 0);
  }
  std::string At(const std::vector<long long>& at, int i, const char* kind) const {
    if (!Known(at, i)) return src_ + ": " + kind + " " + std::to_string(i);
    if (o_.bytes) return src_ + ": byte offset " + std::to_string(at[i]);
    return src_ + ":" + std::to_string(at[i]);
  }
  const std::string& src_;
  const MeshOrigin& o_;
};

std::string ElementText(const Mesh& mesh, int i) {
  const Element& e = mesh.elements[i];
  return "element " + std::to_string(i) + " (" + ElementTypeToString(e.type) + ", region " +
         std::to_string(e.region) + ")";
}

/// Element kinds, index ranges and repeated vertices; returns which vertices are used.
std::vector<char> CheckConnectivity(const Mesh& mesh, const Locator& loc) {
  const int nv = mesh.num_vertices();
  std::vector<char> used(static_cast<std::size_t>(nv), 0);
  for (int i = 0; i < mesh.num_elements(); ++i) {
    const Element& e = mesh.elements[i];
    if (e.type != ElementType::Tet && e.type != ElementType::Prism)
      Throw(loc.Element(i),
            "element " + std::to_string(i) + " has unknown type " + std::to_string(e.k()),
            "a tet (4 vertices) or a prism (6 vertices)");
    const int k = e.k();
    for (int a = 0; a < k; ++a) {
      const int va = e.v[a];
      if (va < 0 || va >= nv)
        Throw(loc.Element(i),
              "element " + std::to_string(i) + " refers to vertex " + std::to_string(va) +
                  ", which is out of range",
              "a vertex index in [0, " + std::to_string(nv) + ")");
      for (int b = 0; b < a; ++b)
        if (e.v[b] == va)
          Throw(loc.Element(i),
                "element " + std::to_string(i) + " uses vertex " + std::to_string(va) + " twice",
                std::to_string(k) + " distinct vertices");
      used[va] = 1;
    }
  }
  return used;
}

/// Two elements with one vertex set: e.g. Gmsh 2.2 writes an element once per physical group.
void CheckDuplicates(const Mesh& mesh, const Locator& loc) {
  const auto dup = DuplicateElementPairs(mesh);
  if (dup.empty()) return;
  const auto [a, b] = dup.front();
  Throw(loc.Element(b),
        ElementText(mesh, b) + " has the same vertices as " + ElementText(mesh, a) +
            loc.ElementWhere(a) +
            (dup.size() > 1 ? "; " + std::to_string(dup.size()) + " such pairs in all"
                            : std::string()),
        "each element once (a Gmsh 2.2 file lists an element once per physical group it belongs "
        "to: give each volume a single physical group)");
}

/// Removes unused vertices; fills rep->source_vertex and notes how many were dropped.
void DropUnused(Mesh& mesh, const std::vector<char>& used, const std::string& source,
                MeshReport* rep) {
  const int nv = mesh.num_vertices();
  std::vector<int> new_index(static_cast<std::size_t>(nv), -1);
  rep->source_vertex.clear();
  rep->source_vertex.reserve(static_cast<std::size_t>(nv));
  for (int j = 0; j < nv; ++j) {
    if (!used[j]) continue;
    new_index[j] = static_cast<int>(rep->source_vertex.size());
    rep->source_vertex.push_back(j);
  }
  rep->unused_vertices = nv - static_cast<int>(rep->source_vertex.size());
  if (rep->unused_vertices == 0) return;
  int first_unused = 0;
  while (used[first_unused]) ++first_unused;
  Eigen::MatrixX3d kept(static_cast<Eigen::Index>(rep->source_vertex.size()), 3);
  for (std::size_t j = 0; j < rep->source_vertex.size(); ++j)
    kept.row(static_cast<Eigen::Index>(j)) = mesh.vertices.row(rep->source_vertex[j]);
  mesh.vertices = std::move(kept);
  for (auto& e : mesh.elements)
    for (int a = 0; a < e.k(); ++a) e.v[a] = new_index[e.v[a]];
  rep->notes.push_back(source + ": dropped " + std::to_string(rep->unused_vertices) + " of " +
                       std::to_string(nv) + " vertices that no element uses (first: vertex " +
                       std::to_string(first_unused) +
                       " of the file, 0-based); vertex indices below refer to the kept vertices");
}

void CheckFinite(const Mesh& mesh, const std::vector<int>& source_vertex, const Locator& loc) {
  for (int j = 0; j < mesh.num_vertices(); ++j) {
    for (int c = 0; c < 3; ++c) {
      const double x = mesh.vertices(j, c);
      if (std::isfinite(x)) continue;
      const int f = source_vertex[j];
      Throw(loc.Vertex(f),
            "vertex " + std::to_string(f) + " has a non-finite coordinate (" +
                (std::isnan(x) ? std::string("NaN") : std::string(x > 0 ? "+Inf" : "-Inf")) + ")",
            "finite numbers");
    }
  }
}

/// Rejects degenerate elements and flips negatively oriented ones (|vol| is compared, so a
/// consistently negatively oriented mesh is flipped rather than rejected).
void Orient(Mesh& mesh, const Locator& loc, MeshReport* rep) {
  const double h = mesh.size();
  const double tol = 1e-12 * h * h * h;
  for (int i = 0; i < mesh.num_elements(); ++i) {
    Element& e = mesh.elements[i];
    const double vol = SignedVolume(e, mesh.vertices);
    if (!(std::abs(vol) > tol)) {
      Throw(loc.Element(i),
            "element " + std::to_string(i) + " (" + ElementTypeToString(e.type) +
                ") is degenerate: signed volume " + FormatNumber(vol) + " mm^3",
            "|volume| > 1e-12 * size^3 = " + FormatNumber(tol) + " mm^3");
    }
    if (vol < 0) {
      FlipElement(e);
      ++rep->flipped;
    }
  }
  if (rep->flipped > 0)
    rep->notes.push_back(loc.source() + ": flipped " + std::to_string(rep->flipped) + " of " +
                         std::to_string(mesh.num_elements()) + " elements (negatively oriented)");
}

/// After Orient every element is positive, so face neighbours must turn their shared face
/// opposite ways; the same way means they overlap (a fold), which no flip can repair.
void CheckFolds(const Mesh& mesh, const Locator& loc) {
  const auto folds = FoldedElementPairs(mesh);
  if (folds.empty()) return;
  const auto [a, b] = folds.front();
  Throw(loc.Element(b),
        ElementText(mesh, b) + " and " + ElementText(mesh, a) + loc.ElementWhere(a) +
            " share a face and lie on the same side of it: the mesh folds over itself" +
            (folds.size() > 1 ? " (" + std::to_string(folds.size()) + " such pairs in all)"
                              : std::string()),
        "face neighbours on opposite sides of their shared face (an untangled mesh; a mesh with "
        "every element reversed is fine and is flipped)");
}

/// Coincident vertices used by elements: the mesh is cut (cracked) there.
void WarnCracks(const Mesh& mesh, const std::vector<int>& source_vertex, const std::string& source,
                MeshReport* rep) {
  const auto pairs = CoincidentVertexPairs(mesh, 1e-10 * mesh.size());
  if (pairs.empty()) return;
  std::string list;
  const std::size_t shown = std::min<std::size_t>(pairs.size(), 10);
  for (std::size_t p = 0; p < shown; ++p)
    list += (p ? ", " : "") + std::to_string(source_vertex[pairs[p].first]) + "/" +
            std::to_string(source_vertex[pairs[p].second]);
  if (shown < pairs.size()) list += ", ...";
  rep->warnings.push_back(source + ": " + std::to_string(pairs.size()) +
                          " pairs of coincident vertices crack the mesh (file vertices, 0-based: " +
                          list + "); merge them unless the cut is intended");
}

}  // namespace

MeshReport ValidateAndOrient(Mesh& mesh, const std::string& source, const MeshOrigin& origin) {
  MeshReport rep;
  const Locator loc(source, origin);
  if (mesh.num_elements() == 0)
    Throw(source, "the mesh has no elements", "at least one tetrahedron or prism");
  const std::vector<char> used = CheckConnectivity(mesh, loc);
  CheckDuplicates(mesh, loc);
  DropUnused(mesh, used, source, &rep);
  CheckFinite(mesh, rep.source_vertex, loc);
  Orient(mesh, loc, &rep);
  CheckFolds(mesh, loc);
  WarnCracks(mesh, rep.source_vertex, source, &rep);
  ElementComponents(mesh, &rep.components);
  if (rep.components > 1)
    rep.warnings.push_back(source + ": the mesh has " + std::to_string(rep.components) +
                           " disconnected parts (groups of elements sharing no vertex)");
  return rep;
}

MeshReport ValidateAndOrient(Mesh& mesh, const std::string& source,
                             const std::vector<int>& element_lines,
                             const std::vector<int>& vertex_lines) {
  MeshOrigin origin;
  origin.element_at.assign(element_lines.begin(), element_lines.end());
  origin.vertex_at.assign(vertex_lines.begin(), vertex_lines.end());
  return ValidateAndOrient(mesh, source, origin);
}

}  // namespace softkin
