#pragma once
/// \file robots.hpp
/// Embedded robot generators: deterministic, parameterised by a resolution, each declaring its
/// actuators (name, type, range), fixed region and a `tip` marker.
#include "softkin/solver/scene/scene.hpp"

#include <map>
#include <string>
#include <vector>

namespace softkin {

/// A named numeric design parameter of a robot (e.g. the material interface of bimaterial_bar).
struct RobotParam {
  std::string name;
  double def = 0, lo = 0, hi = 0;  ///< default and inclusive range
  std::string doc;
};

/// Parameter name -> value; parameters left out take their defaults.
using RobotParams = std::map<std::string, double>;

struct RobotInfo {
  std::string name;
  std::string description;
  int default_resolution = 0;
  std::string resolution_doc;  ///< what the resolution parameter means
  std::vector<RobotParam> params;
};

/// Names and docs of the embedded robots.
std::vector<RobotInfo> ListRobots();
/// Builds robot `name` at resolution `res` (<= 0: its default) with design parameters `params`.
/// Throws std::invalid_argument for an unknown name (listing the known ones), a resolution out of
/// range, or an unknown or out-of-range parameter (naming it and its range).
Scene MakeRobot(const std::string& name, int res = 0, const RobotParams& params = {});

}  // namespace softkin
