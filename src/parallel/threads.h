// femreg's threads: one count governs every parallel part (OpenMP loops, the BLAS under
// CHOLMOD's supernodal factorization, Ceres), so that nothing runs more threads than the
// user asked for, whatever OMP_NUM_THREADS or OPENBLAS_NUM_THREADS say.
#ifndef FEMREG_PARALLEL_THREADS_H_
#define FEMREG_PARALLEL_THREADS_H_

namespace femreg {

// The machine's hardware threads (at least 1): the default of every `num_threads`.
int DefaultThreadCount();

// `requested` if > 0, else DefaultThreadCount().
int ResolveThreadCount(int requested);

// While alive, OpenMP regions started from this thread and OpenBLAS (looked up at run time:
// with another BLAS it does nothing) run on `threads` threads (<= 0: the default); their
// settings before are restored on destruction. Nests: the innermost one holds.
class ScopedThreads {
 public:
  explicit ScopedThreads(int threads);
  ~ScopedThreads();
  ScopedThreads(const ScopedThreads&) = delete;
  ScopedThreads& operator=(const ScopedThreads&) = delete;

  int threads() const { return threads_; }

 private:
  int threads_ = 1;
  int previous_omp_ = 0;     // 0: OpenMP not in use
  int previous_blas_ = 0;    // 0: OpenBLAS not found or unchanged
};

}  // namespace femreg

#endif  // FEMREG_PARALLEL_THREADS_H_
