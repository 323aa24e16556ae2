// femreg owns its threads: what runs under femreg's thread count stays within it, even in
// libraries that ask for teams of their own (CHOLMOD 5's supernodal factorization asks
// OpenMP for 4 threads whatever the program set).
#include <gtest/gtest.h>

#include <Eigen/CholmodSupport>
#include <Eigen/SparseCore>
#include <filesystem>
#include <iterator>
#include <vector>

#include "femreg/fem.h"
#include "femreg/io.h"
#include "parallel/threads.h"

namespace femreg {
namespace {

int ThreadsInProcess() {
  const std::filesystem::directory_iterator tasks("/proc/self/task");
  return static_cast<int>(std::distance(begin(tasks), end(tasks)));
}

// The stiffness of a box of about 3k vertices plus a diagonal: its last supernodes are
// wider than the 64 columns from which CHOLMOD 5 factorizes in parallel.
Eigen::SparseMatrix<double> BoxSystem() {
  const TetMesh mesh = MakeBox(Eigen::Vector3d(0.5, 0.1, 0.1), 40, 8, 8);
  Material material;
  material.youngs_modulus = 5e4;
  ElasticModel model;
  model.Build(mesh, ElasticModelType::kCorotational, material);
  std::vector<Eigen::Triplet<double>> triplets;
  model.AddStiffnessTriplets(&triplets);
  const int dofs = 3 * mesh.num_vertices();
  for (int i = 0; i < dofs; ++i) triplets.emplace_back(i, i, 1.0);
  Eigen::SparseMatrix<double> H(dofs, dofs);
  H.setFromTriplets(triplets.begin(), triplets.end());
  return H;
}

TEST(Threads, ThreadLimitHoldsCholmodsOwnTeams) {
  const Eigen::SparseMatrix<double> H = BoxSystem();
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

TEST(Threads, ThreadLimitRunsTheFunctionOnce) {
  int calls = 0;
  WithThreadLimit(2, [&] { ++calls; });
  EXPECT_EQ(calls, 1);
}

}  // namespace
}  // namespace femreg
