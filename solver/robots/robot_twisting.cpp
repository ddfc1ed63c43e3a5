// The twisting robot of thesis Sec. 3.4.1 (robot_twisting.hpp): generated surfaces, T(S_c, S_b),
// and the twist measurements used by its tests and the fig3_7_twisting_remesh experiment.
#include "softkin/solver/robots/robot_twisting.hpp"

#include "softkin/solver/materials/hyperelastic.hpp"
#include "softkin/solver/fk/rotation.hpp"
#include "softkin/solver/robots/robot_parts.hpp"

#include <Eigen/Geometry>

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>

namespace softkin {

namespace {

constexpr double kPi = 3.14159265358979323846;

double Param(const RobotParams& p, const std::string& name, double def) {
  auto it = p.find(name);
  return it == p.end() ? def : it->second;
}

}  // namespace

TriangleSurface MakeHelicalTubeSurface(double rh, double turns, double z0, double z1, double rt,
                                       int around, int along, int cap_rings) {
  if (!(rh > 0) || !(rt > 0) || !(turns > 0) || !(z1 > z0) || around < 3 || along < 1 ||
      cap_rings < 1)
    throw std::invalid_argument(
        "helical tube: expected helix_radius > 0, tube_radius > 0, turns > 0, z1 > z0, around >= "
        "3, "
        "along >= 1, cap_rings >= 1");
  if (!(rt < rh))
    throw std::invalid_argument("helical tube: tube_radius " + std::to_string(rt) +
                                " must be smaller than helix_radius " + std::to_string(rh) +
                                " (the tube would cross the axis)");
  const double pitch = (z1 - z0) / turns;
  if (!(pitch > 2.0 * rt))
    throw std::invalid_argument("helical tube: pitch " + std::to_string(pitch) +
                                " mm must exceed the tube diameter " + std::to_string(2 * rt) +
                                " mm (neighbouring turns would overlap)");
  const double dphi = 2.0 * kPi * turns, dz = z1 - z0;
  auto frame = [&](double t, Eigen::Vector3d* c, Eigen::Vector3d* T, Eigen::Vector3d* N,
                   Eigen::Vector3d* B) {
    const double phi = dphi * t;
    *c = Eigen::Vector3d(rh * std::cos(phi), rh * std::sin(phi), z0 + dz * t);
    *T = Eigen::Vector3d(-rh * dphi * std::sin(phi), rh * dphi * std::cos(phi), dz).normalized();
    *N = Eigen::Vector3d(-std::cos(phi), -std::sin(phi), 0.0);  // towards the axis, normal to T
    *B = T->cross(*N);
  };
  // Rings of `around` points from the start pole to the end pole, all at the same angles psi_j in
  // their local (N, B) frames, so consecutive rings join by quads.
  std::vector<Eigen::Vector3d> pts;
  std::vector<int> ring_start;
  auto add_ring = [&](const Eigen::Vector3d& centre, const Eigen::Vector3d& N,
                      const Eigen::Vector3d& B, double radius) {
    ring_start.push_back(static_cast<int>(pts.size()));
    for (int j = 0; j < around; ++j) {
      const double psi = 2.0 * kPi * j / around;
      pts.push_back(centre + radius * (std::cos(psi) * N + std::sin(psi) * B));
    }
  };
  Eigen::Vector3d c0, T0, N0, B0, c1, T1, N1, B1;
  frame(0.0, &c0, &T0, &N0, &B0);
  frame(1.0, &c1, &T1, &N1, &B1);
  const int pole0 = 0;
  pts.push_back(c0 - rt * T0);
  for (int k = 1; k < cap_rings; ++k) {
    const double beta =
        0.5 * kPi * (cap_rings - k) / cap_rings;  // from near the pole to the equator
    add_ring(c0 - rt * std::sin(beta) * T0, N0, B0, rt * std::cos(beta));
  }
  for (int i = 0; i <= along; ++i) {
    Eigen::Vector3d c, T, N, B;
    frame(static_cast<double>(i) / along, &c, &T, &N, &B);
    add_ring(c, N, B, rt);
  }
  for (int k = cap_rings - 1; k >= 1; --k) {
    const double beta = 0.5 * kPi * (cap_rings - k) / cap_rings;
    add_ring(c1 + rt * std::sin(beta) * T1, N1, B1, rt * std::cos(beta));
  }
  const int pole1 = static_cast<int>(pts.size());
  pts.push_back(c1 + rt * T1);

  std::vector<Eigen::Vector3i> F;
  const int rings = static_cast<int>(ring_start.size());
  for (int j = 0; j < around; ++j) {
    const int jn = (j + 1) % around;
    F.emplace_back(pole0, ring_start[0] + jn, ring_start[0] + j);
    F.emplace_back(pole1, ring_start[rings - 1] + j, ring_start[rings - 1] + jn);
  }
  for (int r = 0; r + 1 < rings; ++r)
    for (int j = 0; j < around; ++j) {
      const int jn = (j + 1) % around;
      const int a = ring_start[r] + j, b = ring_start[r] + jn, c = ring_start[r + 1] + jn,
                d = ring_start[r + 1] + j;
      F.emplace_back(a, b, c);
      F.emplace_back(a, c, d);
    }
  TriangleSurface s;
  s.source = "helical tube";
  s.vertices.resize(static_cast<int>(pts.size()), 3);
  for (size_t i = 0; i < pts.size(); ++i) s.vertices.row(i) = pts[i].transpose();
  s.faces.resize(static_cast<int>(F.size()), 3);
  for (size_t f = 0; f < F.size(); ++f) s.faces.row(f) = F[f].transpose();
  CheckClosedSurface(&s);  // also orients it outwards
  return s;
}

void TwistingRobotSurfaces(const RobotParams& P, TriangleSurface* chamber, TriangleSurface* body) {
  const double rh = Param(P, "helix_radius", 5.0), rt = Param(P, "tube_radius", 2.5),
               turns = Param(P, "turns", kTwistDefaultTurns);
  if (!(rh + rt <= kTwistBodyRadius - 1.0))
    throw std::invalid_argument(
        "twisting_robot: helix_radius + tube_radius = " + std::to_string(rh + rt) +
        " mm leaves less than a 1 mm wall to the 10 mm body radius; expected <= 9");
  const int along = std::max(48, static_cast<int>(std::ceil(64 * turns)));
  *chamber = MakeHelicalTubeSurface(rh, turns, kTwistHelixZ0, kTwistHelixZ1, rt, 24, along, 6);
  chamber->source = "twisting_robot chamber (helical tube)";
  *body = MakeCylinderSurface(Eigen::Vector3d::Zero(), Eigen::Vector3d::UnitZ(), kTwistBodyRadius,
                              kTwistLength, 64);
  body->source = "twisting_robot body (cylinder)";
}

TessellationOptions TwistingRobotTessellation(int res, double tube_radius) {
  TessellationOptions o;
  o.cell_size = 8.0 / res;
  o.chamber_cell_size = std::min(o.cell_size, 0.8 * tube_radius);
  o.facet_size = o.cell_size;
  o.facet_distance = 0.05 * o.cell_size;
  o.seed = 1;
  o.body_region = 0;
  o.chamber_region = 1;
  return o;
}

TessellationOptions TwistingRobotTessellation(int res, const RobotParams& params) {
  return TwistingRobotTessellation(res <= 0 ? kTwistDefaultRes : res,
                                   Param(params, "tube_radius", 2.5));
}

Scene MakeTwistingRobot(int res, const RobotParams& P) {
  if (res <= 0) res = kTwistDefaultRes;
  if (res < kTwistMinRes || res > kTwistMaxRes)
    throw std::invalid_argument("twisting_robot: --res must be an integer in [" +
                                std::to_string(kTwistMinRes) + ", " + std::to_string(kTwistMaxRes) +
                                "], got " + std::to_string(res));
  TriangleSurface chamber, body;
  TwistingRobotSurfaces(P, &chamber, &body);
  const TessellationOptions topt = TwistingRobotTessellation(res, P);
  Scene s;
  s.name = "twisting_robot";
  s.mesh = Tessellate(chamber, body, topt);
  if (Param(P, "hyperelastic", 1.0) >= 0.5) {
    MooneyRivlin eco;
    NamedMooneyRivlin("ecoflex-00-30", &eco);
    s.body[0] = Material{"ecoflex-00-30", 1.0, 1.0, MaterialLaw::kMooneyRivlin, eco.c1, eco.c2};
  } else {
    s.body[0] = Material{"as-rigid-as-possible", 1.0, 1.0};  // Ch. 2 shape blending, R_omega = 1
  }
  // Optional strain-limiting strip: body tets whose centroid lies beyond x = body radius - strip
  // (a slab along the whole length on the +x side) become region 2, `strip_weight` times stiffer.
  // The chamber elongates the rest of the body, so the robot bends toward +x while it twists, and
  // coils around an object (Fig. 3.8) instead of only twisting.
  const double strip = Param(P, "strip", 0.0);
  if (strip > 0) {
    const double x0 = kTwistBodyRadius - strip;
    int n = 0;
    for (auto& e : s.mesh.elements) {
      if (e.region != 0) continue;
      double cx = 0;
      for (int j = 0; j < e.k(); ++j) cx += s.mesh.vertices(e.v[j], 0);
      if (cx / e.k() > x0) {
        e.region = 2;
        ++n;
      }
    }
    if (n == 0)
      throw std::invalid_argument(
          "twisting_robot: strip = " + std::to_string(strip) +
          " mm holds no body tet at this resolution; expected a thicker strip");
    Material m = s.body[0];
    m.name += "+strip";
    m.weight *= Param(P, "strip_weight", 20.0);
    s.body[2] = m;
  }
  Actuator a;
  a.name = "chamber";
  a.type = ActuatorType::Pneumatic;
  a.regions = {1};
  a.rest = 1.0;
  a.min = 1.0;
  a.max = Param(P, "max_ratio", kTwistDefaultMaxRatio);
  a.weight = Param(P, "chamber_weight", Actuator{}.weight);
  s.actuators.push_back(a);
  const double eps = 1e-6 * kTwistLength;
  s.fixed = VerticesOnPlane(s.mesh, Eigen::Vector3d::Zero(), Eigen::Vector3d::UnitZ(), eps);
  std::vector<int> tip =
      VerticesOnPlane(s.mesh, Eigen::Vector3d(0, 0, kTwistLength), Eigen::Vector3d::UnitZ(), eps);
  int rim = tip.empty() ? -1 : tip[0];
  for (int v : tip)
    if ((s.mesh.vertices.row(v) - Eigen::RowVector3d(kTwistBodyRadius, 0, kTwistLength)).norm() <
        (s.mesh.vertices.row(rim) - Eigen::RowVector3d(kTwistBodyRadius, 0, kTwistLength)).norm())
      rim = v;
  s.markers.push_back({"tip", tip});
  if (rim >= 0) s.markers.push_back({"tip_rim", {rim}});
  s.validate();
  return s;
}

namespace robots_detail {

RobotEntry TwistingRobotEntry() {
  const RobotInfo info = {
      "twisting_robot",
      "Plant-inspired twisting robot (thesis Sec. 3.4.1, Fig. 3.7-3.8): a 100 mm long cylinder of "
      "radius 10 mm (z = long axis, z = 0 fixed, tip face z = 100) of Ecoflex 00-30 (Mooney-Rivlin "
      "c1 = 0.0418, c2 = 0.0106 MPa; region 0) with a spiral tube chamber (region 1, pneumatic "
      "actuator 'chamber', volume ratio in [1, max_ratio], 3 by default, up to 120 with remeshing) "
      "around the helix of radius helix_radius from "
      "z = 8 to 92, meshed by CGAL Mesh_3 from generated surfaces, T(S_c, S_b) "
      "(solver/remesh/tessellation.hpp). For large ratios use progressive remeshing "
      "(solver/remesh/remesh.hpp). "
      "Markers: tip (face z = 100), tip_rim (its vertex nearest (10, 0, 100)).",
      kTwistDefaultRes,
      "Mesh_3 cell size 8/res mm (facet size the same, facet distance 0.05 of it), integer in "
      "[1, 12]; 6.2k / 10.8k / 18.0k / 29.2k / 73k / 154k / 288k tets at res 1 / 2 / 3 / 4 / 6 / "
      "8 / 10. Res 1 (the default, for remeshing) is coarse: the 2.5 mm wall outside the chamber "
      "is under one cell, and the tip twists 6.5 degrees at alpha = 2 against about 21 at res 8-10 "
      "(docs/fidelity.md)",
      {{"helix_radius", 5.0, 2.0, 7.0, "radius of the chamber's helical centreline, mm"},
       {"tube_radius", 2.5, 1.0, 4.0,
        "radius of the chamber tube, mm (helix_radius + tube_radius <= 9)"},
       {"turns", kTwistDefaultTurns, 1.0, 8.0, "turns of the helix between z = 8 and z = 92"},
       {"hyperelastic", 1.0, 0.0, 1.0,
        "1: Ecoflex 00-30 Mooney-Rivlin body (Eq. 3.6-3.7); 0: Ch. 2 shape blending with R_omega = "
        "1"},
       {"strip", 0.0, 0.0, 6.0,
        "thickness (mm, from the +x side) of a strain-limiting strip along the body (region 2); 0: "
        "none. "
        "With a strip the robot bends toward +x as it twists, and coils (Fig. 3.8)"},
       {"strip_weight", 20.0, 1.0, 1000.0, "the strip's element weight, relative to the body's"},
       {"max_ratio", kTwistDefaultMaxRatio, 1.5, kTwistMaxAlpha,
        "top of the chamber's volume-ratio range. Solved on the initial mesh the body stays free "
        "of inverted elements up to about 3 (res 1: one inverted tet at 3.5 with the Mooney-Rivlin "
        "body, at 4 with shape blending); beyond, chamber-wall tets fold. Raise it (to 120) with "
        "progressive remeshing (fig3_7_twisting_remesh) or to study the folded states"},
       ChamberWeightParam()}};
  return {info, kTwistMinRes, kTwistMaxRes, &MakeTwistingRobot};
}

}  // namespace robots_detail

double TwistAboutAxisDegrees(const Eigen::Ref<const Eigen::MatrixX3d>& P,
                             const Eigen::Ref<const Eigen::MatrixX3d>& Q,
                             const Eigen::Vector3d& axis) {
  if (P.rows() != Q.rows() || P.rows() < 3)
    throw std::invalid_argument(
        "TwistAboutAxisDegrees: expected two point sets of the same size >= 3, got " +
        std::to_string(P.rows()) + " and " + std::to_string(Q.rows()));
  const Eigen::RowVector3d pc = P.colwise().mean(), qc = Q.colwise().mean();
  const Eigen::MatrixX3d Pc = P.rowwise() - pc, Qc = Q.rowwise() - qc;
  // R maximises tr(R^T Qc^T Pc): the rotation taking the rest points onto the deformed ones.
  const Eigen::Matrix3d R = BestRotation(Qc.transpose() * Pc);
  const Eigen::Quaterniond q(R);
  const Eigen::Vector3d a = axis.normalized();
  const double proj = q.vec().dot(a);
  double deg = 2.0 * std::atan2(proj, q.w()) * 180.0 / kPi;
  while (deg > 180.0) deg -= 360.0;
  while (deg <= -180.0) deg += 360.0;
  return deg;
}

std::vector<double> TwistProfileDegrees(const Scene& scene,
                                        const Eigen::Ref<const Eigen::MatrixX3d>& X, double length,
                                        int sections, int body_region, const std::string& tip) {
  const Mesh& m = scene.mesh;
  if (X.rows() != m.num_vertices())
    throw std::invalid_argument("TwistProfileDegrees: positions have " + std::to_string(X.rows()) +
                                " rows, the mesh " + std::to_string(m.num_vertices()) +
                                " vertices");
  if (sections < 1 || !(length > 0))
    throw std::invalid_argument("TwistProfileDegrees: expected sections >= 1 and length > 0");
  const int mi = scene.marker_index(tip);
  if (mi < 0)
    throw std::invalid_argument("TwistProfileDegrees: the scene has no marker '" + tip + "'");
  std::vector<char> in_body(m.num_vertices(), 0);
  for (const auto& e : m.elements)
    if (e.region == body_region)
      for (int j = 0; j < e.k(); ++j) in_body[e.v[j]] = 1;
  std::vector<std::vector<int>> slab(sections);
  const double w = length / sections;
  for (int v = 0; v < m.num_vertices(); ++v) {
    if (!in_body[v]) continue;
    const int s = static_cast<int>(std::floor(m.vertices(v, 2) / w));
    if (s >= 0 && s < sections) slab[s].push_back(v);
  }
  slab[sections - 1] = scene.markers[mi].vertices;
  std::vector<double> out(sections);
  double prev = 0.0;
  for (int s = 0; s < sections; ++s) {
    const auto& ids = slab[s];
    if (ids.size() < 3)
      throw std::invalid_argument("TwistProfileDegrees: section " + std::to_string(s) + " has " +
                                  std::to_string(ids.size()) +
                                  " body vertices; expected >= 3 (fewer sections?)");
    Eigen::MatrixX3d P(ids.size(), 3), Q(ids.size(), 3);
    for (size_t i = 0; i < ids.size(); ++i) {
      P.row(i) = m.vertices.row(ids[i]);
      Q.row(i) = X.row(ids[i]);
    }
    double a = TwistAboutAxisDegrees(P, Q, Eigen::Vector3d::UnitZ());
    a += 360.0 * std::round((prev - a) / 360.0);  // unwrap: within 180 degrees of the section below
    out[s] = a;
    prev = a;
  }
  return out;
}

}  // namespace softkin
