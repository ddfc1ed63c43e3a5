#pragma once
/// \file actuation.hpp
/// Geometry of the actuation elements of Sec. 2.3.3: the quantity each actuator type constrains,
/// measured per element, and the reshaping of an element's rest shape by its local ratio.
///
///   type       measure m_i(X)                              rest shape reshaped by S(r_i)
///   pneumatic  volume Vol_i                                 cbrt(alpha_i) I (Eq. 2.8) cable l_i
///   |F_i d_i|: its share l_i of the cable    I - (1 - s_i) d d^T              (Eq. 2.6)
///              length, stretched along the cable direction d
///              (F_i: the element's best-fit deformation gradient)
///   dea        (area(bottom) + area(top)) / 2 of the prism  sqrt(lambda_i) (I - n n^T) (Eq. 2.7)
///                                                             + n n^T / lambda_i
///
/// S acts on the centred rest rows (rows P S^T); the reshaped shape is then rotated onto the
/// current one (targets.hpp). For DEA, n is the prism's rest normal (the mean of its two triangle
/// normals): the triangles scale by sqrt(lambda) in their plane about their own centroids and the
/// thickness by 1 / lambda, so the volume is kept. For the cable, d is the cable's direction at
/// the element (element_geometry of the path, model.cpp).
///
/// The local ratios r_i follow the current measures (Sec. 2.3.3, "proportionally to the ratios of
/// an element's current shape w.r.t. its rest shape"): r_i = kappa m_i / mu_i with mu_i = m_i(rest)
/// and kappa chosen so that the actuator's constraint holds exactly:
///   c (M + L_R) - L_R = sum_i r_i mu_i,   M = sum_i mu_i,
/// where L_R is the cable length outside actuation elements (0 for pneumatic and DEA). This is the
/// least-norm solution of the constraint among ratios proportional to m_i / mu_i.
#include "softkin/solver/mesh/element_geometry.hpp"

#include <Eigen/Dense>

namespace softkin {

struct ModelElement;

/// m_i for actuation element e at centred (or uncentred) rows D. Not for body elements.
double ActuationMeasure(const ModelElement& e, const ElemRows& D);
/// dm_i / dD (first k rows), D centred.
ElemRows ActuationMeasureGradient(const ModelElement& e, const ElemRows& D);
/// S(r) for element e (3 x 3, acts on rest rows as P S^T).
Eigen::Matrix3d ActuationShape(const ModelElement& e, double ratio);
/// dS/dr.
Eigen::Matrix3d ActuationShapeDerivative(const ModelElement& e, double ratio);

/// Area of the triangle (a, b, c) and its gradient with respect to a, b, c.
double TriangleArea(const Eigen::RowVector3d& a, const Eigen::RowVector3d& b,
                    const Eigen::RowVector3d& c);
/// Unit normal of the prism's rest triangles (mean of the bottom and top normals, oriented from
/// the bottom triangle towards the top one).
Eigen::Vector3d PrismNormal(const ElemRows& P);

}  // namespace softkin
