// femreg owns its threads: what runs under femreg's thread count stays within it, even in
// libraries that ask for teams of their own (CHOLMOD 5's supernodal factorization asks
// OpenMP for 4 threads whatever the program set).
#include <gtest/gtest.h>

#include <Eigen/CholmodSupport>
#include <Eigen/SparseCore>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <functional>
#include <iterator>
#include <string>
#include <thread>
#include <vector>

#include "femreg/blas_kernels.h"
#include "forked_child.h"
#include "femreg/io.h"
#include "parallel/blas_choice.h"
#include "parallel/load.h"
#include "parallel/threads.h"
#include "test_util.h"

namespace femreg {
namespace {

int ThreadsInProcess() {
  const std::filesystem::directory_iterator tasks("/proc/self/task");
  return static_cast<int>(std::distance(begin(tasks), end(tasks)));
}

// A sparse system with one dense 300 x 300 block (and a diagonal beside it): its factor has
// a supernode far wider than the 64 columns from which CHOLMOD 5 factorizes in parallel.
Eigen::SparseMatrix<double> SystemWithAWideSupernode() {
  constexpr int kDense = 300, kSize = 1000;
  std::vector<Eigen::Triplet<double>> triplets;
  for (int i = 0; i < kDense; ++i) {
    for (int j = 0; j < kDense; ++j) {
      triplets.emplace_back(i, j, i == j ? 2.0 * kDense : 1.0 / (1.0 + std::abs(i - j)));
    }
  }
  for (int i = kDense; i < kSize; ++i) triplets.emplace_back(i, i, 1.0);
  Eigen::SparseMatrix<double> H(kSize, kSize);
  H.setFromTriplets(triplets.begin(), triplets.end());
  return H;
}

TEST(Threads, ThreadLimitHoldsCholmodsOwnTeams) {
  const Eigen::SparseMatrix<double> H = SystemWithAWideSupernode();
  Eigen::CholmodDecomposition<Eigen::SparseMatrix<double>, Eigen::Lower> factor;
  factor.setMode(Eigen::CholmodSupernodalLLt);
  factor.analyzePattern(H);
  const ScopedThreads blas(1);  // OpenBLAS's own pool, started at load time, stays idle

  const int before = ThreadsInProcess();
  WithThreadLimit(1, [&] { factor.factorize(H); });
  ASSERT_EQ(factor.info(), Eigen::Success);
  EXPECT_EQ(ThreadsInProcess(), before) << "a factorization under a limit of 1 started threads";

  // The control: without the limit the same factorization starts OpenMP threads (if this
  // CHOLMOD was built with OpenMP), so the check above can fail.
  factor.factorize(H);
  ASSERT_EQ(factor.info(), Eigen::Success);
  if (ThreadsInProcess() == before) GTEST_SKIP() << "this CHOLMOD starts no threads of its own";
  EXPECT_GT(ThreadsInProcess(), before);
}

// Writing a VTU (VTK's writer computes each array's range with its SMP tools, which on
// Debian's VTK 9.1 start a TBB worker pool, one thread per core) leaves the thread count as
// it was: femreg runs VTK's SMP tools on one thread.
TEST(Threads, WritingAVtuStartsNoThreads) {
  TetMesh mesh = MakeBox(Eigen::Vector3d(1, 1, 1), 20, 20, 20);
  testing_util::TempDir dir("femreg_threads");
  const int before = ThreadsInProcess();
  for (int i = 0; i < 3; ++i) {
    ASSERT_TRUE(WriteVtu(dir.path() + "/box.vtu", mesh, mesh.rest, {}).ok());
  }
  EXPECT_EQ(ThreadsInProcess(), before);
}

TEST(Threads, ThreadLimitRunsTheFunctionOnce) {
  int calls = 0;
  WithThreadLimit(2, [&] { ++calls; });
  EXPECT_EQ(calls, 1);
}

// Each thread of a team knows its number and the team's size; outside a team, 0 and 1.
TEST(Threads, TeamThreadNumbersTheTeam) {
  EXPECT_EQ(TeamThread(), 0);
  EXPECT_EQ(TeamSize(), 1);
  std::vector<int> seen(3, 0), sizes(3, 0);
#pragma omp parallel num_threads(3)
  {
    const int t = TeamThread();
    if (t >= 0 && t < 3) {
      seen[static_cast<size_t>(t)] = 1;
      sizes[static_cast<size_t>(t)] = TeamSize();
    }
  }
  const int team = sizes[0];
  ASSERT_GE(team, 1);
  for (int t = 0; t < 3; ++t) {
    EXPECT_EQ(seen[static_cast<size_t>(t)], t < team ? 1 : 0) << t;
    if (t < team) {
      EXPECT_EQ(sizes[static_cast<size_t>(t)], team) << t;
    }
  }
#ifdef _OPENMP
  EXPECT_EQ(team, 3);  // dynamic adjustment is off by default
#endif
}

// An OpenMP team of two threads: 0 when it had them.
int TeamOfTwo() {
  std::atomic<int> threads{0};
#ifdef _OPENMP
#pragma omp parallel num_threads(2)
#endif
  threads.fetch_add(1);
  return threads.load() == 2 ? 0 : 1;
}

// Forks; the child opens an OpenMP team of two. "" when it did, else what happened.
std::string ForkAndOpenATeam() {
  std::string failure;
  const int code = testing_util::ExitCodeOfForkedChild(&TeamOfTwo, &failure);
  if (code < 0) return failure;
  return code == 0 ? "" : "the child's team did not have two threads";
}

// Python's multiprocessing forks a process that has run femreg's OpenMP teams: libgomp's
// child would wait for the parent's idle team threads, which it does not have. femreg frees
// the forking thread's OpenMP threads before a fork (threads.cc), so the child starts its own.
TEST(Threads, AForkedChildOpensOpenMpTeams) {
#ifndef _OPENMP
  GTEST_SKIP() << "built without OpenMP";
#endif
  ASSERT_EQ(TeamOfTwo(), 0);  // the parent's threads, idle
  EXPECT_EQ(ForkAndOpenATeam(), "");
  EXPECT_EQ(TeamOfTwo(), 0);  // and the parent's teams still have their threads
  if (!HasFailure()) {
    EXPECT_EQ(ForkAndOpenATeam(), "");  // again, after teams in the parent
  }
}

// A phase takes at most its threads, one per `per_thread` units of work, at least one.
TEST(Threads, PhaseThreadsRunSmallPhasesSerially) {
  EXPECT_EQ(PhaseThreads(2, 100, 64), 1);
  EXPECT_EQ(PhaseThreads(2, 128, 64), 2);
  EXPECT_EQ(PhaseThreads(4, 200, 64), 3);
  EXPECT_EQ(PhaseThreads(4, 1 << 20, 64), 4);
  EXPECT_EQ(PhaseThreads(1, 1 << 20, 64), 1);
  EXPECT_EQ(PhaseThreads(2, 0, 64), 1);
}

// 0 threads: the innermost ScopedThreads' count (a frame's), else the machine's; the
// adaptive count is within [1, the machine's].
TEST(Threads, ZeroThreadsIsTheEnclosingCount) {
  EXPECT_EQ(ResolveThreadCount(0), DefaultThreadCount());
  EXPECT_EQ(ResolveThreadCount(3), 3);
  {
    const ScopedThreads frame(2);
    EXPECT_EQ(ResolveThreadCount(0), 2);
    {
      const ScopedThreads inner(1);
      EXPECT_EQ(ResolveThreadCount(0), 1);
    }
    EXPECT_EQ(ResolveThreadCount(0), 2);
  }
  EXPECT_EQ(ResolveThreadCount(0), DefaultThreadCount());
  const int available = AvailableThreadCount();
  EXPECT_GE(available, 1);
  EXPECT_LE(available, DefaultThreadCount());
  EXPECT_EQ(AdaptiveThreadCount(5), 5);
}

// The adaptive count takes the machine's runnable threads less this process's own: a worker
// of femreg's that polls for its next job (or an OpenMP thread that spins) is runnable, and
// counted as another process's it would cost the next frame a thread.
TEST(Threads, OwnRunnableThreadsAreNotOtherProcessesLoad) {
  std::atomic<bool> stop{false};
  std::atomic<int> started{0};
  std::vector<std::thread> spinning;
  for (int k = 0; k < 2; ++k) {
    spinning.emplace_back([&] {
      started.fetch_add(1);
      while (!stop.load(std::memory_order_relaxed)) {
      }
    });
  }
  while (started.load() < 2) std::this_thread::yield();
  const int own = OwnRunnableThreads();
  stop = true;
  for (std::thread& t : spinning) t.join();
  EXPECT_GE(own, 3);  // the two spinning and the caller
  // Two cores, and the runnable threads are this process's three: both cores are free.
  EXPECT_EQ(ThreadsLeftFree(2, 3, 3), 2);
  EXPECT_EQ(ThreadsLeftFree(2, 2, 3), 2);  // one stopped between the two counts
  EXPECT_EQ(ThreadsLeftFree(2, 4, 3), 1);  // another process's thread
  EXPECT_EQ(ThreadsLeftFree(8, 6, 2), 4);
  EXPECT_EQ(ThreadsLeftFree(2, 9, 1), 1);  // at least one
  EXPECT_EQ(ThreadsLeftFree(4, 1, 0), 4);  // the caller is running even when not counted
}

#ifdef FEMREG_CLI_PATH
// The command line's OpenMP threads sleep between teams (OMP_WAIT_POLICY=passive, a spin
// count of 0) unless the user chose a policy: libgomp's own report of its settings. Unset,
// libgomp spins 300000 times before it sleeps.
TEST(Threads, TheCommandLineWaitsPassively) {
  testing_util::TempDir dir("femreg_threads");
  auto spin_count = [&](const std::string& env) {
    const std::string log = dir.path() + "/env.txt";
    const std::string cmd = "env -u OMP_WAIT_POLICY -u GOMP_SPINCOUNT " + env + " OMP_DISPLAY_ENV=verbose " +
                            FEMREG_CLI_PATH + " --version > " + log + " 2>&1";
    EXPECT_EQ(std::system(cmd.c_str()), 0) << cmd;
    // The last report: the process that runs the command (it may have started itself again).
    std::ifstream in(log);
    std::string last = "(no GOMP_SPINCOUNT in libgomp's report)";
    for (std::string line; std::getline(in, line);) {
      if (line.find("GOMP_SPINCOUNT") != std::string::npos) last = line;
    }
    return last;
  };
  EXPECT_NE(spin_count("").find("'0'"), std::string::npos) << spin_count("");
  EXPECT_EQ(spin_count("OMP_WAIT_POLICY=active").find("'0'"), std::string::npos) << spin_count("OMP_WAIT_POLICY=active");
}
#endif

// OpenBLAS's kernels: a user's OPENBLAS_CORETYPE is never overridden, and a switch to this
// CPU's kernels (where OpenBLAS chose slower ones) leaves the factorizations right.
TEST(BlasKernels, UsersChoiceIsKept) {
  const char* before = std::getenv("OPENBLAS_CORETYPE");
  const std::string kept = before != nullptr ? before : "";
  ASSERT_EQ(setenv("OPENBLAS_CORETYPE", "Prescott", 1), 0);
  EXPECT_EQ(BetterBlasCoreType(), nullptr);
  if (before != nullptr) {
    setenv("OPENBLAS_CORETYPE", kept.c_str(), 1);
  } else {
    unsetenv("OPENBLAS_CORETYPE");
  }
}

// The rule itself: only generic kernels are replaced, by the best the CPU runs and the library
// has; kernels OpenBLAS chose for the CPU, and names it does not list, are left alone.
TEST(BlasKernels, OnlyGenericKernelsAreReplacedByTheBestTheCpuRuns) {
  auto all = [](const char*) { return true; };
  auto no_skylakex = [](const char* table) { return std::string(table) != "gotoblas_SKYLAKEX"; };
  auto none = [](const char*) { return false; };
  auto choose = [](const char* current, int cpu, const std::function<bool(const char*)>& has) {
    const char* k = ChooseBlasKernels(current, cpu, has);
    return std::string(k != nullptr ? k : "(kept)");
  };
  EXPECT_EQ(choose("Prescott", 3, all), "SkylakeX");
  EXPECT_EQ(choose("Prescott", 3, no_skylakex), "Haswell");
  EXPECT_EQ(choose("Core2", 2, all), "Haswell");
  EXPECT_EQ(choose("Nehalem", 1, all), "Sandybridge");
  EXPECT_EQ(choose("Prescott", 0, all), "(kept)");  // nothing better to run
  EXPECT_EQ(choose("Prescott", 3, none), "(kept)");  // the library has no better tables
  EXPECT_EQ(choose("Haswell", 3, all), "(kept)");    // OpenBLAS's own choice
  EXPECT_EQ(choose("Zen", 3, all), "(kept)");
  EXPECT_EQ(choose("Sandybridge", 2, all), "(kept)");
  EXPECT_EQ(choose("SomeFutureCore", 3, all), "(kept)");
}

TEST(BlasKernels, SwitchKeepsTheFactorizationsRight) {
  if (BlasCoreName().empty()) GTEST_SKIP() << "the BLAS is not OpenBLAS";
  const Eigen::SparseMatrix<double> H = SystemWithAWideSupernode();
  const Eigen::VectorXd b = Eigen::VectorXd::LinSpaced(H.rows(), -1.0, 1.0);
  auto solve = [&] {
    Eigen::CholmodDecomposition<Eigen::SparseMatrix<double>, Eigen::Lower> factor;
    factor.setMode(Eigen::CholmodSupernodalLLt);
    factor.compute(H);
    EXPECT_EQ(factor.info(), Eigen::Success);
    return Eigen::VectorXd(factor.solve(b));
  };
  const Eigen::VectorXd x0 = solve();
  const bool user_chose = std::getenv("OPENBLAS_CORETYPE") != nullptr;
  const char* better = BetterBlasCoreType();
  const std::string wanted = better != nullptr ? better : BlasCoreName();
  EXPECT_EQ(UseBetterBlasKernels(), wanted);
  EXPECT_EQ(BlasCoreName(), wanted);
  EXPECT_FALSE(BlasLibraryPath().empty());
  if (!user_chose) unsetenv("OPENBLAS_CORETYPE");  // the switch sets it; the later tests as before
  const Eigen::VectorXd x1 = solve();
  EXPECT_LE((H * x1 - b).norm(), 1e-10 * b.norm());
  EXPECT_LE((x1 - x0).norm(), 1e-10 * x0.norm());
}

}  // namespace
}  // namespace femreg
