// Time of one forward quasi-static solve of a clamped beam (L = 1 m, 0.1 m square section,
// E = 1e6 Pa) under a small tip load, for about 1,000 and 10,000 vertices.
//   build/bench/femreg_forward_bench --benchmark_repetitions=5 --benchmark_report_aggregates_only
#include <benchmark/benchmark.h>

#include "femreg/fem.h"
#include "femreg/forward.h"
#include "femreg/io.h"
#include "femreg/mesh.h"

namespace femreg {
namespace {

// n cells across the section, 10 n along: n = 4 gives 1,025 vertices, n = 9 gives 9,100.
void BM_ForwardSolveBeam(benchmark::State& state) {
  const int n = static_cast<int>(state.range(0));
  const auto type = static_cast<ElasticModelType>(state.range(1));
  const TetMesh beam = MakeBox(Eigen::Vector3d(1.0, 0.1, 0.1), 10 * n, n, n);
  ForwardProblem problem;
  std::vector<int> tip;
  for (int v = 0; v < beam.num_vertices(); ++v) {
    if (beam.rest(v, 0) < 1e-9) problem.clamped.push_back(v);
    if (beam.rest(v, 0) > 1.0 - 1e-9) tip.push_back(v);
  }
  for (int v : tip) problem.nodal_loads.push_back({v, Eigen::Vector3d(0, 0, -0.5 / tip.size())});
  Material material;
  material.youngs_modulus = 1e6;
  ForwardOptions options;
  ForwardSummary summary;
  for (auto _ : state) {
    state.PauseTiming();
    TetMesh mesh = beam;
    ElasticModel model;
    model.Build(mesh, type, material);
    state.ResumeTiming();
    SolveQuasiStatic(problem, options, &model, &mesh, &summary);
    if (summary.termination != ForwardTermination::kConverged) {
      state.SkipWithError(summary.message.c_str());
      break;
    }
  }
  state.counters["vertices"] = beam.num_vertices();
  state.counters["iterations"] = static_cast<double>(summary.iterations.size());
  state.counters["factorization_s"] = summary.factorization_time_s;
}
BENCHMARK(BM_ForwardSolveBeam)
    ->ArgNames({"n", "model"})
    ->Args({4, static_cast<int>(ElasticModelType::kCorotational)})
    ->Args({4, static_cast<int>(ElasticModelType::kLinear)})
    ->Args({9, static_cast<int>(ElasticModelType::kCorotational)})
    ->Args({9, static_cast<int>(ElasticModelType::kLinear)})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();

}  // namespace
}  // namespace femreg

BENCHMARK_MAIN();
