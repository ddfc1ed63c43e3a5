/// \file mesh_io_vtk.cpp
/// Legacy ASCII VTK UNSTRUCTURED_GRID: reader (classic CELLS and VTK 5.1 OFFSETS/CONNECTIVITY,
/// cell types 10 tetra and 13 wedge, lower-dimensional cells skipped) and writer. VTK wedges have
/// the opposite bottom-triangle orientation from SoftKin/Gmsh prisms and are converted both ways.
#include <cmath>

#include "softkin/solver/mesh/io/mesh_io.hpp"
#include "softkin/solver/mesh/io/mesh_io_binary.hpp"
#include "softkin/solver/mesh/io/mesh_io_detail.hpp"
#include "softkin/solver/mesh/io/mesh_io_vtk_common.hpp"

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

using detail::CellArray;
using detail::KeptPoints;

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
  bool binary = false;  ///< BINARY file: vertex_lines and cell_lines hold byte offsets

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

  /// "<file>:<line>" (ASCII) or "<file>: byte offset <n>" (binary) for a recorded location.
  std::string Where(long long at) const {
    return binary ? s.path() + ": byte offset " + std::to_string(at)
                  : detail::At(s.path(), static_cast<int>(at));
  }

  /// Binary data (big-endian) of n values of VTK type `type`, starting on the line after the
  /// keyword line; at[i] receives each value's byte offset when given.
  std::vector<double> BinaryValues(long long n, std::string_view type, const char* what,
                                   std::vector<int>* at = nullptr) {
    const detail::NumType t = detail::NumTypeOf(type);
    if (t == detail::NumType::None)
      s.FailHere("data type " + detail::Quote(type),
                 "a VTK data type (float, double, int, unsigned_char, vtktypeint64, ...)");
    s.NextLine();
    detail::ByteReader r(s.path(), s.Begin(), s.Ptr(), s.End(), /*little_endian=*/false);
    std::vector<double> v;
    v.reserve(static_cast<std::size_t>(detail::SafeReserve(n, s.size())));
    for (long long i = 0; i < n; ++i) {
      if (at) at->push_back(static_cast<int>(std::min<long long>(r.Offset(), INT_MAX)));
      v.push_back(r.Number(t, what));
    }
    s.JumpTo(r.Ptr());
    return v;
  }

  /// Reads n numbers of a data array of VTK type `type`, keeping them in *keep if given.
  void Values(long long n, std::string_view type, const char* what, std::vector<double>* keep) {
    if (binary) {
      std::vector<double> v = BinaryValues(n, type, what);
      if (keep) *keep = std::move(v);
      return;
    }
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
    const std::string type(RequireWord("the point data type (float or double)"));
    s.ExpectEol("'POINTS <n> <type>'");
    if (binary) {
      std::vector<int> at;
      const std::vector<double> v = BinaryValues(3 * num_points, type, "a point coordinate", &at);
      mesh.vertices.resize(num_points, 3);
      for (long long j = 0; j < num_points; ++j) {
        for (int d = 0; d < 3; ++d) mesh.vertices(j, d) = v[static_cast<std::size_t>(3 * j + d)];
        vertex_lines.push_back(at[static_cast<std::size_t>(3 * j)]);
      }
      return;
    }
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
    if (binary) {
      if (!IEquals(w, "OFFSETS")) s.Seek(here);
      BinaryCells(a, b, IEquals(w, "OFFSETS"));
      return;
    }
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

  /// BINARY cells: classic (a cells in b int32 numbers 'k i1 .. ik') or, when `v51`, OFFSETS
  /// (a values) and CONNECTIVITY (b values) of the types their lines name.
  void BinaryCells(long long a, long long b, bool v51) {
    std::vector<int> at;
    if (v51) {
      const std::string otype(RequireWord("the OFFSETS data type"));
      s.ExpectEol("'OFFSETS <type>'");
      const std::vector<double> o = BinaryValues(a, otype, "an offset", &at);
      num_cells = a > 0 ? a - 1 : 0;
      for (long long i = 0; i < a; ++i) {
        const double v = o[static_cast<std::size_t>(i)];
        const long long prev = offsets.empty() ? 0 : offsets.back();
        if ((i == 0 && v != 0) || v < static_cast<double>(prev) || v > static_cast<double>(b))
          detail::Fail(Where(at[static_cast<std::size_t>(i)]), "offset " + std::to_string(v),
                       "non-decreasing offsets from 0 to " + std::to_string(b));
        offsets.push_back(static_cast<long long>(v));
      }
      if (a == 0) offsets.push_back(0);
      if (offsets.back() != b)
        s.FailHere("last offset " + std::to_string(offsets.back()),
                   std::to_string(b) + " (the connectivity size)");
      const std::string_view c = s.StreamWord();
      if (!IEquals(c, "CONNECTIVITY")) s.FailHere("found " + detail::Quote(c), "CONNECTIVITY");
      const std::string ctype(RequireWord("the CONNECTIVITY data type"));
      s.ExpectEol("'CONNECTIVITY <type>'");
      at.clear();
      for (double v : BinaryValues(b, ctype, "a point index", &at))
        conn.push_back(BinaryPoint(v, at[conn.size()]));
      for (long long q = 0; q < num_cells; ++q)
        cell_lines.push_back(offsets[q] < b ? at[static_cast<std::size_t>(offsets[q])] : 0);
      return;
    }
    const std::vector<double> v = BinaryValues(b, "int", "a CELLS entry", &at);
    num_cells = a;
    offsets.push_back(0);
    std::size_t pos = 0;
    for (long long q = 0; q < a; ++q) {
      const long long k = pos < v.size() ? static_cast<long long>(v[pos]) : -1;
      if (k < 0 || static_cast<long long>(pos) + 1 + k > b)
        detail::Fail(pos < at.size() ? Where(at[pos]) : s.Here(),
                     "cell " + std::to_string(q) + " with " + std::to_string(k) + " points",
                     "cells using " + std::to_string(b) + " numbers in all (CELLS line " +
                         std::to_string(cells_line) + ")");
      cell_lines.push_back(at[pos]);
      for (long long i = 1; i <= k; ++i) conn.push_back(BinaryPoint(v[pos + i], at[pos + i]));
      pos += 1 + k;
      offsets.push_back(static_cast<long long>(conn.size()));
    }
    if (static_cast<long long>(pos) != b)
      s.FailHere("cells use " + std::to_string(pos) + " numbers",
                 std::to_string(b) + " as declared on line " + std::to_string(cells_line));
  }

  int BinaryPoint(double v, int at) const {
    if (!(v >= 0 && v < static_cast<double>(num_points)))
      detail::Fail(Where(at),
                   "point index " + std::to_string(static_cast<long long>(v)) + " is out of range",
                   "a point index in [0, " + std::to_string(num_points) + ")");
    return static_cast<int>(v);
  }

  void CellTypes() {
    if (num_cells < 0) s.FailHere("CELL_TYPES before CELLS", "CELLS first");
    const long long n = Count("the number of cell types");
    s.ExpectEol("'CELL_TYPES <n>'");
    if (n != num_cells)
      s.FailHere("CELL_TYPES count " + std::to_string(n),
                 std::to_string(num_cells) + " (the number of cells)");
    cell_types.reserve(static_cast<std::size_t>(n));
    std::vector<int> at;
    const std::vector<double> bt =
        binary ? BinaryValues(n, "int", "a cell type", &at) : std::vector<double>();
    for (long long c = 0; c < n; ++c) {
      if (!binary && !s.SkipWs())
        s.FailHere(
            "file ends after " + std::to_string(c) + " of " + std::to_string(n) + " cell types",
            std::to_string(n) + " cell types");
      const long long where = binary ? at[static_cast<std::size_t>(c)] : s.line();
      const long long t = binary ? static_cast<long long>(bt[static_cast<std::size_t>(c)])
                                 : s.StreamInteger("a cell type");
      if (KeptPoints(t) > 0) {
        const long long k = offsets[c + 1] - offsets[c];
        const long long want = KeptPoints(t);
        if (k != want)
          detail::Fail(Where(cell_lines[c]),
                       "cell " + std::to_string(c) + " (" + VtkCellName(t) + ") has " +
                           std::to_string(k) + " points",
                       std::to_string(want) + " points for a " + VtkCellName(t));
      } else if (!IsSkippedCellType(t)) {
        const char* name = VtkCellName(t);
        detail::Fail(Where(where),
                     (name ? "unsupported" : "unknown") + std::string(" cell type ") +
                         std::to_string(t) +
                         (name ? std::string(" (") + name + ")" : std::string()),
                     "10 (tetra), 13 (wedge), 24 (quadratic tetra) or 26 (quadratic wedge), or a "
                     "lower-dimensional cell type to skip (1, 3, 5, 9, ...)");
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
      cell_arrays.push_back({name, line, detail::IsIntegerType(type), {}});
      keep = &cell_arrays.back().values;
    }
    Values(mode_count * ncomp, type, "a data value", keep);
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
        cell_arrays.push_back({name, line, detail::IsIntegerType(type), {}});
        keep = &cell_arrays.back().values;
      }
      Values(ncomp * ntup, type, "a field value", keep);
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
    binary = IEquals(fmt, "BINARY");
    if (!binary && !IEquals(fmt, "ASCII"))
      s.FailHere("found " + detail::Quote(fmt), "ASCII or BINARY");
    s.ExpectEol("ASCII or BINARY");
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
        const std::string type(RequireWord("the data type"));
        s.ExpectEol("'<KEYWORD> <name> <type>'");
        const long long per = IEquals(key, "TENSORS") ? 9 : IEquals(key, "TENSORS6") ? 6 : 3;
        Values(mode_count * per, type, "a data value", nullptr);
      } else if (IEquals(key, "TEXTURE_COORDINATES") || IEquals(key, "COLOR_SCALARS")) {
        RequireData(key.c_str());
        RequireWord("the array name");
        const long long dim = Count("the number of components");
        std::string type = "unsigned_char";  // binary COLOR_SCALARS are bytes
        if (IEquals(key, "TEXTURE_COORDINATES")) type = RequireWord("the data type");
        s.ExpectEol("'<KEYWORD> <name> <components> [<type>]'");
        Values(mode_count * dim, type, "a data value", nullptr);
      } else if (IEquals(key, "LOOKUP_TABLE")) {
        RequireData("LOOKUP_TABLE");
        RequireWord("the table name");
        const long long n = Count("the table size");
        s.ExpectEol("'LOOKUP_TABLE <name> <size>'");
        Values(4 * n, "unsigned_char", "a table value", nullptr);
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
};

}  // namespace

Mesh ReadVtk(const std::string& path, const std::string& tag_array, MeshReport* report) {
  Reader r(path);
  r.Read();
  const CellArray* tags = detail::ChooseRegionArray(path, r.cell_arrays, tag_array);
  MeshOrigin origin;
  const int higher_order = detail::AddVtkElements(path, r.cell_types, r.offsets, r.conn, tags,
                                                  r.cell_lines, &r.mesh, &origin.element_at);
  origin.vertex_at.assign(r.vertex_lines.begin(), r.vertex_lines.end());
  origin.bytes = r.binary;
  MeshReport rep = ValidateAndOrient(r.mesh, path, origin);
  detail::NoteCornersOnly(path, higher_order, &rep);
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
