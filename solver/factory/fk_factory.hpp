#pragma once
/// \file fk_factory.hpp
/// Forward-kinematics solvers by type, with everything wired in: the two-tier API of SoftKin.
///  - MakeFkSolver(model, options): the stateful solver options.solver, which reuses the
///    model's factorisation across calls (sweeps, IK, datasets);
///  - SolveFk(scene, c): one shot, building the model first.
/// Solvers (FkSolverType; FkSolverTypeNames() lists their names): "lg" and "lg-aa" (local-global,
/// solver/fk/, with the spring response of solver/collision/ when the scene has collision handling
/// on), "ceres", "ipopt-lbfgs", "ipopt-newton", "ipopt-hard" (solver/baselines/nlp_solvers.hpp),
/// "calculix-linear" and "calculix-nonlinear" (solver/baselines/calculix.hpp).
#include "softkin/solver/fk/fk_solver.hpp"

#include <memory>
#include <string>
#include <vector>

namespace softkin {

/// Builds the solver options.solver; throws std::invalid_argument for invalid options (message
/// from FkOptions::IsValid).
std::unique_ptr<FkSolver> MakeFkSolver(std::shared_ptr<const Model> model,
                                       const FkOptions& options);

/// One shot: builds the model and solves. Options default to the scene's.
FkResult SolveFk(const Scene& scene, const Eigen::Ref<const Eigen::VectorXd>& c,
                 const FkOptions* options = nullptr);

}  // namespace softkin
