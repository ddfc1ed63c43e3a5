#include "softkin/solver/factory/fk_factory.hpp"

#include "softkin/solver/baselines/calculix.hpp"
#include "softkin/solver/baselines/nlp_solvers.hpp"
#include "softkin/solver/collision/collision_response.hpp"
#include "softkin/solver/fk/local_global.hpp"
#include "softkin/solver/newton/auto_solver.hpp"
#include "softkin/solver/newton/newton_solver.hpp"

#include <stdexcept>

namespace softkin {

namespace {

/// The contact term of the local-global solvers: the spring response of Sec. 3.3.
std::unique_ptr<ContactTerm> SpringResponse(const Model& model, const CollisionOptions& options) {
  return std::make_unique<CollisionResponse>(model, options);
}

}  // namespace

std::unique_ptr<FkSolver> MakeFkSolver(std::shared_ptr<const Model> model,
                                       const FkOptions& options) {
  std::string why;
  if (!options.IsValid(&why)) throw std::invalid_argument("solver options: " + why);
  switch (options.solver) {
    case FkSolverType::kLg:
    case FkSolverType::kLgAa:
      return std::make_unique<LocalGlobalSolver>(std::move(model), options, SpringResponse);
    case FkSolverType::kNewton:
      return std::make_unique<NewtonSolver>(std::move(model), options, SpringResponse);
    case FkSolverType::kAuto:
      return std::make_unique<AutoSolver>(std::move(model), options, SpringResponse);
    case FkSolverType::kCeres:
    case FkSolverType::kIpoptLbfgs:
    case FkSolverType::kIpoptNewton:
    case FkSolverType::kIpoptHard:
      return MakeNlpSolver(std::move(model), options);
    case FkSolverType::kCalculixLinear:
    case FkSolverType::kCalculixNonlinear: {
      CalculixOptions co;
      co.law = options.solver == FkSolverType::kCalculixLinear ? "linear" : "neo-hooke";
      return std::make_unique<CalculixSolver>(std::move(model), options, co);
    }
  }
  throw std::invalid_argument("unknown FK solver " +
                              std::to_string(static_cast<int>(options.solver)));
}

FkResult SolveFk(const Scene& scene, const Eigen::Ref<const Eigen::VectorXd>& c,
                 const FkOptions* options) {
  auto model = std::make_shared<const Model>(scene);
  auto solver = MakeFkSolver(model, options ? *options : scene.solver);
  return solver->Solve(c);
}

}  // namespace softkin
