// femreg's threads: one count governs every parallel part (OpenMP loops, the BLAS under
// CHOLMOD's supernodal factorization, Ceres), so that nothing runs more threads than the
// user asked for, whatever OMP_NUM_THREADS or OPENBLAS_NUM_THREADS say.
#ifndef FEMREG_PARALLEL_THREADS_H_
#define FEMREG_PARALLEL_THREADS_H_

#include <functional>

namespace femreg {

// The machine's hardware threads (at least 1): the default of every `num_threads`.
int DefaultThreadCount();

// `requested` if > 0, else the innermost ScopedThreads' count on this thread, else
// DefaultThreadCount().
int ResolveThreadCount(int requested);

// The hardware threads that other processes leave free: DefaultThreadCount() less the
// threads of other processes that are running or ready to run (the kernel's count, less this
// process's own: parallel/load.h), at least 1. Sampled at most once per kLoadSampleMs
// (threads.cc), so that it is cheap to call per frame or per solve.
// A busy machine gets fewer threads, so that no team waits on a core another process holds.
int AvailableThreadCount();

// `requested` if > 0, else AvailableThreadCount(): the adaptive default (solver.threads: 0).
int AdaptiveThreadCount(int requested);

// The threads for a parallel phase of `work` units on up to `threads`: fewer where each
// would get less than `per_thread` units (1 below that), so that a small phase runs serially
// instead of paying for a team it cannot use.
int PhaseThreads(int threads, long long work, long long per_thread);

// While alive, OpenMP regions started from this thread and OpenBLAS (looked up at run time:
// with another BLAS it does nothing) run on `threads` threads (<= 0: ResolveThreadCount(0)),
// and ResolveThreadCount(0) is that count; their settings before are restored on
// destruction. Nests: the innermost one holds.
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
  int previous_scoped_ = 0;  // the enclosing ScopedThreads' count (0: none)
};

// The calling thread's number in its OpenMP team and the team's size (0 and 1 outside a
// parallel region, or without OpenMP).
int TeamThread();
int TeamSize();

// Runs f() with OpenMP's thread limit at `threads` (<= 0: the default), so that parallel
// regions inside libraries that ask for a fixed team get at most `threads`: CHOLMOD 5's
// supernodal factorization opens teams of 4 (its compile-time CHOLMOD_OMP_NUM_THREADS)
// whatever omp_set_num_threads says. Done with a host `teams` region of one team
// (OpenMP 5.0), whose thread_limit bounds every region inside it; from inside a parallel
// region, where teams may not nest, f() runs as it is.
void WithThreadLimit(int threads, const std::function<void()>& f);

}  // namespace femreg

#endif  // FEMREG_PARALLEL_THREADS_H_
