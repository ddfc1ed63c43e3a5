#include "softkin/solver/fk/anderson.hpp"

#include <Eigen/Cholesky>

namespace softkin {

Anderson::Anderson(int dim, int window)
    : dim_(dim),
      m_(window),
      dG_(dim, window),
      dF_(dim, window),
      gram_(window, window),
      g_prev_(dim),
      f_prev_(dim),
      x_(dim) {}

void Anderson::Reset() {
  cols_ = 0;
  next_ = 0;
  iter_ = 0;
}

const Eigen::VectorXd& Anderson::Compute(const Eigen::Ref<const Eigen::VectorXd>& g,
                                         const Eigen::Ref<const Eigen::VectorXd>& f) {
  if (iter_ == 0) {
    x_ = g;
  } else {
    const int c = next_;
    dF_.col(c) = f - f_prev_;
    dG_.col(c) = g - g_prev_;
    // Unit-normalise the new column pair (scale-free Gram matrix).
    const double n = dF_.col(c).norm();
    if (n > 0) {
      dF_.col(c) /= n;
      dG_.col(c) /= n;
    }
    cols_ = std::min(cols_ + 1, m_);
    next_ = (next_ + 1) % m_;
    for (int j = 0; j < cols_; ++j) {
      const double v = dF_.col(c).dot(dF_.col(j));
      gram_(c, j) = v;
      gram_(j, c) = v;
    }
    const Eigen::MatrixXd M =
        gram_.topLeftCorner(cols_, cols_) + 1e-10 * Eigen::MatrixXd::Identity(cols_, cols_);
    const Eigen::VectorXd rhs = dF_.leftCols(cols_).transpose() * f;
    const Eigen::VectorXd theta = M.ldlt().solve(rhs);
    if (theta.allFinite())
      x_ = g - dG_.leftCols(cols_) * theta;
    else
      x_ = g;
  }
  g_prev_ = g;
  f_prev_ = f;
  ++iter_;
  return x_;
}

}  // namespace softkin
