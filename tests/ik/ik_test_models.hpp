#pragma once
/// \file
/// Analytic Kinematics for the IK tests: a linear map, and a decorator that records every
/// actuation evaluated (and can fail on request), plus a finite-difference helper.
#include "softkin/ik/kinematics.hpp"

#include <Eigen/Dense>
#include <gtest/gtest.h>

#include <functional>
#include <random>
#include <string>
#include <vector>

namespace softkin {
namespace test {

/// p_i = A_i c + b_i for #points points; A is 3 #points x #actuators (row 3 i + d).
class LinearKinematics : public Kinematics {
 public:
  LinearKinematics(Eigen::MatrixXd A, Eigen::MatrixX3d b, Eigen::VectorXd lo, Eigen::VectorXd hi,
                   std::vector<std::string> names)
      : A_(std::move(A)),
        b_(std::move(b)),
        lo_(std::move(lo)),
        hi_(std::move(hi)),
        names_(std::move(names)) {}
  /// A seeded random well-conditioned map: 3 actuators in [0, 10], points "tip", "p1", ...
  static LinearKinematics Random(int num_points, unsigned seed) {
    std::mt19937 rng(seed);
    std::uniform_real_distribution<double> u(-1.0, 1.0);
    Eigen::MatrixXd A(3 * num_points, 3);
    for (int i = 0; i < A.rows(); ++i)
      for (int j = 0; j < 3; ++j) A(i, j) = u(rng) + (i % 3 == j ? 2.0 : 0.0);
    Eigen::MatrixX3d b(num_points, 3);
    for (int i = 0; i < num_points; ++i) b.row(i) << 10 * u(rng), 10 * u(rng), 50 + 10 * u(rng);
    std::vector<std::string> names{"tip"};
    for (int i = 1; i < num_points; ++i) names.push_back("p" + std::to_string(i));
    return LinearKinematics(A, b, Eigen::VectorXd::Zero(3), Eigen::VectorXd::Constant(3, 10.0),
                            names);
  }
  std::string name() const override { return "linear"; }
  int num_actuators() const override { return static_cast<int>(A_.cols()); }
  const std::vector<std::string>& point_names() const override { return names_; }
  const Eigen::VectorXd& lower() const override { return lo_; }
  const Eigen::VectorXd& upper() const override { return hi_; }
  Eigen::VectorXd rest() const override { return lo_; }
  KinematicsEval Evaluate(const Eigen::Ref<const Eigen::VectorXd>& c, bool with_jacobian) override {
    KinematicsEval e;
    e.message = CheckKinematicsInput(*this, c);
    if (!e.message.empty()) return e;
    ++count_;
    e.fk_solves = 1;
    const Eigen::VectorXd flat = A_ * c;
    e.p.resize(b_.rows(), 3);
    for (int i = 0; i < b_.rows(); ++i)
      for (int d = 0; d < 3; ++d) e.p(i, d) = flat[3 * i + d] + b_(i, d);
    if (with_jacobian) e.J = A_;
    e.ok = true;
    return e;
  }
  long long total_fk_solves() const override { return count_; }

 private:
  Eigen::MatrixXd A_;
  Eigen::MatrixX3d b_;
  Eigen::VectorXd lo_, hi_;
  std::vector<std::string> names_;
  long long count_ = 0;
};

/// Forwards to another Kinematics, recording every c asked for; `fail_if` makes chosen
/// evaluations fail with a message (as a simulator that does not converge would), `alter`
/// changes what the inner one returns.
class RecordingKinematics : public Kinematics {
 public:
  explicit RecordingKinematics(Kinematics& inner) : inner_(inner) {}
  std::string name() const override { return "recording(" + inner_.name() + ")"; }
  int num_actuators() const override { return inner_.num_actuators(); }
  const std::vector<std::string>& point_names() const override { return inner_.point_names(); }
  const Eigen::VectorXd& lower() const override { return inner_.lower(); }
  const Eigen::VectorXd& upper() const override { return inner_.upper(); }
  Eigen::VectorXd rest() const override { return inner_.rest(); }
  KinematicsEval Evaluate(const Eigen::Ref<const Eigen::VectorXd>& c, bool with_jacobian) override {
    calls.push_back(c);
    if (fail_if && fail_if(c)) {
      KinematicsEval e;
      e.message = "injected failure: the solver did not converge";
      return e;
    }
    KinematicsEval e = inner_.Evaluate(c, with_jacobian);
    if (alter) alter(&e);
    return e;
  }
  long long total_fk_solves() const override { return inner_.total_fk_solves(); }

  std::vector<Eigen::VectorXd> calls;
  std::function<bool(const Eigen::VectorXd&)> fail_if;
  /// Applied to every evaluation the inner kinematics returns (e.g. a wrong J on purpose).
  std::function<void(KinematicsEval*)> alter;

 private:
  Kinematics& inner_;
};

/// Asserts a == b entrywise within atol + rtol |b|, naming the first failing (i, j).
inline ::testing::AssertionResult NearMatrix(const Eigen::MatrixXd& a, const Eigen::MatrixXd& b,
                                             double rtol, double atol) {
  if (a.rows() != b.rows() || a.cols() != b.cols())
    return ::testing::AssertionFailure()
           << "shape " << a.rows() << "x" << a.cols() << " vs " << b.rows() << "x" << b.cols();
  for (int i = 0; i < a.rows(); ++i)
    for (int j = 0; j < a.cols(); ++j)
      if (!(std::abs(a(i, j) - b(i, j)) <= atol + rtol * std::abs(b(i, j))))
        return ::testing::AssertionFailure()
               << "entry (" << i << ", " << j << "): " << a(i, j) << " vs " << b(i, j);
  return ::testing::AssertionSuccess();
}

/// Central-difference gradient of f at x (same shape as x), step h.
template <class F>
Eigen::MatrixXd FdGradient(F f, const Eigen::MatrixXd& x, double h) {
  Eigen::MatrixXd g(x.rows(), x.cols());
  for (int i = 0; i < x.rows(); ++i)
    for (int j = 0; j < x.cols(); ++j) {
      Eigen::MatrixXd xp = x, xm = x;
      xp(i, j) += h;
      xm(i, j) -= h;
      g(i, j) = (f(xp) - f(xm)) / (2 * h);
    }
  return g;
}

}  // namespace test
}  // namespace softkin
