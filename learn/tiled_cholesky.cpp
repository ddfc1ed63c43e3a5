#include "softkin/learn/tiled_cholesky.hpp"

#include <Eigen/Cholesky>

#include <algorithm>
#include <cassert>

namespace softkin {

bool TiledCholeskyInPlace(Eigen::Ref<Eigen::MatrixXd> A, int tile, int threads) {
  assert(A.rows() == A.cols() && tile >= 1 && threads >= 1);
  const Eigen::Index n = A.rows();
  for (Eigen::Index k0 = 0; k0 < n; k0 += tile) {
    const Eigen::Index kw = std::min<Eigen::Index>(tile, n - k0);
    auto Akk = A.block(k0, k0, kw, kw);
    // Diagonal tile: serial Cholesky, in place (reads and writes its lower triangle).
    Eigen::LLT<Eigen::Ref<Eigen::MatrixXd>> llt(Akk);
    if (llt.info() != Eigen::Success) return false;
    const Eigen::Index r0 = k0 + kw;
    const Eigen::Index rest = n - r0;
    if (rest == 0) break;
    const int ntiles = static_cast<int>((rest + tile - 1) / tile);
#pragma omp parallel num_threads(threads)
    {
      // Panel below the diagonal tile: A_ik <- A_ik L_kk^-T, one row tile per task.
#pragma omp for schedule(static)
      for (int i = 0; i < ntiles; ++i) {
        const Eigen::Index i0 = r0 + static_cast<Eigen::Index>(i) * tile;
        auto P = A.block(i0, k0, std::min<Eigen::Index>(tile, n - i0), kw);
        Akk.transpose().triangularView<Eigen::Upper>().solveInPlace<Eigen::OnTheRight>(P);
      }
      // Trailing update of the lower part, one column tile per task:
      // A(j0:, j0:j0+jw) -= A(j0:, panel) A(j0:j0+jw, panel)^T.
#pragma omp for schedule(dynamic, 1)
      for (int j = 0; j < ntiles; ++j) {
        const Eigen::Index j0 = r0 + static_cast<Eigen::Index>(j) * tile;
        const Eigen::Index jw = std::min<Eigen::Index>(tile, n - j0);
        A.block(j0, j0, n - j0, jw).noalias() -=
            A.block(j0, k0, n - j0, kw) * A.block(j0, k0, jw, kw).transpose();
      }
    }
  }
  return true;
}

void TiledCholeskySolveInPlace(const Eigen::Ref<const Eigen::MatrixXd>& A,
                               Eigen::Ref<Eigen::VectorXd> b) {
  assert(A.rows() == A.cols() && b.size() == A.rows());
  A.triangularView<Eigen::Lower>().solveInPlace(b);
  A.triangularView<Eigen::Lower>().transpose().solveInPlace(b);
}

}  // namespace softkin
