#include "softkin/solver/baselines/nlp_solvers.hpp"

#include "softkin/solver/fk/actuation.hpp"
#include "softkin/solver/fk/energy.hpp"
#include "softkin/solver/fk/rotation.hpp"
#include "softkin/solver/fk/targets.hpp"
#include "softkin/solver/common/text_format.hpp"
#include "softkin/solver/common/stopwatch.hpp"

#include <ceres/ceres.h>
#include <ceres/rotation.h>

#include <IpIpoptApplication.hpp>
#include <IpTNLP.hpp>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <stdexcept>

namespace softkin {
namespace {

using Clock = std::chrono::steady_clock;
// ------------------------------------------------------------------------------------------------
// The ratio-update loop shared by the optimiser-based solvers
// ------------------------------------------------------------------------------------------------

/// Outcome of one minimisation with frozen ratios.
struct InnerResult {
  bool ok = true;  ///< false: the optimiser failed (message says why)
  int iterations = 0;
  std::string message;
};

class RatioUpdateSolver : public FkSolver {
 public:
  RatioUpdateSolver(std::shared_ptr<const Model> model, const FkOptions& options)
      : FkSolver(std::move(model)), options_(options) {
    for (const auto& e : model_->elements()) total_weight_ += e.wv;
  }
  std::string name() const override { return ToString(options_.solver); }

  FkResult SolveImpl(const Eigen::Ref<const Eigen::VectorXd>& c,
                     const Eigen::MatrixX3d* warm_start) override {
    const Model& m = *model_;
    const auto t0 = Clock::now();
    FkResult r;
    if (StartResult(c, warm_start, &r)) r.message = Unsupported();
    if (!r.message.empty()) {
      r.status = FkStatus::InvalidInput;
      r.time_s = Seconds(t0, Clock::now());
      return r;
    }
    const Eigen::VectorXd rest = m.scene().rest_actuation();
    const int K = warm_start ? 1 : options_.continuation_steps;
    has_deadline_ = options_.time_limit_s > 0;
    if (has_deadline_)
      deadline_ = t0 + std::chrono::duration_cast<Clock::duration>(
                           std::chrono::duration<double>(options_.time_limit_s));
    int updates = 0;
    for (int s = 1; s <= K; ++s) {
      const Eigen::VectorXd cs =
          K == 1 ? Eigen::VectorXd(c) : Eigen::VectorXd(rest + (c - rest) * (double(s) / K));
      updates += SolveStage(cs, &r);
      if (options_.on_step)
        options_.on_step(s, K, FkStatusToString(r.status), r.iterations, Seconds(t0, Clock::now()));
      if (r.status != FkStatus::Converged) break;
    }
    std::vector<double> ratios;
    ComputeLocalRatios(m, r.positions, c, &ratios, &r.volume_ratios);
    Eigen::MatrixX3d g;
    r.energy = FixedRatioEnergyAndGradient(m, r.positions, ratios, &g);
    const std::string upd = std::to_string(updates) + " ratio update" + (updates == 1 ? "" : "s");
    r.message = r.message.empty() ? upd : upd + "; " + r.message;
    r.time_s = Seconds(t0, Clock::now());
    return r;
  }

 protected:
  /// "" or why the scene uses something this solver cannot express.
  virtual std::string Unsupported() const { return ""; }
  /// Minimises E with `ratios` frozen, from X (prescribed coordinates already set), until the
  /// 2-norm of the gradient over the free coordinates is below grad_tol or max_iterations.
  virtual InnerResult Minimize(const std::vector<double>& ratios, double grad_tol,
                               int max_iterations, Eigen::MatrixX3d* X) = 0;

  /// Gradient norm over the free coordinates of E with ratios frozen at their values at X.
  double FreeGradientNorm(const Eigen::VectorXd& c, const Eigen::MatrixX3d& X,
                          std::vector<double>* ratios, double* E) const {
    ComputeLocalRatios(*model_, X, c, ratios);
    Eigen::MatrixX3d G;
    *E = FixedRatioEnergyAndGradient(*model_, X, *ratios, &G);
    Eigen::VectorXd g;
    model_->GatherFree(G, &g);
    return g.norm();
  }

  /// Seconds left before the time limit (a large number without one).
  double SecondsLeft() const { return has_deadline_ ? Seconds(Clock::now(), deadline_) : 1e30; }

  FkOptions options_;
  double total_weight_ = 0;
  bool has_deadline_ = false;
  Clock::time_point deadline_;

 private:
  /// One continuation stage; returns the number of ratio updates.
  int SolveStage(const Eigen::VectorXd& c, FkResult* r) {
    const Model& m = *model_;
    Eigen::MatrixX3d& X = r->positions;
    m.ApplyConstraints(c, &X);
    std::vector<double> ratios;
    double E = 0;
    // Reference: the gradient at the rest shape for this actuation (as the local-global solver).
    Eigen::MatrixX3d Xr = m.rest_positions();
    m.ApplyConstraints(c, &Xr);
    double ref = FreeGradientNorm(c, Xr, &ratios, &E);
    const double floor = 1e-12 * total_weight_ * m.size();
    int updates = 0;
    double move = std::numeric_limits<double>::infinity();
    for (;;) {
      const double grad = FreeGradientNorm(c, X, &ratios, &E);
      if (!std::isfinite(grad) || !std::isfinite(E)) {
        r->status = FkStatus::Diverged;
        r->message =
            "non-finite energy or gradient after " + std::to_string(updates) + " ratio updates";
        return updates;
      }
      if (updates == 0) ref = std::max({ref, grad, 1e-8 * total_weight_ * m.size()});
      r->gradient_ratio = ref > 0 ? grad / ref : 0.0;
      r->max_move = std::isfinite(move) ? move : 0.0;
      if (updates > 0 && move < options_.tolerance &&
          (r->gradient_ratio < options_.gradient_tolerance || grad <= floor)) {
        r->status = FkStatus::Converged;
        return updates;
      }
      if (updates > 0 && move == 0.0) {
        // The last inner solve left every coordinate as it was, so the ratios are those it was
        // given and every further update would repeat it: the loop is at a fixed point in floating
        // point. That happens at the precision floor, where the optimiser can no longer lower the
        // energy (Ceres: |cost change| / cost = 0), and before the gradient target when that target
        // is below what double precision resolves. Within 100x of the target this is convergence;
        // further out the optimiser is stuck.
        if (r->gradient_ratio < 100.0 * options_.gradient_tolerance) {
          r->status = FkStatus::Converged;
          r->message =
              "stopped at the precision floor: the optimiser no longer changes the positions "
              "(gradient ratio " +
              FormatNumber(r->gradient_ratio, 3) + ", target " +
              FormatNumber(options_.gradient_tolerance, 3) + ")";
        } else {
          r->status = FkStatus::Diverged;
          r->message = "stalled: the optimiser no longer changes the positions at gradient ratio " +
                       FormatNumber(r->gradient_ratio, 3) + " (target " +
                       FormatNumber(options_.gradient_tolerance, 3) + ")";
        }
        return updates;
      }
      if (SecondsLeft() <= 0) {
        r->status = FkStatus::TimeLimit;
        r->message = "time limit of " + std::to_string(options_.time_limit_s) + " s reached";
        return updates;
      }
      const int left = options_.max_iterations - r->iterations;
      if (left <= 0) {
        r->status = FkStatus::IterationCap;
        r->message = "iteration cap of " + std::to_string(options_.max_iterations) + " reached";
        return updates;
      }
      const Eigen::MatrixX3d before = X;
      // The inner solve goes well below the outer threshold, so that the ratio update, not the
      // inner tolerance, decides when to stop.
      const InnerResult in = Minimize(ratios, 0.1 * options_.gradient_tolerance * ref, left, &X);
      r->iterations += in.iterations;
      ++updates;
      if (!in.ok || !X.allFinite()) {
        if (!X.allFinite()) X = before;
        r->status = FkStatus::Diverged;
        r->message =
            in.message.empty() ? "the optimiser returned non-finite positions" : in.message;
        return updates;
      }
      move = (X - before).rowwise().norm().maxCoeff() / m.size();
    }
  }
};

// ------------------------------------------------------------------------------------------------
// Ceres
// ------------------------------------------------------------------------------------------------

/// sqrt(w Vol) (N V - R P~) for an element with K vertices: P~ the shaped, centred rest rows.
template <int K>
struct ElementResidual {
  Eigen::Matrix<double, K, 3> P;
  double sw = 1.0;

  template <typename T>
  bool Eval(const T* aa, const T* const* v, T* res) const {
    T mean[3] = {T(0), T(0), T(0)};
    for (int j = 0; j < K; ++j)
      for (int d = 0; d < 3; ++d) mean[d] += v[j][d];
    for (int d = 0; d < 3; ++d) mean[d] /= T(K);
    for (int j = 0; j < K; ++j) {
      const T p[3] = {T(P(j, 0)), T(P(j, 1)), T(P(j, 2))};
      T q[3];
      ceres::AngleAxisRotatePoint(aa, p, q);
      for (int d = 0; d < 3; ++d) res[3 * j + d] = T(sw) * (v[j][d] - mean[d] - q[d]);
    }
    return true;
  }
};

struct TetResidual : ElementResidual<4> {
  template <typename T>
  bool operator()(const T* aa, const T* v0, const T* v1, const T* v2, const T* v3, T* res) const {
    const T* v[4] = {v0, v1, v2, v3};
    return Eval(aa, v, res);
  }
};

struct PrismResidual : ElementResidual<6> {
  template <typename T>
  bool operator()(const T* aa, const T* v0, const T* v1, const T* v2, const T* v3, const T* v4,
                  const T* v5, T* res) const {
    const T* v[6] = {v0, v1, v2, v3, v4, v5};
    return Eval(aa, v, res);
  }
};

class CeresFkSolver : public RatioUpdateSolver {
 public:
  using RatioUpdateSolver::RatioUpdateSolver;

 protected:
  std::string Unsupported() const override {
    for (const auto& [tag, mat] : model_->scene().body)
      if (mat.hyperelastic())
        return "ceres: body region " + std::to_string(tag) +
               " is hyperelastic (mooney-rivlin); the Ceres problem supports the blend law with "
               "r_omega = 1 only (use ipopt-* or lg)";
      else if (mat.r_omega < 1.0)
        return "ceres: body region " + std::to_string(tag) + " has r_omega " +
               std::to_string(mat.r_omega) +
               "; the Ceres problem supports r_omega = 1 only (use ipopt-* or lg)";
    return "";
  }

  InnerResult Minimize(const std::vector<double>& ratios, double grad_tol, int max_iterations,
                       Eigen::MatrixX3d* Xp) override {
    const Model& m = *model_;
    const Scene& scene = m.scene();
    Eigen::MatrixX3d& X = *Xp;
    const int nv = m.num_vertices();
    std::vector<double> pos(3 * static_cast<size_t>(nv));
    for (int v = 0; v < nv; ++v)
      for (int d = 0; d < 3; ++d) pos[3 * v + d] = X(v, d);
    const auto& els = m.elements();
    std::vector<double> rot(3 * els.size(), 0.0);

    ceres::Problem::Options po;
    po.manifold_ownership = ceres::TAKE_OWNERSHIP;
    ceres::Problem problem(po);
    for (int v = 0; v < nv; ++v) problem.AddParameterBlock(&pos[3 * v], 3);
    for (size_t i = 0; i < els.size(); ++i) {
      const ModelElement& e = els[i];
      if (e.role != ElementRole::Body && ratios[i] == kVented) continue;  // no energy
      ElemRows Pt = ElemRows::Zero();
      Pt.topRows(e.k) = e.rest.topRows(e.k);
      if (e.role != ElementRole::Body)
        Pt.topRows(e.k) = e.rest.topRows(e.k) * ActuationShape(e, ratios[i]).transpose();
      ElemRows D = ElemRows::Zero();
      for (int j = 0; j < e.k; ++j) D.row(j) = X.row(e.v[j]);
      CenterRows(D, e.k);
      const Eigen::Matrix3d R = BestRotation(D.topRows(e.k).transpose() * Pt.topRows(e.k));
      ceres::RotationMatrixToAngleAxis(R.data(), &rot[3 * i]);
      double* aa = &rot[3 * i];
      auto vp = [&](int j) { return &pos[3 * e.v[j]]; };
      if (e.k == 4) {
        auto* f = new TetResidual;
        f->P = Pt.topRows<4>();
        f->sw = std::sqrt(e.wv);
        problem.AddResidualBlock(new ceres::AutoDiffCostFunction<TetResidual, 12, 3, 3, 3, 3, 3>(f),
                                 nullptr, aa, vp(0), vp(1), vp(2), vp(3));
      } else {
        auto* f = new PrismResidual;
        f->P = Pt.topRows<6>();
        f->sw = std::sqrt(e.wv);
        problem.AddResidualBlock(
            new ceres::AutoDiffCostFunction<PrismResidual, 18, 3, 3, 3, 3, 3, 3, 3>(f), nullptr, aa,
            vp(0), vp(1), vp(2), vp(3), vp(4), vp(5));
      }
    }
    // Prescribed coordinates: fixed and moved vertices constant, per-axis holds via a manifold.
    for (int v = 0; v < nv; ++v) {
      std::vector<int> held;
      for (int d = 0; d < 3; ++d)
        if (m.free_index(d)[v] < 0) held.push_back(d);
      if (held.size() == 3)
        problem.SetParameterBlockConstant(&pos[3 * v]);
      else if (!held.empty())
        problem.SetManifold(&pos[3 * v], new ceres::SubsetManifold(3, held));
    }
    (void)scene;

    ceres::Solver::Options so;
    so.minimizer_type = ceres::TRUST_REGION;
    so.trust_region_strategy_type = ceres::LEVENBERG_MARQUARDT;
    so.linear_solver_type = ceres::SPARSE_NORMAL_CHOLESKY;
    so.sparse_linear_algebra_library_type = ceres::SUITE_SPARSE;
    so.max_num_iterations = max_iterations;
    so.num_threads = options_.threads > 0 ? options_.threads : 2;
    // Ceres minimises (1/2) sum ||r||^2 = E / 2 and tests the max-norm of its gradient; a
    // max-norm below t / sqrt(n) keeps the 2-norm below t.
    so.gradient_tolerance = 0.5 * grad_tol / std::sqrt(std::max(1, m.num_free_dofs()));
    so.function_tolerance = 1e-16;
    so.parameter_tolerance = 1e-16;
    so.logging_type = ceres::SILENT;
    so.max_solver_time_in_seconds = std::max(1e-3, std::min(1e9, SecondsLeft()));
    ceres::Solver::Summary summary;
    ceres::Solve(so, &problem, &summary);

    InnerResult out;
    out.iterations = static_cast<int>(summary.iterations.size()) - 1;
    if (summary.termination_type == ceres::FAILURE ||
        summary.termination_type == ceres::USER_FAILURE) {
      out.ok = false;
      out.message = "ceres: " + summary.message;
      return out;
    }
    for (int v = 0; v < nv; ++v)
      for (int d = 0; d < 3; ++d) X(v, d) = pos[3 * v + d];
    return out;
  }
};

// ------------------------------------------------------------------------------------------------
// Ipopt
// ------------------------------------------------------------------------------------------------

/// What the Ipopt problems share: the free vertex coordinates as unbounded variables, the energy
/// with per-element ratios `ratios` (FixedRatioEnergyAndGradient) and its gradient cached per x,
/// equality constraints g(x) = 0 (if any), the iteration count, a wall-clock deadline, and the
/// final point written back to X.
class VertexTnlp : public Ipopt::TNLP {
 public:
  VertexTnlp(const Model& m, const std::vector<double>& ratios, Eigen::MatrixX3d* X,
             double seconds_left)
      : m_(m),
        ratios_(ratios),
        X_(X),
        deadline_(Clock::now() + std::chrono::duration_cast<Clock::duration>(
                                     std::chrono::duration<double>(std::min(seconds_left, 1e9)))) {
    m.GatherFree(*X, &x0_);
    int off = 0;
    for (int d = 0; d < 3; ++d) {
      offset_[d] = off;
      off += static_cast<int>(m.free_vertices(d).size());
    }
  }
  int iterations = 0;
  bool timed_out = false;
  Ipopt::SolverReturn status = Ipopt::INTERNAL_ERROR;

  bool get_bounds_info(Ipopt::Index n, Ipopt::Number* xl, Ipopt::Number* xu, Ipopt::Index mc,
                       Ipopt::Number* gl, Ipopt::Number* gu) override {
    for (Ipopt::Index i = 0; i < n; ++i) {
      xl[i] = -2e19;  // Ipopt's "no bound" (nlp_lower_bound_inf = -1e19)
      xu[i] = 2e19;
    }
    for (Ipopt::Index q = 0; q < mc; ++q) gl[q] = gu[q] = 0.0;
    return true;
  }
  bool get_starting_point(Ipopt::Index n, bool init_x, Ipopt::Number* x, bool, Ipopt::Number*,
                          Ipopt::Number*, Ipopt::Index, bool, Ipopt::Number*) override {
    if (init_x) std::copy(x0_.data(), x0_.data() + n, x);
    return true;
  }
  bool eval_f(Ipopt::Index n, const Ipopt::Number* x, bool, Ipopt::Number& f) override {
    Eval(n, x);
    f = E_;
    return std::isfinite(E_);
  }
  bool eval_grad_f(Ipopt::Index n, const Ipopt::Number* x, bool, Ipopt::Number* g) override {
    Eval(n, x);
    std::copy(g_.data(), g_.data() + n, g);
    return g_.allFinite();
  }
  bool intermediate_callback(Ipopt::AlgorithmMode, Ipopt::Index iter, Ipopt::Number, Ipopt::Number,
                             Ipopt::Number, Ipopt::Number, Ipopt::Number, Ipopt::Number,
                             Ipopt::Number, Ipopt::Number, Ipopt::Index, const Ipopt::IpoptData*,
                             Ipopt::IpoptCalculatedQuantities*) override {
    iterations = iter;
    timed_out = Clock::now() >= deadline_;
    return !timed_out;  // false stops Ipopt (USER_REQUESTED_STOP)
  }
  void finalize_solution(Ipopt::SolverReturn st, Ipopt::Index n, const Ipopt::Number* x,
                         const Ipopt::Number*, const Ipopt::Number*, Ipopt::Index mc,
                         const Ipopt::Number* g, const Ipopt::Number*, Ipopt::Number,
                         const Ipopt::IpoptData*, Ipopt::IpoptCalculatedQuantities*) override {
    status = st;
    const Eigen::Map<const Eigen::VectorXd> xs(x, n);
    if (xs.allFinite()) m_.ScatterFree(Eigen::VectorXd(xs), X_);
    OnFinal(mc, g);
  }

 protected:
  /// Extra work per new x (after the energy and gradient), and at the end (final g values).
  virtual void OnEval(const Eigen::MatrixX3d&) {}
  virtual void OnFinal(Ipopt::Index, const Ipopt::Number*) {}

  void Eval(Ipopt::Index n, const Ipopt::Number* x) {
    const Eigen::Map<const Eigen::VectorXd> xv(x, n);
    if (have_ && xv == last_) return;
    last_ = xv;
    have_ = true;
    work_ = *X_;
    m_.ScatterFree(last_, &work_);
    Eigen::MatrixX3d G;
    E_ = FixedRatioEnergyAndGradient(m_, work_, ratios_, &G);
    m_.GatherFree(G, &g_);
    OnEval(work_);
  }

  const Model& m_;
  const std::vector<double>& ratios_;
  Eigen::MatrixX3d* X_;
  Clock::time_point deadline_;
  Eigen::VectorXd x0_, last_, g_;
  Eigen::MatrixX3d work_;
  bool have_ = false;
  double E_ = 0;
  int offset_[3] = {0, 0, 0};
};

/// The unconstrained problem of ipopt-lbfgs / ipopt-newton (Gauss-Newton Hessian 2 A_ff).
class FkTnlp : public VertexTnlp {
 public:
  FkTnlp(const Model& m, const std::vector<double>& ratios, Eigen::MatrixX3d* X, bool gn_hessian,
         double seconds_left)
      : VertexTnlp(m, ratios, X, seconds_left), gn_(gn_hessian) {}

  bool get_nlp_info(Ipopt::Index& n, Ipopt::Index& mc, Ipopt::Index& nnz_jac, Ipopt::Index& nnz_h,
                    IndexStyleEnum& style) override {
    n = m_.num_free_dofs();
    mc = 0;
    nnz_jac = 0;
    nnz_h = 0;
    if (gn_)
      for (int d = 0; d < 3; ++d) nnz_h += LowerNonZeros(m_.A_ff(d));
    style = C_STYLE;
    return true;
  }
  bool eval_g(Ipopt::Index, const Ipopt::Number*, bool, Ipopt::Index, Ipopt::Number*) override {
    return true;
  }
  bool eval_jac_g(Ipopt::Index, const Ipopt::Number*, bool, Ipopt::Index, Ipopt::Index,
                  Ipopt::Index*, Ipopt::Index*, Ipopt::Number*) override {
    return true;
  }
  bool eval_h(Ipopt::Index, const Ipopt::Number*, bool, Ipopt::Number obj_factor, Ipopt::Index,
              const Ipopt::Number*, bool, Ipopt::Index, Ipopt::Index* rows, Ipopt::Index* cols,
              Ipopt::Number* values) override {
    // Gauss-Newton Hessian 2 A_ff per axis (lower triangle), constant in x.
    Ipopt::Index q = 0;
    for (int d = 0; d < 3; ++d) {
      const auto& A = m_.A_ff(d);
      for (int col = 0; col < A.outerSize(); ++col)
        for (Eigen::SparseMatrix<double>::InnerIterator it(A, col); it; ++it) {
          if (it.row() < col) continue;
          if (values) {
            values[q] = 2.0 * obj_factor * it.value();
          } else {
            rows[q] = offset_[d] + static_cast<Ipopt::Index>(it.row());
            cols[q] = offset_[d] + col;
          }
          ++q;
        }
    }
    return true;
  }

 private:
  static int LowerNonZeros(const Eigen::SparseMatrix<double>& A) {
    int n = 0;
    for (int col = 0; col < A.outerSize(); ++col)
      for (Eigen::SparseMatrix<double>::InnerIterator it(A, col); it; ++it)
        if (it.row() >= col) ++n;
    return n;
  }
  bool gn_;
};

/// Ipopt options shared by the solvers: quiet unless SOFTKIN_IPOPT_PRINT_LEVEL (0-12) asks for
/// Ipopt's own log; no automatic scaling; the max-norm tolerance `tol` on the KKT error; no
/// "acceptable" early stop.
void ConfigureIpopt(Ipopt::OptionsList& o, int max_iterations, double tol) {
  const char* pl = std::getenv("SOFTKIN_IPOPT_PRINT_LEVEL");
  o.SetIntegerValue("print_level", pl ? std::clamp(std::atoi(pl), 0, 12) : 0);
  o.SetStringValue("sb", "yes");
  o.SetStringValue("nlp_scaling_method", "none");
  o.SetIntegerValue("max_iter", max_iterations);
  o.SetNumericValue("tol", tol);
  o.SetNumericValue("dual_inf_tol", tol);
  o.SetIntegerValue("acceptable_iter", 0);
}

class IpoptFkSolver : public RatioUpdateSolver {
 public:
  IpoptFkSolver(std::shared_ptr<const Model> model, const FkOptions& options, bool newton)
      : RatioUpdateSolver(std::move(model), options), newton_(newton) {}

 protected:
  InnerResult Minimize(const std::vector<double>& ratios, double grad_tol, int max_iterations,
                       Eigen::MatrixX3d* X) override {
    Ipopt::SmartPtr<FkTnlp> nlp = new FkTnlp(*model_, ratios, X, newton_, SecondsLeft());
    Ipopt::SmartPtr<Ipopt::IpoptApplication> app = IpoptApplicationFactory();
    auto& o = *app->Options();
    // Unconstrained: the NLP error is the max-norm of the gradient; a max-norm below
    // grad_tol / sqrt(n) keeps the 2-norm target of the ratio-update loop.
    ConfigureIpopt(o, max_iterations, grad_tol / std::sqrt(std::max(1, model_->num_free_dofs())));
    o.SetStringValue("hessian_approximation", newton_ ? "exact" : "limited-memory");
    if (newton_) o.SetStringValue("hessian_constant", "yes");
    InnerResult out;
    if (app->Initialize() != Ipopt::Solve_Succeeded) {
      out.ok = false;
      out.message = "ipopt: initialisation failed";
      return out;
    }
    app->OptimizeTNLP(nlp);
    out.iterations = nlp->iterations;
    const Ipopt::SolverReturn st = nlp->status;
    // Stopping short (iteration cap, time limit, tiny step) is fine here: the ratio-update loop
    // decides with its own test; a failure is not.
    if (!(st == Ipopt::SUCCESS || st == Ipopt::STOP_AT_ACCEPTABLE_POINT ||
          st == Ipopt::MAXITER_EXCEEDED || st == Ipopt::STOP_AT_TINY_STEP ||
          st == Ipopt::USER_REQUESTED_STOP)) {
      out.ok = false;
      out.message = "ipopt stopped with return code " + std::to_string(static_cast<int>(st));
    }
    return out;
  }

 private:
  bool newton_;
};

// ------------------------------------------------------------------------------------------------
// Ipopt with hard actuation constraints ("the straightforward method" of Sec. 2.3.3)
// ------------------------------------------------------------------------------------------------

/// min sum over body elements w Vol ||N V^d - R N V||^2 subject to, for every active actuation
/// group g, sum_i m_i(x) = rho_g (M_g + L_R) - L_R (chamber volume, Eq. 3.2; cable length; DEA
/// area). The actuation elements carry no energy: their region only defines the measured
/// quantity. L-BFGS Hessian (the constraints' Hessians are not formed).
class HardTnlp : public VertexTnlp {
 public:
  HardTnlp(const Model& m, const std::vector<double>& body_ratios, const std::vector<int>& groups,
           const std::vector<double>& targets, Eigen::MatrixX3d* X, double seconds_left)
      : VertexTnlp(m, body_ratios, X, seconds_left), groups_(groups), targets_(targets) {
    // Jacobian sparsity: the free coordinates of each group's vertices.
    for (int g : groups_) {
      std::vector<int> cols;
      for (int i : m.group_elements(g)) {
        const ModelElement& e = m.elements()[i];
        for (int j = 0; j < e.k; ++j)
          for (int d = 0; d < 3; ++d) {
            const int f = m.free_index(d)[e.v[j]];
            if (f >= 0) cols.push_back(offset_[d] + f);
          }
      }
      std::sort(cols.begin(), cols.end());
      cols.erase(std::unique(cols.begin(), cols.end()), cols.end());
      jac_cols_.push_back(std::move(cols));
    }
  }
  double max_violation = 0;  ///< largest |g_q| / |target_q| at the end

  bool get_nlp_info(Ipopt::Index& n, Ipopt::Index& mc, Ipopt::Index& nnz_jac, Ipopt::Index& nnz_h,
                    IndexStyleEnum& style) override {
    n = m_.num_free_dofs();
    mc = static_cast<Ipopt::Index>(groups_.size());
    nnz_jac = 0;
    for (const auto& c : jac_cols_) nnz_jac += static_cast<Ipopt::Index>(c.size());
    nnz_h = 0;
    style = C_STYLE;
    return true;
  }
  bool eval_g(Ipopt::Index n, const Ipopt::Number* x, bool, Ipopt::Index mc,
              Ipopt::Number* g) override {
    Eval(n, x);
    for (Ipopt::Index q = 0; q < mc; ++q) g[q] = measure_[q] - targets_[q];
    return true;
  }
  bool eval_jac_g(Ipopt::Index n, const Ipopt::Number* x, bool, Ipopt::Index, Ipopt::Index,
                  Ipopt::Index* rows, Ipopt::Index* cols, Ipopt::Number* values) override {
    Ipopt::Index k = 0;
    if (!values) {
      for (size_t q = 0; q < jac_cols_.size(); ++q)
        for (int c : jac_cols_[q]) {
          rows[k] = static_cast<Ipopt::Index>(q);
          cols[k++] = c;
        }
      return true;
    }
    Eval(n, x);
    for (size_t q = 0; q < jac_cols_.size(); ++q)
      for (int c : jac_cols_[q]) values[k++] = jac_[q][c];
    return true;
  }

 protected:
  void OnEval(const Eigen::MatrixX3d& X) override {
    measure_.assign(groups_.size(), 0.0);
    jac_.assign(groups_.size(), {});
    for (size_t q = 0; q < groups_.size(); ++q) {
      Eigen::MatrixX3d Gm = Eigen::MatrixX3d::Zero(m_.num_vertices(), 3);
      for (int i : m_.group_elements(groups_[q])) {
        const ModelElement& e = m_.elements()[i];
        ElemRows P = ElemRows::Zero();
        for (int j = 0; j < e.k; ++j) P.row(j) = X.row(e.v[j]);
        measure_[q] += ActuationMeasure(e, P);
        const ElemRows gm = ActuationMeasureGradient(e, P);
        for (int j = 0; j < e.k; ++j) Gm.row(e.v[j]) += gm.row(j);
      }
      m_.GatherFree(Gm, &jac_[q]);
    }
  }
  void OnFinal(Ipopt::Index mc, const Ipopt::Number* g) override {
    max_violation = 0;
    for (Ipopt::Index q = 0; q < mc; ++q)
      max_violation =
          std::max(max_violation, std::abs(g[q]) / std::max(1e-300, std::abs(targets_[q])));
  }

 private:
  const std::vector<int>& groups_;
  const std::vector<double>& targets_;
  std::vector<double> measure_;
  std::vector<Eigen::VectorXd> jac_;
  std::vector<std::vector<int>> jac_cols_;
};

class IpoptHardSolver : public FkSolver {
 public:
  IpoptHardSolver(std::shared_ptr<const Model> model, const FkOptions& options)
      : FkSolver(std::move(model)), options_(options) {}
  std::string name() const override { return ToString(options_.solver); }

  FkResult SolveImpl(const Eigen::Ref<const Eigen::VectorXd>& c,
                     const Eigen::MatrixX3d* warm_start) override {
    const Model& m = *model_;
    const auto t0 = Clock::now();
    FkResult r;
    if (!StartResult(c, warm_start, &r)) {
      r.time_s = Seconds(t0, Clock::now());
      return r;
    }
    Eigen::MatrixX3d& X = r.positions;
    m.ApplyConstraints(c, &X);
    // Active groups (the inactive side of a signed actuator is vented: no constraint) and their
    // targets; every actuation element is left out of the energy (ratio kVented).
    std::vector<double> ratios;
    ComputeLocalRatios(m, X, c, &ratios);
    std::vector<int> groups;
    std::vector<double> targets;
    for (int g = 0; g < m.num_groups(); ++g) {
      const auto& ids = m.group_elements(g);
      if (ids.empty() || ratios[ids[0]] == kVented) continue;
      groups.push_back(g);
      targets.push_back(m.GroupRatio(g, c) * (m.group_rest_measure(g) + m.group_offset(g)) -
                        m.group_offset(g));
    }
    std::vector<double> body_ratios(m.elements().size(), 1.0);
    for (size_t i = 0; i < m.elements().size(); ++i)
      if (m.elements()[i].role != ElementRole::Body) body_ratios[i] = kVented;
    // Reference gradient as for the other solvers (Eq. 2.10 at the rest shape for c).
    Eigen::MatrixX3d Xr = m.rest_positions(), G;
    m.ApplyConstraints(c, &Xr);
    std::vector<double> rr;
    ComputeLocalRatios(m, Xr, c, &rr);
    FixedRatioEnergyAndGradient(m, Xr, rr, &G);
    Eigen::VectorXd g0;
    m.GatherFree(G, &g0);
    const double ref = std::max(g0.norm(), 1e-12);

    const double left = options_.time_limit_s > 0 ? options_.time_limit_s : 1e30;
    Ipopt::SmartPtr<HardTnlp> nlp = new HardTnlp(m, body_ratios, groups, targets, &X, left);
    Ipopt::SmartPtr<Ipopt::IpoptApplication> app = IpoptApplicationFactory();
    auto& o = *app->Options();
    ConfigureIpopt(o, options_.max_iterations,
                   options_.gradient_tolerance * ref / std::sqrt(std::max(1, m.num_free_dofs())));
    o.SetStringValue("hessian_approximation", "limited-memory");
    // Each volume constraint is a dense-ish row over the chamber's vertices. MUMPS's default
    // ordering (SCOTCH here) then estimates a huge fill and fails to allocate (7.5 GB asked on the
    // 46.7k-tet finger); QAMD detects dense rows and orders them last.
    o.SetIntegerValue("mumps_pivot_order", 6);
    double tscale = 0;
    for (double t : targets) tscale = std::max(tscale, std::abs(t));
    o.SetNumericValue("constr_viol_tol", 1e-8 * std::max(1.0, tscale));
    if (app->Initialize() != Ipopt::Solve_Succeeded) {
      r.status = FkStatus::Diverged;
      r.message = "ipopt: initialisation failed";
    } else {
      app->OptimizeTNLP(nlp);
      r.iterations = nlp->iterations;
      switch (nlp->status) {
        case Ipopt::SUCCESS:
          r.status = FkStatus::Converged;
          break;
        case Ipopt::MAXITER_EXCEEDED:
          r.status = FkStatus::IterationCap;
          r.message = "iteration cap of " + std::to_string(options_.max_iterations) + " reached";
          break;
        case Ipopt::USER_REQUESTED_STOP:
          r.status = nlp->timed_out ? FkStatus::TimeLimit : FkStatus::Diverged;
          r.message = "time limit of " + std::to_string(options_.time_limit_s) + " s reached";
          break;
        default:
          r.status = FkStatus::Diverged;
          r.message = "ipopt return code " + std::to_string(static_cast<int>(nlp->status));
      }
      if (!X.allFinite()) {
        X = m.rest_positions();
        m.ApplyConstraints(c, &X);
        r.status = FkStatus::Diverged;
        r.message = "ipopt returned non-finite positions";
      }
      char buf[96];
      std::snprintf(buf, sizeof(buf), "largest relative constraint violation %.2e",
                    nlp->max_violation);
      r.message = r.message.empty() ? buf : r.message + "; " + buf;
    }
    // Report the Eq. 2.10 energy (with the local ratios at the result), as the other solvers do.
    ComputeLocalRatios(m, X, c, &ratios, &r.volume_ratios);
    Eigen::MatrixX3d Gx;
    r.energy = FixedRatioEnergyAndGradient(m, X, ratios, &Gx);
    Eigen::VectorXd gx;
    m.GatherFree(Gx, &gx);
    r.gradient_ratio = gx.norm() / ref;
    r.time_s = Seconds(t0, Clock::now());
    return r;
  }

 private:
  FkOptions options_;
};

}  // namespace

bool HasCeresSolver() { return true; }
bool HasIpoptSolver() { return true; }

std::unique_ptr<FkSolver> MakeNlpSolver(std::shared_ptr<const Model> model,
                                        const FkOptions& options) {
  if (options.solver == FkSolverType::kCeres)
    return std::make_unique<CeresFkSolver>(std::move(model), options);
  if (options.solver == FkSolverType::kIpoptLbfgs)
    return std::make_unique<IpoptFkSolver>(std::move(model), options, false);
  if (options.solver == FkSolverType::kIpoptNewton)
    return std::make_unique<IpoptFkSolver>(std::move(model), options, true);
  if (options.solver == FkSolverType::kIpoptHard)
    return std::make_unique<IpoptHardSolver>(std::move(model), options);
  throw std::invalid_argument("MakeNlpSolver: not a general-purpose optimiser: '" +
                              ToString(options.solver) + "'");
}

}  // namespace softkin
