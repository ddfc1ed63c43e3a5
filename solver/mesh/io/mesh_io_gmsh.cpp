/// \file mesh_io_gmsh.cpp
/// Gmsh ASCII `.msh` 2.2 and 4.1: reader (tets and prisms; lower-dimensional elements skipped) and
/// writer. In 2.2 the region is the element's first tag (physical group); in 4.1 it is the first
/// physical tag of the element's volume entity from $Entities (0 if it has none).
#include <cmath>
#include <map>

#include "softkin/solver/mesh/io/mesh_io.hpp"
#include "softkin/solver/mesh/io/mesh_io_detail.hpp"
#include "softkin/solver/mesh/io/mesh_io_gmsh_binary.hpp"
#include "softkin/solver/mesh/io/mesh_io_gmsh_types.hpp"

namespace softkin {

namespace {

using detail::Scanner;

using detail::Corners;
using detail::GmshType;
using detail::LookupGmshType;

constexpr const char* kEntityNames[4] = {"point entity", "curve entity", "surface entity",
                                         "volume entity"};

/// What an element line must hold after the leading tags (static text: no allocation per line).
const char* PerLine(long long type) {
  if (type == 4) return "4 node tags for a 4-node tetrahedron";
  if (type == 6) return "6 node tags for a 6-node prism";
  return "as many node tags as the element type has nodes";
}

constexpr const char* kWanted =
    "a tetrahedron (element type 4, or 11/29/30/31 of higher order) or a prism (6, or 13/18 of "
    "second order)";

/// Checks an element type; returns true if the element is a tet/prism to keep, false if it is a
/// lower-dimensional element to skip; fails on unknown and unsupported 3D types.
bool CheckType(Scanner& s, long long type, GmshType* info) {
  *info = LookupGmshType(type);
  if (info->nodes == 0)
    s.FailHere("unknown element type " + std::to_string(type),
               std::string(kWanted) + ", or a lower-dimensional element to skip");
  if (info->dim < 3) return false;
  if (Corners(type) == 0)
    s.FailHere("unsupported element type " + std::to_string(type) + " (" + info->name + ")",
               kWanted);
  return true;
}

struct Reader {
  Scanner s;
  bool v4 = false;
  Mesh mesh;
  std::vector<int> vertex_lines, element_lines;
  detail::TagIndex nodes;
  bool have_nodes = false, have_elements = false;
  std::map<int, int> volume_physical;  // 4.1: volume entity tag -> first physical tag
  int higher_order = 0;                // elements read as their corner nodes
  int binary_size = 0;                 // binary 4.1: the size_t width; 0 for ASCII

  explicit Reader(const std::string& path) : s(path) {}

  /// Positions on the next non-blank line of section `sec`, failing if the file or the section
  /// ends first. The message (built only on failure) names `item` number i (0-based) of n, and the
  /// block b (0-based) when b >= 0.
  void NeedLine(const char* sec, int opened, const char* item, long long i, long long n,
                long long b = -1) {
    const bool eof = !s.SkipBlankLines();
    if (!eof && s.RestOfLine().substr(0, 1) != "$") return;
    std::string missing =
        std::string(item) + " " + std::to_string(i + 1) + " of " + std::to_string(n);
    if (b >= 0) missing += " in block " + std::to_string(b + 1);
    if (eof)
      s.FailHere("file ends inside $" + std::string(sec) + " (opened on line " +
                     std::to_string(opened) + ") before " + missing,
                 missing + ", then $End" + sec);
    s.FailHere("section $" + std::string(sec) + " ends before " + missing, missing);
  }

  /// Expects the "$End<sec>" line.
  void ExpectEnd(const char* sec, int opened) {
    const std::string want = std::string("$End") + sec;
    if (!s.SkipBlankLines())
      s.FailHere("file ends inside $" + std::string(sec) + " (opened on line " +
                     std::to_string(opened) + ")",
                 want);
    const std::string_view l = s.RestOfLine();
    if (l != want)
      s.FailHere("found " + detail::Quote(l),
                 want + " (the counts declared in $" + sec + " are used up)");
    s.NextLine();
  }

  /// Skips an unknown section up to its $End line.
  void SkipSection(const std::string& sec, int opened) {
    const std::string want = "$End" + sec;
    while (s.NextLine()) {
      if (s.RestOfLine() == want) {
        s.NextLine();
        return;
      }
    }
    s.FailHere("file ends inside $" + sec + " (opened on line " + std::to_string(opened) + ")",
               want);
  }

  long long Count(const char* what) {
    const long long n = s.Integer(what);
    if (n < 0 || n > INT_MAX)
      s.FailHere(std::string(what) + " " + std::to_string(n), "a count in [0, 2^31)");
    return n;
  }

  void FinishNodes(const std::vector<long long>& tags, const std::vector<int>& tag_lines) {
    const int dup = nodes.Build(tags);
    if (dup >= 0)
      detail::Fail(detail::At(s.path(), tag_lines[dup]),
                   "node tag " + std::to_string(tags[dup]) + " is defined twice",
                   "unique node tags");
    have_nodes = true;
  }

  int NodeIndex(long long tag) {
    const int i = nodes.Find(tag);
    if (i < 0)
      s.FailHere("node tag " + std::to_string(tag) + " is not defined in $Nodes",
                 "one of the " + std::to_string(mesh.num_vertices()) + " node tags of $Nodes");
    return i;
  }

  /// Reads the node tags of a kept element (the rest of its line) and adds its corners.
  void AddElement(long long type, const GmshType& info, int region, int line) {
    Element e;
    const int k = Corners(type);
    e.type = k == 4 ? ElementType::Tet : ElementType::Prism;
    e.region = region;
    for (int a = 0; a < k; ++a) e.v[a] = NodeIndex(s.Integer("a node tag"));
    for (int a = k; a < info.nodes; ++a) NodeIndex(s.Integer("a node tag"));
    s.ExpectEol(PerLine(type));
    if (info.nodes > k) ++higher_order;
    mesh.elements.push_back(e);
    element_lines.push_back(line);
  }

  // ---------------- 2.2 ----------------
  void Nodes2(int opened) {
    const long long n = Count("the number of nodes");
    s.ExpectEol("the number of nodes");
    s.NextLine();
    const long long cap = detail::SafeReserve(n, s.size());
    mesh.vertices.resize(cap, 3);
    std::vector<long long> tags;
    tags.reserve(static_cast<std::size_t>(cap));
    vertex_lines.reserve(static_cast<std::size_t>(cap));
    for (long long j = 0; j < n; ++j) {
      NeedLine("Nodes", opened, "node", j, n);
      if (j >= mesh.vertices.rows()) mesh.vertices.conservativeResize(2 * j + 1, 3);  // guard only
      vertex_lines.push_back(s.line());
      tags.push_back(s.Integer("the node tag"));
      mesh.vertices(j, 0) = s.Double("x");
      mesh.vertices(j, 1) = s.Double("y");
      mesh.vertices(j, 2) = s.Double("z");
      s.ExpectEol("'<tag> x y z'");
      s.NextLine();
    }
    mesh.vertices.conservativeResize(n, 3);
    ExpectEnd("Nodes", opened);
    FinishNodes(tags, vertex_lines);
  }

  void Elements2(int opened) {
    const long long n = Count("the number of elements");
    s.ExpectEol("the number of elements");
    s.NextLine();
    for (long long i = 0; i < n; ++i) {
      NeedLine("Elements", opened, "element", i, n);
      const int line = s.line();
      s.Integer("the element tag");
      const long long type = s.Integer("the element type");
      const long long ntags = s.Integer("the number of tags");
      if (ntags < 0 || ntags > 1000)
        s.FailHere("number of tags " + std::to_string(ntags), "a count in [0, 1000]");
      int region = 0;
      for (long long t = 0; t < ntags; ++t) {
        const int v = s.Int("a tag");
        if (t == 0) region = v;
      }
      GmshType info;
      if (!CheckType(s, type, &info)) {
        for (int a = 0; a < info.nodes; ++a) s.Integer("a node tag");
        s.ExpectEol(PerLine(type));
        s.NextLine();
        continue;
      }
      AddElement(type, info, region, line);
      s.NextLine();
    }
    ExpectEnd("Elements", opened);
    have_elements = true;
  }

  // ---------------- 4.1 ----------------
  void Entities4(int opened) {
    long long count[4];
    const char* names[4] = {"the number of points", "the number of curves",
                            "the number of surfaces", "the number of volumes"};
    for (int d = 0; d < 4; ++d) count[d] = Count(names[d]);
    s.ExpectEol("'<#points> <#curves> <#surfaces> <#volumes>'");
    s.NextLine();
    for (int d = 0; d < 4; ++d) {
      for (long long i = 0; i < count[d]; ++i) {
        NeedLine("Entities", opened, kEntityNames[d], i, count[d]);
        if (d == 3) {
          const int tag = s.Int("the volume tag");
          for (int c = 0; c < 6; ++c) s.Double("a bounding-box coordinate");
          const long long nphys = s.Integer("the number of physical tags");
          if (nphys < 0 || nphys > 100000)
            s.FailHere("number of physical tags " + std::to_string(nphys), "a count >= 0");
          int phys = 0;
          for (long long p = 0; p < nphys; ++p) {
            const int v = s.Int("a physical tag");
            if (p == 0) phys = v;
          }
          const long long nb = s.Integer("the number of bounding surfaces");
          if (nb < 0 || nb > 100000000)
            s.FailHere("number of bounding surfaces " + std::to_string(nb), "a count >= 0");
          for (long long b = 0; b < nb; ++b) s.Integer("a bounding surface tag");
          s.ExpectEol("'<tag> <bbox x6> <#physical> <tags> <#surfaces> <tags>'");
          volume_physical[tag] = phys;
        }
        s.NextLine();
      }
    }
    ExpectEnd("Entities", opened);
  }

  void Nodes4(int opened) {
    const long long nblocks = Count("the number of entity blocks");
    const long long n = Count("the number of nodes");
    s.Integer("the minimum node tag");
    s.Integer("the maximum node tag");
    s.ExpectEol("'<#blocks> <#nodes> <min tag> <max tag>'");
    s.NextLine();
    const long long cap = detail::SafeReserve(n, s.size());
    mesh.vertices.resize(cap, 3);
    std::vector<long long> tags;
    tags.reserve(static_cast<std::size_t>(cap));
    vertex_lines.resize(static_cast<std::size_t>(cap));
    std::vector<int> tag_lines;
    tag_lines.reserve(static_cast<std::size_t>(cap));
    long long total = 0;
    for (long long b = 0; b < nblocks; ++b) {
      NeedLine("Nodes", opened, "node block", b, nblocks);
      const long long dim = s.Integer("the entity dimension");
      s.Integer("the entity tag");
      const long long param = s.Integer("the parametric flag");
      const long long m = Count("the number of nodes in the block");
      s.ExpectEol("'<entity dim> <entity tag> <parametric> <#nodes>'");
      if (dim < 0 || dim > 3) s.FailHere("entity dimension " + std::to_string(dim), "0, 1, 2 or 3");
      if (param != 0 && param != 1)
        s.FailHere("parametric flag " + std::to_string(param), "0 or 1");
      if (total + m > n)
        s.FailHere("node blocks hold more than the declared " + std::to_string(n) + " nodes",
                   std::to_string(n) + " nodes in all");
      s.NextLine();
      for (long long j = 0; j < m; ++j) {
        NeedLine("Nodes", opened, "node tag", j, m, b);
        tag_lines.push_back(s.line());
        tags.push_back(s.Integer("the node tag"));
        s.ExpectEol("one node tag per line");
        s.NextLine();
      }
      for (long long j = 0; j < m; ++j) {
        NeedLine("Nodes", opened, "coordinate line", j, m, b);
        const long long r = total + j;
        vertex_lines[static_cast<std::size_t>(r)] = s.line();
        mesh.vertices(r, 0) = s.Double("x");
        mesh.vertices(r, 1) = s.Double("y");
        mesh.vertices(r, 2) = s.Double("z");
        if (param)
          for (long long u = 0; u < dim; ++u) s.Double("a parametric coordinate");
        s.ExpectEol(param ? "'x y z' followed by the entity's parametric coordinates" : "'x y z'");
        s.NextLine();
      }
      total += m;
    }
    if (total != n)
      s.FailHere("node blocks hold " + std::to_string(total) + " nodes",
                 std::to_string(n) + " nodes as declared");
    mesh.vertices.conservativeResize(n, 3);
    vertex_lines.resize(static_cast<std::size_t>(n));
    ExpectEnd("Nodes", opened);
    FinishNodes(tags, tag_lines);
  }

  void Elements4(int opened) {
    const long long nblocks = Count("the number of entity blocks");
    const long long n = Count("the number of elements");
    s.Integer("the minimum element tag");
    s.Integer("the maximum element tag");
    s.ExpectEol("'<#blocks> <#elements> <min tag> <max tag>'");
    s.NextLine();
    long long total = 0;
    for (long long b = 0; b < nblocks; ++b) {
      NeedLine("Elements", opened, "element block", b, nblocks);
      const long long dim = s.Integer("the entity dimension");
      const int entity = s.Int("the entity tag");
      const long long type = s.Integer("the element type");
      const long long m = Count("the number of elements in the block");
      s.ExpectEol("'<entity dim> <entity tag> <element type> <#elements>'");
      GmshType info;
      const bool keep = CheckType(s, type, &info);
      if (dim != info.dim)
        s.FailHere(
            "a " + std::string(info.name) + " in an entity of dimension " + std::to_string(dim),
            "entity dimension " + std::to_string(info.dim));
      if (total + m > n)
        s.FailHere("element blocks hold more than the declared " + std::to_string(n) + " elements",
                   std::to_string(n) + " elements in all");
      int region = 0;
      if (keep) {
        const auto it = volume_physical.find(entity);
        if (it != volume_physical.end()) region = it->second;
      }
      s.NextLine();
      for (long long i = 0; i < m; ++i) {
        NeedLine("Elements", opened, "element", i, m, b);
        const int line = s.line();
        s.Integer("the element tag");
        if (!keep) {
          for (int a = 0; a < info.nodes; ++a) s.Integer("a node tag");
          s.ExpectEol(PerLine(type));
          s.NextLine();
          continue;
        }
        AddElement(type, info, region, line);
        s.NextLine();
      }
      total += m;
    }
    if (total != n)
      s.FailHere("element blocks hold " + std::to_string(total) + " elements",
                 std::to_string(n) + " elements as declared");
    ExpectEnd("Elements", opened);
    have_elements = true;
  }

  void Read() {
    if (!s.SkipBlankLines()) s.FailHere("file is empty", "a Gmsh file starting with $MeshFormat");
    if (s.RestOfLine() != "$MeshFormat")
      s.FailHere("found " + detail::Quote(s.RestOfLine()) + " (not a Gmsh .msh file?)",
                 "$MeshFormat");
    const int fmt_line = s.line();
    s.NextLine();
    if (!s.SkipBlankLines())
      s.FailHere("file ends inside $MeshFormat", "'<version> <file-type> <data-size>'");
    const std::string version(s.Word());
    const long long file_type = s.Integer("the file type");
    if (file_type != 0 && (file_type != 1 || version != "4.1"))
      s.FailHere("binary .msh " + version + " file (file type " + std::to_string(file_type) + ")",
                 "an ASCII .msh file (file type 0) or a binary 4.1 one (file type 1; in Gmsh: "
                 "-format msh41 -bin, or File > Export as version 4.1)");
    const long long data_size = s.Integer("the data size");
    s.ExpectEol("'<version> <file-type> <data-size>'");
    if (file_type == 1) {
      if (data_size != 4 && data_size != 8)
        s.FailHere("data size " + std::to_string(data_size), "8 (or 4): the size of size_t");
      binary_size = static_cast<int>(data_size);
      s.NextLine();
      return;  // ReadGmsh goes on with ReadGmshBinaryBody
    }
    double ver = 0.0;
    {
      const auto r = std::from_chars(version.data(), version.data() + version.size(), ver);
      if (r.ec != std::errc() || r.ptr != version.data() + version.size())
        s.FailHere("version " + detail::Quote(version), "2.2 or 4.1");
    }
    if (ver >= 2.0 && ver < 3.0) {
      v4 = false;
    } else if (std::abs(ver - 4.1) < 1e-9) {
      v4 = true;
    } else {
      s.FailHere("unsupported .msh version " + version,
                 "2.2 or 4.1 (re-export with Gmsh -format msh22 or msh41)");
    }
    s.NextLine();
    ExpectEnd("MeshFormat", fmt_line);

    while (s.SkipBlankLines()) {
      const std::string_view l = s.RestOfLine();
      const int opened = s.line();
      if (l.empty() || l[0] != '$')
        s.FailHere("found " + detail::Quote(l) + " between sections",
                   "a section header such as $Nodes");
      const std::string sec(l.substr(1));
      s.NextLine();
      if (sec == "Nodes") {
        if (have_nodes)
          detail::Fail(detail::At(s.path(), opened), "second $Nodes section", "one $Nodes section");
        if (!s.SkipBlankLines())
          s.FailHere("file ends inside $Nodes (opened on line " + std::to_string(opened) + ")",
                     "the node count");
        if (v4)
          Nodes4(opened);
        else
          Nodes2(opened);
      } else if (sec == "Elements") {
        if (have_elements)
          detail::Fail(detail::At(s.path(), opened), "second $Elements section",
                       "one $Elements section");
        if (!have_nodes)
          detail::Fail(detail::At(s.path(), opened), "$Elements before $Nodes", "$Nodes first");
        if (!s.SkipBlankLines())
          s.FailHere("file ends inside $Elements (opened on line " + std::to_string(opened) + ")",
                     "the element count");
        if (v4)
          Elements4(opened);
        else
          Elements2(opened);
      } else if (sec == "Entities" && v4) {
        if (!s.SkipBlankLines())
          s.FailHere("file ends inside $Entities (opened on line " + std::to_string(opened) + ")",
                     "the entity counts");
        Entities4(opened);
      } else if (sec.compare(0, 3, "End") == 0) {
        detail::Fail(detail::At(s.path(), opened), "unmatched " + detail::Quote(l),
                     "a section header such as $Nodes");
      } else {
        SkipSection(sec, opened);
      }
    }
    if (!have_nodes) s.FailHere("no $Nodes section", "$Nodes and $Elements sections");
    if (!have_elements) s.FailHere("no $Elements section", "an $Elements section");
  }
};

}  // namespace

Mesh ReadGmsh(const std::string& path, MeshReport* report) {
  Reader r(path);
  r.Read();
  if (r.binary_size > 0) {
    detail::GmshBody body;
    detail::ReadGmshBinaryBody(r.s, r.binary_size, &body);
    body.origin.bytes = true;
    MeshReport rep = ValidateAndOrient(body.mesh, path, body.origin);
    detail::NoteCornersOnly(path, body.higher_order, &rep);
    detail::Deliver(rep, report);
    return std::move(body.mesh);
  }
  MeshReport rep = ValidateAndOrient(r.mesh, path, r.element_lines, r.vertex_lines);
  detail::NoteCornersOnly(path, r.higher_order, &rep);
  detail::Deliver(rep, report);
  return std::move(r.mesh);
}

void WriteGmsh(const std::string& path, const Mesh& mesh, const std::string& version) {
  const bool v4 = version == "4.1";
  if (!v4 && version != "2.2" && version != "2")
    detail::Fail(path, "unsupported Gmsh version " + detail::Quote(version), "\"2.2\" or \"4.1\"");
  OutputFile out_file(path);
  std::ostream& out = detail::ForWrite(out_file);
  const int nv = mesh.num_vertices(), ne = mesh.num_elements();
  auto gmsh_type = [](const Element& e) { return e.type == ElementType::Tet ? 4 : 6; };
  // Elementary entities (volumes): one per region, tag = position in the sorted regions + 1 (> 0).
  const std::vector<int> regions = mesh.regions();
  auto entity_of = [&](int region) {
    return static_cast<int>(std::lower_bound(regions.begin(), regions.end(), region) -
                            regions.begin()) +
           1;
  };
  if (!v4) {
    out << "$MeshFormat\n2.2 0 8\n$EndMeshFormat\n";
    out << "$Nodes\n" << nv << '\n';
    for (int j = 0; j < nv; ++j) detail::WriteRow(out << j + 1 << ' ', mesh.vertices, j) << '\n';
    out << "$EndNodes\n$Elements\n" << ne << '\n';
    for (int i = 0; i < ne; ++i) {
      const Element& e = mesh.elements[i];
      // tags: physical group (the region), elementary entity
      out << i + 1 << ' ' << gmsh_type(e) << " 2 " << e.region << ' ' << entity_of(e.region);
      for (int a = 0; a < e.k(); ++a) out << ' ' << e.v[a] + 1;
      out << '\n';
    }
    out << "$EndElements\n";
    out_file.Commit();
    return;
  }

  // 4.1: one volume entity per region (tag = position + 1, physical tag = region unless 0), all
  // nodes in one block of the first volume, one element block per run of equal (region, type) so
  // the element order is kept.
  out << "$MeshFormat\n4.1 0 8\n$EndMeshFormat\n";
  out << "$Entities\n0 0 0 " << regions.size() << '\n';
  // Bounding box of each volume entity, in one pass over the elements.
  Eigen::MatrixX3d lo =
      Eigen::MatrixX3d::Constant(static_cast<Eigen::Index>(regions.size()), 3, 1e300);
  Eigen::MatrixX3d hi = -lo;
  for (const auto& e : mesh.elements) {
    const int r = entity_of(e.region) - 1;
    for (int a = 0; a < e.k(); ++a) {
      lo.row(r) = lo.row(r).cwiseMin(mesh.vertices.row(e.v[a]));
      hi.row(r) = hi.row(r).cwiseMax(mesh.vertices.row(e.v[a]));
    }
  }
  for (std::size_t r = 0; r < regions.size(); ++r) {
    out << r + 1 << ' ';
    detail::WriteRow(out, lo, static_cast<int>(r)) << ' ';
    detail::WriteRow(out, hi, static_cast<int>(r));
    if (regions[r] != 0)
      out << " 1 " << regions[r];
    else
      out << " 0";
    out << " 0\n";
  }
  out << "$EndEntities\n";
  out << "$Nodes\n"
      << (nv > 0 ? 1 : 0) << ' ' << nv << ' ' << (nv > 0 ? 1 : 0) << ' ' << nv << '\n';
  if (nv > 0) {
    out << "3 1 0 " << nv << '\n';
    for (int j = 0; j < nv; ++j) out << j + 1 << '\n';
    for (int j = 0; j < nv; ++j) detail::WriteRow(out, mesh.vertices, j) << '\n';
  }
  out << "$EndNodes\n";
  int nblocks = 0;
  for (int i = 0; i < ne; ++i)
    if (i == 0 || mesh.elements[i].region != mesh.elements[i - 1].region ||
        mesh.elements[i].type != mesh.elements[i - 1].type)
      ++nblocks;
  out << "$Elements\n" << nblocks << ' ' << ne << ' ' << (ne > 0 ? 1 : 0) << ' ' << ne << '\n';
  for (int i = 0; i < ne;) {
    int j = i;
    while (j < ne && mesh.elements[j].region == mesh.elements[i].region &&
           mesh.elements[j].type == mesh.elements[i].type)
      ++j;
    out << "3 " << entity_of(mesh.elements[i].region) << ' ' << gmsh_type(mesh.elements[i]) << ' '
        << j - i << '\n';
    for (int q = i; q < j; ++q) {
      const Element& e = mesh.elements[q];
      out << q + 1;
      for (int a = 0; a < e.k(); ++a) out << ' ' << e.v[a] + 1;
      out << '\n';
    }
    i = j;
  }
  out << "$EndElements\n";
  out_file.Commit();
}

}  // namespace softkin
