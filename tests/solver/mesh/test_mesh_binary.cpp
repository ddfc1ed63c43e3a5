// Tests of the binary mesh readers (solver/mesh/io/mesh_io.hpp): binary Gmsh 4.1 in both byte
// orders, binary legacy VTK (classic CELLS and VTK 5.1 OFFSETS/CONNECTIVITY), and VTK XML .vtu in
// ascii, inline base64 and raw appended form, including WriteVtu's own output. Every binary file
// is written byte by byte here.
#include <gtest/gtest.h>

#include <chrono>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <functional>
#include <string>
#include <vector>

#include "softkin/solver/mesh/io/mesh_io.hpp"
#include "softkin/solver/mesh/mesh.hpp"
#include "tests/solver/mesh/mesh_io_test_util.hpp"

namespace softkin {
namespace {

namespace fs = std::filesystem;

using mesh_test::ErrorOf;
using mesh_test::ExpectHas;
using MeshBinary = mesh_test::MeshIoTest;

/// Builds a byte string of numbers in a chosen byte order.
struct Bytes {
  bool big = false;
  std::string s;

  template <typename T>
  Bytes& Put(T v) {
    char b[sizeof(T)];
    std::memcpy(b, &v, sizeof(T));
    const std::uint16_t one = 1;
    char first;
    std::memcpy(&first, &one, 1);
    const bool host_little = first == 1;
    if (big == host_little)
      for (std::size_t i = 0; i < sizeof(T) / 2; ++i) std::swap(b[i], b[sizeof(T) - 1 - i]);
    s.append(b, sizeof(T));
    return *this;
  }
  Bytes& I32(std::int32_t v) { return Put(v); }
  Bytes& U64(std::uint64_t v) { return Put(v); }
  Bytes& F64(double v) { return Put(v); }
  Bytes& F32(float v) { return Put(v); }
  Bytes& Text(const std::string& t) {
    s += t;
    return *this;
  }
};

/// Five points: the unit tet's corners and (1, 1, 1); tets (0,1,2,3) and (1,2,3,4) share a face.
const double kPts[5][3] = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}, {1, 1, 1}};

void ExpectTwoTets(const Mesh& m, int region0, int region1) {
  ASSERT_EQ(m.num_vertices(), 5);
  ASSERT_EQ(m.num_elements(), 2);
  for (int j = 0; j < 5; ++j)
    for (int d = 0; d < 3; ++d) EXPECT_EQ(m.vertices(j, d), kPts[j][d]);
  EXPECT_EQ(m.elements[0].region, region0);
  EXPECT_EQ(m.elements[1].region, region1);
  for (const auto& e : m.elements) EXPECT_GT(SignedVolume(e, m.vertices), 0);
}

/// A binary Gmsh 4.1 file: a surface entity with one triangle (skipped) and a volume entity
/// (physical 7) with two tets; node tags 10 ... 50.
std::string Gmsh41Binary(bool big) {
  Bytes b;
  b.big = big;
  b.Text("$MeshFormat\n4.1 1 8\n").I32(1).Text("\n$EndMeshFormat\n");
  b.Text("$Entities\n").U64(0).U64(0).U64(1).U64(1);
  b.I32(5);
  for (int i = 0; i < 6; ++i) b.F64(0);
  b.U64(0).U64(0);
  b.I32(1);
  for (int i = 0; i < 6; ++i) b.F64(i < 3 ? 0 : 1);
  b.U64(1).I32(7).U64(1).I32(5);
  b.Text("\n$EndEntities\n$Nodes\n").U64(1).U64(5).U64(10).U64(50);
  b.I32(3).I32(1).I32(0).U64(5);
  for (int j = 0; j < 5; ++j) b.U64(10 * (j + 1));
  for (const auto& p : kPts) b.F64(p[0]).F64(p[1]).F64(p[2]);
  b.Text("\n$EndNodes\n$Elements\n").U64(2).U64(3).U64(1).U64(3);
  b.I32(2).I32(5).I32(2).U64(1).U64(1).U64(10).U64(20).U64(30);
  b.I32(3).I32(1).I32(4).U64(2);
  b.U64(2).U64(10).U64(20).U64(30).U64(40);
  b.U64(3).U64(20).U64(30).U64(40).U64(50);
  b.Text("\n$EndElements\n");
  return b.s;
}

TEST_F(MeshBinary, Gmsh41InBothByteOrders) {
  for (bool big : {false, true}) {
    MeshReport r;
    const Mesh m = ReadGmsh(WriteText(big ? "be.msh" : "le.msh", Gmsh41Binary(big)), &r);
    ExpectTwoTets(m, 7, 7);
    EXPECT_EQ(r.unused_vertices, 0);
    EXPECT_EQ(r.flipped, 0);
  }
  // ReadMesh dispatches it like an ASCII one.
  ExpectTwoTets(ReadMesh(Path("le.msh")), 7, 7);
}

TEST_F(MeshBinary, Gmsh41TruncatedOrBadNamesTheByteOffset) {
  const std::string whole = Gmsh41Binary(false);
  const std::size_t nodes = whole.find("$Nodes\n") + 7;
  const std::string p = WriteText("cut.msh", whole.substr(0, nodes + 100));
  const std::string msg = ErrorOf([&] { ReadGmsh(p); });
  ExpectHas(msg, p + ": byte offset ");
  ExpectHas(msg, "data ends inside");
  ExpectHas(msg, "; expected ");
  std::string bad = whole;
  bad[bad.find("4.1 1 8\n") + 8] = 2;  // the endianness check int reads 2
  const std::string q = WriteText("bad.msh", bad);
  ExpectHas(ErrorOf([&] { ReadGmsh(q); }), q + ": byte offset 20: endianness check reads 2");
}

/// Legacy binary VTK (big-endian): 5 points, two tets and a line; regions from SCALARS.
std::string VtkBinary(bool v51) {
  Bytes b;
  b.big = true;
  b.Text("# vtk DataFile Version " + std::string(v51 ? "5.1" : "3.0") +
         "\nb\nBINARY\nDATASET UNSTRUCTURED_GRID\nPOINTS 5 float\n");
  for (const auto& p : kPts) b.F32(float(p[0])).F32(float(p[1])).F32(float(p[2]));
  if (v51) {
    b.Text("\nCELLS 4 10\nOFFSETS vtktypeint64\n");
    for (std::int64_t o : {0, 4, 8, 10}) b.Put(o);
    b.Text("\nCONNECTIVITY vtktypeint64\n");
    for (std::int64_t c : {0, 1, 2, 3, 1, 2, 3, 4, 0, 4}) b.Put(c);
  } else {
    b.Text("\nCELLS 3 13\n");
    for (int c : {4, 0, 1, 2, 3, 4, 1, 2, 3, 4, 2, 0, 4}) b.I32(c);
  }
  b.Text("\nCELL_TYPES 3\n").I32(10).I32(10).I32(3);
  if (v51) {
    b.Text("\nCELL_DATA 3\nFIELD FieldData 1\nmat 1 3 int\n").I32(7).I32(8).I32(0);
  } else {
    b.Text("\nCELL_DATA 3\nSCALARS region int 1\nLOOKUP_TABLE default\n").I32(7).I32(8).I32(0);
  }
  b.Text("\nPOINT_DATA 5\nVECTORS u double\n");
  for (int i = 0; i < 15; ++i) b.F64(0.5);
  return b.Text("\n").s;
}

TEST_F(MeshBinary, LegacyVtkClassicAnd51) {
  MeshReport r;
  ExpectTwoTets(ReadVtk(WriteText("c.vtk", VtkBinary(false)), "", &r), 7, 8);
  ExpectTwoTets(ReadMesh(WriteText("n.vtk", VtkBinary(true)), &r), 7, 8);
}

TEST_F(MeshBinary, LegacyVtkTruncatedNamesTheByteOffset) {
  const std::string whole = VtkBinary(false);
  const std::string p = WriteText("cut.vtk", whole.substr(0, whole.find("POINTS 5 float\n") + 30));
  const std::string msg = ErrorOf([&] { ReadVtk(p); });
  ExpectHas(msg, p + ": byte offset ");
  ExpectHas(msg, "data ends inside a point coordinate");
  std::string bad = whole;
  const std::size_t cells = bad.find("CELLS 3 13\n") + 11;
  bad[cells + 4 * 6 + 3] = 9;  // second cell's first index (big-endian int 1 -> 9)
  const std::string q = WriteText("bad.vtk", bad);
  const std::string m2 = ErrorOf([&] { ReadVtk(q); });
  ExpectHas(m2, q + ": byte offset " + std::to_string(cells + 4 * 6) + ": point index 9");
}

std::string Base64(const std::string& in) {
  static const char* k = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
  std::string out;
  for (std::size_t i = 0; i < in.size(); i += 3) {
    unsigned v = static_cast<unsigned char>(in[i]) << 16;
    if (i + 1 < in.size()) v |= static_cast<unsigned char>(in[i + 1]) << 8;
    if (i + 2 < in.size()) v |= static_cast<unsigned char>(in[i + 2]);
    out += k[(v >> 18) & 63];
    out += k[(v >> 12) & 63];
    out += i + 1 < in.size() ? k[(v >> 6) & 63] : '=';
    out += i + 2 < in.size() ? k[v & 63] : '=';
  }
  return out;
}

/// The arrays of a .vtu of the five points, two tets and a line (cell types 10, 10, 3), each as
/// a header (byte count) and data in the chosen byte order and header width.
struct VtuBlocks {
  std::vector<std::string> data;  ///< points, connectivity, offsets, types, region
  VtuBlocks(bool big, bool u64) {
    auto block = [&](const std::function<void(Bytes&)>& fill) {
      Bytes body;
      body.big = big;
      fill(body);
      Bytes head;
      head.big = big;
      if (u64)
        head.U64(body.s.size());
      else
        head.Put(static_cast<std::uint32_t>(body.s.size()));
      data.push_back(head.s + body.s);
    };
    block([](Bytes& b) {
      for (const auto& p : kPts) b.F64(p[0]).F64(p[1]).F64(p[2]);
    });
    block([](Bytes& b) {
      for (std::int64_t c : {0, 1, 2, 3, 1, 2, 3, 4, 0, 4}) b.Put(c);
    });
    block([](Bytes& b) {
      for (std::int64_t o : {4, 8, 10}) b.Put(o);
    });
    block([](Bytes& b) {
      for (std::uint8_t t : {10, 10, 3}) b.Put(t);
    });
    block([](Bytes& b) { b.I32(7).I32(8).I32(0); });
  }
};

std::string VtuXml(const std::string& head_attrs, const std::vector<std::string>& arrays,
                   const std::string& tail) {
  const char* names[5] = {"Points", "connectivity", "offsets", "types", "part"};
  const char* types[5] = {"Float64", "Int64", "Int64", "UInt8", "Int32"};
  auto da = [&](int i) {
    return "<DataArray type=\"" + std::string(types[i]) + "\" Name=\"" + names[i] + "\"" +
           (i == 0 ? " NumberOfComponents=\"3\"" : "") + arrays[static_cast<std::size_t>(i)];
  };
  return "<?xml version=\"1.0\"?>\n<VTKFile type=\"UnstructuredGrid\" version=\"1.0\" " +
         head_attrs + ">\n<UnstructuredGrid>\n<Piece NumberOfPoints=\"5\" NumberOfCells=\"3\">\n" +
         "<CellData>\n" + da(4) + "\n</CellData>\n<Points>\n" + da(0) + "\n</Points>\n<Cells>\n" +
         da(1) + "\n" + da(2) + "\n" + da(3) + "\n</Cells>\n</Piece>\n</UnstructuredGrid>\n" +
         tail + "</VTKFile>\n";
}

TEST_F(MeshBinary, VtuInlineBase64AndRawAppended) {
  const VtuBlocks le(false, false);
  std::vector<std::string> inline_arrays;
  for (const auto& d : le.data)
    inline_arrays.push_back(" format=\"binary\">\n" + Base64(d) + "\n</DataArray>");
  const std::string a = WriteText(
      "b64.vtu", VtuXml("byte_order=\"LittleEndian\" header_type=\"UInt32\"", inline_arrays, ""));
  MeshReport r;
  ExpectTwoTets(ReadVtu(a, "", &r), 7, 8);

  const VtuBlocks be(true, true);
  std::vector<std::string> appended_arrays;
  std::string raw;
  for (const auto& d : be.data) {
    appended_arrays.push_back(" format=\"appended\" offset=\"" + std::to_string(raw.size()) +
                              "\"/>");
    raw += d;
  }
  const std::string b = WriteText(
      "raw.vtu", VtuXml("byte_order=\"BigEndian\" header_type=\"UInt64\"", appended_arrays,
                        "<AppendedData encoding=\"raw\">\n_" + raw + "\n</AppendedData>\n"));
  ExpectTwoTets(ReadMesh(b, &r), 7, 8);
}

TEST_F(MeshBinary, VtuCompressedIsRefused) {
  const std::string p = WriteText("z.vtu",
                                  "<?xml version=\"1.0\"?>\n<VTKFile type=\"UnstructuredGrid\" "
                                  "compressor=\"vtkZLibDataCompressor\">\n</VTKFile>\n");
  const std::string msg = ErrorOf([&] { ReadVtu(p); });
  ExpectHas(msg, p + ":2:");
  ExpectHas(msg, "compressed data");
  ExpectHas(msg, "; expected an uncompressed .vtu");
}

TEST_F(MeshBinary, WriteVtuOutputRoundTripsThroughReadMesh) {
  // A prism with a tet on top, regions 3 and 5.
  Mesh m;
  m.vertices.resize(7, 3);
  m.vertices << 0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1, 1, 0, 1, 0, 1, 1, 0.25, 0.25, 2;
  Element prism;
  prism.type = ElementType::Prism;
  prism.v = {{0, 1, 2, 3, 4, 5}};
  prism.region = 3;
  Element tet;
  tet.v = {{3, 4, 5, 6, -1, -1}};
  tet.region = 5;
  m.elements = {prism, tet};
  ValidateAndOrient(m, "mixed");
  const std::string p = Path("out.vtu");
  WriteVtu(p, m, m.vertices);
  MeshReport r;
  const Mesh back = ReadMesh(p, &r);
  ASSERT_EQ(back.num_vertices(), m.num_vertices());
  EXPECT_EQ(back.vertices, m.vertices);
  ASSERT_EQ(back.num_elements(), 2);
  for (int i = 0; i < 2; ++i) {
    EXPECT_EQ(back.elements[i].type, m.elements[i].type);
    EXPECT_EQ(back.elements[i].region, m.elements[i].region);
    EXPECT_EQ(back.elements[i].v, m.elements[i].v);
  }
  EXPECT_EQ(r.flipped, 0);
}

}  // namespace
}  // namespace softkin
