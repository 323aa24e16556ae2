// Time of one forward quasi-static solve of a clamped beam (L = 1 m, 0.1 m square section,
// E = 1e6 Pa) under a small tip load, for about 1,000 and 10,000 vertices; and the soft sag of
// issue 14 (a nearly incompressible cylinder bending under its own weight).
//   export OMP_NUM_THREADS=1 OPENBLAS_NUM_THREADS=1
//   build/bench/femreg_forward_bench --benchmark_repetitions=5 --benchmark_report_aggregates_only
#include <benchmark/benchmark.h>

#include <vector>

#include "femreg/scene.h"
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
  state.counters["iterations"] = summary.NumNewtonIterations();
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

// The soft sag: a silicone-like cylinder, radius 3 cm, length 40 cm (2,009 vertices, 8,640
// tets), E = 440 kPa, nu = 0.49, 1000 kg/m^3, clamped at z = 0 and sagging under gravity
// across its axis (-x) in one load step: the free end moves about 13 cm down and 2.5 cm
// toward the clamp. Arguments: the Newton matrix (ForwardTangent: 0 warped, 1 projected,
// 2 full) and the watchdog (0 = monotone line search). Counters: Newton iterations of the
// step, how many of them fell back to the projected tangent, the free end's deflection.
void BM_ForwardSag(benchmark::State& state) {
  const double length = 0.4;
  const TetMesh rest_mesh = [&] {
    TetMesh mesh = MakeCylinder(0.03, length, 3, 40);
    ComputeLumpedMasses(&mesh, 1000.0);
    return mesh;
  }();
  ForwardProblem problem;
  std::vector<int> tip;
  for (int v = 0; v < rest_mesh.num_vertices(); ++v) {
    if (rest_mesh.rest(v, 2) < 1e-9) problem.clamped.push_back(v);
    if (rest_mesh.rest(v, 2) > length - 1e-9) tip.push_back(v);
  }
  problem.gravity = Eigen::Vector3d(-9.81, 0, 0);
  Material material;
  material.youngs_modulus = 4.4e5;
  material.poisson_ratio = 0.49;
  material.density = 1000.0;
  ForwardOptions options;
  options.max_iterations = 500;
  options.tangent = static_cast<ForwardTangent>(state.range(0));
  options.watchdog_steps = state.range(1) != 0 ? ForwardOptions().watchdog_steps : 0;
  ForwardSummary summary;
  TetMesh mesh;
  for (auto _ : state) {
    state.PauseTiming();
    mesh = rest_mesh;
    ElasticModel model;
    model.Build(mesh, ElasticModelType::kCorotational, material);
    state.ResumeTiming();
    SolveQuasiStatic(problem, options, &model, &mesh, &summary);
    if (summary.termination != ForwardTermination::kConverged) {
      state.SkipWithError(summary.message.c_str());
      break;
    }
  }
  double deflection = 0.0;
  for (int v : tip) deflection -= mesh.x(v, 0) - mesh.rest(v, 0);
  state.counters["vertices"] = rest_mesh.num_vertices();
  state.counters["tets"] = rest_mesh.num_tets();
  state.counters["iterations"] = summary.NumNewtonIterations();
  state.counters["projected_iterations"] =
      summary.load_steps.empty() ? 0 : summary.load_steps[0].projected_iterations;
  state.counters["tip_deflection_m"] = deflection / tip.size();
  state.counters["factorization_s"] = summary.factorization_time_s;
}
BENCHMARK(BM_ForwardSag)
    ->ArgNames({"tangent", "watchdog"})
    ->Args({static_cast<int>(ForwardTangent::kFull), 1})
    ->Args({static_cast<int>(ForwardTangent::kFull), 0})
    ->Args({static_cast<int>(ForwardTangent::kProjected), 1})
    ->Args({static_cast<int>(ForwardTangent::kWarped), 1})
    ->Args({static_cast<int>(ForwardTangent::kWarped), 0})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime()
    ->Iterations(1);

}  // namespace
}  // namespace femreg

BENCHMARK_MAIN();
