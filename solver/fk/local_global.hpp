#pragma once
/// \file local_global.hpp
/// The local-global solver of Algorithm 1 with optional Anderson acceleration.
///  - local step: per-element targets and best rotations (parallel, no per-element allocation);
///  - global step: A_ff X_f = B_f - A_fc X_c with the CHOLMOD factor of the model (3 right-hand
///    sides), fixed vertices eliminated as Dirichlet conditions;
///  - Anderson acceleration of the positions (x <- G(x) = global(local(x))) with a safeguard. An
///    accelerated iterate x_a, extrapolated from x_k, is checked after its own local and global
///    steps; when it fails, the plain step G(x_k) is taken instead and the history is kept (it
///    holds only checked iterates). FkOptions::anderson_safeguard picks the test:
///      "energy": E(x_a) <= E(x_k), the classic rule for local-global solvers of a fixed energy;
///      "hybrid" (default): E(x_a) <= E(x_k) OR ||G(x_a) - x_a|| <= ||G(x_k) - x_k||;
///      "none": every finite step is kept.
///    Why "hybrid": the plain iteration descends on E only when every target is a minimiser over
///    its free variables (rigid bodies, fixed ratios). With the volume-proportional chamber ratios
///    and blended bodies of Ch. 2 the fixed point of Algorithm 1 is not a minimum of E; plain steps
///    raise E near it and the energy rule rejects most accelerated steps (measured in
///    docs/benchmarks.md and the aa_ablation experiment). The residual alternative still rejects
///    extrapolations that make both measures worse.
///  - collision response (Sec. 3.3, Eq. 3.9), when FkOptions::collision is active for the scene:
///    detection and the spring rule run before the local step (every check_interval iterations
///    and always before stopping); the spring targets join the right-hand side and their k the
///    matrix, whose factor follows the spring set by CHOLMOD update/downdate. A change of the
///    spring set restarts the Anderson history (the map G changed).
///    A cold solve with contacts ramps the actuation (continuation_steps stages) and cuts a stage
///    in half, from its start, when the contact response tangles: at a check, the inverted body
///    elements have grown by more than max(16, 0.5 % of the elements) since the stage began while
///    the residual is above its reference (a step that crossed thin gaps before the first check,
///    whose springs then push the wrong way). Up to kMaxCutBacks halvings per solve.
///  - stop when every vertex moves less than tolerance * size in one iteration AND the residual
///    ||2 (A X - B)|| has dropped below gradient_tolerance times its reference (the larger of its
///    value at the warm start and at the rest shape for the same actuation).
#include "softkin/solver/fk/contact_term.hpp"
#include "softkin/solver/fk/fk_solver.hpp"

#include <chrono>

namespace softkin {

class LocalGlobalSolver : public FkSolver {
 public:
  /// `contacts` builds the contact term when FkOptions::collision is active for the scene
  /// (ContactHandlingActive); without one such a scene is reported as invalid_input.
  /// MakeFkSolver (solver/factory/fk_factory.hpp) passes the spring response of solver/collision/.
  LocalGlobalSolver(std::shared_ptr<const Model> model, const FkOptions& options,
                    ContactTermFactory contacts = {});
  std::string name() const override { return ToString(options_.solver); }

 protected:
  FkResult SolveImpl(const Eigen::Ref<const Eigen::VectorXd>& c,
                     const Eigen::MatrixX3d* warm_start) override;

 public:
  const FkOptions& options() const { return options_; }

  /// A checkpoint for callers that switch solvers when local-global is slow (auto_solver.hpp):
  /// when a Solve() reaches `iteration` iterations (at its first checked iterate from there on)
  /// with its residual ratio above `max_ratio`, it stops there with status iteration_cap and a
  /// message saying so. iteration <= 0: none (the default). Until then the iterates are exactly
  /// those without a checkpoint.
  void set_checkpoint(int iteration, double max_ratio) {
    checkpoint_iteration_ = iteration;
    checkpoint_ratio_ = max_ratio;
  }

 private:
  /// One continuation stage: iterate from X towards the solution for c; accumulates into r.
  /// With detect_tangle, returns false (status diverged) when the contact response tangled
  /// (above); otherwise true.
  bool SolveStage(const Eigen::VectorXd& c, Eigen::MatrixX3d* X, FkResult* r, bool detect_tangle);
  /// Whether the iterate just checked stops the solve at the checkpoint (set_checkpoint); if so,
  /// r gets status iteration_cap and the message.
  /// Calls options_.on_progress if progress_interval_s has passed since the last call.
  void ReportProgress(const FkResult& r);
  bool StopsAtCheckpoint(FkResult* r);
  static constexpr int kMaxCutBacks = 6;
  FkOptions options_;
  ContactTermFactory contacts_;
  std::unique_ptr<ContactTerm> response_;  // springs of Eq. 3.5-3.9, when active
  std::vector<ElemRows> weighted_;         // per-element w Vol T, reused across iterations
  std::vector<double> ratios_;
  double total_weight_ = 0.0;  // sum of w_i Vol_i: the scale of the residual's round-off floor
  const std::chrono::steady_clock::time_point* deadline_ = nullptr;  // during Solve(), or none
  std::chrono::steady_clock::time_point started_, reported_;  // Solve()'s start, last progress
  Eigen::VectorXd ref_c_;         // actuation of the cached reference residual
  double ref_value_ = 0.0;        // ||2 (A X_rest - B(X_rest; ref_c_))||
  int checkpoint_iteration_ = 0;  // set_checkpoint
  double checkpoint_ratio_ = 0.0;
  bool checkpoint_passed_ = false;   // in this Solve()
  bool checkpoint_stopped_ = false;  // in this Solve(): it stopped there
};

}  // namespace softkin
