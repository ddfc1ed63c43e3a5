#pragma once
/// \file cli_args.hpp
/// Parsing of `softkin` option values shared by several commands. Every error is a
/// std::invalid_argument that names the option and says what was expected.
#include "softkin/solver/robots/robots.hpp"

#include <Eigen/Core>

#include <string>
#include <vector>

namespace softkin {

/// "v1,v2,..." -> numbers (finite, at least one). `option` names the flag in errors.
Eigen::VectorXd ParseNumberList(const std::string& text, const std::string& option);

/// Repeated "--param NAME=VALUE" values -> robot design parameters (finite numbers).
RobotParams ParseRobotParams(const std::vector<std::string>& items);

}  // namespace softkin
