// Clouds much denser than the mesh: the automatic voxel grid thins them, and the data term
// then weighs what a cloud of preprocess.auto_voxel_min_ratio points per surface vertex
// would, however many points came in (docs/theory/data-weight.md).
#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <cmath>
#include <memory>
#include <random>

#include "femreg/mesh.h"
#include "femreg/point_cloud.h"
#include "femreg/registration.h"
#include "femreg/tracker.h"
#include "registration/correspondences.h"
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

// The scaling benchmark's box (docs/performance/scaling.md) at 2,275 vertices (1,010 on the
// surface), bent as a cantilever (every cross-section turned with the bend), seen whole
// through 300k noisy points a frame, about 300 per surface vertex. Weighed by every point
// they stood for, the thinned points crushed the free end's bottom corner
// (docs/notes/2026-11-30-dense-clouds.md).
TEST(DenseCloud, ThreeHundredThousandPointsDoNotCrushABentBox) {
  const Eigen::Vector3d size(0.2, 0.1, 0.05);
  const TetMesh box = MakeBox(size, 24, 12, 6);
  auto bent = [&](double amount) {
    Vertices x = box.rest;
    for (int v = 0; v < x.rows(); ++v) {
      const double s = box.rest(v, 0) / size.x(), h = box.rest(v, 2) - 0.5 * size.z();
      const double turn = std::atan(2.0 * amount * s / size.x());
      x(v, 0) = box.rest(v, 0) - h * std::sin(turn);
      x(v, 2) = 0.5 * size.z() + amount * s * s + h * std::cos(turn);
    }
    return x;
  };
  std::mt19937 rng(17);
  auto volumes = [&](const Vertices& x) {
    Eigen::VectorXd v(box.num_tets());
    for (int t = 0; t < box.num_tets(); ++t) {
      const Eigen::Vector3d a = x.row(box.tets(t, 0));
      Eigen::Matrix3d e;
      for (int k = 0; k < 3; ++k) e.col(k) = x.row(box.tets(t, k + 1)).transpose() - a;
      v(t) = e.determinant();
    }
    return v;
  };
  RegistrationOptions options;
  options.solver.backend = SolverBackend::kFast;
  options.solver.num_threads = 1;
  ObjectMaterial material;
  material.material.youngs_modulus = 5e4;
  material.material.poisson_ratio = 0.4;
  std::unique_ptr<Tracker> tracker;
  ASSERT_TRUE(Tracker::Create({box}, {material}, options, &tracker).ok());
  const Eigen::VectorXd rest = volumes(box.rest);
  double error = 0.0;
  for (int f = 0; f < 3; ++f) {
    const Vertices truth = bent(0.004 * (f + 1));
    FrameSummary s;
    ASSERT_TRUE(tracker->Track(testing_util::SampleSurfaceByArea(box, truth, 300000, 5e-4, &rng), &s).ok());
    EXPECT_EQ(s.termination, TerminationType::kConverged) << "frame " << f;
    EXPECT_GT(s.voxel_size, 0.0) << "frame " << f;
    EXPECT_GT(volumes(tracker->vertices(0)).cwiseQuotient(rest).minCoeff(), 0.9) << "frame " << f;
    error += (tracker->vertices(0) - truth).rowwise().norm().mean() / 3.0;
  }
  EXPECT_LT(error, 0.15e-3);
}

}  // namespace
}  // namespace femreg
