// What fracture costs (Google Benchmark): Track per frame on the first 12 frames of
// datasets/beam_break (before the break) with effects.fracture off, on with a toughness
// nothing reaches (detection every outer iteration, no split), and on as bundled (its
// toughness: the measure nears it from frame 8 on, and fracture is live from there), plus
// the detection alone. Off is the baseline: with fracture off the tracker computes no tensor
// and allocates nothing for it. Run from a build with -DFEMREG_BUILD_BENCHMARKS=ON, the cases
// interleaved (the machine's load drifts):
//   bench/femreg_fracture_bench --benchmark_filter=TrackBeam --benchmark_repetitions=9
//     --benchmark_enable_random_interleaving=true   (one command line)
// measure:1 also reads Tracker::fracture_measure after each frame, as `femreg register` does
// for its VTU (after a partial detection, a full evaluation).
#include <benchmark/benchmark.h>

#include <cstdio>
#include <memory>
#include <string>
#include <vector>

#include "femreg/scene.h"
#include "femreg/fracture.h"
#include "femreg/io.h"
#include "femreg/point_cloud.h"
#include "femreg/tracker.h"
#include "fracture/measure_bound.h"

namespace {

constexpr int kFrames = 12;

const std::vector<femreg::PointCloud>& Clouds() {
  static std::vector<femreg::PointCloud>* clouds = [] {
    auto* c = new std::vector<femreg::PointCloud>;
    for (int f = 0; f < kFrames; ++f) {
      char path[512];
      std::snprintf(path, sizeof(path), "%s/datasets/beam_break/clouds/frame_%04d.pcd", FEMREG_SOURCE_DIR, f);
      femreg::PointCloud cloud;
      femreg::ReadPointCloud(path, &cloud);
      c->push_back(cloud);
    }
    return c;
  }();
  return *clouds;
}

// state.range(0): 0 = fracture off, 1 = on with an unreachable toughness, 2 = on as bundled;
// state.range(1): 1 = read the measure after each frame.
void TrackBeam(benchmark::State& state) {
  femreg::Scene scene;
  femreg::LoadScene(std::string(FEMREG_SOURCE_DIR) + "/datasets/beam_break/scene.yaml", &scene);
  scene.effects.fracture = state.range(0) >= 1;
  if (state.range(0) == 1) {
    for (femreg::ObjectSpec& o : scene.objects) o.toughness = 1e30;
  }
  double fracture_s = 0.0;
  for (auto _ : state) {
    state.PauseTiming();
    std::unique_ptr<femreg::Tracker> tracker;
    femreg::Tracker::Create(scene, &tracker);
    state.ResumeTiming();
    for (const femreg::PointCloud& cloud : Clouds()) {
      femreg::FrameSummary summary;
      tracker->Track(cloud, &summary);
      fracture_s += summary.time.fracture;
      if (state.range(1) == 1) benchmark::DoNotOptimize(tracker->fracture_measure(0).sum());
    }
  }
  state.SetItemsProcessed(state.iterations() * kFrames);
  state.counters["fracture_ms_per_frame"] =
      1e3 * fracture_s / std::max<double>(1.0, static_cast<double>(state.iterations() * kFrames));
}
BENCHMARK(TrackBeam)
    ->ArgsProduct({{0, 1, 2}, {0, 1}})
    ->ArgNames({"fracture", "measure"})
    ->Unit(benchmark::kMillisecond);

// Detection alone (rotations, stresses, tensors, eigenvalues) on a bent beam.
void DetectFracture(benchmark::State& state) {
  femreg::TetMesh mesh = femreg::MakeBox(Eigen::Vector3d(0.3, 0.045, 0.045), 20 * state.range(0),
                                         3 * state.range(0), 3 * state.range(0));
  femreg::Material material;
  femreg::ElasticModel model;
  model.Build(mesh, femreg::ElasticModelType::kCorotational, material);
  femreg::Vertices x = mesh.rest;
  for (int v = 0; v < x.rows(); ++v) x(v, 2) -= 0.2 * x(v, 0) * x(v, 0);
  model.UpdateRotations(x);
  femreg::FractureOptions options;
  femreg::NodeSeparation separation;
  for (auto _ : state) femreg::DetectFracture(mesh, model, x, options, &separation);
  state.counters["vertices"] = mesh.num_vertices();
}
BENCHMARK(DetectFracture)->Arg(1)->Arg(2)->Unit(benchmark::kMillisecond);

// The tracker's detection before the break (fracture/measure_bound.h): the bound everywhere, the
// measure where the bound reaches 0.3 of the toughness (none here: a beam_break-sized mesh,
// bent a quarter as much as above, with beam_break's toughness), the rotations found from the
// model's.
// state.range(0): 1 = the bound's data kept from the previous call (as the tracker keeps it
// until a split), 0 = built at each call.
void DetectBeforeTheBreak(benchmark::State& state) {
  femreg::TetMesh mesh = femreg::MakeBox(Eigen::Vector3d(0.3, 0.045, 0.045), 20, 3, 3);
  femreg::Material material;
  material.youngs_modulus = 5e4;
  material.poisson_ratio = 0.35;
  femreg::ElasticModel model;
  model.Build(mesh, femreg::ElasticModelType::kCorotational, material);
  femreg::Vertices x = mesh.rest;
  for (int v = 0; v < x.rows(); ++v) x(v, 2) -= 0.05 * x(v, 0) * x(v, 0);
  femreg::FractureOptions options;
  options.toughness = 6000;
  femreg::fracture_internal::BoundData kept;
  femreg::fracture_internal::BuildBoundData(mesh, model, options, &kept);
  femreg::NodeSeparation separation;
  int evaluated = 0;
  for (auto _ : state) {
    if (state.range(0) == 1) {
      evaluated = femreg::fracture_internal::DetectFractureAbove(mesh, model, x, 0.3, false, kept, &separation);
    } else {
      evaluated = femreg::fracture_internal::DetectFractureAbove(mesh, model, x, options, 0.3, false, &separation);
    }
  }
  state.counters["evaluated"] = evaluated;
}
BENCHMARK(DetectBeforeTheBreak)->Arg(0)->Arg(1)->ArgName("kept")->Unit(benchmark::kMicrosecond);

// The same detection at beam_break's tracked shapes at the ends of frames 0-11 (fracture off,
// the scene's mesh and material), each from the model's rotations at the frame before: the
// bound's time on the states of a real sequence, with the data kept.
void DetectOnBeamBreak(benchmark::State& state) {
  femreg::Scene scene;
  femreg::LoadScene(std::string(FEMREG_SOURCE_DIR) + "/datasets/beam_break/scene.yaml", &scene);
  scene.effects.fracture = false;
  std::unique_ptr<femreg::Tracker> tracker;
  femreg::Tracker::Create(scene, &tracker);
  std::vector<femreg::Vertices> shapes;
  for (const femreg::PointCloud& cloud : Clouds()) {
    femreg::FrameSummary summary;
    tracker->Track(cloud, &summary);
    shapes.push_back(tracker->mesh(0).x);
  }
  const femreg::TetMesh& mesh = tracker->mesh(0);
  femreg::ElasticModel model;
  model.Build(mesh, femreg::ElasticModelType::kCorotational, scene.objects[0].material);
  femreg::FractureOptions options;
  options.toughness = scene.objects[0].toughness;
  femreg::fracture_internal::BoundData kept;
  femreg::fracture_internal::BuildBoundData(mesh, model, options, &kept);
  std::vector<femreg::ElasticModel> before(shapes.size(), model);  // rotations at the frame before
  for (size_t f = 1; f < shapes.size(); ++f) {
    before[f] = before[f - 1];
    before[f].UpdateRotations(shapes[f - 1]);
  }
  femreg::NodeSeparation separation;
  int evaluated = 0;
  for (auto _ : state) {
    evaluated = 0;
    for (size_t f = 0; f < shapes.size(); ++f) {
      evaluated += femreg::fracture_internal::DetectFractureAbove(mesh, before[f], shapes[f], 0.3, false, kept,
                                                                  &separation);
    }
  }
  state.counters["evaluated"] = evaluated;
}
BENCHMARK(DetectOnBeamBreak)->Unit(benchmark::kMicrosecond);

}  // namespace

BENCHMARK_MAIN();
