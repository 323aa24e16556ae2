// Time per registered frame on the bundled demo (Google Benchmark): the scene's settings at
// two mesh resolutions, and per regularizer; and on the organ_patch sequence with its body
// divided 4 (729 vertices, the bundled mesh), 6 (2197 / 10368 tetrahedra) and 7 (3375 /
// 16464): the "3k-vertex organ against 500-point clouds" of the speed targets. Run from a
// build with -DFEMREG_BUILD_BENCHMARKS=ON:  bench/femreg_registration_bench --benchmark_repetitions=3
// (the organ cases write their sequences into the temporary folder first, which takes a while).
#include <benchmark/benchmark.h>

#include <cstdio>
#include <filesystem>
#include <map>

#include <memory>
#include <string>
#include <vector>

#include "femreg/datasets.h"
#include "femreg/scene.h"
#include "femreg/experiment.h"
#include "femreg/ground_truth.h"
#include "femreg/point_cloud.h"
#include "femreg/tracker.h"

namespace {

const femreg::Dataset& Demo() {
  static femreg::Dataset* dataset = [] {
    auto* d = new femreg::Dataset;
    const femreg::Status s = femreg::LoadDataset(std::string(FEMREG_SOURCE_DIR) + "/datasets/demo", d, 12);
    if (!s.ok()) std::fprintf(stderr, "%s\n", s.message().c_str());
    return d;
  }();
  return *dataset;
}

const std::vector<femreg::PointCloud>& DemoClouds() {
  static std::vector<femreg::PointCloud>* clouds = [] {
    auto* c = new std::vector<femreg::PointCloud>;
    for (const std::string& f : Demo().clouds) {
      femreg::PointCloud cloud;
      femreg::ReadPointCloud(f, &cloud);
      c->push_back(cloud);
    }
    return c;
  }();
  return *clouds;
}

// Tracks the first 12 frames of the demo per iteration: time / 12 is the time per frame;
// items_per_second is frames per second.
void TrackDemo(benchmark::State& state, double resolution, femreg::Regularizer regularizer) {
  femreg::Scene scene = Demo().scene;
  scene.registration.regularizer = regularizer;
  for (femreg::ObjectSpec& o : scene.objects) {
    o.generate.cells = (o.generate.cells.cast<double>() * resolution).array().round().cast<int>().max(1);
  }
  int vertices = 0;
  for (auto _ : state) {
    state.PauseTiming();
    std::unique_ptr<femreg::Tracker> tracker;
    femreg::Tracker::Create(scene, &tracker);
    vertices = tracker->mesh(0).num_vertices();
    state.ResumeTiming();
    for (const femreg::PointCloud& cloud : DemoClouds()) {
      femreg::FrameSummary summary;
      tracker->Track(cloud, &summary);
      benchmark::DoNotOptimize(summary.final.total());
    }
  }
  state.SetItemsProcessed(state.iterations() * static_cast<int64_t>(DemoClouds().size()));
  state.counters["vertices"] = vertices;
  state.counters["frames"] = static_cast<double>(DemoClouds().size());
}

// organ_patch with its tracked body divided `divisions` times (femreg organ-data
// --divisions), all 12 frames per iteration, on `threads` threads (0: all). Counters: the
// mean vertex error against the ground truth (mm) and the frames that converged.
void TrackOrgan(benchmark::State& state) {
  const int divisions = static_cast<int>(state.range(0));
  static std::map<int, femreg::Dataset>* datasets = new std::map<int, femreg::Dataset>;
  if (datasets->count(divisions) == 0) {
    const std::string dir = (std::filesystem::temp_directory_path() /
                             ("femreg_bench_organ_" + std::to_string(divisions))).string();
    if (!std::filesystem::exists(dir + "/scene.yaml")) {
      const femreg::Status s = femreg::GenerateOrganPatchSequence(dir, nullptr, divisions);
      if (!s.ok()) {
        state.SkipWithError(s.message().c_str());
        return;
      }
    }
    femreg::Dataset d;
    const femreg::Status s = femreg::LoadDataset(dir, &d);
    if (!s.ok()) {
      state.SkipWithError(s.message().c_str());
      return;
    }
    (*datasets)[divisions] = d;
  }
  const femreg::Dataset& dataset = datasets->at(divisions);
  femreg::Scene scene = dataset.scene;
  scene.registration.solver.num_threads = static_cast<int>(state.range(1));
  std::vector<femreg::PointCloud> clouds(dataset.clouds.size());
  std::vector<femreg::GroundTruthFrame> truth(dataset.truth.size());
  for (size_t f = 0; f < clouds.size(); ++f) femreg::ReadPointCloud(dataset.clouds[f], &clouds[f]);
  for (size_t f = 0; f < truth.size(); ++f) femreg::ReadGroundTruthFrame(dataset.truth[f], &truth[f]);
  int vertices = 0, converged = 0;
  double error = 0.0;
  for (auto _ : state) {
    state.PauseTiming();
    std::unique_ptr<femreg::Tracker> tracker;
    femreg::Tracker::Create(scene, &tracker);
    vertices = tracker->mesh(0).num_vertices();
    converged = 0;
    error = 0.0;
    state.ResumeTiming();
    for (size_t f = 0; f < clouds.size(); ++f) {
      femreg::FrameSummary summary;
      tracker->Track(clouds[f], &summary);
      state.PauseTiming();
      converged += summary.termination == femreg::TerminationType::kConverged ? 1 : 0;
      error += (tracker->vertices(0) - truth[f].positions).rowwise().norm().mean() * 1e3;
      state.ResumeTiming();
    }
  }
  state.SetItemsProcessed(state.iterations() * static_cast<int64_t>(clouds.size()));
  state.counters["vertices"] = vertices;
  state.counters["converged"] = converged;
  state.counters["error_mm"] = error / static_cast<double>(clouds.size());
}
BENCHMARK(TrackOrgan)
    ->ArgsProduct({{4, 6, 7}, {1, 2}})
    ->ArgNames({"divisions", "threads"})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();

BENCHMARK_CAPTURE(TrackDemo, corotational_1116_vertices, 1.0, femreg::Regularizer::kCorotational)
    ->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK_CAPTURE(TrackDemo, corotational_coarse, 0.5, femreg::Regularizer::kCorotational)
    ->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK_CAPTURE(TrackDemo, corotational_fine, 1.5, femreg::Regularizer::kCorotational)
    ->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK_CAPTURE(TrackDemo, linear_1116_vertices, 1.0, femreg::Regularizer::kLinear)
    ->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK_CAPTURE(TrackDemo, temporal_only_1116_vertices, 1.0, femreg::Regularizer::kNone)
    ->Unit(benchmark::kMillisecond)->UseRealTime();

}  // namespace

BENCHMARK_MAIN();
