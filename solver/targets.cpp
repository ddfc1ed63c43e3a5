#include "solver/targets.hpp"

#include "solver/rotation.hpp"

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
  if (achieved) achieved->assign(model.num_actuators(), 1.0);
  for (int a = 0; a < model.num_actuators(); ++a) {
    const auto& ids = model.actuator_elements(a);
    const double U = model.actuator_rest_volume(a);
    double Ud = 0.0;
    for (int i : ids) {
      ElemRows D;
      for (int j = 0; j < els[i].k; ++j) D.row(j) = X.row(els[i].v[j]);
      // Inverted or collapsed elements count as (almost) empty.
      (*ratios)[i] = std::max(RowsVolume(D, els[i].k), 1e-6 * els[i].rest_volume);
      Ud += (*ratios)[i];
    }
    if (achieved) (*achieved)[a] = Ud / U;
    // alpha_i u_i = Vol_i^d * (alpha U / U^d): proportional to the current volume, exact total.
    const double scale = c[a] * U / Ud;
    for (int i : ids) (*ratios)[i] = (*ratios)[i] * scale / els[i].rest_volume;
  }
}

void ElementTarget(const ModelElement& e, const ElemRows& D, double ratio, ElemRows* T) {
  const int k = e.k;
  // Best rotation from the rest shape to the current shape: max tr(R^T D^T P).
  const Eigen::Matrix3d M = D.topRows(k).transpose() * e.rest.topRows(k);
  const Eigen::Matrix3d R = BestRotation(M);
  T->setZero();
  if (e.role == ElementRole::Body) {
    T->topRows(k) = e.rest.topRows(k) * R.transpose();  // V^r = R V (rows), Eq. 2.3
    if (e.r_omega < 1.0) {
      const double vd = RowsVolume(D, k);
      double s = 1.0;
      if (vd > 1e-9 * e.rest_volume) s = std::cbrt(e.rest_volume / vd);  // Eq. 2.4, volume restored
      s = std::min(s, 10.0);
      T->topRows(k) = e.r_omega * T->topRows(k) + (1.0 - e.r_omega) * s * D.topRows(k);  // Eq. 2.5
    }
  } else {
    // Pneumatic: rest shape scaled by cbrt(alpha_i) about its centre, rotated (Eq. 2.8).
    T->topRows(k) = std::cbrt(ratio) * (e.rest.topRows(k) * R.transpose());
  }
}

double LocalStep(const Model& model, const Eigen::Ref<const Eigen::MatrixX3d>& X,
                 const std::vector<double>& ratios, std::vector<ElemRows>* weighted, int threads) {
  const auto& els = model.elements();
  const int ne = static_cast<int>(els.size());
  if (static_cast<int>(weighted->size()) != ne) weighted->resize(ne);
  double energy = 0.0;
  const int nt = threads > 0 ? threads : 0;
#pragma omp parallel for schedule(static) reduction(+ : energy) num_threads(nt > 0 ? nt : omp_get_max_threads())
  for (int i = 0; i < ne; ++i) {
    const ModelElement& e = els[i];
    ElemRows D, T;
    GatherRows(e, X, &D);
    ElementTarget(e, D, ratios[i], &T);
    energy += e.wv * (D - T).squaredNorm();
    (*weighted)[i] = e.wv * T;
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
