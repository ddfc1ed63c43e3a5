#pragma once
/// \file free_operator.hpp
/// The linearised equilibrium H = A_ff - K_ff (equilibrium_jacobian.hpp) as an operator on the
/// free coordinates (the axis-major layout of Model::GatherFree), applied to blocks of vectors,
/// and its preconditioner: the model's prefactored A_ff, or a factor of an approximation of H
/// (the "local" preconditioner, EquilibriumJacobianWorkspace). Used by the implicit Jacobian and
/// by the Newton FK solver (solver/newton/).
#include "softkin/solver/sensitivity/equilibrium_jacobian.hpp"

namespace softkin {

class FreeOperator {
 public:
  /// `lin` must stay alive and set up (EquilibriumLinearization::Setup) while Apply is used.
  FreeOperator(const Model& model, EquilibriumLinearization* lin);

  /// Free coordinates x (#free) of the #V x 3 block X.
  void Gather(const Eigen::Ref<const Eigen::MatrixXd>& X, Eigen::Ref<Eigen::VectorXd> x) const;
  /// Writes x (#free) into the free coordinates of the #V x 3 block X.
  void Scatter(const Eigen::Ref<const Eigen::VectorXd>& x, Eigen::Ref<Eigen::MatrixXd> X) const;

  /// H Y = A_ff Y - (K Y)_f for Y: #free x k (every prescribed coordinate taken as zero), in one
  /// pass over the elements for all k columns.
  Eigen::MatrixXd Apply(const Eigen::MatrixXd& Y);

  /// Precondition with this factor of an approximation of H (free layout) instead of A_ff; null
  /// returns to A_ff. The factor must outlive its use.
  void SetPreconditioner(const LocalPreconditioner* p) { pre_ = p; }
  /// M^-1 V: all columns in one solve with the chosen factor.
  Eigen::MatrixXd Precondition(const Eigen::MatrixXd& V) const;

 private:
  const Model& model_;
  EquilibriumLinearization* lin_;
  const LocalPreconditioner* pre_ = nullptr;
  Eigen::MatrixXd zero_c_, Yx_, dB_, AY_;
};

}  // namespace softkin
