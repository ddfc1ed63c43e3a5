#pragma once
/// \file
/// A right-looking tiled Cholesky factorisation A = L L^T with OpenMP over fixed tiles, for the LM
/// trainer's damped normal equations (W x W, W ~ 1500). Every tile is computed by the same serial
/// Eigen operations whatever the thread count (the tile partition is fixed), so the factor is
/// bitwise identical for 1, 2, ... threads, unlike Eigen's LLT with Eigen's own OpenMP products,
/// whose block sizes depend on the thread count.

#include <Eigen/Core>

namespace softkin {

/// Factor the symmetric positive definite matrix whose LOWER triangle is stored in A (n x n), in
/// place: on success the lower triangle holds L (the strict upper triangle is overwritten).
/// Returns false if a pivot is not positive (A is not numerically positive definite); A is then
/// partly overwritten. `tile` >= 1 is the tile size, `threads` >= 1 the OpenMP team size. Call it
/// with Eigen's own threading off (see learn/lm_trainer.cpp) or results depend on Eigen's threads.
bool TiledCholeskyInPlace(Eigen::Ref<Eigen::MatrixXd> A, int tile, int threads);

/// Solve L L^T x = b in place (b of length n), L the lower triangle of A from TiledCholeskyInPlace.
void TiledCholeskySolveInPlace(const Eigen::Ref<const Eigen::MatrixXd>& A,
                               Eigen::Ref<Eigen::VectorXd> b);

}  // namespace softkin
