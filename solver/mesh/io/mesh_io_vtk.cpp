/// \file mesh_io_vtk.cpp
/// Legacy ASCII VTK UNSTRUCTURED_GRID: reader (classic CELLS and VTK 5.1 OFFSETS/CONNECTIVITY,
/// cell types 10 tetra and 13 wedge, lower-dimensional cells skipped) and writer. VTK wedges have
/// the opposite bottom-triangle orientation from SoftKin/Gmsh prisms and are converted both ways.
#include <cmath>

#include "softkin/solver/mesh/io/mesh_io.hpp"
#include "softkin/solver/mesh/io/mesh_io_detail.hpp"

namespace softkin {

namespace {

using detail::Scanner;

bool IEquals(std::string_view a, const char* b) {
  const std::size_t n = std::char_traits<char>::length(b);
  if (a.size() != n) return false;
  for (std::size_t i = 0; i < n; ++i)
    if (std::toupper(static_cast<unsigned char>(a[i])) !=
        std::toupper(static_cast<unsigned char>(b[i])))
      return false;
  return true;
}

bool IsIntegerType(std::string_view t) { return !(IEquals(t, "float") || IEquals(t, "double")); }

bool NameSuggestsTag(std::string_view name) {
  std::string n(name);
  for (char& c : n) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  for (const char* w :
       {"region", "tag", "label", "material", "physical", "attribute", "domain", "entity"})
    if (n.find(w) != std::string::npos) return true;
  return false;
}

/// Lower-dimensional VTK cell types that are skipped (vertex, lines, polygons, quadratic and
/// higher-order curves/surfaces).
bool IsSkippedCellType(long long t) {
  switch (t) {
    case 1:
    case 2:
    case 3:
    case 4:
    case 5:
    case 6:
    case 7:
    case 8:
    case 9:  // linear 0D-2D
    case 21:
    case 22:
    case 23:
    case 28:
    case 30:
    case 34:
    case 35:
    case 36:  // quadratic/cubic 1D-2D
    case 68:
    case 69:
    case 70:
    case 75:
    case 76:
    case 77:  // Lagrange/Bezier 1D-2D
      return true;
    default:
      return false;
  }
}

const char* VtkCellName(long long t) {
  switch (t) {
    case 10:
      return "tetra";
    case 11:
      return "voxel";
    case 12:
      return "hexahedron";
    case 13:
      return "wedge";
    case 14:
      return "pyramid";
    case 15:
      return "pentagonal prism";
    case 16:
      return "hexagonal prism";
    case 24:
      return "quadratic tetra";
    case 25:
      return "quadratic hexahedron";
    case 26:
      return "quadratic wedge";
    case 27:
      return "quadratic pyramid";
    case 42:
      return "polyhedron";
    default:
      return nullptr;
  }
}

struct CellArray {
  std::string name;
  int line = 0;  ///< line of the array header
  bool integer_type = false;
  std::vector<double> values;  ///< one per cell (single-component arrays only)
};

struct Reader {
  Scanner s;
  Mesh mesh;
  std::vector<int> vertex_lines;
  long long num_points = -1;
  // cells
  long long num_cells = -1;
  int cells_line = 0;
  std::vector<long long> offsets;  // num_cells + 1
  std::vector<int> conn;
  std::vector<int> cell_lines;
  std::vector<unsigned char> cell_types;
  bool have_types = false;
  // attribute section state: 0 none, 1 point data, 2 cell data
  int mode = 0;
  long long mode_count = 0;
  std::vector<CellArray> cell_arrays;

  explicit Reader(const std::string& path) : s(path) {}

  std::string_view RequireWord(const char* expected) {
    const std::string_view w = s.Word();
    if (w.empty()) s.FailHere("line ends early", expected);
    return w;
  }

  long long Count(const char* what) {
    const long long n = s.Integer(what);
    if (n < 0 || n > INT_MAX)
      s.FailHere(std::string(what) + " " + std::to_string(n), "a count in [0, 2^31)");
    return n;
  }

  /// Reads n numbers of a data array, keeping them in *keep if given.
  void Values(long long n, const char* what, std::vector<double>* keep) {
    if (keep) keep->reserve(static_cast<std::size_t>(detail::SafeReserve(n, s.size())));
    for (long long i = 0; i < n; ++i) {
      const double v = s.StreamDouble(what);
      if (keep) keep->push_back(v);
    }
  }

  void RequireData(const char* keyword) {
    if (mode == 0)
      s.FailHere(std::string(keyword) + " outside CELL_DATA/POINT_DATA",
                 "CELL_DATA <n> or POINT_DATA <n> first");
  }

  void SkipMetadata() {
    // METADATA blocks end with an empty line.
    s.NextLine();
    while (!s.Eof() && !s.AtEol()) s.NextLine();
  }

  void Points() {
    num_points = Count("the number of points");
    RequireWord("the point data type (float or double)");
    s.ExpectEol("'POINTS <n> <type>'");
    const long long cap = detail::SafeReserve(num_points, s.size());
    mesh.vertices.resize(cap, 3);
    vertex_lines.reserve(static_cast<std::size_t>(cap));
    for (long long j = 0; j < num_points; ++j) {
      if (!s.SkipWs())
        s.FailHere("file ends after " + std::to_string(j) + " of " + std::to_string(num_points) +
                       " points",
                   std::to_string(3 * num_points) + " point coordinates");
      if (j >= mesh.vertices.rows()) mesh.vertices.conservativeResize(2 * j + 1, 3);  // guard only
      vertex_lines.push_back(s.line());
      mesh.vertices(j, 0) = s.StreamDouble("x");
      mesh.vertices(j, 1) = s.StreamDouble("y");
      mesh.vertices(j, 2) = s.StreamDouble("z");
    }
    mesh.vertices.conservativeResize(num_points, 3);
  }

  int PointIndex(long long c) {
    const long long v = s.StreamInteger("a point index");
    if (v < 0 || v >= num_points)
      s.FailHere("cell " + std::to_string(c) + " refers to point " + std::to_string(v) +
                     ", which is out of range",
                 "a point index in [0, " + std::to_string(num_points) + ")");
    return static_cast<int>(v);
  }

  void Cells() {
    if (num_points < 0) s.FailHere("CELLS before POINTS", "POINTS first");
    if (num_cells >= 0) s.FailHere("second CELLS section", "one CELLS section");
    cells_line = s.line();
    const long long a = Count("the first CELLS count");
    const long long b = Count("the second CELLS count");
    s.ExpectEol("'CELLS <n> <size>' or (VTK 5.1) 'CELLS <#offsets> <#connectivity>'");
    const Scanner::Pos here = s.Tell();
    const std::string_view w = s.StreamWord();
    if (IEquals(w, "OFFSETS")) {
      // VTK 5.1: OFFSETS <type> (a values) then CONNECTIVITY <type> (b values).
      RequireWord("the OFFSETS data type");
      s.ExpectEol("'OFFSETS <type>'");
      num_cells = a > 0 ? a - 1 : 0;
      offsets.reserve(static_cast<std::size_t>(detail::SafeReserve(a, s.size())));
      cell_lines.reserve(offsets.capacity());
      for (long long i = 0; i < a; ++i) {
        if (!s.SkipWs())
          s.FailHere(
              "file ends after " + std::to_string(i) + " of " + std::to_string(a) + " offsets",
              std::to_string(a) + " offsets");
        cell_lines.push_back(s.line());
        const long long o = s.StreamInteger("an offset");
        if ((i == 0 && o != 0) || (i > 0 && (o < offsets.back() || o > b)))
          s.FailHere("offset " + std::to_string(o), i == 0 ? std::string("0 as the first offset")
                                                           : "non-decreasing offsets in [" +
                                                                 std::to_string(offsets.back()) +
                                                                 ", " + std::to_string(b) + "]");
        offsets.push_back(o);
      }
      if (a > 0 && offsets.back() != b)
        s.FailHere("last offset " + std::to_string(offsets.back()),
                   std::to_string(b) + " (the connectivity size)");
      if (a == 0) offsets.push_back(0);
      cell_lines.resize(static_cast<std::size_t>(num_cells));
      const std::string_view c = s.StreamWord();
      if (!IEquals(c, "CONNECTIVITY"))
        s.FailHere("found " + (c.empty() ? std::string("end of file") : detail::Quote(c)),
                   "CONNECTIVITY <type>");
      RequireWord("the CONNECTIVITY data type");
      s.ExpectEol("'CONNECTIVITY <type>'");
      conn.reserve(static_cast<std::size_t>(detail::SafeReserve(b, s.size())));
      long long cell = 0;
      for (long long i = 0; i < b; ++i) {
        while (cell < num_cells && offsets[cell + 1] <= i) ++cell;
        if (!s.SkipWs())
          s.FailHere("file ends after " + std::to_string(i) + " of " + std::to_string(b) +
                         " connectivity entries",
                     std::to_string(b) + " connectivity entries");
        if (offsets[cell] == i) cell_lines[static_cast<std::size_t>(cell)] = s.line();
        conn.push_back(PointIndex(cell));
      }
      return;
    }
    s.Seek(here);
    num_cells = a;
    offsets.reserve(static_cast<std::size_t>(detail::SafeReserve(a, s.size())) + 1);
    cell_lines.reserve(static_cast<std::size_t>(detail::SafeReserve(a, s.size())));
    conn.reserve(static_cast<std::size_t>(detail::SafeReserve(b, s.size())));
    offsets.push_back(0);
    long long used = 0;
    for (long long c = 0; c < a; ++c) {
      if (!s.SkipWs())
        s.FailHere("file ends after " + std::to_string(c) + " of " + std::to_string(a) +
                       " cells (CELLS on line " + std::to_string(cells_line) + ")",
                   std::to_string(a) + " cells");
      cell_lines.push_back(s.line());
      const long long k = s.StreamInteger("the number of points of the cell");
      if (k < 0 || k > b - used - 1)
        s.FailHere("cell " + std::to_string(c) + " with " + std::to_string(k) + " points",
                   "cells using " + std::to_string(b) + " numbers in all (CELLS line " +
                       std::to_string(cells_line) + ")");
      for (long long i = 0; i < k; ++i) conn.push_back(PointIndex(c));
      used += 1 + k;
      offsets.push_back(static_cast<long long>(conn.size()));
    }
    if (used != b)
      s.FailHere("cells use " + std::to_string(used) + " numbers",
                 std::to_string(b) + " as declared on line " + std::to_string(cells_line));
  }

  void CellTypes() {
    if (num_cells < 0) s.FailHere("CELL_TYPES before CELLS", "CELLS first");
    const long long n = Count("the number of cell types");
    s.ExpectEol("'CELL_TYPES <n>'");
    if (n != num_cells)
      s.FailHere("CELL_TYPES count " + std::to_string(n),
                 std::to_string(num_cells) + " (the number of cells)");
    cell_types.reserve(static_cast<std::size_t>(n));
    for (long long c = 0; c < n; ++c) {
      if (!s.SkipWs())
        s.FailHere(
            "file ends after " + std::to_string(c) + " of " + std::to_string(n) + " cell types",
            std::to_string(n) + " cell types");
      const long long t = s.StreamInteger("a cell type");
      if (t == 10 || t == 13) {
        const long long k = offsets[c + 1] - offsets[c];
        const long long want = t == 10 ? 4 : 6;
        if (k != want)
          detail::Fail(detail::At(s.path(), cell_lines[c]),
                       "cell " + std::to_string(c) + " (" + VtkCellName(t) + ") has " +
                           std::to_string(k) + " points",
                       std::to_string(want) + " points for a " + VtkCellName(t));
      } else if (!IsSkippedCellType(t)) {
        const char* name = VtkCellName(t);
        s.FailHere(
            (name ? "unsupported" : "unknown") + std::string(" cell type ") + std::to_string(t) +
                (name ? std::string(" (") + name + ")" : std::string()),
            "10 (tetra) or 13 (wedge), or a lower-dimensional cell type to skip (1, 3, 5, 9, ...)");
      }
      cell_types.push_back(static_cast<unsigned char>(t));
    }
    have_types = true;
  }

  /// SCALARS name type [ncomp] [LOOKUP_TABLE name] values...
  void Scalars() {
    RequireData("SCALARS");
    const int line = s.line();
    const std::string name(RequireWord("the array name"));
    const std::string type(RequireWord("the data type"));
    long long ncomp = 1;
    if (!s.AtEol()) ncomp = s.Integer("the number of components");
    s.ExpectEol("'SCALARS <name> <type> [<components>]'");
    if (ncomp < 1 || ncomp > 4)
      s.FailHere("number of components " + std::to_string(ncomp), "1 to 4");
    const Scanner::Pos here = s.Tell();
    const std::string_view w = s.StreamWord();
    if (IEquals(w, "LOOKUP_TABLE")) {
      RequireWord("the lookup table name");
      s.ExpectEol("'LOOKUP_TABLE <name>'");
    } else {
      s.Seek(here);
    }
    std::vector<double>* keep = nullptr;
    if (mode == 2 && ncomp == 1) {
      cell_arrays.push_back({name, line, IsIntegerType(type), {}});
      keep = &cell_arrays.back().values;
    }
    Values(mode_count * ncomp, "a data value", keep);
  }

  /// FIELD name n, then n arrays 'name ncomp ntuples type' + values.
  void Field() {
    s.Word();  // field name
    const long long narr = Count("the number of arrays");
    s.ExpectEol("'FIELD <name> <#arrays>'");
    for (long long a = 0; a < narr; ++a) {
      if (!s.SkipWs())
        s.FailHere("file ends after " + std::to_string(a) + " of " + std::to_string(narr) +
                       " field arrays",
                   std::to_string(narr) + " arrays");
      const int line = s.line();
      const std::string name(s.Word());
      if (IEquals(name, "NULL_ARRAY")) {
        s.NextLine();
        continue;
      }
      if (IEquals(name, "METADATA")) {  // belongs to the previous array
        SkipMetadata();
        --a;
        continue;
      }
      const long long ncomp = Count("the number of components");
      const long long ntup = Count("the number of tuples");
      const std::string type(RequireWord("the data type"));
      s.ExpectEol("'<name> <components> <tuples> <type>'");
      std::vector<double>* keep = nullptr;
      if (mode == 2 && ncomp == 1) {
        if (ntup != mode_count)
          s.FailHere("field array with " + std::to_string(ntup) + " tuples",
                     std::to_string(mode_count) + " (CELL_DATA count)");
        cell_arrays.push_back({name, line, IsIntegerType(type), {}});
        keep = &cell_arrays.back().values;
      }
      Values(ncomp * ntup, "a field value", keep);
    }
  }

  void Read() {
    // Header: version line, title, ASCII/BINARY, DATASET.
    if (s.Eof()) s.FailHere("file is empty", "'# vtk DataFile Version x.y'");
    const std::string_view first = s.RestOfLine();
    if (first.substr(0, 5) != "# vtk" && first.substr(0, 5) != "# VTK")
      s.FailHere("found " + detail::Quote(first) + " (not a legacy VTK file?)",
                 "'# vtk DataFile Version x.y'");
    if (!s.NextLine()) s.FailHere("file ends after the version line", "a title line");
    if (!s.NextLine()) s.FailHere("file ends after the title line", "ASCII");
    if (!s.SkipBlankLines()) s.FailHere("file ends after the title line", "ASCII");
    const std::string_view fmt = s.Word();
    if (IEquals(fmt, "BINARY"))
      s.FailHere("binary legacy VTK file",
                 "an ASCII legacy VTK file (write it with ASCII encoding)");
    if (!IEquals(fmt, "ASCII")) s.FailHere("found " + detail::Quote(fmt), "ASCII");
    s.ExpectEol("ASCII");
    s.NextLine();
    if (!s.SkipBlankLines()) s.FailHere("file ends before DATASET", "DATASET UNSTRUCTURED_GRID");
    if (!IEquals(s.Word(), "DATASET"))
      s.FailHere("found " + detail::Quote(s.RestOfLine()), "DATASET UNSTRUCTURED_GRID");
    const std::string_view ds = s.Word();
    if (!IEquals(ds, "UNSTRUCTURED_GRID"))
      s.FailHere("dataset " + detail::Quote(ds),
                 "UNSTRUCTURED_GRID (other legacy datasets are not meshes of tets/prisms)");
    s.ExpectEol("DATASET UNSTRUCTURED_GRID");
    s.NextLine();

    for (;;) {
      const std::string_view kw = s.StreamWord();
      if (kw.empty()) break;
      const std::string key(kw);
      if (IEquals(key, "POINTS")) {
        if (num_points >= 0) s.FailHere("second POINTS section", "one POINTS section");
        Points();
      } else if (IEquals(key, "CELLS")) {
        Cells();
      } else if (IEquals(key, "CELL_TYPES")) {
        CellTypes();
      } else if (IEquals(key, "CELL_DATA")) {
        mode = 2;
        mode_count = Count("the number of cells");
        s.ExpectEol("'CELL_DATA <n>'");
        if (num_cells >= 0 && mode_count != num_cells)
          s.FailHere("CELL_DATA count " + std::to_string(mode_count),
                     std::to_string(num_cells) + " (the number of cells)");
      } else if (IEquals(key, "POINT_DATA")) {
        mode = 1;
        mode_count = Count("the number of points");
        s.ExpectEol("'POINT_DATA <n>'");
        if (num_points >= 0 && mode_count != num_points)
          s.FailHere("POINT_DATA count " + std::to_string(mode_count),
                     std::to_string(num_points) + " (the number of points)");
      } else if (IEquals(key, "SCALARS")) {
        Scalars();
      } else if (IEquals(key, "FIELD")) {
        const int saved = mode;
        if (mode == 0) mode = 1;  // dataset-level field data: read and ignore
        Field();
        mode = saved;
      } else if (IEquals(key, "METADATA")) {
        SkipMetadata();
      } else if (IEquals(key, "VECTORS") || IEquals(key, "NORMALS") || IEquals(key, "TENSORS") ||
                 IEquals(key, "TENSORS6")) {
        RequireData(key.c_str());
        RequireWord("the array name");
        RequireWord("the data type");
        s.ExpectEol("'<KEYWORD> <name> <type>'");
        const long long per = IEquals(key, "TENSORS") ? 9 : IEquals(key, "TENSORS6") ? 6 : 3;
        Values(mode_count * per, "a data value", nullptr);
      } else if (IEquals(key, "TEXTURE_COORDINATES") || IEquals(key, "COLOR_SCALARS")) {
        RequireData(key.c_str());
        RequireWord("the array name");
        const long long dim = Count("the number of components");
        if (IEquals(key, "TEXTURE_COORDINATES")) RequireWord("the data type");
        s.ExpectEol("'<KEYWORD> <name> <components> [<type>]'");
        Values(mode_count * dim, "a data value", nullptr);
      } else if (IEquals(key, "LOOKUP_TABLE")) {
        RequireData("LOOKUP_TABLE");
        RequireWord("the table name");
        const long long n = Count("the table size");
        s.ExpectEol("'LOOKUP_TABLE <name> <size>'");
        Values(4 * n, "a table value", nullptr);
      } else {
        s.FailHere("unknown keyword " + detail::Quote(key),
                   "POINTS, CELLS, CELL_TYPES, CELL_DATA, POINT_DATA, SCALARS, FIELD or another "
                   "legacy VTK keyword");
      }
    }
    if (num_points < 0) s.FailHere("no POINTS section", "POINTS <n> <type>");
    if (num_cells < 0) s.FailHere("no CELLS section", "CELLS <n> <size>");
    if (!have_types) s.FailHere("no CELL_TYPES section", "CELL_TYPES <n>");
  }

  /// Region values per cell from the chosen array (nullptr: all 0).
  const CellArray* ChooseRegionArray(const std::string& tag_array) const {
    if (!tag_array.empty()) {
      for (const auto& a : cell_arrays)
        if (a.name == tag_array) return &a;
      std::string names;
      for (const auto& a : cell_arrays) names += (names.empty() ? "" : ", ") + a.name;
      detail::Fail(s.path(),
                   "no single-component cell data array named " + detail::Quote(tag_array),
                   names.empty() ? std::string("a CELL_DATA array of that name (the file has none)")
                                 : "one of: " + names);
    }
    for (const auto& a : cell_arrays)
      if (a.integer_type) return &a;
    for (const auto& a : cell_arrays) {
      if (!NameSuggestsTag(a.name)) continue;
      bool integral = true;
      for (double v : a.values) integral = integral && v == std::round(v) && std::abs(v) <= INT_MAX;
      if (integral) return &a;
    }
    return nullptr;
  }
};

}  // namespace

Mesh ReadVtk(const std::string& path, const std::string& tag_array, MeshReport* report) {
  Reader r(path);
  r.Read();
  const CellArray* tags = r.ChooseRegionArray(tag_array);
  if (tags && static_cast<long long>(tags->values.size()) != r.num_cells)
    detail::Fail(detail::At(path, tags->line),
                 "array " + detail::Quote(tags->name) + " has " +
                     std::to_string(tags->values.size()) + " values",
                 std::to_string(r.num_cells) + " (one per cell)");
  std::vector<int> element_lines;
  r.mesh.elements.reserve(static_cast<std::size_t>(r.num_cells));
  element_lines.reserve(static_cast<std::size_t>(r.num_cells));
  for (long long c = 0; c < r.num_cells; ++c) {
    const int t = r.cell_types[c];
    if (t != 10 && t != 13) continue;
    Element e;
    e.type = t == 10 ? ElementType::Tet : ElementType::Prism;
    for (int a = 0; a < e.k(); ++a) e.v[a] = r.conn[static_cast<std::size_t>(r.offsets[c] + a)];
    if (t == 13) detail::VtkWedgeSwap(e.v);
    if (tags) {
      const double v = tags->values[static_cast<std::size_t>(c)];
      if (!(v == std::round(v) && std::abs(v) <= INT_MAX))
        detail::Fail(detail::At(path, tags->line),
                     "array " + detail::Quote(tags->name) + " holds the non-integer region " +
                         std::to_string(v) + " for cell " + std::to_string(c),
                     "integer region tags");
      e.region = static_cast<int>(v);
    }
    r.mesh.elements.push_back(e);
    element_lines.push_back(r.cell_lines[c]);
  }
  MeshReport rep = ValidateAndOrient(r.mesh, path, element_lines, r.vertex_lines);
  detail::Deliver(rep, report);
  return std::move(r.mesh);
}

void WriteVtk(const std::string& path, const Mesh& mesh) {
  OutputFile out_file(path);
  std::ostream& out = detail::ForWrite(out_file);
  const int nv = mesh.num_vertices(), ne = mesh.num_elements();
  long long size = 0;
  for (const auto& e : mesh.elements) size += 1 + e.k();
  out << "# vtk DataFile Version 3.0\nSoftKin mesh\nASCII\nDATASET UNSTRUCTURED_GRID\n";
  out << "POINTS " << nv << " double\n";
  for (int j = 0; j < nv; ++j) detail::WriteRow(out, mesh.vertices, j) << '\n';
  out << "CELLS " << ne << ' ' << size << '\n';
  for (const auto& e : mesh.elements) {
    std::array<int, 6> v = e.v;
    if (e.type == ElementType::Prism) detail::VtkWedgeSwap(v);
    out << e.k();
    for (int a = 0; a < e.k(); ++a) out << ' ' << v[a];
    out << '\n';
  }
  out << "CELL_TYPES " << ne << '\n';
  for (const auto& e : mesh.elements) out << (e.type == ElementType::Tet ? 10 : 13) << '\n';
  out << "CELL_DATA " << ne << "\nSCALARS region int 1\nLOOKUP_TABLE default\n";
  for (const auto& e : mesh.elements) out << e.region << '\n';
  out_file.Commit();
}

}  // namespace softkin
