// femreg's worker threads (parallel/pool.h): every task runs once, whoever runs it, and the
// loops built on them give the serial loop's result on any thread count.
#include <gtest/gtest.h>

#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <stdexcept>
#include <string>
#include <thread>
#include <vector>

#include "forked_child.h"
#include "parallel/pool.h"

namespace femreg {
namespace {

TEST(RunTasks, EveryTaskOnceOnAnyThreadCount) {
  for (int threads : {1, 2, 3, 8}) {
    for (int tasks : {0, 1, 2, 5, 64, 1000}) {
      std::vector<std::atomic<int>> runs(static_cast<size_t>(tasks));
      for (auto& r : runs) r = 0;
      RunTasks(threads, tasks, [&](int i) { runs[static_cast<size_t>(i)].fetch_add(1); });
      for (int i = 0; i < tasks; ++i) {
        EXPECT_EQ(runs[static_cast<size_t>(i)].load(), 1) << threads << " threads, task " << i << " of " << tasks;
      }
    }
  }
}

TEST(RunTasks, ManyJobsInARow) {
  // The workers poll for the next job, then sleep: jobs close together and far apart.
  std::vector<int64_t> out(257, 0);
  for (int job = 0; job < 2000; ++job) {
    RunTasks(2, 257, [&](int i) { out[static_cast<size_t>(i)] += i; });
    if (job % 500 == 0) std::this_thread::sleep_for(std::chrono::milliseconds(2));
  }
  for (int i = 0; i < 257; ++i) EXPECT_EQ(out[static_cast<size_t>(i)], 2000 * static_cast<int64_t>(i));
}

TEST(RunTasks, NestedAndConcurrentCallsComplete) {
  std::atomic<int> inner{0};
  RunTasks(2, 8, [&](int) { RunTasks(2, 16, [&](int) { inner.fetch_add(1); }); });
  EXPECT_EQ(inner.load(), 8 * 16);
  // Two threads of the caller's at once: one of them gets the workers, the other runs alone.
  std::atomic<int> a{0}, b{0};
  std::thread other([&] {
    for (int k = 0; k < 200; ++k) RunTasks(2, 50, [&](int) { a.fetch_add(1); });
  });
  for (int k = 0; k < 200; ++k) RunTasks(2, 50, [&](int) { b.fetch_add(1); });
  other.join();
  EXPECT_EQ(a.load(), 200 * 50);
  EXPECT_EQ(b.load(), 200 * 50);
}

TEST(RunTasks, TwoCallersWithSeveralWorkersEachReturn) {
  // With three workers one caller's job can end while another's runs: each caller must be
  // woken when its own job's last worker finishes (a hang here is the failure).
  std::atomic<int> a{0}, b{0};
  std::thread other([&] {
    for (int k = 0; k < 300; ++k) RunTasks(4, 40, [&](int) { a.fetch_add(1); });
  });
  for (int k = 0; k < 300; ++k) RunTasks(4, 40, [&](int) { b.fetch_add(1); });
  other.join();
  EXPECT_EQ(a.load(), 300 * 40);
  EXPECT_EQ(b.load(), 300 * 40);
}

// True once a call with two threads has run its tasks on two threads: the caller is not
// stuck in serial mode. Tries a number of jobs, since a worker may start late on a busy machine.
bool UsesAWorker() {
  const auto caller = std::this_thread::get_id();
  for (int attempt = 0; attempt < 200; ++attempt) {
    std::atomic<bool> on_worker{false};
    RunTasks(2, 32, [&](int) {
      if (std::this_thread::get_id() != caller) on_worker = true;
      std::this_thread::sleep_for(std::chrono::microseconds(100));
    });
    if (on_worker.load()) return true;
  }
  return false;
}

TEST(RunTasks, AWorkersExceptionReachesTheCaller) {
  const auto caller = std::this_thread::get_id();
  bool thrown = false;
  for (int attempt = 0; attempt < 200 && !thrown; ++attempt) {
    std::atomic<bool> on_worker{false};
    try {
      RunTasks(2, 32, [&](int) {
        if (std::this_thread::get_id() != caller) {
          on_worker = true;
          throw std::runtime_error("on a worker");
        }
        std::this_thread::sleep_for(std::chrono::microseconds(100));
      });
      EXPECT_FALSE(on_worker.load()) << "a worker's task threw and the caller did not see it";
    } catch (const std::runtime_error&) {
      EXPECT_TRUE(on_worker.load());
      thrown = true;
    }
  }
  EXPECT_TRUE(thrown) << "no task ran on a worker in 200 jobs";
  EXPECT_TRUE(UsesAWorker());
}

TEST(RunTasks, ACallersExceptionLeavesItsThreadParallel) {
  const auto caller = std::this_thread::get_id();
  bool thrown = false;
  for (int attempt = 0; attempt < 200 && !thrown; ++attempt) {
    try {
      RunTasks(2, 32, [&](int) {
        if (std::this_thread::get_id() == caller) throw std::runtime_error("on the caller");
      });
    } catch (const std::runtime_error&) {
      thrown = true;
    }
  }
  EXPECT_TRUE(thrown);
  // The thread's next calls still share their tasks with the workers.
  EXPECT_TRUE(UsesAWorker());
}

TEST(RunTasks, ACallersExceptionPropagatesAfterTheWorkersStop) {
  // With one thread the caller runs every task.
  EXPECT_THROW(RunTasks(1, 4, [](int i) {
                 if (i == 0) throw std::runtime_error("task 0");
               }),
               std::runtime_error);
  std::atomic<int> runs{0};
  RunTasks(2, 10, [&](int) { runs.fetch_add(1); });  // the pool still works
  EXPECT_EQ(runs.load(), 10);
}

// In a forked child, a parallel loop: every task once, on a worker of the child's own
// (the parent's workers are not copied). Returns the child's exit code: 0 when that holds.
int ParallelLoopInChild() {
  std::vector<std::atomic<int>> runs(64);
  for (auto& r : runs) r = 0;
  RunTasks(2, 64, [&](int i) { runs[static_cast<size_t>(i)].fetch_add(1); });
  for (auto& r : runs) {
    if (r.load() != 1) return 2;
  }
  return UsesAWorker() ? 0 : 3;
}

// Forks and runs ParallelLoopInChild in the child: "" when it held, else what happened.
std::string ForkAndRunParallelLoop() {
  std::string failure;
  const int code = testing_util::ExitCodeOfForkedChild(&ParallelLoopInChild, &failure);
  if (code < 0) return failure;
  if (code == 2) return "in the child a task did not run exactly once";
  if (code == 3) return "in the child no task ran on a worker (the pool counts the parent's workers)";
  return code == 0 ? "" : "the child exited " + std::to_string(code);
}

TEST(RunTasks, AForkedChildRunsParallelLoops) {
  ASSERT_TRUE(UsesAWorker());  // the parent's pool has a worker
  EXPECT_EQ(ForkAndRunParallelLoop(), "");
  EXPECT_TRUE(UsesAWorker());  // and the parent's still works
}

TEST(RunTasks, AForkedChildRunsParallelLoopsWhileTheParentsPoolIsBusy) {
  // Another thread keeps the pool's workers taking jobs (and its mutex taken and released)
  // while this one forks: no child may inherit the mutex held by a thread it does not have.
  std::atomic<bool> stop{false};
  std::atomic<int64_t> tasks{0};
  std::thread busy([&] {
    while (!stop.load()) RunTasks(3, 8, [&](int) { tasks.fetch_add(1); });
  });
  std::string failure;
  for (int k = 0; k < 20 && failure.empty(); ++k) failure = ForkAndRunParallelLoop();
  stop = true;
  busy.join();
  EXPECT_EQ(failure, "");
  EXPECT_GT(tasks.load(), 0);
}

TEST(ParallelFor, SameAsTheSerialLoop) {
  const int64_t n = 100003;
  std::vector<double> serial(static_cast<size_t>(n)), one(static_cast<size_t>(n)), two(static_cast<size_t>(n));
  auto f = [](int64_t i) { return std::sin(0.001 * static_cast<double>(i)) * std::sqrt(static_cast<double>(i)); };
  for (int64_t i = 0; i < n; ++i) serial[static_cast<size_t>(i)] = f(i);
  ParallelFor(1, n, 64, [&](int64_t i) { one[static_cast<size_t>(i)] = f(i); });
  ParallelFor(2, n, 64, [&](int64_t i) { two[static_cast<size_t>(i)] = f(i); });
  EXPECT_EQ(one, serial);
  EXPECT_EQ(two, serial);
}

TEST(ParallelRanges, PiecesDependOnTheSizeAlone) {
  for (int threads : {1, 2, 4}) {
    std::vector<std::atomic<int64_t>> begins(10);
    for (auto& b : begins) b = -1;
    ParallelRanges(threads, 95, 10, [&](int64_t begin, int64_t end) {
      EXPECT_EQ(end, std::min<int64_t>(95, begin + 10));
      begins[static_cast<size_t>(begin / 10)] = begin;
    });
    for (int p = 0; p < 10; ++p) EXPECT_EQ(begins[static_cast<size_t>(p)].load(), 10 * p) << threads;
  }
}

}  // namespace
}  // namespace femreg
