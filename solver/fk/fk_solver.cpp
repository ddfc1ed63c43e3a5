#include "softkin/solver/fk/fk_solver.hpp"

#include "softkin/solver/baselines/calculix.hpp"
#include "softkin/solver/fk/energy.hpp"
#include "softkin/solver/fk/local_global.hpp"
#include "softkin/solver/baselines/nlp_solvers.hpp"

#include <cstdio>
#include <stdexcept>

namespace softkin {

const char* FkStatusToString(FkStatus s) {
  switch (s) {
    case FkStatus::Converged: return "converged";
    case FkStatus::IterationCap: return "iteration_cap";
    case FkStatus::Diverged: return "diverged";
    case FkStatus::InvalidInput: return "invalid_input";
    case FkStatus::TimeLimit: return "time_limit";
  }
  return "unknown";
}

bool FkStatusFromString(const std::string& s, FkStatus* out) {
  for (FkStatus v : {FkStatus::Converged, FkStatus::IterationCap, FkStatus::Diverged,
                     FkStatus::InvalidInput, FkStatus::TimeLimit})
    if (s == FkStatusToString(v)) {
      *out = v;
      return true;
    }
  return false;
}

std::string FkResult::BriefReport() const {
  char buf[256];
  std::snprintf(buf, sizeof(buf), "%s: %s, %d iterations, energy %.6g, residual ratio %.3g, %.3f s",
                solver.c_str(), FkStatusToString(status), iterations, energy, gradient_ratio,
                time_s);
  std::string s = buf;
  if (!message.empty()) s += " (" + message + ")";
  if (collision_active) {
    std::snprintf(buf, sizeof(buf),
                  "; collisions: %d springs left, %s (max penetration %.3g mm), check %.3f s, "
                  "response %.3f s",
                  springs, collision.collision_free() ? "collision-free" : "contacts left",
                  collision.max_penetration, collision_stats.check_s, collision_stats.response_s);
    s += buf;
    if (collision.inverted_elements > 0) {
      std::snprintf(buf, sizeof(buf), "; %d inverted elements (%d of the self contacts in them)",
                    collision.inverted_elements, collision.tangled_contacts);
      s += buf;
    }
  }
  return s;
}

std::string SolveInputError(const Model& m, const Eigen::Ref<const Eigen::VectorXd>& c,
                            const Eigen::MatrixX3d* warm_start) {
  try {
    CheckActuation(m, c);
  } catch (const std::invalid_argument& e) {
    return e.what();
  }
  if (warm_start) {
    if (warm_start->rows() != m.num_vertices())
      return "warm start: expected " + std::to_string(m.num_vertices()) + " x 3 positions, got " +
             std::to_string(warm_start->rows()) + " rows";
    if (!warm_start->allFinite()) return "warm start: positions must be finite";
  }
  return "";
}

bool FkSolver::StartResult(const Eigen::Ref<const Eigen::VectorXd>& c,
                           const Eigen::MatrixX3d* warm_start, FkResult* r) const {
  r->solver = name();
  r->actuation = c;
  r->positions = model_->rest_positions();
  r->message = SolveInputError(*model_, c, warm_start);
  if (!r->message.empty()) {
    r->status = FkStatus::InvalidInput;
    return false;
  }
  if (warm_start) r->positions = *warm_start;
  return true;
}

std::vector<std::string> FkSolverNames() {
  return {"lg",         "lg-aa",           "ceres",           "ipopt-lbfgs",
          "ipopt-newton", "ipopt-hard", "calculix-linear", "calculix-nonlinear"};
}

std::unique_ptr<FkSolver> MakeFkSolver(std::shared_ptr<const Model> model, const FkOptions& options) {
  std::string why;
  if (!options.IsValid(&why)) throw std::invalid_argument("solver options: " + why);
  if (options.solver == "lg" || options.solver == "lg-aa")
    return std::make_unique<LocalGlobalSolver>(std::move(model), options);
  if (options.solver == "ceres" || options.solver == "ipopt-lbfgs" ||
      options.solver == "ipopt-newton" || options.solver == "ipopt-hard")
    return MakeNlpSolver(std::move(model), options);
  if (options.solver == "calculix-linear" || options.solver == "calculix-nonlinear") {
    CalculixOptions co;
    co.law = options.solver == "calculix-linear" ? "linear" : "neo-hooke";
    return std::make_unique<CalculixSolver>(std::move(model), options, co);
  }
  throw std::invalid_argument("unknown FK solver '" + options.solver + "'");
}

FkResult SolveFk(const Scene& scene, const Eigen::Ref<const Eigen::VectorXd>& c,
                 const FkOptions* options) {
  auto model = std::make_shared<const Model>(scene);
  auto solver = MakeFkSolver(model, options ? *options : scene.solver);
  return solver->Solve(c);
}

}  // namespace softkin
