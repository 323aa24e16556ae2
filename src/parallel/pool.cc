#include "parallel/pool.h"

#include <pthread.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <condition_variable>
#include <exception>
#include <mutex>
#include <new>
#include <system_error>
#include <thread>

#include "parallel/threads.h"

#ifdef _OPENMP
#include <omp.h>
#endif

namespace femreg {

namespace {

thread_local bool inside_task = false;  // this thread runs a task (a nested call runs serially)

// After a job a worker polls for the next one this long before it sleeps: the hot loops come in
// runs (a substitution's two halves, the PCG iterations, an assembly's two steps), and a
// sleeping worker takes longer than that to wake. Short enough to cost a busy machine little.
constexpr std::chrono::microseconds kPoll(50);

struct Job {
  const std::function<void(int)>* body = nullptr;
  int tasks = 0;
  std::atomic<int> next{0};
  int wanted = 0;   // workers that may join
  int joined = 0;   // workers that joined (under the pool's mutex, as the two below)
  int active = 0;   // workers still taking tasks
  bool closed = false;  // the caller took the last task: no worker joins any more
  std::mutex error_mutex;
  std::exception_ptr error;  // the first task that threw, on whichever thread: the caller rethrows it
};

inline void Pause() {
#if defined(__x86_64__) || defined(__i386__)
  __builtin_ia32_pause();
#endif
}

// Marks this thread as running a task for the scope, also when a task throws.
class InsideTask {
 public:
  InsideTask() : was_(inside_task) { inside_task = true; }
  ~InsideTask() { inside_task = was_; }
  InsideTask(const InsideTask&) = delete;
  InsideTask& operator=(const InsideTask&) = delete;

 private:
  bool was_;
};

void TakeTasks(Job* job) {
  InsideTask inside;
  try {
    for (int i = job->next.fetch_add(1, std::memory_order_relaxed); i < job->tasks;
         i = job->next.fetch_add(1, std::memory_order_relaxed)) {
      (*job->body)(i);
    }
  } catch (...) {
    std::lock_guard<std::mutex> lock(job->error_mutex);
    if (!job->error) job->error = std::current_exception();
    job->next.store(job->tasks, std::memory_order_relaxed);  // nobody takes another task
  }
}

class Pool {
 public:
  static Pool& Get() {
    static Pool* pool = [] {
      Pool* p = new Pool;  // never destroyed: workers may still sleep at exit
      forked_.store(p, std::memory_order_release);
      pthread_atfork(&BeforeFork, &AfterForkInParent, &AfterForkInChild);
      return p;
    }();
    return *pool;
  }

  void Run(int threads, int tasks, const std::function<void(int)>& body) {
    Job job;
    job.body = &body;
    job.tasks = tasks;
    job.wanted = threads - 1;
    int workers = 0;  // read under the lock: another caller may add workers once this job ends
    {
      std::lock_guard<std::mutex> lock(mutex_);
      if (job_ != nullptr) {  // another thread's call is running: this one alone
        job.wanted = 0;
      } else {
        const uint64_t before = generation_.load(std::memory_order_relaxed);
        try {
          while (workers_ < job.wanted) {
            std::thread([this, before] { Work(before); }).detach();  // it takes this job too
            ++workers_;
          }
        } catch (const std::system_error&) {  // no more threads to be had: go on with those there are
        }
        workers = workers_;
        job.wanted = std::min(job.wanted, workers);
        if (job.wanted > 0) {
          job_ = &job;
          generation_.store(generation_.load(std::memory_order_relaxed) + 1, std::memory_order_release);
        }
      }
    }
    if (job.wanted == 0) {
      for (int i = 0; i < tasks; ++i) body(i);
      return;
    }
    if (job.wanted >= workers) {
      wake_.notify_all();
    } else {
      for (int w = 0; w < job.wanted; ++w) wake_.notify_one();
    }
    TakeTasks(&job);
    {
      std::unique_lock<std::mutex> lock(mutex_);
      job.closed = true;
      job_ = nullptr;
      done_.wait(lock, [&job] { return job.active == 0; });
    }
    if (job.error) std::rethrow_exception(job.error);
  }

 private:
  // fork() copies only the thread that calls it. Its mutex is taken around the fork so that
  // no worker holds it in the child, where the child starts the pool anew: no workers (the
  // next call starts its own), no job, a fresh mutex and condition variables (the parent's
  // may count waiters that the child does not have).
  // (The handlers reach the pool through forked_, not Get(): a fork while Get() registers them
  // must not wait for Get().)
  static void BeforeFork() { forked_.load(std::memory_order_acquire)->mutex_.lock(); }
  static void AfterForkInParent() { forked_.load(std::memory_order_acquire)->mutex_.unlock(); }
  static void AfterForkInChild() {
    Pool& pool = *forked_.load(std::memory_order_acquire);
    new (&pool.mutex_) std::mutex;
    new (&pool.wake_) std::condition_variable;
    new (&pool.done_) std::condition_variable;
    pool.job_ = nullptr;
    pool.workers_ = 0;
  }

  void Work(uint64_t seen) {
#ifdef _OPENMP
    omp_set_num_threads(1);  // an OpenMP loop inside a task runs on it alone, as one nested in a team
#endif
    std::unique_lock<std::mutex> lock(mutex_);
    for (;;) {
      if (generation_.load(std::memory_order_relaxed) == seen) {
        lock.unlock();
        const auto until = std::chrono::steady_clock::now() + kPoll;
        while (generation_.load(std::memory_order_acquire) == seen && std::chrono::steady_clock::now() < until) {
          for (int i = 0; i < 16; ++i) Pause();
        }
        lock.lock();
        wake_.wait(lock, [&] { return generation_.load(std::memory_order_relaxed) != seen; });
      }
      seen = generation_.load(std::memory_order_relaxed);
      Job* job = job_;
      if (job == nullptr || job->closed || job->joined >= job->wanted) continue;
      ++job->joined;
      ++job->active;
      lock.unlock();
      TakeTasks(job);
      lock.lock();
      // Every waiter: another caller's job may have started (and be waited for) since this one.
      if (--job->active == 0 && job->closed) done_.notify_all();
    }
  }

  std::mutex mutex_;
  std::condition_variable wake_;  // a new job
  std::condition_variable done_;  // a job's last worker finished
  Job* job_ = nullptr;
  std::atomic<uint64_t> generation_{0};  // changed under mutex_, polled without it
  static std::atomic<Pool*> forked_;  // the pool, for the fork handlers
  int workers_ = 0;  // detached: the pool lives to the process's end, and a forked child has none
};

std::atomic<Pool*> Pool::forked_{nullptr};

// The pool is made as the library loads, not at its first use: a fork while another thread
// is inside that first use's initialization would leave the child's Get() waiting for it.
[[maybe_unused]] const bool kPoolMadeAtLoad = (Pool::Get(), true);

}  // namespace

void RunTasks(int threads, int tasks, const std::function<void(int)>& body) {
  if (tasks <= 0) return;
  threads = std::min(ResolveThreadCount(threads), tasks);
  if (threads <= 1 || inside_task) {
    for (int i = 0; i < tasks; ++i) body(i);
    return;
  }
  Pool::Get().Run(threads, tasks, body);
}

void ParallelRanges(int threads, int64_t n, int64_t grain,
                    const std::function<void(int64_t, int64_t)>& body) {
  if (n <= 0) return;
  grain = std::max<int64_t>(grain, 1);
  const int64_t pieces = (n + grain - 1) / grain;
  if (pieces == 1) {
    body(0, n);
    return;
  }
  RunTasks(threads, static_cast<int>(pieces), [&](int p) {
    const int64_t begin = static_cast<int64_t>(p) * grain;
    body(begin, std::min(n, begin + grain));
  });
}

}  // namespace femreg
