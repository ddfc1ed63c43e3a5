#pragma once
/// \file gmres.hpp
/// Restarted, left-preconditioned GMRES for one right-hand side, advanced one operator product at
/// a time (Request / Consume), so that a caller can batch the products of several solves (the
/// implicit Jacobian's columns, equilibrium_jacobian.cpp) or run one solve inside its own loop
/// (the Newton FK solver, solver/newton/). The basis is orthogonalised by classical Gram-Schmidt
/// with one re-orthogonalisation (CGS2: as stable as modified Gram-Schmidt, with matrix-vector
/// products); the residual is recomputed from scratch at each restart and at the end.
#include <Eigen/Core>

namespace softkin {

/// Solves M^-1 A y = M^-1 rhs: the caller applies w = M^-1 A v to the vectors it is asked for.
class GmresColumn {
 public:
  /// b = M^-1 rhs, y0 the start, `restart` the basis size, `max_it` the products allowed (over
  /// all restarts), `tol` the relative (preconditioned) residual to reach.
  GmresColumn(Eigen::VectorXd b, Eigen::VectorXd y0, int restart, int max_it, double tol);

  bool done() const { return done_; }
  /// Operator products consumed so far.
  int products() const { return products_; }
  /// ||b - M^-1 A y|| / ||b|| of the current y (the last recomputed or estimated value). Within
  /// a cycle y (and rel) stay at the cycle's start: see estimate() and Stop().
  double rel() const { return rel_; }
  /// GMRES's running estimate of the relative residual after the products so far (the Givens
  /// residual of the current cycle; rel() before the first product of a cycle).
  double estimate() const;
  /// Ends the solve after the products so far: y takes the current cycle's correction and rel()
  /// its estimate. For a caller that gives up early (a stall test).
  void Stop();
  const Eigen::VectorXd& y() const { return y_; }
  /// The vector the next product is applied to.
  const Eigen::VectorXd& Request();
  /// Feeds w = M^-1 A Request().
  void Consume(const Eigen::VectorXd& w);

 private:
  void Grow(int cols);
  void StartCycle(const Eigen::VectorXd& r);
  /// y += the correction of the current cycle's j_ basis vectors (its small triangular solve).
  void FoldCycle();

  Eigen::VectorXd b_, y_, next_;
  int m_, max_it_;
  double tol_, beta0_ = 0.0, rel_ = 1.0;
  Eigen::MatrixXd V_, Hh_;
  Eigen::VectorXd g_, cs_, sn_;
  int j_ = 0, products_ = 0;
  bool done_ = false, want_residual_ = false;
  bool folded_ = false;  ///< y_ holds the current cycle's correction (awaiting its residual)
};

}  // namespace softkin
