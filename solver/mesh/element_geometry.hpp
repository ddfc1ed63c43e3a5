#pragma once
/// \file element_geometry.hpp
/// Small fixed-size helpers on one element's k x 3 vertex rows (k = 4 tet, 6 prism); no heap use.
#include <Eigen/Dense>

namespace softkin {

/// Row-major storage for up to 6 vertex rows (a tet uses the first 4).
using ElemRows = Eigen::Matrix<double, 6, 3>;

inline double TetVolume6(const Eigen::RowVector3d& a, const Eigen::RowVector3d& b,
                         const Eigen::RowVector3d& c, const Eigen::RowVector3d& d) {
  return (b - a).cross(c - a).dot(d - a);
}

/// Signed volume of a tet (k = 4) or prism (k = 6, bottom 0-1-2, top 3-4-5, split into the tets
/// (0,1,2,5), (0,1,5,4), (0,4,5,3)), mm^3.
inline double RowsVolume(const ElemRows& P, int k) {
  if (k == 4) return TetVolume6(P.row(0), P.row(1), P.row(2), P.row(3)) / 6.0;
  return (TetVolume6(P.row(0), P.row(1), P.row(2), P.row(5)) +
          TetVolume6(P.row(0), P.row(1), P.row(5), P.row(4)) +
          TetVolume6(P.row(0), P.row(4), P.row(5), P.row(3))) /
         6.0;
}

/// Subtracts the centroid of the first k rows (the operator N of Eq. 2.2) in place.
inline void CenterRows(ElemRows& P, int k) {
  Eigen::RowVector3d c = P.topRows(k).colwise().sum() / double(k);
  for (int j = 0; j < k; ++j) P.row(j) -= c;
  for (int j = k; j < 6; ++j) P.row(j).setZero();
}

}  // namespace softkin

namespace softkin {

/// Adds s * d(vol of tet a,b,c,d)/d(rows) into G at rows (ia, ib, ic, id).
inline void AddTetVolumeGradient(const ElemRows& P, int ia, int ib, int ic, int id, double s,
                                 ElemRows* G) {
  const Eigen::RowVector3d a = P.row(ia), b = P.row(ib), c = P.row(ic), d = P.row(id);
  const Eigen::RowVector3d gb = (c - a).cross(d - a) / 6.0;
  const Eigen::RowVector3d gc = (d - a).cross(b - a) / 6.0;
  const Eigen::RowVector3d gd = (b - a).cross(c - a) / 6.0;
  G->row(ib) += s * gb;
  G->row(ic) += s * gc;
  G->row(id) += s * gd;
  G->row(ia) -= s * (gb + gc + gd);
}

/// Gradient of RowsVolume(P, k) with respect to the rows of P (first k rows of G).
inline ElemRows RowsVolumeGradient(const ElemRows& P, int k) {
  ElemRows G = ElemRows::Zero();
  if (k == 4) {
    AddTetVolumeGradient(P, 0, 1, 2, 3, 1.0, &G);
  } else {
    AddTetVolumeGradient(P, 0, 1, 2, 5, 1.0, &G);
    AddTetVolumeGradient(P, 0, 1, 5, 4, 1.0, &G);
    AddTetVolumeGradient(P, 0, 4, 5, 3, 1.0, &G);
  }
  return G;
}

}  // namespace softkin
