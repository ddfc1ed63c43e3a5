/// \file robots.cpp
/// The registry of the embedded robots (robots.hpp): each robot's file (robot_parts.hpp) exports
/// its RobotInfo, resolution range and generator; ListRobots and MakeRobot go through this list.
#include "softkin/solver/robots/robots.hpp"

#include "softkin/solver/common/text_format.hpp"
#include "softkin/solver/robots/robot_parts.hpp"

#include <algorithm>
#include <stdexcept>
#include <string>
#include <vector>

namespace softkin {

namespace {

using robots_detail::RobotEntry;

/// Every robot, in ListRobots() order.
const std::vector<RobotEntry>& Registry() {
  static const std::vector<RobotEntry> kRobots = {
      robots_detail::PneumaticFingerEntry(),     robots_detail::ThreeChamberEntry(),
      robots_detail::CableFingerEntry(),         robots_detail::FingerManipulatorEntry(),
      robots_detail::MultiSegmentGripperEntry(), robots_detail::DeaCrawlerEntry(),
      robots_detail::BimaterialBarEntry(),       robots_detail::CableGripperEntry(),
      robots_detail::SelfCollisionFingerEntry(), robots_detail::MembraneEntry(),
      robots_detail::TwistingRobotEntry(),       robots_detail::BilayerStripEntry(),
  };
  return kRobots;
}

/// The parameter every robot takes: the scene's element_energy (scene.hpp, ElementEnergy).
RobotParam ElementEnergyParam() {
  return {"element_energy", 0.0, 0.0, 1.0,
          "0: element energy terms as Eq. 2.10 writes them (shape; for the same strain a term "
          "grows with its element's size squared); 1: divided by each element's rest size "
          "(strain; small and large elements equally stiff)"};
}

}  // namespace

std::vector<RobotInfo> ListRobots() {
  std::vector<RobotInfo> out;
  for (const auto& r : Registry()) {
    out.push_back(r.info);
    out.back().params.push_back(ElementEnergyParam());
  }
  return out;
}

Scene MakeRobot(const std::string& name, int res, const RobotParams& params) {
  for (const auto& r : Registry()) {
    if (r.info.name != name) continue;
    if (res <= 0) res = r.info.default_resolution;
    if (res < r.min_res || res > r.max_res)
      throw std::invalid_argument(name + ": --res must be an integer in [" +
                                  std::to_string(r.min_res) + ", " + std::to_string(r.max_res) +
                                  "], got " + std::to_string(res));
    std::vector<RobotParam> accepted = r.info.params;
    accepted.push_back(ElementEnergyParam());
    RobotParams full;
    for (const auto& p : accepted) full[p.name] = p.def;
    for (const auto& [key, value] : params) {
      auto it = std::find_if(accepted.begin(), accepted.end(),
                             [&](const RobotParam& p) { return p.name == key; });
      if (it == accepted.end()) {
        std::string known;
        for (const auto& p : accepted) known += (known.empty() ? "" : ", ") + p.name;
        throw std::invalid_argument(name + ": unknown parameter '" + key + "'; its parameters: " +
                                    (known.empty() ? std::string("none") : known));
      }
      if (!(value >= it->lo && value <= it->hi))
        throw std::invalid_argument(name + ": parameter '" + key + "' must be in [" +
                                    FormatNumber(it->lo) + ", " + FormatNumber(it->hi) + "], got " +
                                    FormatNumber(value));
      full[key] = value;
    }
    const bool strain =
        robots_detail::FlagParam(name, full, "element_energy", "shape, Eq. 2.10", "strain");
    full.erase("element_energy");
    Scene scene = r.make(res, full);
    scene.element_energy = strain ? ElementEnergy::kStrain : ElementEnergy::kShape;
    return scene;
  }
  std::string known;
  for (const auto& r : Registry()) known += (known.empty() ? "" : ", ") + r.info.name;
  throw std::invalid_argument("unknown robot '" + name + "'; known robots: " + known);
}

}  // namespace softkin
