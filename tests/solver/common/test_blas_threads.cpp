// ScopedBlasThreads: the BLAS pool is one thread inside the guard and back to its size after.
#include "softkin/solver/common/blas_threads.hpp"

#include <gtest/gtest.h>

namespace softkin {
namespace {

TEST(ScopedBlasThreads, SetsOneThreadAndRestoresThePreviousCount) {
  const int before = ScopedBlasThreads::Current();
  if (before <= 0) GTEST_SKIP() << "the BLAS in use is not OpenBLAS: the guard is a no-op";
  {
    const ScopedBlasThreads outer(1);
    EXPECT_EQ(ScopedBlasThreads::Current(), 1);
    {
      const ScopedBlasThreads inner(1);  // nested: nothing to change, nothing to restore
      EXPECT_EQ(ScopedBlasThreads::Current(), 1);
    }
    EXPECT_EQ(ScopedBlasThreads::Current(), 1);
  }
  EXPECT_EQ(ScopedBlasThreads::Current(), before);
}

TEST(ScopedBlasThreads, IgnoresACountBelowOne) {
  const int before = ScopedBlasThreads::Current();
  {
    const ScopedBlasThreads guard(0);
    EXPECT_EQ(ScopedBlasThreads::Current(), before);
  }
  EXPECT_EQ(ScopedBlasThreads::Current(), before);
}

}  // namespace
}  // namespace softkin
