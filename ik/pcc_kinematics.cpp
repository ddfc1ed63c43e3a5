#include "softkin/ik/pcc_kinematics.hpp"
#include "softkin/solver/common/stopwatch.hpp"

#include <chrono>
#include <cmath>
#include <sstream>
#include <stdexcept>

namespace softkin {
namespace {

// g(t) = (1 - cos x)/x^2 and h(t) = sin(x)/x with x = sqrt(t), and their derivatives in t.
struct ArcFns {
  double g, dg, h, dh;
};

ArcFns Arc(double t) {
  ArcFns f;
  if (t < 0.1) {  // Taylor series; the first omitted term is below 1e-13
    f.g = 0.5 + t * (-1.0 / 24 + t * (1.0 / 720 + t * (-1.0 / 40320 + t * (1.0 / 3628800))));
    f.dg = -1.0 / 24 +
           t * (2.0 / 720 + t * (-3.0 / 40320 + t * (4.0 / 3628800 - t * 5.0 / 479001600)));
    f.h = 1.0 + t * (-1.0 / 6 + t * (1.0 / 120 + t * (-1.0 / 5040 + t * (1.0 / 362880))));
    f.dh = -1.0 / 6 + t * (2.0 / 120 + t * (-3.0 / 5040 + t * (4.0 / 362880 - t * 5.0 / 39916800)));
    return f;
  }
  const double x = std::sqrt(t), s = std::sin(x), c = std::cos(x);
  f.g = (1.0 - c) / t;
  f.dg = s / (2.0 * x * t) - (1.0 - c) / (t * t);
  f.h = s / x;
  f.dh = (x * c - s) / (2.0 * x * t);
  return f;
}

}  // namespace

bool PccParams::IsValid(std::string* why) const {
  std::ostringstream s;
  if (!(std::isfinite(length) && length > 0))
    s << "length must be > 0";
  else if (!(std::isfinite(cable_offset) && cable_offset > 0))
    s << "cable_offset must be > 0";
  else if (!(std::isfinite(max_pull) && max_pull > 0))
    s << "max_pull must be > 0";
  else if (axial && !(max_pull < length))
    s << "max_pull must be < length (the backbone would vanish)";
  else if (backbone_points < 1)
    s << "backbone_points must be >= 1";
  if (why) *why = s.str();
  return s.str().empty();
}

PccKinematics::PccKinematics(const PccParams& params) : params_(params) {
  std::string why;
  if (!params_.IsValid(&why)) throw std::invalid_argument("PccParams: " + why);
  names_.push_back("tip");
  for (int j = 0; j < params_.backbone_points; ++j)
    names_.push_back("backbone[" + std::to_string(j) + "]");
  lower_ = Eigen::VectorXd::Zero(3);
  upper_ = Eigen::VectorXd::Constant(3, params_.max_pull);
}

double PccKinematics::Curvature(const Eigen::Ref<const Eigen::VectorXd>& c) const {
  const double k = 2.0 / (3.0 * params_.cable_offset * params_.length);
  Eigen::Vector2d b = Eigen::Vector2d::Zero();
  for (int i = 0; i < 3; ++i) {
    const double psi = 2.0 * M_PI * i / 3.0;
    b += k * c[i] * Eigen::Vector2d(std::cos(psi), std::sin(psi));
  }
  return b.norm();
}

KinematicsEval PccKinematics::Evaluate(const Eigen::Ref<const Eigen::VectorXd>& c,
                                       bool with_jacobian) {
  const auto t0 = std::chrono::steady_clock::now();
  KinematicsEval e;
  e.message = CheckKinematicsInput(*this, c);
  if (!e.message.empty()) return e;
  ++evaluations_;
  e.fk_solves = 1;

  const double L = params_.length, a = params_.axial ? 1.0 : 0.0;
  const double k = 2.0 / (3.0 * params_.cable_offset * L);
  Eigen::Matrix<double, 2, 3> db_dc;  // db/dc
  for (int i = 0; i < 3; ++i) {
    const double psi = 2.0 * M_PI * i / 3.0;
    db_dc.col(i) = k * Eigen::Vector2d(std::cos(psi), std::sin(psi));
  }
  const Eigen::Vector2d b = db_dc * c;
  const double s = L - a * c.sum() / 3.0;
  const Eigen::RowVector3d ds_dc = Eigen::RowVector3d::Constant(-a / 3.0);
  const double bb = b.squaredNorm();

  const int np = num_points();
  e.p.resize(np, 3);
  if (with_jacobian) e.J.setZero(3 * np, 3);
  for (int r = 0; r < np; ++r) {
    const double frac = r == 0 ? 1.0 : static_cast<double>(r) / params_.backbone_points;
    const double sig = s * frac, t = bb * sig * sig;
    const ArcFns f = Arc(t);
    e.p.row(r) << b.x() * sig * sig * f.g, b.y() * sig * sig * f.g, sig * f.h;
    if (!with_jacobian) continue;
    // Partial derivatives in (b, sigma), then the chain rule to c.
    const Eigen::Matrix2d dxy_db =
        sig * sig *
        (f.g * Eigen::Matrix2d::Identity() + 2.0 * f.dg * sig * sig * b * b.transpose());
    const Eigen::Vector2d dxy_dsig = b * sig * (2.0 * f.g + 2.0 * t * f.dg);
    const Eigen::RowVector2d dz_db = 2.0 * sig * sig * sig * f.dh * b.transpose();
    const double dz_dsig = f.h + 2.0 * t * f.dh;
    const Eigen::RowVector3d dsig_dc = frac * ds_dc;
    e.J.block<2, 3>(3 * r, 0) = dxy_db * db_dc + dxy_dsig * dsig_dc;
    e.J.block<1, 3>(3 * r + 2, 0) = dz_db * db_dc + dz_dsig * dsig_dc;
  }
  e.ok = true;
  e.time_s = SecondsSince(t0);
  return e;
}

}  // namespace softkin
