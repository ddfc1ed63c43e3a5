/// \file blas_threads.cpp
/// ScopedBlasThreads (blas_threads.hpp): OpenBLAS's thread-count calls looked up at run time.
#include "softkin/solver/common/blas_threads.hpp"

#include <dlfcn.h>

namespace softkin {

namespace {
using GetThreads = int (*)();
using SetThreads = void (*)(int);

GetThreads GetFn() {
  static const auto fn =
      reinterpret_cast<GetThreads>(dlsym(RTLD_DEFAULT, "openblas_get_num_threads"));
  return fn;
}
SetThreads SetFn() {
  static const auto fn =
      reinterpret_cast<SetThreads>(dlsym(RTLD_DEFAULT, "openblas_set_num_threads"));
  return fn;
}
}  // namespace

int ScopedBlasThreads::Current() {
  const GetThreads get = GetFn();
  return get ? get() : 0;
}

ScopedBlasThreads::ScopedBlasThreads(int threads) {
  const SetThreads set = SetFn();
  previous_ = Current();
  if (!set || previous_ <= 0 || threads < 1 || threads == previous_) {
    previous_ = 0;  // nothing to restore
    return;
  }
  set(threads);
}

ScopedBlasThreads::~ScopedBlasThreads() {
  if (previous_ > 0) SetFn()(previous_);
}

}  // namespace softkin
