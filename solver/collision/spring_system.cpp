#include "softkin/solver/collision/spring_system.hpp"
#include "softkin/solver/common/stopwatch.hpp"

#include <Eigen/Sparse>
#include <cholmod.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <iterator>
#include <stdexcept>
#include <string>
#include <utility>

namespace softkin {

namespace {
using Clock = std::chrono::steady_clock;
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
    bool own_pattern = false;  // analysed for A_ff + K with coupling springs (not A's pattern)
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

SpringStencil SpringStencil::Unit(int v) {
  SpringStencil s;
  s.vertex[0] = v;
  s.coef[0] = 1.0;
  return s;
}

SpringStencil SpringStencil::VertexFace(int v, const std::array<int, 3>& f,
                                        const Eigen::Vector3d& w) {
  SpringStencil s = Unit(v);
  for (int i = 0; i < 3; ++i) {
    s.vertex[i + 1] = f[i];
    s.coef[i + 1] = -w[i];
  }
  return s;
}

namespace {
/// The free entries (free index, coefficient) of stencil s under `free_index`, duplicates merged.
int FreeEntries(const SpringStencil& s, const std::vector<int>& free_index,
                std::array<std::pair<int, double>, 4>* out) {
  int n = 0;
  for (int j = 0; j < 4; ++j) {
    if (s.vertex[j] < 0 || s.coef[j] == 0.0) continue;
    const int i = free_index[s.vertex[j]];
    if (i < 0) continue;
    int q = 0;
    while (q < n && (*out)[q].first != i) ++q;
    if (q < n)
      (*out)[q].second += s.coef[j];
    else
      (*out)[n++] = {i, s.coef[j]};
  }
  return n;
}
}  // namespace

bool SpringSystem::Modify(const std::vector<SpringStencil>& springs, bool add) {
  if (springs.empty()) return false;
  auto& cm = impl_->cm;
  const double s = std::sqrt(k_);
  for (auto& F : impl_->factors) {
    // C: n x r, one column sqrt(k) c_s per spring, in the factor's permuted row order (L D L^T is
    // the factor of P A P^T, so the update of A by c c^T is P c (P c)^T).
    std::vector<int> Cp = {0}, Ci;
    std::vector<double> Cx;
    for (const auto& sp : springs) {
      std::array<std::pair<int, double>, 4> e;
      int n = FreeEntries(sp, *F.free_index, &e);
      for (int j = 0; j < n; ++j) e[j].first = F.inv_perm[e[j].first];
      std::sort(e.begin(), e.begin() + n);
      for (int j = 0; j < n; ++j) {
        Ci.push_back(e[j].first);
        Cx.push_back(s * e[j].second);
      }
      if (n > 0) Cp.push_back(static_cast<int>(Ci.size()));
    }
    const int r = static_cast<int>(Cp.size()) - 1;
    if (r == 0) continue;
    const int nnz = static_cast<int>(Ci.size());
    cholmod_sparse* C = cholmod_allocate_sparse(F.n, r, nnz, /*sorted=*/1, /*packed=*/1,
                                                /*stype=*/0, CHOLMOD_REAL, &cm);
    if (!C) throw std::runtime_error("spring system: CHOLMOD out of memory");
    std::copy(Cp.begin(), Cp.end(), static_cast<int*>(C->p));
    std::copy(Ci.begin(), Ci.end(), static_cast<int*>(C->i));
    std::copy(Cx.begin(), Cx.end(), static_cast<double*>(C->x));
    const auto t0 = Clock::now();
    const int ok = cholmod_updown(add ? 1 : 0, C, F.L, &cm);
    stats_.update_s += SecondsSince(t0);
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
    std::vector<Eigen::Triplet<double>> t;
    bool coupled = false;  // K has entries off the diagonal
    for (const auto& sp : springs_) {
      std::array<std::pair<int, double>, 4> e;
      const int n = FreeEntries(sp, *F.free_index, &e);
      for (int a = 0; a < n; ++a)
        for (int b = 0; b < n; ++b)
          if (e[a].first >= e[b].first) {
            t.emplace_back(e[a].first, e[b].first, k_ * e[a].second * e[b].second);
            coupled |= a != b;
          }
    }
    Eigen::SparseMatrix<double> K(Aff.rows(), Aff.cols());
    K.setFromTriplets(t.begin(), t.end());
    Eigen::SparseMatrix<double> M = Aff.triangularView<Eigen::Lower>();
    M += K;
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
    if (coupled || F.own_pattern) {
      // cholmod_factorize needs the pattern the factor was analysed for; coupling springs add
      // entries outside A's, so order and analyse A_ff + K itself (simplicial, as the model).
      cm.supernodal = CHOLMOD_SIMPLICIAL;
      cholmod_factor* L = cholmod_analyze(&A, &cm);
      if (!L) throw std::runtime_error("spring system: CHOLMOD could not analyse A_ff + K");
      cholmod_free_factor(&F.L, &cm);
      F.L = L;
      const int* perm = static_cast<const int*>(F.L->Perm);
      for (int i = 0; i < F.n; ++i) F.inv_perm[perm[i]] = i;
      F.own_pattern = coupled;
    }
    const int ok = cholmod_factorize(&A, F.L, &cm);
    stats_.refactor_s += SecondsSince(t0);
    if (!ok || cm.status != CHOLMOD_OK)
      throw std::runtime_error("spring system: CHOLMOD could not factor A_ff + K (status " +
                               std::to_string(cm.status) + ")");
  }
  ++stats_.refactors;
  since_refactor_ = 0;
}

bool SpringSystem::SetSprings(const std::vector<int>& vertices, double k) {
  std::vector<int> v = vertices;
  std::sort(v.begin(), v.end());
  v.erase(std::unique(v.begin(), v.end()), v.end());
  std::vector<SpringStencil> s;
  s.reserve(v.size());
  for (int i : v) s.push_back(SpringStencil::Unit(i));
  return SetSprings(s, k);
}

bool SpringSystem::SetSprings(const std::vector<SpringStencil>& springs, double k) {
  if (!(k > 0) || !std::isfinite(k))
    throw std::invalid_argument("spring system: expected a finite stiffness k > 0");
  const int nv = model_.num_vertices();
  for (const auto& sp : springs)
    for (int j = 0; j < 4; ++j)
      if (sp.vertex[j] >= nv || (sp.vertex[j] < 0 && sp.vertex[j] != -1) ||
          !std::isfinite(sp.coef[j]))
        throw std::invalid_argument("spring system: a spring names vertex " +
                                    std::to_string(sp.vertex[j]) + " (expected 0.." +
                                    std::to_string(nv - 1) + ") or has a non-finite coefficient");
  std::vector<SpringStencil> next = springs;
  std::sort(next.begin(), next.end());
  if (springs_.empty()) k_ = k;  // no spring yet: nothing in the factor depends on k
  if (k != k_) {
    // A new stiffness changes every spring's entry: recompute the factor from A_ff + K.
    k_ = k;
    springs_ = next;
    ++stats_.changes;
    Refactor();
    return true;
  }
  if (next == springs_) return false;
  std::vector<SpringStencil> added, removed;
  std::set_difference(next.begin(), next.end(), springs_.begin(), springs_.end(),
                      std::back_inserter(added));
  std::set_difference(springs_.begin(), springs_.end(), next.begin(), next.end(),
                      std::back_inserter(removed));
  springs_ = next;
  ++stats_.changes;
  if (method_ == Method::kRefactor ||
      (refactor_after_ > 0 &&
       since_refactor_ + long(added.size() + removed.size()) > refactor_after_)) {
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
  stats_.solve_s += SecondsSince(t0);
  ++stats_.solves;
  return y;
}

Eigen::VectorXd SpringSystem::Multiply(const Eigen::VectorXd& x) const {
  Eigen::VectorXd y(x.size());
  for (int d = 0; d < 3; ++d) {
    const int off = model_.free_offset(d);
    const int n = model_.free_offset(d + 1) - off;
    y.segment(off, n) = model_.A_ff(d) * x.segment(off, n);
  }
  AddSpringProduct(x, &y);
  return y;
}

void SpringSystem::AddSpringProduct(const Eigen::VectorXd& x, Eigen::VectorXd* y) const {
  for (int d = 0; d < 3; ++d) {
    const int off = model_.free_offset(d);
    for (const auto& sp : springs_) {
      std::array<std::pair<int, double>, 4> e;
      const int n = FreeEntries(sp, model_.free_index(d), &e);
      double dot = 0;
      for (int j = 0; j < n; ++j) dot += e[j].second * x[off + e[j].first];
      for (int j = 0; j < n; ++j) (*y)[off + e[j].first] += k_ * e[j].second * dot;
    }
  }
}

}  // namespace softkin
