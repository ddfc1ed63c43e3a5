#include "softkin/solver/scene/scene.hpp"

#include "softkin/solver/common/enum_names.hpp"

#include <Eigen/Geometry>

#include <algorithm>
#include <cmath>
#include <set>
#include <sstream>
#include <stdexcept>

namespace softkin {

namespace {
constexpr EnumName<MaterialLaw> kLawNames[] = {
    {MaterialLaw::kBlend, "blend"},
    {MaterialLaw::kMooneyRivlin, "mooney-rivlin"},
};
constexpr EnumName<ElementEnergy> kElementEnergyNames[] = {
    {ElementEnergy::kShape, "shape"},
    {ElementEnergy::kStrain, "strain"},
};
}  // namespace

std::string ToString(MaterialLaw law) { return EnumToString(kLawNames, law); }
MaterialLaw MaterialLawFromString(const std::string& s) {
  return EnumFromString(kLawNames, s, "material law");
}
std::vector<std::string> MaterialLawNames() { return EnumNames(kLawNames); }

std::string ToString(ElementEnergy e) { return EnumToString(kElementEnergyNames, e); }
ElementEnergy ElementEnergyFromString(const std::string& s) {
  return EnumFromString(kElementEnergyNames, s, "element energy");
}
std::vector<std::string> ElementEnergyNames() { return EnumNames(kElementEnergyNames); }

const char* ActuatorTypeToString(ActuatorType t) {
  switch (t) {
    case ActuatorType::Pneumatic:
      return "pneumatic";
    case ActuatorType::Cable:
      return "cable";
    case ActuatorType::Dea:
      return "dea";
    case ActuatorType::Displacement:
      return "displacement";
    case ActuatorType::Twist:
      return "twist";
  }
  return "unknown";
}

bool ActuatorTypeFromString(const std::string& s, ActuatorType* t) {
  if (s == "pneumatic") {
    *t = ActuatorType::Pneumatic;
    return true;
  }
  if (s == "cable") {
    *t = ActuatorType::Cable;
    return true;
  }
  if (s == "dea") {
    *t = ActuatorType::Dea;
    return true;
  }
  if (s == "displacement") {
    *t = ActuatorType::Displacement;
    return true;
  }
  if (s == "twist") {
    *t = ActuatorType::Twist;
    return true;
  }
  return false;
}

Eigen::Vector3d Actuator::Move(const Eigen::Vector3d& p, double v) const {
  const Eigen::Vector3d u = axis.normalized();
  if (type == ActuatorType::Displacement) return p + v * u;
  if (type == ActuatorType::Twist) {
    const double a = v * std::acos(-1.0) / 180.0;
    return centre + Eigen::AngleAxisd(a, u) * (p - centre);
  }
  return p;
}

bool Scene::is_constrained(int v, int d) const {
  if (std::binary_search(fixed.begin(), fixed.end(), v)) return true;
  if (std::binary_search(fixed_axis[d].begin(), fixed_axis[d].end(), v)) return true;
  for (const auto& a : actuators)
    if (a.is_motion() && std::find(a.vertices.begin(), a.vertices.end(), v) != a.vertices.end())
      return true;
  return false;
}

int Scene::actuator_index(const std::string& n) const {
  for (int i = 0; i < num_actuators(); ++i)
    if (actuators[i].name == n) return i;
  return -1;
}

int Scene::marker_index(const std::string& n) const {
  for (int i = 0; i < static_cast<int>(markers.size()); ++i)
    if (markers[i].name == n) return i;
  return -1;
}

Eigen::VectorXd Scene::rest_actuation() const {
  Eigen::VectorXd c(num_actuators());
  for (int i = 0; i < num_actuators(); ++i) c[i] = actuators[i].rest;
  return c;
}

Eigen::MatrixX3d Scene::marker_positions(const Eigen::Ref<const Eigen::MatrixX3d>& X) const {
  Eigen::MatrixX3d P(markers.size(), 3);
  for (size_t i = 0; i < markers.size(); ++i) {
    Eigen::RowVector3d s = Eigen::RowVector3d::Zero();
    for (int v : markers[i].vertices) s += X.row(v);
    P.row(i) = s / std::max<size_t>(1, markers[i].vertices.size());
  }
  return P;
}

const Eigen::MatrixX3d& Scene::rest_positions_of(int region) const {
  for (int r : region_rest.regions)
    if (r == region) return region_rest.positions;
  return mesh.vertices;
}

namespace {

/// The first problem of body material `mat` of region `tag` ("" if none).
std::string BodyMaterialError(int tag, const Material& mat) {
  if (!(mat.r_omega >= 0.0 && mat.r_omega <= 1.0))
    return "body region " + std::to_string(tag) + ": r_omega must be in [0, 1], got " +
           std::to_string(mat.r_omega);
  if (!(mat.weight > 0.0)) return "body region " + std::to_string(tag) + ": weight must be > 0";
  if (mat.hyperelastic() && !(mat.c1 >= 0 && mat.c2 >= 0 && mat.c1 + mat.c2 > 0 && mat.r_omega > 0))
    return "body region " + std::to_string(tag) +
           ": a mooney-rivlin material needs c1, c2 >= 0 "
           "with c1 + c2 > 0 (MPa) and r_omega > 0, got c1 = " +
           std::to_string(mat.c1) + ", c2 = " + std::to_string(mat.c2) +
           ", r_omega = " + std::to_string(mat.r_omega);
  return "";
}

/// The first problem of actuator `a` on its own ("" if none): its range, weight and kind-specific
/// data (a motion actuator's moved vertices, which are added to *moved, of a mesh with
/// num_vertices vertices; a signed actuator's gain; a cable's path).
std::string ActuatorError(const Actuator& a, int num_vertices, std::set<int>* moved) {
  const std::string what = std::string(ActuatorTypeToString(a.type)) + " actuator '" + a.name + "'";
  if (!(a.min <= a.rest && a.rest <= a.max))
    return what + ": expected min <= rest <= max, got " + std::to_string(a.min) + ", " +
           std::to_string(a.rest) + ", " + std::to_string(a.max);
  if (!(a.weight > 0.0)) return what + ": weight must be > 0";
  if (!a.path.empty() && a.type != ActuatorType::Cable)
    return what + ": only cable actuators have a path";
  if (a.is_signed() && a.type != ActuatorType::Pneumatic)
    return what + ": only pneumatic actuators can be signed (have negative_regions)";
  if (!a.vertices.empty() && !a.is_motion())
    return what + ": only displacement and twist actuators move vertices";
  if (a.is_motion()) {
    if (!a.regions.empty()) return what + ": a motion actuator has no regions";
    if (a.vertices.empty()) return what + ": expected at least one moved vertex";
    std::set<int> own;
    for (int v : a.vertices) {
      if (v < 0 || v >= num_vertices)
        return what + ": moved vertex " + std::to_string(v) + " is out of range";
      if (!own.insert(v).second) return what + ": vertex " + std::to_string(v) + " is listed twice";
      moved->insert(v);
    }
    if (!(a.axis.allFinite() && a.axis.norm() > 0)) return what + ": expected a non-zero axis";
    if (!a.centre.allFinite()) return what + ": the centre must be finite";
    if (!(std::isfinite(a.min) && std::isfinite(a.max))) return what + ": expected a finite range";
    return "";
  }
  if (a.is_signed()) {
    if (!(a.min <= 0.0 && a.max >= 0.0 && a.rest == 0.0))
      return what + ": a signed actuator has rest 0 and min <= 0 <= max";
    if (!(a.gain > 0.0 && std::isfinite(a.gain))) return what + ": gain must be > 0";
  } else if (!(a.min > 0.0)) {
    return what + ": expected 0 < min <= rest <= max (the value is a ratio)";
  }
  if (a.regions.empty()) return what + " has no regions";
  if (a.type == ActuatorType::Cable) {
    if (a.path.size() < 2) return "cable '" + a.name + "': expected a path of at least 2 points";
    for (const auto& p : a.path)
      if (!p.allFinite()) return "cable '" + a.name + "': path points must be finite";
    double len = 0;
    for (size_t q = 1; q < a.path.size(); ++q) len += (a.path[q] - a.path[q - 1]).norm();
    if (!(len > 0)) return "cable '" + a.name + "': the path has zero length";
  }
  return "";
}

}  // namespace

void Scene::validate() const {
  auto fail = [&](const std::string& m) {
    throw std::invalid_argument("scene '" + name + "': " + m);
  };
  if (mesh.num_elements() == 0) fail("the mesh has no elements");
  std::map<int, std::string> role;
  for (const auto& [tag, mat] : body) {
    role[tag] = "body material '" + mat.name + "'";
    const std::string error = BodyMaterialError(tag, mat);
    if (!error.empty()) fail(error);
  }
  std::set<std::string> names;
  std::set<int> moved;
  for (const auto& a : actuators) {
    if (a.name.empty()) fail("an actuator has an empty name");
    if (!names.insert(a.name).second) fail("actuator name '" + a.name + "' is used twice");
    const std::string error = ActuatorError(a, mesh.num_vertices(), &moved);
    if (!error.empty()) fail(error);
    if (a.is_motion()) continue;
    std::vector<int> all = a.regions;
    all.insert(all.end(), a.negative_regions.begin(), a.negative_regions.end());
    for (int r : all) {
      auto it = role.find(r);
      if (it != role.end())
        fail("region " + std::to_string(r) + " is both " + it->second + " and actuator '" + a.name +
             "'");
      role[r] = "actuator '" + a.name + "'";
    }
  }
  std::set<int> used;
  for (const auto& e : mesh.elements) used.insert(e.region);
  if (!region_rest.regions.empty()) {
    if (region_rest.positions.rows() != mesh.num_vertices())
      fail("region_rest: expected one row of rest positions per vertex (" +
           std::to_string(mesh.num_vertices()) + "), got " +
           std::to_string(region_rest.positions.rows()));
    if (!region_rest.positions.allFinite()) fail("region_rest: expected finite rest positions");
    for (int r : region_rest.regions)
      if (!used.count(r)) fail("region_rest: region " + std::to_string(r) + " has no elements");
  }
  for (int r : used)
    if (!role.count(r))
      fail("region " + std::to_string(r) + " has elements but no role (body or actuator)");
  for (const auto& a : actuators) {
    if (a.is_motion()) continue;
    for (const auto* regs : {&a.regions, &a.negative_regions}) {
      if (regs->empty()) continue;
      bool any = false;
      for (int r : *regs) any = any || used.count(r);
      if (!any)
        fail("actuator '" + a.name + "' has no elements in the mesh" +
             (regs == &a.negative_regions ? " on its negative side" : ""));
    }
    if (a.type == ActuatorType::Dea) {
      const std::set<int> regs(a.regions.begin(), a.regions.end());
      for (int i = 0; i < mesh.num_elements(); ++i)
        if (regs.count(mesh.elements[i].region) && mesh.elements[i].k() != 6)
          fail("DEA actuator '" + a.name + "': element " + std::to_string(i) +
               " is a tet; expected prism elements (Sec. 2.3.3)");
    }
  }
  auto sorted_unique = [](const std::vector<int>& v) {
    for (size_t q = 1; q < v.size(); ++q)
      if (!(v[q - 1] < v[q])) return false;
    return true;
  };
  if (!sorted_unique(fixed)) fail("the fixed vertex list must be sorted and without repeats");
  for (int d = 0; d < 3; ++d) {
    if (!sorted_unique(fixed_axis[d]))
      fail(std::string("the list of vertices held on axis ") + "xyz"[d] +
           " must be sorted and without repeats");
    if (fixed.empty() && moved.empty() && fixed_axis[d].empty())
      fail(std::string("no vertex is fixed, moved or held on axis ") + "xyz"[d] +
           ": the problem would have a rigid-motion null space");
  }
  for (int v : fixed)
    if (v < 0 || v >= mesh.num_vertices())
      fail("fixed vertex " + std::to_string(v) + " is out of range");
  for (int d = 0; d < 3; ++d)
    for (int v : fixed_axis[d])
      if (v < 0 || v >= mesh.num_vertices())
        fail("vertex " + std::to_string(v) + " held on axis " + "xyz"[d] + " is out of range");
  for (int v : fixed)
    if (moved.count(v)) fail("vertex " + std::to_string(v) + " is both fixed and moved");
  std::set<std::string> mnames;
  for (const auto& m : markers) {
    if (!mnames.insert(m.name).second) fail("marker name '" + m.name + "' is used twice");
    if (m.vertices.empty()) fail("marker '" + m.name + "' selects no vertex");
    for (int v : m.vertices)
      if (v < 0 || v >= mesh.num_vertices())
        fail("marker '" + m.name + "': vertex " + std::to_string(v) + " is out of range");
  }
  std::string why;
  if (!solver.IsValid(&why)) fail("solver options: " + why);
}

std::vector<int> VerticesInBox(const Mesh& m, const Eigen::Vector3d& lo,
                               const Eigen::Vector3d& hi) {
  std::vector<int> out;
  for (int i = 0; i < m.num_vertices(); ++i) {
    Eigen::Vector3d x = m.vertices.row(i).transpose();
    if ((x.array() >= lo.array()).all() && (x.array() <= hi.array()).all()) out.push_back(i);
  }
  return out;
}

std::vector<int> VerticesOnPlane(const Mesh& m, const Eigen::Vector3d& p, const Eigen::Vector3d& n,
                                 double tol) {
  std::vector<int> out;
  const Eigen::Vector3d u = n.normalized();
  for (int i = 0; i < m.num_vertices(); ++i)
    if (std::abs(u.dot(m.vertices.row(i).transpose() - p)) <= tol) out.push_back(i);
  return out;
}

std::vector<int> VerticesOfRegions(const Mesh& m, const std::vector<int>& regions) {
  std::vector<char> mark(m.num_vertices(), 0);
  for (const auto& e : m.elements)
    if (std::find(regions.begin(), regions.end(), e.region) != regions.end())
      for (int j = 0; j < e.k(); ++j) mark[e.v[j]] = 1;
  std::vector<int> out;
  for (int i = 0; i < m.num_vertices(); ++i)
    if (mark[i]) out.push_back(i);
  return out;
}

int NearestVertex(const Mesh& m, const Eigen::Vector3d& p) {
  int best = -1;
  double bd = 0;
  for (int i = 0; i < m.num_vertices(); ++i) {
    double d = (m.vertices.row(i).transpose() - p).squaredNorm();
    if (best < 0 || d < bd) {
      best = i;
      bd = d;
    }
  }
  return best;
}

}  // namespace softkin
