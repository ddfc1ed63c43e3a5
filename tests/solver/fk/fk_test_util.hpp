#pragma once
/// \file fk_test_util.hpp
/// FK helpers shared by tests in several folders: the local-global right-hand side B(X, c) for
/// finite differences of the equilibrium, and FkOptions with every option off its default (for
/// the option table's round-trip and flag tests).
#include "softkin/solver/fk/fk_options.hpp"
#include "softkin/solver/fk/model.hpp"
#include "softkin/solver/fk/targets.hpp"

#include <Eigen/Core>

#include <vector>

namespace softkin {
namespace test {

/// B(X, c): the right-hand side of the global step, as the local-global solver forms it.
inline Eigen::MatrixX3d LocalGlobalRhs(const Model& m, const Eigen::MatrixX3d& X,
                                       const Eigen::VectorXd& c) {
  std::vector<double> ratios;
  std::vector<ElemRows> weighted;
  ComputeLocalRatios(m, X, c, &ratios);
  LocalStep(m, X, ratios, &weighted, 1);
  Eigen::MatrixX3d B;
  AssembleRhs(m, weighted, &B, 1);
  return B;
}

/// FkOptions with every option set to a valid value other than its default. A new option must be
/// added here, so that the tests that use it cover it.
inline FkOptions NonDefaultFkOptions() {
  FkOptions o;
  o.solver = FkSolverType::kLg;
  o.max_iterations = 123;
  o.tolerance = 2e-4;
  o.gradient_tolerance = 3e-3;
  o.anderson_window = 7;
  o.anderson_safeguard = AndersonSafeguard::kEnergy;
  o.continuation_steps = 4;
  o.threads = 2;
  o.time_limit_s = 12.5;
  o.collision.self = true;
  o.collision.obstacles = false;
  o.collision.epsilon = 0.1;
  o.collision.stiffness = 5;
  o.collision.check_interval = 3;
  o.collision.update = SpringUpdate::kRefactor;
  o.collision.self_target = SelfTarget::kAuto;
  o.collision.self_spring = SelfSpring::kTarget;
  o.collision.obstacle_spring = ObstacleSpring::kPoint;
  return o;
}

}  // namespace test
}  // namespace softkin
