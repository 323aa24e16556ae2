// The sparse Cholesky choices of the fast back end, measured on the system it solves: the
// corotational stiffness (R = I) of a box mesh plus a diagonal (masses, data springs), 3 #V
// by 3 #V with full 3x3 vertex blocks. Simplicial and supernodal CHOLMOD, the factorization
// and one solve; the back end's own factorization and substitutions (float and double); one
// product H p (what an iteration of PCG costs besides a solve); the multigrid preconditioner
// that replaces the factor on large meshes (its hierarchy, and one V-cycle against OwnSolve's
// substitution pair).
// Run single-threaded to compare the kernels, then with more threads:
//   bench/femreg_linear_solver_bench --benchmark_repetitions=5 --benchmark_report_aggregates_only
#include <benchmark/benchmark.h>

#include <Eigen/CholmodSupport>
#include <Eigen/SparseCore>
#include <type_traits>
#include <vector>

#include "energy/assembler.h"
#include "femreg/scene.h"
#include "femreg/fem.h"
#include "femreg/io.h"
#include "parallel/threads.h"
#include "solvers/fast/fast_backend.h"
#include "solvers/fast/multigrid.h"
#include "solvers/fast/supernodal_solve.h"

namespace {

// A box of about `vertices` vertices, 5:1:1 like the demo's beam (the mesh to *mesh).
Eigen::SparseMatrix<double> BoxSystem(int vertices, femreg::TetMesh* mesh_out = nullptr) {
  // (5n + 1)(n + 1)^2 ~ vertices
  int n = 1;
  while ((5 * (n + 1) + 1) * (n + 2) * (n + 2) <= vertices) ++n;
  const femreg::TetMesh mesh = femreg::MakeBox(Eigen::Vector3d(0.5, 0.1, 0.1), 5 * n, n, n);
  femreg::Material material;
  material.youngs_modulus = 5e4;
  femreg::ElasticModel model;
  model.Build(mesh, femreg::ElasticModelType::kCorotational, material);
  std::vector<Eigen::Triplet<double>> triplets;
  model.AddStiffnessTriplets(&triplets);
  const int dofs = 3 * mesh.num_vertices();
  for (int i = 0; i < dofs; ++i) triplets.emplace_back(i, i, 1.0);
  Eigen::SparseMatrix<double> H(dofs, dofs);
  H.setFromTriplets(triplets.begin(), triplets.end());
  H.makeCompressed();
  if (mesh_out != nullptr) *mesh_out = mesh;
  return H;
}

template <int kMode>
void Factorize(benchmark::State& state) {
  const Eigen::SparseMatrix<double> H = BoxSystem(static_cast<int>(state.range(0)));
  femreg::ScopedThreads threads(static_cast<int>(state.range(1)));
  Eigen::CholmodDecomposition<Eigen::SparseMatrix<double>, Eigen::Lower> llt;
  llt.setMode(static_cast<Eigen::CholmodMode>(kMode));
  llt.analyzePattern(H);
  for (auto _ : state) {
    llt.factorize(H);
    benchmark::DoNotOptimize(llt.info());
  }
  state.counters["dofs"] = static_cast<double>(H.rows());
}

template <int kMode>
void Solve(benchmark::State& state) {
  const Eigen::SparseMatrix<double> H = BoxSystem(static_cast<int>(state.range(0)));
  femreg::ScopedThreads threads(static_cast<int>(state.range(1)));
  Eigen::CholmodDecomposition<Eigen::SparseMatrix<double>, Eigen::Lower> llt;
  llt.setMode(static_cast<Eigen::CholmodMode>(kMode));
  llt.compute(H);
  const Eigen::VectorXd b = Eigen::VectorXd::Ones(H.rows());
  Eigen::VectorXd x;
  for (auto _ : state) {
    x = llt.solve(b);
    benchmark::DoNotOptimize(x.data());
  }
  state.counters["dofs"] = static_cast<double>(H.rows());
}

// The back end's own substitutions with the supernodal factor (PCG's preconditioner), its
// values in Scalar; on `threads` threads.
// Range 2 (float only): 1 for the substitutions in float (set_single_work), 0 in double.
template <class Scalar>
void OwnSolve(benchmark::State& state) {
  const Eigen::SparseMatrix<double> H = BoxSystem(static_cast<int>(state.range(0)));
  femreg::fast_backend::CholmodFactor llt;
  llt.setMode(Eigen::CholmodSupernodalLLt);
  llt.compute(H);
  femreg::fast_backend::SupernodalSolve<Scalar> solve;
  solve.Load(*llt.raw(), true, static_cast<int>(state.range(1)));
  if constexpr (std::is_same<Scalar, float>::value) solve.set_single_work(state.range(2) != 0);
  const Eigen::VectorXd b = Eigen::VectorXd::Ones(H.rows());
  Eigen::VectorXd x;
  for (auto _ : state) {
    solve.Solve(b, &x);
    benchmark::DoNotOptimize(x.data());
  }
  state.counters["dofs"] = static_cast<double>(H.rows());
  state.counters["serial"] = solve.serial_fraction();
  state.counters["nnzL"] = static_cast<double>(llt.raw()->xsize);
  state.counters["nsuper"] = static_cast<double>(llt.raw()->nsuper);
}

// The back end's own numeric factorization (Scalar) on CHOLMOD's supernodal analysis of the
// same pattern (CHOLMOD's default ordering here, as in Factorize above); its subtrees on
// `threads` threads, each BLAS call on one.
template <class Scalar>
void OwnFactorize(benchmark::State& state) {
  const Eigen::SparseMatrix<double> H = BoxSystem(static_cast<int>(state.range(0)));
  femreg::fast_backend::CholmodFactor llt;
  llt.setMode(Eigen::CholmodSupernodalLLt);
  llt.analyzePattern(H);
  const femreg::ScopedThreads one_blas_thread(1);
  const int threads = static_cast<int>(state.range(1));
  femreg::fast_backend::SupernodalSolve<Scalar> factor;
  if (!factor.Factorize(*llt.raw(), H, true, threads)) state.SkipWithError("not positive definite");
  for (auto _ : state) {
    benchmark::DoNotOptimize(factor.Factorize(*llt.raw(), H, false, threads));
  }
  state.counters["dofs"] = static_cast<double>(H.rows());
  state.counters["flops"] = llt.cholmod().fl;  // CHOLMOD's count, what the back end sizes its team by
  state.counters["serial"] = factor.serial_fraction();
}

// The equilibrium step's L S L^T (FactorizeIndefinite) of the same matrix, positive definite
// (range 2: 0), as OwnFactorize's Cholesky costs, or shifted by a hundredth of its mean
// diagonal (1), where its lowest modes give negative pivots.
template <class Scalar>
void OwnFactorizeIndefinite(benchmark::State& state) {
  Eigen::SparseMatrix<double> H = BoxSystem(static_cast<int>(state.range(0)));
  femreg::fast_backend::CholmodFactor llt;
  llt.setMode(Eigen::CholmodSupernodalLLt);
  llt.analyzePattern(H);
  if (state.range(2) != 0) {
    const double shift = 0.01 * H.diagonal().cwiseAbs().mean();
    for (Eigen::Index c = 0; c < H.cols(); ++c) H.coeffRef(c, c) -= shift;
  }
  const femreg::ScopedThreads one_blas_thread(1);
  const int threads = static_cast<int>(state.range(1));
  femreg::fast_backend::SupernodalSolve<Scalar> factor;
  if (!factor.FactorizeIndefinite(*llt.raw(), H, true, threads)) state.SkipWithError("not finite");
  for (auto _ : state) {
    benchmark::DoNotOptimize(factor.FactorizeIndefinite(*llt.raw(), H, false, threads));
  }
  state.counters["dofs"] = static_cast<double>(H.rows());
  state.counters["negative"] = factor.negative_pivots();
  state.counters["perturbed"] = factor.perturbed_pivots();
}

void Product(benchmark::State& state) {
  const Eigen::SparseMatrix<double> H = BoxSystem(static_cast<int>(state.range(0)));
  const Eigen::VectorXd p = Eigen::VectorXd::Ones(H.rows());
  Eigen::VectorXd y(H.rows());
  for (auto _ : state) {
    y.noalias() = H * p;
    benchmark::DoNotOptimize(y.data());
  }
  state.counters["dofs"] = static_cast<double>(H.rows());
}

// The fast back end's own product (PCG's and the equilibrium step's), on the same matrix:
// one row vertex per 3x3 block.
void BlockProduct(benchmark::State& state) {
  const Eigen::SparseMatrix<double> H = BoxSystem(static_cast<int>(state.range(0)));
  const std::vector<int> block_rows = femreg::energy::BlockRowVertices(H);
  const Eigen::VectorXd p = Eigen::VectorXd::Ones(H.rows());
  Eigen::VectorXd y(H.rows());
  const int threads = static_cast<int>(state.range(1));
  for (auto _ : state) {
    femreg::fast_backend::BlockProduct(H, block_rows, p, threads, &y);
    benchmark::DoNotOptimize(y.data());
  }
  state.counters["dofs"] = static_cast<double>(H.rows());
}

// The multigrid hierarchy's build (aggregation, prolongators, Galerkin products), with the
// box's rest positions as the rigid motions' centre.
void MultigridBuild(benchmark::State& state) {
  femreg::TetMesh mesh;
  const Eigen::SparseMatrix<double> H = BoxSystem(static_cast<int>(state.range(0)), &mesh);
  const femreg::ScopedThreads threads(static_cast<int>(state.range(1)));
  femreg::fast_backend::Multigrid mg;
  for (auto _ : state) {
    benchmark::DoNotOptimize(mg.Build(H, mesh.rest, static_cast<int>(state.range(1))));
  }
  state.counters["dofs"] = static_cast<double>(H.rows());
  state.counters["levels"] = mg.num_levels();
  state.counters["operator_complexity"] = mg.operator_complexity();
}

// A new system for a kept hierarchy (Multigrid::SetFinest): what each step with multigrid
// pays before its PCG (the finest values in bfloat16, the smoother's block inverses).
void MultigridSetFinest(benchmark::State& state) {
  femreg::TetMesh mesh;
  const Eigen::SparseMatrix<double> H = BoxSystem(static_cast<int>(state.range(0)), &mesh);
  const femreg::ScopedThreads threads(static_cast<int>(state.range(1)));
  femreg::fast_backend::Multigrid mg;
  if (!mg.Build(H, mesh.rest, static_cast<int>(state.range(1)))) state.SkipWithError("build failed");
  for (auto _ : state) {
    benchmark::DoNotOptimize(mg.SetFinest(H));
  }
  state.counters["dofs"] = static_cast<double>(H.rows());
}

// One V-cycle: what a PCG iteration with multigrid costs besides the product.
void MultigridCycle(benchmark::State& state) {
  femreg::TetMesh mesh;
  const Eigen::SparseMatrix<double> H = BoxSystem(static_cast<int>(state.range(0)), &mesh);
  const femreg::ScopedThreads threads(static_cast<int>(state.range(1)));
  femreg::fast_backend::Multigrid mg;
  if (!mg.Build(H, mesh.rest, static_cast<int>(state.range(1)))) state.SkipWithError("build failed");
  const Eigen::VectorXd b = Eigen::VectorXd::Ones(H.rows());
  Eigen::VectorXd x;
  for (auto _ : state) {
    mg.Apply(b, &x);
    benchmark::DoNotOptimize(x.data());
  }
  state.counters["dofs"] = static_cast<double>(H.rows());
}

void Sizes(benchmark::internal::Benchmark* b) {
  for (int v : {1000, 4000, 16000, 64000}) {
    for (int t : {1, 2}) b->Args({v, t});
  }
  b->ArgNames({"vertices", "threads"})->Unit(benchmark::kMillisecond);
}

BENCHMARK_TEMPLATE(Factorize, Eigen::CholmodSimplicialLLt)->Apply(Sizes);
BENCHMARK_TEMPLATE(Factorize, Eigen::CholmodSupernodalLLt)->Apply(Sizes);
BENCHMARK_TEMPLATE(Solve, Eigen::CholmodSimplicialLLt)->Apply(Sizes);
BENCHMARK_TEMPLATE(Solve, Eigen::CholmodSupernodalLLt)->Apply(Sizes);
// Between Sizes' 1k and 4k: where a second thread starts to pay for the own factorization
// (kFactorizationFlopsPerThread in fast_backend_factor.cc).
void TeamSizes(benchmark::internal::Benchmark* b) {
  for (int v : {1000, 2000, 2500, 4000}) {  // boxes of 936, 1,519, 2,304 and 3,321 vertices
    for (int t : {1, 2}) b->Args({v, t});
  }
  b->ArgNames({"vertices", "threads"})->Unit(benchmark::kMillisecond);
}

BENCHMARK_TEMPLATE(OwnFactorize, float)->Apply(TeamSizes);
BENCHMARK_TEMPLATE(OwnFactorize, double)->Apply(Sizes);
void IndefiniteSizes(benchmark::internal::Benchmark* b) {
  for (int v : {1000, 4000}) {
    for (int t : {1, 2}) {
      for (int shifted : {0, 1}) b->Args({v, t, shifted});
    }
  }
  b->ArgNames({"vertices", "threads", "shifted"})->Unit(benchmark::kMillisecond);
}
BENCHMARK_TEMPLATE(OwnFactorizeIndefinite, float)->Apply(IndefiniteSizes);
void WorkSizes(benchmark::internal::Benchmark* b) {
  for (int v : {1000, 4000, 16000, 64000}) {
    for (int t : {1, 2}) {
      for (int single : {0, 1}) b->Args({v, t, single});
    }
  }
  b->ArgNames({"vertices", "threads", "single_work"})->Unit(benchmark::kMillisecond);
}
BENCHMARK_TEMPLATE(OwnSolve, float)->Apply(WorkSizes);
BENCHMARK_TEMPLATE(OwnSolve, double)->Apply(Sizes);
BENCHMARK(Product)->Apply(Sizes);
BENCHMARK(BlockProduct)->Apply(Sizes);
BENCHMARK(MultigridBuild)->Apply(Sizes);
BENCHMARK(MultigridSetFinest)->Apply(Sizes);
BENCHMARK(MultigridCycle)->Apply(Sizes);

}  // namespace

BENCHMARK_MAIN();
