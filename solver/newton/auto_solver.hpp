#pragma once
/// \file auto_solver.hpp
/// The "auto" FK solver (the default): lg-aa where it converges quickly, newton where it crawls.
///
/// lg-aa is the faster solver where it converges in a few hundred iterations (compact robots,
/// warm-started sweeps), newton where lg-aa needs thousands (thin, bending-dominated bodies; far
/// actuations from rest): one factorisation of newton's preconditioner costs about as much as
/// 300-1,500 lg-aa iterations (docs/newton.md). Which case a solve is cannot be told beforehand,
/// so "auto" runs lg-aa, and if after Limits::lg_iterations iterations its residual ratio is
/// still above Limits::near_factor times gradient_tolerance (it is then far from done), it
/// solves again with newton from the same start (the warm start or the rest shape: newton does
/// worse from lg-aa's half-converged state, whose soft bending mode is partly bent). Otherwise
/// lg-aa simply goes on: until the switch its iterates are lg-aa's, so where lg-aa is quick the
/// answer, iterations and time are lg-aa's.
///
/// newton gets Limits::newton_time_factor times the time lg-aa has spent. If it has not
/// converged by then (newton has cases it handles badly: cable_finger res 8, docs/newton.md),
/// lg-aa continues from where it stopped (with contacts: solves again from the rest shape, since
/// its checkpoint state may belong to an intermediate stage), so the worst case costs lg-aa's own
/// time plus that budget. The message says when it switched and how it ended. Both solvers stop at
/// the same equilibrium by the same test.
///
/// Scenes with an active collision response switch only when solved from the rest shape. Their
/// answer depends on the path to it: newton's load steps follow the quasi-static path, and lg-aa's
/// one call from rest can end far from it (`selfcollision_finger` at alpha 2.5: 6-22 mm at res
/// 5-8, docs/newton.md). In a warm-started sweep lg-aa's small steps follow that path too, and a
/// switch there would make a sweep's answers lg-aa's at some points and newton's at others. A
/// user's max_iterations at or below lg_iterations is lg-aa's cap, with no switch.
/// FkResult::iterations adds lg-aa's iterations before the switch to newton's (and to those of an
/// lg-aa continuation).
#include "softkin/solver/fk/contact_term.hpp"
#include "softkin/solver/fk/fk_solver.hpp"
#include "softkin/solver/fk/local_global.hpp"

#include <memory>
#include <string>

namespace softkin {

class AutoSolver : public FkSolver {
 public:
  /// `contacts` goes to lg-aa and newton for scenes with collision response (MakeFkSolver passes
  /// the spring response of solver/collision/).
  AutoSolver(std::shared_ptr<const Model> model, const FkOptions& options,
             ContactTermFactory contacts = {});
  std::string name() const override { return ToString(FkSolverType::kAuto); }

  /// When lg-aa hands over to newton.
  struct Limits {
    /// The lg-aa iteration at which the switch is decided.
    int lg_iterations = 500;
    /// lg-aa goes on if its residual ratio then is at most near_factor * gradient_tolerance.
    double near_factor = 100.0;
    /// newton may take newton_time_factor times the time lg-aa has spent; past that (or if it
    /// ends without converging) lg-aa continues from where it stopped (with contacts: from rest).
    double newton_time_factor = 8.0;
  };
  /// Throws std::invalid_argument naming the field and its valid range for a bad value.
  void set_limits(const Limits& limits);

 protected:
  FkResult SolveImpl(const Eigen::Ref<const Eigen::VectorXd>& c,
                     const Eigen::MatrixX3d* warm_start) override;

 private:
  /// A solver of type `type` with the user's options, `max_iterations` and `time_limit_s`.
  FkOptions With(FkSolverType type, int max_iterations, double time_limit_s) const;

  FkOptions options_;
  Limits limits_;
  ContactTermFactory contacts_;
  bool contacts_active_ = false;  ///< the scene has an active collision response
  /// lg-aa with the user's options and the checkpoint (kept: its reference residual is cached)
  std::unique_ptr<LocalGlobalSolver> lg_;
};

}  // namespace softkin
