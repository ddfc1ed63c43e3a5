// Tests for solver/mesh/mesh.hpp and solver/mesh/io/mesh_io.hpp: the real finger mesh, round trips
// through every format, error messages with file:line for corrupted inputs, orientation repair,
// warnings, ParaView output (.vtu/.pvd), the boundary surface (.obj) and the strain measure.
#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <functional>
#include <iostream>
#include <limits>
#include <map>
#include <sstream>
#include <string>
#include <vector>

#include "softkin/solver/mesh/mesh.hpp"
#include "softkin/solver/mesh/io/mesh_io.hpp"
#include "tests/solver/mesh/mesh_io_test_util.hpp"

namespace softkin {
namespace {

namespace fs = std::filesystem;

// ---------------------------------------------------------------------------------------------
// helpers

using mesh_test::ErrorOf;
using mesh_test::MeshIoTest;

// Suite names for the groups of tests below (all share the temp-folder fixture).
using MeshIoRoundTrip = MeshIoTest;
using MeshIoErrors = MeshIoTest;
using MeshIoGmsh = MeshIoTest;
using MeshIoTetGen = MeshIoTest;
using MeshIoVtk = MeshIoTest;
using MeshIoVtu = MeshIoTest;
using MeshIoObj = MeshIoTest;
using MeshIoReport = MeshIoTest;

/// The message names "<file>:<line>:" and contains `text`.
void ExpectErrorAt(const std::string& msg, const std::string& file, int line,
                   const std::string& text) {
  const std::string where = file + ":" + std::to_string(line) + ":";
  EXPECT_NE(msg.find(where), std::string::npos) << "expected '" << where << "' in: " << msg;
  EXPECT_NE(msg.find(text), std::string::npos) << "expected '" << text << "' in: " << msg;
  EXPECT_NE(msg.find("; expected "), std::string::npos) << "expected '; expected' in: " << msg;
}

Element Tet(int a, int b, int c, int d, int region) {
  Element e;
  e.type = ElementType::Tet;
  e.v = {{a, b, c, d, -1, -1}};
  e.region = region;
  return e;
}

Element Prism(std::array<int, 6> v, int region) {
  Element e;
  e.type = ElementType::Prism;
  e.v = v;
  e.region = region;
  return e;
}

/// Two prisms side by side (a unit square extruded by 1) and a tet on top of the first prism,
/// all positively oriented, regions 1, 2, 7. Coordinates are mapped by x -> 1.7 x + 1/3 so that
/// they are not short decimals (exercises full-precision writing).
Mesh MixedMesh() {
  Mesh m;
  m.vertices.resize(9, 3);
  m.vertices << 0, 0, 0, 1, 0, 0, 0, 1, 0, 1, 1, 0,  //
      0, 0, 1, 1, 0, 1, 0, 1, 1, 1, 1, 1,            //
      0.3, 0.3, 2;
  m.vertices = (m.vertices.array() * 1.7 + 1.0 / 3.0).matrix();
  m.elements.push_back(Prism({{0, 1, 2, 4, 5, 6}}, 1));
  m.elements.push_back(Prism({{1, 3, 2, 5, 7, 6}}, 2));
  m.elements.push_back(Tet(4, 5, 6, 8, 7));
  return m;
}

/// A 2 x 1 x 1 block: two unit cubes, each split into 6 Kuhn tets (conforming), oriented,
/// regions i % 3. 12 vertices, 12 tets, 10 boundary unit squares.
Mesh BlockMesh() {
  Mesh m;
  m.vertices.resize(12, 3);
  auto id = [](int x, int y, int z) { return x + 3 * (y + 2 * z); };
  for (int z = 0; z < 2; ++z)
    for (int y = 0; y < 2; ++y)
      for (int x = 0; x < 3; ++x) m.vertices.row(id(x, y, z)) << x * 0.1, y * 0.1, z * 0.1;
  const int perms[6][3] = {{0, 1, 2}, {0, 2, 1}, {1, 0, 2}, {1, 2, 0}, {2, 0, 1}, {2, 1, 0}};
  for (int cube = 0; cube < 2; ++cube) {
    for (const auto& p : perms) {
      int c[3] = {cube, 0, 0};
      int v[4];
      v[0] = id(c[0], c[1], c[2]);
      for (int s = 0; s < 3; ++s) {
        ++c[p[s]];
        v[s + 1] = id(c[0], c[1], c[2]);
      }
      m.elements.push_back(Tet(v[0], v[1], v[2], v[3], static_cast<int>(m.elements.size()) % 3));
    }
  }
  ValidateAndOrient(m, "block");
  return m;
}

void ExpectSameMesh(const Mesh& a, const Mesh& b) {
  ASSERT_EQ(a.num_vertices(), b.num_vertices());
  ASSERT_EQ(a.num_elements(), b.num_elements());
  for (int j = 0; j < a.num_vertices(); ++j)
    for (int c = 0; c < 3; ++c) EXPECT_EQ(a.vertices(j, c), b.vertices(j, c)) << "vertex " << j;
  for (int i = 0; i < a.num_elements(); ++i) {
    const Element& x = a.elements[i];
    const Element& y = b.elements[i];
    EXPECT_EQ(x.type, y.type) << "element " << i;
    EXPECT_EQ(x.region, y.region) << "element " << i;
    for (int k = 0; k < x.k(); ++k) EXPECT_EQ(x.v[k], y.v[k]) << "element " << i << " vertex " << k;
  }
}

const char* kUnitTet = "4 vertices\n1 tets\n0 0 0\n1 0 0\n0 1 0\n0 0 1\n4 0 1 2 3\n";

// ---------------------------------------------------------------------------------------------
// the real mesh

TEST(MeshIoReal, FingerChamberTetWithLabels) {
  const std::string dir = SOFTKIN_THESIS_DATA;
  MeshReport report;
  const auto t0 = std::chrono::steady_clock::now();
  const Mesh m =
      ReadTet(dir + "/finger_chamber1.tet", dir + "/finger_chamber1_labels.txt", &report);
  const double seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  // Recorded only: the read time is a benchmark (bench_fk BM_ReadTetFingerChamber), not a test.
  std::cout << "[ timing   ] ReadTet(finger_chamber1.tet + labels): " << seconds * 1e3 << " ms\n";
  RecordProperty("read_ms", static_cast<int>(seconds * 1e3));

  EXPECT_EQ(m.num_vertices(), 18014);
  EXPECT_EQ(m.num_elements(), 94240);
  EXPECT_EQ(m.num_tets(), 94240);
  EXPECT_EQ(m.num_prisms(), 0);
  int chamber = 0;
  for (const auto& e : m.elements) chamber += e.region == 1;
  EXPECT_EQ(chamber, 27702);
  EXPECT_EQ(m.regions(), (std::vector<int>{0, 1}));
  EXPECT_EQ(report.flipped, 94240);
  ASSERT_EQ(report.notes.size(), 1u);
  EXPECT_NE(report.notes[0].find("flipped 94240 of 94240"), std::string::npos) << report.notes[0];
  EXPECT_EQ(report.unused_vertices, 0);
  EXPECT_EQ(report.components, 1);
  int nonpositive = 0;
  for (const auto& e : m.elements) nonpositive += !(SignedVolume(e, m.vertices) > 0);
  EXPECT_EQ(nonpositive, 0);
  // Size is in millimetres: a finger is several centimetres long.
  EXPECT_GT(m.size(), 20.0);
  EXPECT_LT(m.size(), 500.0);
}

// ---------------------------------------------------------------------------------------------
// mesh basics

TEST(MeshBasics, VolumesCountsAndFlip) {
  Mesh m = MixedMesh();
  EXPECT_EQ(m.num_tets(), 1);
  EXPECT_EQ(m.num_prisms(), 2);
  EXPECT_EQ(m.regions(), (std::vector<int>{1, 2, 7}));
  const double s3 = 1.7 * 1.7 * 1.7;
  EXPECT_NEAR(SignedVolume(m.elements[0], m.vertices), 0.5 * s3, 1e-12);
  EXPECT_NEAR(SignedVolume(m.elements[1], m.vertices), 0.5 * s3, 1e-12);
  EXPECT_NEAR(SignedVolume(m.elements[2], m.vertices), 0.5 * 1.0 / 3.0 * s3, 1e-12);
  for (auto e : m.elements) {
    const double v = SignedVolume(e, m.vertices);
    FlipElement(e);
    EXPECT_NEAR(SignedVolume(e, m.vertices), -v, 1e-12);
  }
  EXPECT_STREQ(ElementTypeToString(ElementType::Tet), "tet");
  EXPECT_STREQ(ElementTypeToString(ElementType::Prism), "prism");
  EXPECT_NEAR(m.size(), 1.7 * std::sqrt(1 + 1 + 4), 1e-12);
}

TEST(MeshBasics, CountsInvertedElements) {
  Mesh m = MixedMesh();
  EXPECT_EQ(CountInvertedElements(m, m.vertices), 0);
  // Mirroring every position inverts every element; flattening one onto a plane makes it count.
  Eigen::MatrixX3d X = m.vertices;
  X.col(2) *= -1.0;
  EXPECT_EQ(CountInvertedElements(m, X), m.num_elements());
  X = m.vertices;
  for (int j = 0; j < m.elements[0].k(); ++j)
    X(m.elements[0].v[j], 2) = 0.0;  // one element flattened
  EXPECT_GE(CountInvertedElements(m, X), 1);
  EXPECT_LE(CountInvertedElements(m, X), m.num_elements());
  EXPECT_EQ(SignedVolume(m.elements[0], X), 0.0);
  EXPECT_THROW(CountInvertedElements(m, Eigen::MatrixX3d::Zero(2, 3)), std::invalid_argument);
}

TEST(MeshValidate, FlipsOneTetAndOnePrism) {
  const Mesh good = MixedMesh();
  Mesh m = good;
  FlipElement(m.elements[0]);  // prism
  FlipElement(m.elements[2]);  // tet
  ASSERT_LT(SignedVolume(m.elements[0], m.vertices), 0);
  ASSERT_LT(SignedVolume(m.elements[2], m.vertices), 0);
  const MeshReport r = ValidateAndOrient(m, "mixed.msh");
  EXPECT_EQ(r.flipped, 2);
  ASSERT_EQ(r.notes.size(), 1u);
  EXPECT_NE(r.notes[0].find("mixed.msh: flipped 2 of 3"), std::string::npos) << r.notes[0];
  for (const auto& e : m.elements) EXPECT_GT(SignedVolume(e, m.vertices), 0);
  ExpectSameMesh(m, good);  // flipping is its own inverse
  EXPECT_TRUE(r.warnings.empty());
  EXPECT_EQ(r.components, 1);
}

TEST(MeshValidate, ErrorsNameElementWithoutLines) {
  Mesh m = MixedMesh();
  m.elements[1].v[3] = 99;
  std::string msg = ErrorOf([&] { ValidateAndOrient(m, "x.vtk"); });
  EXPECT_NE(msg.find("x.vtk: element 1"), std::string::npos) << msg;
  EXPECT_NE(msg.find("out of range"), std::string::npos) << msg;

  m = MixedMesh();
  m.elements[2].v[3] = m.elements[2].v[0];
  msg = ErrorOf([&] { ValidateAndOrient(m, "x.vtk", {5, 6, 7}); });
  ExpectErrorAt(msg, "x.vtk", 7, "twice");

  m = MixedMesh();
  m.vertices(3, 1) = std::numeric_limits<double>::infinity();
  msg = ErrorOf([&] { ValidateAndOrient(m, "x.vtk", {}, {10, 11, 12, 13}); });
  ExpectErrorAt(msg, "x.vtk", 13, "non-finite");
}

// ---------------------------------------------------------------------------------------------
// round trips

TEST_F(MeshIoRoundTrip, TetWithLabels) {
  const Mesh m = BlockMesh();
  WriteTet(Path("block.tet"), m, Path("block_labels.txt"));
  MeshReport r;
  const Mesh back = ReadTet(Path("block.tet"), Path("block_labels.txt"), &r);
  ExpectSameMesh(m, back);
  EXPECT_EQ(r.flipped, 0);
  // Without labels every region is 0.
  const Mesh nolabels = ReadTet(Path("block.tet"), "", &r);
  for (const auto& e : nolabels.elements) EXPECT_EQ(e.region, 0);
  // .tet holds only tets.
  const std::string msg = ErrorOf([&] { WriteTet(Path("mixed.tet"), MixedMesh()); });
  EXPECT_NE(msg.find("mixed.tet"), std::string::npos) << msg;
  EXPECT_NE(msg.find("prism"), std::string::npos) << msg;
}

TEST_F(MeshIoRoundTrip, TetGen) {
  Mesh m = BlockMesh();
  m.vertices = (m.vertices.array() * 3.7 - 1.0 / 7.0).matrix();
  WriteTetGen(Path("block"), m);
  EXPECT_TRUE(fs::exists(Path("block.node")));
  EXPECT_TRUE(fs::exists(Path("block.ele")));
  MeshReport r;
  ExpectSameMesh(m, ReadTetGen(Path("block"), &r));
  EXPECT_EQ(r.flipped, 0);
  ExpectSameMesh(m, ReadMesh(Path("block.ele"), &r));
  ExpectSameMesh(m, ReadMesh(Path("block.node"), &r));
}

TEST_F(MeshIoRoundTrip, Gmsh22Mixed) {
  const Mesh m = MixedMesh();
  WriteGmsh(Path("mixed.msh"), m, "2.2");
  EXPECT_NE(ReadText(Path("mixed.msh")).find("2.2 0 8"), std::string::npos);
  MeshReport r;
  ExpectSameMesh(m, ReadGmsh(Path("mixed.msh"), &r));
  EXPECT_EQ(r.flipped, 0);
  ExpectSameMesh(BlockMesh(), [&] {
    WriteGmsh(Path("block.msh"), BlockMesh());
    return ReadMesh(Path("block.msh"), &r);
  }());
}

TEST_F(MeshIoRoundTrip, Gmsh41Mixed) {
  Mesh m = MixedMesh();
  m.elements[1].region = 0;  // a volume without a physical group
  WriteGmsh(Path("mixed41.msh"), m, "4.1");
  EXPECT_NE(ReadText(Path("mixed41.msh")).find("4.1 0 8"), std::string::npos);
  MeshReport r;
  ExpectSameMesh(m, ReadGmsh(Path("mixed41.msh"), &r));
  EXPECT_EQ(r.flipped, 0);
  const Mesh b = BlockMesh();
  WriteGmsh(Path("block41.msh"), b, "4.1");
  ExpectSameMesh(b, ReadGmsh(Path("block41.msh"), &r));
  const std::string msg = ErrorOf([&] { WriteGmsh(Path("x.msh"), b, "3.0"); });
  EXPECT_NE(msg.find("x.msh"), std::string::npos) << msg;
}

TEST_F(MeshIoRoundTrip, VtkMixed) {
  const Mesh m = MixedMesh();
  WriteVtk(Path("mixed.vtk"), m);
  MeshReport r;
  ExpectSameMesh(m, ReadVtk(Path("mixed.vtk"), "", &r));
  EXPECT_EQ(r.flipped, 0);  // wedges converted both ways
  ExpectSameMesh(m, ReadVtk(Path("mixed.vtk"), "region", &r));
  ExpectSameMesh(m, ReadMesh(Path("mixed.vtk"), &r));
  // The written wedge follows VTK's convention: base normal pointing away from the top.
  const std::string text = ReadText(Path("mixed.vtk"));
  EXPECT_NE(text.find("\n6 0 2 1 4 6 5\n"), std::string::npos) << text;
}

TEST_F(MeshIoRoundTrip, FlippedElementsThroughReader) {
  Mesh m = MixedMesh();
  FlipElement(m.elements[0]);
  FlipElement(m.elements[2]);
  WriteVtk(Path("flipped.vtk"), m);
  WriteGmsh(Path("flipped.msh"), m, "4.1");
  for (const std::string& p : {Path("flipped.vtk"), Path("flipped.msh")}) {
    MeshReport r;
    const Mesh back = ReadMesh(p, &r);
    EXPECT_EQ(r.flipped, 2) << p;
    ASSERT_EQ(r.notes.size(), 1u) << p;
    EXPECT_NE(r.notes[0].find("flipped 2 of 3"), std::string::npos) << r.notes[0];
    ExpectSameMesh(MixedMesh(), back);
  }
}

// ---------------------------------------------------------------------------------------------
// corrupted inputs: each error names the file and the line

TEST_F(MeshIoErrors, TruncatedVertexList) {
  const std::string p = WriteText("t.tet", "3 vertices\n1 tets\n0 0 0\n1 0 0\n");
  ExpectErrorAt(ErrorOf([&] { ReadTet(p); }), p, 5, "file ends after 2 of 3 vertices");
}

TEST_F(MeshIoErrors, TruncatedElementList) {
  const std::string p =
      WriteText("t.tet", "4 vertices\n2 tets\n0 0 0\n1 0 0\n0 1 0\n0 0 1\n4 0 1 2 3\n");
  ExpectErrorAt(ErrorOf([&] { ReadTet(p); }), p, 8, "file ends after 1 of 2 tets");
}

TEST_F(MeshIoErrors, IndexOutOfRange) {
  const std::string p =
      WriteText("t.tet", "4 vertices\n1 tets\n0 0 0\n1 0 0\n0 1 0\n0 0 1\n4 0 1 2 9\n");
  ExpectErrorAt(ErrorOf([&] { ReadTet(p); }), p, 7, "vertex 9, which is out of range");
}

TEST_F(MeshIoErrors, NanCoordinate) {
  const std::string p =
      WriteText("t.tet", "4 vertices\n1 tets\n0 0 0\nnan 0 0\n0 1 0\n0 0 1\n4 0 1 2 3\n");
  ExpectErrorAt(ErrorOf([&] { ReadTet(p); }), p, 4, "non-finite coordinate (NaN)");
  const std::string q =
      WriteText("i.tet", "4 vertices\n1 tets\n0 0 0\n1 0 0\n0 inf 0\n0 0 1\n4 0 1 2 3\n");
  ExpectErrorAt(ErrorOf([&] { ReadTet(q); }), q, 5, "non-finite coordinate (+Inf)");
}

TEST_F(MeshIoErrors, DegenerateFlatTet) {
  const std::string p = WriteText(
      "flat.tet", "5 vertices\n2 tets\n0 0 0\n1 0 0\n0 1 0\n0 0 1\n1 1 0\n4 0 1 2 3\n4 0 1 4 2\n");
  ExpectErrorAt(ErrorOf([&] { ReadTet(p); }), p, 9, "degenerate");
  // Repeated vertex in one element.
  const std::string q =
      WriteText("rep.tet", "4 vertices\n1 tets\n0 0 0\n1 0 0\n0 1 0\n0 0 1\n4 0 1 1 3\n");
  ExpectErrorAt(ErrorOf([&] { ReadTet(q); }), q, 7, "uses vertex 1 twice");
}

TEST_F(MeshIoErrors, LabelFileTooShortOrTooLong) {
  const std::string p = WriteText("t.tet", kUnitTet);
  const std::string l0 = WriteText("empty.txt", "");
  ExpectErrorAt(ErrorOf([&] { ReadTet(p, l0); }), l0, 1, "file ends after 0 of 1 labels");
  const std::string l2 = WriteText("two.txt", "1\n2\n");
  ExpectErrorAt(ErrorOf([&] { ReadTet(p, l2); }), l2, 2, "only 1 tets");
  const std::string lx = WriteText("bad.txt", "one\n");
  ExpectErrorAt(ErrorOf([&] { ReadTet(p, lx); }), lx, 1, "non-numeric token 'one'");
  // The real label file does not match a one-tet mesh.
  const std::string real = std::string(SOFTKIN_THESIS_DATA) + "/finger_chamber1_labels.txt";
  ExpectErrorAt(ErrorOf([&] { ReadTet(p, real); }), real, 2, "only 1 tets");
  // And a label file with too few labels for the real mesh names its last line + 1.
  std::string few;
  for (int i = 0; i < 1000; ++i) few += "1\n";
  const std::string lf = WriteText("few.txt", few);
  ExpectErrorAt(
      ErrorOf([&] { ReadTet(std::string(SOFTKIN_THESIS_DATA) + "/finger_chamber1.tet", lf); }), lf,
      1001, "file ends after 1000 of 94240 labels");
}

TEST_F(MeshIoErrors, NonNumericTokenAndWrongCounts) {
  const std::string p =
      WriteText("t.tet", "4 vertices\n1 tets\n0 0 0\n0 abc 0\n0 1 0\n0 0 1\n4 0 1 2 3\n");
  ExpectErrorAt(ErrorOf([&] { ReadTet(p); }), p, 4, "non-numeric token 'abc'");
  const std::string q =
      WriteText("g.tet", "4 vertices\n1 tets\n0 0 0\n1 0 0\n0 1 0 7\n0 0 1\n4 0 1 2 3\n");
  ExpectErrorAt(ErrorOf([&] { ReadTet(q); }), q, 5, "unexpected extra token '7'");
  const std::string r =
      WriteText("s.tet", "4 vertices\n1 tets\n0 0 0\n1 0 0\n0 1 0\n0 0 1\n4 0 1 2\n");
  ExpectErrorAt(ErrorOf([&] { ReadTet(r); }), r, 7, "line ends before a vertex index");
  const std::string h = WriteText("h.tet", "4 points\n1 tets\n");
  ExpectErrorAt(ErrorOf([&] { ReadTet(h); }), h, 1, "'<N> vertices'");
  const std::string k =
      WriteText("k.tet", "4 vertices\n1 tets\n0 0 0\n1 0 0\n0 1 0\n0 0 1\n3 0 1 2\n");
  ExpectErrorAt(ErrorOf([&] { ReadTet(k); }), k, 7, "element with 3 vertices");
  const std::string x =
      WriteText("x.tet", "4 vertices\n1 tets\n0 0 0\n1 0 0\n0 1 0\n0 0 1\n4 0 1.5 2 3\n");
  ExpectErrorAt(ErrorOf([&] { ReadTet(x); }), x, 7, "non-numeric token '1.5'");
  // A huge declared count is a truncated file, not an allocation failure.
  const std::string big = WriteText("big.tet", "2000000000 vertices\n1 tets\n0 0 0\n");
  ExpectErrorAt(ErrorOf([&] { ReadTet(big); }), big, 4, "file ends after 1 of 2000000000 vertices");
  // Missing files and unknown extensions.
  EXPECT_NE(ErrorOf([&] { ReadTet(Path("missing.tet")); }).find("missing.tet: cannot open"),
            std::string::npos);
  EXPECT_NE(ErrorOf([&] { ReadMesh(Path("a.stl")); }).find("unknown mesh file extension"),
            std::string::npos);
}

TEST_F(MeshIoErrors, GmshMissingEndElements) {
  WriteGmsh(Path("ok.msh"), MixedMesh(), "2.2");
  std::string text = ReadText(Path("ok.msh"));
  const auto pos = text.find("$EndElements\n");
  ASSERT_NE(pos, std::string::npos);
  text.erase(pos);
  const int eof_line = static_cast<int>(std::count(text.begin(), text.end(), '\n')) + 1;
  const std::string p = WriteText("noend.msh", text);
  ExpectErrorAt(ErrorOf([&] { ReadGmsh(p); }), p, eof_line, "file ends inside $Elements");
  // Same for 4.1.
  WriteGmsh(Path("ok41.msh"), MixedMesh(), "4.1");
  text = ReadText(Path("ok41.msh"));
  text.erase(text.find("$EndElements\n"));
  const std::string q = WriteText("noend41.msh", text);
  ExpectErrorAt(ErrorOf([&] { ReadGmsh(q); }), q,
                static_cast<int>(std::count(text.begin(), text.end(), '\n')) + 1, "$EndElements");
}

TEST_F(MeshIoErrors, GmshOtherProblems) {
  const std::string head = "$MeshFormat\n2.2 0 8\n$EndMeshFormat\n";
  const std::string nodes = "$Nodes\n4\n1 0 0 0\n2 1 0 0\n3 0 1 0\n4 0 0 1\n$EndNodes\n";
  // binary
  const std::string b = WriteText("bin.msh", "$MeshFormat\n2.2 1 8\n");
  ExpectErrorAt(ErrorOf([&] { ReadGmsh(b); }), b, 2, "binary .msh 2.2 file");
  // version 4.0
  const std::string v = WriteText("v40.msh", "$MeshFormat\n4 0 8\n$EndMeshFormat\n");
  ExpectErrorAt(ErrorOf([&] { ReadGmsh(v); }), v, 2, "unsupported .msh version 4");
  // element count larger than the element lines: the section ends early
  const std::string t =
      WriteText("short.msh", head + nodes + "$Elements\n2\n1 4 2 5 5 1 2 3 4\n$EndElements\n");
  ExpectErrorAt(ErrorOf([&] { ReadGmsh(t); }), t, 14,
                "section $Elements ends before element 2 of 2");
  // unknown node tag
  const std::string n =
      WriteText("tag.msh", head + nodes + "$Elements\n1\n1 4 2 5 5 1 2 3 9\n$EndElements\n");
  ExpectErrorAt(ErrorOf([&] { ReadGmsh(n); }), n, 13, "node tag 9 is not defined");
  // unsupported and unknown 3D types
  const std::string h =
      WriteText("hex.msh", head + nodes + "$Elements\n1\n1 5 0 1 2 3 4 1 2 3 4\n$EndElements\n");
  ExpectErrorAt(ErrorOf([&] { ReadGmsh(h); }), h, 13,
                "unsupported element type 5 (8-node hexahedron)");
  const std::string u =
      WriteText("unk.msh", head + nodes + "$Elements\n1\n1 77 0 1 2 3 4\n$EndElements\n");
  ExpectErrorAt(ErrorOf([&] { ReadGmsh(u); }), u, 13, "unknown element type 77");
  // missing $EndNodes
  const std::string e = WriteText("noendnodes.msh", head + "$Nodes\n1\n1 0 0 0\n$Elements\n");
  ExpectErrorAt(ErrorOf([&] { ReadGmsh(e); }), e, 7, "found '$Elements'");
  // NaN node
  const std::string q =
      WriteText("nan.msh", head +
                               "$Nodes\n4\n1 0 0 0\n2 1 0 0\n3 0 NaN 0\n4 0 0 "
                               "1\n$EndNodes\n$Elements\n1\n1 4 0 1 2 3 4\n$EndElements\n");
  ExpectErrorAt(ErrorOf([&] { ReadGmsh(q); }), q, 8, "non-finite");
  // duplicate node tag
  const std::string d = WriteText("dup.msh", head + "$Nodes\n2\n1 0 0 0\n1 1 0 0\n$EndNodes\n");
  ExpectErrorAt(ErrorOf([&] { ReadGmsh(d); }), d, 7, "node tag 1 is defined twice");
  // not a gmsh file
  const std::string x = WriteText("x.msh", "hello\n");
  ExpectErrorAt(ErrorOf([&] { ReadGmsh(x); }), x, 1, "$MeshFormat");
}

TEST_F(MeshIoErrors, VtkUnknownCellType) {
  WriteVtk(Path("ok.vtk"), MixedMesh());
  std::string text = ReadText(Path("ok.vtk"));
  const auto ct = text.find("CELL_TYPES 3\n");
  ASSERT_NE(ct, std::string::npos);
  const int types_line = static_cast<int>(std::count(text.begin(), text.begin() + ct, '\n')) + 1;
  // Cell types are 13, 13, 10: make the third one unknown (99), then a hexahedron (12).
  const auto third = text.find("10\n", ct + 13);
  ASSERT_NE(third, std::string::npos);
  std::string bad = text;
  bad.replace(third, 2, "99");
  const std::string p = WriteText("unknown.vtk", bad);
  ExpectErrorAt(ErrorOf([&] { ReadVtk(p); }), p, types_line + 3, "unknown cell type 99");
  bad = text;
  bad.replace(third, 2, "12");
  const std::string q = WriteText("hex.vtk", bad);
  ExpectErrorAt(ErrorOf([&] { ReadVtk(q); }), q, types_line + 3,
                "unsupported cell type 12 (hexahedron)");
}

TEST_F(MeshIoErrors, VtkOtherProblems) {
  const std::string head = "# vtk DataFile Version 3.0\nt\nASCII\nDATASET UNSTRUCTURED_GRID\n";
  const std::string pts = "POINTS 4 double\n0 0 0\n1 0 0\n0 1 0\n0 0 1\n";
  const std::string b = WriteText("bin.vtk", "# vtk DataFile Version 3.0\nt\nUTF8\n");
  ExpectErrorAt(ErrorOf([&] { ReadVtk(b); }), b, 3, "ASCII or BINARY");
  const std::string t = WriteText("trunc.vtk", head + "POINTS 4 double\n0 0 0\n1 0 0\n");
  ExpectErrorAt(ErrorOf([&] { ReadVtk(t); }), t, 8, "file ends after 2 of 4 points");
  const std::string r =
      WriteText("range.vtk", head + pts + "CELLS 1 5\n4 0 1 2 4\nCELL_TYPES 1\n10\n");
  ExpectErrorAt(ErrorOf([&] { ReadVtk(r); }), r, 11, "refers to point 4, which is out of range");
  const std::string k =
      WriteText("count.vtk", head + pts + "CELLS 1 6\n5 0 1 2 3 0\nCELL_TYPES 1\n10\n");
  ExpectErrorAt(ErrorOf([&] { ReadVtk(k); }), k, 11, "(tetra) has 5 points");
  const std::string n = WriteText(
      "noname.vtk",
      head + pts + "CELLS 1 5\n4 0 1 2 3\nCELL_TYPES 1\n10\nCELL_DATA 1\nSCALARS mat int\n3\n");
  EXPECT_EQ(ReadVtk(n).elements[0].region, 3);  // no LOOKUP_TABLE, picked as first integer array
  const std::string msg = ErrorOf([&] { ReadVtk(n, "region"); });
  EXPECT_NE(msg.find("no single-component cell data array named 'region'"), std::string::npos)
      << msg;
  EXPECT_NE(msg.find("one of: mat"), std::string::npos) << msg;
  const std::string c =
      WriteText("cd.vtk", head + pts + "CELLS 1 5\n4 0 1 2 3\nCELL_TYPES 1\n10\nCELL_DATA 2\n");
  ExpectErrorAt(ErrorOf([&] { ReadVtk(c); }), c, 14, "CELL_DATA count 2");
}

TEST_F(MeshIoErrors, WritersNamePathThatCannotBeOpened) {
  const std::string bad = Path("no_such_folder/out");
  const Mesh m = BlockMesh();
  for (const auto& f : std::vector<std::function<void()>>{
           [&] { WriteTet(bad + ".tet", m); }, [&] { WriteTetGen(bad, m); },
           [&] { WriteGmsh(bad + ".msh", m); }, [&] { WriteVtk(bad + ".vtk", m); },
           [&] { WriteVtu(bad + ".vtu", m, m.vertices); },
           [&] {
             WritePvd(bad + ".pvd", {{0.0, "a.vtu"}});
           },
           [&] { WriteSurfaceObj(bad + ".obj", m, m.vertices); }}) {
    const std::string msg = ErrorOf(f);
    EXPECT_NE(msg.find(bad), std::string::npos) << msg;
    EXPECT_NE(msg.find("cannot write (No such file or directory)"), std::string::npos) << msg;
  }
}

// ---------------------------------------------------------------------------------------------
// format details

TEST_F(MeshIoGmsh, Reads22WithLowerDimensionalElementsAndSparseTags) {
  const std::string p =
      WriteText("a.msh",
                "$MeshFormat\n2.2 0 8\n$EndMeshFormat\n"
                "$PhysicalNames\n1\n3 7 \"body\"\n$EndPhysicalNames\n"
                "$Nodes\n5\n1 0 0 0\n2 1 0 0\n3 0 1 0\n4 0 0 1\n70 0 0 -1\n$EndNodes\n"
                "$Elements\n4\n"
                "1 15 2 0 1 1\n"
                "2 2 2 0 5 1 2 3\n"
                "3 4 2 7 1 1 2 3 4\n"
                "4 4 0 1 3 2 70\n"
                "$EndElements\n");
  MeshReport r;
  const Mesh m = ReadGmsh(p, &r);
  ASSERT_EQ(m.num_vertices(), 5);
  ASSERT_EQ(m.num_elements(), 2);
  EXPECT_EQ(m.elements[0].region, 7);
  EXPECT_EQ(m.elements[1].region, 0);
  EXPECT_EQ(m.elements[1].v[3], 4);
  EXPECT_EQ(m.vertices(4, 2), -1.0);
  EXPECT_EQ(r.flipped, 0);
  EXPECT_TRUE(r.warnings.empty());
}

TEST_F(MeshIoGmsh, Reads41EntitiesBlocksAndNonContiguousTags) {
  const std::string p = WriteText("b.msh",
                                  "$MeshFormat\n4.1 0 8\n$EndMeshFormat\n"
                                  "$Entities\n1 0 1 2\n"
                                  "1 0 0 0 0\n"
                                  "1 0 0 0 1 1 0 1 5 0\n"
                                  "10 0 0 0 1 1 1 1 42 1 1\n"
                                  "11 0 0 -1 1 1 0 0 0\n"
                                  "$EndEntities\n"
                                  "$Nodes\n3 6 10 60\n"
                                  "3 10 0 3\n10\n20\n30\n0 0 0\n1 0 0\n0 1 0\n"
                                  "3 11 0 2\n40\n50\n0 0 1\n0 0 -1\n"
                                  "2 1 1 1\n60\n0.5 0.5 0 0.25 0.75\n"
                                  "$EndNodes\n"
                                  "$Elements\n3 3 1 3\n"
                                  "2 1 2 1\n1 10 20 30\n"
                                  "3 10 4 1\n2 10 20 30 40\n"
                                  "3 11 4 1\n3 10 30 20 50\n"
                                  "$EndElements\n");
  MeshReport r;
  const Mesh m = ReadGmsh(p, &r);
  ASSERT_EQ(m.num_vertices(), 5);
  ASSERT_EQ(m.num_elements(), 2);
  EXPECT_EQ(m.elements[0].region, 42);
  EXPECT_EQ(m.elements[1].region, 0);
  EXPECT_EQ((std::array<int, 4>{m.elements[0].v[0], m.elements[0].v[1], m.elements[0].v[2],
                                m.elements[0].v[3]}),
            (std::array<int, 4>{0, 1, 2, 3}));
  EXPECT_EQ((std::array<int, 4>{m.elements[1].v[0], m.elements[1].v[1], m.elements[1].v[2],
                                m.elements[1].v[3]}),
            (std::array<int, 4>{0, 2, 1, 4}));
  EXPECT_EQ(r.flipped, 0);
  EXPECT_EQ(r.unused_vertices, 1);  // the parametric surface node, dropped
  EXPECT_EQ(r.source_vertex, (std::vector<int>{0, 1, 2, 3, 4}));
}

TEST_F(MeshIoTetGen, ZeroBasedWithAttributesMarkersAndComments) {
  WriteText("z.node",
            "# points with one attribute and a boundary marker\n"
            "4 3 1 1\n"
            "0 0 0 0 5.5 1\n"
            "1 1 0 0 5.5 1   # trailing comment\n"
            "\n"
            "2 0 1 0 5.5 0\n"
            "3 0 0 1 5.5 1\n");
  WriteText("z.ele", "1 4 2\n0 0 2 1 3 3 9\n");
  MeshReport r;
  const Mesh m = ReadTetGen(Path("z"), &r);
  ASSERT_EQ(m.num_vertices(), 4);
  ASSERT_EQ(m.num_elements(), 1);
  EXPECT_EQ(m.elements[0].region, 3);
  EXPECT_EQ(r.flipped, 1);  // (0,2,1,3) is negatively oriented
  EXPECT_GT(SignedVolume(m.elements[0], m.vertices), 0);
  // No attributes: region 0.
  WriteText("z.ele", "1 4\n0 0 1 2 3\n");
  EXPECT_EQ(ReadTetGen(Path("z"), &r).elements[0].region, 0);
}

TEST_F(MeshIoTetGen, Errors) {
  WriteText("q.node", "4 3 0 0\n1 0 0 0\n2 1 0 0\n3 0 1 0\n4 0 0 1\n");
  WriteText("q.ele", "1 5 0\n1 1 2 3 4 5\n");
  std::string msg = ErrorOf([&] { ReadTetGen(Path("q")); });
  ExpectErrorAt(msg, Path("q.ele"), 1, "5 nodes per tetrahedron");
  EXPECT_NE(msg.find("10 (tetgen -o2"), std::string::npos) << msg;
  WriteText("q.ele", "1 4 0\n1 1 2 3 5\n");
  ExpectErrorAt(ErrorOf([&] { ReadTetGen(Path("q")); }), Path("q.ele"), 2,
                "node index 5 is out of range");
  WriteText("q.ele", "2 4 0\n1 1 2 3 4\n");
  ExpectErrorAt(ErrorOf([&] { ReadTetGen(Path("q")); }), Path("q.ele"), 3,
                "file ends after 1 of 2 tetrahedra");
  WriteText("q.node", "4 3 0 0\n1 0 0 0\n2 1 0 0\n3 0 1 0\n5 0 0 1\n");
  ExpectErrorAt(ErrorOf([&] { ReadTetGen(Path("q")); }), Path("q.node"), 5, "point index 5");
  WriteText("q.node", "4 3 0 0\n1 0 0 0\n2 1 0 0\n3 0 1 0\n4 0 0 -nan\n");
  ExpectErrorAt(ErrorOf([&] { ReadTetGen(Path("q")); }), Path("q.node"), 5, "non-finite");
  EXPECT_NE(ErrorOf([&] { ReadTetGen(Path("none")); }).find("none.node: cannot open"),
            std::string::npos);
}

TEST_F(MeshIoVtk, ReadsVtk51OffsetsConnectivityAndFieldData) {
  const std::string p =
      WriteText("v51.vtk",
                "# vtk DataFile Version 5.1\nvtk output\nASCII\nDATASET UNSTRUCTURED_GRID\n"
                "POINTS 7 float\n0 0 0 1 0 0 0 1 0\n0 0 1 1 0 1 0 1 1\n0.3 0.3 2\n"
                "METADATA\nINFORMATION 0\n\n"
                "CELLS 4 13\nOFFSETS vtktypeint64\n0 3 9 13\n"
                "CONNECTIVITY vtktypeint64\n0 1 2\n0 2 1 3 5 4\n3 4 5 6\n"
                "CELL_TYPES 3\n5\n13\n10\n\n"
                "CELL_DATA 3\nFIELD FieldData 2\n"
                "quality 1 3 double\n0.5 0.5 0.5\n"
                "mat 1 3 int\n9 4 5\n"
                "POINT_DATA 7\nVECTORS v float\n"
                "0 0 0 0 0 0 0 0 0 0 0 0 0 0 0 0 0 0 0 0 0\n");
  MeshReport r;
  const Mesh m = ReadVtk(p, "", &r);
  ASSERT_EQ(m.num_vertices(), 7);
  ASSERT_EQ(m.num_elements(), 2);  // the triangle is skipped
  EXPECT_EQ(m.elements[0].type, ElementType::Prism);
  EXPECT_EQ(m.elements[0].region, 4);
  EXPECT_EQ(m.elements[0].v, (std::array<int, 6>{0, 1, 2, 3, 4, 5}));  // converted from VTK's wedge
  EXPECT_EQ(m.elements[1].type, ElementType::Tet);
  EXPECT_EQ(m.elements[1].region, 5);
  EXPECT_EQ(r.flipped, 0);
  const std::string msg = ErrorOf([&] { ReadVtk(p, "quality"); });
  EXPECT_NE(msg.find("non-integer region"), std::string::npos) << msg;
}

// ---------------------------------------------------------------------------------------------
// warnings and notes

TEST_F(MeshIoReport, UnusedVertexAndDisconnectedTets) {
  const std::string p =
      WriteText("two.tet",
                "9 vertices\n2 tets\n"
                "0 0 0\n1 0 0\n0 1 0\n0 0 1\n"
                "5 0 0\n6 0 0\n5 1 0\n5 0 1\n"
                "9 9 9\n"
                "4 0 1 2 3\n4 4 6 5 7\n");  // the second tet is negatively oriented
  MeshReport r;
  const Mesh m = ReadTet(p, "", &r);
  EXPECT_EQ(m.num_vertices(), 8);  // the unused vertex is dropped
  EXPECT_EQ(r.unused_vertices, 1);
  EXPECT_EQ(r.components, 2);
  ASSERT_EQ(r.notes.size(), 2u);
  EXPECT_NE(r.notes[0].find("dropped 1 of 9 vertices that no element uses"), std::string::npos)
      << r.notes[0];
  EXPECT_NE(r.notes[0].find("vertex 8"), std::string::npos) << r.notes[0];
  ASSERT_EQ(r.warnings.size(), 1u);
  EXPECT_NE(r.warnings[0].find("2 disconnected parts"), std::string::npos) << r.warnings[0];
  int count = 0;
  const std::vector<int> comp = ElementComponents(m, &count);
  EXPECT_EQ(count, 2);
  EXPECT_EQ(comp, (std::vector<int>{0, 1}));

  // Without a report the messages go to stderr.
  ::testing::internal::CaptureStderr();
  ReadTet(p);
  const std::string err = ::testing::internal::GetCapturedStderr();
  EXPECT_NE(err.find("softkin: note: " + p + ": dropped 1 of 9 vertices"), std::string::npos)
      << err;
  EXPECT_NE(err.find("softkin: warning: " + p + ": the mesh has 2 disconnected parts"),
            std::string::npos)
      << err;
  EXPECT_NE(err.find("softkin: note: " + p + ": flipped"), std::string::npos)
      << err;  // tet 2 is negative
}

// ---------------------------------------------------------------------------------------------
// ParaView output and strain

/// Checks that tags nest properly (<a>..</a>, <b/>, <?..?>); returns the tag names seen.
bool XmlTagsBalanced(const std::string& text, std::map<std::string, int>* counts) {
  std::vector<std::string> stack;
  for (std::size_t i = text.find('<'); i != std::string::npos; i = text.find('<', i + 1)) {
    const std::size_t j = text.find('>', i);
    if (j == std::string::npos) return false;
    const std::string tag = text.substr(i + 1, j - i - 1);
    if (tag.empty()) return false;
    if (tag[0] == '?') continue;
    if (tag[0] == '/') {
      if (stack.empty() || stack.back() != tag.substr(1)) return false;
      stack.pop_back();
      continue;
    }
    const std::string name = tag.substr(0, tag.find_first_of(" \n/"));
    ++(*counts)[name];
    if (tag.back() != '/') stack.push_back(name);
  }
  return stack.empty();
}

std::string Attribute(const std::string& text, const std::string& name) {
  const std::string key = name + "=\"";
  const auto p = text.find(key);
  if (p == std::string::npos) return "";
  return text.substr(p + key.size(), text.find('"', p + key.size()) - p - key.size());
}

/// The values of the DataArray named `name`.
std::vector<double> ArrayValues(const std::string& text, const std::string& name) {
  const auto p = text.find("Name=\"" + name + "\"");
  if (p == std::string::npos) return {};
  const auto b = text.find('>', p) + 1;
  const auto e = text.find("</DataArray>", b);
  std::istringstream in(text.substr(b, e - b));
  std::vector<double> v;
  for (double x; in >> x;) v.push_back(x);
  return v;
}

TEST_F(MeshIoVtu, WritesArraysAndStrain) {
  const Mesh m = MixedMesh();
  WriteVtu(Path("rest.vtu"), m, m.vertices);
  const std::string text = ReadText(Path("rest.vtu"));
  std::map<std::string, int> counts;
  EXPECT_TRUE(XmlTagsBalanced(text, &counts)) << text;
  EXPECT_EQ(counts["VTKFile"], 1);
  EXPECT_EQ(counts["Piece"], 1);
  EXPECT_EQ(counts["DataArray"], 8);
  EXPECT_EQ(Attribute(text, "NumberOfPoints"), "9");
  EXPECT_EQ(Attribute(text, "NumberOfCells"), "3");
  EXPECT_EQ(ArrayValues(text, "region"), (std::vector<double>{1, 2, 7}));
  EXPECT_EQ(ArrayValues(text, "element_type"), (std::vector<double>{13, 13, 10}));
  const std::vector<double> rest_strain = ArrayValues(text, "strain");
  ASSERT_EQ(rest_strain.size(), 3u);
  for (double s : rest_strain) EXPECT_NEAR(s, 0.0, 1e-12);
  EXPECT_EQ(ArrayValues(text, "displacement"), std::vector<double>(27, 0.0));
  EXPECT_EQ(ArrayValues(text, "offsets"), (std::vector<double>{6, 12, 16}));
  EXPECT_EQ(ArrayValues(text, "connectivity").size(), 16u);
  EXPECT_EQ(ArrayValues(text, "Points").size(), 27u);

  // Uniform stretch F = diag(1.1, 1, 1): strain = ||diag(0.21, 0, 0)|| / 2 = 0.105 everywhere.
  Eigen::MatrixX3d X = m.vertices;
  X.col(0) *= 1.1;
  for (double s : ElementStrain(m, X)) EXPECT_NEAR(s, 0.105, 1e-12);
  WriteVtu(Path("stretch.vtu"), m, X);
  const std::string t2 = ReadText(Path("stretch.vtu"));
  for (double s : ArrayValues(t2, "strain")) EXPECT_NEAR(s, 0.105, 1e-12);
  const std::vector<double> d = ArrayValues(t2, "displacement");
  ASSERT_EQ(d.size(), 27u);
  for (int j = 0; j < 9; ++j) {
    EXPECT_NEAR(d[3 * j], 0.1 * m.vertices(j, 0), 1e-12);
    EXPECT_EQ(d[3 * j + 1], 0.0);
  }
  // A rigid rotation has no strain.
  const Eigen::Matrix3d R =
      Eigen::AngleAxisd(0.7, Eigen::Vector3d(1, 2, 3).normalized()).toRotationMatrix();
  const Eigen::MatrixX3d Y = (m.vertices * R.transpose()).rowwise() + Eigen::RowVector3d(5, -2, 1);
  for (double s : ElementStrain(m, Y)) EXPECT_NEAR(s, 0.0, 1e-12);
  // Region 7 resting in the stretched shape (a Scene's region_rest, e.g. a remeshed chamber):
  // its element has no strain at X, the others keep theirs, and it is written so.
  const std::vector<double> own = ElementStrain(m, X, {7}, &X);
  ASSERT_EQ(own.size(), 3u);
  EXPECT_NEAR(own[0], 0.105, 1e-12);
  EXPECT_NEAR(own[1], 0.105, 1e-12);
  EXPECT_NEAR(own[2], 0.0, 1e-12);
  WriteVtu(Path("own_rest.vtu"), m, X, {7}, &X);
  const std::vector<double> own_written = ArrayValues(ReadText(Path("own_rest.vtu")), "strain");
  ASSERT_EQ(own_written.size(), 3u);
  EXPECT_NEAR(own_written[2], 0.0, 1e-12);
  EXPECT_THROW(ElementStrain(m, X, {7}, nullptr), std::invalid_argument);
  const Eigen::MatrixX3d short_rest = X.topRows(3);
  EXPECT_THROW(ElementStrain(m, X, {7}, &short_rest), std::invalid_argument);
  // Wrong number of rows is rejected.
  EXPECT_NE(ErrorOf([&] { WriteVtu(Path("bad.vtu"), m, X.topRows(3)); }).find("bad.vtu"),
            std::string::npos);
  // A state too large for double precision (a solve that ran away): the strain is marked -1,
  // never written as NaN, and the solve's outcome is in the field data.
  const Eigen::MatrixX3d huge = 1e200 * X;
  const VtuSolveInfo info{false, 10000, 0.25, 3};
  WriteVtu(Path("huge.vtu"), m, huge, {}, nullptr, &info);
  const std::string t3 = ReadText(Path("huge.vtu"));
  EXPECT_EQ(t3.find("nan"), std::string::npos);
  for (double s : ArrayValues(t3, "strain")) EXPECT_EQ(s, -1.0);
  EXPECT_EQ(ArrayValues(t3, "converged"), std::vector<double>{0.0});
  EXPECT_EQ(ArrayValues(t3, "iterations"), std::vector<double>{10000.0});
  EXPECT_EQ(ArrayValues(t3, "residual_ratio"), std::vector<double>{0.25});
  EXPECT_EQ(ArrayValues(t3, "inverted_elements"), std::vector<double>{3.0});
  EXPECT_LT(t3.find("<FieldData>"), t3.find("<Piece"));
  EXPECT_EQ(t2.find("<FieldData>"), std::string::npos);  // no solve, no field data
}

TEST_F(MeshIoVtu, PvdListsSteps) {
  WritePvd(Path("run.pvd"), {{0.0, "frame_0000.vtu"}, {0.5, "frames/a&b.vtu"}});
  const std::string text = ReadText(Path("run.pvd"));
  std::map<std::string, int> counts;
  EXPECT_TRUE(XmlTagsBalanced(text, &counts)) << text;
  EXPECT_EQ(counts["DataSet"], 2);
  EXPECT_NE(text.find("type=\"Collection\""), std::string::npos);
  EXPECT_NE(text.find("timestep=\"0.5\""), std::string::npos) << text;
  EXPECT_NE(text.find("file=\"frame_0000.vtu\""), std::string::npos) << text;
  EXPECT_NE(text.find("file=\"frames/a&amp;b.vtu\""), std::string::npos) << text;
}

// ---------------------------------------------------------------------------------------------
// boundary surface

struct Obj {
  std::vector<Eigen::Vector3d> v;
  std::vector<std::vector<int>> f;  // 0-based
};

Obj ReadObj(const std::string& p) {
  Obj o;
  std::ifstream in(p);
  for (std::string line; std::getline(in, line);) {
    std::istringstream ss(line);
    std::string k;
    ss >> k;
    if (k == "v") {
      Eigen::Vector3d x;
      ss >> x(0) >> x(1) >> x(2);
      o.v.push_back(x);
    } else if (k == "f") {
      std::vector<int> face;
      for (int i; ss >> i;) face.push_back(i - 1);
      o.f.push_back(face);
    }
  }
  return o;
}

/// For a convex solid: every face normal points away from the centre; returns the faces that don't.
int InwardFaces(const Obj& o, const Eigen::Vector3d& centre) {
  int bad = 0;
  for (const auto& f : o.f) {
    Eigen::Vector3d n = Eigen::Vector3d::Zero(), c = Eigen::Vector3d::Zero();
    for (std::size_t i = 0; i < f.size(); ++i) {
      n += o.v[f[i]].cross(o.v[f[(i + 1) % f.size()]]);  // Newell
      c += o.v[f[i]];
    }
    c /= static_cast<double>(f.size());
    bad += !(n.dot(c - centre) > 0);
  }
  return bad;
}

TEST_F(MeshIoObj, SingleTetHasFourOutwardFaces) {
  Mesh m;
  m.vertices.resize(5, 3);
  m.vertices << 0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1, 7, 7, 7;  // vertex 4 unused
  m.elements.push_back(Tet(0, 2, 1, 3, 0));
  ValidateAndOrient(m, "tet");
  WriteSurfaceObj(Path("tet.obj"), m, m.vertices);
  const Obj o = ReadObj(Path("tet.obj"));
  EXPECT_EQ(o.v.size(), 4u);  // only used vertices
  ASSERT_EQ(o.f.size(), 4u);
  for (const auto& f : o.f) EXPECT_EQ(f.size(), 3u);
  EXPECT_EQ(InwardFaces(o, Eigen::Vector3d(0.25, 0.25, 0.25)), 0);
}

TEST_F(MeshIoObj, BlockOfTwelveTetsHasTwentyBoundaryTriangles) {
  const Mesh m = BlockMesh();
  ASSERT_EQ(m.num_elements(), 12);
  WriteSurfaceObj(Path("block.obj"), m, m.vertices);
  const Obj o = ReadObj(Path("block.obj"));
  EXPECT_EQ(o.v.size(), 12u);
  EXPECT_EQ(o.f.size(), 20u);  // 10 unit squares x 2 triangles
  EXPECT_EQ(InwardFaces(o, Eigen::Vector3d(0.1, 0.05, 0.05)), 0);
  // At deformed positions the surface follows X.
  Eigen::MatrixX3d X = m.vertices;
  X.col(2) *= 2.0;
  WriteSurfaceObj(Path("block2.obj"), m, X);
  const Obj o2 = ReadObj(Path("block2.obj"));
  double zmax = 0;
  for (const auto& v : o2.v) zmax = std::max(zmax, v(2));
  EXPECT_DOUBLE_EQ(zmax, 0.2);
}

TEST_F(MeshIoObj, PrismsGiveTrianglesAndQuads) {
  Mesh one;
  one.vertices.resize(6, 3);
  one.vertices << 0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1, 1, 0, 1, 0, 1, 1;
  one.elements.push_back(Prism({{0, 1, 2, 3, 4, 5}}, 0));
  WriteSurfaceObj(Path("prism.obj"), one, one.vertices);
  Obj o = ReadObj(Path("prism.obj"));
  ASSERT_EQ(o.f.size(), 5u);
  int quads = 0;
  for (const auto& f : o.f) quads += f.size() == 4;
  EXPECT_EQ(quads, 3);
  EXPECT_EQ(InwardFaces(o, Eigen::Vector3d(1.0 / 3, 1.0 / 3, 0.5)), 0);
  // Two prisms sharing a quad and a tet on top: 2 + 2 + 4 quads... count faces by hand:
  // bottom 2 tris, top 1 tri (prism B) + 3 tet tris, 4 outer quads.
  const Mesh m = MixedMesh();
  WriteSurfaceObj(Path("mixed.obj"), m, m.vertices);
  o = ReadObj(Path("mixed.obj"));
  quads = 0;
  for (const auto& f : o.f) quads += f.size() == 4;
  EXPECT_EQ(quads, 4);
  EXPECT_EQ(o.f.size() - quads, 6u);
  EXPECT_EQ(o.v.size(), 9u);
}

}  // namespace
}  // namespace softkin
