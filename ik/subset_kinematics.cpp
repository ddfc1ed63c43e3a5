#include "softkin/ik/subset_kinematics.hpp"

#include <algorithm>
#include <stdexcept>

namespace softkin {

SubsetKinematics::SubsetKinematics(Kinematics& base, std::vector<int> driven,
                                   const Eigen::VectorXd& fixed)
    : base_(base), driven_(std::move(driven)), fixed_(fixed) {
  const int n = base_.num_actuators();
  if (driven_.empty()) throw std::invalid_argument("SubsetKinematics: no driven actuator");
  std::vector<int> sorted = driven_;
  std::sort(sorted.begin(), sorted.end());
  if (std::adjacent_find(sorted.begin(), sorted.end()) != sorted.end())
    throw std::invalid_argument("SubsetKinematics: an actuator is listed twice");
  if (sorted.front() < 0 || sorted.back() >= n)
    throw std::invalid_argument("SubsetKinematics: actuator index out of range [0, " +
                                std::to_string(n) + ")");
  const std::string why = CheckKinematicsInput(base_, fixed_);
  if (!why.empty()) throw std::invalid_argument("SubsetKinematics: fixed actuation: " + why);
  lower_.resize(driven_.size());
  upper_.resize(driven_.size());
  for (size_t i = 0; i < driven_.size(); ++i) {
    lower_[i] = base_.lower()[driven_[i]];
    upper_[i] = base_.upper()[driven_[i]];
  }
}

std::string SubsetKinematics::name() const {
  std::string s = base_.name() + "[driven:";
  for (size_t i = 0; i < driven_.size(); ++i) s += (i ? "," : "") + std::to_string(driven_[i]);
  return s + "]";
}

Eigen::VectorXd SubsetKinematics::rest() const {
  Eigen::VectorXd r(driven_.size());
  for (size_t i = 0; i < driven_.size(); ++i) r[i] = fixed_[driven_[i]];
  return r;
}

Eigen::VectorXd SubsetKinematics::Full(const Eigen::Ref<const Eigen::VectorXd>& c) const {
  Eigen::VectorXd full = fixed_;
  for (size_t i = 0; i < driven_.size() && static_cast<Eigen::Index>(i) < c.size(); ++i)
    full[driven_[i]] = c[i];
  return full;
}

KinematicsEval SubsetKinematics::Evaluate(const Eigen::Ref<const Eigen::VectorXd>& c,
                                          bool with_jacobian) {
  const std::string why = CheckKinematicsInput(*this, c);
  if (!why.empty()) {
    KinematicsEval e;
    e.message = why;
    return e;
  }
  KinematicsEval e = base_.Evaluate(Full(c), with_jacobian);
  if (e.ok && with_jacobian) {
    Eigen::MatrixXd J(e.J.rows(), static_cast<Eigen::Index>(driven_.size()));
    for (size_t i = 0; i < driven_.size(); ++i) J.col(i) = e.J.col(driven_[i]);
    e.J = std::move(J);
  }
  return e;
}

}  // namespace softkin
