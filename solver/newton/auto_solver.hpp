#pragma once
/// \file auto_solver.hpp
/// The "auto" FK solver: lg-aa where it converges quickly, newton where it would crawl.
///
/// lg-aa is the faster solver where it converges in a few hundred iterations (compact robots,
/// warm-started sweeps), newton where lg-aa needs thousands (thin, bending-dominated bodies; far
/// actuations from rest): one factorisation of newton's preconditioner costs about as much as
/// 300-1,500 lg-aa iterations (docs/newton.md). Which case a solve is cannot be told beforehand,
/// so "auto" runs lg-aa first, for at most Limits::lg_iterations iterations (another round of
/// as many if by then the residual ratio is within Limits::near_factor of gradient_tolerance),
/// and if lg-aa has not converged by then it solves again with newton from the same start (the
/// warm start or the rest shape: newton does worse from lg-aa's half-converged state, whose soft
/// bending mode is partly bent). The worst case is the lg-aa iterations spent before the switch;
/// the message says when it switched. Both stop at the same equilibrium by the same test, so the
/// answer is the one either would give.
///
/// Scenes newton does not cover (Mooney-Rivlin bodies, active collision response) are solved by
/// lg-aa alone, with the full iteration cap and no message. A user's max_iterations at or below
/// lg_iterations is lg-aa's cap, and then there is no switch. FkResult::iterations adds the lg-aa
/// iterations before the switch to newton's (and its fallback's).
#include "softkin/solver/fk/contact_term.hpp"
#include "softkin/solver/fk/fk_solver.hpp"

#include <memory>
#include <string>

namespace softkin {

class AutoSolver : public FkSolver {
 public:
  /// `contacts` goes to lg-aa for scenes with collision response (MakeFkSolver passes the spring
  /// response of solver/collision/).
  AutoSolver(std::shared_ptr<const Model> model, const FkOptions& options,
             ContactTermFactory contacts = {});
  std::string name() const override { return ToString(FkSolverType::kAuto); }

  /// When lg-aa hands over to newton.
  struct Limits {
    /// lg-aa iterations before the switch (per round).
    int lg_iterations = 500;
    /// A second round of lg_iterations is given when lg-aa's residual ratio after the first is
    /// at most near_factor * gradient_tolerance (it is then usually a few iterations from done).
    double near_factor = 100.0;
  };
  /// Throws std::invalid_argument naming the field and its valid range for a bad value.
  void set_limits(const Limits& limits);

 protected:
  FkResult SolveImpl(const Eigen::Ref<const Eigen::VectorXd>& c,
                     const Eigen::MatrixX3d* warm_start) override;

 private:
  /// A solver of type `type` with the user's options, `max_iterations` and `time_limit_s`.
  std::unique_ptr<FkSolver> Make(FkSolverType type, int max_iterations, double time_limit_s) const;

  FkOptions options_;
  Limits limits_;
  ContactTermFactory contacts_;
  bool newton_covers_ = true;         ///< the scene is one newton solves (no fallback)
  std::unique_ptr<FkSolver> lg_;      ///< lg-aa capped at lg_iterations (or the full cap)
  std::unique_ptr<FkSolver> newton_;  ///< kept across calls: its preconditioner is reused
};

}  // namespace softkin
