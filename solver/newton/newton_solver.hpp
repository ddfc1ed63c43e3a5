#pragma once
/// \file newton_solver.hpp
/// The second-order FK solver ("newton"): inexact Newton-Krylov on the equilibrium that the
/// local-global iteration of Algorithm 1 converges to, so both solvers stop at the same state by
/// the same test.
///
/// The problem. The free coordinates x solve g(x) = A_ff x + A_fc x_c - B_f(X) = 0 (half the
/// local-global residual; B gathers the element targets, targets.hpp). Its Jacobian is
/// H = A_ff - K_ff with K = dB/dX applied exactly by EquilibriumLinearization (rotations, blend
/// scales, and the actuation ratios' coupling within each group). H is not symmetric in general,
/// and g is not the gradient of one energy when bodies blend (R_omega < 1) or chambers share a
/// volume constraint, so the method works on g itself:
///  - Newton step: H d = -g solved by GMRES (gmres.hpp) to a relative tolerance eta_k, the
///    Eisenstat-Walker forcing term (choice 2: eta_k = 0.9 (|g_k| / |g_k-1|)^2, safeguarded),
///    preconditioned by a CHOLMOD factor of P = sum_e |A_e - sym(K_e)|, the per-element blocks
///    with their eigenvalues made positive (the projected-Newton Hessian of the rotation-free
///    energy; EquilibriumJacobianWorkspace::Factor). P drops only the groups' rank-one coupling
///    and the skew part of K, so GMRES needs few products;
///  - globalisation: a backtracking line search (halving) along the Newton direction, bent by its
///    geodesic acceleration, that accepts a point lowering the frozen-ratio energy (Armijo) or the
///    residual |g|; every trial point is first smoothed by local-global steps, which re-fit the
///    rotations a straight-line step distorts (Smooth); an intermediate load step ends at |g| <=
///    1e-3 of its start, the last one by the local-global test (FkOptions::tolerance and
///    gradient_tolerance: the local-global step's largest vertex move and the residual ratio
///    against the same reference); the final state takes that local-global step, as lg-aa's does;
///  - adaptive load stepping: from the rest shape the actuation is applied in one step first;
///    a load step whose Newton iteration fails (no decrease along the Newton direction, a
///    degenerate element, or 30 iterations) is halved; the next step doubles after one that took
///    at most 4 iterations and halves after one that took more than 10. Each step starts from the
///    tangent predictor x + dlambda dx/dlambda (the equilibrium's derivative along the actuation,
///    solved with the same operator and factor). A warm start is tried at the full actuation
///    first, then from the rest shape;
///  - fallback: when the step falls below 1/1024 of the range, or GMRES stalls twice with a
///    fresh factor of P (P far from H: strongly indefinite or non-normal systems; Limits), the
///    remaining actuation is left to lg-aa from the last converged state, and the message says
///    so;
///  - collision response (ContactHandlingActive): the contact term's springs are quadratic with
///    targets held fixed between checks, so they join g, H and the local-global steps exactly
///    (Evaluate, ApplyH, Smooth). The contacts are checked and the springs updated before every
///    Newton iteration, and a state that passes the stopping test is checked once more (its
///    springs released or stiffened as lg-aa's final check does) before it is accepted.
/// FkResult::iterations counts Newton iterations (plus the fallback's local-global ones),
/// linear_iterations the Krylov products and load_steps the converged load steps; local_time_s is
/// the time of the residual evaluations, global_time_s that of the Newton directions (the
/// linearisation, the factorisation of P and GMRES).
#include "softkin/solver/fk/contact_term.hpp"
#include "softkin/solver/fk/fk_solver.hpp"
#include "softkin/solver/sensitivity/equilibrium_jacobian.hpp"
#include "softkin/solver/sensitivity/free_operator.hpp"

#include <chrono>
#include <memory>
#include <optional>
#include <string>
#include <vector>

namespace softkin {

class NewtonSolver : public FkSolver {
 public:
  /// `contacts` builds the contact term of scenes with collision response (MakeFkSolver passes
  /// the spring response of solver/collision/); the lg-aa fallback gets it too.
  NewtonSolver(std::shared_ptr<const Model> model, const FkOptions& options,
               ContactTermFactory contacts = {});
  std::string name() const override { return ToString(FkSolverType::kNewton); }

 protected:
  FkResult SolveImpl(const Eigen::Ref<const Eigen::VectorXd>& c,
                     const Eigen::MatrixX3d* warm_start) override;

 public:
  const FkOptions& options() const { return options_; }

  /// The load stepping's limits (the defaults are what FkOptions selects by name).
  struct Limits {
    /// Newton iterations allowed per load step before it counts as failed.
    int step_iterations = 30;
    /// The smallest load step, as a fraction of the actuation range of one call.
    double min_load_step = 1.0 / 1024.0;
    /// A GMRES solve is stopped as stalled when its relative residual is still above
    /// stall_residual after stall_products products; two such solves with a fresh
    /// preconditioner hand the solve over to lg-aa.
    int stall_products = 50;
    double stall_residual = 0.9;
  };
  /// Throws std::invalid_argument naming the field and its valid range for a bad value.
  void set_limits(const Limits& limits);

  /// The residual 2 |g| before each Newton iteration of the last load step of the last Solve(),
  /// and at its end (for convergence studies).
  const std::vector<double>& residual_history() const { return history_; }

 private:
  /// One evaluated iterate: positions, free coordinates, the residual g (free layout) and the
  /// local-global right-hand side's free part.
  struct State {
    Eigen::MatrixX3d X;
    Eigen::VectorXd x, g, Bf;
    std::vector<double> ratios;  ///< the actuation ratios at X (ComputeLocalRatios)
    double energy = 0.0;
    double residual = 0.0;  ///< 2 |g|: the local-global residual of FkResult::gradient_ratio
  };
  enum class StepEnd { Converged, Failed, TimeLimit, IterationCap };

  /// Evaluates s at positions s->X for actuation c (local step, right-hand side, residual; the
  /// contact springs' energy and terms when a contact term is active).
  void Evaluate(const Eigen::VectorXd& c, State* s);
  /// H v for the linearisation lin_ is set up with, plus the springs' K v.
  Eigen::VectorXd ApplyH(FreeOperator* op, const Eigen::VectorXd& v) const;
  /// With contacts, the deepest penetration a step from X may make: the deeper of X's deepest
  /// contact and kContactDepth mean edges (newton_solver.cpp).
  double AllowedDepth(const Eigen::MatrixX3d& X) const;
  /// (A_ff + K_springs)^-1 v: the local-global step's solve.
  Eigen::VectorXd SolveGlobal(const Eigen::VectorXd& v) const;
  /// Contact check at s and the spring rule; re-evaluates s and returns true if the springs
  /// changed. `final`: also stiffens the springs if handled contacts are left (lg-aa's last check).
  bool UpdateContacts(const Eigen::VectorXd& c, bool final, State* s);
  /// Newton iterations at actuation c from *X. `final`: stop by the local-global test; else at
  /// |g| <= 1e-3 of its start. *X receives the last accepted iterate; *why the reason of a failure.
  StepEnd NewtonStep(const Eigen::VectorXd& c, bool final, Eigen::MatrixX3d* X, FkResult* r,
                     std::string* why);
  /// The Newton direction at s: H d = -g by preconditioned GMRES to relative tolerance eta.
  /// false with *why if the linearisation or the preconditioner cannot be set up.
  bool Direction(const Eigen::VectorXd& c, const State& s, double eta, Eigen::VectorXd* d,
                 FkResult* r, std::string* why);
  /// kSmoothingSteps local-global steps from s (re-evaluated at each): applied to every trial
  /// point of the line search, they remove the stretch a straight-line step leaves in rotating
  /// elements (newton_solver.cpp).
  void Smooth(const Eigen::VectorXd& c, State* s);
  /// The geodesic acceleration of the Newton direction d at s: *acc (#V x 3) = a / 2 with
  /// H a = -g''[d, d], the second derivative of g along d by differences (h = 0.1); zero when it
  /// is not finite or |a| >= 1.5 |d|. *probe is scratch. Uses the linearisation and factor that
  /// Direction left. Returns whether *acc is used (false: it is zero).
  bool Acceleration(const Eigen::VectorXd& c, const State& s, const Eigen::VectorXd& d,
                    State* probe, Eigen::MatrixX3d* acc, FkResult* r);
  /// Adaptive load stepping from x0 (an equilibrium at c0) to c. Returns the status; *X the last
  /// converged state.
  StepEnd LoadSteps(const Eigen::VectorXd& c0, const Eigen::VectorXd& c, Eigen::MatrixX3d* X,
                    FkResult* r, std::string* why);
  /// dX/dlambda along the actuation direction dc at the equilibrium X for c (the predictor of a
  /// load step); false if it cannot be computed.
  bool Tangent(const Eigen::VectorXd& c, const Eigen::MatrixX3d& X, const Eigen::VectorXd& dc,
               Eigen::MatrixX3d* dX, FkResult* r);
  /// lg-aa from `start` (null: the rest shape), which the message calls `from`, for c; its result
  /// under this solver's name, with `reason` in the message and this solve's Newton counts added.
  FkResult Fallback(const Eigen::VectorXd& c, const Eigen::MatrixX3d* start,
                    const std::string& from, const std::string& reason, const FkResult& so_far,
                    std::chrono::steady_clock::time_point t0);
  /// ||2 (A X_rest - B(X_rest; c))||, as the local-global solver's reference (cached per c).
  double ReferenceResidual(const Eigen::VectorXd& c);
  bool TimeUp() const;

  FkOptions options_;
  Limits limits_;
  ContactTermFactory contacts_;
  std::unique_ptr<ContactTerm> response_;
  ContactTerm* active_contacts_ = nullptr;  ///< response_ during a Solve with collision response
  double mean_edge_ = 0.0;                  ///< of the rest mesh, mm (set with the contacts)
  std::vector<double> history_;
  EquilibriumLinearization lin_;
  EquilibriumJacobianWorkspace workspace_;
  std::vector<ElemRows> weighted_, scratch_;
  std::vector<double> ratios_;
  Eigen::MatrixX3d B_;
  double total_weight_ = 0.0;
  double local_time_s_ = 0.0;  ///< in Evaluate during one Solve
  /// GMRES products per digit of residual reduction right after the last factorisation of P
  /// (-1: refactor at the next Newton step).
  double fresh_rate_ = -1.0;
  int factorizations_ = 0;
  int stalls_ = 0;  ///< GMRES solves with a fresh factor that stalled, in this Solve()
  std::optional<std::chrono::steady_clock::time_point> deadline_;
  std::chrono::steady_clock::time_point started_, reported_;  ///< Solve()'s start, last progress
  Eigen::VectorXd ref_c_;
  double ref_value_ = 0.0;
};

}  // namespace softkin
