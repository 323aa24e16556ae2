// What contacts cost (Google Benchmark): Track per frame over datasets/contact_pair and
// datasets/tool_table with effects.collision off and on, on either back end, and the
// detection alone (refit, broad and narrow phase) on the contact_pair meshes. Run from a build with
// -DFEMREG_BUILD_BENCHMARKS=ON:
//   bench/femreg_collision_bench --benchmark_repetitions=3
#include <benchmark/benchmark.h>

#include <algorithm>
#include <cstdio>
#include <memory>
#include <string>
#include <vector>

#include "femreg/scene.h"
#include "femreg/collision.h"
#include "femreg/point_cloud.h"
#include "femreg/tracker.h"

namespace {

constexpr int kFrames = 12;
const char* kSequences[] = {"contact_pair", "tool_table"};

const std::vector<femreg::PointCloud>& Clouds(int sequence) {
  static std::vector<femreg::PointCloud> clouds[2];
  if (clouds[sequence].empty()) {
    for (int f = 0; f < kFrames; ++f) {
      char path[512];
      std::snprintf(path, sizeof(path), "%s/datasets/%s/clouds/frame_%04d.pcd", FEMREG_SOURCE_DIR,
                    kSequences[sequence], f);
      femreg::PointCloud cloud;
      femreg::ReadPointCloud(path, &cloud);
      clouds[sequence].push_back(cloud);
    }
  }
  return clouds[sequence];
}

// range(0): sequence (0 contact_pair, 1 tool_table); range(1): collision off / on;
// range(2): back end (0 Ceres, 1 fast).
void Track(benchmark::State& state) {
  const int sequence = static_cast<int>(state.range(0));
  femreg::Scene scene;
  if (!femreg::LoadScene(std::string(FEMREG_SOURCE_DIR) + "/datasets/" + kSequences[sequence] +
                             "/scene.yaml", &scene).ok()) {
    state.SkipWithError("dataset missing: run femreg contact-data");
    return;
  }
  scene.effects.collision = state.range(1) == 1;
  scene.registration.solver.backend =
      state.range(2) == 1 ? femreg::SolverBackend::kFast : femreg::SolverBackend::kCeres;
  double collision_s = 0.0;
  int contacts = 0;
  for (auto _ : state) {
    state.PauseTiming();
    std::unique_ptr<femreg::Tracker> tracker;
    femreg::Tracker::Create(scene, &tracker);
    state.ResumeTiming();
    for (const femreg::PointCloud& cloud : Clouds(sequence)) {
      femreg::FrameSummary summary;
      tracker->Track(cloud, &summary);
      collision_s += summary.time.collision;
      contacts += summary.contacts;
    }
  }
  const double frames = std::max<double>(1.0, static_cast<double>(state.iterations() * kFrames));
  state.SetItemsProcessed(state.iterations() * kFrames);
  state.counters["collision_ms_per_frame"] = 1e3 * collision_s / frames;
  state.counters["contacts_per_frame"] = contacts / frames;
}
BENCHMARK(Track)
    ->ArgsProduct({{0, 1}, {0, 1}, {0, 1}})
    ->ArgNames({"sequence", "collision", "fast"})
    ->Unit(benchmark::kMillisecond);

// Detection alone on the two contact_pair blocks pressed together (the last frame's pose).
void Detect(benchmark::State& state) {
  femreg::Scene scene;
  std::unique_ptr<femreg::Tracker> tracker;
  if (!femreg::LoadScene(std::string(FEMREG_SOURCE_DIR) + "/datasets/contact_pair/scene.yaml", &scene).ok() ||
      !femreg::Tracker::Create(scene, &tracker).ok() || tracker->collision() == nullptr) {
    state.SkipWithError("dataset missing: run femreg contact-data");
    return;
  }
  for (const femreg::PointCloud& cloud : Clouds(0)) {
    femreg::FrameSummary summary;
    tracker->Track(cloud, &summary);
  }
  femreg::Vertices x(tracker->mesh(0).num_vertices() + tracker->mesh(1).num_vertices(), 3);
  x << tracker->vertices(0), tracker->vertices(1);
  const femreg::CollisionWorld& tracked = *tracker->collision();
  femreg::CollisionWorld world = tracked;
  std::vector<femreg::Contact> contacts;
  for (auto _ : state) {
    world.Detect(x, scene.collision.distance, &contacts);
    benchmark::DoNotOptimize(contacts.data());
  }
  state.counters["contacts"] = static_cast<double>(contacts.size());
}
BENCHMARK(Detect)->Unit(benchmark::kMicrosecond);

}  // namespace

BENCHMARK_MAIN();
