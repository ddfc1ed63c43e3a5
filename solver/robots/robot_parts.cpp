/// \file robot_parts.cpp
/// The helpers the robot generators share (robot_parts.hpp).
#include "softkin/solver/robots/robot_parts.hpp"

#include "softkin/solver/common/text_format.hpp"
#include "softkin/solver/materials/hyperelastic.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>
#include <vector>

namespace softkin {
namespace robots_detail {

int Cells(double mm, double h) { return std::max(1, static_cast<int>(std::lround(mm / h))); }

void AddDistalFaceMarkers(double xmax, double zmax, double eps, Scene* s) {
  const Mesh& m = s->mesh;
  s->markers.push_back({"tip", VerticesInBox(m, Eigen::Vector3d(xmax - eps, -kInf, -kInf),
                                             Eigen::Vector3d(xmax + eps, kInf, kInf))});
  s->markers.push_back(
      {"tip_top", VerticesInBox(m, Eigen::Vector3d(xmax - eps, -kInf, 0.75 * zmax - eps),
                                Eigen::Vector3d(xmax + eps, kInf, kInf))});
  s->markers.push_back(
      {"tip_bottom", VerticesInBox(m, Eigen::Vector3d(xmax - eps, -kInf, -kInf),
                                   Eigen::Vector3d(xmax + eps, kInf, 0.25 * zmax + eps))});
}

ChamberRow MakeChamberRow(int x0, int x1, int wall, int cavity, int min_solid) {
  ChamberRow r{x0, x1, wall, cavity, 0, 0};
  const int pitch = wall + cavity;
  r.chambers = std::max(0, (x1 - x0 - min_solid - wall) / pitch);
  r.first = x1 - r.chambers * pitch - wall;
  return r;
}

std::vector<double> DesignLines(const std::vector<double>& b, double h,
                                const std::vector<bool>& even) {
  std::vector<double> lines = {b[0]};
  for (size_t q = 0; q + 1 < b.size(); ++q) {
    int n = std::max(1, static_cast<int>(std::lround((b[q + 1] - b[q]) / h)));
    if (q < even.size() && even[q] && n % 2) ++n;
    for (int i = 1; i <= n; ++i) lines.push_back(b[q] + (b[q + 1] - b[q]) * i / n);
  }
  return lines;
}

bool FlagParam(const std::string& robot, const RobotParams& P, const std::string& key,
               const std::string& off, const std::string& on) {
  const double v = P.at(key);
  if (v != 0.0 && v != 1.0)
    throw std::invalid_argument(robot + ": parameter '" + key + "' must be 0 (" + off + ") or 1 (" +
                                on + "), got " + FormatNumber(v));
  return v == 1.0;
}

bool DesignGridFlag(const std::string& robot, const RobotParams& P) {
  return FlagParam(robot, P, "design_grid", "snap to cells",
                   "grid lines on the design's dimensions");
}

RobotParam ChamberWeightParam() {
  return {"chamber_weight", Actuator{}.weight, 0.01, 100.0,
          "weight w_i of the chamber (actuation) elements in Eq. 2.10, against the body's 1 "
          "(default 5, Sec. 2.5); a soft chamber fill lags its target volume (docs/fidelity.md)"};
}

bool InCavity(const ChamberRow& r, int i) {
  const int u = i - r.first;
  if (u < 0 || u >= r.chambers * (r.wall + r.cavity)) return false;
  return u % (r.wall + r.cavity) >= r.wall;
}

Material MooneyRivlinMaterial(const std::string& name, const std::string& named, double weight) {
  MooneyRivlin mr;
  if (!NamedMooneyRivlin(named, &mr))
    throw std::logic_error("unknown built-in material '" + named + "'");
  Material m{name, 1.0, weight};
  m.law = MaterialLaw::kMooneyRivlin;
  m.c1 = mr.c1;
  m.c2 = mr.c2;
  return m;
}

void CutSlit(Mesh* mesh, const std::function<bool(const Eigen::Vector3d&)>& on_cut,
             const std::function<bool(const Eigen::Vector3d&)>& far_side,
             const Eigen::Vector3d& shift) {
  const int n0 = mesh->num_vertices();
  std::vector<char> near(n0, 0), far(n0, 0);
  std::vector<char> tet_far(mesh->elements.size(), 0);
  for (size_t t = 0; t < mesh->elements.size(); ++t) {
    const auto& e = mesh->elements[t];
    Eigen::Vector3d c = Eigen::Vector3d::Zero();
    for (int a = 0; a < e.k(); ++a) c += mesh->vertices.row(e.v[a]).transpose() / e.k();
    tet_far[t] = far_side(c);
    for (int a = 0; a < e.k(); ++a) (tet_far[t] ? far : near)[e.v[a]] = 1;
  }
  std::vector<int> copy(n0, -1);
  int next = n0;
  for (int v = 0; v < n0; ++v)
    if (far[v] && on_cut(mesh->vertices.row(v).transpose())) copy[v] = near[v] ? next++ : v;
  mesh->vertices.conservativeResize(next, 3);
  for (int v = 0; v < n0; ++v) {
    if (copy[v] < 0) continue;
    mesh->vertices.row(copy[v]) = mesh->vertices.row(v) + shift.transpose();
  }
  for (size_t t = 0; t < mesh->elements.size(); ++t) {
    if (!tet_far[t]) continue;
    auto& e = mesh->elements[t];
    for (int a = 0; a < e.k(); ++a)
      if (copy[e.v[a]] >= 0) e.v[a] = copy[e.v[a]];
  }
}

}  // namespace robots_detail
}  // namespace softkin
