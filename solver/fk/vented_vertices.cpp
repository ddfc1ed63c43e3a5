/// \file vented_vertices.cpp
/// VentedVertices and PlaceVentedVertices (vented_vertices.hpp).
#include "softkin/solver/fk/vented_vertices.hpp"

#include "softkin/solver/fk/rotation.hpp"

#include <Eigen/SparseCholesky>

#include <algorithm>

namespace softkin {

namespace {

/// Local-global iterations of the as-rigid-as-possible fit, and its stopping move (of the model
/// size). finger_manipulator at s1 = 0.5 has 60, 525 and 2,450 such vertices at res 8, 12 and 16;
/// at res 16 the fit takes 29 iterations, 290 ms, under 1.2 % of its solve.
constexpr int kMaxIterations = 200;
constexpr double kMoveTolerance = 1e-10;

/// Per element: whether it is a vented actuation element at c.
std::vector<char> VentedElements(const Model& model, const Eigen::Ref<const Eigen::VectorXd>& c) {
  std::vector<char> vented(model.elements().size(), 0);
  for (int g = 0; g < model.num_groups(); ++g)
    if (model.GroupVented(g, c))
      for (int i : model.group_elements(g)) vented[i] = 1;
  return vented;
}

}  // namespace

std::vector<int> VentedVertices(const Model& model, const Eigen::Ref<const Eigen::VectorXd>& c) {
  const std::vector<char> vented = VentedElements(model, c);
  if (std::find(vented.begin(), vented.end(), 1) == vented.end()) return {};
  const int nv = model.num_vertices();
  // 1: only vented elements so far; 2: held by some other element.
  std::vector<char> state(nv, 0);
  const auto& els = model.elements();
  for (size_t i = 0; i < els.size(); ++i)
    for (int j = 0; j < els[i].k; ++j) {
      char& s = state[els[i].v[j]];
      s = vented[i] ? (s == 0 ? 1 : s) : 2;
    }
  std::vector<int> out;
  for (int v = 0; v < nv; ++v)
    if (state[v] == 1 && model.free_index(0)[v] >= 0 && model.free_index(1)[v] >= 0 &&
        model.free_index(2)[v] >= 0)
      out.push_back(v);
  return out;
}

void PlaceVentedVertices(const Model& model, const Eigen::Ref<const Eigen::VectorXd>& c,
                         Eigen::MatrixX3d* X) {
  if (model.num_groups() == 0 || X->rows() != model.num_vertices() || !X->allFinite()) return;
  const std::vector<int> inner = VentedVertices(model, c);
  if (inner.empty()) return;
  const int n = static_cast<int>(inner.size());
  std::vector<int> index(model.num_vertices(), -1);
  for (int q = 0; q < n; ++q) index[inner[q]] = q;
  // The elements that hold them (all vented).
  const auto& els = model.elements();
  std::vector<int> touching;
  {
    std::vector<char> seen(els.size(), 0);
    for (int u : inner)
      for (int p = model.incidence_offset()[u]; p < model.incidence_offset()[u + 1]; ++p) {
        const int i = model.incidence()[p] / 6;
        if (!seen[i]) touching.push_back(i);
        seen[i] = 1;
      }
  }
  // E = sum_e wv_e sum_j |d_j - t_j|^2 over those elements (d: centred current rows, t: the
  // centred rest rows rotated by the element's best rotation, as the local step of Eq. 2.10
  // fits). Its Hessian in the inner vertices, L = sum_e wv_e (I - 1/k) restricted to them, is the
  // same for x, y and z and does not change: factored once.
  std::vector<Eigen::Triplet<double>> trip;
  for (int i : touching) {
    const ModelElement& e = els[i];
    for (int a = 0; a < e.k; ++a)
      for (int b = 0; b < e.k; ++b)
        if (index[e.v[a]] >= 0 && index[e.v[b]] >= 0)
          trip.emplace_back(index[e.v[a]], index[e.v[b]],
                            e.wv * ((a == b ? 1.0 : 0.0) - 1.0 / e.k));
  }
  Eigen::SparseMatrix<double> L(n, n);
  L.setFromTriplets(trip.begin(), trip.end());
  const Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>> ldlt(L);
  if (ldlt.info() != Eigen::Success) return;  // a vented region that touches nothing else

  const double tolerance = kMoveTolerance * model.size();
  // One local-global step of the fit at Y: the correction of the inner vertices (n x 3), from half
  // the gradient of E with the rotations fitted at Y.
  auto step_at = [&](const Eigen::MatrixX3d& Y) -> Eigen::MatrixX3d {
    Eigen::MatrixX3d g = Eigen::MatrixX3d::Zero(n, 3);
    for (int i : touching) {
      const ModelElement& e = els[i];
      ElemRows D = ElemRows::Zero();
      for (int j = 0; j < e.k; ++j) D.row(j) = Y.row(e.v[j]);
      CenterRows(D, e.k);
      const Eigen::Matrix3d R = BestRotation(D.transpose() * e.rest);  // rows past k are zero
      const ElemRows r = D - e.rest * R.transpose();
      for (int j = 0; j < e.k; ++j)
        if (index[e.v[j]] >= 0) g.row(index[e.v[j]]) += e.wv * r.row(j);
    }
    return -ldlt.solve(g);
  };
  // Already placed (the default solver's inner solve, or newton's lg-aa fallback, has done it):
  // one step that moves nothing confirms it.
  {
    const Eigen::MatrixX3d step = step_at(*X);
    if (step.allFinite() && step.rowwise().norm().maxCoeff() <= tolerance) return;
  }
  // Start: the rest positions moved by the harmonic extension of the other vertices'
  // displacements (exact when nothing moved, and when everything translates), then local-global
  // iterations on the corrections, so that a state at rest stays at rest to round-off.
  Eigen::MatrixX3d Y = *X;
  Eigen::MatrixX3d rhs = Eigen::MatrixX3d::Zero(n, 3);
  for (int i : touching) {
    const ModelElement& e = els[i];
    for (int a = 0; a < e.k; ++a) {
      const int ra = index[e.v[a]];
      if (ra < 0) continue;
      for (int b = 0; b < e.k; ++b)
        if (index[e.v[b]] < 0)
          rhs.row(ra) -= e.wv * ((a == b ? 1.0 : 0.0) - 1.0 / e.k) *
                         (X->row(e.v[b]) - model.rest_positions().row(e.v[b]));
    }
  }
  const Eigen::MatrixX3d start = ldlt.solve(rhs);
  for (int q = 0; q < n; ++q) Y.row(inner[q]) = model.rest_positions().row(inner[q]) + start.row(q);
  for (int it = 0; it < kMaxIterations; ++it) {
    const Eigen::MatrixX3d step = step_at(Y);
    if (!step.allFinite()) return;
    for (int q = 0; q < n; ++q) Y.row(inner[q]) += step.row(q);
    if (step.rowwise().norm().maxCoeff() <= tolerance) break;
  }
  if (Y.allFinite()) *X = Y;
}

}  // namespace softkin
