/// \file equilibrium_jacobian.cpp
/// The implicit Jacobian dX/dc (equilibrium_jacobian.hpp): the "local" preconditioner, the
/// batched Krylov solves (GMRES columns of gmres.hpp, BiCGSTAB) on the operator of
/// free_operator.hpp, and ComputeEquilibriumJacobian. The linearization they apply is in
/// equilibrium_linearization.cpp.
#include "softkin/solver/sensitivity/equilibrium_jacobian.hpp"

#include "softkin/solver/common/blas_threads.hpp"
#include "softkin/solver/common/enum_names.hpp"
#include "softkin/solver/sensitivity/free_operator.hpp"
#include "softkin/solver/sensitivity/gmres.hpp"

#include "softkin/solver/fk/actuation.hpp"
#include "softkin/solver/fk/rotation.hpp"
#include "softkin/solver/fk/targets.hpp"
#include "softkin/solver/common/stopwatch.hpp"

#include <Eigen/Eigenvalues>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <sstream>
#include <tuple>

#include <omp.h>

namespace softkin {

namespace {
constexpr EnumName<KrylovMethod> kKrylovNames[] = {
    {KrylovMethod::kGmres, "gmres"},
    {KrylovMethod::kBicgstab, "bicgstab"},
};
constexpr EnumName<JacobianPreconditioner> kPreconditionerNames[] = {
    {JacobianPreconditioner::kAff, "A_ff"},
    {JacobianPreconditioner::kLocal, "local"},
};
}  // namespace

std::string ToString(KrylovMethod k) { return EnumToString(kKrylovNames, k); }
KrylovMethod KrylovMethodFromString(const std::string& s) {
  return EnumFromString(kKrylovNames, s, "Krylov method");
}
std::vector<std::string> KrylovMethodNames() { return EnumNames(kKrylovNames); }

std::string ToString(JacobianPreconditioner p) { return EnumToString(kPreconditionerNames, p); }
JacobianPreconditioner JacobianPreconditionerFromString(const std::string& s) {
  return EnumFromString(kPreconditionerNames, s, "preconditioner");
}
std::vector<std::string> JacobianPreconditionerNames() { return EnumNames(kPreconditionerNames); }

bool EquilibriumJacobianOptions::IsValid(std::string* why) const {
  auto bad = [&](const std::string& m) {
    if (why) *why = m;
    return false;
  };
  if (!(tolerance > 0.0 && tolerance < 1.0))
    return bad("implicit.tolerance: expected a number in (0, 1)");
  if (max_iterations < 1) return bad("implicit.max_iterations: expected an integer >= 1");
  if (restart < 1 || restart > 1000)
    return bad("implicit.restart: expected an integer in [1, 1000]");
  if (threads < 0) return bad("implicit.threads: expected an integer >= 0");
  return true;
}

Eigen::MatrixX3d PrescribedDerivative(const Model& model,
                                      const Eigen::Ref<const Eigen::VectorXd>& c, int a) {
  Eigen::MatrixX3d dXc = Eigen::MatrixX3d::Zero(model.num_vertices(), 3);
  const Actuator& act = model.scene().actuators[a];
  if (!act.is_motion()) return dXc;
  const double h = 1e-6 * std::max(act.max - act.min, 1e-6);
  Eigen::VectorXd cp = c, cm = c;
  cp[a] += h;
  cm[a] -= h;
  Eigen::MatrixX3d Xp = Eigen::MatrixX3d::Zero(model.num_vertices(), 3), Xm = Xp;
  model.ApplyConstraints(cp, &Xp);
  model.ApplyConstraints(cm, &Xm);
  dXc = (Xp - Xm) / (2.0 * h);
  // Free coordinates are zero in both (ApplyConstraints leaves them untouched).
  return dXc;
}

/// What the "local" preconditioner keeps between Jacobians of one model: the pattern of
/// P = A_ff - sym(K_local)_ff in the free layout of FreeOperator (axis-major), where each of its
/// values comes from (an entry of A's pattern, d, d'), and CHOLMOD's symbolic analysis.
struct EquilibriumJacobianWorkspace::Impl {
  const Model* model = nullptr;
  std::vector<int>
      elem_pos;  ///< element i, local (q, qc): A value index of (v_q, v_qc); 36 per element
  Eigen::SparseMatrix<double> P;  ///< free-layout pattern and values
  std::vector<int> p_src;         ///< per P value: 9 * (A entry) + 3 d + d'
  LocalPreconditioner llt;
  bool analyzed = false;
  bool has_factor = false;  ///< llt holds a numeric factor (of some earlier state)
  bool stale = false;       ///< the last solve with a reused factor took too many rounds
  /// The last factorisation failed (P indefinite, e.g. cable_finger's slack cables); with
  /// reuse on, this workspace stops trying and preconditions by A_ff.
  bool not_positive_definite = false;
  /// A_ff - sym(K_local) was indefinite once: assemble the per-element PSD projection directly.
  bool project = false;
  int fresh_rounds = -1;  ///< GMRES rounds of the first solve after the last factorisation
  std::vector<std::vector<double>> blocks;  ///< per thread: 9 values per A entry (K_local)
  std::vector<int> diag_pos;  ///< per free coordinate: the index of its diagonal entry in P
  Eigen::VectorXd a_diag;     ///< per free coordinate: A's diagonal entry of its vertex
  int factorizations = 0;

  void Build(const Model& m) {
    model = &m;
    const Eigen::SparseMatrix<double>& A = m.A();
    const int nv = m.num_vertices(), nf = m.num_free_dofs();
    const int nnz = static_cast<int>(A.nonZeros());
    auto find = [&](int row, int col) {
      const int* b = A.innerIndexPtr() + A.outerIndexPtr()[col];
      const int* e = A.innerIndexPtr() + A.outerIndexPtr()[col + 1];
      const int* it = std::lower_bound(b, e, row);
      return (it != e && *it == row) ? static_cast<int>(it - A.innerIndexPtr()) : -1;
    };
    const auto& els = m.elements();
    elem_pos.assign(36 * els.size(), -1);
    for (size_t i = 0; i < els.size(); ++i)
      for (int q = 0; q < els[i].k; ++q)
        for (int qc = 0; qc < els[i].k; ++qc)
          elem_pos[36 * i + 6 * q + qc] = find(els[i].v[q], els[i].v[qc]);
    std::vector<int> fidx(3 * static_cast<size_t>(nv), -1);
    for (int d = 0; d < 3; ++d) {
      const auto& fv = m.free_vertices(d);
      const int o = m.free_offset(d);
      for (size_t i = 0; i < fv.size(); ++i)
        fidx[3 * static_cast<size_t>(fv[i]) + d] = o + static_cast<int>(i);
    }
    // The pattern: every (free a, free b) of a vertex pair of A, all 9 coordinate pairs. The
    // values of the first assembly are the source ids, read back to map P's storage.
    std::vector<Eigen::Triplet<double>> t;
    t.reserve(9 * static_cast<size_t>(nnz));
    for (int col = 0; col < A.outerSize(); ++col)
      for (int p = A.outerIndexPtr()[col]; p < A.outerIndexPtr()[col + 1]; ++p) {
        const int row = A.innerIndexPtr()[p];
        for (int d = 0; d < 3; ++d)
          for (int dd = 0; dd < 3; ++dd) {
            const int a = fidx[3 * static_cast<size_t>(row) + d],
                      b = fidx[3 * static_cast<size_t>(col) + dd];
            if (a >= 0 && b >= 0) t.emplace_back(a, b, 9.0 * p + 3 * d + dd);
          }
      }
    P.resize(nf, nf);
    P.setFromTriplets(t.begin(), t.end());
    P.makeCompressed();
    has_factor = false;
    p_src.resize(P.nonZeros());
    for (Eigen::Index k = 0; k < P.nonZeros(); ++k)
      p_src[k] = static_cast<int>(std::lround(P.valuePtr()[k]));
    diag_pos.assign(nf, -1);
    a_diag.resize(nf);
    for (int col = 0; col < nf; ++col)
      for (int k = P.outerIndexPtr()[col]; k < P.outerIndexPtr()[col + 1]; ++k)
        if (P.innerIndexPtr()[k] == col) diag_pos[col] = k;
    for (int v = 0; v < nv; ++v)
      for (int d = 0; d < 3; ++d)
        if (fidx[3 * static_cast<size_t>(v) + d] >= 0)
          a_diag[fidx[3 * static_cast<size_t>(v) + d]] = A.coeff(v, v);
    analyzed = false;
  }
};

EquilibriumJacobianWorkspace::EquilibriumJacobianWorkspace() : impl_(std::make_unique<Impl>()) {}
EquilibriumJacobianWorkspace::~EquilibriumJacobianWorkspace() = default;

namespace {

/// Assembles P = A_ff - sym(K_local)_ff into the workspace's pattern and factors it (the symbolic
/// analysis once per workspace and model). false if CHOLMOD finds P not positive definite.
bool FactorLocalPreconditioner(const Model& model, const EquilibriumLinearization& lin, int threads,
                               EquilibriumJacobianWorkspace::Impl* w, bool project = false) {
  if (w->model != &model) w->Build(model);
  const size_t nnz = static_cast<size_t>(model.A().nonZeros());
  const int nt = threads > 0 ? threads : omp_get_max_threads();
  const auto& els = model.elements();
  // P = sum_e H_e, H_e = wv_e (I - 1/k) (x) I_3 - (K_e + K_e^T) / 2: A is exactly the sum of the
  // first terms (Model), so P = A - sym(K_local). With `project`, each H_e is replaced by
  // V |Lambda| V^T (its eigenvalues' absolute values), which keeps P positive definite where
  // stretched elements make A - sym(K_local) indefinite. On cable_finger this took 93 products
  // and 1.5e-5 accuracy, against 223 and 1.4e-4 with negative eigenvalues set to 0 instead.
  auto assemble = [&](bool project) {
    w->blocks.resize(nt);
    for (auto& b : w->blocks) b.assign(9 * nnz, 0.0);
    lin.ForEachLocalBlock([&](int i, const LocalBlock& Kb, int t) {
      const ModelElement& e = els[i];
      const int k = e.k;
      LocalBlock H = -0.5 * (Kb + Kb.transpose());
      for (int q = 0; q < k; ++q)
        for (int qc = 0; qc < k; ++qc)
          for (int d = 0; d < 3; ++d)
            H(3 * q + d, 3 * qc + d) += e.wv * ((q == qc ? 1.0 : 0.0) - 1.0 / k);
      if (project) {
        Eigen::SelfAdjointEigenSolver<LocalBlock> es(H);
        H = es.eigenvectors() * es.eigenvalues().cwiseAbs().asDiagonal() *
            es.eigenvectors().transpose();
      }
      double* out = w->blocks[t].data();
      for (int q = 0; q < k; ++q)
        for (int qc = 0; qc < k; ++qc) {
          const size_t p =
              static_cast<size_t>(w->elem_pos[36 * static_cast<size_t>(i) + 6 * q + qc]);
          for (int d = 0; d < 3; ++d)
            for (int dd = 0; dd < 3; ++dd) out[9 * p + 3 * d + dd] += H(3 * q + d, 3 * qc + dd);
        }
    });
    for (int t = 1; t < nt; ++t)
      for (size_t j = 0; j < 9 * nnz; ++j) w->blocks[0][j] += w->blocks[t][j];
    const double* B = w->blocks[0].data();
    double* Pv = w->P.valuePtr();
    for (Eigen::Index k = 0; k < w->P.nonZeros(); ++k) Pv[k] = B[w->p_src[k]];
    // A coordinate that no element holds: the inner vertices of a vented chamber (the unloaded
    // side of a signed actuator), whose targets are their current shape (H_e = 0), so H has a
    // zero row and column there and the step leaves them. P takes A's diagonal for them, which
    // keeps it definite without coupling them to anything (finger_manipulator res 8).
    for (size_t j = 0; j < w->diag_pos.size(); ++j) {
      double& pjj = Pv[w->diag_pos[j]];
      if (std::abs(pjj) <= 1e-10 * w->a_diag[j]) pjj = w->a_diag[j];
    }
    if (!w->analyzed) {
      cholmod_common& cc = w->llt.cholmod();
      cc.print = 0;  // silent: "not positive definite" is handled here
      // CHOLMOD tries AMD and METIS (nested dissection) and keeps the ordering with less fill
      // (three_chamber, the bilayer strip: METIS). The analysis is done once per workspace.
      cc.nmethods = 2;
      cc.method[0].ordering = CHOLMOD_AMD;
      cc.method[1].ordering = CHOLMOD_METIS;
      w->llt.analyzePattern(w->P);
      w->analyzed = true;
    }
    w->llt.factorize(w->P);
    ++w->factorizations;
    return w->llt.info() == Eigen::Success;
  };
  if (project) w->project = true;
  bool ok = !w->project && assemble(false);
  if (!ok) {
    w->project = true;  // remembered: later Jacobians of this workspace project at once
    ok = assemble(true);
  }
  w->has_factor = ok;
  w->not_positive_definite = !ok;
  w->stale = false;
  w->fresh_rounds = -1;
  return ok;
}

}  // namespace

int EquilibriumJacobianWorkspace::factorizations() const { return impl_->factorizations; }

bool EquilibriumJacobianWorkspace::Factor(const Model& model, const EquilibriumLinearization& lin,
                                          int threads, bool project) {
  return FactorLocalPreconditioner(model, lin, threads, impl_.get(), project);
}

const LocalPreconditioner* EquilibriumJacobianWorkspace::factor() const {
  return impl_->has_factor ? &impl_->llt : nullptr;
}

bool EquilibriumJacobianWorkspace::projected() const { return impl_->project; }

namespace {

/// Runs the columns' GMRES solves, batching the products of every column still running (all of
/// them together with lockstep, else one column after the other). Returns the number of batched
/// products.
int RunGmres(FreeOperator* op, std::vector<GmresColumn>* cols, bool lockstep) {
  int rounds = 0;
  const int n = static_cast<int>(cols->size());
  for (int first = 0; first < n; first = lockstep ? n : first + 1) {
    const int last = lockstep ? n : first + 1;
    while (true) {
      std::vector<int> active;
      for (int j = first; j < last; ++j)
        if (!(*cols)[j].done()) active.push_back(j);
      if (active.empty()) break;
      Eigen::MatrixXd V((*cols)[active[0]].Request().size(), active.size());
      for (size_t q = 0; q < active.size(); ++q) V.col(q) = (*cols)[active[q]].Request();
      const Eigen::MatrixXd W = op->Precondition(op->Apply(V));
      ++rounds;
      for (size_t q = 0; q < active.size(); ++q) (*cols)[active[q]].Consume(W.col(q));
    }
  }
  return rounds;
}

/// BiCGSTAB for op(y) = rhs, left-preconditioned, from y0: two operator products per iteration
/// and no stored basis. Returns the number of operator products; *rel receives the final
/// preconditioned relative residual (recomputed from scratch at the end).
int BiCgStab(FreeOperator* op, const Eigen::VectorXd& rhs, int max_it, double tol,
             Eigen::VectorXd* y, double* rel) {
  auto pop = [&](const Eigen::VectorXd& v) -> Eigen::VectorXd {
    return op->Precondition(op->Apply(v));
  };
  const int n = static_cast<int>(rhs.size());
  const Eigen::VectorXd b = op->Precondition(rhs);
  const double beta0 = b.norm();
  *rel = 0.0;
  if (!(beta0 > 0.0)) {
    y->setZero(n);
    return 0;
  }
  int total = 0;
  Eigen::VectorXd r = b;
  if (y->squaredNorm() > 0.0) {
    r = b - pop(*y);
    ++total;
  }
  const Eigen::VectorXd r0 = r;
  Eigen::VectorXd p = Eigen::VectorXd::Zero(n), v = Eigen::VectorXd::Zero(n), s(n), t(n);
  double rho = 1.0, alpha = 1.0, omega = 1.0;
  while (total + 2 <= max_it && r.norm() > tol * beta0) {
    const double rho_new = r0.dot(r);
    if (!(std::abs(rho_new) > 0.0)) break;  // breakdown
    const double beta = (rho_new / rho) * (alpha / omega);
    p = r + beta * (p - omega * v);
    v = pop(p);
    ++total;
    const double r0v = r0.dot(v);
    if (!(std::abs(r0v) > 0.0)) break;
    alpha = rho_new / r0v;
    s = r - alpha * v;
    if (s.norm() <= tol * beta0) {
      *y += alpha * p;
      r = s;
      break;
    }
    t = pop(s);
    ++total;
    const double tt = t.squaredNorm();
    if (!(tt > 0.0)) break;
    omega = t.dot(s) / tt;
    *y += alpha * p + omega * s;
    r = s - omega * t;
    rho = rho_new;
    if (!(std::abs(omega) > 0.0)) break;
  }
  *rel = (b - pop(*y)).norm() / beta0;
  ++total;
  return total;
}

/// The message for an invalid call of ComputeEquilibriumJacobian ("" if none): invalid options,
/// positions or actuation of the wrong size or not finite, a column that is no actuator. Sets
/// *columns to columns_in, or every actuator if it is empty.
std::string JacobianInputError(const Model& model, const Eigen::Ref<const Eigen::MatrixX3d>& X,
                               const Eigen::Ref<const Eigen::VectorXd>& c,
                               const std::vector<int>& columns_in,
                               const EquilibriumJacobianOptions& options,
                               std::vector<int>* columns) {
  std::string why;
  if (!options.IsValid(&why)) return why;
  const int nv = model.num_vertices(), na = model.num_actuators();
  if (X.rows() != nv || !X.allFinite() || c.size() != na || !c.allFinite())
    return "ComputeEquilibriumJacobian: expected finite positions (" + std::to_string(nv) +
           " x 3) and actuation (" + std::to_string(na) + ")";
  *columns = columns_in;
  if (columns->empty())
    for (int a = 0; a < na; ++a) columns->push_back(a);
  for (int a : *columns)
    if (a < 0 || a >= na)
      return "ComputeEquilibriumJacobian: column " + std::to_string(a) + " is not an actuator";
  return "";
}

/// The local preconditioner of op: the workspace's factor of an earlier state (if allow_reuse
/// and the options and workspace allow it), else factored now; A_ff if the local one is not
/// positive definite. Records what preconditions in res->preconditioner and adds the time.
/// Returns whether the earlier factor was reused.
bool SetLocalPreconditioner(const Model& model, const EquilibriumLinearization& lin,
                            const EquilibriumJacobianOptions& options, bool allow_reuse,
                            EquilibriumJacobianWorkspace::Impl* ws, FreeOperator* op,
                            EquilibriumJacobianResult* res) {
  const auto tp = std::chrono::steady_clock::now();
  const bool reused = allow_reuse && options.reuse_preconditioner && ws->model == &model &&
                      ws->has_factor && !ws->stale;
  if (reused || FactorLocalPreconditioner(model, lin, options.threads, ws)) {
    op->SetPreconditioner(&ws->llt);
    res->preconditioner =
        std::string(reused ? "local (reused)" : "local") + (ws->project ? ", projected" : "");
  } else {
    op->SetPreconditioner(nullptr);
    res->preconditioner = "A_ff (the local preconditioner is not positive definite)";
  }
  res->preconditioner_time_s += SecondsSince(tp);
  return reused;
}

/// The right-hand sides of the free systems, all columns in one pass: dB/dc_a + (K_fc - A_fc)
/// dx_c/dc_a (#free x #columns). *dXc receives each column's derivative dx_c/dc_a of the
/// prescribed coordinates (#V x 3), *Y0 the initial guesses: zero, or the free coordinates of
/// initial_guess (3 #V x #columns, vertex-major) if it is not null.
Eigen::MatrixXd JacobianRhs(const Model& model, EquilibriumLinearization* lin,
                            const FreeOperator& op, const Eigen::Ref<const Eigen::VectorXd>& c,
                            const std::vector<int>& columns, const Eigen::MatrixXd* initial_guess,
                            std::vector<Eigen::MatrixX3d>* dXc, Eigen::MatrixXd* Y0) {
  const int nv = model.num_vertices(), na = model.num_actuators(), nf = model.num_free_dofs();
  const int nc = static_cast<int>(columns.size());
  dXc->assign(nc, Eigen::MatrixX3d());
  Eigen::MatrixXd dXcb(nv, 3 * nc), dcb = Eigen::MatrixXd::Zero(na, nc), dBb;
  for (int j = 0; j < nc; ++j) {
    (*dXc)[j] = PrescribedDerivative(model, c, columns[j]);
    dXcb.middleCols(3 * j, 3) = (*dXc)[j];
    dcb(columns[j], j) = 1.0;
  }
  lin->ApplyRhsDerivativeBatch(dXcb, dcb, &dBb);
  dBb.noalias() -= model.A() * dXcb;
  Eigen::MatrixXd rhs(nf, nc);
  *Y0 = Eigen::MatrixXd::Zero(nf, nc);
  for (int j = 0; j < nc; ++j) {
    op.Gather(dBb.middleCols(3 * j, 3), rhs.col(j));
    if (initial_guess) {
      Eigen::MatrixX3d G(nv, 3);
      for (int v = 0; v < nv; ++v)
        for (int d = 0; d < 3; ++d) G(v, d) = (*initial_guess)(3 * v + d, j);
      op.Gather(G, Y0->col(j));
    }
  }
  return rhs;
}

/// GMRES for every column from Y0 (RunGmres; lockstep as the options say): the solutions into
/// *Yf, the preconditioned relative residuals into *rels; adds the rounds and each column's
/// products to res. Returns whether every column converged, and the number of rounds.
std::pair<bool, int> SolveGmresColumns(FreeOperator* op, const Eigen::MatrixXd& rhs,
                                       const Eigen::MatrixXd& Y0,
                                       const EquilibriumJacobianOptions& options,
                                       Eigen::MatrixXd* Yf, std::vector<double>* rels,
                                       EquilibriumJacobianResult* res) {
  const int nc = static_cast<int>(rhs.cols());
  const Eigen::MatrixXd B = op->Precondition(rhs);
  std::vector<GmresColumn> cols;
  cols.reserve(nc);
  for (int j = 0; j < nc; ++j)
    cols.emplace_back(B.col(j), Y0.col(j), options.restart, options.max_iterations,
                      options.tolerance);
  const int rounds = RunGmres(op, &cols, options.lockstep);
  res->rounds += rounds;
  bool converged = true;
  for (int j = 0; j < nc; ++j) {
    Yf->col(j) = cols[j].y();
    (*rels)[j] = cols[j].rel();
    res->iterations[j] += cols[j].products();
    converged = converged && Yf->col(j).allFinite() && (*rels)[j] <= options.tolerance;
  }
  return std::make_pair(converged, rounds);
}

/// res->dXdc (3 #V x #columns, vertex-major): each column's prescribed part dXc[j] with its free
/// coordinates from Yf. false, with res->message and an empty dXdc, if a column's solve did not
/// converge.
bool AssembleDxdc(const Model& model, const FreeOperator& op, const std::vector<int>& columns,
                  const std::vector<Eigen::MatrixX3d>& dXc, const Eigen::MatrixXd& Yf,
                  const std::vector<double>& rels, const EquilibriumJacobianOptions& options,
                  EquilibriumJacobianResult* res) {
  const int nv = model.num_vertices(), nc = static_cast<int>(columns.size());
  res->dXdc.setZero(3 * nv, nc);
  for (int j = 0; j < nc; ++j) {
    const int a = columns[j];
    if (!Yf.col(j).allFinite() || !(rels[j] <= options.tolerance)) {
      std::ostringstream s;
      s << "implicit Jacobian: "
        << (options.krylov == KrylovMethod::kBicgstab ? "BiCGSTAB" : "GMRES") << " for actuator '"
        << model.scene().actuators[a].name << "' stopped at relative residual " << rels[j]
        << " after " << res->iterations[j] << " iterations (tolerance " << options.tolerance << ")";
      res->message = s.str();
      res->dXdc.resize(0, 0);
      return false;
    }
    Eigen::MatrixX3d dX = dXc[j];
    op.Scatter(Yf.col(j), dX);
    for (int v = 0; v < nv; ++v)
      for (int d = 0; d < 3; ++d) res->dXdc(3 * v + d, j) = dX(v, d);
  }
  return true;
}

}  // namespace

EquilibriumJacobianResult ComputeEquilibriumJacobian(const Model& model,
                                                     const Eigen::Ref<const Eigen::MatrixX3d>& X,
                                                     const Eigen::Ref<const Eigen::VectorXd>& c,
                                                     const std::vector<int>& columns_in,
                                                     const EquilibriumJacobianOptions& options,
                                                     const Eigen::MatrixXd* initial_guess,
                                                     EquilibriumJacobianWorkspace* workspace) {
  const auto t0 = std::chrono::steady_clock::now();
  const ScopedBlasThreads one_blas_thread(1);  // single-RHS solves between OpenMP loops
  EquilibriumJacobianResult res;
  auto finish = [&]() {
    res.time_s = SecondsSince(t0);
    return res;
  };
  std::vector<int> columns;
  res.message = JacobianInputError(model, X, c, columns_in, options, &columns);
  if (!res.message.empty()) return finish();
  const int nv = model.num_vertices();
  const int nc = static_cast<int>(columns.size());
  const bool use_guess = initial_guess && initial_guess->rows() == 3 * nv &&
                         initial_guess->cols() == nc && initial_guess->allFinite();

  EquilibriumLinearization lin;
  std::string why;
  if (!lin.Setup(model, X, c, &why, options.threads)) {
    res.message = why;
    return finish();
  }
  const int nf = model.num_free_dofs();
  FreeOperator op(model, &lin);
  EquilibriumJacobianWorkspace own;
  if (!workspace) workspace = &own;
  EquilibriumJacobianWorkspace::Impl* ws = workspace->impl_.get();
  res.preconditioner = "A_ff";
  bool reused = false;
  // The local preconditioner: factored now, or the workspace's factor of an earlier state.
  if (options.preconditioner == JacobianPreconditioner::kLocal) {
    if (options.reuse_preconditioner && ws->model == &model && ws->not_positive_definite)
      res.preconditioner = "A_ff (the local preconditioner was not positive definite earlier)";
    else
      reused = SetLocalPreconditioner(model, lin, options, true, ws, &op, &res);
  }

  std::vector<Eigen::MatrixX3d> dXc;
  Eigen::MatrixXd Y0;
  const Eigen::MatrixXd rhs =
      JacobianRhs(model, &lin, op, c, columns, use_guess ? initial_guess : nullptr, &dXc, &Y0);
  Eigen::MatrixXd Yf(nf, nc);
  std::vector<double> rels(nc, 0.0);
  res.iterations.assign(nc, 0);
  if (options.krylov == KrylovMethod::kBicgstab) {
    for (int j = 0; j < nc; ++j) {
      Eigen::VectorXd y = Y0.col(j);
      res.iterations[j] =
          BiCgStab(&op, rhs.col(j), options.max_iterations, options.tolerance, &y, &rels[j]);
      res.rounds += res.iterations[j];
      Yf.col(j) = y;
    }
  } else {
    auto [converged, rounds] = SolveGmresColumns(&op, rhs, Y0, options, &Yf, &rels, &res);
    if (options.preconditioner == JacobianPreconditioner::kLocal &&
        res.preconditioner.rfind("local (reused)", 0) == 0) {
      // A factor of an earlier state that no longer helps: factor now, and retry if it failed.
      const int limit = std::max(2 * ws->fresh_rounds, ws->fresh_rounds + 10);
      if (!converged || rounds > limit) ws->stale = true;
      if (!converged) {
        reused = SetLocalPreconditioner(model, lin, options, false, ws, &op, &res);
        std::tie(converged, rounds) = SolveGmresColumns(&op, rhs, Y0, options, &Yf, &rels, &res);
      }
    }
    if (res.preconditioner.rfind("local", 0) == 0 && !reused) ws->fresh_rounds = rounds;
  }
  // The unpreconditioned residuals, for the report (one batched product).
  const Eigen::MatrixXd HY = op.Apply(Yf);
  for (int j = 0; j < nc; ++j) {
    const double rn = rhs.col(j).norm();
    res.residuals.push_back(rn > 0 ? (HY.col(j) - rhs.col(j)).norm() / rn : 0.0);
  }
  if (!AssembleDxdc(model, op, columns, dXc, Yf, rels, options, &res)) return finish();
  res.ok = true;
  return finish();
}

}  // namespace softkin
