// Clouds that crush a mesh's corners. Much denser than the mesh: the automatic voxel grid
// thins them, and the data term then weighs what a cloud of preprocess.auto_voxel_min_ratio
// points per surface vertex would, however many points came in (docs/theory/data-weight.md).
// Pairs made far from the shape on a soft mesh: solver.stiff_restart_volume.
#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <memory>
#include <random>
#include <string>

#include "femreg/mesh.h"
#include "femreg/point_cloud.h"
#include "femreg/registration.h"
#include "femreg/tracker.h"
#include "registration/correspondences.h"
#include "registration/tracker_state.h"
#include "surface_samples.h"

namespace femreg {
namespace {

TEST(DenseCloud, SubsamplingBoundsTheTotalWeight) {
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> u(0.0, 0.1);
  PointCloud cloud;
  cloud.points.resize(5000, 3);
  for (int i = 0; i < cloud.points.rows(); ++i) cloud.points.row(i) << u(rng), u(rng), u(rng);
  PointCloud unbounded = cloud;
  Eigen::VectorXd weights, counts;
  SubsampleCloud(0.02, &unbounded, &counts);
  EXPECT_DOUBLE_EQ(counts.sum(), 5000.0);
  SubsampleCloud(0.02, &cloud, &weights, 1200.0);
  ASSERT_EQ(cloud.size(), unbounded.size());
  EXPECT_NEAR(weights.sum(), 1200.0, 1e-9);
  // Scaled together: a voxel of many points still weighs more than one of few.
  for (int v = 0; v < weights.size(); ++v) EXPECT_NEAR(weights(v), counts(v) * 1200.0 / 5000.0, 1e-12);
  // A bound above the total changes nothing; one below it scales the weights even where the
  // grid keeps every point.
  cloud = unbounded = PointCloud();
  cloud.points = Eigen::MatrixXd::Identity(3, 3);
  SubsampleCloud(0.01, &cloud, &weights, 10.0);
  EXPECT_EQ(weights, Eigen::VectorXd::Ones(3));
  SubsampleCloud(0.01, &cloud, &weights, 1.5);
  EXPECT_NEAR(weights.sum(), 1.5, 1e-12);
}

const Eigen::Vector3d kBoxSize(0.2, 0.1, 0.05);

// The scaling benchmark's box (docs/performance/scaling.md) bent as a cantilever by `amount`
// (m) at its free end, every cross-section turned with the bend.
Vertices Bent(const TetMesh& box, double amount) {
  Vertices x = box.rest;
  for (int v = 0; v < x.rows(); ++v) {
    const double s = box.rest(v, 0) / kBoxSize.x(), h = box.rest(v, 2) - 0.5 * kBoxSize.z();
    const double turn = std::atan(2.0 * amount * s / kBoxSize.x());
    x(v, 0) = box.rest(v, 0) - h * std::sin(turn);
    x(v, 2) = 0.5 * kBoxSize.z() + amount * s * s + h * std::cos(turn);
  }
  return x;
}

// The smallest ratio of an element's volume at x to its rest volume.
double SmallestVolumeRatio(const TetMesh& box, const Vertices& x) {
  double smallest = 1.0;
  for (int t = 0; t < box.num_tets(); ++t) {
    auto volume = [&](const Vertices& y) {
      Eigen::Matrix3d e;
      for (int k = 0; k < 3; ++k) e.col(k) = (y.row(box.tets(t, k + 1)) - y.row(box.tets(t, 0))).transpose();
      return e.determinant();
    };
    smallest = std::min(smallest, volume(x) / volume(box.rest));
  }
  return smallest;
}

std::unique_ptr<Tracker> BoxTracker(const TetMesh& box, double youngs_modulus, const RegistrationOptions& options) {
  ObjectMaterial material;
  material.material.youngs_modulus = youngs_modulus;
  material.material.poisson_ratio = 0.4;
  std::unique_ptr<Tracker> tracker;
  EXPECT_TRUE(Tracker::Create({box}, {material}, options, &tracker).ok());
  return tracker;
}

// The box at 2,275 vertices (1,010 on the surface), seen whole through 300k noisy points a
// frame, about 300 per surface vertex. Weighed by every point they stood for, the thinned
// points crushed the free end's bottom corner (docs/notes/2026-11-30-dense-clouds.md).
TEST(DenseCloud, ThreeHundredThousandPointsDoNotCrushABentBox) {
  const TetMesh box = MakeBox(kBoxSize, 24, 12, 6);
  std::mt19937 rng(17);
  RegistrationOptions options;
  options.solver.num_threads = 1;
  const std::unique_ptr<Tracker> tracker = BoxTracker(box, 5e4, options);
  ASSERT_TRUE(tracker);
  double error = 0.0;
  for (int f = 0; f < 3; ++f) {
    const Vertices truth = Bent(box, 0.004 * (f + 1));
    FrameSummary s;
    ASSERT_TRUE(tracker->Track(testing_util::SampleSurfaceByArea(box, truth, 300000, 5e-4, &rng), &s).ok());
    EXPECT_EQ(s.termination, TerminationType::kConverged) << "frame " << f;
    EXPECT_GT(s.voxel_size, 0.0) << "frame " << f;
    EXPECT_GT(SmallestVolumeRatio(box, tracker->vertices(0)), 0.9) << "frame " << f;
    error += (tracker->vertices(0) - truth).rowwise().norm().mean() / 3.0;
  }
  EXPECT_LT(error, 0.15e-3);
}

// A soft box (10 kPa, 5,049 vertices) bent 4 mm from rest under 20k points: the first solve's
// pairs, made at rest, pull the free end's bottom corner in, and the frame converges with it
// crushed. With solver.stiff_restart_volume the frame starts again stiff once one of the
// first two solves has taken an element below that share of its volume
// (docs/notes/2026-12-01-crushed-first-steps.md).
TEST(CrushedFirstStep, AStiffRestartKeepsTheSoftBoxsCornerWhole) {
  const TetMesh box = MakeBox(kBoxSize, 32, 16, 8);
  const Vertices truth = Bent(box, 0.004);
  std::mt19937 rng(17);
  const PointCloud cloud = testing_util::SampleSurfaceByArea(box, truth, 20000, 5e-4, &rng);
  double smallest[2], error[2];
  int restarts[2];
  for (int run = 0; run < 2; ++run) {
    RegistrationOptions options;
    options.solver.num_threads = 1;
    options.solver.max_outer_iterations = 20;
    if (run == 1) options.solver.stiff_restart_volume = 0.75;
    const std::unique_ptr<Tracker> tracker = BoxTracker(box, 1e4, options);
    ASSERT_TRUE(tracker);
    FrameSummary s;
    ASSERT_TRUE(tracker->Track(cloud, &s).ok());
    EXPECT_EQ(s.termination, TerminationType::kConverged) << "run " << run;
    smallest[run] = SmallestVolumeRatio(box, tracker->vertices(0));
    error[run] = (tracker->vertices(0) - truth).rowwise().norm().mean();
    restarts[run] = s.crushed_restarts;
    EXPECT_EQ(s.large_motion_restarts, 0) << "run " << run;
  }
  EXPECT_EQ(restarts[0], 0);
  EXPECT_LT(smallest[0], 0.5);  // crushed: the case is still one that needs the option
  EXPECT_EQ(restarts[1], 1);
  EXPECT_GT(smallest[1], 0.7);
  EXPECT_LT(error[1], 0.85 * error[0]);
}

// With the forces estimated the restart is on by default (solver.stiff_restart_volume
// automatic, < 0: 0.1): an equilibrium solve that starts from a crushed element stops against
// the inversion barrier's force (docs/notes/2026-12-01-soft-modes.md). 0 still turns it off.
TEST(CrushedFirstStep, TheRestartIsOnByDefaultWithTheForcesEstimated) {
  RegistrationOptions options;
  EXPECT_LT(options.solver.stiff_restart_volume, 0.0);
  EXPECT_EQ(StiffRestartVolume(options, options.forces.estimate), 0.0);
  options.forces.estimate = true;
  EXPECT_EQ(StiffRestartVolume(options, options.forces.estimate), 0.1);
  options.solver.stiff_restart_volume = 0.0;
  EXPECT_EQ(StiffRestartVolume(options, options.forces.estimate), 0.0);
  options.solver.stiff_restart_volume = 0.75;
  EXPECT_EQ(StiffRestartVolume(options, options.forces.estimate), 0.75);
  options.forces.estimate = false;
  EXPECT_EQ(StiffRestartVolume(options, options.forces.estimate), 0.75);
  std::string error;
  options.solver.stiff_restart_volume = -1.0;
  EXPECT_TRUE(options.IsValid(&error)) << error;
  options.solver.stiff_restart_volume = 1.0;
  EXPECT_FALSE(options.IsValid(&error));
}

// The tracker takes the automatic value: a soft box whose cloud has a deep dent at one end (the
// top pressed down by 80 % of the height); with the forces estimated the frame's warm start
// (the classic energy) crushes an element there, and by default the frame starts again stiff;
// with stiff_restart_volume 0 it does not.
TEST(CrushedFirstStep, WithTheForcesEstimatedACrushedWarmStartStartsAgainByDefault) {
  const TetMesh box = MakeBox(kBoxSize, 8, 4, 2);
  Vertices truth = box.rest;
  for (int v = 0; v < truth.rows(); ++v) {
    if (box.rest(v, 0) > 0.75 * kBoxSize.x() && box.rest(v, 2) > 0.9 * kBoxSize.z()) truth(v, 2) -= 0.8 * kBoxSize.z();
  }
  std::mt19937 rng(17);
  const PointCloud cloud = testing_util::SampleSurfaceByArea(box, truth, 4000, 2e-4, &rng);
  int restarts[2];
  for (int run = 0; run < 2; ++run) {
    RegistrationOptions options;
    options.solver.num_threads = 1;
    options.forces.estimate = true;
    if (run == 1) options.solver.stiff_restart_volume = 0.0;
    const std::unique_ptr<Tracker> tracker = BoxTracker(box, 1e3, options);
    ASSERT_TRUE(tracker);
    FrameSummary s;
    ASSERT_TRUE(tracker->Track(cloud, &s).ok());
    EXPECT_EQ(s.termination, TerminationType::kConverged) << "run " << run;
    restarts[run] = s.crushed_restarts;
  }
  EXPECT_EQ(restarts[0], 1);
  EXPECT_EQ(restarts[1], 0);
}

// Stray points above a box seen through 20k points (data.max_strain_step low, so that their pull
// counts as implausible): 18 points (0.09 % of the cloud's weight) strain the elements under
// them, and the frame goes on without them from where it is; a cluster of 2 % of the cloud (a
// hand's finger) pulled the shape, and the frame starts again without it
// (docs/notes/2026-12-02-fine-box-stalls.md). The cloud's thinning leaves both clusters as the
// same few points of different weights. (A single point's pull moves no edge by more than the
// cloud's spacing, and marks nothing: docs/notes/2026-12-07-sliver-strains.md.)
TEST(ImplausiblePoints, AFewOfADenseCloudsAreLeftOutWithoutARestart) {
  const TetMesh box = MakeBox(kBoxSize, 16, 8, 4);
  const Vertices truth = Bent(box, 0.004);
  int restarts[2], implausible[2];
  double error[2];
  for (int run = 0; run < 2; ++run) {
    std::mt19937 rng(17);
    PointCloud cloud = testing_util::SampleSurfaceByArea(box, truth, 20000, 5e-4, &rng);
    const int stray = run == 0 ? 18 : 400;
    std::uniform_real_distribution<double> u(-0.003, 0.003);
    const Eigen::Index n = cloud.points.rows();
    cloud.points.conservativeResize(n + stray, 3);
    for (int i = 0; i < stray; ++i) {
      cloud.points.row(n + i) << 0.5 * kBoxSize.x() + u(rng), 0.5 * kBoxSize.y() + u(rng), kBoxSize.z() + 0.015;
    }
    RegistrationOptions options;
    options.solver.num_threads = 1;
    options.data.max_strain_step = 0.05;
    const std::unique_ptr<Tracker> tracker = BoxTracker(box, 1e4, options);
    ASSERT_TRUE(tracker);
    FrameSummary s;
    ASSERT_TRUE(tracker->Track(cloud, &s).ok());
    EXPECT_EQ(s.termination, TerminationType::kConverged) << "run " << run;
    restarts[run] = s.implausible_restarts;
    implausible[run] = s.implausible_points;
    error[run] = (tracker->vertices(0) - truth).rowwise().norm().mean();
  }
  EXPECT_GE(implausible[0], 1);
  EXPECT_EQ(restarts[0], 0);
  EXPECT_GE(implausible[1], 1);
  EXPECT_GE(restarts[1], 1);
  EXPECT_LT(error[0], 0.3e-3);
  EXPECT_LT(error[1], 0.3e-3);
}

}  // namespace
}  // namespace femreg
