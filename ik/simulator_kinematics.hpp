#pragma once
/// \file simulator_kinematics.hpp
/// The simulator as a Kinematics (DESIGN.md): p(c) by a forward solve of the scene's model, J(c)
/// by one of three modes (docs/kinematics.md):
///   fd        central differences (thesis Eq. 4.2 / 5.3), every probe solved as the plain FK at
///             that actuation would be (warm-started from the same state the centre solve starts
///             from);
///   fd-warm   central differences whose probes start from the converged state at c;
///   implicit  implicit differentiation of the local-global equilibrium
///             (solver/sensitivity/equilibrium_jacobian.hpp): no extra forward solves.
/// Step of the differences: delta_a = fd_step * (c_max,a - c_min,a) (default 1/160 = 1/(10 N) with
/// N = 16 samples per actuator, thesis Sec. 5.2.1 and 5.3.2). At a bound, where c +- delta would
/// leave [c_min, c_max], the second-order one-sided difference (3 p(c) - 4 p(c -+ delta) +
/// p(c -+ 2 delta)) / (+-2 delta) is used instead, so probes stay in the box.
///
/// Warm-start policy (deterministic for a given call sequence): the solve for p(c) starts from the
/// converged state of the previous successful p solve of this object (the rest shape for the
/// first call, after Reset(), or with warm_start = false). Probes never change that state. If c
/// equals the previous successful c exactly, its state is reused without a solve (fk_solves = 0):
/// IK often asks for p(c) and then J(c) at the same c. `fd` probes start from the state the
/// centre solve started from (so each probe is solved exactly as a plain p solve would have been
/// in its place); `fd-warm` probes start from the converged state at c. With `implicit`, a p solve
/// starts from the first-order prediction of the previous state when its Jacobian is known
/// (predict_warm_start), and each Jacobian's linear solves start from the previous one
/// (jacobian_initial_guess).
///
/// A solve from a stored or predicted state gets warm_max_iterations; if it does not converge, c
/// is solved again from the rest shape (retry_from_rest). A forward solve that does not converge
/// (status iteration_cap, diverged, time_limit) from there makes the evaluation fail (ok = false,
/// message with the FK status and the actuation), unless accept_iteration_cap is set, in which case
/// an iteration_cap result is used and `message` says so. p and J are never NaN when ok.
#include "softkin/ik/kinematics.hpp"
#include "softkin/solver/sensitivity/equilibrium_jacobian.hpp"
#include "softkin/solver/fk/fk_solver.hpp"
#include "softkin/solver/scene/scene.hpp"

#include <memory>
#include <string>
#include <vector>

namespace softkin {

enum class JacobianMode { kFd, kFdWarm, kImplicit };
/// "fd", "fd-warm", "implicit".
const char* JacobianModeToString(JacobianMode m);
/// Parses the names of JacobianModeToString; returns false for anything else.
bool JacobianModeFromString(const std::string& s, JacobianMode* m);
/// The accepted names, for help texts: "fd, fd-warm, implicit".
std::string JacobianModeNames();

struct SimulatorKinematicsOptions {
  JacobianMode jacobian = JacobianMode::kImplicit;
  /// Tracked points, in row order of p. Each entry is
  ///   "name"      a scene marker, tracked as the mean of its vertices (Scene::marker_positions);
  ///   "name[*]"   every vertex of marker `name`, as points "name[0]", "name[1]", ... in the
  ///               marker's vertex order (e.g. grip_layer for the grasp circle fit);
  ///   "name[i]"   vertex i (0-based, in the marker's vertex order) of marker `name`.
  /// Empty: every marker of the scene, as means, in scene order.
  std::vector<std::string> points;
  /// Central-difference step as a fraction of each actuator's range, in (0, 0.25].
  double fd_step = 1.0 / 160.0;
  /// Warm-start each p solve from the previous converged state (see the file comment).
  bool warm_start = true;
  /// Accept forward solves that stop at the iteration cap (message says so); else ok = false.
  bool accept_iteration_cap = false;
  /// implicit only: start a p solve from the first-order prediction X + dX/dc (c - c_prev) of the
  /// previous state, when the last implicit Jacobian was taken at that state (IK takes J at the
  /// current iterate and then solves at the next one). Near the previous state the solve
  /// converges to the same equilibrium from a closer start (fewer iterations). The energy can have
  /// several equilibria, though, and a long extrapolation can fold elements over and land in
  /// another (cable_finger: a folded finger, the tip 60 mm off) or need thousands of iterations.
  /// So the prediction is used only within predict_max_step and when it inverts no element that
  /// is upright in the previous state (rejected_predictions() counts the others, which start
  /// from the previous state). A prediction whose solve fails is retried from the plain warm
  /// start (both solves are counted).
  bool predict_warm_start = true;
  /// implicit only: the longest step the prediction is trusted over, as the Euclidean norm of
  /// the step divided by each actuator's range (the cable_finger jumps that went wrong were 0.70;
  /// the steps of IK along a path are a few hundredths). > 0.
  double predict_max_step = 0.25;
  /// implicit only: after each p solve that started from the state dX/dc belongs to, update
  /// dX/dc by Broyden's secant rule (dX/dc += (dX - dX/dc dc) w^T / (dc^T w), w = dc / range^2)
  /// so that it belongs to the new state. Predictions then stay first-order along a path on
  /// which no new Jacobian is evaluated (IK's broyden method). The update is exact along the
  /// step just taken; the converged states do not depend on it, only where solves start. Over
  /// steps shorter than fd_step (in range-scaled norm) dX/dc is carried to the new state
  /// unchanged: there the change of the state is mostly the forward solves' tolerance, not the
  /// derivative.
  bool secant_update = true;
  /// implicit only: start each Jacobian's Krylov solves from the previous implicit Jacobian
  /// (dX/dc changes slowly along a path). The tolerance stays relative to the right-hand side.
  bool jacobian_initial_guess = true;
  /// implicit only: when the implicit derivative fails (its Krylov solve does not converge, an
  /// element it cannot differentiate), compute those columns as fd-warm does and say so in
  /// `message`, instead of failing the evaluation. Collision response stays an error.
  bool implicit_fallback = true;
  /// Iteration cap of the solves that start from a stored state, a prediction or (fd) the centre
  /// state, below the solver's own max_iterations; 0: the solver's. Such starts converge in tens
  /// to hundreds of iterations, or crawl: cable_finger went 10000 lg-aa iterations without
  /// converging from a neighbouring sample's state, where a solve from rest took 79.
  int warm_max_iterations = 2000;
  /// When a solve from a start fails (iteration cap, divergence), solve c again from the rest
  /// shape with the solver's full cap; the evaluation fails only if that fails too.
  /// rest_retries() counts them.
  bool retry_from_rest = true;
  /// Print one line per forward solve to stderr: its number, the start (predicted, warm, probe;
  /// "from rest" without a state), c, the status, the iterations and the time. For finding the
  /// solves an IK run spends its time in (softkin ik --trace-fk).
  bool trace = false;
  /// Options of the implicit mode's linear solve.
  EquilibriumJacobianOptions implicit;
  /// implicit only: solve the Jacobian's linear systems to the relative residual
  /// max(implicit.tolerance, min(1e-2 g, 1e-4)), g the forward solves' gradient_tolerance,
  /// instead of implicit.tolerance alone. dX/dc is taken at a state converged to g, and differs
  /// from the exact equilibrium's by about g already (three_chamber res 4 at g = 1e-5: 0.8-4e-5
  /// relative); solving its systems to 1e-2 g adds a few per cent to that, where 1e-8 costs a
  /// fifth more GMRES rounds (docs/learning.md). With the default g = 1e-6 nothing changes.
  bool implicit_tolerance_follows_fk = true;
  bool IsValid(std::string* why) const;
};

class SimulatorKinematics : public Kinematics {
 public:
  /// Builds the model of `scene` once (shared), with forward-solver options `fk` (nullptr: the
  /// scene's). Throws std::invalid_argument for invalid options, an unknown marker or a vertex
  /// index out of range in the point spec, or an invalid scene.
  SimulatorKinematics(const Scene& scene, const SimulatorKinematicsOptions& options,
                      const FkOptions* fk = nullptr);
  /// Shares an existing model (e.g. with other solvers).
  SimulatorKinematics(std::shared_ptr<const Model> model, const SimulatorKinematicsOptions& options,
                      const FkOptions* fk = nullptr);

  std::string name() const override;
  int num_actuators() const override { return model_->num_actuators(); }
  const std::vector<std::string>& point_names() const override { return names_; }
  const Eigen::VectorXd& lower() const override { return lower_; }
  const Eigen::VectorXd& upper() const override { return upper_; }
  Eigen::VectorXd rest() const override { return model_->scene().rest_actuation(); }
  /// p(c) (#points x 3, mm) and, with with_jacobian, J (3 #points x #actuators). ok = false with a
  /// message naming the actuator for bad c (wrong size, NaN, out of range), and with the FK
  /// status for a forward solve that fails.
  KinematicsEval Evaluate(const Eigen::Ref<const Eigen::VectorXd>& c, bool with_jacobian) override;
  long long total_fk_solves() const override { return total_fk_solves_; }

  /// Forgets the warm-start state: the next p solve starts from the rest shape, and the implicit
  /// Jacobian starts with no initial guess and a new preconditioner, as a new object would.
  void Reset();
  const Model& model() const { return *model_; }
  std::shared_ptr<const Model> shared_model() const { return model_; }
  const SimulatorKinematicsOptions& options() const { return options_; }
  const FkOptions& fk_options() const { return fk_; }
  /// Central-difference step of actuator a (fd_step times its range).
  double fd_step(int a) const;
  /// Positions (#V x 3) of the last successful p solve (empty before the first).
  const Eigen::MatrixX3d& last_positions() const { return last_X_; }
  /// implicit: first-order predictions not used as a start, because the step was longer than
  /// predict_max_step or the prediction would invert an element (PredictionIsSafe).
  long long rejected_predictions() const { return rejected_predictions_; }
  /// Solves from a start that failed and were solved again from the rest shape (retry_from_rest).
  long long rest_retries() const { return rest_retries_; }
  /// Diagnostics of the last implicit Jacobian (GMRES iterations and residuals per column).
  const EquilibriumJacobianResult& last_implicit() const { return last_implicit_; }

 private:
  void Init(const SimulatorKinematicsOptions& options, const FkOptions* fk);
  /// Tracked points for positions X (#points x 3).
  Eigen::MatrixX3d Points(const Eigen::Ref<const Eigen::MatrixX3d>& X) const;
  /// One forward solve from `start` (nullptr: rest); "" or the failure message. Counts the solve.
  /// With a start, the solve gets warm_max_iterations and, if it fails, c is solved again from
  /// the rest shape (retry_from_rest). Adds the solves made to *solves; *from_rest: the result
  /// came from a solve started at the rest shape. `kind` names the start for the trace.
  std::string Solve(const Eigen::VectorXd& c, const Eigen::MatrixX3d* start, FkResult* r,
                    std::string* note, const char* kind, int* solves, bool* from_rest = nullptr);
  /// c - last_c_ over the Jacobian's columns (jac_columns_), and in *scaled its Euclidean norm
  /// with each component divided by its actuator's range.
  Eigen::VectorXd ColumnStep(const Eigen::VectorXd& c, double* scaled) const;
  /// Whether `predicted` (extrapolated from `from` over a range-scaled step of length `step`) is
  /// a safe start: step <= predict_max_step, and it inverts no element upright in `from`. Counts
  /// rejections.
  bool PredictionIsSafe(const Eigen::MatrixX3d& from, const Eigen::MatrixX3d& predicted,
                        double step);

  std::shared_ptr<const Model> model_;
  SimulatorKinematicsOptions options_;
  FkOptions fk_;
  std::unique_ptr<FkSolver> solver_;
  std::unique_ptr<FkSolver> warm_solver_;  ///< solver_ with warm_max_iterations (null: none lower)
  std::vector<std::string> names_;
  /// Point q = sum over [offset_[q], offset_[q+1]) of weight_ * X.row(vertex_).
  std::vector<int> offset_, vertex_;
  std::vector<double> weight_;
  Eigen::VectorXd lower_, upper_;
  Eigen::MatrixX3d last_X_;
  Eigen::MatrixX3d last_start_;  ///< where last_X_ was solved from (empty: rest shape)
  int last_inverted_ = 0;        ///< inverted body elements of last_X_
  double last_min_volume_ratio_ = 1.0;
  Eigen::VectorXd last_c_;
  /// The last implicit dX/dc (3 #V x #columns), the actuation it was taken at and its columns.
  Eigen::MatrixXd jac_dXdc_;
  Eigen::VectorXd jac_c_;
  std::vector<int> jac_columns_;
  long long total_fk_solves_ = 0;
  long long rejected_predictions_ = 0;
  long long rest_retries_ = 0;
  EquilibriumJacobianResult last_implicit_;
  /// The implicit mode's preconditioner pattern, symbolic analysis and factor, kept along a path.
  std::unique_ptr<EquilibriumJacobianWorkspace> workspace_ =
      std::make_unique<EquilibriumJacobianWorkspace>();
};

}  // namespace softkin
