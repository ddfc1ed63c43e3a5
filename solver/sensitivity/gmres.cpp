/// \file gmres.cpp
/// GmresColumn (gmres.hpp).
#include "softkin/solver/sensitivity/gmres.hpp"

#include <Eigen/Dense>

#include <algorithm>
#include <cmath>
#include <limits>
#include <utility>

namespace softkin {

GmresColumn::GmresColumn(Eigen::VectorXd b, Eigen::VectorXd y0, int restart, int max_it, double tol)
    : b_(std::move(b)),
      y_(std::move(y0)),
      m_(std::max(1, std::min(restart, max_it))),
      max_it_(max_it),
      tol_(tol) {
  beta0_ = b_.norm();
  if (!(beta0_ > 0.0)) {
    done_ = true;  // rhs = 0: y = 0 exactly
    y_.setZero();
    rel_ = 0.0;
    return;
  }
  if (y_.squaredNorm() > 0.0) {
    want_residual_ = true;  // the start's residual costs a product
  } else {
    StartCycle(b_);
  }
}

const Eigen::VectorXd& GmresColumn::Request() {
  if (want_residual_) return y_;
  next_ = V_.col(j_);
  return next_;
}

void GmresColumn::Consume(const Eigen::VectorXd& w) {
  ++products_;
  if (want_residual_) {
    want_residual_ = false;
    StartCycle(b_ - w);
    return;
  }
  const int j = j_;
  // CGS2 against the j + 1 basis vectors.
  Eigen::VectorXd v = w;
  Eigen::VectorXd h = V_.leftCols(j + 1).transpose() * v;
  v.noalias() -= V_.leftCols(j + 1) * h;
  const Eigen::VectorXd h2 = V_.leftCols(j + 1).transpose() * v;
  v.noalias() -= V_.leftCols(j + 1) * h2;
  h += h2;
  const double hn = v.norm();
  Hh_.col(j).head(j + 1) = h;
  Hh_(j + 1, j) = hn;
  const bool breakdown = !(hn > 1e-14 * w.norm());
  if (!breakdown) {
    if (V_.cols() < j + 2) Grow(j + 2);
    V_.col(j + 1) = v / hn;
  }
  for (int i = 0; i < j; ++i) {  // previous Givens rotations
    const double t = cs_(i) * Hh_(i, j) + sn_(i) * Hh_(i + 1, j);
    Hh_(i + 1, j) = -sn_(i) * Hh_(i, j) + cs_(i) * Hh_(i + 1, j);
    Hh_(i, j) = t;
  }
  const double den = std::hypot(Hh_(j, j), Hh_(j + 1, j));
  cs_(j) = den > 0.0 ? Hh_(j, j) / den : 1.0;
  sn_(j) = den > 0.0 ? Hh_(j + 1, j) / den : 0.0;
  Hh_(j, j) = den;
  Hh_(j + 1, j) = 0.0;
  g_(j + 1) = -sn_(j) * g_(j);
  g_(j) = cs_(j) * g_(j);
  j_ = j + 1;
  const bool end = std::abs(g_(j + 1)) <= tol_ * beta0_ || breakdown || !(den > 0.0) || j_ >= m_ ||
                   products_ >= max_it_;
  if (!end) return;
  FoldCycle();
  if (!y_.allFinite()) {
    done_ = true;
    rel_ = std::numeric_limits<double>::infinity();
    return;
  }
  if (products_ >= max_it_) {
    // No budget for the true residual: report the estimate of the cycle.
    rel_ = std::abs(g_(j_)) / beta0_;
    done_ = true;
    return;
  }
  want_residual_ = true;  // recompute the residual from scratch (next product)
}

void GmresColumn::FoldCycle() {
  const Eigen::VectorXd z =
      Hh_.topLeftCorner(j_, j_).triangularView<Eigen::Upper>().solve(g_.head(j_));
  y_.noalias() += V_.leftCols(j_) * z;
  folded_ = true;
}

double GmresColumn::estimate() const { return done_ || j_ == 0 ? rel_ : std::abs(g_(j_)) / beta0_; }

void GmresColumn::Stop() {
  if (done_) return;
  if (j_ > 0) {
    if (!folded_) FoldCycle();
    rel_ = std::abs(g_(j_)) / beta0_;
  }
  if (!y_.allFinite()) rel_ = std::numeric_limits<double>::infinity();
  done_ = true;
}

void GmresColumn::Grow(int cols) {
  const int n = static_cast<int>(b_.size());
  const int want = std::min(m_ + 1, std::max(cols, 2 * static_cast<int>(V_.cols())));
  V_.conservativeResize(n, want);
}

void GmresColumn::StartCycle(const Eigen::VectorXd& r) {
  folded_ = false;
  const double beta = r.norm();
  rel_ = beta / beta0_;
  if (rel_ <= tol_ || products_ >= max_it_ || !(beta > 0.0)) {
    done_ = true;
    return;
  }
  if (V_.cols() < 1) Grow(16);
  V_.col(0) = r / beta;
  Hh_.setZero(m_ + 1, m_);
  g_.setZero(m_ + 1);
  g_(0) = beta;
  cs_.setZero(m_);
  sn_.setZero(m_);
  j_ = 0;
}

}  // namespace softkin
