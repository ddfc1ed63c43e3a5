#include "solver/equilibrium_jacobian.hpp"

#include "solver/actuation.hpp"
#include "solver/rotation.hpp"
#include "solver/targets.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <sstream>

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
  dratio_.assign(ne, 0.0);
  if (static_cast<int>(weighted_.size()) != ne) weighted_.resize(ne);

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
    if (e.role == ElementRole::Body && e.r_omega < 1.0) {
      const double vd = RowsVolume(D, e.k);
      ec.vol = vd;
      if (vd > 1e-9 * e.rest_volume) {
        const double s = std::cbrt(e.rest_volume / vd);
        ec.s = std::min(s, 10.0);
        ec.s_active = s < 10.0;
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
  const Model& model = *model_;
  const auto& els = model.elements();
  const int ne = static_cast<int>(els.size());

  // Pass 1: ratio derivatives, group by group (the rank-one coupling through sum_j m_j).
  for (int g = 0; g < model.num_groups(); ++g) {
    const GroupCache& gc = groups_[g];
    const auto& ids = model.group_elements(g);
    if (gc.vented) {
      for (int i : ids) dratio_[i] = 0.0;
      continue;
    }
    double dMd = 0.0;
    for (int i : ids) {
      double dm = 0.0;
      if (measure_active_[i]) {
        ElemRows dD;
        Gather(els[i], dX, &dD);
        dm = measure_grad_[i].topRows(els[i].k).cwiseProduct(dD.topRows(els[i].k)).sum();
      }
      dratio_[i] = dm;  // holds dm_i until the group's dsigma is known
      dMd += dm;
    }
    const double M = model.group_rest_measure(g), LR = model.group_offset(g);
    const double drho = gc.drho * dc[model.group_actuator(g)];
    const double dsigma = -gc.sigma * dMd / gc.Md + (gc.num_active ? (M + LR) * drho / gc.Md : 0.0);
    for (int i : ids)
      dratio_[i] = (gc.sigma * dratio_[i] + measure_[i] * dsigma) / els[i].measure0;
  }

  // Pass 2: per-element target derivatives dT (already in the current frame, centred). Products
  // use the fixed 6 x 3 row blocks: rows k..5 of the rest and centred rows are zero, so the
  // fixed-size kernels give the same result without dynamic-size overhead.
  const int nt = threads_ > 0 ? threads_ : omp_get_max_threads();
#pragma omp parallel for schedule(static) num_threads(nt)
  for (int i = 0; i < ne; ++i) {
    const ModelElement& e = els[i];
    const ElementCache& ec = cache_[i];
    const int k = e.k;
    const double r = ratios_[i];
    ElemRows dD, dT;
    Gather(e, dX, &dD);
    const ElemRows& P = e.rest;
    if (e.role != ElementRole::Body && r == kVented) {
      dT = dD;  // vented: T = D
    } else if (e.role == ElementRole::Body) {
      const Eigen::Matrix3d dM = dD.transpose() * P;
      const Eigen::Matrix3d W = PolarDerivativeW(ec.R, ec.Sinv, dM);
      // T = r_w P R^T + (1 - r_w) s D; d(P R^T) = P dR^T = -P W R^T.
      const Eigen::Matrix3d WRt = W * ec.R.transpose();
      dT.noalias() = (-e.r_omega) * (P * WRt);
      if (e.r_omega < 1.0) {
        ElemRows D;
        Gather(e, X_, &D);
        double ds = 0.0;
        if (ec.s_active) {
          const double dvol = RowsVolumeGradient(D, k).cwiseProduct(dD).sum();
          ds = -(ec.s / 3.0) * dvol / ec.vol;
        }
        dT += (1.0 - e.r_omega) * (ds * D + ec.s * dD);
      }
    } else if (e.role == ElementRole::Pneumatic) {
      // T = q P R^T, q = cbrt(r).
      const double q = std::cbrt(r), dq = q * dratio_[i] / (3.0 * r);
      const Eigen::Matrix3d dM = dD.transpose() * P;
      const Eigen::Matrix3d W = PolarDerivativeW(ec.R, ec.Sinv, dM);
      const Eigen::Matrix3d G = dq * ec.R.transpose() - q * (W * ec.R.transpose());
      dT.noalias() = P * G;
    } else {
      // Cable / DEA: T = Ps R^T, Ps = P S(r)^T, R = polar(D^T Ps).
      ElemRows D;
      Gather(e, X_, &D);
      const Eigen::Matrix3d Sr = ActuationShape(e, r);
      const Eigen::Matrix3d dSr = dratio_[i] * ActuationShapeDerivative(e, r);
      const ElemRows Ps = P * Sr.transpose(), dPs = P * dSr.transpose();
      const Eigen::Matrix3d dM = dD.transpose() * Ps + D.transpose() * dPs;
      const Eigen::Matrix3d W = PolarDerivativeW(ec.R, ec.Sinv, dM);
      dT.noalias() = dPs * ec.R.transpose() - Ps * (W * ec.R.transpose());
    }
    weighted_[i] = e.wv * dT;
  }
  AssembleRhs(model, weighted_, dB, threads_);
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

/// The Krylov basis V (n x (m + 1)) and Hessenberg matrix Hbar ((m + 1) x m, before the Givens
/// rotations) of the last GMRES cycle: prec(op(V_m)) = V_{m+1} Hbar. Kept to start the next column.
struct KrylovMemory {
  Eigen::MatrixXd V, Hbar;
  int m = 0;
};

/// Restarted GMRES for op(y) = rhs, left-preconditioned by prec (y and rhs of size n).
/// Start: y = 0, or, when `memory` holds the last cycle of a previous solve with the same
/// operator, the minimiser of the preconditioned residual over that cycle's Krylov space (no
/// operator product: prec(op(V_m z)) = V_{m+1} Hbar z). The columns of J share their slow (soft)
/// modes, so later columns start with those already resolved. Returns the number of operator
/// products; *rel receives the final preconditioned residual relative to ||prec(rhs)||.
template <class Op, class Prec>
int Gmres(const Op& op, const Prec& prec, const Eigen::VectorXd& rhs, int restart, int max_it,
          double tol, Eigen::VectorXd* y, double* rel, KrylovMemory* memory) {
  const int n = static_cast<int>(rhs.size());
  y->setZero(n);
  const Eigen::VectorXd b = prec(rhs);
  const double beta0 = b.norm();
  *rel = 0.0;
  if (!(beta0 > 0.0)) return 0;
  Eigen::VectorXd r = b;
  if (memory && memory->m > 0) {
    const int pm = memory->m;
    const Eigen::VectorXd t = memory->V.leftCols(pm + 1).transpose() * b;
    const Eigen::VectorXd z = memory->Hbar.topLeftCorner(pm + 1, pm).colPivHouseholderQr().solve(t);
    if (z.allFinite()) {
      *y = memory->V.leftCols(pm) * z;
      r = b - memory->V.leftCols(pm + 1) * (memory->Hbar.topLeftCorner(pm + 1, pm) * z);
    }
  }
  const int m = std::max(1, std::min(restart, max_it));
  Eigen::MatrixXd V(n, m + 1);
  Eigen::MatrixXd Hh = Eigen::MatrixXd::Zero(m + 1, m), Hraw(m + 1, m);
  Eigen::VectorXd g(m + 1), cs(m), sn(m), w(n);
  int total = 0, last_m = 0;
  double beta = r.norm();
  bool first = true;
  while (true) {
    if (!first) {
      r = prec(rhs - op(*y));
      beta = r.norm();
    }
    first = false;
    *rel = beta / beta0;
    if (*rel <= tol || total >= max_it || !(beta > 0.0)) break;
    V.col(0) = r / beta;
    g.setZero();
    g(0) = beta;
    Hh.setZero();
    Hraw.setZero();
    int j_end = 0;
    for (int j = 0; j < m && total < max_it; ++j) {
      w = prec(op(V.col(j)));
      ++total;
      for (int i = 0; i <= j; ++i) {  // modified Gram-Schmidt
        Hh(i, j) = w.dot(V.col(i));
        w -= Hh(i, j) * V.col(i);
      }
      Hh(j + 1, j) = w.norm();
      Hraw.col(j) = Hh.col(j);
      if (Hh(j + 1, j) > 0.0) V.col(j + 1) = w / Hh(j + 1, j);
      for (int i = 0; i < j; ++i) {  // previous Givens rotations
        const double t = cs(i) * Hh(i, j) + sn(i) * Hh(i + 1, j);
        Hh(i + 1, j) = -sn(i) * Hh(i, j) + cs(i) * Hh(i + 1, j);
        Hh(i, j) = t;
      }
      const double den = std::hypot(Hh(j, j), Hh(j + 1, j));
      cs(j) = den > 0.0 ? Hh(j, j) / den : 1.0;
      sn(j) = den > 0.0 ? Hh(j + 1, j) / den : 0.0;
      Hh(j, j) = den;
      Hh(j + 1, j) = 0.0;
      g(j + 1) = -sn(j) * g(j);
      g(j) = cs(j) * g(j);
      j_end = j + 1;
      if (std::abs(g(j + 1)) <= tol * beta0 || !(den > 0.0) || !(Hraw(j + 1, j) > 0.0)) break;
    }
    if (j_end == 0) break;
    const Eigen::VectorXd z = Hh.topLeftCorner(j_end, j_end)
                                  .triangularView<Eigen::Upper>()
                                  .solve(g.head(j_end));
    *y += V.leftCols(j_end) * z;
    last_m = Hraw(j_end, j_end - 1) > 0.0 ? j_end : 0;  // a breakdown leaves no usable relation
    if (!y->allFinite()) break;
  }
  if (memory && last_m > 0) {
    memory->V.swap(V);
    memory->Hbar = Hraw;
    memory->m = last_m;
  }
  return total;
}

/// BiCGSTAB for op(y) = rhs, left-preconditioned by prec, from y = 0: two operator products per
/// iteration and no stored basis (GMRES's orthogonalisation reads its whole basis every step).
/// Returns the number of operator products; *rel receives the final preconditioned relative
/// residual (recomputed from scratch at the end).
template <class Op, class Prec>
int BiCgStab(const Op& op, const Prec& prec, const Eigen::VectorXd& rhs, int max_it, double tol,
             Eigen::VectorXd* y, double* rel) {
  const int n = static_cast<int>(rhs.size());
  y->setZero(n);
  Eigen::VectorXd r = prec(rhs);
  const double beta0 = r.norm();
  *rel = 0.0;
  if (!(beta0 > 0.0)) return 0;
  const Eigen::VectorXd r0 = r;
  Eigen::VectorXd p = Eigen::VectorXd::Zero(n), v = Eigen::VectorXd::Zero(n), s(n), t(n);
  double rho = 1.0, alpha = 1.0, omega = 1.0;
  int total = 0;
  while (total + 2 <= max_it) {
    const double rho_new = r0.dot(r);
    if (!(std::abs(rho_new) > 0.0)) break;  // breakdown
    const double beta = (rho_new / rho) * (alpha / omega);
    p = r + beta * (p - omega * v);
    v = prec(op(p));
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
    t = prec(op(s));
    ++total;
    const double tt = t.squaredNorm();
    if (!(tt > 0.0)) break;
    omega = t.dot(s) / tt;
    *y += alpha * p + omega * s;
    r = s - omega * t;
    rho = rho_new;
    if (r.norm() <= tol * beta0 || !(std::abs(omega) > 0.0)) break;
  }
  *rel = (prec(rhs) - prec(op(*y))).norm() / beta0;
  ++total;
  return total;
}

}  // namespace

EquilibriumJacobianResult ComputeEquilibriumJacobian(const Model& model,
                                                     const Eigen::Ref<const Eigen::MatrixX3d>& X,
                                                     const Eigen::Ref<const Eigen::VectorXd>& c,
                                                     const std::vector<int>& columns_in,
                                                     const EquilibriumJacobianOptions& options) {
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

  EquilibriumLinearization lin;
  if (!lin.Setup(model, X, c, &why, options.threads)) {
    res.message = why;
    return finish();
  }
  const int nf = model.num_free_dofs();
  Eigen::MatrixX3d Y(nv, 3), dB(nv, 3);
  Eigen::VectorXd AY, KY;
  const Eigen::VectorXd zero_c = Eigen::VectorXd::Zero(na);
  // H y = A_ff y - (K Y)_f with Y = y on the free coordinates, 0 elsewhere.
  auto op = [&](const Eigen::VectorXd& y) -> Eigen::VectorXd {
    Y.setZero();
    model.ScatterFree(y, &Y);
    lin.ApplyRhsDerivative(Y, zero_c, &dB);
    model.GatherFree(model.A() * Y, &AY);
    model.GatherFree(dB, &KY);
    return AY - KY;
  };
  auto prec = [&](const Eigen::VectorXd& v) -> Eigen::VectorXd { return model.SolveFree(v); };

  res.dXdc.setZero(3 * nv, static_cast<Eigen::Index>(columns.size()));
  Eigen::VectorXd rhs, y, Ac;
  KrylovMemory memory;
  for (size_t j = 0; j < columns.size(); ++j) {
    const int a = columns[j];
    const Eigen::MatrixX3d dXc = PrescribedDerivative(model, c, a);
    Eigen::VectorXd dc = zero_c;
    dc[a] = 1.0;
    lin.ApplyRhsDerivative(dXc, dc, &dB);
    model.GatherFree(dB - model.A() * dXc, &rhs);
    double rel = 0.0;
    const int its =
        options.krylov == "bicgstab"
            ? BiCgStab(op, prec, rhs, options.max_iterations, options.tolerance, &y, &rel)
            : Gmres(op, prec, rhs, options.restart, options.max_iterations, options.tolerance, &y,
                    &rel, options.recycle ? &memory : nullptr);
    res.iterations.push_back(its);
    const double rn = rhs.norm();
    const double true_rel = rn > 0 ? (op(y) - rhs).norm() / rn : 0.0;
    res.residuals.push_back(true_rel);
    if (!y.allFinite() || !(rel <= options.tolerance)) {
      std::ostringstream s;
      s << "implicit Jacobian: GMRES for actuator '" << model.scene().actuators[a].name
        << "' stopped at relative residual " << rel << " after " << its
        << " iterations (tolerance " << options.tolerance << ")";
      res.message = s.str();
      res.dXdc.resize(0, 0);
      return finish();
    }
    Eigen::MatrixX3d dX = dXc;
    model.ScatterFree(y, &dX);
    for (int v = 0; v < nv; ++v)
      for (int d = 0; d < 3; ++d) res.dXdc(3 * v + d, static_cast<Eigen::Index>(j)) = dX(v, d);
  }
  (void)nf;
  res.ok = true;
  return finish();
}

}  // namespace softkin
