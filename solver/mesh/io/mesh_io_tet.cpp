/// \file mesh_io_tet.cpp
/// The thesis group's `.tet` format and its per-tet label file.
#include <cmath>

#include "softkin/solver/mesh/io/mesh_io.hpp"
#include "softkin/solver/mesh/io/mesh_io_detail.hpp"

namespace softkin {

namespace {

using detail::Scanner;

/// Reads "<count> <word>" where word must start with `word_prefix` (e.g. "vert", "tet").
long long ReadCountLine(Scanner& s, const char* word_prefix, const char* expected) {
  if (!s.SkipBlankLines()) s.FailHere("file ends before the header", expected);
  const long long n = s.Integer("the count");
  if (n < 0) s.FailHere("negative count " + std::to_string(n), expected);
  const std::string_view w = s.Word();
  if (w.substr(0, std::char_traits<char>::length(word_prefix)) != word_prefix)
    s.FailHere(
        "found " + (w.empty() ? std::string("end of line") : detail::Quote(w)) + " after the count",
        expected);
  s.ExpectEol(expected);
  s.NextLine();
  return n;
}

/// Reads one label per line (blank lines are skipped) and assigns them as regions.
void ReadLabels(const std::string& labels_path, Mesh& mesh) {
  Scanner s(labels_path, '#');
  const int ne = mesh.num_elements();
  int i = 0;
  while (s.SkipBlankLines()) {
    if (i == ne)
      s.FailHere("label " + std::to_string(i + 1) + " but the mesh has only " + std::to_string(ne) +
                     " tets",
                 std::to_string(ne) + " labels, one per tet");
    mesh.elements[i].region = s.Int("the label");
    s.ExpectEol("one integer label per line");
    ++i;
    s.NextLine();
  }
  if (i < ne)
    s.FailHere("file ends after " + std::to_string(i) + " of " + std::to_string(ne) + " labels",
               std::to_string(ne) + " labels, one per tet");
}

/// True if `mesh` (indices in range) has no degenerate element and no fold once every element is
/// oriented positively.
bool CleanWhenOriented(Mesh mesh) {
  const double h = mesh.size();
  for (auto& e : mesh.elements) {
    const double vol = SignedVolume(e, mesh.vertices);
    if (!(std::abs(vol) > 1e-12 * h * h * h)) return false;
    if (vol < 0) FlipElement(e);
  }
  return FoldedElementPairs(mesh).empty();
}

/// The thesis format is 0-based. A 1-based file uses no vertex 0; it is refused when it also uses
/// index N (the vertex count, out of range when 0-based), or when it reads as a clean mesh 1-based
/// but as a degenerate or folded one 0-based. A 0-based file that merely leaves vertex 0 unused
/// reads normally (the vertex is dropped with a note).
void CheckZeroBased(const Mesh& mesh, const std::string& path, const std::vector<int>& lines) {
  const int nv = mesh.num_vertices();
  int top = -1, top_elem = 0;
  for (int i = 0; i < mesh.num_elements(); ++i)
    for (int a = 0; a < 4; ++a) {
      const int v = mesh.elements[i].v[a];
      if (v == 0 || v < 0 || v > nv) return;  // 0-based, or out of range (reported later)
      if (v > top) {
        top = v;
        top_elem = i;
      }
    }
  if (top < 0) return;
  const char* expected =
      "0-based vertex indices (the .tet format counts vertices from 0): subtract 1 from every "
      "index of the tet lines";
  if (top == nv)
    detail::Fail(detail::At(path, lines[top_elem]),
                 "the file looks 1-based: this tet uses vertex " + std::to_string(nv) +
                     " (the vertex count) and no tet uses vertex 0",
                 expected);
  Mesh one_based = mesh;
  for (auto& e : one_based.elements)
    for (int a = 0; a < 4; ++a) --e.v[a];
  if (!CleanWhenOriented(mesh) && CleanWhenOriented(one_based))
    detail::Fail(path,
                 "the file looks 1-based: no tet uses vertex 0, and the tets are degenerate or "
                 "overlap when read 0-based but not when read 1-based",
                 expected);
}

}  // namespace

Mesh ReadTet(const std::string& path, const std::string& labels_path, MeshReport* report) {
  Scanner s(path);
  const int header_line = s.line();
  const long long nv = ReadCountLine(s, "vert", "'<N> vertices' on the first line");
  const int tets_line = s.line();
  const long long ne = ReadCountLine(s, "tet", "'<M> tets' on the second line");
  if (nv > INT_MAX || ne > INT_MAX)
    detail::Fail(detail::At(path, nv > INT_MAX ? header_line : tets_line), "count too large",
                 "fewer than 2^31 vertices and tets");

  Mesh mesh;
  std::vector<int> vertex_lines, element_lines;
  {
    const long long cap = detail::SafeReserve(nv, s.size());
    mesh.vertices.resize(cap, 3);
    vertex_lines.reserve(static_cast<std::size_t>(cap));
  }
  for (long long j = 0; j < nv; ++j) {
    if (!s.SkipBlankLines())
      s.FailHere("file ends after " + std::to_string(j) + " of " + std::to_string(nv) +
                     " vertices (count declared on line " + std::to_string(header_line) + ")",
                 std::to_string(nv) + " vertex lines 'x y z'");
    if (j >= mesh.vertices.rows())
      mesh.vertices.conservativeResize(2 * j + 1, 3);  // guard only: every line takes >= 2 bytes
    vertex_lines.push_back(s.line());
    mesh.vertices(j, 0) = s.Double("x");
    mesh.vertices(j, 1) = s.Double("y");
    mesh.vertices(j, 2) = s.Double("z");
    s.ExpectEol("3 coordinates 'x y z' per vertex line");
    s.NextLine();
  }
  mesh.vertices.conservativeResize(nv, 3);

  mesh.elements.reserve(static_cast<std::size_t>(detail::SafeReserve(ne, s.size())));
  element_lines.reserve(mesh.elements.capacity());
  for (long long i = 0; i < ne; ++i) {
    if (!s.SkipBlankLines())
      s.FailHere("file ends after " + std::to_string(i) + " of " + std::to_string(ne) +
                     " tets (count declared on line " + std::to_string(tets_line) + ")",
                 std::to_string(ne) + " tet lines '4 a b c d'");
    element_lines.push_back(s.line());
    const int k = s.Int("the vertex count");
    if (k != 4)
      s.FailHere("element with " + std::to_string(k) + " vertices",
                 "4 (lines '4 a b c d'; .tet holds only tetrahedra)");
    Element e;
    e.type = ElementType::Tet;
    for (int a = 0; a < 4; ++a) e.v[a] = s.Int("a vertex index");
    s.ExpectEol("'4 a b c d': 4 vertex indices per tet");
    mesh.elements.push_back(e);
    s.NextLine();
  }
  MeshReport rep;
  if (s.SkipBlankLines())
    rep.warnings.push_back(s.Here() + ": ignoring data after the " + std::to_string(ne) +
                           " declared tets");

  if (!labels_path.empty()) ReadLabels(labels_path, mesh);
  CheckZeroBased(mesh, path, element_lines);

  MeshReport v = ValidateAndOrient(mesh, path, element_lines, vertex_lines);
  v.warnings.insert(v.warnings.begin(), rep.warnings.begin(), rep.warnings.end());
  detail::Deliver(v, report);
  return mesh;
}

void WriteTet(const std::string& path, const Mesh& mesh, const std::string& labels_path) {
  if (mesh.num_prisms() > 0)
    detail::Fail(path, "cannot write " + std::to_string(mesh.num_prisms()) + " prisms to .tet",
                 "a tet-only mesh (use Gmsh or VTK for prisms)");
  {
    OutputFile out_file(path);
    std::ostream& out = detail::ForWrite(out_file);
    out << mesh.num_vertices() << " vertices\n" << mesh.num_elements() << " tets\n";
    for (int j = 0; j < mesh.num_vertices(); ++j) detail::WriteRow(out, mesh.vertices, j) << '\n';
    for (const auto& e : mesh.elements)
      out << "4 " << e.v[0] << ' ' << e.v[1] << ' ' << e.v[2] << ' ' << e.v[3] << '\n';
    out_file.Commit();
  }
  if (!labels_path.empty()) {
    OutputFile out_file(labels_path);
    std::ostream& out = detail::ForWrite(out_file);
    for (const auto& e : mesh.elements) out << e.region << '\n';
    out_file.Commit();
  }
}

}  // namespace softkin
