// Cost against size (issue 12): ms per registered frame for box meshes of about 1k, 4k, 16k
// and 64k vertices against clouds of 2k to 300k points, the fast back end with default
// settings, one thread. The clouds are the mesh's own surface under a growing bend, sampled
// uniformly by area with 0.5 mm noise, so every size sees the same motion. Run from a build
// with -DFEMREG_BUILD_BENCHMARKS=ON (tools/scaling.sh writes the table and the plot):
//   bench/femreg_scaling_bench --benchmark_filter='Track/1000/'
#include <benchmark/benchmark.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <map>
#include <memory>
#include <random>
#include <utility>
#include <vector>

#include "femreg/io.h"
#include "femreg/mesh.h"
#include "femreg/point_cloud.h"
#include "femreg/registration.h"
#include "femreg/tracker.h"

namespace {

constexpr int kFrames = 5;
const Eigen::Vector3d kSize(0.2, 0.1, 0.05);  // m; cells 4k x 2k x k

// A box with about `vertices` vertices: (4k + 1)(2k + 1)(k + 1) ~ 8 k^3.
femreg::TetMesh Box(int vertices) {
  const int k = std::max(1, static_cast<int>(std::lround(std::cbrt(vertices / 8.0))));
  return femreg::MakeBox(kSize, 4 * k, 2 * k, k);
}

// The rest shape bent by `amount` (m at the far end: z += amount (x / L)^2).
femreg::Vertices Bent(const femreg::TetMesh& mesh, double amount) {
  femreg::Vertices x = mesh.rest;
  for (int v = 0; v < x.rows(); ++v) {
    const double s = x(v, 0) / kSize.x();
    x(v, 2) += amount * s * s;
  }
  return x;
}

// `points` points on the surface at x, uniform by area, with Gaussian noise (sigma 0.5 mm).
femreg::PointCloud SampleSurface(const femreg::TetMesh& mesh, const femreg::Vertices& x, int points,
                                 uint32_t seed) {
  std::mt19937 rng(seed);
  std::vector<double> cumulative;
  double total = 0.0;
  for (int f = 0; f < mesh.num_surface_triangles(); ++f) {
    const Eigen::Vector3d a = x.row(mesh.surface(f, 0)), b = x.row(mesh.surface(f, 1)),
                          c = x.row(mesh.surface(f, 2));
    total += 0.5 * (b - a).cross(c - a).norm();
    cumulative.push_back(total);
  }
  std::uniform_real_distribution<double> u(0.0, 1.0);
  std::normal_distribution<double> noise(0.0, 5e-4);
  femreg::PointCloud cloud;
  cloud.points.resize(points, 3);
  for (int i = 0; i < points; ++i) {
    const int f = static_cast<int>(std::lower_bound(cumulative.begin(), cumulative.end(), u(rng) * total) -
                                   cumulative.begin());
    double r1 = u(rng), r2 = u(rng);
    if (r1 + r2 > 1.0) {
      r1 = 1.0 - r1;
      r2 = 1.0 - r2;
    }
    const Eigen::Vector3d a = x.row(mesh.surface(f, 0)), b = x.row(mesh.surface(f, 1)),
                          c = x.row(mesh.surface(f, 2));
    const Eigen::Vector3d p = a + r1 * (b - a) + r2 * (c - a) + Eigen::Vector3d(noise(rng), noise(rng), noise(rng));
    cloud.points.row(i) = p.transpose();
  }
  return cloud;
}

struct Case {
  femreg::TetMesh mesh;
  std::vector<femreg::PointCloud> clouds;
  std::vector<femreg::Vertices> truth;  // the shape each cloud was sampled from
};

const Case& CaseFor(int vertices, int points) {
  static std::map<std::pair<int, int>, std::unique_ptr<Case>> cases;
  auto& c = cases[{vertices, points}];
  if (!c) {
    c = std::make_unique<Case>();
    c->mesh = Box(vertices);
    for (int f = 0; f < kFrames; ++f) {
      c->truth.push_back(Bent(c->mesh, 0.004 * (f + 1)));
      c->clouds.push_back(SampleSurface(c->mesh, c->truth.back(), points, 17u + static_cast<uint32_t>(f)));
    }
  }
  return *c;
}

// One iteration: a new tracker (not timed) and kFrames frames; the time per frame is the
// reported time / kFrames, items_per_second the frames per second. Arguments: vertices,
// points, preconditioner (0: auto, the default; 1: factor; 2: multigrid), data weight (0:
// per pair, the default 200 N/m; 1: per area, the setting docs/theory/data-weight.md suggests:
// data_per_area 1.15e7 with model_to_cloud_share 0.1; 2: per pair at 36 N/m, what that
// per-area setting gives each point of these 2000-point clouds on the 64k-vertex box, where
// its area-per-point estimate is one triangle's area: docs/performance/scaling.md), threads
// (solver.num_threads; 1 in the size rows, so that they measure the mesh and not the machine).
void Track(benchmark::State& state) {
  const int vertices = static_cast<int>(state.range(0));
  const int points = static_cast<int>(state.range(1));
  const Case& c = CaseFor(vertices, points);
  femreg::RegistrationOptions options;
  options.solver.backend = femreg::SolverBackend::kFast;
  const femreg::Preconditioner preconditioners[] = {femreg::Preconditioner::kAuto, femreg::Preconditioner::kFactor,
                                                    femreg::Preconditioner::kMultigrid};
  options.solver.preconditioner = preconditioners[state.range(2)];
  options.solver.num_threads = static_cast<int>(state.range(4));
  if (state.range(3) == 1) {
    options.weights.data = -1.0;
    options.weights.data_per_area = 1.15e7;
    options.weights.model_to_cloud_share = 0.1;
  } else if (state.range(3) == 2) {
    options.weights.data = 36.0;
  }
  femreg::ObjectMaterial material;
  material.material.youngs_modulus = 5e4;
  material.material.poisson_ratio = 0.4;
  std::map<std::string, double> phase, counts, later;  // per frame, summed
  double converged = 0, frames = 0, used = 0, error = 0;
  // The first frame's wall time apart from the later ones': it also builds the pattern, the
  // analysis and the hierarchy, once per tracker, and first touches their memory.
  double first_frame_s = 0, later_frames_s = 0, later_frames = 0;
  for (auto _ : state) {
    state.PauseTiming();
    std::unique_ptr<femreg::Tracker> tracker;
    if (!femreg::Tracker::Create({c.mesh}, {material}, options, &tracker).ok()) {
      state.SkipWithError("Tracker::Create failed");
      return;
    }
    state.ResumeTiming();
    for (size_t f = 0; f < c.clouds.size(); ++f) {
      femreg::FrameSummary s;
      const auto t0 = std::chrono::steady_clock::now();
      tracker->Track(c.clouds[f], &s);
      const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
      if (f == 0) {
        first_frame_s += seconds;
      } else {
        later_frames_s += seconds;
        later_frames += 1;
      }
      error += (tracker->vertices(0) - c.truth[f]).rowwise().norm().mean();  // negligible beside a frame
      // Every frame's phases, and the later frames' apart (the first one also builds the
      // pattern, the analysis and the hierarchy); `other`: preprocessing, prealignment, collision.
      for (auto* sums : {&phase, &later}) {
        if (sums == &later && f == 0) continue;
        (*sums)["correspondences"] += s.time.correspondences;
        (*sums)["rotations"] += s.time.rotations;
        (*sums)["solve"] += s.time.solve;
        (*sums)["assembly"] += s.time.assembly;
        (*sums)["factorization"] += s.time.factorization;
        (*sums)["linear_solve"] += s.time.linear_solve;
        (*sums)["evaluation"] += s.time.evaluation;
        (*sums)["outputs"] += s.time.outputs;
        (*sums)["preprocess"] += s.time.preprocess;
        (*sums)["other"] += s.time.total - s.time.solve - s.time.correspondences - s.time.rotations - s.time.outputs;
      }
      counts["factorizations"] += s.factorizations;
      counts["pcg_iterations"] += s.pcg_iterations;
      counts["outer_iterations"] += s.outer_iterations;
      counts["inner_iterations"] += s.inner_iterations;
      converged += s.termination == femreg::TerminationType::kConverged;
      used += s.points_used;
      frames += 1;
    }
  }
  state.SetItemsProcessed(state.iterations() * kFrames);
  state.counters["vertices"] = c.mesh.num_vertices();
  state.counters["tets"] = c.mesh.num_tets();
  state.counters["points"] = points;
  state.counters["preconditioner"] = static_cast<double>(state.range(2));
  state.counters["per_area"] = state.range(3) == 1 ? 1.0 : 0.0;
  state.counters["data_per_pair"] = options.weights.data;  // N/m; < 0: per area
  state.counters["threads"] = static_cast<double>(state.range(4));
  state.counters["points_used"] = frames > 0 ? used / frames : 0;
  state.counters["converged"] = frames > 0 ? converged / frames : 0;
  // Mean vertex error against the bent shape the clouds were sampled from (mm).
  state.counters["error_mm"] = frames > 0 ? 1e3 * error / frames : 0;
  state.counters["first_frame_ms"] = state.iterations() > 0 ? 1e3 * first_frame_s / state.iterations() : 0;
  state.counters["later_frame_ms"] = later_frames > 0 ? 1e3 * later_frames_s / later_frames : 0;
  for (const auto& [name, seconds] : phase) state.counters[name + "_ms"] = frames > 0 ? 1e3 * seconds / frames : 0;
  for (const auto& [name, n] : counts) state.counters[name] = frames > 0 ? n / frames : 0;
  for (const auto& [name, seconds] : later) state.counters["later_" + name + "_ms"] = later_frames > 0 ? 1e3 * seconds / later_frames : 0;
}

BENCHMARK(Track)
    ->ArgsProduct({{1000, 4000, 16000, 64000}, {2000, 20000, 300000}, {0}, {0}, {1}})
    // The factor where auto takes multigrid (the boxes from 5k vertices on), to compare.
    ->Args({4000, 2000, 1, 0, 1})
    ->Args({16000, 2000, 1, 0, 1})
    ->Args({64000, 2000, 1, 0, 1})
    // The data weight per area (its area-per-point estimate saturates at a triangle's area
    // on the finer boxes, so each point weighs 288 N/m at 1.4k vertices down to 36 at 70k).
    ->ArgsProduct({{1000, 4000, 16000, 64000}, {2000}, {0}, {1}, {1}})
    // Per pair with the weight per area gives each point on the finest box: the cost of the
    // data term's stiffness against the elements', whatever the weighting.
    ->ArgsProduct({{1000, 4000, 16000, 64000}, {2000}, {0}, {2}, {1}})
    // Two threads against the one-thread rows above (issue 41: at least 1.6x from 20k
    // vertices on a free second core).
    ->ArgsProduct({{4000, 16000, 64000}, {2000}, {0}, {0}, {2}})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime()
    ->Iterations(1);

}  // namespace

BENCHMARK_MAIN();
