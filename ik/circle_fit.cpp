#include "softkin/ik/circle_fit.hpp"

#include <Eigen/Dense>

#include <cmath>
#include <sstream>

namespace softkin {
namespace {

// An orthonormal pair (e1, e2) perpendicular to the unit vector n.
void PlaneBasis(const Eigen::Vector3d& n, Eigen::Vector3d* e1, Eigen::Vector3d* e2) {
  Eigen::Vector3d a = std::abs(n.x()) < 0.9 ? Eigen::Vector3d::UnitX() : Eigen::Vector3d::UnitY();
  *e1 = (a - n.dot(a) * n).normalized();
  *e2 = n.cross(*e1);
}

}  // namespace

CircleFit FitCircle(const Eigen::Ref<const Eigen::MatrixX3d>& points,
                    const Eigen::Vector3d& plane_normal, bool with_derivative) {
  CircleFit out;
  const int n_pts = static_cast<int>(points.rows());
  if (n_pts < 3) {
    out.message = "circle fit needs at least 3 points, got " + std::to_string(n_pts);
    return out;
  }
  if (!points.allFinite()) {
    out.message = "circle fit: a point is not finite";
    return out;
  }
  const Eigen::RowVector3d m = points.colwise().mean();
  const Eigen::MatrixX3d y = points.rowwise() - m;  // centred points

  // 1. The plane: given, or the least-squares plane of the points.
  Eigen::Vector3d n, e1, e2;
  Eigen::Vector3d lambda = Eigen::Vector3d::Zero();  // scatter eigenvalues, ascending
  const bool fit_plane = plane_normal.squaredNorm() == 0.0;
  if (!plane_normal.allFinite()) {
    out.message = "circle fit: the plane normal is not finite";
    return out;
  }
  if (fit_plane) {
    const Eigen::Matrix3d C = y.transpose() * y;
    Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> es(C);
    lambda = es.eigenvalues();
    if (!(lambda[1] - lambda[0] > 1e-10 * lambda[2])) {
      out.message = "circle fit: the points do not span a plane (scatter eigenvalues " +
                    std::to_string(lambda[0]) + ", " + std::to_string(lambda[1]) + ", " +
                    std::to_string(lambda[2]) + ")";
      return out;
    }
    n = es.eigenvectors().col(0);
    e1 = es.eigenvectors().col(1);
    e2 = es.eigenvectors().col(2);
  } else {
    n = plane_normal.normalized();
    PlaneBasis(n, &e1, &e2);
  }
  Eigen::Matrix<double, 3, 2> E;
  E << e1, e2;

  // 2. In-plane coordinates, scaled to unit RMS for conditioning (the Kasa fit is equivariant
  // under scaling, so r = scale * r~ exactly and dr/du = dr~/du~).
  Eigen::MatrixX2d u = y * E;
  const double scale = std::sqrt(u.squaredNorm() / n_pts);
  if (!(scale > 0.0)) {
    out.message = "circle fit: all points coincide in the plane";
    return out;
  }
  u /= scale;
  {
    const Eigen::Matrix2d cov = u.transpose() * u;
    Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d> es2(cov);
    if (!(es2.eigenvalues()[0] > 1e-12 * es2.eigenvalues()[1])) {
      out.message = "circle fit: the points are collinear in the circle's plane";
      return out;
    }
  }

  // 3. Kasa fit: [u_x u_y 1] theta = -(u_x^2 + u_y^2) in the least-squares sense.
  Eigen::MatrixX3d A(n_pts, 3);
  A.col(0) = u.col(0);
  A.col(1) = u.col(1);
  A.col(2).setOnes();
  const Eigen::VectorXd b = -u.rowwise().squaredNorm();
  const Eigen::Matrix3d M = A.transpose() * A;
  Eigen::LDLT<Eigen::Matrix3d> ldlt(M);
  if (ldlt.info() != Eigen::Success || !(ldlt.rcond() > 1e-14)) {
    out.message = "circle fit: singular least-squares system";
    return out;
  }
  const Eigen::Vector3d theta = ldlt.solve(A.transpose() * b);
  const double r2 = 0.25 * (theta[0] * theta[0] + theta[1] * theta[1]) - theta[2];
  if (!(r2 > 0.0) || !std::isfinite(r2)) {
    out.message = "circle fit: no real circle (r^2 = " + std::to_string(r2) + ")";
    return out;
  }
  const double rt = std::sqrt(r2);  // radius in scaled coordinates
  const Eigen::Vector2d c2(-0.5 * theta[0], -0.5 * theta[1]);

  out.ok = true;
  out.normal = n;
  out.radius = scale * rt;
  out.diameter = 2.0 * out.radius;
  out.center = m.transpose() + E * (scale * c2);
  double ss = 0.0;
  for (int i = 0; i < n_pts; ++i) {
    const double d = scale * ((u.row(i).transpose() - c2).norm() - rt);
    ss += d * d;
  }
  out.rms_residual = std::sqrt(ss / n_pts);
  if (!with_derivative) return out;

  // Reverse mode through the least-squares solve: w = dr/dtheta, s = M^-1 w, q = A s,
  // dr/du_i = res_i s_xy - q_i (theta_xy + 2 u_i).
  const Eigen::Vector3d w(theta[0] / (4.0 * rt), theta[1] / (4.0 * rt), -1.0 / (2.0 * rt));
  const Eigen::Vector3d s = ldlt.solve(w);
  const Eigen::VectorXd res = b - A * theta;
  const Eigen::VectorXd q = A * s;
  Eigen::MatrixX2d g(n_pts, 2);  // dr/du_i (unscaled u; see the note above)
  for (int i = 0; i < n_pts; ++i)
    g.row(i) =
        res[i] * s.head<2>().transpose() - q[i] * (theta.head<2>().transpose() + 2.0 * u.row(i));

  // Into 3D: u_i = E^T (x_i - m).
  Eigen::MatrixX3d dr = g * E.transpose();
  dr.rowwise() -= g.colwise().sum() * E.transpose() / n_pts;  // through m (zero in exact math)
  if (fit_plane) {
    // Tilt of the plane: de_k = n (n^T dC e_k) / (lambda_k - lambda_0), k = 1, 2.
    const Eigen::Vector3d G1 = y.transpose() * g.col(0), G2 = y.transpose() * g.col(1);
    const double a1 = G1.dot(n) / (lambda[1] - lambda[0]);
    const double a2 = G2.dot(n) / (lambda[2] - lambda[0]);
    for (int i = 0; i < n_pts; ++i) {
      const Eigen::Vector3d yi = y.row(i).transpose();
      const double yn = yi.dot(n);
      dr.row(i) += (a1 * (n * yi.dot(e1) + yn * e1) + a2 * (n * yi.dot(e2) + yn * e2)).transpose();
    }
  }
  out.d_diameter = 2.0 * dr;
  return out;
}

}  // namespace softkin
