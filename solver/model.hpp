#pragma once
/// \file model.hpp
/// Everything that does not change with the actuation: per-element rest shapes, weights and
/// volumes, the vertex-element incidence and the global matrix of Eq. 2.11 with the fixed vertices
/// eliminated, factored once with SuiteSparse CHOLMOD. Built once, then shared read-only.
#include "solver/element_geometry.hpp"
#include "solver/scene.hpp"

#include <Eigen/CholmodSupport>
#include <Eigen/Sparse>

#include <memory>
#include <vector>

namespace softkin {

enum class ElementRole : std::uint8_t { Body, Pneumatic, Cable, Dea };

/// Per-element constants.
struct ModelElement {
  std::array<int, 6> v{};
  int k = 4;
  ElementRole role = ElementRole::Body;
  int group = -1;         ///< actuator index for actuation elements, -1 for body elements
  double rest_volume = 0; ///< Vol_i, mm^3 (> 0)
  double wv = 0;          ///< w_i * Vol_i, the weight in Eq. 2.10
  double r_omega = 1.0;   ///< shape-blending parameter R_omega (Eq. 2.5), body elements
  ElemRows rest;          ///< N * V_i: centred rest shape (first k rows), mm
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
  const Eigen::MatrixX3d& rest_positions() const { return scene_.mesh.vertices; }
  int num_vertices() const { return scene_.mesh.num_vertices(); }
  int num_free() const { return static_cast<int>(free_vertices_.size()); }
  int num_actuators() const { return scene_.num_actuators(); }
  /// Bounding-box diagonal of the rest mesh, mm (the "model size" for tolerances).
  double size() const { return size_; }

  const std::vector<ModelElement>& elements() const { return elements_; }
  /// Element indices of actuator a.
  const std::vector<int>& actuator_elements(int a) const { return actuator_elements_[a]; }
  /// M_a = sum of mu_i over actuator a's elements: U (volume), A (area) or the cable length
  /// inside actuation elements (actuation.hpp).
  double actuator_rest_measure(int a) const { return actuator_rest_measure_[a]; }
  /// L_R of a cable actuator: the length of its path outside its actuation elements (0 for the
  /// other types). The constraint is c (M + L_R) - L_R = sum_i r_i mu_i.
  double actuator_offset(int a) const { return actuator_offset_[a]; }

  /// Free (non-fixed) vertex ids in order; free_index()[v] is v's row among them, or -1.
  const std::vector<int>& free_vertices() const { return free_vertices_; }
  const std::vector<int>& free_index() const { return free_index_; }

  /// Incidence in CSR form: for vertex v, entries [incidence_offset()[v], incidence_offset()[v+1])
  /// of incidence() encode element e and local slot j as e * 6 + j.
  const std::vector<int>& incidence_offset() const { return inc_offset_; }
  const std::vector<int>& incidence() const { return inc_; }

  /// Full #V x #V matrix A = sum_i w_i Vol_i S_i^T N_i S_i (the Hessian of Eq. 2.10 / 2 with
  /// frozen targets), and its free-free and free-fixed blocks.
  const Eigen::SparseMatrix<double>& A() const { return A_; }
  const Eigen::SparseMatrix<double>& A_ff() const { return A_ff_; }
  const Eigen::SparseMatrix<double>& A_fc() const { return A_fc_; }
  /// Fixed vertex ids in the column order of A_fc.
  const std::vector<int>& fixed_vertices() const { return scene_.fixed; }

  /// Solves A_ff Y = rhs for #free x 3 right-hand sides with the prefactored CHOLMOD factor.
  /// Not safe to call concurrently on one Model.
  Eigen::MatrixX3d SolveFree(const Eigen::Ref<const Eigen::MatrixX3d>& rhs) const;
  /// Time spent in symbolic + numeric factorisation, s.
  double factor_time_s() const { return factor_time_s_; }

 private:
  /// Cable actuator a: per-element directions, Q d and length shares; L_R.
  void SetUpCable(int a);
  Scene scene_;
  double size_ = 0;
  std::vector<ModelElement> elements_;
  std::vector<std::vector<int>> actuator_elements_;
  std::vector<double> actuator_rest_measure_, actuator_offset_;
  std::vector<int> free_vertices_, free_index_;
  std::vector<int> inc_offset_, inc_;
  Eigen::SparseMatrix<double> A_, A_ff_, A_fc_;
  mutable Eigen::CholmodDecomposition<Eigen::SparseMatrix<double>, Eigen::Lower> chol_;
  double factor_time_s_ = 0;
};

}  // namespace softkin
