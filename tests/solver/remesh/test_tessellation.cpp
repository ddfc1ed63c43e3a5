// T(S_c, S_b) (solver/remesh/tessellation.hpp): a box chamber in a box body, re-tessellation of one
// region's interior, and the errors on bad surfaces.
#include "softkin/solver/collision/collision.hpp"
#include "softkin/solver/remesh/tessellation.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <set>
#include <string>

namespace softkin {
namespace {

constexpr double kBody = 3.0, kChamber = 1.0;  // half sides of the two boxes, mm

TessellationOptions BoxOptions() {
  TessellationOptions o;
  o.cell_size = 0.8;
  o.seed = 7;
  o.body_region = 0;
  o.chamber_region = 5;
  return o;
}

Mesh BoxMesh(TessellationReport* rep = nullptr) {
  return Tessellate(
      MakeBoxSurface(Eigen::Vector3d::Constant(-kChamber), Eigen::Vector3d::Constant(kChamber)),
      MakeBoxSurface(Eigen::Vector3d::Constant(-kBody), Eigen::Vector3d::Constant(kBody)),
      BoxOptions(), rep);
}

/// Face -> the elements using it (sorted vertex ids).
std::map<std::array<int, 3>, std::vector<int>> FaceUse(const Mesh& m) {
  static const int kFace[4][3] = {{1, 2, 3}, {0, 3, 2}, {0, 1, 3}, {0, 2, 1}};
  std::map<std::array<int, 3>, std::vector<int>> use;
  for (int i = 0; i < m.num_elements(); ++i)
    for (const auto& f : kFace) {
      std::array<int, 3> t = {m.elements[i].v[f[0]], m.elements[i].v[f[1]], m.elements[i].v[f[2]]};
      std::sort(t.begin(), t.end());
      use[t].push_back(i);
    }
  return use;
}

Eigen::Vector3d Centroid(const Mesh& m, const Element& e) {
  Eigen::Vector3d c = Eigen::Vector3d::Zero();
  for (int j = 0; j < 4; ++j) c += m.vertices.row(e.v[j]).transpose();
  return c / 4.0;
}

TEST(Tessellation, BoxInBoxVolumesLabelsAndConformity) {
  TessellationReport rep;
  const Mesh m = BoxMesh(&rep);
  ASSERT_GT(m.num_tets(), 100);
  EXPECT_EQ(m.num_prisms(), 0);
  EXPECT_EQ(rep.tets, m.num_tets());
  EXPECT_EQ(rep.body_tets + rep.chamber_tets, rep.tets);
  EXPECT_EQ(m.regions(), (std::vector<int>{0, 5}));
  // Positive volumes; the regions' volumes are the volumes the surfaces enclose (sharp edges are
  // protected, so the flat faces are reproduced).
  double body = 0, chamber = 0;
  for (int i = 0; i < m.num_elements(); ++i) {
    const double v = SignedVolume(m.elements[i], m.vertices);
    ASSERT_GT(v, 0) << "tet " << i;
    (m.elements[i].region == 0 ? body : chamber) += v;
  }
  const double body_exact = std::pow(2 * kBody, 3) - std::pow(2 * kChamber, 3),
               chamber_exact = std::pow(2 * kChamber, 3);
  EXPECT_NEAR(body, body_exact, 1e-3 * body_exact);
  EXPECT_NEAR(chamber, chamber_exact, 1e-3 * chamber_exact);
  EXPECT_NEAR(rep.body_volume, body, 1e-9 * body);
  EXPECT_NEAR(rep.body_enclosed, body_exact, 1e-9);
  EXPECT_NEAR(rep.chamber_enclosed, chamber_exact, 1e-9);
  // Labels: chamber tets inside the inner box, body tets outside it.
  for (const auto& e : m.elements) {
    const double r = Centroid(m, e).cwiseAbs().maxCoeff();
    if (e.region == 5)
      EXPECT_LT(r, kChamber + 1e-9);
    else
      EXPECT_GT(r, kChamber - 1e-9);
  }
  // Conforming: every face is used by one tet (on the outer box) or two; a face between a body
  // and a chamber tet lies on the chamber box.
  int interface = 0, outer = 0;
  for (const auto& [f, els] : FaceUse(m)) {
    ASSERT_LE(els.size(), 2u);
    double rmin = std::numeric_limits<double>::infinity(), rmax = 0;
    for (int v : f) {
      const double r = m.vertices.row(v).cwiseAbs().maxCoeff();
      rmin = std::min(rmin, r);
      rmax = std::max(rmax, r);
    }
    if (els.size() == 1) {
      ++outer;
      EXPECT_NEAR(rmin, kBody, 1e-9) << "a boundary face inside the body";
    } else if (m.elements[els[0]].region != m.elements[els[1]].region) {
      ++interface;
      EXPECT_NEAR(rmax, kChamber, 1e-9);
      EXPECT_NEAR(rmin, kChamber, 1e-9);  // all three vertices on the chamber box
    }
  }
  EXPECT_GT(outer, 12);
  EXPECT_GT(interface, 12);
  // Every interface face is a boundary face of the chamber region and vice versa.
  EXPECT_EQ(static_cast<int>(RegionBoundaryFaces(m, 5).size()), interface);
}

TEST(Tessellation, SameInputGivesTheSameMesh) {
  const Mesh a = BoxMesh(), b = BoxMesh();
  ASSERT_EQ(a.num_vertices(), b.num_vertices());
  ASSERT_EQ(a.num_elements(), b.num_elements());
  EXPECT_EQ(a.vertices, b.vertices);
  for (int i = 0; i < a.num_elements(); ++i) {
    EXPECT_EQ(a.elements[i].v, b.elements[i].v) << "element " << i;
    EXPECT_EQ(a.elements[i].region, b.elements[i].region);
  }
  // A smaller cell size gives a finer mesh (the option is used).
  TessellationOptions fine = BoxOptions();
  fine.cell_size = 0.4;
  fine.facet_size = 0.4;
  const Mesh f = Tessellate(
      MakeBoxSurface(Eigen::Vector3d::Constant(-kChamber), Eigen::Vector3d::Constant(kChamber)),
      MakeBoxSurface(Eigen::Vector3d::Constant(-kBody), Eigen::Vector3d::Constant(kBody)), fine);
  EXPECT_GT(f.num_tets(), 2 * a.num_tets());
  // A smaller chamber cell size refines the chamber, not the body's interior.
  TessellationOptions ch = BoxOptions();
  ch.chamber_cell_size = 0.3;
  TessellationReport ra, rc;
  BoxMesh(&ra);
  Tessellate(
      MakeBoxSurface(Eigen::Vector3d::Constant(-kChamber), Eigen::Vector3d::Constant(kChamber)),
      MakeBoxSurface(Eigen::Vector3d::Constant(-kBody), Eigen::Vector3d::Constant(kBody)), ch, &rc);
  EXPECT_GT(rc.chamber_tets, 2 * ra.chamber_tets);
  EXPECT_LT(rc.body_tets, 2 * ra.body_tets);
}

TEST(Tessellation, EnclosedVolumeOfABox) {
  EXPECT_NEAR(EnclosedVolume(MakeBoxSurface(Eigen::Vector3d(0, 0, 0), Eigen::Vector3d(1, 2, 3))),
              6.0, 1e-12);
}

std::string ErrorOf(TriangleSurface c, TriangleSurface b,
                    const TessellationOptions& o = BoxOptions()) {
  try {
    Tessellate(c, b, o);
  } catch (const std::invalid_argument& e) {
    return e.what();
  }
  return "";
}

TEST(Tessellation, BadInputGivesClearErrors) {
  const TriangleSurface body =
      MakeBoxSurface(Eigen::Vector3d::Constant(-kBody), Eigen::Vector3d::Constant(kBody));
  TriangleSurface chamber =
      MakeBoxSurface(Eigen::Vector3d::Constant(-kChamber), Eigen::Vector3d::Constant(kChamber));
  chamber.source = "chamber.obj";

  // Not closed: one triangle missing.
  TriangleSurface open = chamber;
  open.faces.conservativeResize(open.faces.rows() - 1, 3);
  std::string msg = ErrorOf(open, body);
  EXPECT_NE(msg.find("chamber.obj"), std::string::npos) << msg;
  EXPECT_NE(msg.find("edge"), std::string::npos) << msg;

  // NaN coordinate.
  TriangleSurface nan = chamber;
  nan.vertices(2, 1) = std::numeric_limits<double>::quiet_NaN();
  msg = ErrorOf(nan, body);
  EXPECT_NE(msg.find("chamber.obj"), std::string::npos) << msg;
  EXPECT_NE(msg.find("finite"), std::string::npos) << msg;

  // Chamber crossing the body surface.
  TriangleSurface crossing =
      MakeBoxSurface(Eigen::Vector3d::Constant(-1), Eigen::Vector3d(1, 1, 4));
  crossing.source = "crossing.stl";
  msg = ErrorOf(crossing, body);
  EXPECT_NE(msg.find("crossing.stl"), std::string::npos) << msg;
  EXPECT_NE(msg.find("strictly inside"), std::string::npos) << msg;

  // Chamber entirely outside the body.
  TriangleSurface outside =
      MakeBoxSurface(Eigen::Vector3d::Constant(10), Eigen::Vector3d::Constant(11));
  outside.source = "outside.obj";
  msg = ErrorOf(outside, body);
  EXPECT_NE(msg.find("outside.obj"), std::string::npos) << msg;
  EXPECT_NE(msg.find("not inside the body"), std::string::npos) << msg;

  // Self-intersecting body: two overlapping boxes in one surface.
  TriangleSurface a =
      MakeBoxSurface(Eigen::Vector3d::Constant(-kBody), Eigen::Vector3d::Constant(kBody));
  TriangleSurface b2 =
      MakeBoxSurface(Eigen::Vector3d::Constant(0), Eigen::Vector3d::Constant(2 * kBody));
  TriangleSurface two;
  two.source = "two_boxes.obj";
  two.vertices.resize(16, 3);
  two.vertices << a.vertices, b2.vertices;
  two.faces.resize(24, 3);
  two.faces << a.faces, (b2.faces.array() + 8).matrix();
  msg = ErrorOf(chamber, two);
  EXPECT_NE(msg.find("two_boxes.obj"), std::string::npos) << msg;
  EXPECT_NE(msg.find("intersects itself"), std::string::npos) << msg;

  // Options.
  TessellationOptions bad = BoxOptions();
  bad.cell_size = 0;
  msg = ErrorOf(chamber, body, bad);
  EXPECT_NE(msg.find("cell_size"), std::string::npos) << msg;
  bad = BoxOptions();
  bad.chamber_region = bad.body_region;
  msg = ErrorOf(chamber, body, bad);
  EXPECT_NE(msg.find("different tags"), std::string::npos) << msg;
}

/// A smooth, orientation-preserving deformation: twist about z plus a bulge.
Eigen::MatrixX3d Deform(const Eigen::MatrixX3d& V) {
  Eigen::MatrixX3d X = V;
  for (int i = 0; i < V.rows(); ++i) {
    const double a = 0.15 * V(i, 2), c = std::cos(a), s = std::sin(a);
    const double g = 1.0 + 0.3 * std::exp(-V.row(i).squaredNorm() / 4.0);
    X(i, 0) = g * (c * V(i, 0) - s * V(i, 1));
    X(i, 1) = g * (s * V(i, 0) + c * V(i, 1));
    X(i, 2) = g * V(i, 2);
  }
  return X;
}

TEST(Tessellation, RemeshRegionInteriorKeepsEverythingElse) {
  const Mesh m = BoxMesh();
  const Eigen::MatrixX3d X = Deform(m.vertices);
  RegionRemeshOptions o;
  o.target_edge = 0.35;  // finer than the chamber's tets: the remesher must split
  const RegionRemeshResult r = RemeshRegionInterior(m, X, 5, o);
  EXPECT_GT(r.new_vertices, 0);
  EXPECT_GT(r.region_tets_after, r.region_tets_before);
  ASSERT_EQ(static_cast<int>(r.old_index.size()), r.mesh.num_vertices());
  // The body's tets are the input's, in order, on the same vertices and positions.
  int k = 0;
  for (const auto& e : m.elements) {
    if (e.region == 5) continue;
    const Element& n = r.mesh.elements[k++];
    EXPECT_EQ(n.region, e.region);
    for (int j = 0; j < 4; ++j) {
      ASSERT_EQ(r.old_index[n.v[j]], e.v[j]);
      EXPECT_EQ(r.mesh.vertices.row(n.v[j]), X.row(e.v[j]));
    }
  }
  EXPECT_EQ(k + r.region_tets_after, r.mesh.num_elements());
  // The chamber's boundary triangles are the ones it had (conforming to the body), its volume at X
  // is unchanged, every tet is positive, and faces are shared by at most two tets.
  std::vector<std::array<int, 3>> before = RegionBoundaryFaces(m, 5),
                                  after = RegionBoundaryFaces(r.mesh, 5);
  for (auto& f : after) {
    for (int& v : f) v = r.old_index[v];
    std::sort(f.begin(), f.end());
  }
  std::sort(after.begin(), after.end());
  EXPECT_EQ(after, before);
  double v0 = 0, v1 = 0;
  for (const auto& e : m.elements)
    if (e.region == 5) v0 += SignedVolume(e, X);
  for (const auto& e : r.mesh.elements) {
    const double v = SignedVolume(e, r.mesh.vertices);
    ASSERT_GT(v, 0);
    if (e.region == 5) v1 += v;
  }
  EXPECT_NEAR(v1, v0, 1e-9 * v0);
  for (const auto& [f, els] : FaceUse(r.mesh)) ASSERT_LE(els.size(), 2u);

  // Bad input.
  EXPECT_THROW(RemeshRegionInterior(m, X, 42, o), std::invalid_argument);
  EXPECT_THROW(RemeshRegionInterior(m, X.topRows(3), 5, o), std::invalid_argument);
  Eigen::MatrixX3d flipped = X;
  flipped.col(0) *= -1.0;  // a mirror image: every tet inverted
  EXPECT_THROW(RemeshRegionInterior(m, flipped, 5, o), std::invalid_argument);
}

}  // namespace
}  // namespace softkin
