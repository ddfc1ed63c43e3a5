/// \file mesh_io_gmsh_binary.cpp
/// The body of a binary Gmsh 4.1 `.msh` file (file type 1): the endianness check after the
/// format line, then $Entities, $Nodes and $Elements as binary records (section headers and $End
/// lines stay text); other sections are skipped. Errors name byte offsets inside binary data.
#include <map>

#include "softkin/solver/mesh/io/mesh_io_binary.hpp"
#include "softkin/solver/mesh/io/mesh_io_gmsh_binary.hpp"
#include "softkin/solver/mesh/io/mesh_io_gmsh_types.hpp"

namespace softkin {
namespace detail {

namespace {

class BinaryGmsh {
 public:
  BinaryGmsh(Scanner& s, int data_size, GmshBody* out)
      : s_(s), size_t_(data_size == 8 ? NumType::U64 : NumType::U32), out_(*out) {}

  void Read() {
    Endianness();
    ExpectEnd("MeshFormat");
    bool have_nodes = false, have_elements = false;
    while (s_.SkipBlankLines()) {
      const std::string_view l = s_.RestOfLine();
      const int opened = s_.line();
      if (l.empty() || l[0] != '$')
        s_.FailHere("found " + Quote(l) + " between sections", "a section header such as $Nodes");
      const std::string sec(l.substr(1));
      s_.NextLine();
      ByteReader r(s_.path(), s_.Begin(), s_.Ptr(), s_.End(), little_);
      if (sec == "Entities") {
        Entities(r);
      } else if (sec == "Nodes" && !have_nodes) {
        Nodes(r);
        have_nodes = true;
      } else if (sec == "Elements" && !have_elements) {
        if (!have_nodes) Fail(At(s_.path(), opened), "$Elements before $Nodes", "$Nodes first");
        Elements(r);
        have_elements = true;
      } else if (sec == "Nodes" || sec == "Elements") {
        Fail(At(s_.path(), opened), "second $" + sec + " section", "one $" + sec + " section");
      } else {
        SkipTo("$End" + sec, opened);
        continue;
      }
      s_.JumpTo(r.Ptr());
      ExpectEnd(sec);
    }
    if (!have_nodes) s_.FailHere("no $Nodes section", "$Nodes and $Elements sections");
    if (!have_elements) s_.FailHere("no $Elements section", "an $Elements section");
  }

 private:
  /// The int 1 written after the format line tells the byte order.
  void Endianness() {
    ByteReader r(s_.path(), s_.Begin(), s_.Ptr(), s_.End(), true);
    const long long one = r.Integer(NumType::I32, "the endianness check (int 1)");
    if (one == 0x01000000) {
      little_ = false;
    } else if (one != 1) {
      Fail(r.AtByte(r.Offset() - 4), "endianness check reads " + std::to_string(one),
           "the binary int 1 after '4.1 1 <data-size>' (a binary .msh 4.1 file)");
    }
    s_.JumpTo(r.Ptr());
  }

  void ExpectEnd(const std::string& sec) {
    const std::string want = "$End" + sec;
    if (!s_.SkipBlankLines()) s_.FailHere("file ends inside $" + sec, want);
    if (s_.RestOfLine() != want)
      Fail(At(s_.path(), s_.line()) + " (byte offset " + std::to_string(s_.Offset()) + ")",
           "found " + Quote(s_.RestOfLine()),
           want + " (the counts declared in the binary $" + sec + " data are used up)");
    s_.NextLine();
  }

  void SkipTo(const std::string& want, int opened) {
    while (s_.NextLine())
      if (s_.RestOfLine() == want) {
        s_.NextLine();
        return;
      }
    s_.FailHere(
        "file ends inside $" + want.substr(4) + " (opened on line " + std::to_string(opened) + ")",
        want);
  }

  long long Count(ByteReader& r, const char* what) {
    const long long n = r.Integer(size_t_, what);
    if (n < 0 || n > INT_MAX)
      Fail(r.AtByte(r.Offset() - NumSize(size_t_)), std::string(what) + " " + std::to_string(n),
           "a count in [0, 2^31)");
    return n;
  }

  void Entities(ByteReader& r) {
    long long count[4];
    const char* names[4] = {"the number of points", "the number of curves",
                            "the number of surfaces", "the number of volumes"};
    for (int d = 0; d < 4; ++d) count[d] = Count(r, names[d]);
    for (int d = 0; d < 4; ++d)
      for (long long i = 0; i < count[d]; ++i) {
        const int tag = static_cast<int>(r.Integer(NumType::I32, "an entity tag"));
        r.Skip(d == 0 ? 24 : 48, "the entity's coordinates or bounding box");
        const long long nphys = Count(r, "the number of physical tags");
        int phys = 0;
        for (long long p = 0; p < nphys; ++p) {
          const int v = static_cast<int>(r.Integer(NumType::I32, "a physical tag"));
          if (p == 0) phys = v;
        }
        if (d > 0) r.Skip(4 * Count(r, "the number of bounding entities"), "bounding tags");
        if (d == 3) volume_physical_[tag] = phys;
      }
  }

  void Nodes(ByteReader& r) {
    const long long nblocks = Count(r, "the number of node blocks");
    const long long n = Count(r, "the number of nodes");
    r.Skip(2 * NumSize(size_t_), "the minimum and maximum node tags");
    Mesh& mesh = out_.mesh;
    mesh.vertices.resize(SafeReserve(n, s_.size()), 3);
    std::vector<long long> tags;
    long long total = 0;
    for (long long b = 0; b < nblocks; ++b) {
      const long long dim = r.Integer(NumType::I32, "the entity dimension");
      r.Integer(NumType::I32, "the entity tag");
      const long long param = r.Integer(NumType::I32, "the parametric flag");
      const long long m = Count(r, "the number of nodes in the block");
      if (total + m > n || dim < 0 || dim > 3 || (param != 0 && param != 1))
        Fail(r.AtByte(r.Offset() - NumSize(size_t_)),
             "node block " + std::to_string(b + 1) + " (dimension " + std::to_string(dim) +
                 ", parametric " + std::to_string(param) + ", " + std::to_string(m) + " nodes)",
             "dimension 0-3, parametric 0 or 1, at most the declared " + std::to_string(n) +
                 " nodes in all");
      for (long long j = 0; j < m; ++j) tags.push_back(r.Integer(size_t_, "a node tag"));
      for (long long j = 0; j < m; ++j) {
        out_.origin.vertex_at.push_back(r.Offset());
        for (int d = 0; d < 3; ++d) mesh.vertices(total + j, d) = r.Number(NumType::F64, "x y z");
        r.Skip(8 * (param ? dim : 0), "the parametric coordinates");
      }
      total += m;
    }
    if (total != n)
      Fail(r.Here(), "node blocks hold " + std::to_string(total) + " nodes",
           std::to_string(n) + " nodes as declared");
    const int dup = nodes_.Build(tags);
    if (dup >= 0)
      Fail(r.AtByte(out_.origin.vertex_at[static_cast<std::size_t>(dup)]),
           "node tag " + std::to_string(tags[static_cast<std::size_t>(dup)]) + " is defined twice",
           "unique node tags");
  }

  void Elements(ByteReader& r) {
    const long long nblocks = Count(r, "the number of element blocks");
    const long long n = Count(r, "the number of elements");
    r.Skip(2 * NumSize(size_t_), "the minimum and maximum element tags");
    long long total = 0;
    for (long long b = 0; b < nblocks; ++b) {
      const long long dim = r.Integer(NumType::I32, "the entity dimension");
      const int entity = static_cast<int>(r.Integer(NumType::I32, "the entity tag"));
      const long long type = r.Integer(NumType::I32, "the element type");
      const long long m = Count(r, "the number of elements in the block");
      const GmshType info = LookupGmshType(type);
      const long long at = r.Offset() - NumSize(size_t_) - 12;
      if (info.nodes == 0 || info.dim != dim || (dim == 3 && Corners(type) == 0) || total + m > n)
        Fail(r.AtByte(at),
             "element block " + std::to_string(b + 1) + " of type " + std::to_string(type) + " (" +
                 (info.nodes ? info.name : "unknown") + ") in an entity of dimension " +
                 std::to_string(dim),
             "a known element type of the entity's dimension; of 3D ones a tetrahedron (4, "
             "11, 29-31) or a prism (6, 13, 18); at most the declared " +
                 std::to_string(n) + " elements");
      total += m;
      if (dim < 3) {
        r.Skip(m * (1 + info.nodes) * NumSize(size_t_), "the block's elements");
        continue;
      }
      const auto it = volume_physical_.find(entity);
      const int region = it == volume_physical_.end() ? 0 : it->second;
      for (long long i = 0; i < m; ++i) AddElement(r, type, info, region);
    }
    if (total != n)
      Fail(r.Here(), "element blocks hold " + std::to_string(total) + " elements",
           std::to_string(n) + " elements as declared");
  }

  void AddElement(ByteReader& r, long long type, const GmshType& info, int region) {
    out_.origin.element_at.push_back(r.Offset());
    r.Integer(size_t_, "the element tag");
    Element e;
    const int k = Corners(type);
    e.type = k == 4 ? ElementType::Tet : ElementType::Prism;
    e.region = region;
    for (int a = 0; a < info.nodes; ++a) {
      const long long tag = r.Integer(size_t_, "a node tag");
      const int v = nodes_.Find(tag);
      if (v < 0)
        Fail(r.AtByte(r.Offset() - NumSize(size_t_)),
             "node tag " + std::to_string(tag) + " is not defined in $Nodes",
             "one of the " + std::to_string(out_.mesh.num_vertices()) + " node tags of $Nodes");
      if (a < k) e.v[a] = v;
    }
    if (info.nodes > k) ++out_.higher_order;
    out_.mesh.elements.push_back(e);
  }

  Scanner& s_;
  NumType size_t_;
  GmshBody& out_;
  bool little_ = true;
  TagIndex nodes_;
  std::map<int, int> volume_physical_;
};

}  // namespace

void ReadGmshBinaryBody(Scanner& s, int data_size, GmshBody* out) {
  BinaryGmsh(s, data_size, out).Read();
}

}  // namespace detail
}  // namespace softkin
