#include "softkin/solver/fk/local_global.hpp"

#include "softkin/solver/common/text_format.hpp"
#include "softkin/solver/fk/anderson.hpp"
#include "softkin/solver/fk/energy.hpp"
#include "softkin/solver/fk/targets.hpp"
#include "softkin/solver/common/stopwatch.hpp"

#include <algorithm>
#include <chrono>
#include <optional>
#include <cmath>
#include <stdexcept>

namespace softkin {

namespace {
using Clock = std::chrono::steady_clock;
/// The prescribed coordinates' contribution A_fc x_c to the global system for actuation c (motion
/// actuators move theirs with c): A X restricted to the free rows, every free coordinate zero.
Eigen::VectorXd PrescribedRhs(const Model& m, const Eigen::VectorXd& c) {
  Eigen::MatrixX3d Xc = Eigen::MatrixX3d::Zero(m.num_vertices(), 3);
  m.ApplyConstraints(c, &Xc);
  Eigen::VectorXd Cfix;
  m.GatherFree(m.A() * Xc, &Cfix);
  return Cfix;
}

/// The largest vertex move of a step (free layout) relative to the model size; Mv is scratch.
double MaxRelativeMove(const Model& m, const Eigen::VectorXd& step, Eigen::MatrixX3d* Mv) {
  Mv->setZero();
  m.ScatterFree(step, Mv);
  return Mv->rowwise().norm().maxCoeff() / m.size();
}

/// What one continuation stage evaluates at the current positions X (the caller's): the local
/// step with its energy and right-hand side B_f (and the contact term's part), the free
/// coordinates x_f and the residual. Holds B, B_f, x_f and scratch; the per-element targets and
/// the local step's time are the solver's.
struct StageEvaluation {
  StageEvaluation(const Model& model, const Eigen::VectorXd& actuation, Eigen::MatrixX3d* positions,
                  ContactTerm* contacts, std::vector<double>* element_ratios,
                  std::vector<ElemRows>* element_rows, int num_threads, double* local_seconds)
      : m(model),
        c(actuation),
        X(*positions),
        resp(contacts),
        ratios(*element_ratios),
        weighted(*element_rows),
        nt(num_threads),
        local_time_s(local_seconds),
        B(model.num_vertices(), 3),
        Bf(model.num_free_dofs()),
        xf(model.num_free_dofs()),
        AX(model.num_free_dofs()) {}

  /// The local step at X: the targets, the energy *E and B_f.
  void Local(double* E) {
    const auto t0 = Clock::now();
    ComputeLocalRatios(m, X, c, &ratios);
    *E = LocalStep(m, X, ratios, &weighted, nt);
    AssembleRhs(m, weighted, &B, nt);
    m.GatherFree(B, &Bf);
    if (resp) {
      *E += resp->Energy(X);
      resp->AddToRhs(X, &Bf);
    }
    *local_time_s += Seconds(t0, Clock::now());
  }
  void StoreFree(const Eigen::VectorXd& y) { m.ScatterFree(y, &X); }
  /// ||A_ff x_f + A_fc x_c - B_f||: the energy gradient over the free coordinates (up to 2).
  /// Loads x_f from X as well.
  double Residual() {
    m.GatherFree(X, &xf);
    m.GatherFree(m.A() * X, &AX);
    if (resp) resp->AddSpringProduct(xf, &AX);
    return 2.0 * (AX - Bf).norm();
  }
  /// The residual at the rest shape for this actuation (X is restored afterwards).
  double RestResidual() {
    const Eigen::MatrixX3d keep = X;
    X = m.rest_positions();
    m.ApplyConstraints(c, &X);
    double E0;
    Local(&E0);
    const double ref = Residual();
    X = keep;
    return ref;
  }

  const Model& m;
  const Eigen::VectorXd& c;
  Eigen::MatrixX3d& X;
  ContactTerm* resp;
  std::vector<double>& ratios;
  std::vector<ElemRows>& weighted;
  int nt;
  double* local_time_s;
  Eigen::MatrixX3d B;
  Eigen::VectorXd Bf, xf, AX;
};
}  // namespace

LocalGlobalSolver::LocalGlobalSolver(std::shared_ptr<const Model> model, const FkOptions& options,
                                     ContactTermFactory contacts)
    : FkSolver(std::move(model)), options_(options), contacts_(std::move(contacts)) {
  std::string why;
  if (!options_.IsValid(&why)) throw std::invalid_argument("solver options: " + why);
}

bool LocalGlobalSolver::SolveStage(const Eigen::VectorXd& c, Eigen::MatrixX3d* Xp, FkResult* r,
                                   bool detect_tangle) {
  const Model& m = *model_;
  Eigen::MatrixX3d& X = *Xp;
  const int nf = m.num_free_dofs();
  const int nt = options_.threads;
  const bool aa_on = options_.solver == FkSolverType::kLgAa;
  const double tol = options_.tolerance;
  const double gtol = options_.gradient_tolerance;

  m.ApplyConstraints(c, &X);  // the prescribed coordinates for this actuation
  const Eigen::VectorXd Cfix = PrescribedRhs(m, c);

  Eigen::MatrixX3d Mv(m.num_vertices(), 3);
  Eigen::VectorXd Gf(nf), Gprev(nf), step(nf);
  ContactTerm* resp = response_.get();
  StageEvaluation ev(m, c, &X, resp, &ratios_, &weighted_, nt, &r->local_time_s);
  const Eigen::VectorXd& Bf = ev.Bf;
  const Eigen::VectorXd& xf = ev.xf;

  // Reference residual: the residual at the rest shape for this actuation. It depends on c only,
  // so it is cached across calls (sweeps and finite differences re-solve the same c often).
  if (ref_c_.size() != c.size() || ref_c_ != c) {
    ref_value_ = ev.RestResidual();
    ref_c_ = c;
  }
  double ref = ref_value_;

  if (total_weight_ == 0.0)
    for (const auto& e : m.elements()) total_weight_ += e.wv;
  Anderson aa(nf, options_.anderson_window);
  Eigen::MatrixX3d X_good = X;
  const AndersonSafeguard guard = options_.anderson_safeguard;
  // Merits of the iterate an accelerated step was extrapolated from.
  double base_E = 0.0, base_f = 0.0;
  bool accelerated = false;  // X is an Anderson (extrapolated) iterate, not yet checked
  auto reject = [&]() {      // fall back to the plain step G(x_k); the history is kept
    ev.StoreFree(Gprev);
    ++r->aa_rejected;
    accelerated = false;
  };
  const int interval = options_.collision.check_interval;
  const int tangle_limit = std::max(16, static_cast<int>(0.005 * m.elements().size()));
  int inverted_at_start = 0;
  for (int it = 0; it < options_.max_iterations; ++it) {
    if (deadline_ && Clock::now() > *deadline_) {
      X = X_good;
      r->status = FkStatus::TimeLimit;
      r->message = "time limit of " + std::to_string(options_.time_limit_s) + " s reached";
      return true;
    }
    if (resp && detect_tangle && it % interval == 0) {
      const int inverted = CountInverted(m, X).body;
      if (it == 0) inverted_at_start = inverted;
      if (inverted - inverted_at_start > tangle_limit && r->gradient_ratio > 1.0) {
        X = X_good;
        r->status = FkStatus::Diverged;
        r->message = "the contact response tangled at iteration " + std::to_string(r->iterations) +
                     " (" + std::to_string(inverted) + " inverted body elements)";
        return false;
      }
    }
    if (resp && it % interval == 0 && resp->Update(X)) {
      // The spring set (so the energy and the map G) changed: this iterate starts a new history.
      aa.Reset();
      accelerated = false;
    }
    double E;
    ev.Local(&E);
    const double grad = ev.Residual();
    const bool finite = std::isfinite(E) && X.allFinite() && std::isfinite(grad);
    if (accelerated && (!finite || (guard == AndersonSafeguard::kEnergy && !(E <= base_E)))) {
      reject();
      ++r->iterations;
      continue;
    }
    if (!finite) {
      X = X_good;
      r->status = FkStatus::Diverged;
      r->message = "non-finite energy or positions at iteration " + std::to_string(r->iterations);
      return true;
    }

    const auto t1 = Clock::now();
    Gf = resp ? resp->Solve(Bf - Cfix) : m.SolveFree(Bf - Cfix);
    r->global_time_s += Seconds(t1, Clock::now());
    ++r->iterations;
    if (!Gf.allFinite()) {
      if (accelerated) {
        reject();
        continue;
      }
      X = X_good;
      r->status = FkStatus::Diverged;
      r->message = "the global step produced non-finite positions";
      return true;
    }
    step = Gf - xf;
    const double fnorm = step.norm();  // fixed-point residual ||G(x) - x||
    if (accelerated) {
      if (guard == AndersonSafeguard::kHybrid && !(E <= base_E || fnorm <= base_f)) {
        reject();
        continue;
      }
      ++r->aa_accepted;
      accelerated = false;
    }
    X_good = X;  // the last iterate whose merit was checked
    if (it == 0) {
      // Floor: a residual this small is round-off (e.g. at the rest actuation, where both the
      // residual at rest and at the start are ~0 and their ratio would be noise).
      ref = std::max({ref, grad, 1e-8 * total_weight_ * m.size()});
    }
    r->gradient_ratio = ref > 0 ? grad / ref : 0.0;
    ReportProgress(*r);
    const double move = MaxRelativeMove(m, step, &Mv);
    r->max_move = move;
    // A residual at round-off level (e.g. at the rest actuation, where the reference is itself
    // round-off) counts as converged whatever the ratio.
    const bool roundoff = grad <= 1e-12 * total_weight_ * m.size();
    if (move < tol && (r->gradient_ratio < gtol || roundoff)) {
      ev.StoreFree(Gf);
      // With collisions, stop only if a check at this state leaves the spring set as it is.
      if (resp &&
          (resp->Update(X) || (resp->HasHandledContacts(resp->Check(X)) && resp->Stiffen()))) {
        // Springs changed, or contacts are left (springs yield by force / k): raise k.
        aa.Reset();
        continue;
      }
      r->status = FkStatus::Converged;
      return true;
    }
    if (StopsAtCheckpoint(r)) return true;
    if (aa_on) {
      const Eigen::VectorXd& xn = aa.Compute(Gf, step);
      Gprev = Gf;
      base_E = E;
      base_f = fnorm;
      accelerated = aa.history() > 0;
      ev.StoreFree(xn);
    } else {
      ev.StoreFree(Gf);
    }
  }
  X = X_good;  // never return an unchecked (extrapolated) iterate
  r->status = FkStatus::IterationCap;
  r->message = "iteration cap of " + std::to_string(options_.max_iterations) + " reached";
  return true;
}

void LocalGlobalSolver::ReportProgress(const FkResult& r) {
  if (!options_.on_progress || Seconds(reported_, Clock::now()) < options_.progress_interval_s)
    return;
  reported_ = Clock::now();
  options_.on_progress(r.iterations, r.gradient_ratio, Seconds(started_, reported_));
}

bool LocalGlobalSolver::StopsAtCheckpoint(FkResult* r) {
  // Judged at the first checked iterate from the checkpoint's iteration on (a rejected Anderson
  // step does not reach this test).
  if (checkpoint_passed_ || checkpoint_iteration_ <= 0 || r->iterations < checkpoint_iteration_)
    return false;
  checkpoint_passed_ = true;
  if (!(r->gradient_ratio > checkpoint_ratio_)) return false;
  checkpoint_stopped_ = true;
  r->status = FkStatus::IterationCap;
  r->message = "stopped at the checkpoint after " + std::to_string(r->iterations) +
               " iterations (residual ratio " + FormatNumber(r->gradient_ratio) + ", above " +
               FormatNumber(checkpoint_ratio_) + ")";
  return true;
}

FkResult LocalGlobalSolver::SolveImpl(const Eigen::Ref<const Eigen::VectorXd>& c,
                                      const Eigen::MatrixX3d* warm_start) {
  const Model& m = *model_;
  const auto t0 = Clock::now();
  started_ = reported_ = t0;
  FkResult r;
  if (!StartResult(c, warm_start, &r)) {
    r.time_s = Seconds(t0, Clock::now());
    return r;
  }
  if (warm_start) m.ApplyConstraints(c, &r.positions);
  checkpoint_passed_ = checkpoint_stopped_ = false;
  const Eigen::VectorXd rest = m.scene().rest_actuation();
  const int K = warm_start ? 1 : options_.continuation_steps;  // a warm start is already close
  std::optional<Clock::time_point> deadline;
  if (options_.time_limit_s > 0)
    deadline = t0 + std::chrono::duration_cast<Clock::duration>(
                        std::chrono::duration<double>(options_.time_limit_s));
  deadline_ = deadline ? &*deadline : nullptr;
  if (ContactHandlingActive(m.scene(), options_.collision)) {
    if (!EnsureContactTerm(contacts_, m, options_.collision, &response_, &r.message)) {
      r.status = FkStatus::InvalidInput;
      r.time_s = Seconds(t0, Clock::now());
      return r;
    }
    response_->Reset();
  }
  // Stages at load fractions t of the way from the rest actuation to c. A cold solve whose stage
  // tangles the contacts restarts that stage from its start with half the step.
  const bool cut_back =
      !warm_start && response_ && ContactHandlingActive(m.scene(), options_.collision);
  double t = 0.0, h = 1.0 / K;
  int stage = 0, cuts = 0;
  std::string first_tangle;
  CollisionStats discarded;  // counts and times of the stages cut back
  while (t < 1.0) {
    const double t_next = std::min(1.0, t + h);
    const Eigen::VectorXd cs =
        t_next >= 1.0 ? Eigen::VectorXd(c) : Eigen::VectorXd(rest + (c - rest) * t_next);
    const Eigen::MatrixX3d start = cut_back ? r.positions : Eigen::MatrixX3d();
    const bool ok = SolveStage(cs, &r.positions, &r, cut_back && cuts < kMaxCutBacks);
    ++stage;
    if (options_.on_step) {
      const int left = static_cast<int>(std::ceil((1.0 - t_next) / h - 1e-9));
      options_.on_step(stage, stage + left, FkStatusToString(r.status), r.iterations,
                       Seconds(t0, Clock::now()));
    }
    if (!ok && cut_back && cuts < kMaxCutBacks) {
      if (cuts++ == 0) first_tangle = r.message;
      r.positions = start;
      r.message.clear();
      discarded.Add(response_->stats());
      // A fresh contact term, so that the retry is the solve a new solver with that load step
      // makes (the contact events, and so the iteration count, are sensitive to round-off: a
      // Reset() term, whose factor went through CHOLMOD updates and downdates, took 3,952
      // iterations here against 1,821 on selfcollision_finger res 8, and 1,065 against 1,199
      // at res 6; refactoring it on Reset() changed nothing).
      response_ = contacts_(*model_, options_.collision);
      response_->Reset();
      h = 0.5 * (t_next - t);
      continue;
    }
    if (r.status == FkStatus::Diverged || r.status == FkStatus::TimeLimit || checkpoint_stopped_)
      break;  // (a stop at the checkpoint ends the whole solve, not only its stage)
    t = t_next;
  }
  if (cuts > 0) {
    const std::string note = "cut the load step back " + std::to_string(cuts) +
                             " time(s) where the contact response tangled (first: " + first_tangle +
                             "); " + std::to_string(stage) + " stages";
    r.message = r.message.empty() ? note : r.message + "; " + note;
  }
  deadline_ = nullptr;
  ComputeLocalRatios(m, r.positions, c, &ratios_, &r.volume_ratios);
  r.energy = LocalStep(m, r.positions, ratios_, &weighted_, options_.threads);
  if (response_ && ContactHandlingActive(m.scene(), options_.collision)) {
    r.collision_active = true;
    r.springs = response_->num_springs();
    r.collision_stats = response_->stats();
    r.collision_stats.Add(discarded);
    const auto tc = Clock::now();
    r.collision = response_->Check(r.positions);  // the exact check of the final state
    r.collision_stats.check_s += Seconds(tc, Clock::now());
  }
  r.time_s = Seconds(t0, Clock::now());
  return r;
}

}  // namespace softkin
