#include "parallel/threads.h"

#include <dirent.h>
#include <dlfcn.h>
#include <pthread.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <limits>
#include <string>
#include <thread>

#ifdef _OPENMP
#include <omp.h>
#endif

#include "parallel/load.h"

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
// Looked up as the library loads, not at the first ScopedThreads: a fork while another thread
// is inside that first lookup would leave the child waiting for it (parallel/pool.cc's pool too).
[[maybe_unused]] const bool kOpenBlasLookedUpAtLoad = (OpenBlas(), true);

}  // namespace

int DefaultThreadCount() {
  return std::max(1, static_cast<int>(std::thread::hardware_concurrency()));
}

namespace {
thread_local int scoped_threads = 0;  // the innermost ScopedThreads' count on this thread
}  // namespace

int ResolveThreadCount(int requested) {
  if (requested > 0) return requested;
  return scoped_threads > 0 ? scoped_threads : DefaultThreadCount();
}

int RunnableThreads() {
  FILE* f = std::fopen("/proc/loadavg", "r");
  if (f == nullptr) return -1;
  double a = 0, b = 0, c = 0;
  int running = -1, total = 0;
  if (std::fscanf(f, "%lf %lf %lf %d/%d", &a, &b, &c, &running, &total) != 5) running = -1;
  std::fclose(f);
  return running;
}

int OwnRunnableThreads() {
  DIR* tasks = opendir("/proc/self/task");
  if (tasks == nullptr) return -1;
  int running = 0;
  while (const dirent* entry = readdir(tasks)) {
    if (entry->d_name[0] == '.') continue;
    const std::string path = std::string("/proc/self/task/") + entry->d_name + "/stat";
    FILE* f = std::fopen(path.c_str(), "r");
    if (f == nullptr) continue;  // the thread ended since the listing
    char line[512];
    const bool read = std::fgets(line, sizeof(line), f) != nullptr;
    std::fclose(f);
    if (!read) continue;
    // "tid (name) S ...": the state follows the last ')' (a thread's name may hold one).
    const char* close = std::strrchr(line, ')');
    if (close != nullptr && close[1] == ' ' && close[2] == 'R') ++running;
  }
  closedir(tasks);
  return running;
}

int ThreadsLeftFree(int cores, int running, int own) {
  const int others = std::max(0, running - std::max(own, 1));  // the caller is running, at least
  return std::clamp(cores - others, 1, std::max(cores, 1));
}

// AvailableThreadCount's sampling interval: the load a frame sees, without reading /proc per call.
constexpr int64_t kLoadSampleMs = 50;

int AvailableThreadCount() {
  using Clock = std::chrono::steady_clock;
  static std::atomic<int64_t> sampled_at{std::numeric_limits<int64_t>::min()};
  static std::atomic<int> available{0};
  const int64_t now = std::chrono::duration_cast<std::chrono::milliseconds>(Clock::now().time_since_epoch()).count();
  const int64_t then = sampled_at.load(std::memory_order_relaxed);
  const int known = available.load(std::memory_order_relaxed);
  if (known > 0 && then != std::numeric_limits<int64_t>::min() && now - then < kLoadSampleMs) return known;
  const int cores = DefaultThreadCount();
  // This process's own runnable threads are no competition: the caller, and the workers that
  // poll for their next job after the last one (parallel/pool.cc) or OpenMP threads that spin.
  // Counted before and after the kernel's count, so that one that starts or stops between is
  // not taken for another process's.
  const int own_before = OwnRunnableThreads();
  const int running = RunnableThreads();
  const int own = std::max(own_before, OwnRunnableThreads());
  const int n = running > 0 ? ThreadsLeftFree(cores, running, own) : cores;
  available.store(n, std::memory_order_relaxed);
  sampled_at.store(now, std::memory_order_relaxed);
  return n;
}

int AdaptiveThreadCount(int requested) { return requested > 0 ? requested : AvailableThreadCount(); }

int PhaseThreads(int threads, long long work, long long per_thread) {
  if (threads <= 1 || per_thread <= 0) return std::max(1, threads);
  return static_cast<int>(std::clamp<long long>(work / per_thread, 1, threads));
}

ScopedThreads::ScopedThreads(int threads) : threads_(ResolveThreadCount(threads)) {
  previous_scoped_ = scoped_threads;
  scoped_threads = threads_;
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
  scoped_threads = previous_scoped_;
#ifdef _OPENMP
  if (previous_omp_ > 0) omp_set_num_threads(previous_omp_);
#endif
  if (previous_blas_ > 0) OpenBlas().set(previous_blas_);
}

namespace {

#ifdef _OPENMP
// fork() copies only the forking thread. libgomp keeps the threads of that thread's last team
// idle for its next one, and a forked child would wait for them forever (Python's
// multiprocessing forks after femreg's teams ran): they are freed before the fork, so parent
// and child each start new ones at their next team. From inside a team nothing is freed.
void FreeOpenMpThreadsBeforeFork() {
  if (!omp_in_parallel()) omp_pause_resource_all(omp_pause_hard);
}
const int kOpenMpForkHandler = pthread_atfork(&FreeOpenMpThreadsBeforeFork, nullptr, nullptr);
#endif

}  // namespace

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
