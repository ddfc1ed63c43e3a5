/// \file free_operator.cpp
/// FreeOperator (free_operator.hpp).
#include "softkin/solver/sensitivity/free_operator.hpp"

namespace softkin {

FreeOperator::FreeOperator(const Model& model, EquilibriumLinearization* lin)
    : model_(model), lin_(lin), zero_c_(Eigen::MatrixXd::Zero(model.num_actuators(), 1)) {}

void FreeOperator::Gather(const Eigen::Ref<const Eigen::MatrixXd>& X,
                          Eigen::Ref<Eigen::VectorXd> x) const {
  for (int d = 0; d < 3; ++d) {
    const auto& fv = model_.free_vertices(d);
    const int o = model_.free_offset(d);
    for (size_t i = 0; i < fv.size(); ++i) x[o + static_cast<int>(i)] = X(fv[i], d);
  }
}

void FreeOperator::Scatter(const Eigen::Ref<const Eigen::VectorXd>& x,
                           Eigen::Ref<Eigen::MatrixXd> X) const {
  for (int d = 0; d < 3; ++d) {
    const auto& fv = model_.free_vertices(d);
    const int o = model_.free_offset(d);
    for (size_t i = 0; i < fv.size(); ++i) X(fv[i], d) = x[o + static_cast<int>(i)];
  }
}

Eigen::MatrixXd FreeOperator::Apply(const Eigen::MatrixXd& Y) {
  const int k = static_cast<int>(Y.cols()), nv = model_.num_vertices();
  Yx_.setZero(nv, 3 * k);
  for (int j = 0; j < k; ++j) Scatter(Y.col(j), Yx_.middleCols(3 * j, 3));
  if (zero_c_.cols() != k) zero_c_.setZero(model_.num_actuators(), k);
  lin_->ApplyRhsDerivativeBatch(Yx_, zero_c_, &dB_);
  AY_.noalias() = model_.A() * Yx_;
  AY_ -= dB_;
  Eigen::MatrixXd out(Y.rows(), k);
  for (int j = 0; j < k; ++j) Gather(AY_.middleCols(3 * j, 3), out.col(j));
  return out;
}

Eigen::MatrixXd FreeOperator::Precondition(const Eigen::MatrixXd& V) const {
  const int k = static_cast<int>(V.cols());
  if (pre_) return pre_->solve(V);
  Eigen::MatrixXd out(V.rows(), k);
  if (model_.factor_of_axis(0) == model_.factor_of_axis(1) &&
      model_.factor_of_axis(1) == model_.factor_of_axis(2)) {
    // One factor: every axis of every column is one right-hand side of one solve.
    const int n0 = model_.free_offset(1);
    Eigen::Map<const Eigen::MatrixXd> B(V.data(), n0, 3 * k);
    Eigen::Map<Eigen::MatrixXd> Y(out.data(), n0, 3 * k);
    Y = model_.factorization(model_.factor_of_axis(0)).solve(B);
    return out;
  }
  for (int d = 0; d < 3; ++d) {
    const int o = model_.free_offset(d), n = model_.free_offset(d + 1) - o;
    out.middleRows(o, n) =
        model_.factorization(model_.factor_of_axis(d)).solve(V.middleRows(o, n).eval());
  }
  return out;
}

}  // namespace softkin
