#pragma once
/// \file robots.hpp
/// Embedded robot generators: deterministic, parameterised by a resolution, each declaring its
/// actuators (name, type, range), fixed region and a `tip` marker.
#include "solver/scene.hpp"

#include <string>
#include <vector>

namespace softkin {

struct RobotInfo {
  std::string name;
  std::string description;
  int default_resolution = 0;
  std::string resolution_doc;  ///< what the resolution parameter means
};

/// Names and docs of the embedded robots.
std::vector<RobotInfo> ListRobots();
/// Builds robot `name` at resolution `res` (<= 0: its default). Throws std::invalid_argument for an
/// unknown name (listing the known ones) or a resolution out of range.
Scene MakeRobot(const std::string& name, int res = 0);

}  // namespace softkin
