#include "softkin/solver/fk/energy.hpp"

#include "softkin/solver/fk/actuation.hpp"
#include "softkin/solver/fk/rotation.hpp"
#include "softkin/solver/fk/targets.hpp"

#include <cmath>
#include <sstream>
#include <stdexcept>

namespace softkin {

void CheckActuation(const Model& model, const Eigen::Ref<const Eigen::VectorXd>& c) {
  const auto& acts = model.scene().actuators;
  if (c.size() != static_cast<Eigen::Index>(acts.size())) {
    std::ostringstream os;
    os << "actuation: expected " << acts.size() << " value(s) (";
    for (size_t a = 0; a < acts.size(); ++a) os << (a ? ", " : "") << acts[a].name;
    os << "), got " << c.size();
    throw std::invalid_argument(os.str());
  }
  for (size_t a = 0; a < acts.size(); ++a) {
    if (!std::isfinite(c[a]) || c[a] < acts[a].min || c[a] > acts[a].max) {
      std::ostringstream os;
      os << "actuation of '" << acts[a].name << "': expected a number in [" << acts[a].min << ", "
         << acts[a].max << "], got " << c[a];
      throw std::invalid_argument(os.str());
    }
  }
}

double Energy(const Model& model, const Eigen::Ref<const Eigen::MatrixX3d>& X,
              const Eigen::Ref<const Eigen::VectorXd>& c) {
  std::vector<double> ratios;
  ComputeLocalRatios(model, X, c, &ratios);
  std::vector<ElemRows> w;
  return LocalStep(model, X, ratios, &w);
}

double FrozenTargetGradient(const Model& model, const Eigen::Ref<const Eigen::MatrixX3d>& X,
                            const Eigen::Ref<const Eigen::VectorXd>& c, Eigen::MatrixX3d* grad) {
  std::vector<double> ratios;
  ComputeLocalRatios(model, X, c, &ratios);
  std::vector<ElemRows> w;
  const double E = LocalStep(model, X, ratios, &w);
  Eigen::MatrixX3d B;
  AssembleRhs(model, w, &B);
  *grad = 2.0 * (model.A() * X - B);
  return E;
}

namespace {

/// E and its gradient for the given per-element ratios; `chain` adds the dependence of the ratios
/// on the chamber measures (EnergyAndGradient), without it the ratios are constants.
double EnergyAndGradientImpl(const Model& model, const Eigen::Ref<const Eigen::MatrixX3d>& X,
                             const std::vector<double>& ratios, bool chain,
                             Eigen::MatrixX3d* grad) {
  const auto& els = model.elements();
  const int ne = static_cast<int>(els.size());
  grad->setZero(model.num_vertices(), 3);
  // dE_i/dr_i for actuation elements: needed for the chain rule through the ratio distribution.
  std::vector<double> dE_dratio(ne, 0.0);
  std::vector<ElemRows> Gs(ne, ElemRows::Zero());  // per-element dE_i/dV (centred rows)
  double E = 0.0;
#pragma omp parallel for schedule(static) reduction(+ : E)
  for (int i = 0; i < ne; ++i) {
    const ModelElement& e = els[i];
    const int k = e.k;
    ElemRows D = ElemRows::Zero();
    for (int j = 0; j < k; ++j) D.row(j) = X.row(e.v[j]);
    CenterRows(D, k);
    ElemRows G = ElemRows::Zero();  // dE_i/dD (centred rows)
    if (e.role == ElementRole::Body && e.curve) {
      // Hyperelastic (Eq. 3.6-3.7): E_i = wv ||D - T(D)||^2, where T depends on D through the
      // rotation, the strain-dependent R_omega and the volume rescale. Its gradient is taken by
      // central differences of this element's term over its 3k vertex coordinates (relative
      // accuracy ~1e-8; tested against differences of the total energy).
      auto term = [&](const ElemRows& V) {
        ElemRows Dx = V, T;
        CenterRows(Dx, k);
        ElementTarget(e, Dx, 1.0, &T);
        return e.wv * (Dx - T).topRows(k).squaredNorm();
      };
      ElemRows V = ElemRows::Zero();
      for (int j = 0; j < k; ++j) V.row(j) = X.row(e.v[j]);
      E += term(V);
      const double h = 1e-6 * std::sqrt(e.rest.topRows(k).squaredNorm() / k);
      for (int j = 0; j < k; ++j)
        for (int d = 0; d < 3; ++d) {
          ElemRows Vp = V, Vm = V;
          Vp(j, d) += h;
          Vm(j, d) -= h;
          G(j, d) = (term(Vp) - term(Vm)) / (2.0 * h);
        }
    } else if (e.role == ElementRole::Body) {
      const Eigen::Matrix3d R = BestRotation(D.topRows(k).transpose() * e.rest.topRows(k));
      ElemRows RP = ElemRows::Zero();
      RP.topRows(k) = e.rest.topRows(k) * R.transpose();
      // E_i = wv || beta D - Rw R P ||^2, beta = 1 - (1 - Rw) s(Vol(D)).
      const double vd = RowsVolume(D, k);
      double s = 1.0;
      bool s_varies = false;
      if (e.r_omega < 1.0 && vd > 1e-9 * e.rest_volume) {
        s = std::cbrt(e.rest_volume / vd);
        s_varies = s < 10.0;
        s = std::min(s, 10.0);
      }
      const double beta = 1.0 - (1.0 - e.r_omega) * s;
      const ElemRows r = beta * D - e.r_omega * RP;
      E += e.wv * r.squaredNorm();
      G = 2.0 * e.wv * beta * r;
      if (s_varies) {
        // dbeta/dD = -(1 - Rw) ds/dVol dVol/dD, ds/dVol = -s / (3 Vol).
        const double dE_dbeta = 2.0 * e.wv * (r.topRows(k).cwiseProduct(D.topRows(k))).sum();
        const double dbeta_dvol = (1.0 - e.r_omega) * s / (3.0 * vd);
        G += dE_dbeta * dbeta_dvol * RowsVolumeGradient(D, k);
      }
    } else if (ratios[i] == kVented) {
      continue;  // vented chamber: no energy, no force
    } else {
      // E_i = wv || D - P S(r)^T R^T ||^2 with R the best rotation (no derivative needed: R
      // minimises the term).
      ElemRows Ps = ElemRows::Zero();
      Ps.topRows(k) = e.rest.topRows(k) * ActuationShape(e, ratios[i]).transpose();
      const Eigen::Matrix3d R = BestRotation(D.topRows(k).transpose() * Ps.topRows(k));
      ElemRows r = D;
      r.topRows(k) -= Ps.topRows(k) * R.transpose();
      E += e.wv * r.squaredNorm();
      G = 2.0 * e.wv * r;
      ElemRows dT = ElemRows::Zero();
      dT.topRows(k) =
          e.rest.topRows(k) * ActuationShapeDerivative(e, ratios[i]).transpose() * R.transpose();
      dE_dratio[i] = -2.0 * e.wv * (r.topRows(k).cwiseProduct(dT.topRows(k))).sum();
    }
    // D = N V: dE/dV = N^T dE/dD = dE/dD centred.
    CenterRows(G, k);
    Gs[i] = G;
  }
  for (int i = 0; i < ne; ++i)
    for (int j = 0; j < els[i].k; ++j) grad->row(els[i].v[j]) += Gs[i].row(j);
  if (!chain) return E;
  // Chain rule through r_i = kappa m_i / mu_i, kappa = T_a / sum_j m_j:
  //   dr_i/dm_j = r_i (delta_ij / m_i - 1 / sum m),
  // so dE/dm_j = g_j r_j / m_j - (sum_i g_i r_i) / sum m, with g_i = dE/dr_i. (A measure at its
  // floor kMinMeasure * mu_j has a zero gradient.)
  for (int g = 0; g < model.num_groups(); ++g) {
    const auto& ids = model.group_elements(g);
    if (!ids.empty() && ratios[ids[0]] == kVented) continue;
    double Md = 0.0, sum_gr = 0.0;
    std::vector<double> meas(ids.size());
    std::vector<bool> floored(ids.size());
    for (size_t q = 0; q < ids.size(); ++q) {
      const ModelElement& e = els[ids[q]];
      ElemRows P;
      for (int j = 0; j < e.k; ++j) P.row(j) = X.row(e.v[j]);
      const double m = ActuationMeasure(e, P);
      floored[q] = !(m > kMinMeasure * e.measure0);
      meas[q] = floored[q] ? kMinMeasure * e.measure0 : m;
      Md += meas[q];
      sum_gr += dE_dratio[ids[q]] * ratios[ids[q]];
    }
    for (size_t q = 0; q < ids.size(); ++q) {
      if (floored[q]) continue;
      const ModelElement& e = els[ids[q]];
      const double coef = dE_dratio[ids[q]] * ratios[ids[q]] / meas[q] - sum_gr / Md;
      ElemRows P;
      for (int j = 0; j < e.k; ++j) P.row(j) = X.row(e.v[j]);
      const ElemRows gm = ActuationMeasureGradient(e, P);
      for (int j = 0; j < e.k; ++j) grad->row(e.v[j]) += coef * gm.row(j);
    }
  }
  return E;
}

}  // namespace

double EnergyAndGradient(const Model& model, const Eigen::Ref<const Eigen::MatrixX3d>& X,
                         const Eigen::Ref<const Eigen::VectorXd>& c, Eigen::MatrixX3d* grad) {
  std::vector<double> ratios;
  ComputeLocalRatios(model, X, c, &ratios);
  return EnergyAndGradientImpl(model, X, ratios, true, grad);
}

double FixedRatioEnergyAndGradient(const Model& model, const Eigen::Ref<const Eigen::MatrixX3d>& X,
                                   const std::vector<double>& ratios, Eigen::MatrixX3d* grad) {
  if (ratios.size() != model.elements().size())
    throw std::invalid_argument("FixedRatioEnergyAndGradient: expected one ratio per element");
  return EnergyAndGradientImpl(model, X, ratios, false, grad);
}

}  // namespace softkin
