#include "softkin/experiments/cli_args.hpp"

#include <cctype>
#include <cmath>
#include <cstdlib>
#include <sstream>
#include <stdexcept>

namespace softkin {

Eigen::VectorXd ParseNumberList(const std::string& text, const std::string& option) {
  std::vector<double> v;
  std::stringstream ss(text);
  std::string item;
  while (std::getline(ss, item, ',')) {
    size_t pos = 0;
    double x = 0;
    try {
      x = std::stod(item, &pos);
    } catch (const std::exception&) {
      pos = 0;
    }
    while (pos < item.size() && isspace(static_cast<unsigned char>(item[pos]))) ++pos;
    if (item.empty() || pos != item.size() || !std::isfinite(x))
      throw std::invalid_argument(option + ": expected comma-separated finite numbers, got '" +
                                  text + "'");
    v.push_back(x);
  }
  if (!text.empty() && text.back() == ',')
    throw std::invalid_argument(option + ": expected comma-separated finite numbers, got '" + text +
                                "'");
  if (v.empty()) throw std::invalid_argument(option + ": expected at least one number");
  return Eigen::Map<Eigen::VectorXd>(v.data(), static_cast<Eigen::Index>(v.size()));
}

RobotParams ParseRobotParams(const std::vector<std::string>& items) {
  RobotParams params;
  for (const auto& text : items) {
    const auto eq = text.find('=');
    char* end = nullptr;
    const std::string value = eq == std::string::npos ? "" : text.substr(eq + 1);
    const double v = value.empty() ? 0.0 : std::strtod(value.c_str(), &end);
    if (eq == std::string::npos || eq == 0 || value.empty() ||
        end != value.c_str() + value.size() || !std::isfinite(v))
      throw std::invalid_argument("--param: expected NAME=VALUE with a finite number, got '" +
                                  text + "'");
    params[text.substr(0, eq)] = v;
  }
  return params;
}

}  // namespace softkin
