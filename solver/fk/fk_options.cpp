#include "softkin/solver/fk/fk_options.hpp"

#include <cmath>

namespace softkin {

bool CollisionOptions::IsValid(std::string* why) const {
  auto bad = [&](const std::string& m) {
    if (why) *why = m;
    return false;
  };
  if (!(epsilon >= 0.0) || !std::isfinite(epsilon))
    return bad("collision.epsilon: expected a number >= 0 (mm)");
  if (!(stiffness > 0.0) || !std::isfinite(stiffness))
    return bad("collision.stiffness: expected a number > 0");
  if (check_interval < 1) return bad("collision.check_interval: expected an integer >= 1");
  if (update != "updown" && update != "refactor")
    return bad("collision.update: expected one of updown, refactor; got '" + update + "'");
  if (self_target != "auto" && self_target != "walk")
    return bad("collision.self_target: expected one of auto, walk; got '" + self_target + "'");
  if (self_spring != "target" && self_spring != "pair")
    return bad("collision.self_spring: expected one of target, pair; got '" + self_spring + "'");
  if (obstacle_spring != "point" && obstacle_spring != "plane")
    return bad("collision.obstacle_spring: expected one of point, plane; got '" + obstacle_spring +
               "'");
  return true;
}

bool FkOptions::IsValid(std::string* why) const {
  auto bad = [&](const std::string& m) {
    if (why) *why = m;
    return false;
  };
  if (solver != "lg" && solver != "lg-aa" && solver != "newton" && solver != "ceres" &&
      solver != "ipopt-lbfgs" && solver != "ipopt-newton" && solver != "ipopt-hard" &&
      solver != "calculix-linear" && solver != "calculix-nonlinear")
    return bad(
        "solver: expected one of lg, lg-aa, newton, ceres, ipopt-lbfgs, ipopt-newton, ipopt-hard, "
        "calculix-linear, calculix-nonlinear; got '" +
        solver + "'");
  if (max_iterations < 1) return bad("max_iterations: expected an integer >= 1");
  if (!(tolerance > 0.0) || !std::isfinite(tolerance))
    return bad("tolerance: expected a number > 0");
  if (!(gradient_tolerance > 0.0) || !std::isfinite(gradient_tolerance))
    return bad("gradient_tolerance: expected a number > 0");
  if (anderson_window < 1 || anderson_window > 50)
    return bad("anderson_window: expected an integer in [1, 50]");
  if (anderson_safeguard != "hybrid" && anderson_safeguard != "energy" &&
      anderson_safeguard != "none")
    return bad("anderson_safeguard: expected one of hybrid, energy, none; got '" +
               anderson_safeguard + "'");
  if (continuation_steps < 1) return bad("continuation_steps: expected an integer >= 1");
  if (threads < 0) return bad("threads: expected an integer >= 0");
  if (!(time_limit_s >= 0.0) || !std::isfinite(time_limit_s))
    return bad("time_limit_s: expected a number >= 0 (0: no limit)");
  if (!collision.IsValid(why)) return false;
  return true;
}

}  // namespace softkin
