// Time per registered frame on the bundled demo (Google Benchmark): the scene's settings at
// two mesh resolutions, and per regularizer. Run from a build with
// -DFEMREG_BUILD_BENCHMARKS=ON:  bench/femreg_registration_bench --benchmark_repetitions=3
#include <benchmark/benchmark.h>

#include <memory>
#include <string>
#include <vector>

#include "femreg/scene.h"
#include "femreg/experiment.h"
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
