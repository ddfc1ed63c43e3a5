/// \file mesh_io_vtu.cpp
/// VTK XML UnstructuredGrid (`.vtu`) reader: a small tag scanner (no general XML parser) that
/// collects the DataArrays of the one Piece and decodes those it needs from ascii text, inline
/// base64 (`binary`) or raw appended data. Compressed files are refused.
#include <algorithm>
#include <charconv>
#include <cctype>
#include <cmath>
#include <map>

#include "softkin/solver/mesh/io/mesh_io.hpp"
#include "softkin/solver/mesh/io/mesh_io_binary.hpp"
#include "softkin/solver/mesh/io/mesh_io_detail.hpp"
#include "softkin/solver/mesh/io/mesh_io_vtk_common.hpp"

namespace softkin {

namespace {

using detail::Fail;
using detail::NumType;

struct Tag {
  std::string name;  ///< e.g. "DataArray", "/DataArray"
  std::map<std::string, std::string> attr;
  bool self_closing = false;
  const char* end = nullptr;  ///< just after '>'
  int line = 0;
};

struct Array {
  std::string name, section, format;
  NumType type = NumType::None;
  std::string type_name;
  long long ncomp = 1, offset = 0;
  const char* text = nullptr;  ///< content (ascii / binary formats)
  const char* text_end = nullptr;
  int line = 0;       ///< line of the <DataArray> tag
  int text_line = 0;  ///< line where its content starts
};

/// Decoded values of an array, with the line of each value (ascii) or of the array.
struct Values {
  std::vector<double> v;
  std::vector<int> line;
};

class VtuReader {
 public:
  explicit VtuReader(const std::string& path) : s_(path), path_(path), scan_(s_.Begin()) {}

  void Scan() {
    Tag t;
    if (!NextTag(&t) || t.name != "VTKFile")
      Fail(path_, "no <VTKFile> element (not a VTK XML file?)", "a .vtu file starting <VTKFile");
    Header(t);
    while (NextTag(&t)) {
      if (t.name == "Piece") {
        if (pieces_++) Fail(At(t.line), "a second <Piece>", "one Piece (merge the pieces first)");
        num_points_ = CountAttr(t, "NumberOfPoints");
        num_cells_ = CountAttr(t, "NumberOfCells");
      } else if (t.name == "Points" || t.name == "Cells" || t.name == "PointData" ||
                 t.name == "CellData" || t.name == "FieldData") {
        if (!t.self_closing) section_ = t.name;
      } else if (!t.name.empty() && t.name[0] == '/' && t.name.substr(1) == section_) {
        section_.clear();
      } else if (t.name == "DataArray") {
        AddArray(t);
      } else if (t.name == "AppendedData") {
        Appended(t);
        break;
      }
    }
    if (pieces_ == 0) Fail(path_, "no <Piece> element", "an UnstructuredGrid with one Piece");
  }

  Mesh Build(const std::string& tag_array, MeshOrigin* origin, int* higher_order) {
    Mesh mesh;
    const Array& pts = Find("Points", "", "the <Points> DataArray");
    if (pts.ncomp != 3)
      Fail(At(pts.line), "Points with " + std::to_string(pts.ncomp) + " components",
           "3 components (x y z)");
    const Values X = Decode(pts, 3 * num_points_);
    mesh.vertices.resize(num_points_, 3);
    for (long long j = 0; j < num_points_; ++j) {
      for (int d = 0; d < 3; ++d) mesh.vertices(j, d) = X.v[static_cast<std::size_t>(3 * j + d)];
      origin->vertex_at.push_back(X.line[static_cast<std::size_t>(3 * j)]);
    }
    const Array& ta = Find("Cells", "types", "a <Cells> DataArray named \"types\"");
    const Array& oa = Find("Cells", "offsets", "a <Cells> DataArray named \"offsets\"");
    const Array& ca = Find("Cells", "connectivity", "a <Cells> DataArray named \"connectivity\"");
    const Values types = Decode(ta, num_cells_), ends = Decode(oa, num_cells_);
    std::vector<long long> offsets(1, 0);
    for (long long c = 0; c < num_cells_; ++c) {
      const double o = ends.v[static_cast<std::size_t>(c)];
      if (!(o >= static_cast<double>(offsets.back())) || o != std::floor(o))
        Fail(At(ends.line[static_cast<std::size_t>(c)]),
             "offset " + detail::Quote(std::to_string(o)) + " of cell " + std::to_string(c),
             "non-decreasing integer offsets (the end of each cell's connectivity)");
      offsets.push_back(static_cast<long long>(o));
    }
    const Values conn = Decode(ca, offsets.back());
    std::vector<int> cell_line(static_cast<std::size_t>(num_cells_));
    for (long long c = 0; c < num_cells_; ++c) {
      const std::size_t c0 = static_cast<std::size_t>(c);
      const long long want = detail::KeptPoints(static_cast<long long>(types.v[c0]));
      cell_line[c0] =
          offsets[c0] < offsets.back() ? conn.line[static_cast<std::size_t>(offsets[c0])] : ca.line;
      if (want > 0 && offsets[c0 + 1] - offsets[c0] != want)
        Fail(At(cell_line[c0]),
             "cell " + std::to_string(c) + " (VTK type " +
                 std::to_string(static_cast<long long>(types.v[c0])) + ") has " +
                 std::to_string(offsets[c0 + 1] - offsets[c0]) + " points",
             std::to_string(want) + " points for its type");
      if (want == 0) CheckSkipped(static_cast<long long>(types.v[c0]), types.line[c0]);
    }
    for (double v : conn.v)
      if (v < 0 || v >= static_cast<double>(num_points_) || v != std::floor(v))
        Fail(At(ca.line), "connectivity holds point index " + std::to_string(v),
             "point indices in [0, " + std::to_string(num_points_) + ")");
    const std::vector<detail::CellArray> arrays = CellArrays();
    const detail::CellArray* tags = detail::ChooseRegionArray(path_, arrays, tag_array);
    *higher_order = detail::AddVtkElements(path_, types.v, offsets, conn.v, tags, cell_line, &mesh,
                                           &origin->element_at);
    return mesh;
  }

 private:
  std::string At(int line) const { return detail::At(path_, line); }

  void Header(const Tag& t) {
    if (Attr(t, "type") != "UnstructuredGrid")
      Fail(At(t.line), "VTKFile type " + detail::Quote(Attr(t, "type")),
           "type=\"UnstructuredGrid\" (other XML datasets are not tet/prism meshes)");
    if (!Attr(t, "compressor").empty())
      Fail(At(t.line), "compressed data (compressor " + detail::Quote(Attr(t, "compressor")) + ")",
           "an uncompressed .vtu: save it without compression (ParaView: Save Data, Compressor "
           "None; meshio: write(..., compression=None)), or as ascii");
    const std::string order = Attr(t, "byte_order");
    if (!order.empty() && order != "LittleEndian" && order != "BigEndian")
      Fail(At(t.line), "byte_order " + detail::Quote(order), "LittleEndian or BigEndian");
    little_ = order != "BigEndian";
    const std::string header = Attr(t, "header_type");
    if (!header.empty() && header != "UInt32" && header != "UInt64")
      Fail(At(t.line), "header_type " + detail::Quote(header), "UInt32 or UInt64");
    header_ = header == "UInt64" ? NumType::U64 : NumType::U32;
  }

  void AddArray(const Tag& t) {
    Array a;
    a.name = Attr(t, "Name");
    a.section = section_;
    a.type_name = Attr(t, "type");
    a.type = detail::NumTypeOf(a.type_name);
    a.format = Attr(t, "format").empty() ? "ascii" : Attr(t, "format");
    a.line = t.line;
    if (a.type == NumType::None)
      Fail(At(t.line), "DataArray type " + detail::Quote(a.type_name),
           "Int8 ... Int64, UInt8 ... UInt64, Float32 or Float64");
    if (a.format != "ascii" && a.format != "binary" && a.format != "appended")
      Fail(At(t.line), "DataArray format " + detail::Quote(a.format), "ascii, binary or appended");
    if (!Attr(t, "NumberOfComponents").empty()) a.ncomp = CountAttr(t, "NumberOfComponents");
    if (a.format == "appended") a.offset = CountAttr(t, "offset");
    a.text = t.end;
    a.text_end = t.self_closing ? t.end : FindChar(t.end, '<');
    a.text_line = LineOfPtr(a.text);
    arrays_.push_back(a);
  }

  void Appended(const Tag& t) {
    const std::string enc = Attr(t, "encoding");
    if (enc != "raw")
      Fail(At(t.line), "appended data encoding " + detail::Quote(enc),
           "encoding=\"raw\" (or inline DataArrays: format ascii or binary)");
    const char* u = FindChar(t.end, '_');
    if (u >= s_.End()) Fail(At(t.line), "no '_' opening the appended data", "'_' then raw data");
    appended_ = u + 1;
  }

  const Array& Find(const std::string& section, const std::string& name, const char* expected) {
    for (const auto& a : arrays_)
      if (a.section == section && (name.empty() || a.name == name)) return a;
    Fail(path_, std::string("no ") + expected, expected);
  }

  void CheckSkipped(long long t, int line) const {
    static const long long kSkipped[] = {1,  2,  3,  4,  5,  6,  7,  8,  9,  21, 22, 23,
                                         28, 30, 34, 35, 36, 68, 69, 70, 75, 76, 77};
    for (long long k : kSkipped)
      if (k == t) return;
    Fail(At(line), "unsupported cell type " + std::to_string(t),
         "10 (tetra), 13 (wedge), 24 (quadratic tetra) or 26 (quadratic wedge), or a "
         "lower-dimensional cell type to skip (1, 3, 5, 9, ...)");
  }

  std::vector<detail::CellArray> CellArrays() {
    std::vector<detail::CellArray> out;
    for (const auto& a : arrays_) {
      if (a.section != "CellData" || a.ncomp != 1) continue;
      out.push_back({a.name, a.line, detail::NumIsInteger(a.type), Decode(a, num_cells_).v});
    }
    return out;
  }

  /// The values of array a (n of them; n < 0: as many as there are).
  Values Decode(const Array& a, long long n) {
    Values out;
    if (a.format == "ascii") {
      Ascii(a, &out);
    } else {
      std::string decoded;
      if (a.format == "binary") {
        if (!detail::DecodeBase64(
                std::string_view(a.text, static_cast<std::size_t>(a.text_end - a.text)), &decoded))
          Fail(At(a.line), "DataArray " + detail::Quote(a.name) + " is not valid base64",
               "base64 text (format=\"binary\")");
        const std::string where =
            At(a.line) + " (decoded base64 of DataArray " + detail::Quote(a.name) + ")";
        detail::ByteReader r(where, decoded.data(), decoded.data(), decoded.data() + decoded.size(),
                             little_);
        Binary(a, &r, &out);
      } else {
        if (!appended_)
          Fail(At(a.line), "DataArray " + detail::Quote(a.name) + " is appended",
               "an <AppendedData> element after the Piece");
        if (a.offset > s_.End() - appended_)
          Fail(At(a.line), "offset " + std::to_string(a.offset) + " is past the end of the file",
               "an offset inside <AppendedData>");
        detail::ByteReader r(path_, s_.Begin(), appended_ + a.offset, s_.End(), little_);
        Binary(a, &r, &out);
      }
    }
    if (n >= 0 && static_cast<long long>(out.v.size()) != n)
      Fail(
          At(a.line),
          "DataArray " + detail::Quote(a.name) + " has " + std::to_string(out.v.size()) + " values",
          std::to_string(n) + " (from NumberOfPoints/NumberOfCells and the components)");
    return out;
  }

  void Ascii(const Array& a, Values* out) {
    const char* p = a.text;
    int line = a.text_line;
    while (p < a.text_end) {
      if (*p == '\n') ++line;
      if (std::isspace(static_cast<unsigned char>(*p))) {
        ++p;
        continue;
      }
      double v = 0;
      const auto r = std::from_chars(p, a.text_end, v);
      if (r.ec != std::errc() ||
          (r.ptr < a.text_end && !std::isspace(static_cast<unsigned char>(*r.ptr))))
        Fail(At(line), "non-numeric value in DataArray " + detail::Quote(a.name),
             "numbers separated by blanks");
      out->v.push_back(v);
      out->line.push_back(line);
      p = r.ptr;
    }
  }

  /// A header (the byte count) then the data, in the file's byte order.
  void Binary(const Array& a, detail::ByteReader* rp, Values* out) {
    detail::ByteReader& r = *rp;
    const long long bytes = r.Integer(header_, "the DataArray's byte count");
    const int size = detail::NumSize(a.type);
    if (bytes < 0 || bytes % size != 0)
      r.FailHere("byte count " + std::to_string(bytes) + " of DataArray " + detail::Quote(a.name),
                 "a multiple of " + std::to_string(size));
    for (long long i = 0; i < bytes / size; ++i) {
      out->v.push_back(r.Number(a.type, "a DataArray value"));
      out->line.push_back(a.line);
    }
  }

  int LineOfPtr(const char* q) {
    for (; scan_ < q; ++scan_)
      if (*scan_ == '\n') ++scan_line_;
    return scan_line_;
  }

  const char* FindChar(const char* p, char c) const {
    while (p < s_.End() && *p != c) ++p;
    return p;
  }

  /// Next tag from the cursor (skipping <?...?>, <!--...--> and text); false at the end.
  bool NextTag(Tag* t) {
    for (;;) {
      const char* p = FindChar(cur_ ? cur_ : s_.Ptr(), '<');
      if (p >= s_.End()) return false;
      cur_ = p + 1;
      if (cur_ < s_.End() && (*cur_ == '?' || *cur_ == '!')) {
        const char* close = FindChar(cur_, '>');
        cur_ = close < s_.End() ? close + 1 : close;
        continue;
      }
      return ParseTag(p, t);
    }
  }

  bool ParseTag(const char* lt, Tag* t) {
    *t = Tag();
    t->line = LineOfPtr(lt);
    const char* p = lt + 1;
    const char* e = s_.End();
    while (p < e && !std::isspace(static_cast<unsigned char>(*p)) && *p != '>' && *p != '/') ++p;
    if (p < e && *p == '/' && p == lt + 1) ++p;  // closing tag
    while (p < e && !std::isspace(static_cast<unsigned char>(*p)) && *p != '>' && *p != '/') ++p;
    t->name.assign(lt + 1, p);
    for (;;) {
      while (p < e && std::isspace(static_cast<unsigned char>(*p))) ++p;
      if (p >= e) Fail(At(t->line), "file ends inside <" + t->name + ">", "'>'");
      if (*p == '>' || (*p == '/' && p + 1 < e && p[1] == '>')) break;
      const char* k = p;
      while (p < e && *p != '=' && *p != '>' && !std::isspace(static_cast<unsigned char>(*p))) ++p;
      const std::string key(k, p);
      if (p >= e || *p != '=' || p + 1 >= e || (p[1] != '"' && p[1] != '\''))
        Fail(At(LineOfPtr(k)), "attribute " + detail::Quote(key) + " of <" + t->name + ">",
             "key=\"value\"");
      const char q = p[1];
      const char* v = p + 2;
      p = v;
      while (p < e && *p != q) ++p;
      if (p >= e) Fail(At(t->line), "file ends inside an attribute of <" + t->name + ">", "'\"'");
      t->attr[key].assign(v, p);
      ++p;
    }
    t->self_closing = *p == '/';
    cur_ = p + (t->self_closing ? 2 : 1);
    t->end = cur_;
    return true;
  }

  static std::string Attr(const Tag& t, const char* key) {
    const auto it = t.attr.find(key);
    return it == t.attr.end() ? std::string() : it->second;
  }

  long long CountAttr(const Tag& t, const char* key) const {
    const std::string v = Attr(t, key);
    long long n = -1;
    const auto r = std::from_chars(v.data(), v.data() + v.size(), n);
    if (v.empty() || r.ec != std::errc() || r.ptr != v.data() + v.size() || n < 0 || n > INT_MAX)
      Fail(At(t.line), std::string(key) + "=" + detail::Quote(v) + " in <" + t.name + ">",
           std::string(key) + " as a count in [0, 2^31)");
    return n;
  }

  detail::Scanner s_;
  std::string path_;
  const char* cur_ = nullptr;
  const char* scan_ = nullptr;
  int scan_line_ = 1;
  bool little_ = true;
  NumType header_ = NumType::U32;
  int pieces_ = 0;
  long long num_points_ = 0, num_cells_ = 0;
  std::string section_;
  std::vector<Array> arrays_;
  const char* appended_ = nullptr;
};

}  // namespace

Mesh ReadVtu(const std::string& path, const std::string& tag_array, MeshReport* report) {
  VtuReader r(path);
  r.Scan();
  MeshOrigin origin;
  int higher_order = 0;
  Mesh mesh = r.Build(tag_array, &origin, &higher_order);
  MeshReport rep = ValidateAndOrient(mesh, path, origin);
  detail::NoteCornersOnly(path, higher_order, &rep);
  detail::Deliver(rep, report);
  return mesh;
}

}  // namespace softkin
