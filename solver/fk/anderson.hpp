#pragma once
/// \file anderson.hpp
/// Anderson acceleration (type II, window m) of a fixed-point map x <- G(x), as used to speed up
/// local-global solvers: given G(x_k) and the residual f_k = G(x_k) - x_k it returns
/// x_{k+1} = G(x_k) - dG theta with theta = argmin || f_k - dF theta ||, where dF and dG hold the
/// last m differences of f and G. The caller owns the safeguard (reject when the energy rises).
#include <Eigen/Core>

namespace softkin {

class Anderson {
 public:
  /// dim: length of x; window: m (history columns), >= 1.
  Anderson(int dim, int window);
  /// Forget the history (after a rejected step).
  void Reset();
  /// g = G(x_k), f = G(x_k) - x_k (both length dim). Returns the accelerated x_{k+1} (equal to g on
  /// the first call after a reset).
  const Eigen::VectorXd& Compute(const Eigen::Ref<const Eigen::VectorXd>& g,
                                 const Eigen::Ref<const Eigen::VectorXd>& f);
  int history() const { return cols_; }

 private:
  int dim_, m_;
  int cols_ = 0, next_ = 0, iter_ = 0;
  Eigen::MatrixXd dG_, dF_;  // dim x m
  Eigen::MatrixXd gram_;     // m x m, dF^T dF
  Eigen::VectorXd g_prev_, f_prev_, x_;
};

}  // namespace softkin
