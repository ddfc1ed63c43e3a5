#pragma once
/// \file fk_solver.hpp
/// The forward-kinematics solver interface: Solve(c, warm_start) -> FkResult. Implementations are
/// chosen by name (FkOptions::solver) in solver/factory/fk_factory.hpp, which offers the two tiers:
/// the one-shot SolveFk(scene, c) and a stateful solver (MakeFkSolver) that reuses the model's
/// factorisation across calls.
#include "softkin/solver/fk/contact_term.hpp"
#include "softkin/solver/fk/fk_options.hpp"
#include "softkin/solver/fk/model.hpp"

#include <memory>
#include <string>
#include <vector>

namespace softkin {

/// How a solve ended. TimeLimit: FkOptions::time_limit_s ran out (the positions are the last
/// checked iterate). Inverted: the iteration met its tolerance, but body elements of the state
/// are inverted (signed volume <= 0), a state no material takes; it is never reported as
/// converged (FkSolver::Solve).
enum class FkStatus { Converged, IterationCap, Diverged, InvalidInput, TimeLimit, Inverted };
const char* FkStatusToString(FkStatus s);
bool FkStatusFromString(const std::string& s, FkStatus* out);

struct FkResult {
  FkStatus status = FkStatus::InvalidInput;
  std::string message;
  std::string solver;
  Eigen::VectorXd actuation;   ///< the actuation solved for
  Eigen::MatrixX3d positions;  ///< #V x 3, mm; never NaN (the last finite iterate on divergence)
  int iterations = 0;  ///< local-global iterations (summed over continuation steps); newton: its
                       ///< iterations (plus those of an lg-aa fallback)
  double energy = 0;   ///< E at `positions` (Eq. 2.10)
  double gradient_ratio = 0;  ///< ||local-global residual|| / its reference value at the start
  double max_move = 0;        ///< last per-iteration vertex move / model size
  double time_s = 0, local_time_s = 0, global_time_s = 0;
  int aa_accepted = 0, aa_rejected = 0;
  /// Elements with signed volume <= 0 at `positions`: body elements (a state no material takes;
  /// BriefReport warns) and actuation elements (a chamber's elements may fold while its cavity
  /// volume is right), and the smallest signed / rest volume of a body element.
  int inverted_elements = 0, inverted_actuation_elements = 0;
  double min_volume_ratio = 1.0;
  int linear_iterations = 0;          ///< newton: Krylov operator products
  int load_steps = 0;                 ///< newton: converged load steps
  std::vector<double> volume_ratios;  ///< achieved volume ratio per actuator
  /// Collision handling (lg / lg-aa when FkOptions::collision is active for the scene): whether
  /// it ran, the exact check of the final positions, the springs still active at the end, and
  /// the detection / response counts and times of this solve.
  bool collision_active = false;
  CollisionCheck collision;
  int springs = 0;
  CollisionStats collision_stats;
  /// One line: status, iterations, energy, time.
  std::string BriefReport() const;
};

class FkSolver {
 public:
  virtual ~FkSolver() = default;
  virtual std::string name() const = 0;
  /// Solves for actuation c (one value per actuator, within its range). warm_start: #V x 3
  /// positions to start from (nullptr: rest shape). Bad input yields status InvalidInput with a
  /// message (never an exception from here), non-convergence IterationCap or Diverged. Every
  /// result reports its inverted elements (ReportInvertedElements).
  FkResult Solve(const Eigen::Ref<const Eigen::VectorXd>& c,
                 const Eigen::MatrixX3d* warm_start = nullptr);
  const Model& model() const { return *model_; }

 protected:
  explicit FkSolver(std::shared_ptr<const Model> m) : model_(std::move(m)) {}
  /// The solver's own Solve().
  virtual FkResult SolveImpl(const Eigen::Ref<const Eigen::VectorXd>& c,
                             const Eigen::MatrixX3d* warm_start) = 0;
  /// Fills in what every Solve() starts from: the solver's name, the actuation, the positions
  /// (the warm start, or the rest shape). Returns false, with status invalid_input and the reason
  /// (SolveInputError) in *r, if c or the warm start is bad.
  bool StartResult(const Eigen::Ref<const Eigen::VectorXd>& c, const Eigen::MatrixX3d* warm_start,
                   FkResult* r) const;
  std::shared_ptr<const Model> model_;
};

/// Elements of a model whose signed volume is not positive, body and actuation elements apart,
/// and the smallest signed / rest volume ratio of a body element (1 if it has none).
struct InvertedCount {
  int body = 0, actuation = 0;
  double min_body_ratio = 1.0;
};
/// InvertedCount of `model` at positions X (#V x 3, finite).
InvertedCount CountInverted(const Model& model, const Eigen::MatrixX3d& X);

/// Counts the elements of `model` whose signed volume at r->positions is not positive (body and
/// actuation elements apart) and the smallest signed / rest volume ratio of a body element, into
/// r->inverted_elements, inverted_actuation_elements and min_volume_ratio. Positions that are
/// missing or not finite leave them unset.
void ReportInvertedElements(const Model& model, FkResult* r);

/// Checks an actuation vector (CheckActuation) and an optional warm start (#V x 3, finite) for
/// `model`; returns "" or the reason. Every solver's Solve() reports it as invalid_input.
std::string SolveInputError(const Model& model, const Eigen::Ref<const Eigen::VectorXd>& c,
                            const Eigen::MatrixX3d* warm_start);

}  // namespace softkin
