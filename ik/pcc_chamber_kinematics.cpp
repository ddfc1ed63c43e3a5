#include "softkin/ik/pcc_chamber_kinematics.hpp"
#include "softkin/solver/common/stopwatch.hpp"

#include <ceres/jet.h>
#include <Eigen/Dense>

#include <chrono>
#include <cmath>
#include <sstream>
#include <stdexcept>

namespace softkin {

namespace {

constexpr double kPi = 3.14159265358979323846;

// g(t) = (1 - cos sqrt t)/t and h(t) = sin(sqrt t)/sqrt t, series below t = 0.1 (first omitted
// term < 1e-13), for doubles and Jets alike.
template <typename T>
void ArcGH(const T& t, T* g, T* h) {
  using ceres::cos;
  using ceres::sin;
  using ceres::sqrt;
  using std::cos;
  using std::sin;
  using std::sqrt;
  if (t < 0.1) {
    *g = 0.5 + t * (-1.0 / 24 + t * (1.0 / 720 + t * (-1.0 / 40320 + t * (1.0 / 3628800))));
    *h = 1.0 + t * (-1.0 / 6 + t * (1.0 / 120 + t * (-1.0 / 5040 + t * (1.0 / 362880))));
    return;
  }
  const T x = sqrt(t);
  *g = (1.0 - cos(x)) / t;
  *h = sin(x) / x;
}

template <typename T>
void BendingVector(const PccChamberParams& p, const T* c, T* bx, T* bz, T* len) {
  T l[3];
  for (int k = 0; k < 3; ++k) l[k] = p.chamber_length * (1.0 + p.gain * (c[k] - 1.0));
  *len = (l[0] + l[1] + l[2]) / 3.0;
  *bx = T(0.0);
  *bz = T(0.0);
  for (int k = 0; k < 3; ++k) {
    const double psi = (180.0 + 120.0 * k) * kPi / 180.0;
    *bx += l[k] * std::cos(psi);
    *bz += l[k] * std::sin(psi);
  }
  const T s = -2.0 / (3.0 * *len * p.offset);
  *bx *= s;
  *bz *= s;
}

template <typename T>
void TipT(const PccChamberParams& p, const T* c, T* out) {
  T bx, bz, l;
  BendingVector(p, c, &bx, &bz, &l);
  const T t = (bx * bx + bz * bz) * l * l;
  T g, h;
  ArcGH(t, &g, &h);
  const T ex = bx * l * l * g, ez = bz * l * l * g, ey = p.base + l * h;  // arc end
  const T tx = bx * l * h, tz = bz * l * h, ty = 1.0 - t * g;             // unit end tangent
  out[0] = ex + p.cap * tx;
  out[1] = ey + p.cap * ty;
  out[2] = ez + p.cap * tz;
}

}  // namespace

bool PccChamberParams::IsValid(std::string* why) const {
  std::ostringstream s;
  auto fin = [](double v) { return std::isfinite(v); };
  if (!(fin(base) && base >= 0))
    s << "base must be >= 0 mm";
  else if (!(fin(chamber_length) && chamber_length > 0))
    s << "chamber_length must be > 0 mm";
  else if (!(fin(cap) && cap >= 0))
    s << "cap must be >= 0 mm";
  else if (!(fin(offset) && offset > 0))
    s << "offset must be > 0 mm";
  else if (!(fin(gain) && gain > 0))
    s << "gain must be > 0";
  else if (!(fin(lower) && fin(upper) && lower < upper))
    s << "lower < upper expected";
  else if (!(rest >= lower && rest <= upper))
    s << "rest must lie in [lower, upper]";
  else if (!(1.0 + gain * (lower - 1.0) > 0))
    s << "gain and lower give a chamber of length <= 0";
  if (why) *why = s.str();
  return s.str().empty();
}

PccChamberKinematics::PccChamberKinematics(const PccChamberParams& params) : params_(params) {
  std::string why;
  if (!params_.IsValid(&why)) throw std::invalid_argument("PccChamberParams: " + why);
  lower_ = Eigen::VectorXd::Constant(3, params_.lower);
  upper_ = Eigen::VectorXd::Constant(3, params_.upper);
}

Eigen::Vector3d PccChamberKinematics::Tip(const PccChamberParams& params,
                                          const Eigen::Vector3d& c) {
  Eigen::Vector3d p;
  TipT<double>(params, c.data(), p.data());
  return p;
}

PccArc PccChamberKinematics::ArcParameters(const Eigen::Ref<const Eigen::VectorXd>& c) const {
  const Eigen::Vector3d cc = c.head<3>();
  double bx, bz, l;
  BendingVector<double>(params_, cc.data(), &bx, &bz, &l);
  PccArc a;
  a.kappa = std::hypot(bx, bz);
  a.phi = a.kappa > 0 ? std::atan2(bz, bx) : 0.0;
  a.length = l;
  return a;
}

KinematicsEval PccChamberKinematics::Evaluate(const Eigen::Ref<const Eigen::VectorXd>& c,
                                              bool with_jacobian) {
  const auto t0 = std::chrono::steady_clock::now();
  KinematicsEval e;
  e.message = CheckKinematicsInput(*this, c);
  if (!e.message.empty()) return e;
  ++evaluations_;
  e.fk_solves = 1;
  e.p.resize(1, 3);
  if (with_jacobian) {
    using Jet = ceres::Jet<double, 3>;
    Jet cj[3], pj[3];
    for (int a = 0; a < 3; ++a) cj[a] = Jet(c[a], a);
    TipT<Jet>(params_, cj, pj);
    e.J.resize(3, 3);
    for (int d = 0; d < 3; ++d) {
      e.p(0, d) = pj[d].a;
      e.J.row(d) = pj[d].v.transpose();
    }
  } else {
    const Eigen::Vector3d p = Tip(params_, c.head<3>());
    e.p.row(0) = p.transpose();
  }
  e.ok = e.p.allFinite() && (!with_jacobian || e.J.allFinite());
  if (!e.ok) e.message = "non-finite PCC tip";
  e.time_s = SecondsSince(t0);
  return e;
}

PccFitResult FitPccChamber(const Eigen::Ref<const Eigen::MatrixXd>& C,
                           const Eigen::Ref<const Eigen::MatrixXd>& P,
                           const PccChamberParams& start) {
  if (C.rows() != P.rows() || C.cols() != 3 || P.cols() != 3)
    throw std::invalid_argument(
        "FitPccChamber: expected n x 3 actuations and n x 3 tip positions, got " +
        std::to_string(C.rows()) + " x " + std::to_string(C.cols()) + " and " +
        std::to_string(P.rows()) + " x " + std::to_string(P.cols()));
  if (C.rows() < 3) throw std::invalid_argument("FitPccChamber: at least 3 samples are needed");
  if (!C.allFinite() || !P.allFinite())
    throw std::invalid_argument("FitPccChamber: non-finite data");
  std::string why;
  if (!start.IsValid(&why)) throw std::invalid_argument("FitPccChamber: start: " + why);
  const int n = static_cast<int>(C.rows());
  auto with = [&start](const Eigen::Vector3d& q) {
    PccChamberParams p = start;
    p.gain = q[0];
    p.offset = q[1];
    p.cap = q[2];
    return p;
  };
  auto residuals = [&](const Eigen::Vector3d& q, Eigen::VectorXd* r) {
    const PccChamberParams p = with(q);
    r->resize(3 * n);
    for (int i = 0; i < n; ++i)
      r->segment<3>(3 * i) =
          PccChamberKinematics::Tip(p, C.row(i).transpose()) - P.row(i).transpose();
  };
  Eigen::Vector3d q(start.gain, start.offset, start.cap);
  Eigen::VectorXd r;
  residuals(q, &r);
  PccFitResult out;
  out.rms_start_mm = std::sqrt(r.squaredNorm() / n);
  double cost = r.squaredNorm(), mu = 1e-3;
  // The tip moves by about its own length over the box, so the cost is far from quadratic in the
  // gain and offset (the bending angle wraps): a coarse scan picks the basin first.
  for (int i = 0; i <= 40; ++i)
    for (double f : {0.6, 0.8, 1.0, 1.25, 1.6}) {
      const Eigen::Vector3d qs(start.gain * std::pow(10.0, -1.0 + 1.5 * i / 40.0), start.offset * f,
                               start.cap);
      if (!with(qs).IsValid(nullptr)) continue;
      Eigen::VectorXd rs;
      residuals(qs, &rs);
      if (rs.allFinite() && rs.squaredNorm() < cost) {
        cost = rs.squaredNorm();
        q = qs;
        r = rs;
      }
    }
  for (int it = 0; it < 100; ++it) {
    Eigen::MatrixXd J(3 * n, 3);  // central differences in the 3 parameters
    for (int k = 0; k < 3; ++k) {
      const double h = 1e-6 * std::max(1.0, std::abs(q[k]));
      Eigen::Vector3d qp = q, qm = q;
      qp[k] += h;
      qm[k] -= h;
      Eigen::VectorXd rp, rm;
      residuals(qp, &rp);
      residuals(qm, &rm);
      J.col(k) = (rp - rm) / (2 * h);
    }
    const Eigen::Matrix3d H = J.transpose() * J;
    const Eigen::Vector3d gr = J.transpose() * r;
    bool accepted = false;
    while (mu < 1e12) {
      Eigen::Matrix3d A = H;
      A.diagonal() += mu * H.diagonal().cwiseMax(1e-12);
      const Eigen::Vector3d dq = -A.ldlt().solve(gr);
      const Eigen::Vector3d qn = q + dq;
      if (with(qn).IsValid(nullptr)) {
        Eigen::VectorXd rn;
        residuals(qn, &rn);
        if (rn.allFinite() && rn.squaredNorm() < cost) {
          const double rel = (cost - rn.squaredNorm()) / cost;
          q = qn;
          r = rn;
          cost = rn.squaredNorm();
          mu = std::max(mu * 0.1, 1e-12);
          accepted = true;
          out.iterations = it + 1;
          if (rel < 1e-14) it = 100;
          break;
        }
      }
      mu *= 10;
    }
    if (!accepted || gr.norm() < 1e-12) break;
  }
  out.params = with(q);
  out.rms_mm = std::sqrt(cost / n);
  return out;
}

}  // namespace softkin
