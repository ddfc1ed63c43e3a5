// Tests of the mesh-input checks every reader shares (ValidateAndOrient, solver/mesh/mesh.hpp):
// unused vertices dropped with a map to file positions, duplicate elements, 1-based .tet files,
// cracks, folds versus all-reversed meshes, and second-order elements read by their corners;
// and the boundary vertices of a mesh (element_faces.hpp).
#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <chrono>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <functional>
#include <limits>
#include <sstream>
#include <string>
#include <vector>

#include "softkin/solver/mesh/element_faces.hpp"
#include "softkin/solver/mesh/io/mesh_io.hpp"
#include "softkin/solver/mesh/mesh_gen.hpp"
#include "softkin/solver/mesh/mesh.hpp"
#include "tests/solver/mesh/mesh_io_test_util.hpp"

namespace softkin {
namespace {

namespace fs = std::filesystem;

using mesh_test::ErrorOf;
using mesh_test::ExpectHas;
using MeshTopology = mesh_test::MeshIoTest;

bool AnyHas(const std::vector<std::string>& lines, const std::string& text) {
  for (const auto& l : lines)
    if (l.find(text) != std::string::npos) return true;
  return false;
}

/// 6 x the signed volume of the block tet with vertex ids v (id = x + 3 (y + 2 z)).
double Kuhn(const int v[4]) {
  Eigen::Vector3d p[4];
  for (int a = 0; a < 4; ++a) p[a] = Eigen::Vector3d(v[a] % 3, (v[a] / 3) % 2, v[a] / 6);
  return (p[1] - p[0]).cross(p[2] - p[0]).dot(p[3] - p[0]);
}

/// A 2 x 1 x 1 block of two unit cubes, 6 Kuhn tets each (conforming, positively oriented):
/// 12 vertices, 12 tets, written as .tet text with `pad_front` unused vertices before the real
/// ones and `pad_back` after them, and indices shifted by `shift`.
std::string BlockTet(int pad_front, int pad_back, int shift, bool reverse = false) {
  auto id = [](int x, int y, int z) { return x + 3 * (y + 2 * z); };
  std::ostringstream o;
  o << 12 + pad_front + pad_back << " vertices\n12 tets\n";
  for (int i = 0; i < pad_front; ++i) o << "50 50 " << i << "\n";
  for (int z = 0; z < 2; ++z)
    for (int y = 0; y < 2; ++y)
      for (int x = 0; x < 3; ++x) o << x << ' ' << y << ' ' << z << '\n';
  for (int i = 0; i < pad_back; ++i) o << "60 60 " << i << "\n";
  const int perms[6][3] = {{0, 1, 2}, {0, 2, 1}, {1, 0, 2}, {1, 2, 0}, {2, 0, 1}, {2, 1, 0}};
  for (int cube = 0; cube < 2; ++cube)
    for (const auto& p : perms) {
      int c[3] = {cube, 0, 0};
      int v[4] = {id(cube, 0, 0), 0, 0, 0};
      for (int s = 0; s < 3; ++s) {
        ++c[p[s]];
        v[s + 1] = id(c[0], c[1], c[2]);
      }
      // Orient positively (Kuhn tets alternate), then reverse all of them if asked.
      const bool negative = Kuhn(v) < 0;
      if (negative != reverse) std::swap(v[1], v[2]);
      o << "4";
      for (int a : v) o << ' ' << a + shift;
      o << '\n';
    }
  return o.str();
}

// ---- 1. unused vertices ----

TEST_F(MeshTopology, UnusedVerticesAreDroppedWithANoteAndAMap) {
  // Node tag 3 (the third node) is used by no element, as Gmsh leaves geometry points.
  const std::string p =
      WriteText("u.msh",
                "$MeshFormat\n2.2 0 8\n$EndMeshFormat\n"
                "$Nodes\n5\n1 0 0 0\n2 1 0 0\n3 9 9 9\n4 0 1 0\n5 0 0 1\n$EndNodes\n"
                "$Elements\n1\n1 4 2 7 1 1 2 4 5\n$EndElements\n");
  MeshReport r;
  const Mesh m = ReadGmsh(p, &r);
  ASSERT_EQ(m.num_vertices(), 4);
  EXPECT_EQ(r.unused_vertices, 1);
  EXPECT_EQ(r.source_vertex, (std::vector<int>{0, 1, 3, 4}));
  EXPECT_TRUE(AnyHas(r.notes, "dropped 1 of 5 vertices that no element uses")) << r.notes.size();
  EXPECT_TRUE(r.warnings.empty());
  EXPECT_EQ(m.vertices.row(2), Eigen::RowVector3d(0, 1, 0));
  EXPECT_NEAR(SignedVolume(m.elements[0], m.vertices), 1.0 / 6, 1e-15);
  for (int a = 0; a < 4; ++a) EXPECT_LT(m.elements[0].v[a], 4);
}

TEST(MeshTopologyValidate, UnusedNonFiniteVertexDoesNotFail) {
  Mesh m;
  m.vertices.resize(5, 3);
  m.vertices << 0, 0, 0, std::nan(""), 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1;
  Element e;
  e.v = {{0, 2, 3, 4, -1, -1}};
  m.elements.push_back(e);
  const MeshReport r = ValidateAndOrient(m, "nan.vtk");
  EXPECT_EQ(m.num_vertices(), 4);
  EXPECT_TRUE(m.vertices.allFinite());
  EXPECT_EQ(r.source_vertex, (std::vector<int>{0, 2, 3, 4}));
}

// ---- 2. duplicate elements ----

TEST_F(MeshTopology, DuplicateElementsFromOverlappingPhysicalGroupsAreRefused) {
  const std::string p = WriteText("dup.msh",
                                  "$MeshFormat\n2.2 0 8\n$EndMeshFormat\n"
                                  "$Nodes\n4\n1 0 0 0\n2 1 0 0\n3 0 1 0\n4 0 0 1\n$EndNodes\n"
                                  "$Elements\n2\n"
                                  "1 4 2 1 1 1 2 3 4\n"
                                  "2 4 2 2 1 2 1 3 4\n"
                                  "$EndElements\n");
  const std::string msg = ErrorOf([&] { ReadGmsh(p); });
  ExpectHas(msg, p + ":14:");
  ExpectHas(msg, "element 1 (tet, region 2) has the same vertices as element 0 (tet, region 1)");
  ExpectHas(msg, "(line 13)");
  ExpectHas(msg, "; expected each element once");
}

TEST(MeshTopologyValidate, DuplicatePairsIgnoreVertexOrder) {
  Mesh m;
  m.vertices.resize(4, 3);
  m.vertices << 0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1;
  Element e;
  e.v = {{0, 1, 2, 3, -1, -1}};
  m.elements = {e, e};
  m.elements[1].v = {{3, 2, 1, 0, -1, -1}};
  EXPECT_EQ(DuplicateElementPairs(m), (std::vector<std::pair<int, int>>{{0, 1}}));
  const std::string msg = ErrorOf([&] { ValidateAndOrient(m, "d.vtk"); });
  ExpectHas(msg, "d.vtk: element 1");
}

// ---- 3. 1-based .tet ----

TEST_F(MeshTopology, OneBasedTetUsingIndexNIsRefused) {
  const std::string p =
      WriteText("one.tet", "4 vertices\n1 tets\n0 0 0\n1 0 0\n0 1 0\n0 0 1\n4 1 2 3 4\n");
  const std::string msg = ErrorOf([&] { ReadTet(p); });
  ExpectHas(msg, p + ":7:");
  ExpectHas(msg, "looks 1-based");
  ExpectHas(msg, "; expected 0-based vertex indices");
}

TEST_F(MeshTopology, OneBasedTetWhoseLargestIndexExistsIsRefused) {
  // 1-based indices with a spare last vertex: every index is in range when read 0-based, but the
  // tets then connect the wrong vertices.
  const std::string p = WriteText("shift.tet", BlockTet(0, 1, 1));
  const std::string msg = ErrorOf([&] { ReadTet(p); });
  ExpectHas(msg, "looks 1-based");
  // The same tets after an unused vertex 0 are a valid 0-based file: vertex 0 is dropped.
  MeshReport r;
  const Mesh m = ReadTet(WriteText("pad.tet", BlockTet(1, 0, 1)), "", &r);
  EXPECT_EQ(m.num_vertices(), 12);
  EXPECT_EQ(r.unused_vertices, 1);
  EXPECT_EQ(r.source_vertex.front(), 1);
  EXPECT_EQ(r.flipped, 0);
}

// ---- 4. cracks, folds and reversed meshes ----

TEST_F(MeshTopology, CoincidentVerticesWarnWithTheirFilePositions) {
  // Two tets that would share the face (1, 2, 3); the second uses copies 5, 6, 7 of those
  // vertices, so the mesh is cut along the face.
  const std::string p = WriteText("crack.tet",
                                  "8 vertices\n2 tets\n"
                                  "0 0 0\n1 0 0\n0 1 0\n0 0 1\n1 1 1\n1 0 0\n0 1 0\n0 0 1\n"
                                  "4 0 1 2 3\n4 4 5 7 6\n");
  MeshReport r;
  ReadTet(p, "", &r);
  ASSERT_FALSE(r.warnings.empty());
  EXPECT_TRUE(AnyHas(r.warnings, "3 pairs of coincident vertices crack the mesh"));
  EXPECT_TRUE(AnyHas(r.warnings, "1/5, 2/6, 3/7")) << r.warnings[0];
}

TEST_F(MeshTopology, FoldedNeighboursAreRefusedNamingBothElements) {
  // Tets (0,1,2,3) and (0,1,2,4) share face (0,1,2); vertex 4 lies on the same side as vertex 3,
  // so the second tet overlaps the first whichever way it is oriented.
  const std::string p = WriteText("fold.tet",
                                  "5 vertices\n2 tets\n"
                                  "0 0 0\n1 0 0\n0 1 0\n0 0 1\n0.2 0.2 0.5\n"
                                  "4 0 1 2 3\n4 0 2 1 4\n");
  const std::string msg = ErrorOf([&] { ReadTet(p); });
  ExpectHas(msg, p + ":9:");
  ExpectHas(msg, "element 1 (tet, region 0) and element 0 (tet, region 0) (line 8)");
  ExpectHas(msg, "folds over itself");
  ExpectHas(msg, "; expected face neighbours on opposite sides");
}

TEST_F(MeshTopology, AllReversedMeshIsFlippedWithANote) {
  MeshReport r;
  const Mesh m = ReadTet(WriteText("rev.tet", BlockTet(0, 0, 0, /*reverse=*/true)), "", &r);
  EXPECT_EQ(r.flipped, 12);
  EXPECT_TRUE(AnyHas(r.notes, "flipped 12 of 12"));
  EXPECT_TRUE(r.warnings.empty());
  EXPECT_TRUE(FoldedElementPairs(m).empty());
  EXPECT_EQ(CountInvertedElements(m, m.vertices), 0);
}

// ---- 5. second-order elements ----

TEST_F(MeshTopology, GmshTet10IsReadByItsCorners) {
  std::ostringstream nodes;
  const double P[10][3] = {{0, 0, 0},     {1, 0, 0},   {0, 1, 0},   {0, 0, 1},     {0.5, 0, 0},
                           {0.5, 0.5, 0}, {0, 0.5, 0}, {0, 0, 0.5}, {0, 0.5, 0.5}, {0.5, 0, 0.5}};
  for (int i = 0; i < 10; ++i)
    nodes << i + 1 << ' ' << P[i][0] << ' ' << P[i][1] << ' ' << P[i][2] << '\n';
  const std::string p =
      WriteText("t10.msh", "$MeshFormat\n2.2 0 8\n$EndMeshFormat\n$Nodes\n10\n" + nodes.str() +
                               "$EndNodes\n$Elements\n1\n"
                               "1 11 2 3 1 1 2 3 4 5 6 7 8 9 10\n$EndElements\n");
  MeshReport r;
  const Mesh m = ReadGmsh(p, &r);
  ASSERT_EQ(m.num_vertices(), 4);
  EXPECT_EQ(m.elements[0].region, 3);
  EXPECT_NEAR(SignedVolume(m.elements[0], m.vertices), 1.0 / 6, 1e-15);
  ASSERT_EQ(r.notes.size(), 2u);
  ExpectHas(r.notes[0], "read 1 higher-order elements by their corner nodes");
  ExpectHas(r.notes[1], "dropped 6 of 10 vertices");
}

TEST_F(MeshTopology, TetGenO2AndVtkQuadraticTetAreReadByTheirCorners) {
  WriteText("q.node",
            "10 3 0 0\n1 0 0 0\n2 1 0 0\n3 0 1 0\n4 0 0 1\n5 0.5 0 0\n6 0.5 0.5 0\n"
            "7 0 0.5 0\n8 0 0 0.5\n9 0 0.5 0.5\n10 0.5 0 0.5\n");
  WriteText("q.ele", "1 10 1\n1 1 2 3 4 5 6 7 8 9 10 4\n");
  MeshReport r;
  Mesh m = ReadTetGen(Path("q"), &r);
  ASSERT_EQ(m.num_vertices(), 4);
  EXPECT_EQ(m.elements[0].region, 4);
  EXPECT_TRUE(AnyHas(r.notes, "higher-order elements by their corner nodes"));

  const std::string v =
      WriteText("q.vtk",
                "# vtk DataFile Version 3.0\nq\nASCII\nDATASET UNSTRUCTURED_GRID\n"
                "POINTS 10 double\n0 0 0 1 0 0 0 1 0 0 0 1 0.5 0 0 0.5 0.5 0\n"
                "0 0.5 0 0 0 0.5 0 0.5 0.5 0.5 0 0.5\n"
                "CELLS 1 11\n10 0 1 2 3 4 5 6 7 8 9\nCELL_TYPES 1\n24\n");
  m = ReadVtk(v, "", &r);
  ASSERT_EQ(m.num_vertices(), 4);
  EXPECT_NEAR(SignedVolume(m.elements[0], m.vertices), 1.0 / 6, 1e-15);
  EXPECT_TRUE(AnyHas(r.notes, "higher-order elements by their corner nodes"));
  EXPECT_EQ(r.unused_vertices, 6);
}

}  // namespace
}  // namespace softkin

namespace softkin {
namespace {

// BoundaryVertices (element_faces.hpp): on a 3 x 3 x 3 grid of cells (4^3 vertices) every vertex
// but the 2^3 inner ones is on the surface; on a grid of prisms, every vertex of a one-layer slab.
TEST(BoundaryVertices, GridInteriorVerticesAreLeftOut) {
  const Mesh m = VoxelTetMesh(Eigen::Vector3d::Zero(), 1.0, Eigen::Vector3i(3, 3, 3),
                              [](const Eigen::Vector3d&, const Eigen::Vector3i&) { return 0; });
  const std::vector<int> b = BoundaryVertices(m);
  EXPECT_EQ(b.size(), 64u - 8u);
  for (int v : b) {
    const Eigen::RowVector3d x = m.vertices.row(v);
    EXPECT_TRUE((x.array() == 0.0).any() || (x.array() == 3.0).any()) << x;
  }
  Mesh slab;
  slab.vertices.resize(6, 3);
  slab.vertices << 0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1, 1, 0, 1, 0, 1, 1;
  Element e;
  e.type = ElementType::Prism;
  e.v = {{0, 1, 2, 3, 4, 5}};
  slab.elements.push_back(e);
  EXPECT_EQ(BoundaryVertices(slab).size(), 6u);
}

}  // namespace
}  // namespace softkin
