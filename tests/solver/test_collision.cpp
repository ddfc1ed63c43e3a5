// Collision detection (solver/collision.hpp, thesis Sec. 3.2.2): obstacle surfaces (readers,
// closedness checks, inside and closest-point queries) and self-collision of a tet mesh (no false
// positives at rest, a built overlap found exactly).
#include "solver/collision.hpp"

#include "solver/mesh_gen.hpp"
#include "solver/robots.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <set>
#include <string>

namespace softkin {
namespace {

namespace fs = std::filesystem;

fs::path Temp(const std::string& name) {
  const fs::path d = fs::temp_directory_path() / "softkin_collision_test";
  fs::create_directories(d);
  return d / name;
}

void Write(const fs::path& p, const std::string& text) {
  std::ofstream o(p, std::ios::binary);
  o << text;
}

/// A unit cube [0, 2]^3 as OBJ text (quads, outward).
const char* kCubeObj =
    "# cube\nv 0 0 0\nv 2 0 0\nv 2 2 0\nv 0 2 0\nv 0 0 2\nv 2 0 2\nv 2 2 2\nv 0 2 2\n"
    "f 1 4 3 2\nf 5 6 7 8\nf 1 2 6 5\nf 2 3 7 6\nf 3 4 8 7\nf 4 1 5 8\n";

void ExpectError(const fs::path& p, const std::vector<std::string>& parts) {
  try {
    ReadSurfaceMesh(p.string());
    ADD_FAILURE() << "accepted " << p;
  } catch (const std::invalid_argument& e) {
    for (const auto& part : parts) EXPECT_NE(std::string(e.what()).find(part), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find(p.string()), std::string::npos) << e.what();
  }
}

TEST(Collision, ObstacleQueries) {
  const Obstacle box(MakeBoxSurface(Eigen::Vector3d(0, 0, 0), Eigen::Vector3d(4, 2, 2)));
  EXPECT_TRUE(box.Contains(Eigen::Vector3d(1, 1, 1)));
  EXPECT_FALSE(box.Contains(Eigen::Vector3d(5, 1, 1)));
  EXPECT_FALSE(box.Contains(Eigen::Vector3d(4, 1, 1)));  // on the surface is outside
  Eigen::Vector3d n;
  const Eigen::Vector3d c = box.ClosestPoint(Eigen::Vector3d(3.8, 1, 1.2), &n);
  EXPECT_TRUE(c.isApprox(Eigen::Vector3d(4, 1, 1.2), 1e-12)) << c.transpose();
  EXPECT_TRUE(n.isApprox(Eigen::Vector3d(1, 0, 0), 1e-12)) << n.transpose();
  const Obstacle cyl(MakeCylinderSurface(Eigen::Vector3d(0, 0, -5), Eigen::Vector3d(0, 0, 1), 3.0, 10.0, 64));
  EXPECT_TRUE(cyl.Contains(Eigen::Vector3d(2.9, 0, 0)));
  EXPECT_FALSE(cyl.Contains(Eigen::Vector3d(3.1, 0, 0)));
  // From the axis side, the closest point is on the 64-gon's side: between the apothem and the
  // radius from the axis, in the direction of the query.
  const Eigen::Vector3d cc = cyl.ClosestPoint(Eigen::Vector3d(2.0, 0, 0), &n);
  EXPECT_GE(cc.head<2>().norm(), 3.0 * std::cos(M_PI / 64) - 1e-9);
  EXPECT_LE(cc.head<2>().norm(), 3.0 + 1e-9);
  EXPECT_NEAR(cc.z(), 0.0, 1e-9);
  EXPECT_GT(cc.x(), 2.9);
  EXPECT_GT(n.x(), 0.99);
}

TEST(Collision, ReadersAcceptObjAndBothStlForms) {
  const fs::path obj = Temp("cube.obj");
  Write(obj, kCubeObj);
  const TriangleSurface s = ReadSurfaceMesh(obj.string());
  EXPECT_EQ(s.vertices.rows(), 8);
  EXPECT_EQ(s.faces.rows(), 12);
  EXPECT_TRUE(Obstacle(s).Contains(Eigen::Vector3d(1, 1, 1)));
  // The same cube as ASCII and binary STL (corner points repeated per facet, merged on reading).
  std::string ascii = "solid cube\n";
  std::string bin(80, ' ');
  const std::uint32_t n = static_cast<std::uint32_t>(s.faces.rows());
  bin.append(reinterpret_cast<const char*>(&n), 4);
  for (int f = 0; f < s.faces.rows(); ++f) {
    ascii += " facet normal 0 0 0\n  outer loop\n";
    char rec[50] = {};
    for (int k = 0; k < 3; ++k) {
      const Eigen::Vector3d p = s.vertices.row(s.faces(f, k));
      ascii += "   vertex " + std::to_string(p.x()) + " " + std::to_string(p.y()) + " " + std::to_string(p.z()) + "\n";
      const float xyz[3] = {float(p.x()), float(p.y()), float(p.z())};
      std::memcpy(rec + 12 + 12 * k, xyz, 12);
    }
    ascii += "  endloop\n endfacet\n";
    bin.append(rec, 50);
  }
  ascii += "endsolid cube\n";
  Write(Temp("cube_ascii.stl"), ascii);
  Write(Temp("cube_bin.stl"), bin);
  for (const char* name : {"cube_ascii.stl", "cube_bin.stl"}) {
    const TriangleSurface t = ReadSurfaceMesh(Temp(name).string());
    EXPECT_EQ(t.vertices.rows(), 8) << name;
    EXPECT_EQ(t.faces.rows(), 12) << name;
    EXPECT_FALSE(Obstacle(t).Contains(Eigen::Vector3d(3, 1, 1))) << name;
  }
  // An inside-out surface is turned outward.
  std::string flipped = kCubeObj;
  for (const char* from : {"f 1 4 3 2", "f 5 6 7 8", "f 1 2 6 5", "f 2 3 7 6", "f 3 4 8 7", "f 4 1 5 8"}) {
    std::string f(from);
    const std::string rev = "f " + std::string(1, f[8]) + " " + f[6] + " " + f[4] + " " + f[2];
    flipped.replace(flipped.find(f), f.size(), rev);
  }
  Write(Temp("flipped.obj"), flipped);
  EXPECT_TRUE(Obstacle(ReadSurfaceMesh(Temp("flipped.obj").string())).Contains(Eigen::Vector3d(1, 1, 1)));
}

TEST(Collision, CorruptedObstacleMeshesAreRejected) {
  std::string open = kCubeObj;
  open.erase(open.find("f 4 1 5 8"));  // a missing side
  Write(Temp("open.obj"), open);
  ExpectError(Temp("open.obj"), {"belongs to one triangle only", "closed surface"});
  std::string nan = kCubeObj;
  nan.replace(nan.find("v 2 2 2"), 7, "v 2 nan 2");
  Write(Temp("nan.obj"), nan);
  ExpectError(Temp("nan.obj"), {":8:", "expected 'v x y z' with three numbers"});
  // A binary STL with a NaN corner.
  std::string bin(80, ' ');
  const std::uint32_t one = 1;
  bin.append(reinterpret_cast<const char*>(&one), 4);
  char rec[50] = {};
  const float bad_xyz[3] = {0.0f, std::nanf(""), 1.0f};
  std::memcpy(rec + 12, bad_xyz, 12);
  bin.append(rec, 50);
  Write(Temp("nan.stl"), bin);
  ExpectError(Temp("nan.stl"), {"triangle 0 has a non-finite coordinate"});
  std::string bad = kCubeObj;
  bad.replace(bad.find("f 5 6 7 8"), 9, "f 5 6 7 18");
  Write(Temp("bad.obj"), bad);
  ExpectError(Temp("bad.obj"), {":11:", "face index 18 refers to no vertex"});
  Write(Temp("words.stl"), "solid x\n facet normal 0 0 1\n  outer loop\n   vertex 0 0\n");
  ExpectError(Temp("words.stl"), {":4:", "expected 'vertex x y z'"});
  Write(Temp("cube.ply"), "ply\n");
  ExpectError(Temp("cube.ply"), {"expected .obj or .stl"});
  ExpectError(Temp("absent.obj"), {"cannot open"});
}

TEST(Collision, NoSelfContactAtRestOrUnderRigidMotion) {
  for (const char* robot : {"pneumatic_finger", "three_chamber"})
    for (auto method : {SelfCollisionDetector::Method::kBoxIntersection, SelfCollisionDetector::Method::kAabbTree}) {
    const Scene s = MakeRobot(robot, robot == std::string("three_chamber") ? 3 : 5);
    SelfCollisionDetector d(s.mesh, method);
    EXPECT_GT(d.boundary_vertices().size(), 100u);
    EXPECT_TRUE(d.Detect().empty()) << robot;
    const Eigen::Matrix3d R = Eigen::AngleAxisd(0.7, Eigen::Vector3d(1, 2, 3).normalized()).toRotationMatrix();
    d.Update((s.mesh.vertices * R.transpose()).rowwise() + Eigen::RowVector3d(5, -2, 1));
    EXPECT_TRUE(d.Detect().empty()) << robot;
  }
}

TEST(Collision, BuiltOverlapIsFoundExactly) {
  // Two 2 x 2 x 2 blocks of 1 mm cells with a 1 mm gap (x in [0, 2] and [3, 5]); the second one
  // is then pushed 1.5 mm into the first. The second block's end face (now x = 1.5) lies in the
  // first block, and the first block's end face (x = 2) lies in the second: those 18 vertices, no
  // others. (They sit on faces shared by tets, which the test must not miss.)
  const Mesh m = VoxelTetMesh(Eigen::Vector3d::Zero(), 1.0, Eigen::Vector3i(5, 2, 2),
                              [](const Eigen::Vector3d&, const Eigen::Vector3i& c) { return c.x() == 2 ? -1 : 0; });
  for (auto method : {SelfCollisionDetector::Method::kBoxIntersection, SelfCollisionDetector::Method::kAabbTree}) {
    SelfCollisionDetector d(m, method);
    EXPECT_TRUE(d.Detect().empty());
    Eigen::MatrixX3d X = m.vertices;
    for (int v = 0; v < X.rows(); ++v)
      if (X(v, 0) > 2.5) X(v, 0) -= 1.5;
    d.Update(X);
    std::set<int> found;
    for (const auto& c : d.Detect()) {
      found.insert(c.vertex);
      // The reported tet really contains the vertex and is not incident to it.
      const Element& e = m.elements[c.tet];
      for (int k = 0; k < 4; ++k) EXPECT_NE(e.v[k], c.vertex);
    }
    std::set<int> expected;
    for (int v = 0; v < X.rows(); ++v) {
      const bool moved = m.vertices(v, 0) > 2.5;
      if ((moved && X(v, 0) <= 2.0) || (!moved && X(v, 0) >= 1.5)) expected.insert(v);
    }
    EXPECT_EQ(expected.size(), 18u);
    EXPECT_EQ(found, expected);
    EXPECT_GT(d.last_query_s(), 0.0);  // the timing is reported
  }
}

TEST(Collision, RobotVerticesInsideAnObstacle) {
  const Scene s = MakeRobot("pneumatic_finger", 5);
  std::vector<Obstacle> obs;
  obs.emplace_back(MakeBoxSurface(Eigen::Vector3d(100, -5, -5), Eigen::Vector3d(130, 30, 30)));
  const auto contacts = DetectObstacleContacts(obs, s.mesh.vertices);
  ASSERT_FALSE(contacts.empty());
  for (const auto& c : contacts) {
    const Eigen::Vector3d p = s.mesh.vertices.row(c.vertex);
    EXPECT_GT(p.x(), 100.0);
    EXPECT_NEAR(c.depth, (c.closest - p).norm(), 1e-12);
    const double to_face = std::min({p.x() - 100.0, 130.0 - p.x(), p.y() + 5.0, 30.0 - p.y(), p.z() + 5.0, 30.0 - p.z()});
    EXPECT_NEAR(c.depth, to_face, 1e-9);
    EXPECT_GT(c.normal.norm(), 0.99);
  }
  int inside = 0;
  for (int v = 0; v < s.mesh.num_vertices(); ++v) inside += s.mesh.vertices(v, 0) > 100.0;
  EXPECT_EQ(static_cast<int>(contacts.size()), inside);
}

}  // namespace
}  // namespace softkin
