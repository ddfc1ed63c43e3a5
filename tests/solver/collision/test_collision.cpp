// Collision detection (solver/collision/collision.hpp, thesis Sec. 3.2.2): obstacle surfaces
// (readers, closedness checks, inside and closest-point queries) and self-collision of a tet mesh
// (no false positives at rest, a built overlap found exactly, the three broad phases and a
// brute-force search give the same contacts on penetrating states, the filtered point-in-tet test
// is exact).
#include "softkin/solver/collision/collision.hpp"

#include "softkin/solver/mesh/mesh_gen.hpp"
#include "softkin/solver/robots/robots.hpp"

#include <gtest/gtest.h>
#include <omp.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <memory>
#include <fstream>
#include <random>
#include <set>
#include <string>

namespace softkin {
namespace {

namespace fs = std::filesystem;
using Method = SelfCollisionDetector::Method;
const Method kMethods[] = {Method::kBoxIntersection, Method::kAabbTree, Method::kGrid};

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
    for (const auto& part : parts)
      EXPECT_NE(std::string(e.what()).find(part), std::string::npos) << e.what();
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
  const Obstacle cyl(
      MakeCylinderSurface(Eigen::Vector3d(0, 0, -5), Eigen::Vector3d(0, 0, 1), 3.0, 10.0, 64));
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

// MovingSurface: closest points on the box [0, 2] x [0, 3] x [0, 4], moved rigidly, against the
// analytic answers: the distance to the box from outside, the nearest face from inside, and the
// top face for a point whose own surface faces down (ClosestFacing with n = -z).
TEST(Collision, MovingSurfaceClosestPoints) {
  const TriangleSurface box = MakeBoxSurface(Eigen::Vector3d::Zero(), Eigen::Vector3d(2, 3, 4));
  std::vector<std::array<int, 3>> faces;
  for (int f = 0; f < box.faces.rows(); ++f)
    faces.push_back({box.faces(f, 0), box.faces(f, 1), box.faces(f, 2)});
  MovingSurface surface(faces);
  const Eigen::Vector3d shift(10, -5, 7);
  Eigen::MatrixX3d X = box.vertices;
  X.rowwise() += shift.transpose();
  surface.Update(X);
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> U(-2, 6);
  const Eigen::Array3d hi(2, 3, 4);
  int inside = 0, outside = 0;
  for (int k = 0; k < 400; ++k) {
    const Eigen::Vector3d q(U(rng), U(rng), U(rng));  // box frame
    const Eigen::Array3d below = (-q.array()).max(0.0), above = (q.array() - hi).max(0.0);
    const Eigen::Vector3d p = q + shift;
    int face = -1;
    const Eigen::Vector3d c = surface.ClosestPoint(p, &face);
    ASSERT_GE(face, 0);
    if ((below + above).maxCoeff() > 0) {
      ++outside;
      EXPECT_NEAR((c - p).norm(), (below + above).matrix().norm(), 1e-9);
    } else {
      ++inside;
      const double d = std::min((q.array()).minCoeff(), (hi - q.array()).minCoeff());
      EXPECT_NEAR((c - p).norm(), d, 1e-9);
      Eigen::Vector3d top;
      ASSERT_TRUE(surface.ClosestFacing(p, -Eigen::Vector3d::UnitZ(), &top, &face));
      EXPECT_NEAR((top - (p + (4.0 - q.z()) * Eigen::Vector3d::UnitZ())).norm(), 0.0, 1e-9);
      const auto& t = faces[face];
      EXPECT_NEAR(X(t[0], 2) + X(t[1], 2) + X(t[2], 2), 3 * (4.0 + shift.z()),
                  1e-9);  // a top triangle
    }
  }
  EXPECT_GT(inside, 10);
  EXPECT_GT(outside, 20);
  // No face of a box faces against the zero vector.
  Eigen::Vector3d none;
  EXPECT_FALSE(surface.ClosestFacing(shift, Eigen::Vector3d::Zero(), &none));
  EXPECT_THROW(MovingSurface({}), std::invalid_argument);
  EXPECT_THROW(MovingSurface({{0, 1, -2}}), std::invalid_argument);
  MovingSurface small({{0, 1, 9}});
  EXPECT_THROW(small.Update(X), std::invalid_argument);  // X has 8 rows
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
      ascii += "   vertex " + std::to_string(p.x()) + " " + std::to_string(p.y()) + " " +
               std::to_string(p.z()) + "\n";
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
  for (const char* from :
       {"f 1 4 3 2", "f 5 6 7 8", "f 1 2 6 5", "f 2 3 7 6", "f 3 4 8 7", "f 4 1 5 8"}) {
    std::string f(from);
    const std::string rev = "f " + std::string(1, f[8]) + " " + f[6] + " " + f[4] + " " + f[2];
    flipped.replace(flipped.find(f), f.size(), rev);
  }
  Write(Temp("flipped.obj"), flipped);
  EXPECT_TRUE(
      Obstacle(ReadSurfaceMesh(Temp("flipped.obj").string())).Contains(Eigen::Vector3d(1, 1, 1)));
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
    for (auto method : kMethods) {
      const Scene s = MakeRobot(robot, robot == std::string("three_chamber") ? 3 : 5);
      SelfCollisionDetector d(s.mesh, method);
      EXPECT_GT(d.boundary_vertices().size(), 100u);
      EXPECT_TRUE(d.Detect().empty()) << robot;
      const Eigen::Matrix3d R =
          Eigen::AngleAxisd(0.7, Eigen::Vector3d(1, 2, 3).normalized()).toRotationMatrix();
      d.Update((s.mesh.vertices * R.transpose()).rowwise() + Eigen::RowVector3d(5, -2, 1));
      EXPECT_TRUE(d.Detect().empty()) << robot;
    }
}

TEST(Collision, BuiltOverlapIsFoundExactly) {
  // Two 2 x 2 x 2 blocks of 1 mm cells with a 1 mm gap (x in [0, 2] and [3, 5]); the second one
  // is then pushed 1.5 mm into the first. The second block's end face (now x = 1.5) lies in the
  // first block, and the first block's end face (x = 2) lies in the second: those 18 vertices, no
  // others. (They sit on faces shared by tets, which the test must not miss.)
  const Mesh m = VoxelTetMesh(
      Eigen::Vector3d::Zero(), 1.0, Eigen::Vector3i(5, 2, 2),
      [](const Eigen::Vector3d&, const Eigen::Vector3i& c) { return c.x() == 2 ? -1 : 0; });
  for (auto method : kMethods) {
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
    // The vertices lie exactly on faces of the other block's tets: the exact predicate decided.
    EXPECT_GT(d.last_exact_tests(), 0) << SelfCollisionMethodToString(method);
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
    const double to_face = std::min(
        {p.x() - 100.0, 130.0 - p.x(), p.y() + 5.0, 30.0 - p.y(), p.z() + 5.0, 30.0 - p.z()});
    EXPECT_NEAR(c.depth, to_face, 1e-9);
    EXPECT_GT(c.normal.norm(), 0.99);
  }
  int inside = 0;
  for (int v = 0; v < s.mesh.num_vertices(); ++v) inside += s.mesh.vertices(v, 0) > 100.0;
  EXPECT_EQ(static_cast<int>(contacts.size()), inside);
}

TEST(Collision, TetContainsPointIsExact) {
  // A tet with integer corners and points on a 1/1024 lattice: every coordinate, the tet's image
  // under the integer affine map below and the lattice test are exact in double, so the truth is
  // known. Many points lie exactly on a face, edge or corner (the exact predicate decides those);
  // the rest the filter decides.
  const Eigen::Matrix3d M = (Eigen::Matrix3d() << 2, 1, 0, 0, 1, 1, 1, 0, 3).finished();  // det 7
  const Eigen::Vector3d shift(5, -3, 2);
  auto map = [&](const Eigen::Vector3d& x) -> Eigen::Vector3d { return M * x + shift; };
  const Eigen::Vector3d a(0, 0, 0), b(4, 0, 0), c(0, 4, 0), d(0, 0, 4);
  std::mt19937 rng(11);
  std::uniform_int_distribution<int> k(-512, 4608);  // -0.5 .. 4.5 in steps of 1/1024
  std::uniform_int_distribution<int> snap(0, 3);
  int by_filter = 0, by_exact = 0, on_boundary = 0, inside = 0;
  for (int i = 0; i < 20000; ++i) {
    Eigen::Vector3d x(k(rng) / 1024.0, k(rng) / 1024.0, k(rng) / 1024.0);
    // Put a third of the points on the slanted face x + y + z = 4 or a coordinate plane.
    if (snap(rng) == 0)
      x.z() = 4 - x.x() - x.y();
    else if (snap(rng) == 0)
      x[snap(rng) % 3] = 0;
    const double sum = x.sum();  // exact: few bits
    const bool truth = x.minCoeff() >= 0 && sum <= 4;
    on_boundary += truth && (x.minCoeff() == 0 || sum == 4);
    inside += truth;
    for (int flip = 0; flip < 2; ++flip) {  // both orientations
      bool exact = false;
      const bool got = flip ? TetContainsPoint(map(a), map(c), map(b), map(d), map(x), &exact)
                            : TetContainsPoint(map(a), map(b), map(c), map(d), map(x), &exact);
      ASSERT_EQ(got, truth) << "point " << x.transpose() << " flip " << flip;
      (exact ? by_exact : by_filter) += 1;
    }
  }
  EXPECT_GT(on_boundary, 1000);
  EXPECT_GT(inside - on_boundary, 500);
  EXPECT_GT(by_exact, 2000);
  EXPECT_GT(by_filter, 20000);
  // One ulp off a face: outside, inside.
  const double below = std::nextafter(0.0, -1.0);
  EXPECT_FALSE(TetContainsPoint(a, b, c, d, Eigen::Vector3d(1, 1, below)));
  EXPECT_TRUE(TetContainsPoint(a, b, c, d, Eigen::Vector3d(1, 1, 0)));
  EXPECT_TRUE(TetContainsPoint(a, b, c, d, Eigen::Vector3d(1, 1, std::nextafter(0.0, 1.0))));
  EXPECT_FALSE(TetContainsPoint(a, b, c, d,
                                Eigen::Vector3d(2, 2, std::nextafter(0.0, 1.0))));  // past x+y+z=4
  // A flat tet contains nothing, not even its own corners; a tiny tet is handled like a big one.
  EXPECT_FALSE(TetContainsPoint(a, b, c, Eigen::Vector3d(1, 1, 0), Eigen::Vector3d(1, 0.5, 0)));
  EXPECT_FALSE(TetContainsPoint(a, b, c, Eigen::Vector3d(1, 1, 0), a));
  const double s = 1e-150;
  EXPECT_TRUE(TetContainsPoint(s * a, s * b, s * c, s * d, s * Eigen::Vector3d(1, 1, 1)));
  EXPECT_FALSE(TetContainsPoint(s * a, s * b, s * c, s * d, s * Eigen::Vector3d(1, 1, 2.5)));
  EXPECT_THROW(TetContainsPoint(a, b, c, d, Eigen::Vector3d(NAN, 0, 0)), std::invalid_argument);
}

/// Reference answer: every boundary vertex against every non-incident tet, lowest tet first.
std::vector<SelfContact> BruteForceContacts(const Mesh& m, const std::vector<int>& boundary,
                                            const Eigen::MatrixX3d& X) {
  std::vector<SelfContact> out;
  for (int v : boundary)
    for (int t = 0; t < m.num_elements(); ++t) {
      const auto& e = m.elements[t].v;
      if (e[0] == v || e[1] == v || e[2] == v || e[3] == v) continue;
      if (TetContainsPoint(X.row(e[0]), X.row(e[1]), X.row(e[2]), X.row(e[3]), X.row(v))) {
        out.push_back({v, t});
        break;
      }
    }
  return out;
}

std::string Describe(const std::vector<SelfContact>& c) {
  std::string s = std::to_string(c.size()) + " contacts:";
  for (size_t i = 0; i < std::min<size_t>(c.size(), 8); ++i)
    s += " (" + std::to_string(c[i].vertex) + ", " + std::to_string(c[i].tet) + ")";
  return s;
}

bool Same(const std::vector<SelfContact>& a, const std::vector<SelfContact>& b) {
  if (a.size() != b.size()) return false;
  for (size_t i = 0; i < a.size(); ++i)
    if (a[i].vertex != b[i].vertex || a[i].tet != b[i].tet) return false;
  return true;
}

/// Penetrating states of a robot mesh: its far half along the longest axis pushed back into the
/// near half, its top half folded down into the bottom half, and random vertex jitter (seeded).
std::vector<std::pair<std::string, Eigen::MatrixX3d>> PenetratingStates(const Mesh& m,
                                                                        unsigned seed) {
  const Eigen::MatrixX3d& X0 = m.vertices;
  const Eigen::RowVector3d lo = X0.colwise().minCoeff(), hi = X0.colwise().maxCoeff();
  const Eigen::RowVector3d mid = 0.5 * (lo + hi), ext = hi - lo;
  int axis = 0;
  ext.maxCoeff(&axis);
  const int up = (axis + 2) % 3;
  std::vector<std::pair<std::string, Eigen::MatrixX3d>> states;
  Eigen::MatrixX3d X = X0;
  for (int v = 0; v < X.rows(); ++v)
    if (X(v, axis) > mid[axis]) X(v, axis) -= 0.2 * ext[axis];
  states.emplace_back("translated half", X);
  X = X0;
  for (int v = 0; v < X.rows(); ++v)
    if (X(v, up) > mid[up]) X(v, up) = mid[up] - 0.5 * (X(v, up) - mid[up]) + 0.1 * ext[up];
  states.emplace_back("folded top", X);
  // Mean edge length of the tets, for the jitter amplitude.
  double edge = 0;
  for (const auto& e : m.elements) edge += (X0.row(e.v[0]) - X0.row(e.v[1])).norm();
  edge /= m.num_elements();
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(-0.45 * edge, 0.45 * edge);
  X = X0;
  for (int v = 0; v < X.rows(); ++v)
    for (int a = 0; a < 3; ++a) X(v, a) += u(rng);
  states.emplace_back("jitter", X);
  return states;
}

TEST(Collision, AllMethodsAndBruteForceAgreeOnPenetratingStates) {
  for (const auto& [robot, res] :
       {std::pair<std::string, int>{"pneumatic_finger", 5}, {"three_chamber", 3}}) {
    const Scene s = MakeRobot(robot, res);
    const Mesh& m = s.mesh;
    std::vector<std::unique_ptr<SelfCollisionDetector>> det;
    for (auto method : kMethods) det.push_back(std::make_unique<SelfCollisionDetector>(m, method));
    const std::vector<int>& boundary = det[0]->boundary_vertices();
    for (const auto& [name, X] : PenetratingStates(m, 42)) {
      const std::vector<SelfContact> truth = BruteForceContacts(m, boundary, X);
      // Guard: the state really penetrates, so agreement is not vacuous.
      EXPECT_GT(truth.size(), 10u) << robot << " " << name;
      for (size_t i = 0; i < det.size(); ++i) {
        det[i]->Update(X);
        const auto got = det[i]->Detect();
        EXPECT_TRUE(Same(got, truth))
            << robot << " " << name << " " << SelfCollisionMethodToString(kMethods[i]) << ": got "
            << Describe(got) << "; expected " << Describe(truth);
        EXPECT_GE(det[i]->last_narrow_tests(), static_cast<long long>(truth.size()));
      }
      // The grid's filter decides nearly every test by itself.
      const auto& grid = *det[2];
      EXPECT_LT(grid.last_exact_tests(), grid.last_narrow_tests() / 10 + 10)
          << robot << " " << name;
    }
    // Back at rest: nothing, with every method (the grid reuses its buffers).
    for (auto& d : det) {
      d->Update(m.vertices);
      EXPECT_TRUE(d->Detect().empty()) << robot << " " << SelfCollisionMethodToString(d->method());
    }
  }
}

TEST(Collision, GridIsDeterministicAcrossThreadCountsAndSurvivesOutliers) {
  {
    // Res 9 (19.7k tets, 1.8k boundary vertices) is above the sizes below which the grid runs on
    // one thread, so 3 threads really split the counting sort and the queries.
    const Scene big = MakeRobot("pneumatic_finger", 9);
    ASSERT_GE(big.mesh.num_elements(), 16384);
    SelfCollisionDetector grid(big.mesh, Method::kGrid), box(big.mesh, Method::kBoxIntersection);
    ASSERT_GE(grid.boundary_vertices().size(), 1024u);
    const int threads = omp_get_max_threads();
    for (const auto& [name, X] : PenetratingStates(big.mesh, 7)) {
      std::vector<SelfContact> got[2];
      for (int k = 0; k < 2; ++k) {
        omp_set_num_threads(k == 0 ? 1 : 3);
        grid.Update(X);
        got[k] = grid.Detect();
      }
      omp_set_num_threads(threads);
      box.Update(X);
      const auto ref = box.Detect();
      EXPECT_FALSE(ref.empty()) << name;
      EXPECT_TRUE(Same(got[0], ref)) << name << ": " << Describe(got[0]) << " vs " << Describe(ref);
      EXPECT_TRUE(Same(got[1], ref)) << name << ": " << Describe(got[1]) << " vs " << Describe(ref);
    }
  }
  const Scene s = MakeRobot("pneumatic_finger", 5);
  const Mesh& m = s.mesh;
  const auto states = PenetratingStates(m, 7);
  SelfCollisionDetector grid(m, Method::kGrid), box(m, Method::kBoxIntersection);
  // One vertex thrown 1e5 mm away: its tets span the whole (capped) grid and go to the list of
  // large tets, which every vertex scans. Same answer as the CGAL broad phase.
  Eigen::MatrixX3d X = states[0].second;
  X.row(0) += Eigen::RowVector3d(1e5, -2e4, 3e4);
  grid.Update(X);
  box.Update(X);
  EXPECT_GT(grid.grid_large_tets(), 0);
  const auto g = grid.Detect(), b = box.Detect();
  EXPECT_FALSE(g.empty());
  EXPECT_TRUE(Same(g, b)) << Describe(g) << " vs " << Describe(b);
  // Everything collapsed to a point: every tet is flat and contains nothing.
  grid.Update(Eigen::MatrixX3d::Zero(m.num_vertices(), 3));
  EXPECT_TRUE(grid.Detect().empty());
  EXPECT_GT(grid.last_narrow_tests(), 0);
}

TEST(Collision, SelfCollisionInputErrorsAndMethodNames) {
  const Scene s = MakeRobot("pneumatic_finger", 5);
  SelfCollisionDetector d(s.mesh);
  EXPECT_EQ(d.method(), Method::kGrid);  // the default
  try {
    d.Update(Eigen::MatrixX3d::Zero(5, 3));
    ADD_FAILURE() << "accepted 5 rows";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("got 5 rows"), std::string::npos) << e.what();
  }
  Eigen::MatrixX3d X = s.mesh.vertices;
  X(17, 1) = NAN;
  try {
    d.Update(X);
    ADD_FAILURE() << "accepted a NaN";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("vertex 17"), std::string::npos) << e.what();
  }
  for (auto m : kMethods)
    EXPECT_EQ(SelfCollisionMethodFromString(SelfCollisionMethodToString(m)), m);
  try {
    SelfCollisionMethodFromString("bvh");
    ADD_FAILURE() << "accepted 'bvh'";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("'bvh'"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("grid"), std::string::npos) << e.what();
  }
}

TEST(Collision, ObstacleContactsOfAVertexSubsetAndFarObstacles) {
  const Scene s = MakeRobot("pneumatic_finger", 5);
  const Eigen::MatrixX3d& X = s.mesh.vertices;
  std::vector<Obstacle> obs;
  obs.emplace_back(
      MakeBoxSurface(Eigen::Vector3d(1000, 0, 0), Eigen::Vector3d(1010, 10, 10)));  // far away
  obs.emplace_back(
      MakeCylinderSurface(Eigen::Vector3d(90, 10, -50), Eigen::Vector3d(0, 0, 1), 12.0, 100.0));
  std::vector<int> odd;
  for (int v = 1; v < X.rows(); v += 2) odd.push_back(v);
  const auto contacts = DetectObstacleContacts(obs, X, odd);
  // The same as asking every obstacle about every listed vertex.
  std::vector<int> expected;
  for (int v : odd)
    if (obs[0].Contains(X.row(v).transpose()) || obs[1].Contains(X.row(v).transpose()))
      expected.push_back(v);
  ASSERT_FALSE(expected.empty());
  ASSERT_EQ(contacts.size(), expected.size());
  for (size_t i = 0; i < contacts.size(); ++i) {
    EXPECT_EQ(contacts[i].vertex, expected[i]);
    EXPECT_EQ(contacts[i].obstacle, 1);
    const Eigen::Vector3d p = X.row(contacts[i].vertex);
    EXPECT_LE((p.head<2>() - Eigen::Vector2d(90, 10)).norm(), 12.0);
    EXPECT_NEAR(contacts[i].depth, (contacts[i].closest - p).norm(), 1e-12);
  }
  std::vector<Obstacle> far;
  far.emplace_back(MakeBoxSurface(Eigen::Vector3d(1000, 0, 0), Eigen::Vector3d(1010, 10, 10)));
  EXPECT_TRUE(DetectObstacleContacts(far, X).empty());
  EXPECT_THROW(DetectObstacleContacts(obs, X, {0, static_cast<int>(X.rows())}),
               std::invalid_argument);
}

}  // namespace
}  // namespace softkin
