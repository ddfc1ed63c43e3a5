#pragma once
/// \file model.hpp
/// Everything that does not change with the actuation: per-element rest shapes, weights and
/// volumes, the vertex-element incidence and the global matrix of Eq. 2.11 with the fixed vertices
/// eliminated, factored once with SuiteSparse CHOLMOD. Built once, then shared read-only.
#include "softkin/solver/mesh/element_geometry.hpp"
#include "softkin/solver/materials/hyperelastic.hpp"
#include "softkin/solver/scene/scene.hpp"

#include <Eigen/CholmodSupport>
#include <Eigen/Sparse>

#include <array>
#include <map>
#include <memory>
#include <vector>

namespace softkin {

enum class ElementRole : std::uint8_t { Body, Pneumatic, Cable, Dea };

/// Eigen's CHOLMOD wrapper with read access to the CHOLMOD factor it holds, so that a solver can
/// copy it and modify the copy (update/downdate, spring_system.hpp).
class CholmodFactorization
    : public Eigen::CholmodDecomposition<Eigen::SparseMatrix<double>, Eigen::Lower> {
 public:
  /// The numeric factor (null before compute()).
  const cholmod_factor* factor() const { return m_cholmodFactor; }
};

/// Per-element constants.
struct ModelElement {
  std::array<int, 6> v{};
  int k = 4;
  ElementRole role = ElementRole::Body;
  int group =
      -1;  ///< actuation group (Model::group_elements) of actuation elements, -1 for body elements
  double rest_volume = 0;  ///< Vol_i, mm^3 (> 0)
  double wv = 0;           ///< w_i * Vol_i, the weight in Eq. 2.10
  double r_omega = 1.0;    ///< shape-blending parameter R_omega (Eq. 2.5), body elements
  /// Hyperelastic body elements (Eq. 3.6-3.7): R_omega(strain), owned by the Model; else null.
  const ROmegaCurve* curve = nullptr;
  ElemRows rest;  ///< N * V_i: centred rest shape (first k rows), mm
  /// Actuation elements (actuation.hpp): mu_i, the rest value of the constrained measure (volume,
  /// mm^3; mean triangle area, mm^2; the element's share l_i of the cable length, mm).
  double measure0 = 0;
  /// Cable: unit cable direction d at the element; DEA: unit rest normal n. Rest frame.
  Eigen::Vector3d axis = Eigen::Vector3d::Zero();
  /// Cable: Q d with Q = P (P^T P)^-1 (P the centred rest rows), so that F d = D^T (Q d).
  std::array<double, 6> qd{};
};

class Model {
 public:
  /// Builds the model of a validated scene; throws std::invalid_argument if the scene is invalid
  /// and std::runtime_error if the matrix cannot be factored.
  explicit Model(const Scene& scene);
  Model(const Model&) = delete;
  Model& operator=(const Model&) = delete;

  const Scene& scene() const { return scene_; }
  const Mesh& mesh() const { return scene_.mesh; }
  /// The mesh's rest vertex positions (the solvers' starting point). Elements of the regions in
  /// Scene::region_rest take their rest shapes from there instead (ModelElement::rest).
  const Eigen::MatrixX3d& rest_positions() const { return scene_.mesh.vertices; }
  int num_vertices() const { return scene_.mesh.num_vertices(); }
  int num_actuators() const { return scene_.num_actuators(); }
  /// Bounding-box diagonal of the rest mesh, mm (the "model size" for tolerances).
  double size() const { return size_; }

  const std::vector<ModelElement>& elements() const { return elements_; }
  /// The fitted R_omega(strain) of a hyperelastic body region, null for other regions.
  const ROmegaCurve* curve(int region) const {
    auto it = curves_.find(region);
    return it == curves_.end() ? nullptr : &it->second;
  }

  // ---- Actuation groups ----
  // A group is the set of actuation elements that share one constraint (Eq. 2.6-2.8): one per
  // element actuator, two for a signed pneumatic actuator (its positive and negative sides).
  // Motion actuators have no group.
  int num_groups() const { return static_cast<int>(groups_.size()); }
  const std::vector<int>& group_elements(int g) const { return groups_[g].elements; }
  int group_actuator(int g) const { return groups_[g].actuator; }
  /// 0: unsigned actuator; +1 / -1: positive / negative side of a signed one.
  int group_side(int g) const { return groups_[g].side; }
  /// M_g = sum of mu_i over the group's elements: U (volume), A (area) or the cable length inside
  /// actuation elements (actuation.hpp).
  double group_rest_measure(int g) const { return groups_[g].rest_measure; }
  /// L_R of a cable group: its path length outside its actuation elements (0 for the other types).
  /// The constraint is rho (M + L_R) - L_R = sum_i r_i mu_i, rho = GroupRatio(g, c).
  double group_offset(int g) const { return groups_[g].offset; }
  /// The group's target ratio rho for actuation vector c (Actuator::SideRatio).
  double GroupRatio(int g, const Eigen::Ref<const Eigen::VectorXd>& c) const;
  /// Whether group g is vented at c: the side of a signed actuator that c does not drive (its
  /// elements follow the deformation with no energy; targets.hpp, kVented).
  bool GroupVented(int g, const Eigen::Ref<const Eigen::VectorXd>& c) const {
    return groups_[g].side != 0 && !(groups_[g].side * c[groups_[g].actuator] > 0.0);
  }
  /// Actuator a's value implied by per-group achieved ratios (the inverse of GroupRatio; a motion
  /// actuator's value is prescribed exactly, so it is c[a]).
  double ActuatorValue(int a, const std::vector<double>& group_ratios,
                       const Eigen::Ref<const Eigen::VectorXd>& c) const;
  /// Shorthands for the first (positive or only) group of an element actuator a.
  const std::vector<int>& actuator_elements(int a) const;
  double actuator_rest_measure(int a) const;
  double actuator_offset(int a) const;

  // ---- Constraints and the free degrees of freedom ----
  // Coordinate d of vertex v is either prescribed (v fixed, held on axis d, or moved by a motion
  // actuator) or free. The free coordinates, axis by axis (all free x, then y, then z, each in
  // vertex order), form the unknown vector x of the global step.
  /// Number of free coordinates.
  int num_free_dofs() const { return free_offset_[3]; }
  /// Free vertex ids of axis d in order; free_index(d)[v] is v's position among them, or -1.
  const std::vector<int>& free_vertices(int d = 0) const { return free_[d]; }
  const std::vector<int>& free_index(int d = 0) const { return free_index_[d]; }
  /// Number of vertices with every coordinate free.
  int num_free() const { return num_fully_free_; }
  /// Vertices with every coordinate prescribed (fixed or moved), sorted.
  const std::vector<int>& fixed_vertices() const { return fully_held_; }
  /// x = the free coordinates of X (#V x 3).
  void GatherFree(const Eigen::Ref<const Eigen::MatrixX3d>& X, Eigen::VectorXd* x) const;
  /// Writes the free coordinates x into X, leaving the prescribed ones untouched.
  void ScatterFree(const Eigen::VectorXd& x, Eigen::MatrixX3d* X) const;
  /// Sets X's prescribed coordinates for actuation c: rest values for fixed and held ones, the
  /// moved rest positions for motion actuators' vertices. Free coordinates are untouched.
  void ApplyConstraints(const Eigen::Ref<const Eigen::VectorXd>& c, Eigen::MatrixX3d* X) const;

  /// Incidence in CSR form: for vertex v, entries [incidence_offset()[v], incidence_offset()[v+1])
  /// of incidence() encode element e and local slot j as e * 6 + j.
  const std::vector<int>& incidence_offset() const { return inc_offset_; }
  const std::vector<int>& incidence() const { return inc_; }

  /// Full #V x #V matrix A = sum_i w_i Vol_i S_i^T N_i S_i (the Hessian of Eq. 2.10 / 2 with
  /// frozen targets; the same for x, y and z), and its free-free block of axis d.
  const Eigen::SparseMatrix<double>& A() const { return A_; }
  const Eigen::SparseMatrix<double>& A_ff(int d = 0) const {
    return *factors_[factor_of_axis_[d]].A_ff;
  }
  /// Number of distinct factorisations (1 when every axis has the same free vertices).
  int num_factors() const { return static_cast<int>(factors_.size()); }
  /// Which factorisation axis d uses (in [0, num_factors())).
  int factor_of_axis(int d) const { return factor_of_axis_[d]; }
  /// Factorisation f (A_ff of its axes, factored by CHOLMOD; simplicial LL^T).
  const CholmodFactorization& factorization(int f) const { return *factors_[f].chol; }
  /// Offset of axis d's block in the free-coordinate layout (GatherFree).
  int free_offset(int d) const { return free_offset_[d]; }

  /// Solves A_ff y = rhs axis by axis with the prefactored CHOLMOD factors; rhs and the result
  /// are in the free-coordinate layout (GatherFree). Not safe to call concurrently on one Model.
  Eigen::VectorXd SolveFree(const Eigen::VectorXd& rhs) const;
  /// Time spent in symbolic + numeric factorisation, s.
  double factor_time_s() const { return factor_time_s_; }

 private:
  /// Throws std::invalid_argument if the coordinates held in one connected part of the mesh
  /// (`part`: its vertices; held[d][v]: coordinate d of v is prescribed) leave a rigid motion of
  /// that part free, e.g. a rotation about a single fixed vertex or a line of fixed vertices.
  void CheckRotationsHeld(const std::vector<int>& part,
                          const std::array<std::vector<char>, 3>& held) const;
  struct Group {
    int actuator = -1, side = 0;
    std::vector<int> elements;
    double rest_measure = 0, offset = 0;
  };
  struct Factor {
    std::unique_ptr<Eigen::SparseMatrix<double>> A_ff;
    std::unique_ptr<CholmodFactorization> chol;
  };
  /// Cable group g: per-element directions, Q d and length shares; L_R.
  void SetUpCable(int g);
  void SetUpConstraints();
  Scene scene_;
  double size_ = 0;
  std::vector<ModelElement> elements_;
  std::map<int, ROmegaCurve> curves_;  ///< per hyperelastic body region (stable addresses)
  std::vector<Group> groups_;
  std::vector<int> first_group_;  ///< per actuator: its first group, -1 for motion actuators
  std::array<std::vector<int>, 3> free_, free_index_;
  std::array<int, 4> free_offset_{};
  std::vector<int> fully_held_;
  int num_fully_free_ = 0;
  std::vector<int> inc_offset_, inc_;
  Eigen::SparseMatrix<double> A_;
  std::vector<Factor> factors_;
  std::array<int, 3> factor_of_axis_{};
  double factor_time_s_ = 0;
};

}  // namespace softkin
