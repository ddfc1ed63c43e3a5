#include "softkin/solver/fk/actuation.hpp"

#include "softkin/solver/fk/model.hpp"

#include <cmath>

namespace softkin {

double TriangleArea(const Eigen::RowVector3d& a, const Eigen::RowVector3d& b,
                    const Eigen::RowVector3d& c) {
  return 0.5 * (b - a).cross(c - a).norm();
}

namespace {

/// Adds s * d area(a, b, c) / d(rows ia, ib, ic) into G.
void AddTriangleAreaGradient(const ElemRows& P, int ia, int ib, int ic, double s, ElemRows* G) {
  const Eigen::RowVector3d a = P.row(ia), b = P.row(ib), c = P.row(ic);
  const Eigen::RowVector3d n2 = (b - a).cross(c - a);  // 2 * area * unit normal
  const double len = n2.norm();
  if (!(len > 0)) return;  // degenerate triangle: no defined gradient
  const Eigen::RowVector3d u = n2 / len;
  // d area / d c = 0.5 u x (b - a), and cyclically: the normal crossed with the opposite edge.
  G->row(ia) += s * 0.5 * u.cross(c - b);
  G->row(ib) += s * 0.5 * u.cross(a - c);
  G->row(ic) += s * 0.5 * u.cross(b - a);
}

/// F d for a cable element: D^T (Q d), with Q d precomputed in the model.
Eigen::Vector3d CableStretchVector(const ModelElement& e, const ElemRows& D) {
  Eigen::Vector3d v = Eigen::Vector3d::Zero();
  for (int j = 0; j < e.k; ++j) v += e.qd[j] * D.row(j).transpose();
  return v;
}

}  // namespace

Eigen::Vector3d PrismNormal(const ElemRows& P) {
  const Eigen::Vector3d nb = (P.row(1) - P.row(0)).cross(P.row(2) - P.row(0)).transpose();
  const Eigen::Vector3d nt = (P.row(4) - P.row(3)).cross(P.row(5) - P.row(3)).transpose();
  return (nb + nt).normalized();
}

double ActuationMeasure(const ModelElement& e, const ElemRows& D) {
  switch (e.role) {
    case ElementRole::Pneumatic:
      return RowsVolume(D, e.k);
    case ElementRole::Dea:
      return 0.5 * (TriangleArea(D.row(0), D.row(1), D.row(2)) +
                    TriangleArea(D.row(3), D.row(4), D.row(5)));
    case ElementRole::Cable: {
      // Translation invariant: sum_j qd_j = 0 because Q's rows come from centred rest rows.
      return e.measure0 * CableStretchVector(e, D).norm();
    }
    case ElementRole::Body:
      break;
  }
  return 0.0;
}

ElemRows ActuationMeasureGradient(const ModelElement& e, const ElemRows& D) {
  ElemRows G = ElemRows::Zero();
  switch (e.role) {
    case ElementRole::Pneumatic:
      return RowsVolumeGradient(D, e.k);
    case ElementRole::Dea:
      AddTriangleAreaGradient(D, 0, 1, 2, 0.5, &G);
      AddTriangleAreaGradient(D, 3, 4, 5, 0.5, &G);
      return G;
    case ElementRole::Cable: {
      const Eigen::Vector3d v = CableStretchVector(e, D);
      const double len = v.norm();
      if (!(len > 0)) return G;
      const Eigen::RowVector3d u = (v / len).transpose();
      for (int j = 0; j < e.k; ++j) G.row(j) = e.measure0 * e.qd[j] * u;
      return G;
    }
    case ElementRole::Body:
      break;
  }
  return G;
}

Eigen::Matrix3d ActuationShape(const ModelElement& e, double r) {
  const Eigen::Matrix3d I = Eigen::Matrix3d::Identity();
  switch (e.role) {
    case ElementRole::Pneumatic:
      return std::cbrt(r) * I;
    case ElementRole::Cable:
      return I - (1.0 - r) * e.axis * e.axis.transpose();
    case ElementRole::Dea: {
      const Eigen::Matrix3d nn = e.axis * e.axis.transpose();
      return std::sqrt(r) * (I - nn) + nn / r;
    }
    case ElementRole::Body:
      break;
  }
  return I;
}

Eigen::Matrix3d ActuationShapeDerivative(const ModelElement& e, double r) {
  const Eigen::Matrix3d I = Eigen::Matrix3d::Identity();
  switch (e.role) {
    case ElementRole::Pneumatic:
      return (std::cbrt(r) / (3.0 * r)) * I;
    case ElementRole::Cable:
      return e.axis * e.axis.transpose();
    case ElementRole::Dea: {
      const Eigen::Matrix3d nn = e.axis * e.axis.transpose();
      return (0.5 / std::sqrt(r)) * (I - nn) - nn / (r * r);
    }
    case ElementRole::Body:
      break;
  }
  return Eigen::Matrix3d::Zero();
}

}  // namespace softkin
