/// \file newton_solver.cpp
/// NewtonSolver (newton_solver.hpp): the residual, the Newton direction by preconditioned GMRES,
/// the line search, adaptive load stepping and the lg-aa fallback.
#include "softkin/solver/newton/newton_solver.hpp"

#include "softkin/solver/common/blas_threads.hpp"
#include "softkin/solver/fk/energy.hpp"
#include "softkin/solver/fk/local_global.hpp"
#include "softkin/solver/fk/targets.hpp"
#include "softkin/solver/sensitivity/free_operator.hpp"
#include "softkin/solver/sensitivity/gmres.hpp"
#include "softkin/solver/common/stopwatch.hpp"

#include <algorithm>
#include <cmath>
#include <sstream>
#include <stdexcept>

namespace softkin {

namespace {
using Clock = std::chrono::steady_clock;
/// Krylov products allowed per Newton step (no restart below this).
constexpr int kMaxKrylov = 300;
/// The largest Eisenstat-Walker forcing term (and the first one).
constexpr double kMaxForcing = 0.1;
/// An intermediate load step ends when |g| has dropped by this factor.
constexpr double kStepReduction = 1e-3;
/// GMRES is stopped as stalled when its relative residual is still above Limits::stall_residual
/// (0.9) after Limits::stall_products (50) products. On the embedded robots and bilayer_strip a
/// fresh factor brings it below 0.1 well within 50 products. kMaxStalls stalls with a fresh
/// factor end Newton for one Solve.
constexpr int kMaxStalls = 2;
/// Geodesic acceleration (Acceleration): the difference step h along the Newton direction, the
/// largest |a| / |d| it is used at, and its GMRES forcing term and product budget.
constexpr double kAccelerationStep = 0.1;
constexpr double kMaxAccelerationRatio = 1.5;
constexpr double kAccelerationForcing = 0.1;
constexpr int kAccelerationProducts = 50;
/// A full Newton step that divides the residual by at least 2 is taken without the acceleration
/// (on the pneumatic_finger sweep of fig2_11 computing it at every step cost 26 % of the time).
constexpr double kGoodStep = 0.5;
/// Local-global steps applied to every trial point of the line search (Smooth). Measured on
/// bilayer_strip res 2 at alpha = 1.1 (Newton iterations / s, one run each): 0 steps 13 / 3.3,
/// 1: 11 / 3.0, 2: 8 / 2.6, 4: 8 / 2.4, 8: 7 / 2.7, 16: 6 / 2.8; at alpha = 1.5: 0 steps 274 /
/// 155 s, 4 steps not converged in 300 s, 8 steps 20 / 8.7 s. Stopping the steps once the
/// residual falls by less than 0.5 or 0.8 per step changed the times by under 10 %.
/// docs/newton.md.
constexpr int kSmoothingSteps = 8;
/// Armijo constant and the halvings of the line search.
constexpr double kArmijo = 1e-4;
constexpr int kMaxHalvings = 12;
/// The tangent predictor of a load step is halved at most this many times to keep every body
/// element upright that was (LoadSteps), then dropped.
constexpr int kPredictorHalvings = 5;
/// With contact response, the deepest new penetration a Newton trial point may make, in mean
/// edge lengths (NewtonStep).
constexpr double kContactDepth = 0.05;

double MeanEdgeLength(const Model& m) {
  const Mesh& mesh = m.mesh();
  double sum = 0.0;
  for (const Element& e : mesh.elements)
    sum += (mesh.vertices.row(e.v[1]) - mesh.vertices.row(e.v[0])).norm();
  return mesh.elements.empty() ? 0.0 : sum / static_cast<double>(mesh.elements.size());
}
}  // namespace

NewtonSolver::NewtonSolver(std::shared_ptr<const Model> model, const FkOptions& options,
                           ContactTermFactory contacts)
    : FkSolver(std::move(model)), options_(options), contacts_(std::move(contacts)) {
  std::string why;
  if (!options_.IsValid(&why)) throw std::invalid_argument("solver options: " + why);
  for (const auto& e : model_->elements()) total_weight_ += e.wv;
}

void NewtonSolver::set_limits(const Limits& l) {
  auto bad = [](const std::string& field, const std::string& expected, double got) {
    std::ostringstream os;
    os << "newton limits: " << field << " must be " << expected << ", got " << got;
    throw std::invalid_argument(os.str());
  };
  if (l.step_iterations < 1) bad("step_iterations", "an integer >= 1", l.step_iterations);
  if (!(l.min_load_step > 0.0 && l.min_load_step <= 1.0))
    bad("min_load_step", "in (0, 1]", l.min_load_step);
  if (l.stall_products < 1) bad("stall_products", "an integer >= 1", l.stall_products);
  if (!(l.stall_residual >= 0.0 && l.stall_residual <= 1.0))
    bad("stall_residual", "in [0, 1]", l.stall_residual);
  limits_ = l;
}

bool NewtonSolver::TimeUp() const { return deadline_ && Clock::now() > *deadline_; }

void NewtonSolver::Evaluate(const Eigen::VectorXd& c, State* s) {
  const auto t0 = Clock::now();
  const Model& m = *model_;
  const int nt = options_.threads;
  ComputeLocalRatios(m, s->X, c, &s->ratios);
  s->energy = LocalStep(m, s->X, s->ratios, &weighted_, nt);
  AssembleRhs(m, weighted_, &B_, nt);
  m.GatherFree(B_, &s->Bf);
  m.GatherFree(s->X, &s->x);
  m.GatherFree(m.A() * s->X, &s->g);  // A_ff x + A_fc x_c
  if (active_contacts_) {
    // The springs' E = sum k |c^T x - t|^2 with their targets held: K x joins A_ff x and the
    // targets' part joins B_f, as in lg-aa's global step (contact_term.hpp).
    s->energy += active_contacts_->Energy(s->X);
    active_contacts_->AddToRhs(s->X, &s->Bf);
    active_contacts_->AddSpringProduct(s->x, &s->g);
  }
  s->g -= s->Bf;
  s->residual = 2.0 * s->g.norm();
  local_time_s_ += Seconds(t0, Clock::now());
}

Eigen::VectorXd NewtonSolver::ApplyH(FreeOperator* op, const Eigen::VectorXd& v) const {
  Eigen::VectorXd y = op->Apply(v).col(0);
  if (active_contacts_) active_contacts_->AddSpringProduct(v, &y);
  return y;
}

double NewtonSolver::AllowedDepth(const Eigen::MatrixX3d& X) const {
  if (!active_contacts_) return 0.0;
  return std::max(active_contacts_->Check(X).max_penetration, kContactDepth * mean_edge_);
}

Eigen::VectorXd NewtonSolver::SolveGlobal(const Eigen::VectorXd& v) const {
  return active_contacts_ ? active_contacts_->Solve(v) : model_->SolveFree(v);
}

bool NewtonSolver::UpdateContacts(const Eigen::VectorXd& c, bool final, State* s) {
  if (!active_contacts_) return false;
  bool changed = active_contacts_->Update(s->X);
  if (!changed && final)  // contacts left that the springs do not push out: stiffen them
    changed = active_contacts_->HasHandledContacts(active_contacts_->Check(s->X)) &&
              active_contacts_->Stiffen();
  if (changed) Evaluate(c, s);
  return changed;
}

double NewtonSolver::ReferenceResidual(const Eigen::VectorXd& c) {
  if (ref_c_.size() != c.size() || ref_c_ != c) {
    // Without the contact springs: the rest shape is collision-free, and the reference must not
    // depend on the spring set of the moment.
    ContactTerm* const contacts = active_contacts_;
    active_contacts_ = nullptr;
    State s;
    s.X = model_->rest_positions();
    model_->ApplyConstraints(c, &s.X);
    Evaluate(c, &s);
    active_contacts_ = contacts;
    ref_value_ = s.residual;
    ref_c_ = c;
  }
  return ref_value_;
}

bool NewtonSolver::Direction(const Eigen::VectorXd& c, const State& s, double eta,
                             Eigen::VectorXd* d, FkResult* r, std::string* why) {
  const auto t0 = Clock::now();
  struct AddTime {
    Clock::time_point t0;
    double* to;
    ~AddTime() { *to += Seconds(t0, Clock::now()); }
  } add_time{t0, &r->global_time_s};
  const Model& m = *model_;
  if (!lin_.Setup(m, s.X, c, why, options_.threads)) return false;
  FreeOperator op(m, &lin_);
  // GMRES with the factor of P: the one of an earlier iterate while it keeps working (its cost
  // per digit of residual reduction stays within twice that right after it was factored), else
  // factored at this state.
  bool stalled = false;
  auto solve = [&](int budget) {
    op.SetPreconditioner(workspace_.factor());
    // Right-preconditioned: GMRES on H P^-1 u = -g bounds the true residual |H d + g| <= eta |g|
    // with d = P^-1 u. (Left preconditioning bounds |P^-1 (H d + g)|, which on bilayer_strip
    // was up to 50 times smaller than the true residual: the steps were not Newton steps.)
    GmresColumn gm(-s.g, Eigen::VectorXd::Zero(s.g.size()), budget, budget, eta);
    while (!gm.done() &&
           !(gm.products() >= limits_.stall_products && gm.estimate() > limits_.stall_residual))
      gm.Consume(ApplyH(&op, op.Precondition(gm.Request()).col(0)));
    gm.Stop();  // a stalled solve keeps what it has
    r->linear_iterations += gm.products();
    *d = op.Precondition(gm.y()).col(0);
    const double digits = std::max(0.5, -std::log10(std::max(gm.rel(), 1e-16)));
    const bool ok = d->allFinite() && gm.rel() <= eta;
    stalled = gm.rel() > limits_.stall_residual;
    return std::make_pair(ok, gm.products() / digits);
  };
  auto factor = [&]() {
    ++factorizations_;
    if (!workspace_.Factor(m, lin_, options_.threads, /*project=*/true)) {
      *why = "the projected Hessian is not positive definite (is every body held?)";
      return false;
    }
    return true;
  };
  if (workspace_.factor() && fresh_rate_ > 0.0) {
    const int budget = std::min(
        kMaxKrylov,
        static_cast<int>(std::ceil(4.0 * fresh_rate_ * std::max(1.0, -std::log10(eta)))) + 10);
    const auto [ok, rate] = solve(budget);
    if (ok && rate <= 2.0 * fresh_rate_ + 1.0) return true;
    if (ok) {
      fresh_rate_ = -1.0;  // worked, but slowly: factor at the next iteration
      return true;
    }
  }
  if (!factor()) return false;
  const auto [ok, rate] = solve(kMaxKrylov);
  fresh_rate_ = rate;
  // A direction short of eta is still used (the line search guards it), but GMRES that stalls
  // with a fresh factor means P is far from H here (H strongly indefinite or non-normal): after
  // kMaxStalls of those Newton gives up and lg-aa takes over (LoadSteps, Solve), since smaller
  // load steps do not make the linear systems easier.
  if (!ok && stalled && ++stalls_ >= kMaxStalls) {
    *why = "GMRES with a fresh preconditioner stalled " + std::to_string(stalls_) +
           " times (the Newton systems are far from their projected Hessian here";
    // An inverted element's block of H is far from positive, so the projection changes it most:
    // the message says how many there are (a crushed wall; docs/newton.md).
    const int inverted = CountInverted(m, s.X).body;
    if (inverted > 0) *why += "; " + std::to_string(inverted) + " body elements are inverted";
    *why += ")";
    return false;
  }
  if (!d->allFinite()) {
    *why = "the Krylov solve of the Newton step produced non-finite values";
    return false;
  }
  return true;
}

void NewtonSolver::Smooth(const Eigen::VectorXd& c, State* s) {
  // A Newton step moves the vertices along straight lines, so where the elements rotate (a
  // bending thin body) it leaves their edges stretched to second order in the turn; the stiff
  // in-plane modes then dominate the residual and the line search cuts the step to a small
  // fraction. A local-global step re-fits every element's rotation and removes exactly that
  // part (its stiff modes converge in a few steps), while it moves the soft bending modes that
  // the Newton step has just corrected only slowly. x <- x - A_ff^-1 g is one such step (g is
  // half the local-global residual, so -A_ff^-1 g is the local-global step), with the factor of
  // A_ff the model already holds.
  const Model& m = *model_;
  for (int q = 0; q < kSmoothingSteps && std::isfinite(s->residual) && s->X.allFinite(); ++q) {
    m.ScatterFree(s->x - SolveGlobal(s->g), &s->X);
    Evaluate(c, s);
  }
}

bool NewtonSolver::Acceleration(const Eigen::VectorXd& c, const State& s, const Eigen::VectorXd& d,
                                State* probe, Eigen::MatrixX3d* acc, FkResult* r) {
  // Along a bending mode the equilibrium path turns (rotations), so x + t d leaves it
  // quadratically and the line search cuts t to 1/4-1/8 for many iterations (docs/newton.md).
  // The second-order term of g along d, g(x + h d) = g + h H d + (h^2 / 2) g''[d, d] + O(h^3),
  // by one more residual and one product, gives the acceleration a = -H^-1 g''[d, d] (one more
  // GMRES solve with the same factor), and the step follows x + t d + t^2 a / 2: geodesic
  // acceleration, as in Transtrum and Sethna's Levenberg-Marquardt. It is dropped when |a| is
  // large against |d| (the expansion is not to be trusted there).
  const auto t0 = Clock::now();
  const Model& m = *model_;
  acc->setZero();
  const double h = kAccelerationStep;
  probe->X = s.X;
  m.ScatterFree(s.x + h * d, &probe->X);
  Evaluate(c, probe);
  if (!std::isfinite(probe->residual) || !workspace_.factor()) return false;
  FreeOperator op(m, &lin_);  // lin_ is still set up at s (Direction)
  const Eigen::VectorXd Hd = ApplyH(&op, d);
  const Eigen::VectorXd second = (2.0 / (h * h)) * (probe->g - s.g - h * Hd);
  op.SetPreconditioner(workspace_.factor());
  GmresColumn gm(-second, Eigen::VectorXd::Zero(second.size()), kAccelerationProducts,
                 kAccelerationProducts, kAccelerationForcing);
  while (!gm.done() &&
         !(gm.products() >= limits_.stall_products && gm.estimate() > limits_.stall_residual))
    gm.Consume(ApplyH(&op, op.Precondition(gm.Request()).col(0)));
  gm.Stop();
  r->linear_iterations += gm.products() + 1;
  const Eigen::VectorXd a = op.Precondition(gm.y()).col(0);
  const bool used = a.allFinite() && gm.rel() < 1.0 && a.norm() < kMaxAccelerationRatio * d.norm();
  if (used) m.ScatterFree(0.5 * a, acc);
  r->global_time_s += Seconds(t0, Clock::now());
  return used;
}

NewtonSolver::StepEnd NewtonSolver::NewtonStep(const Eigen::VectorXd& c, bool final,
                                               Eigen::MatrixX3d* Xp, FkResult* r,
                                               std::string* why) {
  const Model& m = *model_;
  State s, trial, probe;
  s.X = *Xp;
  m.ApplyConstraints(c, &s.X);
  Evaluate(c, &s);
  UpdateContacts(c, false, &s);
  if (!std::isfinite(s.residual)) {
    *why = "non-finite residual at the start of a load step";
    return StepEnd::Failed;
  }
  // The stopping reference of the local-global solver, and the round-off floor.
  const double floor = 1e-8 * total_weight_ * m.size();
  const double ref =
      final ? std::max({ReferenceResidual(c), s.residual, floor}) : std::max(s.residual, floor);
  const bool roundoff_ok = final;
  Eigen::MatrixX3d Mv(m.num_vertices(), 3), D(m.num_vertices(), 3), Acc(m.num_vertices(), 3);
  Eigen::VectorXd d;
  double eta = kMaxForcing, previous = s.residual;
  history_.clear();
  bool checked = true;  // the contacts were checked at s
  for (int it = 0;; ++it) {
    // The springs change only here, between iterations: each line search sees one energy.
    if (!checked && UpdateContacts(c, false, &s)) {
      eta = kMaxForcing;
      previous = s.residual;
    }
    checked = false;
    history_.push_back(s.residual);
    if (options_.on_progress && Seconds(reported_, Clock::now()) >= options_.progress_interval_s) {
      reported_ = Clock::now();  // the ratio is the load step's own until the last step
      options_.on_progress(r->iterations, s.residual / ref, Seconds(started_, reported_));
    }
    // Convergence: the local-global test at s (its step, and the residual ratio).
    if (final) {
      const Eigen::VectorXd step = -SolveGlobal(s.g);
      Mv.setZero();
      m.ScatterFree(step, &Mv);
      const double move = Mv.rowwise().norm().maxCoeff() / m.size();
      r->gradient_ratio = s.residual / ref;
      r->max_move = move;
      const bool roundoff = roundoff_ok && s.residual <= 1e-12 * total_weight_ * m.size();
      if (move < options_.tolerance &&
          (r->gradient_ratio < options_.gradient_tolerance || roundoff)) {
        m.ScatterFree(s.x + step, &s.X);  // the local-global step, as lg-aa ends
        // With contacts, only if a check of that state leaves the springs as they are (lg-aa's
        // rule); else Newton goes on with the new springs.
        if (active_contacts_) {
          Evaluate(c, &s);
          if (UpdateContacts(c, true, &s)) {
            checked = true;
            eta = kMaxForcing;
            previous = s.residual;
            continue;
          }
        }
        *Xp = s.X;
        return StepEnd::Converged;
      }
    } else if (s.residual <= kStepReduction * ref) {
      *Xp = s.X;
      return StepEnd::Converged;
    }
    if (TimeUp()) {
      *Xp = s.X;
      return StepEnd::TimeLimit;
    }
    if (r->iterations >= options_.max_iterations) {
      *Xp = s.X;
      return StepEnd::IterationCap;
    }
    if (it >= limits_.step_iterations) {
      *why = std::to_string(limits_.step_iterations) + " Newton iterations without convergence";
      return StepEnd::Failed;
    }
    // Eisenstat-Walker forcing term (choice 2), with its safeguards.
    if (it > 0) {
      const double ratio = s.residual / previous;
      const double next = 0.9 * ratio * ratio, kept = 0.9 * eta * eta;
      eta = kept > 0.1 ? std::max(next, kept) : next;
      // No oversolving near the end: the target residual is gradient_tolerance * ref.
      eta = std::max(eta, 0.5 * options_.gradient_tolerance * ref / s.residual);
      eta = std::clamp(eta, 1e-10, kMaxForcing);
    }
    previous = s.residual;
    if (!Direction(c, s, eta, &d, r, why)) return StepEnd::Failed;
    // A descent direction of the energy with the ratios frozen at x (whose gradient is 2 g for
    // rigid bodies): the Newton direction if it is one, else the projected-Newton one -P^-1 g.
    double slope = 2.0 * s.g.dot(d);
    if (!(slope < 0.0)) {
      d = -Eigen::VectorXd(workspace_.factor()->solve(s.g));
      slope = 2.0 * s.g.dot(d);
    }
    D.setZero();
    m.ScatterFree(d, &D);
    // The full Newton step is taken if it reduces the residual by kGoodStep (the quadratic
    // regime). Otherwise the line search follows the parabola x + t d + t^2 a / 2 with a the
    // geodesic acceleration (Acceleration; zero where it is not trusted), backtracking (halving)
    // until the step lowers the frozen-ratio energy (Armijo) or the residual |g| (the hybrid rule
    // of lg-aa's safeguard: with volume-coupled ratios or blended bodies the equilibrium is not a
    // minimum of the energy, and near it the residual decides).
    // The line search's rule at step t for the evaluated trial.
    // With contacts, no trial point may push a vertex deeper into the robot or an obstacle than
    // the larger of s's deepest contact and kContactDepth mean edges: a Newton step, unlike
    // lg-aa's small ones, could otherwise carry a wall through another before any spring exists
    // (selfcollision_finger res 5 ended tangled, 4 elements inverted). The springs for the
    // shallow contacts it may make are added at the next iteration.
    const double allowed_depth = AllowedDepth(s.X);
    auto shallow = [&]() {
      return !active_contacts_ || active_contacts_->Check(trial.X).max_penetration <= allowed_depth;
    };
    auto decreases = [&](double t) {
      if (!shallow()) return false;
      const double frozen = LocalStep(m, trial.X, s.ratios, &scratch_, options_.threads) +
                            (active_contacts_ ? active_contacts_->Energy(trial.X) : 0.0);
      if (!std::isfinite(trial.residual) || !trial.X.allFinite() || !std::isfinite(frozen))
        return false;
      return frozen <= s.energy + kArmijo * t * slope ||
             trial.residual <= (1.0 - kArmijo * t) * s.residual;
    };
    double t = 1.0;
    trial.X = s.X + D;
    Evaluate(c, &trial);
    Smooth(c, &trial);
    bool accepted = std::isfinite(trial.residual) && trial.X.allFinite() &&
                    trial.residual <= kGoodStep * s.residual && shallow();
    int first_halving = 0;
    if (!accepted && !Acceleration(c, s, d, &probe, &Acc, r)) {
      // No acceleration: the path is the straight line, whose t = 1 trial is already evaluated.
      accepted = decreases(1.0);
      first_halving = 1;
      t = 0.5;
    }
    for (int h = first_halving; h <= kMaxHalvings && !accepted; ++h, t *= 0.5) {
      trial.X = s.X + t * D + t * t * Acc;
      Evaluate(c, &trial);
      Smooth(c, &trial);
      accepted = decreases(t);
    }
    ++r->iterations;
    if (!accepted) {
      *why = "the line search found no decrease of the residual along the Newton direction";
      *Xp = s.X;
      return StepEnd::Failed;
    }
    std::swap(s, trial);
  }
}

bool NewtonSolver::Tangent(const Eigen::VectorXd& c, const Eigen::MatrixX3d& X,
                           const Eigen::VectorXd& dc, Eigen::MatrixX3d* dX, FkResult* r) {
  const auto t0 = Clock::now();
  const Model& m = *model_;
  std::string why;
  if (!lin_.Setup(m, X, c, &why, options_.threads)) return false;
  // H dx_f = dB/dc dc + (K_fc - A_fc) dx_c with dx_c the prescribed coordinates' motion
  // (equilibrium_jacobian.hpp), along the one direction dc.
  Eigen::MatrixX3d dXc = Eigen::MatrixX3d::Zero(m.num_vertices(), 3), dB;
  for (int a = 0; a < m.num_actuators(); ++a)
    if (dc[a] != 0.0) dXc += dc[a] * PrescribedDerivative(m, c, a);
  lin_.ApplyRhsDerivative(dXc, dc, &dB);
  dB -= m.A() * dXc;
  Eigen::VectorXd rhs;
  m.GatherFree(dB, &rhs);
  if (!workspace_.factor()) {
    ++factorizations_;
    if (!workspace_.Factor(m, lin_, options_.threads, /*project=*/true)) return false;
  }
  FreeOperator op(m, &lin_);
  op.SetPreconditioner(workspace_.factor());
  GmresColumn gm(rhs, Eigen::VectorXd::Zero(rhs.size()), kMaxKrylov, kMaxKrylov, 1e-3);
  while (!gm.done()) gm.Consume(ApplyH(&op, op.Precondition(gm.Request()).col(0)));
  r->linear_iterations += gm.products();
  const Eigen::VectorXd y = op.Precondition(gm.y()).col(0);
  r->global_time_s += Seconds(t0, Clock::now());
  if (!y.allFinite()) return false;
  *dX = dXc;
  m.ScatterFree(y, dX);
  return true;
}

NewtonSolver::StepEnd NewtonSolver::LoadSteps(const Eigen::VectorXd& c0, const Eigen::VectorXd& c,
                                              Eigen::MatrixX3d* X, FkResult* r, std::string* why) {
  const Model& m = *model_;
  double lambda = 0.0, delta = 1.0 / std::max(1, options_.continuation_steps);
  Eigen::MatrixX3d converged = *X, tangent;
  bool have_tangent = false;
  const auto t0 = Clock::now();
  while (lambda < 1.0) {
    const double dl = std::min(delta, 1.0 - lambda);
    const double target = (1.0 - lambda - dl) < 1e-12 ? 1.0 : lambda + dl;
    const bool final = target == 1.0;
    const Eigen::VectorXd cl = lambda == 0.0 ? c0 : Eigen::VectorXd(c0 + (c - c0) * lambda);
    const Eigen::VectorXd cs = final ? c : Eigen::VectorXd(c0 + (c - c0) * target);
    // Predictor: the tangent of the equilibrium path at the last converged state, shortened
    // (halved up to kPredictorHalvings times, else dropped) until it inverts no body element that
    // the converged state has upright. The tangent is the path's first-order term only: over a
    // long load step (from rest to the far end of a chamber's range) it drives the walls through
    // each other, and Newton, which follows the residual, then converges to a tangled
    // equilibrium lg-aa never reaches (pneumatic_finger res 8, alpha 10: 426 inverted elements
    // and 11 % more energy than lg-aa's 18, in 21 iterations; from a quarter of the tangent,
    // lg-aa's state in 9; docs/newton.md).
    if (!have_tangent) have_tangent = Tangent(cl, converged, c - c0, &tangent, r);
    Eigen::MatrixX3d trial = converged;
    if (have_tangent) {
      const int upright = CountInverted(m, converged).body;
      // With contacts, it must not push a vertex deeper into another part than NewtonStep's
      // trial points may.
      const double depth = AllowedDepth(converged);
      double scale = target - lambda;
      for (int q = 0; q <= kPredictorHalvings; ++q, scale *= 0.5) {
        trial = converged + scale * tangent;
        if (CountInverted(m, trial).body <= upright &&
            (!active_contacts_ || active_contacts_->Check(trial).max_penetration <= depth))
          break;
        if (q == kPredictorHalvings) trial = converged;
      }
    }
    std::string step_why;
    const int before = r->iterations;
    const StepEnd end = NewtonStep(cs, final, &trial, r, &step_why);
    if (end == StepEnd::Converged) {
      converged = trial;
      const int used = r->iterations - before;
      lambda = target;
      have_tangent = false;
      ++r->load_steps;
      // Aim at a few Newton iterations per load step.
      delta = used <= 4 ? 2.0 * dl : used <= 10 ? dl : 0.5 * dl;
      if (options_.on_step)
        options_.on_step(r->load_steps, 0, final ? "converged" : "load_step", r->iterations,
                         Seconds(t0, Clock::now()));
      continue;
    }
    if (end == StepEnd::TimeLimit || end == StepEnd::IterationCap) {
      *X = final ? trial : converged;
      return end;
    }
    delta = 0.5 * dl;
    if (stalls_ >= kMaxStalls) {  // smaller load steps do not make the linear systems easier
      *X = converged;
      *why = step_why;
      return StepEnd::Failed;
    }
    if (delta < limits_.min_load_step) {
      *X = converged;
      std::ostringstream os;
      os << step_why << " (load step cut below " << limits_.min_load_step << " at " << lambda
         << " of the actuation)";
      *why = os.str();
      return StepEnd::Failed;
    }
  }
  *X = converged;
  return StepEnd::Converged;
}

FkResult NewtonSolver::Fallback(const Eigen::VectorXd& c, const Eigen::MatrixX3d* start,
                                const std::string& from, const std::string& reason,
                                const FkResult& so_far, Clock::time_point t0) {
  FkOptions o = options_;
  o.solver = FkSolverType::kLgAa;
  if (deadline_) o.time_limit_s = std::max(1e-3, Seconds(Clock::now(), *deadline_));
  LocalGlobalSolver lg(model_, o, contacts_);
  FkResult f = lg.Solve(c, start);
  f.solver = name();
  f.message = "newton: " + reason + "; continued with lg-aa from " + from +
              (f.message.empty() ? "" : ": " + f.message);
  f.iterations += so_far.iterations;
  f.linear_iterations = so_far.linear_iterations;
  f.load_steps = so_far.load_steps;
  f.time_s = Seconds(t0, Clock::now());
  return f;
}

FkResult NewtonSolver::SolveImpl(const Eigen::Ref<const Eigen::VectorXd>& c_in,
                                 const Eigen::MatrixX3d* warm_start) {
  const Model& m = *model_;
  const auto t0 = Clock::now();
  started_ = reported_ = t0;
  // The factor's solves are single right-hand sides between OpenMP loops: BLAS threads only
  // compete with the OpenMP ones (blas_threads.hpp).
  const ScopedBlasThreads one_blas_thread(1);
  FkResult r;
  if (!StartResult(c_in, warm_start, &r)) {
    r.time_s = Seconds(t0, Clock::now());
    return r;
  }
  const Eigen::VectorXd c = c_in;
  local_time_s_ = 0.0;
  stalls_ = 0;
  deadline_.reset();
  if (options_.time_limit_s > 0)
    deadline_ = t0 + std::chrono::duration_cast<Clock::duration>(
                         std::chrono::duration<double>(options_.time_limit_s));
  active_contacts_ = nullptr;
  if (ContactHandlingActive(m.scene(), options_.collision)) {
    if (!EnsureContactTerm(contacts_, m, options_.collision, &response_, &r.message)) {
      r.status = FkStatus::InvalidInput;
      r.time_s = Seconds(t0, Clock::now());
      return r;
    }
    response_->Reset();
    active_contacts_ = response_.get();
    if (mean_edge_ <= 0.0) mean_edge_ = MeanEdgeLength(m);
  }
  struct Release {
    ContactTerm** p;
    ~Release() { *p = nullptr; }
  } release{&active_contacts_};

  Eigen::MatrixX3d X = r.positions;
  std::string why;
  StepEnd end = StepEnd::Failed;
  if (warm_start) {
    // A warm start is usually close: try the full actuation from it first.
    end = NewtonStep(c, true, &X, &r, &why);
    if (end == StepEnd::Converged) r.load_steps = 1;
  }
  if (end == StepEnd::Failed) {
    X = m.rest_positions();
    const Eigen::VectorXd rest = m.scene().rest_actuation();
    m.ApplyConstraints(rest, &X);
    end = LoadSteps(rest, c, &X, &r, &why);
  }
  if (end == StepEnd::Failed) {
    // From the last converged load step (none: the warm start, or the rest shape), within what
    // is left of the time limit.
    FkResult f = r.load_steps > 0 ? Fallback(c, &X, "the last converged load step", why, r, t0)
                 : warm_start     ? Fallback(c, warm_start, "the warm start", why, r, t0)
                                  : Fallback(c, nullptr, "the rest shape", why, r, t0);
    deadline_.reset();
    return f;
  }
  deadline_.reset();
  r.positions = X;
  r.local_time_s = local_time_s_;
  r.status = end == StepEnd::Converged   ? FkStatus::Converged
             : end == StepEnd::TimeLimit ? FkStatus::TimeLimit
                                         : FkStatus::IterationCap;
  if (end == StepEnd::TimeLimit)
    r.message = "time limit of " + std::to_string(options_.time_limit_s) + " s reached";
  if (end == StepEnd::IterationCap)
    r.message = "iteration cap of " + std::to_string(options_.max_iterations) + " reached";
  ComputeLocalRatios(m, r.positions, c, &ratios_, &r.volume_ratios);
  r.energy = LocalStep(m, r.positions, ratios_, &weighted_, options_.threads);
  if (active_contacts_) {
    r.collision_active = true;
    r.springs = active_contacts_->num_springs();
    r.collision_stats = active_contacts_->stats();
    const auto tc = Clock::now();
    r.collision = active_contacts_->Check(r.positions);  // the exact check of the final state
    r.collision_stats.check_s += Seconds(tc, Clock::now());
  }
  r.time_s = Seconds(t0, Clock::now());
  return r;
}

}  // namespace softkin
