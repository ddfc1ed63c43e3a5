#pragma once
/// \file blas_threads.hpp
/// ScopedBlasThreads: runs a block with the BLAS library's own thread pool set to a given size,
/// and restores the previous size after it.
///
/// SoftKin parallelises its element loops with OpenMP. CHOLMOD's supernodal factor calls BLAS,
/// and OpenBLAS (Debian's default BLAS) starts its own pthreads for that. On a small machine the
/// two pools spin against each other: on bilayer_strip res 2 with newton, 2 OpenMP threads and
/// 2 OpenBLAS threads on 2 cores spent ~45 % of the time in sched_yield and spin waits, mostly
/// around the single-right-hand-side triangular solves of GMRES's preconditioner, which gain
/// nothing from threads. The guard finds OpenBLAS's `openblas_get_num_threads` /
/// `openblas_set_num_threads` at run time (dlsym), so it does nothing with another BLAS and needs
/// no link-time dependency.

namespace softkin {

class ScopedBlasThreads {
 public:
  /// Sets the BLAS thread count to `threads` (>= 1) until destruction; no-op without OpenBLAS.
  explicit ScopedBlasThreads(int threads);
  ~ScopedBlasThreads();
  ScopedBlasThreads(const ScopedBlasThreads&) = delete;
  ScopedBlasThreads& operator=(const ScopedBlasThreads&) = delete;

  /// The BLAS library's current thread count, or 0 if it cannot be queried (not OpenBLAS).
  static int Current();

 private:
  int previous_ = 0;
};

}  // namespace softkin
