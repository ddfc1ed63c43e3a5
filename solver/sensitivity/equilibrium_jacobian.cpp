#include "softkin/solver/sensitivity/equilibrium_jacobian.hpp"

#include "softkin/solver/fk/actuation.hpp"
#include "softkin/solver/fk/rotation.hpp"
#include "softkin/solver/fk/targets.hpp"

#include <Eigen/Eigenvalues>

#include <algorithm>
#include <cassert>
#include <chrono>
#include <cmath>
#include <functional>
#include <sstream>
#include <tuple>

#include <omp.h>

namespace softkin {

namespace {

/// Axial vector a of the skew part Z - Z^T: [a]_x = Z - Z^T.
inline Eigen::Vector3d AxialOfSkewPart(const Eigen::Matrix3d& Z) {
  return Eigen::Vector3d(Z(2, 1) - Z(1, 2), Z(0, 2) - Z(2, 0), Z(1, 0) - Z(0, 1));
}

inline Eigen::Matrix3d Skew(const Eigen::Vector3d& w) {
  Eigen::Matrix3d W;
  W << 0, -w.z(), w.y(), w.z(), 0, -w.x(), -w.y(), w.x(), 0;
  return W;
}

/// Rows of element e from X, centred.
inline void Gather(const ModelElement& e, const Eigen::Ref<const Eigen::MatrixX3d>& X, ElemRows* D) {
  for (int j = 0; j < e.k; ++j) D->row(j) = X.row(e.v[j]);
  CenterRows(*D, e.k);
}

/// Per-element polar-factor data: R = BestRotation(M), Sinv = (tr(S) I - S)^-1 with S = R^T M.
/// Returns false if tr(S) I - S is (numerically) singular.
bool PolarData(const Eigen::Matrix3d& M, Eigen::Matrix3d* R, Eigen::Matrix3d* Sinv) {
  *R = BestRotation(M);
  Eigen::Matrix3d S = R->transpose() * M;
  S = 0.5 * (S + S.transpose()).eval();
  const Eigen::Matrix3d Q = S.trace() * Eigen::Matrix3d::Identity() - S;
  const double det = Q.determinant();
  const double scale = std::max(1e-300, S.norm());
  if (!(std::abs(det) > 1e-12 * scale * scale * scale)) return false;
  *Sinv = Q.inverse();
  return true;
}

/// W = R^T dR = [w]_x for a change dM of M (callers form P dR^T = -P W R^T).
inline Eigen::Matrix3d PolarDerivativeW(const Eigen::Matrix3d& R, const Eigen::Matrix3d& Sinv,
                                        const Eigen::Matrix3d& dM) {
  return Skew(Sinv * AxialOfSkewPart(R.transpose() * dM));
}

}  // namespace

bool EquilibriumJacobianOptions::IsValid(std::string* why) const {
  auto bad = [&](const std::string& m) { if (why) *why = m; return false; };
  if (!(tolerance > 0.0 && tolerance < 1.0)) return bad("implicit.tolerance: expected a number in (0, 1)");
  if (max_iterations < 1) return bad("implicit.max_iterations: expected an integer >= 1");
  if (restart < 1 || restart > 1000) return bad("implicit.restart: expected an integer in [1, 1000]");
  if (threads < 0) return bad("implicit.threads: expected an integer >= 0");
  if (krylov != "gmres" && krylov != "bicgstab")
    return bad("implicit.krylov: expected one of gmres, bicgstab; got '" + krylov + "'");
  if (preconditioner != "A_ff" && preconditioner != "local")
    return bad("implicit.preconditioner: expected one of A_ff, local; got '" + preconditioner + "'");
  return true;
}

std::string EquilibriumJacobianUnsupported(const Model& model) {
  const auto& els = model.elements();
  for (size_t i = 0; i < els.size(); ++i)
    if (els[i].role == ElementRole::Body && els[i].curve)
      return "element " + std::to_string(i) +
             " has a hyperelastic (Mooney-Rivlin) body material, which implicit differentiation "
             "does not support; use the fd or fd-warm Jacobian";
  return "";
}

bool EquilibriumLinearization::Setup(const Model& model, const Eigen::Ref<const Eigen::MatrixX3d>& X,
                                     const Eigen::Ref<const Eigen::VectorXd>& c, std::string* why,
                                     int threads) {
  model_ = &model;
  threads_ = threads;
  const std::string unsupported = EquilibriumJacobianUnsupported(model);
  if (!unsupported.empty()) {
    if (why) *why = unsupported;
    return false;
  }
  X_ = X;
  ComputeLocalRatios(model, X_, c, &ratios_);
  const auto& els = model.elements();
  const int ne = static_cast<int>(els.size());
  cache_.resize(ne);
  measure_.assign(ne, 0.0);
  measure_active_.assign(ne, 0);
  if (static_cast<int>(measure_grad_.size()) != ne) measure_grad_.resize(ne);
  if (static_cast<int>(rows_.size()) != ne) rows_.resize(ne);
  if (static_cast<int>(vol_grad_.size()) != ne) vol_grad_.resize(ne);

  // Groups: current measures and the normalisation of ComputeLocalRatios.
  groups_.assign(model.num_groups(), GroupCache());
  for (int g = 0; g < model.num_groups(); ++g) {
    GroupCache& gc = groups_[g];
    const int a = model.group_actuator(g), side = model.group_side(g);
    gc.vented = side != 0 && !(side * c[a] > 0.0);
    const double M = model.group_rest_measure(g), LR = model.group_offset(g);
    double Md = 0.0;
    for (int i : model.group_elements(g)) {
      ElemRows D;
      Gather(els[i], X_, &D);
      const double m = ActuationMeasure(els[i], D), floor = kMinMeasure * els[i].measure0;
      measure_active_[i] = m > floor;
      measure_[i] = std::max(m, floor);
      measure_grad_[i] = ActuationMeasureGradient(els[i], D);
      Md += measure_[i];
    }
    gc.Md = Md;
    const double rho = model.GroupRatio(g, c);
    const double num = rho * (M + LR) - LR;
    gc.num_active = num > kMinMeasure * M;
    gc.sigma = std::max(num, kMinMeasure * M) / Md;
    // d rho / d c[a] (Actuator::SideRatio): 1 for an unsigned actuator, gain * side on the
    // active side of a signed one.
    const Actuator& act = model.scene().actuators[a];
    gc.drho = side == 0 ? 1.0 : (side * c[a] > 0.0 ? act.gain * side : 0.0);
  }

  // Elements: rotations and polar-derivative data.
  int bad = -1;
  const int nt = threads_ > 0 ? threads_ : omp_get_max_threads();
#pragma omp parallel for schedule(static) num_threads(nt)
  for (int i = 0; i < ne; ++i) {
    const ModelElement& e = els[i];
    ElementCache& ec = cache_[i];
    const double r = ratios_[i];
    if (e.role != ElementRole::Body && r == kVented) continue;
    ElemRows D;
    Gather(e, X_, &D);
    const auto P = e.rest.topRows(e.k);
    Eigen::Matrix3d M;
    if (e.role == ElementRole::Body || e.role == ElementRole::Pneumatic) {
      M = D.topRows(e.k).transpose() * P;
    } else {
      const Eigen::Matrix<double, Eigen::Dynamic, 3, 0, 6, 3> Ps =
          P * ActuationShape(e, r).transpose();
      M = D.topRows(e.k).transpose() * Ps;
    }
    if (!PolarData(M, &ec.R, &ec.Sinv)) {
#pragma omp critical
      bad = std::max(bad, i);
      continue;
    }
    if (e.role != ElementRole::Body || e.r_omega < 1.0) rows_[i] = D;
    if (e.role == ElementRole::Body && e.r_omega < 1.0) {
      const double vd = RowsVolume(D, e.k);
      ec.vol = vd;
      if (vd > 1e-9 * e.rest_volume) {
        const double s = std::cbrt(e.rest_volume / vd);
        ec.s = std::min(s, 10.0);
        ec.s_active = s < 10.0;
        if (ec.s_active) vol_grad_[i] = RowsVolumeGradient(D, e.k);
      } else {
        ec.s = 1.0;  // as ElementTarget: a collapsed or inverted element keeps s = 1
        ec.s_active = false;
      }
    }
  }
  if (bad >= 0) {
    if (why)
      *why = "element " + std::to_string(bad) +
             " is degenerate at this state (flat or inverted: its best rotation is not "
             "differentiable); implicit differentiation is not defined here";
    return false;
  }
  return true;
}

void EquilibriumLinearization::ApplyRhsDerivative(const Eigen::Ref<const Eigen::MatrixX3d>& dX,
                                                  const Eigen::Ref<const Eigen::VectorXd>& dc,
                                                  Eigen::MatrixX3d* dB) {
  const Eigen::MatrixXd dXm = dX, dcm = dc;
  Eigen::MatrixXd out;
  ApplyRhsDerivativeBatch(dXm, dcm, &out);
  *dB = out;
}

void EquilibriumLinearization::ElementTargetDerivative(int i, bool vented, const ElemRows& dD,
                                                       double dr, const ElemRows& Ps,
                                                       const ElemRows& dPs0, ElemRows* dT) const {
  const ModelElement& e = model_->elements()[i];
  const ElementCache& ec = cache_[i];
  const double r = ratios_[i];
  const ElemRows& P = e.rest;
  const Eigen::Matrix3d Rt = ec.R.transpose();
  if (vented) {
    *dT = dD;  // vented: T = D
  } else if (e.role == ElementRole::Body) {
    const Eigen::Matrix3d dM = dD.transpose() * P;
    const Eigen::Matrix3d W = PolarDerivativeW(ec.R, ec.Sinv, dM);
    // T = r_w P R^T + (1 - r_w) s D; d(P R^T) = P dR^T = -P W R^T.
    const Eigen::Matrix3d WRt = W * Rt;
    dT->noalias() = (-e.r_omega) * (P * WRt);
    if (e.r_omega < 1.0) {
      const ElemRows& D = rows_[i];
      double ds = 0.0;
      if (ec.s_active) ds = -(ec.s / 3.0) * vol_grad_[i].cwiseProduct(dD).sum() / ec.vol;
      *dT += (1.0 - e.r_omega) * (ds * D + ec.s * dD);
    }
  } else if (e.role == ElementRole::Pneumatic) {
    // T = q P R^T, q = cbrt(r).
    const double q = std::cbrt(r), dq = q * dr / (3.0 * r);
    const Eigen::Matrix3d dM = dD.transpose() * P;
    const Eigen::Matrix3d W = PolarDerivativeW(ec.R, ec.Sinv, dM);
    const Eigen::Matrix3d G = dq * Rt - q * (W * Rt);
    dT->noalias() = P * G;
  } else {
    const ElemRows& D = rows_[i];
    const ElemRows dPs = dr * dPs0;
    const Eigen::Matrix3d dM = dD.transpose() * Ps + D.transpose() * dPs;
    const Eigen::Matrix3d W = PolarDerivativeW(ec.R, ec.Sinv, dM);
    dT->noalias() = dPs * Rt - Ps * (W * Rt);
  }
}

void EquilibriumLinearization::ForEachLocalBlock(
    const std::function<void(int element, const LocalBlock& block, int thread)>& f) const {
  const Model& model = *model_;
  const auto& els = model.elements();
  const int ne = static_cast<int>(els.size());
  const int nt = threads_ > 0 ? threads_ : omp_get_max_threads();
#pragma omp parallel for schedule(static) num_threads(nt)
  for (int i = 0; i < ne; ++i) {
    const ModelElement& e = els[i];
    const double r = ratios_[i];
    const bool vented = e.role != ElementRole::Body && r == kVented;
    ElemRows Ps, dPs0;
    if (!vented && (e.role == ElementRole::Cable || e.role == ElementRole::Dea)) {
      Ps.noalias() = e.rest * ActuationShape(e, r).transpose();
      dPs0.noalias() = e.rest * ActuationShapeDerivative(e, r).transpose();
    }
    // The element's own share of its ratio's derivative (the group's d sigma is left out).
    double sigma = 0.0;
    if (e.role != ElementRole::Body && !vented && e.group >= 0 && !groups_[e.group].vented)
      sigma = groups_[e.group].sigma;
    LocalBlock Kb = LocalBlock::Zero(3 * e.k, 3 * e.k);
    for (int qc = 0; qc < e.k; ++qc)
      for (int dc = 0; dc < 3; ++dc) {
        ElemRows dD = ElemRows::Zero(), dT;
        dD(qc, dc) = 1.0;
        CenterRows(dD, e.k);
        double dr = 0.0;
        if (sigma > 0.0 && measure_active_[i])
          dr = sigma * measure_grad_[i].topRows(e.k).cwiseProduct(dD.topRows(e.k)).sum() / e.measure0;
        ElementTargetDerivative(i, vented, dD, dr, Ps, dPs0, &dT);
        for (int q = 0; q < e.k; ++q)
          for (int d = 0; d < 3; ++d) Kb(3 * q + d, 3 * qc + dc) = e.wv * dT(q, d);
      }
    f(i, Kb, omp_get_thread_num());
  }
}

Eigen::SparseMatrix<double> EquilibriumLinearization::LocalStiffness() const {
  const int nt = threads_ > 0 ? threads_ : omp_get_max_threads();
  std::vector<std::vector<Eigen::Triplet<double>>> parts(nt);
  const auto& els = model_->elements();
  ForEachLocalBlock([&](int i, const LocalBlock& Kb, int t) {
    const ModelElement& e = els[i];
    for (int a = 0; a < 3 * e.k; ++a)
      for (int b = 0; b < 3 * e.k; ++b)
        if (Kb(a, b) != 0.0) parts[t].emplace_back(3 * e.v[a / 3] + a % 3, 3 * e.v[b / 3] + b % 3, Kb(a, b));
  });
  std::vector<Eigen::Triplet<double>> all;
  for (const auto& p : parts) all.insert(all.end(), p.begin(), p.end());
  const int nv = model_->num_vertices();
  Eigen::SparseMatrix<double> K(3 * nv, 3 * nv);
  K.setFromTriplets(all.begin(), all.end());
  return K;
}

void EquilibriumLinearization::ApplyRhsDerivativeBatch(const Eigen::Ref<const Eigen::MatrixXd>& dX,
                                                       const Eigen::Ref<const Eigen::MatrixXd>& dc,
                                                       Eigen::MatrixXd* dB) {
  const Model& model = *model_;
  const auto& els = model.elements();
  const int ne = static_cast<int>(els.size());
  const int nv = model.num_vertices();
  const int m = static_cast<int>(dc.cols());
  assert(dX.rows() == nv && dX.cols() == 3 * m && dc.rows() == model.num_actuators());
  dratio_.assign(static_cast<size_t>(ne) * m, 0.0);
  if (weighted_.size() != static_cast<size_t>(ne) * m) weighted_.resize(static_cast<size_t>(ne) * m);
  // Rows of element e in direction j, centred.
  auto gather = [&](const ModelElement& e, int j, ElemRows* D) {
    for (int q = 0; q < e.k; ++q)
      for (int d = 0; d < 3; ++d) (*D)(q, d) = dX(e.v[q], 3 * j + d);
    CenterRows(*D, e.k);
  };

  // Pass 1: ratio derivatives, group by group (the rank-one coupling through sum_j m_j).
  for (int g = 0; g < model.num_groups(); ++g) {
    const GroupCache& gc = groups_[g];
    const auto& ids = model.group_elements(g);
    if (gc.vented) continue;  // dratio_ stays 0
    const double M = model.group_rest_measure(g), LR = model.group_offset(g);
    for (int j = 0; j < m; ++j) {
      double dMd = 0.0;
      for (int i : ids) {
        double dm = 0.0;
        if (measure_active_[i]) {
          ElemRows dD;
          gather(els[i], j, &dD);
          dm = measure_grad_[i].topRows(els[i].k).cwiseProduct(dD.topRows(els[i].k)).sum();
        }
        dratio_[static_cast<size_t>(i) * m + j] = dm;  // holds dm_i until dsigma is known
        dMd += dm;
      }
      const double drho = gc.drho * dc(model.group_actuator(g), j);
      const double dsigma =
          -gc.sigma * dMd / gc.Md + (gc.num_active ? (M + LR) * drho / gc.Md : 0.0);
      for (int i : ids) {
        double& r = dratio_[static_cast<size_t>(i) * m + j];
        r = (gc.sigma * r + measure_[i] * dsigma) / els[i].measure0;
      }
    }
  }

  // Pass 2: per-element target derivatives dT (already in the current frame, centred), every
  // direction while the element's cached data is at hand. Products use the fixed 6 x 3 row
  // blocks: rows k..5 of the rest and centred rows are zero.
  const int nt = threads_ > 0 ? threads_ : omp_get_max_threads();
#pragma omp parallel for schedule(static) num_threads(nt)
  for (int i = 0; i < ne; ++i) {
    const ModelElement& e = els[i];
    const double r = ratios_[i];
    const ElemRows& P = e.rest;
    const bool vented = e.role != ElementRole::Body && r == kVented;
    // Cable / DEA: T = Ps R^T, Ps = P S(r)^T, R = polar(D^T Ps).
    ElemRows Ps, dPs0;
    if (!vented && (e.role == ElementRole::Cable || e.role == ElementRole::Dea)) {
      Ps.noalias() = P * ActuationShape(e, r).transpose();
      dPs0.noalias() = P * ActuationShapeDerivative(e, r).transpose();
    }
    for (int j = 0; j < m; ++j) {
      ElemRows dD, dT;
      gather(e, j, &dD);
      ElementTargetDerivative(i, vented, dD, dratio_[static_cast<size_t>(i) * m + j], Ps, dPs0, &dT);
      weighted_[static_cast<size_t>(i) * m + j] = e.wv * dT;
    }
  }
  // Gather sum_i w_i Vol_i S_i^T dT_i per vertex and direction (AssembleRhs, batched).
  dB->resize(nv, 3 * m);
  const auto& off = model.incidence_offset();
  const auto& inc = model.incidence();
#pragma omp parallel for schedule(static) num_threads(nt)
  for (int v = 0; v < nv; ++v) {
    for (int j = 0; j < m; ++j) {
      Eigen::RowVector3d sum = Eigen::RowVector3d::Zero();
      for (int q = off[v]; q < off[v + 1]; ++q)
        sum += weighted_[static_cast<size_t>(inc[q] / 6) * m + j].row(inc[q] % 6);
      for (int d = 0; d < 3; ++d) (*dB)(v, 3 * j + d) = sum[d];
    }
  }
}

Eigen::MatrixX3d PrescribedDerivative(const Model& model, const Eigen::Ref<const Eigen::VectorXd>& c,
                                      int a) {
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

namespace {

/// The operator of the linear solve on the free coordinates, applied to a block of vectors:
/// Apply(Y) = H Y = A_ff Y - (K Y)_f (Y: #free x k, every other coordinate zero), and
/// Precondition(V) = A_ff^-1 V with the model's CHOLMOD factors, all columns in one solve.
class FreeOperator {
 public:
  FreeOperator(const Model& model, EquilibriumLinearization* lin)
      : model_(model), lin_(lin), zero_c_(Eigen::MatrixXd::Zero(model.num_actuators(), 1)) {}

  /// Free coordinates x (#free) of the #V x 3 block X.
  void Gather(const Eigen::Ref<const Eigen::MatrixXd>& X, Eigen::Ref<Eigen::VectorXd> x) const {
    for (int d = 0; d < 3; ++d) {
      const auto& fv = model_.free_vertices(d);
      const int o = model_.free_offset(d);
      for (size_t i = 0; i < fv.size(); ++i) x[o + static_cast<int>(i)] = X(fv[i], d);
    }
  }
  /// Writes x (#free) into the free coordinates of the #V x 3 block X.
  void Scatter(const Eigen::Ref<const Eigen::VectorXd>& x, Eigen::Ref<Eigen::MatrixXd> X) const {
    for (int d = 0; d < 3; ++d) {
      const auto& fv = model_.free_vertices(d);
      const int o = model_.free_offset(d);
      for (size_t i = 0; i < fv.size(); ++i) X(fv[i], d) = x[o + static_cast<int>(i)];
    }
  }

  Eigen::MatrixXd Apply(const Eigen::MatrixXd& Y) {
    const int k = static_cast<int>(Y.cols()), nv = model_.num_vertices();
    Yx_.setZero(nv, 3 * k);
    for (int j = 0; j < k; ++j) Scatter(Y.col(j), Yx_.middleCols(3 * j, 3));
    if (zero_c_.cols() != k) zero_c_.setZero(model_.num_actuators(), k);
    lin_->ApplyRhsDerivativeBatch(Yx_, zero_c_, &dB_);
    AY_.noalias() = model_.A() * Yx_;
    AY_ -= dB_;
    Eigen::MatrixXd out(Y.rows(), k);
    for (int j = 0; j < k; ++j) Gather(AY_.middleCols(3 * j, 3), out.col(j));
    return out;
  }

  /// Precondition with this factor of an approximation of H (free layout) instead of A_ff.
  void SetPreconditioner(const LocalPreconditioner* p) { pre_ = p; }

  Eigen::MatrixXd Precondition(const Eigen::MatrixXd& V) const {
    const int k = static_cast<int>(V.cols());
    if (pre_) return pre_->solve(V);
    Eigen::MatrixXd out(V.rows(), k);
    if (model_.factor_of_axis(0) == model_.factor_of_axis(1) &&
        model_.factor_of_axis(1) == model_.factor_of_axis(2)) {
      // One factor: every axis of every column is one right-hand side of one solve.
      const int n0 = model_.free_offset(1);
      Eigen::Map<const Eigen::MatrixXd> B(V.data(), n0, 3 * k);
      Eigen::Map<Eigen::MatrixXd> Y(out.data(), n0, 3 * k);
      Y = model_.factorization(model_.factor_of_axis(0)).solve(B);
      return out;
    }
    for (int d = 0; d < 3; ++d) {
      const int o = model_.free_offset(d), n = model_.free_offset(d + 1) - o;
      out.middleRows(o, n) =
          model_.factorization(model_.factor_of_axis(d)).solve(V.middleRows(o, n).eval());
    }
    return out;
  }

 private:
  const Model& model_;
  EquilibriumLinearization* lin_;
  const LocalPreconditioner* pre_ = nullptr;
  Eigen::MatrixXd zero_c_, Yx_, dB_, AY_;
};

}  // namespace

/// What the "local" preconditioner keeps between Jacobians of one model: the pattern of
/// P = A_ff - sym(K_local)_ff in the free layout of FreeOperator (axis-major), where each of its
/// values comes from (an entry of A's pattern, d, d'), and CHOLMOD's symbolic analysis.
struct EquilibriumJacobianWorkspace::Impl {
  const Model* model = nullptr;
  std::vector<int> elem_pos;     ///< element i, local (q, qc): A value index of (v_q, v_qc); 36 per element
  Eigen::SparseMatrix<double> P; ///< free-layout pattern and values
  std::vector<int> p_src;        ///< per P value: 9 * (A entry) + 3 d + d'
  LocalPreconditioner llt;
  bool analyzed = false;
  bool has_factor = false;  ///< llt holds a numeric factor (of some earlier state)
  bool stale = false;       ///< the last solve with a reused factor took too many rounds
  /// The last factorisation failed (P indefinite, e.g. cable_finger's slack cables); with
  /// reuse on, this workspace stops trying and preconditions by A_ff.
  bool not_positive_definite = false;
  /// A_ff - sym(K_local) was indefinite once: assemble the per-element PSD projection directly.
  bool project = false;
  int fresh_rounds = -1;    ///< GMRES rounds of the first solve after the last factorisation
  std::vector<std::vector<double>> blocks;  ///< per thread: 9 values per A entry (K_local)
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
        for (int qc = 0; qc < els[i].k; ++qc) elem_pos[36 * i + 6 * q + qc] = find(els[i].v[q], els[i].v[qc]);
    std::vector<int> fidx(3 * static_cast<size_t>(nv), -1);
    for (int d = 0; d < 3; ++d) {
      const auto& fv = m.free_vertices(d);
      const int o = m.free_offset(d);
      for (size_t i = 0; i < fv.size(); ++i) fidx[3 * static_cast<size_t>(fv[i]) + d] = o + static_cast<int>(i);
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
            const int a = fidx[3 * static_cast<size_t>(row) + d], b = fidx[3 * static_cast<size_t>(col) + dd];
            if (a >= 0 && b >= 0) t.emplace_back(a, b, 9.0 * p + 3 * d + dd);
          }
      }
    P.resize(nf, nf);
    P.setFromTriplets(t.begin(), t.end());
    P.makeCompressed();
    has_factor = false;
    p_src.resize(P.nonZeros());
    for (Eigen::Index k = 0; k < P.nonZeros(); ++k) p_src[k] = static_cast<int>(std::lround(P.valuePtr()[k]));
    analyzed = false;
  }
};

EquilibriumJacobianWorkspace::EquilibriumJacobianWorkspace() : impl_(std::make_unique<Impl>()) {}
EquilibriumJacobianWorkspace::~EquilibriumJacobianWorkspace() = default;
int EquilibriumJacobianWorkspace::factorizations() const { return impl_->factorizations; }

namespace {

/// Assembles P = A_ff - sym(K_local)_ff into the workspace's pattern and factors it (the symbolic
/// analysis once per workspace and model). false if CHOLMOD finds P not positive definite.
bool FactorLocalPreconditioner(const Model& model, const EquilibriumLinearization& lin, int threads,
                               EquilibriumJacobianWorkspace::Impl* w) {
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
          for (int d = 0; d < 3; ++d) H(3 * q + d, 3 * qc + d) += e.wv * ((q == qc ? 1.0 : 0.0) - 1.0 / k);
      if (project) {
        Eigen::SelfAdjointEigenSolver<LocalBlock> es(H);
        H = es.eigenvectors() * es.eigenvalues().cwiseAbs().asDiagonal() * es.eigenvectors().transpose();
      }
      double* out = w->blocks[t].data();
      for (int q = 0; q < k; ++q)
        for (int qc = 0; qc < k; ++qc) {
          const size_t p = static_cast<size_t>(w->elem_pos[36 * static_cast<size_t>(i) + 6 * q + qc]);
          for (int d = 0; d < 3; ++d)
            for (int dd = 0; dd < 3; ++dd) out[9 * p + 3 * d + dd] += H(3 * q + d, 3 * qc + dd);
        }
    });
    for (int t = 1; t < nt; ++t)
      for (size_t j = 0; j < 9 * nnz; ++j) w->blocks[0][j] += w->blocks[t][j];
    const double* B = w->blocks[0].data();
    double* Pv = w->P.valuePtr();
    for (Eigen::Index k = 0; k < w->P.nonZeros(); ++k) Pv[k] = B[w->p_src[k]];
    if (!w->analyzed) {
      w->llt.cholmod().print = 0;  // silent: "not positive definite" is handled here
      w->llt.analyzePattern(w->P);
      w->analyzed = true;
    }
    w->llt.factorize(w->P);
    ++w->factorizations;
    return w->llt.info() == Eigen::Success;
  };
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

/// GMRES state of one column (left-preconditioned, restarted, from a given start), advanced one
/// operator product at a time so that several columns can share batched products. The basis is
/// orthogonalised by classical Gram-Schmidt with one re-orthogonalisation (CGS2: as stable as
/// modified Gram-Schmidt, with matrix-vector products).
class GmresColumn {
 public:
  /// b = prec(rhs) (#free), y0 the start (#free), restart/max_it/tol as the options.
  GmresColumn(Eigen::VectorXd b, Eigen::VectorXd y0, int restart, int max_it, double tol)
      : b_(std::move(b)), y_(std::move(y0)), m_(std::max(1, std::min(restart, max_it))),
        max_it_(max_it), tol_(tol) {
    beta0_ = b_.norm();
    if (!(beta0_ > 0.0)) {
      done_ = true;  // rhs = 0: y = 0 exactly
      y_.setZero();
      rel_ = 0.0;
      return;
    }
    if (y_.squaredNorm() > 0.0) {
      want_residual_ = true;  // the start's residual costs a product
    } else {
      StartCycle(b_);
    }
  }

  bool done() const { return done_; }
  int products() const { return products_; }
  double rel() const { return rel_; }
  const Eigen::VectorXd& y() const { return y_; }
  /// The vector the next product is applied to.
  const Eigen::VectorXd& Request() {
    if (want_residual_) return y_;
    next_ = V_.col(j_);
    return next_;
  }
  /// Feeds w = prec(op(Request())).
  void Consume(const Eigen::VectorXd& w) {
    ++products_;
    if (want_residual_) {
      want_residual_ = false;
      StartCycle(b_ - w);
      return;
    }
    const int j = j_;
    // CGS2 against the j + 1 basis vectors.
    Eigen::VectorXd v = w;
    Eigen::VectorXd h = V_.leftCols(j + 1).transpose() * v;
    v.noalias() -= V_.leftCols(j + 1) * h;
    const Eigen::VectorXd h2 = V_.leftCols(j + 1).transpose() * v;
    v.noalias() -= V_.leftCols(j + 1) * h2;
    h += h2;
    const double hn = v.norm();
    Hh_.col(j).head(j + 1) = h;
    Hh_(j + 1, j) = hn;
    const bool breakdown = !(hn > 1e-14 * w.norm());
    if (!breakdown) {
      if (V_.cols() < j + 2) Grow(j + 2);
      V_.col(j + 1) = v / hn;
    }
    for (int i = 0; i < j; ++i) {  // previous Givens rotations
      const double t = cs_(i) * Hh_(i, j) + sn_(i) * Hh_(i + 1, j);
      Hh_(i + 1, j) = -sn_(i) * Hh_(i, j) + cs_(i) * Hh_(i + 1, j);
      Hh_(i, j) = t;
    }
    const double den = std::hypot(Hh_(j, j), Hh_(j + 1, j));
    cs_(j) = den > 0.0 ? Hh_(j, j) / den : 1.0;
    sn_(j) = den > 0.0 ? Hh_(j + 1, j) / den : 0.0;
    Hh_(j, j) = den;
    Hh_(j + 1, j) = 0.0;
    g_(j + 1) = -sn_(j) * g_(j);
    g_(j) = cs_(j) * g_(j);
    j_ = j + 1;
    const bool end = std::abs(g_(j + 1)) <= tol_ * beta0_ || breakdown || !(den > 0.0) ||
                     j_ >= m_ || products_ >= max_it_;
    if (!end) return;
    const Eigen::VectorXd z =
        Hh_.topLeftCorner(j_, j_).triangularView<Eigen::Upper>().solve(g_.head(j_));
    y_.noalias() += V_.leftCols(j_) * z;
    if (!y_.allFinite()) {
      done_ = true;
      rel_ = std::numeric_limits<double>::infinity();
      return;
    }
    if (products_ >= max_it_) {
      // No budget for the true residual: report the estimate of the cycle.
      rel_ = std::abs(g_(j_)) / beta0_;
      done_ = true;
      return;
    }
    want_residual_ = true;  // recompute the residual from scratch (next product)
  }

 private:
  void Grow(int cols) {
    const int n = static_cast<int>(b_.size());
    const int want = std::min(m_ + 1, std::max(cols, 2 * static_cast<int>(V_.cols())));
    V_.conservativeResize(n, want);
  }
  void StartCycle(const Eigen::VectorXd& r) {
    const double beta = r.norm();
    rel_ = beta / beta0_;
    if (rel_ <= tol_ || products_ >= max_it_ || !(beta > 0.0)) {
      done_ = true;
      return;
    }
    if (V_.cols() < 1) Grow(16);
    V_.col(0) = r / beta;
    Hh_.setZero(m_ + 1, m_);
    g_.setZero(m_ + 1);
    g_(0) = beta;
    cs_.setZero(m_);
    sn_.setZero(m_);
    j_ = 0;
  }

  Eigen::VectorXd b_, y_, next_;
  int m_, max_it_;
  double tol_, beta0_ = 0.0, rel_ = 1.0;
  Eigen::MatrixXd V_, Hh_;
  Eigen::VectorXd g_, cs_, sn_;
  int j_ = 0, products_ = 0;
  bool done_ = false, want_residual_ = false;
};

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

}  // namespace

EquilibriumJacobianResult ComputeEquilibriumJacobian(const Model& model,
                                                     const Eigen::Ref<const Eigen::MatrixX3d>& X,
                                                     const Eigen::Ref<const Eigen::VectorXd>& c,
                                                     const std::vector<int>& columns_in,
                                                     const EquilibriumJacobianOptions& options,
                                                     const Eigen::MatrixXd* initial_guess,
                                                     EquilibriumJacobianWorkspace* workspace) {
  const auto t0 = std::chrono::steady_clock::now();
  EquilibriumJacobianResult res;
  auto finish = [&]() {
    res.time_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    return res;
  };
  std::string why;
  if (!options.IsValid(&why)) {
    res.message = why;
    return finish();
  }
  const int nv = model.num_vertices(), na = model.num_actuators();
  if (X.rows() != nv || !X.allFinite() || c.size() != na || !c.allFinite()) {
    res.message = "ComputeEquilibriumJacobian: expected finite positions (" + std::to_string(nv) +
                  " x 3) and actuation (" + std::to_string(na) + ")";
    return finish();
  }
  std::vector<int> columns = columns_in;
  if (columns.empty())
    for (int a = 0; a < na; ++a) columns.push_back(a);
  for (int a : columns)
    if (a < 0 || a >= na) {
      res.message = "ComputeEquilibriumJacobian: column " + std::to_string(a) + " is not an actuator";
      return finish();
    }
  const int nc = static_cast<int>(columns.size());
  const bool use_guess = initial_guess && initial_guess->rows() == 3 * nv &&
                         initial_guess->cols() == nc && initial_guess->allFinite();

  EquilibriumLinearization lin;
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
  auto set_local = [&](bool allow_reuse) {
    const auto tp = std::chrono::steady_clock::now();
    reused = allow_reuse && options.reuse_preconditioner && ws->model == &model && ws->has_factor &&
             !ws->stale;
    if (reused || FactorLocalPreconditioner(model, lin, options.threads, ws)) {
      op.SetPreconditioner(&ws->llt);
      res.preconditioner = std::string(reused ? "local (reused)" : "local") +
                           (ws->project ? ", projected" : "");
    } else {
      op.SetPreconditioner(nullptr);
      res.preconditioner = "A_ff (the local preconditioner is not positive definite)";
    }
    res.preconditioner_time_s +=
        std::chrono::duration<double>(std::chrono::steady_clock::now() - tp).count();
  };
  if (options.preconditioner == "local") {
    if (options.reuse_preconditioner && ws->model == &model && ws->not_positive_definite)
      res.preconditioner = "A_ff (the local preconditioner was not positive definite earlier)";
    else
      set_local(true);
  }

  // Right-hand sides, all columns in one pass: dB/dc_a + (K_fc - A_fc) dx_c/dc_a.
  std::vector<Eigen::MatrixX3d> dXc(nc);
  Eigen::MatrixXd dXcb(nv, 3 * nc), dcb = Eigen::MatrixXd::Zero(na, nc), dBb;
  for (int j = 0; j < nc; ++j) {
    dXc[j] = PrescribedDerivative(model, c, columns[j]);
    dXcb.middleCols(3 * j, 3) = dXc[j];
    dcb(columns[j], j) = 1.0;
  }
  lin.ApplyRhsDerivativeBatch(dXcb, dcb, &dBb);
  dBb.noalias() -= model.A() * dXcb;
  Eigen::MatrixXd rhs(nf, nc), Y0 = Eigen::MatrixXd::Zero(nf, nc), Yf(nf, nc);
  for (int j = 0; j < nc; ++j) {
    op.Gather(dBb.middleCols(3 * j, 3), rhs.col(j));
    if (use_guess) {
      Eigen::MatrixX3d G(nv, 3);
      for (int v = 0; v < nv; ++v)
        for (int d = 0; d < 3; ++d) G(v, d) = (*initial_guess)(3 * v + d, j);
      op.Gather(G, Y0.col(j));
    }
  }

  std::vector<double> rels(nc, 0.0);
  res.iterations.assign(nc, 0);
  if (options.krylov == "bicgstab") {
    for (int j = 0; j < nc; ++j) {
      Eigen::VectorXd y = Y0.col(j);
      res.iterations[j] =
          BiCgStab(&op, rhs.col(j), options.max_iterations, options.tolerance, &y, &rels[j]);
      res.rounds += res.iterations[j];
      Yf.col(j) = y;
    }
  } else {
    auto run = [&]() {
      const Eigen::MatrixXd B = op.Precondition(rhs);
      std::vector<GmresColumn> cols;
      cols.reserve(nc);
      for (int j = 0; j < nc; ++j)
        cols.emplace_back(B.col(j), Y0.col(j), options.restart, options.max_iterations,
                          options.tolerance);
      const int rounds = RunGmres(&op, &cols, options.lockstep);
      res.rounds += rounds;
      bool converged = true;
      for (int j = 0; j < nc; ++j) {
        Yf.col(j) = cols[j].y();
        rels[j] = cols[j].rel();
        res.iterations[j] += cols[j].products();
        converged = converged && Yf.col(j).allFinite() && rels[j] <= options.tolerance;
      }
      return std::make_pair(converged, rounds);
    };
    auto [converged, rounds] = run();
    if (options.preconditioner == "local" && res.preconditioner.rfind("local (reused)", 0) == 0) {
      // A factor of an earlier state that no longer helps: factor now, and retry if it failed.
      const int limit = std::max(2 * ws->fresh_rounds, ws->fresh_rounds + 10);
      if (!converged || rounds > limit) ws->stale = true;
      if (!converged) {
        set_local(false);
        std::tie(converged, rounds) = run();
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
  res.dXdc.setZero(3 * nv, nc);
  for (int j = 0; j < nc; ++j) {
    const int a = columns[j];
    if (!Yf.col(j).allFinite() || !(rels[j] <= options.tolerance)) {
      std::ostringstream s;
      s << "implicit Jacobian: " << (options.krylov == "bicgstab" ? "BiCGSTAB" : "GMRES")
        << " for actuator '" << model.scene().actuators[a].name
        << "' stopped at relative residual " << rels[j] << " after " << res.iterations[j]
        << " iterations (tolerance " << options.tolerance << ")";
      res.message = s.str();
      res.dXdc.resize(0, 0);
      return finish();
    }
    Eigen::MatrixX3d dX = dXc[j];
    op.Scatter(Yf.col(j), dX);
    for (int v = 0; v < nv; ++v)
      for (int d = 0; d < 3; ++d) res.dXdc(3 * v + d, j) = dX(v, d);
  }
  res.ok = true;
  return finish();
}

}  // namespace softkin
