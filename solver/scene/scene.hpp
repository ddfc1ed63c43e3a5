#pragma once
/// \file scene.hpp
/// What the user describes: a mesh with region tags, the role of every region (body material or
/// actuator), fixed vertices, markers and solver options. Built by an embedded robot generator
/// (robots.hpp) or from a mesh file plus a scene JSON (scene_json.hpp).
#include "softkin/solver/mesh/surface.hpp"
#include "softkin/solver/fk/fk_options.hpp"
#include "softkin/solver/mesh/mesh.hpp"

#include <algorithm>
#include <array>
#include <map>
#include <string>
#include <vector>

namespace softkin {

/// A body material: the shape-blending parameter R_omega of Eq. 2.5 (1 = rigid target, i.e.
/// as-rigid-as-possible; 0 = volume-preserving soft target) and the element weight w_i of Eq. 2.10.
/// A body material. law "blend": Ch. 2 shape blending (Eq. 2.5) with a constant R_omega.
/// law "mooney-rivlin": the hyperelastic target of Eq. 3.6-3.7 with R_omega a function of strain,
/// fitted to the Mooney-Rivlin constants c1, c2 (MPa) with r_omega as its zero-strain value
/// (solver/materials/hyperelastic.hpp).
/// A body material's law (Material::law). Names as for the FK options (fk_options.hpp): ToString,
/// MaterialLawFromString, MaterialLawNames.
enum class MaterialLaw {
  kBlend,         ///< "blend"
  kMooneyRivlin,  ///< "mooney-rivlin"
};
std::string ToString(MaterialLaw law);
MaterialLaw MaterialLawFromString(const std::string& s);
std::vector<std::string> MaterialLawNames();

/// How an element's term of the FK energy is weighted (Scene::element_energy; Eq. 2.10).
/// kShape, "shape": w_i Vol_i |N V^d - R N V^t|^2 as the thesis writes it. The norm compares
/// vertex positions, so for the same strain an element's term grows with its size squared: a
/// mesh with elements of different sizes (graded, or a grid with thin walls) makes its small
/// elements softer, and the energy of a refined mesh falls as h^2.
/// kStrain, "strain": the same term divided by the element's rest size |N V^t|^2 / 3, which for
/// an element without a preferred direction is w_i Vol_i |F - R|^2 to first order: a strain
/// energy, the same for small and large elements. On a mesh whose elements all have the same size
/// and shape both give the same state (the energy differs by a constant factor).
enum class ElementEnergy {
  kShape,   ///< "shape"
  kStrain,  ///< "strain"
};
std::string ToString(ElementEnergy e);
ElementEnergy ElementEnergyFromString(const std::string& s);
std::vector<std::string> ElementEnergyNames();

struct Material {
  std::string name = "default";
  double r_omega = 1.0;
  double weight = 1.0;
  MaterialLaw law = MaterialLaw::kBlend;
  double c1 = 0.0, c2 = 0.0;
  bool hyperelastic() const { return law == MaterialLaw::kMooneyRivlin; }
};

/// Element actuators (pneumatic, cable, DEA) drive actuation elements. Motion actuators
/// (displacement, twist) prescribe a rigid motion of a vertex set instead: a boundary condition
/// swept like an actuation value (the tensile and twisting tests of Fig. 2.6).
enum class ActuatorType { Pneumatic, Cable, Dea, Displacement, Twist };
const char* ActuatorTypeToString(ActuatorType t);
/// Parses "pneumatic" / "cable" / "dea" / "displacement" / "twist"; returns false if unknown.
bool ActuatorTypeFromString(const std::string& s, ActuatorType* t);

/// An actuator: its elements are all elements whose region tag is in `regions` (or in
/// `negative_regions`, for a signed pneumatic actuator).
/// Pneumatic: value = total volume ratio alpha (rest 1). Signed pneumatic (non-empty
/// `negative_regions`, thesis Sec. 5.3.1): value v (rest 0), v > 0 drives the chambers in `regions`
/// to volume ratio 1 + gain v, v < 0 those in `negative_regions` to 1 + gain |v|; the other side
/// is vented (its elements follow the deformation with no energy: targets.hpp, kVented). Cable:
/// shortening ratio s (rest 1). DEA: area ratio lambda (rest 1). Displacement: translation (mm) of
/// `vertices` along `axis`. Twist: rotation (degrees, right-hand rule) of `vertices` about the line
/// through `centre` along `axis`. Motion actuators have no regions; their vertices are held (every
/// coordinate) at the moved positions. A vertex moved by several motion actuators gets their
/// motions composed in actuator order (each applied to the position left by the previous ones; a
/// twist's centre and axis are fixed in space).
struct Actuator {
  std::string name;
  ActuatorType type = ActuatorType::Pneumatic;
  std::vector<int> regions;
  double min = 1.0;     ///< lower bound of the actuation value
  double max = 2.0;     ///< upper bound of the actuation value
  double rest = 1.0;    ///< value at which the actuator is at rest
  double weight = 5.0;  ///< w_i of its elements (Sec. 2.5: 5 vs 1 for body elements)
  /// Cable only: the cable's path, a polyline of >= 2 points (mm), from its anchored end to where
  /// it is pulled. Its length is L; the part inside the actuator's elements is sum l_i, the rest
  /// L_R (Eq. 2.6). Each element's cable direction is the tangent of the nearest path segment.
  std::vector<Eigen::Vector3d> path;
  /// Signed pneumatic only: the opposite side's chamber regions, and the volume ratio per unit of
  /// |value| (e.g. per bar when the value is a pressure).
  std::vector<int> negative_regions;
  double gain = 1.0;
  /// Motion actuators only: the moved vertices, the unit direction / rotation axis, the centre.
  std::vector<int> vertices;
  Eigen::Vector3d axis = Eigen::Vector3d::UnitX();
  Eigen::Vector3d centre = Eigen::Vector3d::Zero();

  bool is_signed() const { return !negative_regions.empty(); }
  bool is_motion() const {
    return type == ActuatorType::Displacement || type == ActuatorType::Twist;
  }
  /// Target ratio of the elements of one side for value v: side 0 = an unsigned actuator (v
  /// itself), +1 / -1 = the positive / negative side of a signed pneumatic actuator.
  double SideRatio(int side, double v) const {
    if (side == 0) return v;
    return 1.0 + gain * std::max(0.0, side * v);
  }
  /// Position of rest point p under the prescribed motion for value v (motion actuators).
  Eigen::Vector3d Move(const Eigen::Vector3d& p, double v) const;

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
  /// For a mesh read from a file (scene JSON): the 0-based position in that file of each mesh
  /// vertex (MeshReport::source_vertex; readers drop vertices no element uses). Empty for a
  /// generated mesh. Vertex indices written in the scene JSON (index files, markers[].vertex) are
  /// file positions and are mapped through it.
  std::vector<int> mesh_source_vertex;
  std::map<int, Material> body;     ///< region tag -> body material
  std::vector<Actuator> actuators;  ///< in actuation-vector order
  std::vector<int> fixed;           ///< sorted, unique vertex indices held at rest positions
  /// Vertices with only some coordinates held at their rest values: fixed_axis[d] lists (sorted,
  /// unique) the vertices whose coordinate d is held, e.g. fixed_axis[2] for vertices sliding on a
  /// plane z = const. Vertices in `fixed` need not be repeated here.
  std::array<std::vector<int>, 3> fixed_axis;
  std::vector<Marker> markers;
  /// Static obstacles (closed, outward-oriented surfaces, mm) the robot must stay out of (Eq. 3.4);
  /// the local-global solvers respond to them with springs (FkOptions::collision).
  std::vector<TriangleSurface> obstacles;
  FkOptions solver;  ///< default solver options for this scene
  /// The weighting of the elements' energy terms (ElementEnergy): "shape" (Eq. 2.10, default) or
  /// "strain" (each term divided by its element's rest size squared).
  ElementEnergy element_energy = ElementEnergy::kShape;
  /// Rest positions for the elements of some regions when they differ from mesh.vertices.
  /// Progressive remeshing (remesh.hpp, thesis Algorithm 2) gives a re-tessellated chamber the
  /// shape it was meshed in as its rest shape, while the body tets sharing its interface vertices
  /// keep theirs (mesh.vertices). Empty `regions`: none. Such a scene has no zero-energy state (the
  /// interface vertices rest differently for the two sides), so warm-start its solves from the
  /// state it was remeshed in; exporters that need one rest mesh (CalculiX) refuse it.
  struct RegionRest {
    std::vector<int> regions;    ///< region tags whose elements use `positions`
    Eigen::MatrixX3d positions;  ///< #V x 3, mm (only the rows of those elements' vertices matter)
  } region_rest;

  int num_actuators() const { return static_cast<int>(actuators.size()); }
  /// Index of the actuator or marker with that name, or -1.
  int actuator_index(const std::string& name) const;
  int marker_index(const std::string& name) const;
  /// Actuation vector with every actuator at rest.
  Eigen::VectorXd rest_actuation() const;
  /// Marker positions (#markers x 3) for vertex positions X.
  Eigen::MatrixX3d marker_positions(const Eigen::Ref<const Eigen::MatrixX3d>& X) const;
  /// The rest positions of the elements with region tag `region`: region_rest.positions if its
  /// regions list it, else mesh.vertices.
  const Eigen::MatrixX3d& rest_positions_of(int region) const;
  /// Whether vertex v's coordinate d is prescribed (fixed, held on axis d, or moved by a motion
  /// actuator). Linear in the constraint lists; for setup code, not inner loops.
  bool is_constrained(int v, int d) const;
  /// Throws std::invalid_argument with a clear message if the scene is inconsistent: a region with
  /// no role or two roles, an actuator without elements, empty fixed set, marker vertex out of
  /// range, bad ranges or materials, a region_rest of the wrong size, non-finite or naming a region
  /// with no elements.
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
