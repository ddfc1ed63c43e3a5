/// \file mesh_io_tetgen.cpp
/// TetGen `.node` + `.ele` files ('#' comments, 0- or 1-based numbering taken from the first node).
#include <cmath>

#include "softkin/solver/mesh/io/mesh_io.hpp"
#include "softkin/solver/mesh/io/mesh_io_detail.hpp"

namespace softkin {

namespace {

using detail::Scanner;

/// "foo.node" / "foo.ele" / "foo" -> "foo".
std::string StripTetGenExtension(const std::string& base) {
  const std::string ext = detail::LowerExtension(base);
  if (ext == ".node" || ext == ".ele") return base.substr(0, base.size() - ext.size());
  return base;
}

/// Reads the points of TetGen's <base>.node into mesh->vertices and returns their number;
/// *first_index receives the numbering's base (0 or 1, from the first point).
long long ReadTetGenNodes(const std::string& base, Mesh* out, long long* first_index_out) {
  Mesh& mesh = *out;
  long long& first_index = *first_index_out;
  long long nv = 0;
  Scanner s(base + ".node", '#');
  const char* header = "'<#points> 3 <#attributes> <#boundary markers 0|1>'";
  if (!s.SkipBlankLines()) s.FailHere("file is empty", header);
  const int header_line = s.line();
  nv = s.Integer("the number of points");
  const long long dim = s.Integer("the dimension");
  long long nattr = 0, nmark = 0;
  if (!s.AtEol()) nattr = s.Integer("the number of attributes");
  if (!s.AtEol()) nmark = s.Integer("the number of boundary markers");
  s.ExpectEol(header);
  if (nv <= 0 || nv > INT_MAX)
    s.FailHere("number of points " + std::to_string(nv), "a positive count");
  if (dim != 3) s.FailHere("dimension " + std::to_string(dim), "3");
  if (nattr < 0 || nattr > 1000)
    s.FailHere("number of attributes " + std::to_string(nattr), "a count in [0, 1000]");
  if (nmark != 0 && nmark != 1)
    s.FailHere("number of boundary markers " + std::to_string(nmark), "0 or 1");
  s.NextLine();

  const long long cap = detail::SafeReserve(nv, s.size());
  mesh.vertices.resize(cap, 3);
  for (long long j = 0; j < nv; ++j) {
    if (!s.SkipBlankLines())
      s.FailHere("file ends after " + std::to_string(j) + " of " + std::to_string(nv) +
                     " points (count declared on line " + std::to_string(header_line) + ")",
                 std::to_string(nv) + " point lines '<index> x y z'");
    if (j >= mesh.vertices.rows()) mesh.vertices.conservativeResize(2 * j + 1, 3);  // guard only
    const long long idx = s.Integer("the point index");
    if (j == 0) {
      if (idx != 0 && idx != 1) s.FailHere("first point index " + std::to_string(idx), "0 or 1");
      first_index = idx;
    } else if (idx != first_index + j) {
      s.FailHere("point index " + std::to_string(idx),
                 std::to_string(first_index + j) + " (points numbered consecutively)");
    }
    mesh.vertices(j, 0) = s.Double("x");
    mesh.vertices(j, 1) = s.Double("y");
    mesh.vertices(j, 2) = s.Double("z");
    if (!mesh.vertices.row(j).allFinite())
      s.FailHere("point " + std::to_string(idx) + " has a non-finite coordinate (NaN or Inf)",
                 "finite numbers");
    for (long long a = 0; a < nattr; ++a) s.Double("a point attribute");
    if (nmark) s.Integer("the boundary marker");
    s.ExpectEol(nattr || nmark ? "'<index> x y z' followed by the declared attributes/marker"
                               : "'<index> x y z'");
    s.NextLine();
  }
  mesh.vertices.conservativeResize(nv, 3);
  return nv;
}

/// Reads the tets of TetGen's <base>.ele (node indices numbered from first_index, nv nodes) into
/// mesh->elements, with each one's line in *element_lines (for ValidateAndOrient's messages).
/// Returns the nodes per tetrahedron (4, or 10 for tetgen -o2, read by their corners).
long long ReadTetGenElements(const std::string& base, long long nv, long long first_index,
                             Mesh* out, std::vector<int>* element_lines_out) {
  Mesh& mesh = *out;
  std::vector<int>& element_lines = *element_lines_out;
  Scanner s(base + ".ele", '#');
  const char* header = "'<#tetrahedra> 4 <#attributes>'";
  if (!s.SkipBlankLines()) s.FailHere("file is empty", header);
  const int header_line = s.line();
  const long long ne = s.Integer("the number of tetrahedra");
  const long long npt = s.Integer("the nodes per tetrahedron");
  long long nattr = 0;
  if (!s.AtEol()) nattr = s.Integer("the number of attributes");
  s.ExpectEol(header);
  if (ne < 0 || ne > INT_MAX)
    s.FailHere("number of tetrahedra " + std::to_string(ne), "a count >= 0");
  if (npt != 4 && npt != 10)
    s.FailHere(std::to_string(npt) + " nodes per tetrahedron",
               "4, or 10 (tetgen -o2; read by the 4 corner nodes)");
  if (nattr < 0 || nattr > 1000)
    s.FailHere("number of attributes " + std::to_string(nattr), "a count in [0, 1000]");
  s.NextLine();

  mesh.elements.reserve(static_cast<std::size_t>(detail::SafeReserve(ne, s.size())));
  element_lines.reserve(mesh.elements.capacity());
  long long first_ele = 0;
  for (long long i = 0; i < ne; ++i) {
    if (!s.SkipBlankLines())
      s.FailHere("file ends after " + std::to_string(i) + " of " + std::to_string(ne) +
                     " tetrahedra (count declared on line " + std::to_string(header_line) + ")",
                 std::to_string(ne) + " lines '<index> n1 n2 n3 n4 [attributes]'");
    element_lines.push_back(s.line());
    const long long idx = s.Integer("the tetrahedron index");
    if (i == 0) {
      first_ele = idx;
    } else if (idx != first_ele + i) {
      s.FailHere("tetrahedron index " + std::to_string(idx),
                 std::to_string(first_ele + i) + " (tetrahedra numbered consecutively)");
    }
    Element e;
    e.type = ElementType::Tet;
    for (int a = 0; a < npt; ++a) {
      const long long n = s.Integer("a node index");
      if (n < first_index || n >= first_index + nv)
        s.FailHere("node index " + std::to_string(n) + " is out of range",
                   "a node index in [" + std::to_string(first_index) + ", " +
                       std::to_string(first_index + nv - 1) + "] (numbering of the .node file)");
      if (a < 4) e.v[a] = static_cast<int>(n - first_index);  // corners come first
    }
    for (long long a = 0; a < nattr; ++a) {
      const double x = s.Double("an attribute");
      if (a == 0) {
        const double r = std::round(x);
        if (!(std::abs(x - r) <= 1e-9 * std::max(1.0, std::abs(x))) || std::abs(r) > INT_MAX)
          s.FailHere("region attribute " + std::to_string(x) + " is not an integer",
                     "an integer region attribute");
        e.region = static_cast<int>(r);
      }
    }
    s.ExpectEol(npt == 4 ? "'<index> n1 n2 n3 n4' followed by the declared number of attributes"
                         : "'<index> n1 ... n10' followed by the declared number of attributes");
    mesh.elements.push_back(e);
    s.NextLine();
  }
  return npt;
}

}  // namespace

Mesh ReadTetGen(const std::string& base_in, MeshReport* report) {
  const std::string base = StripTetGenExtension(base_in);
  Mesh mesh;
  std::vector<int> element_lines;
  long long first_index = 0;  // 0 or 1, from the first node
  const long long nv = ReadTetGenNodes(base, &mesh, &first_index);
  const long long npt = ReadTetGenElements(base, nv, first_index, &mesh, &element_lines);

  // Coordinates were checked against the .node file's lines as they were read (ReadTetGenNodes);
  // elements name the .ele file.
  MeshReport rep = ValidateAndOrient(mesh, base + ".ele", element_lines, {});
  if (npt == 10) detail::NoteCornersOnly(base + ".ele", mesh.num_elements(), &rep);
  detail::Deliver(rep, report);
  return mesh;
}

void WriteTetGen(const std::string& base_in, const Mesh& mesh) {
  const std::string base = StripTetGenExtension(base_in);
  if (mesh.num_prisms() > 0)
    detail::Fail(base + ".ele",
                 "cannot write " + std::to_string(mesh.num_prisms()) + " prisms to TetGen",
                 "a tet-only mesh (use Gmsh or VTK for prisms)");
  {
    const std::string p = base + ".node";
    OutputFile out_file(p);
    std::ostream& out = detail::ForWrite(out_file);
    out << "# SoftKin mesh: <#points> <dim> <#attributes> <#boundary markers>\n";
    out << mesh.num_vertices() << " 3 0 0\n";
    for (int j = 0; j < mesh.num_vertices(); ++j)
      detail::WriteRow(out << j + 1 << ' ', mesh.vertices, j) << '\n';
    out_file.Commit();
  }
  {
    const std::string p = base + ".ele";
    OutputFile out_file(p);
    std::ostream& out = detail::ForWrite(out_file);
    out << "# SoftKin mesh: <#tetrahedra> <nodes per tet> <#attributes (region)>\n";
    out << mesh.num_elements() << " 4 1\n";
    for (int i = 0; i < mesh.num_elements(); ++i) {
      const auto& e = mesh.elements[i];
      out << i + 1 << ' ' << e.v[0] + 1 << ' ' << e.v[1] + 1 << ' ' << e.v[2] + 1 << ' '
          << e.v[3] + 1 << ' ' << e.region << '\n';
    }
    out_file.Commit();
  }
}

}  // namespace softkin
