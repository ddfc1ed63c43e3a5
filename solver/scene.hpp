#pragma once
/// \file scene.hpp
/// What the user describes: a mesh with region tags, the role of every region (body material or
/// actuator), fixed vertices, markers and solver options. Built by an embedded robot generator
/// (robots.hpp) or from a mesh file plus a scene JSON (scene_json.hpp).
#include "solver/fk_options.hpp"
#include "solver/mesh.hpp"

#include <map>
#include <string>
#include <vector>

namespace softkin {

/// A body material: the shape-blending parameter R_omega of Eq. 2.5 (1 = rigid target, i.e.
/// as-rigid-as-possible; 0 = volume-preserving soft target) and the element weight w_i of Eq. 2.10.
struct Material {
  std::string name = "default";
  double r_omega = 1.0;
  double weight = 1.0;
};

enum class ActuatorType { Pneumatic, Cable, Dea };
const char* ActuatorTypeToString(ActuatorType t);
/// Parses "pneumatic" / "cable" / "dea"; returns false if unknown.
bool ActuatorTypeFromString(const std::string& s, ActuatorType* t);

/// An actuator: its elements are all elements whose region tag is in `regions`.
/// Pneumatic: value = total volume ratio alpha (rest 1). Cable: shortening ratio s (rest 1).
/// DEA: area ratio lambda (rest 1).
struct Actuator {
  std::string name;
  ActuatorType type = ActuatorType::Pneumatic;
  std::vector<int> regions;
  double min = 1.0;   ///< lower bound of the actuation value
  double max = 2.0;   ///< upper bound of the actuation value
  double rest = 1.0;  ///< value at which the actuator is at rest
  double weight = 5.0;  ///< w_i of its elements (Sec. 2.5: 5 vs 1 for body elements)
  /// Cable only: the cable's path, a polyline of >= 2 points (mm), from its anchored end to where
  /// it is pulled. Its length is L; the part inside the actuator's elements is sum l_i, the rest
  /// L_R (Eq. 2.6). Each element's cable direction is the tangent of the nearest path segment.
  std::vector<Eigen::Vector3d> path;

  /// The end of the range away from rest: max for an inflating chamber (rest = min), min for a
  /// shortening cable (rest = max).
  double FarEnd() const { return max > rest ? max : min; }
};

/// A named tracked point: the mean of the listed vertices' positions.
struct Marker {
  std::string name;
  std::vector<int> vertices;
};

struct Scene {
  std::string name;
  Mesh mesh;
  std::map<int, Material> body;      ///< region tag -> body material
  std::vector<Actuator> actuators;   ///< in actuation-vector order
  std::vector<int> fixed;            ///< sorted, unique vertex indices held at rest positions
  std::vector<Marker> markers;
  FkOptions solver;                  ///< default solver options for this scene

  int num_actuators() const { return static_cast<int>(actuators.size()); }
  /// Index of the actuator or marker with that name, or -1.
  int actuator_index(const std::string& name) const;
  int marker_index(const std::string& name) const;
  /// Actuation vector with every actuator at rest.
  Eigen::VectorXd rest_actuation() const;
  /// Marker positions (#markers x 3) for vertex positions X.
  Eigen::MatrixX3d marker_positions(const Eigen::Ref<const Eigen::MatrixX3d>& X) const;
  /// Throws std::invalid_argument with a clear message if the scene is inconsistent: a region with
  /// no role or two roles, an actuator without elements, empty fixed set, marker vertex out of
  /// range, bad ranges or materials.
  void validate() const;
};

// ---- helpers to select vertices (shared by robot generators and the scene JSON) ----

/// Vertices with lo <= x <= hi component-wise.
std::vector<int> VerticesInBox(const Mesh& m, const Eigen::Vector3d& lo, const Eigen::Vector3d& hi);
/// Vertices with |n.(x - p)| <= tol (n normalised internally).
std::vector<int> VerticesOnPlane(const Mesh& m, const Eigen::Vector3d& p, const Eigen::Vector3d& n,
                                 double tol);
/// Vertices used by any element with a region tag in `regions`.
std::vector<int> VerticesOfRegions(const Mesh& m, const std::vector<int>& regions);
/// Index of the vertex nearest to p.
int NearestVertex(const Mesh& m, const Eigen::Vector3d& p);

}  // namespace softkin
