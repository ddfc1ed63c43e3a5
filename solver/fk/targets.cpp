#include "softkin/solver/fk/targets.hpp"

#include "softkin/solver/fk/actuation.hpp"
#include "softkin/solver/fk/rotation.hpp"

#include <algorithm>
#include <cmath>

#include <omp.h>

namespace softkin {

namespace {

inline void GatherRows(const ModelElement& e, const Eigen::Ref<const Eigen::MatrixX3d>& X,
                       ElemRows* D) {
  for (int j = 0; j < e.k; ++j) D->row(j) = X.row(e.v[j]);
  CenterRows(*D, e.k);
}

}  // namespace

void ComputeLocalRatios(const Model& model, const Eigen::Ref<const Eigen::MatrixX3d>& X,
                        const Eigen::Ref<const Eigen::VectorXd>& c, std::vector<double>* ratios,
                        std::vector<double>* achieved) {
  const auto& els = model.elements();
  ratios->assign(els.size(), 1.0);
  std::vector<double> group_achieved(model.num_groups(), 1.0);
  for (int g = 0; g < model.num_groups(); ++g) {
    const auto& ids = model.group_elements(g);
    const double M = model.group_rest_measure(g), LR = model.group_offset(g);
    const double rho = model.GroupRatio(g, c);
    const bool vented = model.GroupVented(g, c);
    // The measures in parallel (each element on its own), their sum in element order, so the
    // result does not depend on the number of threads.
    const int ng = static_cast<int>(ids.size());
#pragma omp parallel for schedule(static) if (ng > 2048)
    for (int q = 0; q < ng; ++q) {
      const int i = ids[q];
      ElemRows D;
      for (int j = 0; j < els[i].k; ++j) D.row(j) = X.row(els[i].v[j]);
      // Inverted or collapsed elements count as (almost) empty.
      (*ratios)[i] = std::max(ActuationMeasure(els[i], D), kMinMeasure * els[i].measure0);
    }
    double Md = 0.0;
    for (int i : ids) Md += (*ratios)[i];
    group_achieved[g] = (Md + LR) / (M + LR);
    if (vented) {
      for (int i : ids) (*ratios)[i] = kVented;
      continue;
    }
    // r_i mu_i = m_i * (c (M + L_R) - L_R) / M^d: proportional to the current measure, exact
    // total. (A cable pulled shorter than its rigid part L_R allows gets tiny positive ratios.)
    const double scale = std::max(rho * (M + LR) - LR, kMinMeasure * M) / Md;
    for (int i : ids) (*ratios)[i] = (*ratios)[i] * scale / els[i].measure0;
  }
  if (achieved) {
    achieved->resize(model.num_actuators());
    for (int a = 0; a < model.num_actuators(); ++a)
      (*achieved)[a] = model.ActuatorValue(a, group_achieved, c);
  }
}

double HyperelasticBlendWeight(const ElemRows& Rr, const ElemRows& D, int k, double rho,
                               double rest_volume) {
  auto volume = [&](double t) {
    ElemRows B = ElemRows::Zero();
    B.topRows(k) = t * Rr.topRows(k) + (1.0 - t) * D.topRows(k);
    return RowsVolume(B, k);
  };
  const double floor = kMinBlendVolume * rest_volume;
  const double vr = volume(rho);
  if (vr >= floor) return rho;
  // The blend's volume is a cubic in t (each of a tet's edge vectors is linear in t): sample it at
  // t = 0, 1/3, 2/3, 1 and write it in Newton's forward differences, in s = 3 t. volume(1) =
  // rest_volume > floor, so [rho, 1] brackets a crossing: Newton's method on the cubic, kept inside
  // the bracket (a step that would leave it bisects instead), to a step below 1e-15.
  const double v0 = volume(0.0), v1 = volume(1.0 / 3.0), v2 = volume(2.0 / 3.0), v3 = volume(1.0);
  const double d1 = v1 - v0, d2 = v2 - 2.0 * v1 + v0, d3 = v3 - 3.0 * v2 + 3.0 * v1 - v0;
  double lo = rho, hi = 1.0;
  double t = rho + (1.0 - rho) * (floor - vr) / (v3 - vr);  // the chord's crossing
  for (int it = 0; it < 100; ++it) {
    const double s = 3.0 * t;
    const double f = v0 + s * (d1 + (s - 1.0) / 2.0 * (d2 + (s - 2.0) / 3.0 * d3)) - floor;
    const double df =
        3.0 * (d1 + (2.0 * s - 1.0) / 2.0 * d2 + (3.0 * s * s - 6.0 * s + 2.0) / 6.0 * d3);
    (f < 0.0 ? lo : hi) = t;
    double next = t - f / df;
    if (!(next > lo && next < hi)) next = 0.5 * (lo + hi);
    const double step = std::abs(next - t);
    t = next;
    if (step < 1e-15 || hi - lo < 1e-15) break;
  }
  return std::isfinite(t) ? t : 1.0;  // non-finite rows: the rotated rest shape
}

Eigen::Matrix3d DeformationGradient(const ModelElement& e, const ElemRows& D) {
  // Least-squares affine map of the centred rest rows onto the centred current rows (exact for a
  // tet): D^T = F P^T, F = D^T P (P^T P)^-1.
  const auto P = e.rest.topRows(e.k);
  const Eigen::Matrix3d G = P.transpose() * P;
  return (D.topRows(e.k).transpose() * P) * G.inverse();
}

namespace {

/// The shape an element's best rotation is fitted to (max tr(R^T D^T P)): the rest shape for body
/// and pneumatic elements (isotropic scaling does not change the rotation), the reshaped rest shape
/// for cable and DEA elements (actuation.hpp), written to `buf`. Null for a vented chamber, which
/// has no rotation.
inline const ElemRows* FittedShape(const ModelElement& e, double ratio, ElemRows* buf) {
  if (ratio == kVented && e.role != ElementRole::Body) return nullptr;
  if (e.role == ElementRole::Body || e.role == ElementRole::Pneumatic) return &e.rest;
  buf->setZero();
  buf->topRows(e.k) = e.rest.topRows(e.k) * ActuationShape(e, ratio).transpose();
  return buf;
}

/// The target of an element with a fitted shape, given the best rotation R of D onto P.
void TargetFromRotation(const ModelElement& e, const ElemRows& D, double ratio, const ElemRows& P,
                        const Eigen::Matrix3d& R, ElemRows* T) {
  // P's and D's rows past k are zero (CenterRows, FittedShape), and so are T's.
  const int k = e.k;
  if (e.role == ElementRole::Body) {
    T->noalias() = P * R.transpose();  // V^r = R V (rows), Eq. 2.3
    if (e.curve) {
      // Hyperelastic (Eq. 3.6-3.7): blend the current shape with the rotated rest shape by
      // R_omega(strain), then rescale the blend to the rest volume.
      const double rho = (*e.curve)(EquivalentStrain(DeformationGradient(e, D)));
      const double t = HyperelasticBlendWeight(*T, D, k, rho, e.rest_volume);
      T->topRows(k) = t * T->topRows(k) + (1.0 - t) * D.topRows(k);
      T->topRows(k) *= std::cbrt(e.rest_volume / RowsVolume(*T, k));
    } else if (e.r_omega < 1.0) {
      const double vd = RowsVolume(D, k);
      double s = 1.0;
      if (vd > 1e-9 * e.rest_volume) s = std::cbrt(e.rest_volume / vd);  // Eq. 2.4, volume restored
      s = std::min(s, 10.0);
      *T = e.r_omega * *T + (1.0 - e.r_omega) * s * D;  // Eq. 2.5
    }
  } else if (e.role == ElementRole::Pneumatic) {
    // Rest shape scaled by cbrt(alpha_i) about its centre, rotated (Eq. 2.8).
    T->noalias() = std::cbrt(ratio) * (P * R.transpose());
  } else {
    // Cable / DEA: the reshaped rest shape rotated onto the current shape.
    T->noalias() = P * R.transpose();
  }
}

}  // namespace

void ElementTarget(const ModelElement& e, const ElemRows& D, double ratio, ElemRows* T) {
  // TargetFromRotation works on full 6-row blocks: the caller's rows past k may hold anything.
  ElemRows Dk = D;
  Dk.bottomRows(6 - e.k).setZero();
  ElemRows buf;
  const ElemRows* P = FittedShape(e, ratio, &buf);
  if (!P) {
    *T = Dk;  // vented chamber: empty space
    return;
  }
  const Eigen::Matrix3d R = BestRotation(Dk.transpose() * *P);  // rows past k are zero
  TargetFromRotation(e, Dk, ratio, *P, R, T);
}

double LocalStep(const Model& model, const Eigen::Ref<const Eigen::MatrixX3d>& X,
                 const std::vector<double>& ratios, std::vector<ElemRows>* weighted, int threads) {
  const auto& els = model.elements();
  const int ne = static_cast<int>(els.size());
  if (static_cast<int>(weighted->size()) != ne) weighted->resize(ne);
  // Elements go in blocks of kRotationBatch so that their best rotations are computed together
  // (BestRotations: the same bits as ElementTarget's BestRotation, about twice as fast).
  constexpr int W = kRotationBatch;
  const int nb = (ne + W - 1) / W;
  double energy = 0.0;
  const int nt = threads > 0 ? threads : 0;
#pragma omp parallel for schedule(static) reduction(+ : energy) num_threads(nt > 0 ? nt : omp_get_max_threads())
  for (int b = 0; b < nb; ++b) {
    const int i0 = b * W, m = std::min(W, ne - i0);
    ElemRows D[W], buf[W];
    const ElemRows* P[W];
    Eigen::Matrix3d M[W], R[W];
    for (int l = 0; l < m; ++l) {
      const ModelElement& e = els[i0 + l];
      GatherRows(e, X, &D[l]);
      P[l] = FittedShape(e, ratios[i0 + l], &buf[l]);
      // The rows past k are zero in both (CenterRows, FittedShape), so the fixed 6-row product
      // is the k-row one, without a runtime-sized loop.
      if (P[l])
        M[l].noalias() = D[l].transpose() * *P[l];
      else
        M[l].setIdentity();
    }
    BestRotations(M, m, R);
    for (int l = 0; l < m; ++l) {
      const int i = i0 + l;
      const ModelElement& e = els[i];
      ElemRows T;
      if (P[l])
        TargetFromRotation(e, D[l], ratios[i], *P[l], R[l], &T);
      else
        T = D[l];  // vented chamber: empty space
      energy += e.wv * (D[l] - T).squaredNorm();
      (*weighted)[i] = e.wv * T;
    }
  }
  return energy;
}

void AssembleRhs(const Model& model, const std::vector<ElemRows>& weighted, Eigen::MatrixX3d* B,
                 int threads) {
  const int nv = model.num_vertices();
  B->resize(nv, 3);
  const auto& off = model.incidence_offset();
  const auto& inc = model.incidence();
  const int nt = threads > 0 ? threads : 0;
#pragma omp parallel for schedule(static) num_threads(nt > 0 ? nt : omp_get_max_threads())
  for (int v = 0; v < nv; ++v) {
    Eigen::RowVector3d s = Eigen::RowVector3d::Zero();
    for (int q = off[v]; q < off[v + 1]; ++q) s += weighted[inc[q] / 6].row(inc[q] % 6);
    B->row(v) = s;
  }
}

}  // namespace softkin
