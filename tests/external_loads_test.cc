// External loads in registration (registration.loads; energy/load.h): the scene's gravity and
// nodal loads act in the registration energy as in a forward solve, so what the camera does
// not see takes the shape the loads give it; and on sag_track, tracking with gravity, and
// with the material `femreg calibrate` identified, comes closer to the ground truth.
#include <gtest/gtest.h>

#include <cstdio>
#include <fstream>
#include <memory>
#include <string>
#include <vector>

#include "femreg/calibration.h"
#include "femreg/ground_truth.h"
#include "femreg/point_cloud.h"
#include "femreg/scene.h"
#include "femreg/tracker.h"
#include "femreg_test_config.h"
#include "test_util.h"

namespace femreg {
namespace {

// A soft cantilever clamped at x = 0 under its own weight (tip sag ~ 2 cm at E = 200 kPa).
constexpr const char* kCantilever = R"(
objects:
  - name: beam
    generate: {shape: box, size: [0.2, 0.04, 0.04], cells: [10, 2, 2]}
    material: {youngs_modulus: 2e5, poisson_ratio: 0.3, density: 1000}
gravity: [0, 0, -9.81]
boundary:
  - {select: {box: {min: [-1, -1, -1], max: [0.0001, 1, 1]}}, clamp: true}
forward: {max_iterations: 60, load_steps: 2}
registration:
  weights: {temporal: 0}
  solver: {max_outer_iterations: 40, step_tolerance: 1e-5, bulk_step_tolerance: 0, relative_energy_tolerance: 0,
           inner_tolerance: 1e-10}
)";

class ExternalLoadsBackend : public ::testing::TestWithParam<SolverBackend> {};

// The camera sees the clamped half (its vertices at the forward equilibrium): the registration
// energy is then stationary at that equilibrium, and the unseen free half must sag as the
// forward solve says. Without the loads it stays nearly straight.
TEST_P(ExternalLoadsBackend, UnseenHalfSagsAsTheForwardSolveSays) {
  testing_util::TempDir tmp;
  const std::string path = tmp.path() + "/cantilever.yaml";
  std::ofstream(path) << kCantilever;
  Scene scene;
  ASSERT_TRUE(LoadScene(path, &scene).ok());
  scene.registration.solver.backend = GetParam();
  TetMesh equilibrium;
  ASSERT_TRUE(SolveSceneObject(scene, 0, &equilibrium).ok());
  std::vector<int> seen, unseen;
  for (int v = 0; v < equilibrium.num_vertices(); ++v) {
    (equilibrium.rest(v, 0) < 0.1 ? seen : unseen).push_back(v);
  }
  PointCloud cloud;
  cloud.points.resize(static_cast<Eigen::Index>(seen.size()), 3);
  for (size_t i = 0; i < seen.size(); ++i) cloud.points.row(static_cast<Eigen::Index>(i)) = equilibrium.x.row(seen[i]);
  double tip_sag = 0.0;
  for (int v : unseen) tip_sag = std::max(tip_sag, equilibrium.rest(v, 2) - equilibrium.x(v, 2));
  ASSERT_GT(tip_sag, 0.01);

  auto unseen_error = [&](bool loads) {
    Scene s = scene;
    s.registration.loads = loads;
    std::unique_ptr<Tracker> tracker;
    EXPECT_TRUE(Tracker::Create(s, &tracker).ok());
    FrameSummary summary;
    EXPECT_TRUE(tracker->Track(cloud, &summary).ok());
    EXPECT_TRUE(summary.IsSolutionUsable()) << summary.BriefReport();
    std::printf("%s: %s\n", summary.stopped_by.c_str(), summary.message.c_str());
    EXPECT_EQ(summary.final.load != 0.0, loads) << "the load term is there exactly when on";
    double worst = 0.0;
    for (int v : unseen) worst = std::max(worst, (tracker->vertices(0).row(v) - equilibrium.x.row(v)).norm());
    return worst;
  };
  const double with_loads = unseen_error(true);
  const double without = unseen_error(false);
  std::printf("tip sag %.2f mm; worst unseen vertex off the forward equilibrium: %.3f mm with "
              "the loads, %.2f mm without\n", tip_sag * 1e3, with_loads * 1e3, without * 1e3);
  EXPECT_LT(with_loads, 0.05 * tip_sag);  // the data term's small bias aside, the same shape
  EXPECT_GT(without, 0.3 * tip_sag);
}

INSTANTIATE_TEST_SUITE_P(Backends, ExternalLoadsBackend,
                         ::testing::Values(SolverBackend::kFast, SolverBackend::kCeres),
                         [](const ::testing::TestParamInfo<SolverBackend>& info) {
                           return std::string(ToString(info.param));
                         });

// sag_track: a gel beam turned by its holder (a hard anchor in the tracking scene), sagging.
// Mean vertex error (m) over all frames and vertices.
double SagTrackError(const Scene& scene) {
  const std::string dir = std::string(FEMREG_DATASETS_DIR) + "/sag_track";
  std::unique_ptr<Tracker> tracker;
  EXPECT_TRUE(Tracker::Create(scene, &tracker).ok());
  double sum = 0.0;
  int frames = 0;
  for (int i = 0; i < 16; ++i) {
    PointCloud cloud;
    GroundTruthFrame truth;
    EXPECT_TRUE(testing_util::ReadDatasetFrame(dir, i, &cloud, &truth).ok());
    FrameSummary summary;
    EXPECT_TRUE(tracker->Track(cloud, &summary).ok());
    EXPECT_TRUE(summary.IsSolutionUsable()) << summary.BriefReport();
    sum += ComputeVertexErrors(tracker->vertices(0), truth).all.mean;
    ++frames;
  }
  return sum / frames;
}

TEST(ExternalLoads, SagTrackWithGravityTracksCloserWithTheNominalAndTheCalibratedMaterial) {
  Scene scene;
  ASSERT_TRUE(LoadScene(std::string(FEMREG_DATASETS_DIR) + "/sag_track/scene.yaml", &scene).ok());
  scene.registration.solver.num_threads = 1;
  ASSERT_GT(scene.gravity.norm(), 0.0) << "the tracking scene knows gravity";
  Scene no_loads = scene;
  no_loads.registration.loads = false;
  // What `femreg calibrate` fits on frame 0 with calibration.yaml (docs/guide/loads.md: 202 kPa).
  Scene calibrated = scene;
  calibrated.objects[0].material.youngs_modulus = 2.025e5;
  const double nominal = SagTrackError(scene);
  const double without = SagTrackError(no_loads);
  const double fitted = SagTrackError(calibrated);
  std::printf("sag_track mean vertex error: nominal E without loads %.3f mm, with gravity %.3f mm, "
              "calibrated E with gravity %.3f mm\n", without * 1e3, nominal * 1e3, fitted * 1e3);
  EXPECT_LT(nominal, 0.95 * without);
  // The calibrated E's own gain over the nominal one is smaller than what rounding moves this
  // sequence's mean across CPUs' BLAS kernels (docs/guide/loads.md): both are held against
  // the run without loads.
  EXPECT_LT(fitted, 0.95 * without);
}

}  // namespace
}  // namespace femreg
