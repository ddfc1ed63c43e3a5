#include "softkin/ik/kinematics.hpp"

#include <cmath>
#include <sstream>

namespace softkin {

int Kinematics::point_index(const std::string& name) const {
  const auto& n = point_names();
  for (size_t i = 0; i < n.size(); ++i)
    if (n[i] == name) return static_cast<int>(i);
  return -1;
}

std::string CheckKinematicsInput(const Kinematics& k, const Eigen::Ref<const Eigen::VectorXd>& c) {
  std::ostringstream s;
  if (c.size() != k.num_actuators()) {
    s << "actuation has " << c.size() << " values, expected " << k.num_actuators();
    return s.str();
  }
  for (int a = 0; a < c.size(); ++a) {
    const double lo = k.lower()[a], hi = k.upper()[a], slack = 1e-12 * std::max(1.0, hi - lo);
    if (!std::isfinite(c[a]) || c[a] < lo - slack || c[a] > hi + slack) {
      s << "actuator " << a << " value " << c[a] << " is outside its range [" << lo << ", " << hi
        << "]";
      return s.str();
    }
  }
  return "";
}

}  // namespace softkin
