#include "solver/spring_system.hpp"

#include <cholmod.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <stdexcept>
#include <string>

namespace softkin {

namespace {
using Clock = std::chrono::steady_clock;
double Since(Clock::time_point t0) {
  return std::chrono::duration<double>(Clock::now() - t0).count();
}
}  // namespace

struct SpringSystem::Impl {
  cholmod_common cm;
  /// Per model factorisation: our (modifiable) factor, the free index map of its axes, and the
  /// inverse of the fill-reducing permutation (updates are given in the permuted order).
  struct Factor {
    cholmod_factor* L = nullptr;
    const std::vector<int>* free_index = nullptr;
    std::vector<int> inv_perm;
    int n = 0;
  };
  std::vector<Factor> factors;
  std::vector<int> axes_of_factor_first;  // one axis per factor
  Impl() { cholmod_start(&cm); }
  ~Impl() {
    for (auto& f : factors)
      if (f.L) cholmod_free_factor(&f.L, &cm);
    cholmod_finish(&cm);
  }
};

SpringSystem::SpringSystem(const Model& model, Method method)
    : model_(model), method_(method), impl_(std::make_unique<Impl>()) {
  auto& cm = impl_->cm;
  for (int f = 0; f < model.num_factors(); ++f) {
    Impl::Factor F;
    const cholmod_factor* src = model.factorization(f).factor();
    if (!src) throw std::runtime_error("spring system: the model has no numeric factor");
    F.L = cholmod_copy_factor(const_cast<cholmod_factor*>(src), &cm);
    if (!F.L) throw std::runtime_error("spring system: CHOLMOD could not copy the factor");
    int axis = 0;
    while (model.factor_of_axis(axis) != f) ++axis;
    F.free_index = &model.free_index(axis);
    F.n = static_cast<int>(F.L->n);
    F.inv_perm.assign(F.n, 0);
    const int* perm = static_cast<const int*>(F.L->Perm);
    for (int i = 0; i < F.n; ++i) F.inv_perm[perm[i]] = i;
    impl_->factors.push_back(std::move(F));
    impl_->axes_of_factor_first.push_back(axis);
  }
  refactor_after_ = std::max<long>(64, model.num_free_dofs() / 12);  // ~ a quarter of one axis
}

SpringSystem::~SpringSystem() = default;

bool SpringSystem::Modify(const std::vector<int>& verts, bool add) {
  if (verts.empty()) return false;
  auto& cm = impl_->cm;
  const double s = std::sqrt(k_);
  for (auto& F : impl_->factors) {
    // C: n x r, one entry sqrt(k) per column, in the factor's permuted row order (L D L^T is
    // the factor of P A P^T, so the update of A by c c^T is P c (P c)^T).
    std::vector<int> rows;
    rows.reserve(verts.size());
    for (int v : verts) {
      const int i = (*F.free_index)[v];
      if (i >= 0) rows.push_back(F.inv_perm[i]);
    }
    if (rows.empty()) continue;
    const int r = static_cast<int>(rows.size());
    cholmod_sparse* C = cholmod_allocate_sparse(F.n, r, r, /*sorted=*/1, /*packed=*/1,
                                                /*stype=*/0, CHOLMOD_REAL, &cm);
    if (!C) throw std::runtime_error("spring system: CHOLMOD out of memory");
    int* Cp = static_cast<int*>(C->p);
    int* Ci = static_cast<int*>(C->i);
    double* Cx = static_cast<double*>(C->x);
    for (int j = 0; j < r; ++j) {
      Cp[j] = j;
      Ci[j] = rows[j];
      Cx[j] = s;
    }
    Cp[r] = r;
    const auto t0 = Clock::now();
    const int ok = cholmod_updown(add ? 1 : 0, C, F.L, &cm);
    stats_.update_s += Since(t0);
    cholmod_free_sparse(&C, &cm);
    stats_.columns_updated += r;
    since_refactor_ += r;
    if (!ok || cm.status != CHOLMOD_OK) {
      // A downdate that lost positive definiteness to round-off: start over from A_ff + K.
      Refactor();
      return true;
    }
  }
  return false;
}

void SpringSystem::Refactor() {
  auto& cm = impl_->cm;
  for (size_t f = 0; f < impl_->factors.size(); ++f) {
    auto& F = impl_->factors[f];
    const Eigen::SparseMatrix<double>& Aff = model_.A_ff(impl_->axes_of_factor_first[f]);
    // Lower triangle of A_ff + K as a CHOLMOD symmetric matrix.
    Eigen::SparseMatrix<double> M = Aff.triangularView<Eigen::Lower>();
    for (int v : vertices_) {
      const int i = (*F.free_index)[v];
      if (i >= 0) M.coeffRef(i, i) += k_;
    }
    M.makeCompressed();
    cholmod_sparse A{};
    A.nrow = A.ncol = M.rows();
    A.nzmax = M.nonZeros();
    A.p = M.outerIndexPtr();
    A.i = M.innerIndexPtr();
    A.x = M.valuePtr();
    A.stype = -1;
    A.itype = CHOLMOD_INT;
    A.xtype = CHOLMOD_REAL;
    A.dtype = CHOLMOD_DOUBLE;
    A.sorted = 1;
    A.packed = 1;
    const auto t0 = Clock::now();
    const int ok = cholmod_factorize(&A, F.L, &cm);
    stats_.refactor_s += Since(t0);
    if (!ok || cm.status != CHOLMOD_OK)
      throw std::runtime_error("spring system: CHOLMOD could not factor A_ff + K (status " +
                               std::to_string(cm.status) + ")");
  }
  ++stats_.refactors;
  since_refactor_ = 0;
}

bool SpringSystem::SetSprings(const std::vector<int>& vertices, double k) {
  if (!(k > 0) || !std::isfinite(k))
    throw std::invalid_argument("spring system: expected a finite stiffness k > 0");
  std::vector<int> next = vertices;
  std::sort(next.begin(), next.end());
  next.erase(std::unique(next.begin(), next.end()), next.end());
  if (vertices_.empty()) k_ = k;  // no spring yet: nothing in the factor depends on k
  if (k != k_) {
    // A new stiffness changes every spring's entry: recompute the factor from A_ff + K.
    k_ = k;
    vertices_ = next;
    ++stats_.changes;
    Refactor();
    return true;
  }
  if (next == vertices_) return false;
  std::vector<int> added, removed;
  std::set_difference(next.begin(), next.end(), vertices_.begin(), vertices_.end(),
                      std::back_inserter(added));
  std::set_difference(vertices_.begin(), vertices_.end(), next.begin(), next.end(),
                      std::back_inserter(removed));
  vertices_ = next;
  ++stats_.changes;
  if (method_ == Method::kRefactor ||
      (refactor_after_ > 0 && since_refactor_ + long(added.size() + removed.size()) > refactor_after_)) {
    Refactor();
    return true;
  }
  // Updates before downdates keeps every intermediate matrix positive definite.
  if (Modify(added, true)) return true;  // fell back to a refactorisation of A_ff + K
  Modify(removed, false);
  return true;
}

Eigen::VectorXd SpringSystem::Solve(const Eigen::VectorXd& rhs) const {
  const auto t0 = Clock::now();
  auto& cm = impl_->cm;
  Eigen::VectorXd y(rhs.size());
  auto solve_block = [&](const Impl::Factor& F, const double* b, int ncol, double* out) {
    cholmod_dense B{};
    B.nrow = F.n;
    B.ncol = ncol;
    B.nzmax = static_cast<size_t>(F.n) * ncol;
    B.d = F.n;
    B.x = const_cast<double*>(b);
    B.xtype = CHOLMOD_REAL;
    B.dtype = CHOLMOD_DOUBLE;
    cholmod_dense* X = cholmod_solve(CHOLMOD_A, F.L, &B, &cm);
    if (!X) throw std::runtime_error("spring system: CHOLMOD solve failed");
    std::copy_n(static_cast<const double*>(X->x), static_cast<size_t>(F.n) * ncol, out);
    cholmod_free_dense(&X, &cm);
  };
  const int f0 = model_.factor_of_axis(0);
  if (f0 == model_.factor_of_axis(1) && f0 == model_.factor_of_axis(2)) {
    solve_block(impl_->factors[f0], rhs.data(), 3, y.data());
  } else {
    for (int d = 0; d < 3; ++d) {
      const int off = model_.free_offset(d);
      solve_block(impl_->factors[model_.factor_of_axis(d)], rhs.data() + off, 1, y.data() + off);
    }
  }
  stats_.solve_s += Since(t0);
  ++stats_.solves;
  return y;
}

Eigen::VectorXd SpringSystem::Multiply(const Eigen::VectorXd& x) const {
  Eigen::VectorXd y(x.size());
  for (int d = 0; d < 3; ++d) {
    const int off = model_.free_offset(d);
    const int n = model_.free_offset(d + 1) - off;
    y.segment(off, n) = model_.A_ff(d) * x.segment(off, n);
    for (int v : vertices_) {
      const int i = model_.free_index(d)[v];
      if (i >= 0) y[off + i] += k_ * x[off + i];
    }
  }
  return y;
}

}  // namespace softkin
