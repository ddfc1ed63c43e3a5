/// \file equilibrium_linearization.cpp
/// EquilibriumLinearization (equilibrium_jacobian.hpp): the derivatives of the element targets,
/// and so of B(X, c), at one equilibrium, applied to blocks of directions; the local stiffness.
/// ComputeEquilibriumJacobian (equilibrium_jacobian.cpp) solves with them.
#include "softkin/solver/sensitivity/equilibrium_jacobian.hpp"

#include "softkin/solver/fk/actuation.hpp"
#include "softkin/solver/fk/rotation.hpp"
#include "softkin/solver/fk/targets.hpp"
#include "softkin/solver/materials/hyperelastic.hpp"

#include <algorithm>
#include <cassert>
#include <cmath>
#include <functional>

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
inline void Gather(const ModelElement& e, const Eigen::Ref<const Eigen::MatrixX3d>& X,
                   ElemRows* D) {
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

/// The data of a hyperelastic body element's target derivative at centred rows D with best
/// rotation R (ElementTarget's hyperelastic branch, targets.cpp, step by step).
void SetupHyperelastic(const ModelElement& e, const ElemRows& D, const Eigen::Matrix3d& R,
                       EquilibriumLinearization::HyperCache* h) {
  const int k = e.k;
  const ElemRows RP = e.rest * R.transpose();  // rows past k are zero
  const Eigen::Matrix3d F = DeformationGradient(e, D);
  const double eps = EquivalentStrain(F);
  const double rho = (*e.curve)(eps);
  h->t = HyperelasticBlendWeight(RP, D, k, rho, e.rest_volume);
  h->floor = h->t != rho;
  h->diff = RP - D;
  h->blend = h->t * RP + (1.0 - h->t) * D;
  h->vol = RowsVolume(h->blend, k);
  h->c = std::cbrt(e.rest_volume / h->vol);
  h->vol_grad = RowsVolumeGradient(h->blend, k);
  // d eps = <G, dF> with dF = dD^T P (P^T P)^-1, so d eps / dD = P (P^T P)^-1 G^T.
  const auto P = e.rest.topRows(k);
  const Eigen::Matrix3d Ginv = (P.transpose() * P).inverse();
  h->drho.setZero();
  h->drho.topRows(k) = e.curve->Slope(eps) * (P * (Ginv * EquivalentStrainGradient(F).transpose()));
}

/// Whether element e's target derivative takes the closed form of ApplyRhsDerivativeBatch: a
/// rigid body (R_omega = 1), or a pneumatic element that is not vented (its ratio r).
inline bool HasClosedFormDerivative(const ModelElement& e, double r) {
  return (e.role == ElementRole::Body && e.r_omega >= 1.0 && !e.curve) ||
         (e.role == ElementRole::Pneumatic && r != kVented);
}

}  // namespace

bool EquilibriumLinearization::Setup(const Model& model,
                                     const Eigen::Ref<const Eigen::MatrixX3d>& X,
                                     const Eigen::Ref<const Eigen::VectorXd>& c, std::string* why,
                                     int threads) {
  model_ = &model;
  threads_ = threads;
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
  if (static_cast<int>(rotated_rest_.size()) != ne) rotated_rest_.resize(ne);
  if (static_cast<int>(rotated_sinv_.size()) != ne) rotated_sinv_.resize(ne);
  const bool any_curve =
      std::any_of(els.begin(), els.end(), [](const ModelElement& e) { return e.curve; });
  if (!any_curve)
    hyper_.clear();
  else if (static_cast<int>(hyper_.size()) != ne)
    hyper_.resize(ne);

  // Groups: current measures and the normalisation of ComputeLocalRatios.
  groups_.assign(model.num_groups(), GroupCache());
  for (int g = 0; g < model.num_groups(); ++g) {
    GroupCache& gc = groups_[g];
    const int a = model.group_actuator(g), side = model.group_side(g);
    gc.vented = model.GroupVented(g, c);
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
    if (HasClosedFormDerivative(e, r)) {
      rotated_rest_[i].setZero();
      rotated_rest_[i].topRows(e.k).noalias() = P * ec.R.transpose();
      rotated_sinv_[i].noalias() = ec.R * ec.Sinv * ec.R.transpose();
    }
    if (e.curve) {
      SetupHyperelastic(e, D, ec.R, &hyper_[i]);
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
  } else if (e.curve) {
    // T = c Bl, Bl = t R P + (1 - t) D (Eq. 3.6-3.7); d(R P) = P dR^T = -P W R^T.
    const HyperCache& h = hyper_[i];
    const Eigen::Matrix3d W = PolarDerivativeW(ec.R, ec.Sinv, dD.transpose() * P);
    const ElemRows dRP = -(P * (W * Rt));
    const ElemRows moved = h.t * dRP + (1.0 - h.t) * dD;  // dBl at a fixed t
    const double dt =
        h.floor ? -h.vol_grad.cwiseProduct(moved).sum() / h.vol_grad.cwiseProduct(h.diff).sum()
                : h.drho.cwiseProduct(dD).sum();
    const ElemRows dBl = moved + dt * h.diff;
    const double dc = -(h.c / 3.0) * h.vol_grad.cwiseProduct(dBl).sum() / h.vol;
    *dT = dc * h.blend + h.c * dBl;
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
          dr = sigma * measure_grad_[i].topRows(e.k).cwiseProduct(dD.topRows(e.k)).sum() /
               e.measure0;
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
        if (Kb(a, b) != 0.0)
          parts[t].emplace_back(3 * e.v[a / 3] + a % 3, 3 * e.v[b / 3] + b % 3, Kb(a, b));
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
  if (weighted_.size() != static_cast<size_t>(ne) * m)
    weighted_.resize(static_cast<size_t>(ne) * m);
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
    if (HasClosedFormDerivative(e, r)) {
      // The closed form of ElementTargetDerivative for these elements. With the rows t_q = R P_q
      // of the rotated rest shape (centred, as P is), R^T dR = [w]_x, and w' = R w:
      //   w' = R (tr(S) I - S)^-1 R^T sum_q t_q x dD_q,   d(R P_q) = w' x t_q,
      // the first since axial(R^T dD^T P) = R^T sum_q t_q x dD_q (the rows need no centring:
      // sum_q t_q = 0). Bodies: dT_q = R_omega w' x t_q; pneumatic (T = q P R^T, q = cbrt(r)):
      // dT_q = dq t_q + q w' x t_q.
      const ElemRows& t = rotated_rest_[i];
      const Eigen::Matrix3d& Sr = rotated_sinv_[i];
      const bool pneumatic = e.role == ElementRole::Pneumatic;
      const double q = pneumatic ? std::cbrt(r) : e.r_omega;
      for (int j = 0; j < m; ++j) {
        Eigen::Vector3d b = Eigen::Vector3d::Zero();
        for (int v = 0; v < e.k; ++v) {
          const Eigen::Vector3d d(dX(e.v[v], 3 * j), dX(e.v[v], 3 * j + 1), dX(e.v[v], 3 * j + 2));
          b += t.row(v).transpose().cross(d);
        }
        const Eigen::Vector3d w = Sr * b;
        const double dq = pneumatic ? q * dratio_[static_cast<size_t>(i) * m + j] / (3.0 * r) : 0.0;
        ElemRows& out = weighted_[static_cast<size_t>(i) * m + j];
        for (int v = 0; v < e.k; ++v) {
          const Eigen::Vector3d tv = t.row(v).transpose();
          out.row(v) = (e.wv * (q * w.cross(tv) + dq * tv)).transpose();
        }
      }
      continue;
    }
    for (int j = 0; j < m; ++j) {
      ElemRows dD, dT;
      gather(e, j, &dD);
      ElementTargetDerivative(i, vented, dD, dratio_[static_cast<size_t>(i) * m + j], Ps, dPs0,
                              &dT);
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

}  // namespace softkin
