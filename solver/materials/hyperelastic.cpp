#include "softkin/solver/materials/hyperelastic.hpp"

#include <algorithm>
#include <cmath>
#include <sstream>
#include <stdexcept>

namespace softkin {

double MooneyRivlin::NominalStress(double l) const {
  return 2.0 * (l - 1.0 / (l * l)) * (c1 + c2 / l);
}

namespace {
struct Named {
  const char* name;
  double c1, c2;
};
// Thesis Sec. 3.4 (MPa).
constexpr Named kNamed[] = {{"ecoflex-00-30", 0.0418, 0.0106}, {"dragon-skin-20", 0.119, 0.023}};
}  // namespace

bool NamedMooneyRivlin(const std::string& name, MooneyRivlin* out) {
  for (const auto& n : kNamed)
    if (name == n.name) {
      out->c1 = n.c1;
      out->c2 = n.c2;
      return true;
    }
  return false;
}

std::vector<std::string> NamedMooneyRivlinNames() {
  std::vector<std::string> v;
  for (const auto& n : kNamed) v.push_back(n.name);
  return v;
}

double BlendUniaxialStress(double lambda, double rho, double* lateral) {
  if (!(lambda > 0) || !(rho >= 0 && rho <= 1))
    throw std::invalid_argument("BlendUniaxialStress: expected lambda > 0 and rho in [0, 1]");
  const double a = (1.0 - rho) * lambda + rho;
  // g(l) = l - T_22(l) = l - b^(1/3) a^(-1/3), b = (1 - rho) l + rho. g is increasing where it
  // matters (g' = 1 - (1 - rho) b^(-2/3) a^(-1/3) / 3 > 0 for b, a not tiny); bisection on
  // [lo, hi] with g(lo) < 0 < g(hi).
  auto g = [&](double l) { return l - std::cbrt(((1.0 - rho) * l + rho) / a); };
  double lo = 1e-6, hi = 1.0;
  while (g(hi) < 0) hi *= 2.0;
  for (int it = 0; it < 200 && hi - lo > 1e-15 * hi; ++it) {
    const double mid = 0.5 * (lo + hi);
    (g(mid) < 0 ? lo : hi) = mid;
  }
  const double l = 0.5 * (lo + hi);
  const double b = (1.0 - rho) * l + rho;
  const double t11 = a / std::cbrt(a * b * b);
  if (lateral) *lateral = l;
  return 2.0 * (lambda - t11);
}

double EquivalentStrain(const Eigen::Matrix3d& F) {
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> es;
  es.computeDirect(F.transpose() * F, Eigen::EigenvaluesOnly);
  Eigen::Vector3d e;  // ln of the principal stretches
  for (int i = 0; i < 3; ++i) e[i] = 0.5 * std::log(std::max(es.eigenvalues()[i], 1e-12));
  e.array() -= e.mean();
  return std::sqrt(2.0 / 3.0 * e.squaredNorm());
}

Eigen::Matrix3d EquivalentStrainGradient(const Eigen::Matrix3d& F) {
  const Eigen::Matrix3d C = F.transpose() * F;
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> es(C);  // iterative: backward stable
  const Eigen::Vector3d mu = es.eigenvalues();
  if (!(mu.minCoeff() > 1e-12)) return Eigen::Matrix3d::Zero();
  Eigen::Vector3d e = 0.5 * mu.array().log().matrix();
  e.array() -= e.mean();
  const double eps = std::sqrt(2.0 / 3.0 * e.squaredNorm());
  if (!(eps >= 1e-12)) return Eigen::Matrix3d::Zero();
  // (dev e) C^-1 in C's eigenbasis: diag(e_i / mu_i).
  const Eigen::Matrix3d& V = es.eigenvectors();
  const Eigen::Vector3d w = e.cwiseQuotient(mu);
  return (2.0 / (3.0 * eps)) * F * (V * w.asDiagonal() * V.transpose());
}

ROmegaCurve::ROmegaCurve(std::vector<double> eps, std::vector<double> rho)
    : eps_(std::move(eps)), rho_(std::move(rho)) {
  if (eps_.empty() || eps_.size() != rho_.size())
    throw std::invalid_argument("R_omega curve: expected as many strains as R_omega values (>= 1)");
  for (size_t i = 0; i < eps_.size(); ++i) {
    if (!std::isfinite(eps_[i]) || (i > 0 && !(eps_[i] > eps_[i - 1])))
      throw std::invalid_argument("R_omega curve: strains must be finite and strictly increasing");
    if (!(rho_[i] >= 0 && rho_[i] <= 1))
      throw std::invalid_argument("R_omega curve: R_omega values must be in [0, 1]");
  }
}

double ROmegaCurve::operator()(double eps) const {
  if (eps <= eps_.front()) return rho_.front();
  if (eps >= eps_.back()) return rho_.back();
  const size_t j = std::upper_bound(eps_.begin(), eps_.end(), eps) - eps_.begin();  // 1..n-1
  const double t = (eps - eps_[j - 1]) / (eps_[j] - eps_[j - 1]);
  return (1.0 - t) * rho_[j - 1] + t * rho_[j];
}

double ROmegaCurve::Slope(double eps) const {
  if (eps < eps_.front() || eps >= eps_.back()) return 0.0;
  const size_t j = std::upper_bound(eps_.begin(), eps_.end(), eps) - eps_.begin();  // 1..n-1
  return (rho_[j] - rho_[j - 1]) / (eps_[j] - eps_[j - 1]);
}

double CurveUniaxialStress(const ROmegaCurve& curve, double lambda, double* lateral,
                           double* rho_out) {
  double rho = curve(0.0), l = 1.0;
  for (int it = 0; it < 500; ++it) {
    BlendUniaxialStress(lambda, rho, &l);
    const double next = curve(2.0 / 3.0 * std::abs(std::log(lambda / l)));
    const bool done = std::abs(next - rho) < 1e-12;
    rho = next;
    if (done) break;
  }
  if (rho_out) *rho_out = rho;
  return BlendUniaxialStress(lambda, rho, lateral);
}

ROmegaCurve FitMooneyRivlinROmega(const MooneyRivlin& m, double rho0, double lambda_max, int n) {
  if (!(m.c1 >= 0 && m.c2 >= 0 && m.c1 + m.c2 > 0) || !(rho0 > 0 && rho0 <= 1) ||
      !(lambda_max > 1) || n < 2) {
    std::ostringstream s;
    s << "Mooney-Rivlin R_omega fit: expected c1, c2 >= 0 with c1 + c2 > 0, R_omega(0) in (0, 1], "
      << "lambda_max > 1, n >= 2; got c1 = " << m.c1 << ", c2 = " << m.c2
      << ", R_omega(0) = " << rho0 << ", lambda_max = " << lambda_max << ", n = " << n;
    throw std::invalid_argument(s.str());
  }
  // Units: the geometric small-strain modulus at rho0, 6 rho0 / (2 + rho0) per unit weight
  // (s = 2 (lambda - T_11)), against the Mooney-Rivlin one.
  const double k = 6.0 * rho0 / (2.0 + rho0) / m.Modulus();
  std::vector<double> eps{0.0}, rho{rho0};
  for (int i = 1; i < n; ++i) {
    const double lambda = 1.0 + (lambda_max - 1.0) * i / (n - 1);
    const double goal = k * m.NominalStress(lambda);
    // s(lambda; rho) grows with rho: bisection on [0, 1], clamped at the ends.
    double lo = 0.0, hi = 1.0, r;
    if (BlendUniaxialStress(lambda, 1.0) <= goal) {
      r = 1.0;
    } else if (BlendUniaxialStress(lambda, 0.0) >= goal) {
      r = 0.0;
    } else {
      for (int it = 0; it < 100 && hi - lo > 1e-13; ++it) {
        const double mid = 0.5 * (lo + hi);
        (BlendUniaxialStress(lambda, mid) < goal ? lo : hi) = mid;
      }
      r = 0.5 * (lo + hi);
    }
    double l = 1.0;
    BlendUniaxialStress(lambda, r, &l);
    const double e = 2.0 / 3.0 * std::log(lambda / l);
    if (e > eps.back()) {
      eps.push_back(e);
      rho.push_back(r);
    }
  }
  return ROmegaCurve(std::move(eps), std::move(rho));
}

}  // namespace softkin
