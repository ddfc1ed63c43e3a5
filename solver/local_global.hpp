#pragma once
/// \file local_global.hpp
/// The local-global solver of Algorithm 1 with optional Anderson acceleration.
///  - local step: per-element targets and best rotations (parallel, no per-element allocation);
///  - global step: A_ff X_f = B_f - A_fc X_c with the CHOLMOD factor of the model (3 right-hand
///    sides), fixed vertices eliminated as Dirichlet conditions;
///  - Anderson acceleration with an energy safeguard: an accelerated iterate whose energy exceeds
///    that of the previous accepted iterate is replaced by the plain step and the history reset;
///  - stop when every vertex moves less than tolerance * size in one iteration AND the residual
///    ||2 (A X - B)|| has dropped below gradient_tolerance times its reference (the larger of its
///    value at the warm start and at the rest shape for the same actuation).
#include "solver/fk_solver.hpp"

namespace softkin {

class LocalGlobalSolver : public FkSolver {
 public:
  LocalGlobalSolver(std::shared_ptr<const Model> model, const FkOptions& options);
  std::string name() const override { return options_.solver; }
  FkResult Solve(const Eigen::Ref<const Eigen::VectorXd>& c,
                 const Eigen::MatrixX3d* warm_start = nullptr) override;
  const FkOptions& options() const { return options_; }

 private:
  /// One continuation stage: iterate from X towards the solution for c; accumulates into r.
  void SolveStage(const Eigen::VectorXd& c, Eigen::MatrixX3d* X, FkResult* r);
  FkOptions options_;
  std::vector<ElemRows> weighted_;  // per-element w Vol T, reused across iterations
  std::vector<double> ratios_;
  double total_weight_ = 0.0;
  Eigen::VectorXd ref_c_;    // actuation of the cached reference residual
  double ref_value_ = 0.0;   // ||2 (A X_rest - B(X_rest; ref_c_))||  // sum of w_i Vol_i, sets the scale of the residual's round-off floor
};

}  // namespace softkin
