#pragma once
/// \file matched_volume.hpp
/// FK at a prescribed chamber volume: the actuation whose achieved volume ratios equal a target
/// (used where a pneumatic robot is compared at equal chamber volume: against the pressure FEM,
/// and across resolutions, where the same actuation value fills a chamber differently).
#include "softkin/solver/fk/fk_solver.hpp"
#include "softkin/solver/scene/scene.hpp"

#include <Eigen/Dense>

#include <vector>

namespace softkin {

/// A solve at a prescribed volume: the last FK result, the actuation it was solved at, and
/// whether every loaded actuator's achieved ratio is within 0.1 % of its target.
struct MatchedVolume {
  FkResult r;
  Eigen::VectorXd c;
  bool matched = false;
};

/// FK at the actuation whose achieved volume ratios (FkResult::volume_ratios) equal `target` on
/// the actuators with `loaded` set; the others stay at rest. A secant iteration per actuator,
/// from c = target (the ratio a chamber with no resistance reaches), at most 12 solves, each
/// warm-started from the last (the first from `warm`, or the rest shape). It stops early when a
/// solve does not converge, or when an actuator is held at the end of its range.
MatchedVolume SolveAtVolume(FkSolver* solver, const Scene& scene, const std::vector<double>& target,
                            const std::vector<bool>& loaded,
                            const Eigen::MatrixX3d* warm = nullptr);

}  // namespace softkin
