// femreg's own worker threads for the hot loops of a frame. An OpenMP team ends with a barrier
// that waits for every thread of the team, also for one that a busy machine has not yet given a
// core: the caller then sits idle for a time slice of another process. Here the caller takes
// tasks as the workers do, and at the end waits only for the tasks a worker has already taken,
// so a worker that starts late costs nothing but its wake-up
// (docs/notes/2026-11-30-two-threads.md).
#ifndef FEMREG_PARALLEL_POOL_H_
#define FEMREG_PARALLEL_POOL_H_

#include <cstdint>
#include <functional>

#include "parallel/threads.h"

namespace femreg {

// Runs body(i) once for every i in [0, tasks), on the calling thread and on up to threads - 1
// workers (threads <= 0: ResolveThreadCount(0)). Each task must write only its own data: which
// thread runs a task, and in which order the tasks run, is not fixed. Serial (no worker woken)
// with one thread or one task, and when called from inside a task or while another thread's
// call is running.
void RunTasks(int threads, int tasks, const std::function<void(int)>& body);

// body(begin, end) over [0, n) cut into pieces of `grain` (the last one shorter): RunTasks on
// the pieces. The pieces depend on n and grain only, never on the thread count.
void ParallelRanges(int threads, int64_t n, int64_t grain,
                    const std::function<void(int64_t, int64_t)>& body);

// The pieces ParallelFor and ParallelSpans cut [0, n) into: at most 16, of this length (the last
// one shorter). Piece k begins at k * SpanGrain(n).
inline int64_t SpanGrain(int64_t n) { return (n + 15) / 16; }

// f(i) for every i in [0, n): on PhaseThreads(threads, n, per_thread) threads (threads <= 0:
// ResolveThreadCount(0)), in pieces of about n / 16 so that the caller can take over the part
// of a worker that starts late. Serial where one thread is given or the loop is small.
template <class F>
void ParallelFor(int threads, int64_t n, int64_t per_thread, F&& f) {
  const int team = PhaseThreads(ResolveThreadCount(threads), n, per_thread);
  if (team <= 1) {
    for (int64_t i = 0; i < n; ++i) f(i);
    return;
  }
  ParallelRanges(team, n, SpanGrain(n), [&f](int64_t begin, int64_t end) {
    for (int64_t i = begin; i < end; ++i) f(i);
  });
}

// body(begin, end) over [0, n) in spans: one call on the caller where PhaseThreads gives one
// thread (fewer than 2 * per_thread elements), else the pieces of SpanGrain(n). For element-wise
// work on long arrays (copies, fills, vector updates): no reduction, so the result is the
// same on any thread count.
template <class F>
void ParallelSpans(int threads, int64_t n, int64_t per_thread, F&& body) {
  const int team = PhaseThreads(ResolveThreadCount(threads), n, per_thread);
  if (team <= 1) {
    if (n > 0) body(int64_t{0}, n);
    return;
  }
  ParallelRanges(team, n, SpanGrain(n), body);
}

}  // namespace femreg

#endif  // FEMREG_PARALLEL_POOL_H_
