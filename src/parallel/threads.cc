#include "parallel/threads.h"

#include <dlfcn.h>

#include <algorithm>
#include <thread>

#ifdef _OPENMP
#include <omp.h>
#endif

namespace femreg {

namespace {

// OpenBLAS's thread count, found at run time so that any BLAS links.
using GetThreads = int (*)();
using SetThreads = void (*)(int);
struct Blas {
  GetThreads get = nullptr;
  SetThreads set = nullptr;
};
const Blas& OpenBlas() {
  static const Blas blas = [] {
    Blas b;
    b.get = reinterpret_cast<GetThreads>(dlsym(RTLD_DEFAULT, "openblas_get_num_threads"));
    b.set = reinterpret_cast<SetThreads>(dlsym(RTLD_DEFAULT, "openblas_set_num_threads"));
    if (b.get == nullptr || b.set == nullptr) b = Blas();
    return b;
  }();
  return blas;
}

}  // namespace

int DefaultThreadCount() {
  return std::max(1, static_cast<int>(std::thread::hardware_concurrency()));
}

int ResolveThreadCount(int requested) { return requested > 0 ? requested : DefaultThreadCount(); }

ScopedThreads::ScopedThreads(int threads) : threads_(ResolveThreadCount(threads)) {
#ifdef _OPENMP
  previous_omp_ = omp_get_max_threads();
  omp_set_num_threads(threads_);
#endif
  const Blas& blas = OpenBlas();
  if (blas.set != nullptr) {
    const int previous = blas.get();
    if (previous != threads_) {
      previous_blas_ = previous;
      blas.set(threads_);
    }
  }
}

ScopedThreads::~ScopedThreads() {
#ifdef _OPENMP
  if (previous_omp_ > 0) omp_set_num_threads(previous_omp_);
#endif
  if (previous_blas_ > 0) OpenBlas().set(previous_blas_);
}

int TeamThread() {
#ifdef _OPENMP
  return omp_get_thread_num();
#else
  return 0;
#endif
}

int TeamSize() {
#ifdef _OPENMP
  return omp_get_num_threads();
#else
  return 1;
#endif
}

void WithThreadLimit(int threads, const std::function<void()>& f) {
#ifdef _OPENMP
  if (!omp_in_parallel()) {
    const int limit = ResolveThreadCount(threads);
#pragma omp teams num_teams(1) thread_limit(limit)
    f();
    return;
  }
#endif
  f();
}

}  // namespace femreg
