// The per-frame confidence and the lost state (FrameSummary::confidence, lost;
// registration/confidence.h): high where the cloud is the object, low where the object went
// away, junk pulls the fit or the fit swells in one frame; a lost frame keeps the last good
// shape and tracking resumes when the object comes back.
#include <gtest/gtest.h>

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <memory>
#include <random>
#include <vector>

#include "embedded_helpers.h"
#include "femreg/io.h"
#include "femreg/tracker.h"
#include "registration/confidence.h"
#include "registration/correspondences.h"
#include "registration/tracker_state.h"

namespace femreg {
namespace {

TetMesh Box() { return MakeBox(Eigen::Vector3d(0.1, 0.04, 0.04), 5, 2, 2); }

// Points on the box's surface (its surface vertices and triangle centres), moved by `shift`.
PointCloud SurfaceCloud(const TetMesh& mesh, const Eigen::Vector3d& shift) {
  PointCloud cloud;
  const int nv = static_cast<int>(mesh.surface_vertices.size()), nf = mesh.num_surface_triangles();
  cloud.points.resize(nv + nf, 3);
  for (int i = 0; i < nv; ++i) cloud.points.row(i) = mesh.rest.row(mesh.surface_vertices[i]) + shift.transpose();
  for (int f = 0; f < nf; ++f) {
    Eigen::RowVector3d c = Eigen::RowVector3d::Zero();
    for (int k = 0; k < 3; ++k) c += mesh.rest.row(mesh.surface(f, k)) / 3.0;
    cloud.points.row(nv + f) = c + shift.transpose();
  }
  return cloud;
}

std::unique_ptr<Tracker> MakeTracker(double lost_coverage) {
  RegistrationOptions options;
  options.data.lost_coverage = lost_coverage;
  std::unique_ptr<Tracker> tracker;
  EXPECT_TRUE(Tracker::Create({Box()}, {ObjectMaterial()}, options, &tracker).ok());
  return tracker;
}

// The box's surface cloud scaled by `scale` about the box's centre, with 0.5 mm of noise (a
// noise-free cloud leaves the residual reference at 0).
PointCloud ScaledCloud(const TetMesh& mesh, double scale, std::mt19937* rng) {
  std::normal_distribution<double> noise(0.0, 0.0005);
  PointCloud cloud = SurfaceCloud(mesh, Eigen::Vector3d::Zero());
  const Eigen::RowVector3d centre(0.05, 0.02, 0.02);
  for (int i = 0; i < cloud.size(); ++i) {
    cloud.points.row(i) = centre + scale * (cloud.points.row(i) - centre) +
                          Eigen::RowVector3d(noise(*rng), noise(*rng), noise(*rng));
  }
  return cloud;
}

// A fit that swells in one frame (towards a cloud 6 % larger every way: junk all round pulls so) is
// doubted by the volume score, though every point fits and every element's strain is small;
// an object that grows as much over many frames is not.
TEST(TrackingLoss, AVolumeJumpLowersTheConfidenceASteadyChangeDoesNot) {
  const TetMesh mesh = Box();
  std::mt19937 rng(5);
  auto tracker = MakeTracker(0.3);
  FrameSummary s;
  for (int f = 0; f < 3; ++f) ASSERT_TRUE(tracker->Track(ScaledCloud(mesh, 1.0, &rng), &s).ok());
  EXPECT_GT(s.confidence.confidence, 0.9);
  // 0.1 % larger each frame, 3 % in all.
  for (int f = 1; f <= 30; ++f) {
    ASSERT_TRUE(tracker->Track(ScaledCloud(mesh, 1.0 + 0.001 * f, &rng), &s).ok());
    EXPECT_LT(s.confidence.volume_change, 0.02) << "frame " << f;
    EXPECT_GT(s.confidence.confidence, 0.8) << "frame " << f << ": " << s.confidence.volume_change;
  }
  auto jumped = MakeTracker(0.3);
  for (int f = 0; f < 3; ++f) ASSERT_TRUE(jumped->Track(ScaledCloud(mesh, 1.0, &rng), &s).ok());
  ASSERT_TRUE(jumped->Track(ScaledCloud(mesh, 1.06, &rng), &s).ok());
  EXPECT_FALSE(s.lost);
  EXPECT_GT(s.confidence.fit, 0.9);
  EXPECT_GT(s.confidence.volume_change, 0.04);
  EXPECT_LT(s.confidence.confidence, 0.5) << s.confidence.volume_change;
}

// A model sat on part of another object's cloud, or on the half of its own still in view, keeps
// few model->cloud pairs: with the fit and the coverage as they were, a third of the pairs the
// trusted frames kept scales the confidence by (1/3 / 0.6)^2, all of them not at all.
TEST(TrackingLoss, FewerModelPairsThanTheTrustedFramesKeptLowerTheConfidence) {
  TrackerState state;
  OneObject(Box(), &state);
  state.residuals.assign(1, Eigen::VectorXd::Zero(state.num_vertices));  // every vertex covered
  state.coverage_reference = 1.0;
  state.residual_reference = 1e-3;
  state.pairs_reference = 30.0;
  state.volume_reference = VolumeRatios(state);
  FrameCloud fc;  // no view: every surface vertex faces it
  std::vector<DataPair> pairs;
  DataPair on_surface;  // a cloud->model pair on the surface: the fit
  on_surface.num_vertices = 3;
  for (int k = 0; k < 3; ++k) on_surface.vertices[k] = state.surface(0, k);
  on_surface.barycentric = Eigen::Vector3d::Constant(1.0 / 3.0);
  on_surface.target = on_surface.Point(state.x);
  pairs.push_back(on_surface);
  const auto with_model_pairs = [&](int n) {
    std::vector<DataPair> all = pairs;
    for (int i = 0; i < n; ++i) {
      DataPair p;
      p.vertices[0] = state.surface_vertices[static_cast<size_t>(i) % state.surface_vertices.size()];
      p.target = state.x.row(p.vertices[0]).transpose();
      all.push_back(p);
    }
    return MeasureConfidence(state, fc, all, 1e-3);
  };
  const FrameConfidence kept = with_model_pairs(30), few = with_model_pairs(10);
  EXPECT_GT(kept.confidence, 0.9) << kept.fit << " " << kept.coverage;
  EXPECT_EQ(few.fit, kept.fit);
  EXPECT_EQ(few.coverage, kept.coverage);
  const double share = 10.0 / (0.6 * 30.0);
  EXPECT_NEAR(few.confidence, share * share * kept.confidence, 1e-12);
}

TEST(TrackingLoss, LostWhileTheObjectIsAwayAndFoundWhenItComesBack) {
  const TetMesh mesh = Box();
  auto tracker = MakeTracker(0.3);
  FrameSummary s;
  const Eigen::Vector3d here(0.002, 0.0, 0.0);
  for (int f = 0; f < 2; ++f) {
    ASSERT_TRUE(tracker->Track(SurfaceCloud(mesh, here), &s).ok());
    EXPECT_FALSE(s.lost);
    EXPECT_GT(s.confidence.confidence, 0.9) << s.confidence.fit << " " << s.confidence.coverage;
    EXPECT_GT(s.confidence.coverage, 0.9);
  }
  const Vertices good = tracker->vertices(0);
  // The object is gone: the cloud holds something else half a metre away.
  ASSERT_TRUE(tracker->Track(SurfaceCloud(mesh, Eigen::Vector3d(0.5, 0.0, 0.0)), &s).ok());
  EXPECT_TRUE(s.lost) << s.BriefReport();
  EXPECT_LT(s.confidence.confidence, 0.3);
  EXPECT_LT((tracker->vertices(0) - good).cwiseAbs().maxCoeff(), 1e-12);  // the last good shape
  // An empty frame: lost too.
  ASSERT_TRUE(tracker->Track(PointCloud(), &s).ok());
  EXPECT_TRUE(s.lost);
  EXPECT_EQ(s.confidence.confidence, 0.0);
  // Back, 3 mm further: found and followed.
  ASSERT_TRUE(tracker->Track(SurfaceCloud(mesh, Eigen::Vector3d(0.005, 0.0, 0.0)), &s).ok());
  EXPECT_FALSE(s.lost);
  EXPECT_GT(s.confidence.confidence, 0.9);
  const double shift = (tracker->vertices(0) - mesh.rest).col(0).mean();
  EXPECT_NEAR(shift, 0.005, 1e-3);
}

// The first frame after held ones makes up for their motion: it starts stiff, as a large
// motion does, and has max_outer_iterations for each frame it makes up for (at most four).
TEST(TrackingLoss, TheFrameAfterAnAbsenceCatchesUpWithMoreIterations) {
  const TetMesh mesh = Box();
  RegistrationOptions options;
  options.solver.max_outer_iterations = 2;
  // No stopping rule but the budget: every frame runs its outer iterations to the end.
  options.solver.relative_energy_tolerance = 0.0;
  options.solver.step_tolerance = 0.0;
  options.solver.bulk_step_tolerance = 0.0;
  std::unique_ptr<Tracker> tracker;
  ASSERT_TRUE(Tracker::Create({Box()}, {ObjectMaterial()}, options, &tracker).ok());
  FrameSummary s;
  for (int f = 0; f < 2; ++f) {
    ASSERT_TRUE(tracker->Track(SurfaceCloud(mesh, Eigen::Vector3d(0.001 * f, 0, 0)), &s).ok());
    EXPECT_EQ(s.outer_iterations, 2);
    EXPECT_EQ(s.large_motion_restarts, 0);
  }
  for (int f = 0; f < 3; ++f) ASSERT_TRUE(tracker->Track(PointCloud(), &s).ok());
  ASSERT_TRUE(tracker->Track(SurfaceCloud(mesh, Eigen::Vector3d(0.006, 0, 0)), &s).ok());
  EXPECT_EQ(s.large_motion_restarts, 1);
  // The stiff start (1 + 4 stages), then 2 x (1 + 3) iterations.
  EXPECT_EQ(s.outer_iterations, 5 + 8) << s.message;
  EXPECT_NE(s.message.find("catching up after 3 held or lost frames"), std::string::npos) << s.message;
  EXPECT_NEAR((tracker->vertices(0) - mesh.rest).col(0).mean(), 0.006, 1e-3);
  // The next frame is an ordinary one again.
  ASSERT_TRUE(tracker->Track(SurfaceCloud(mesh, Eigen::Vector3d(0.007, 0, 0)), &s).ok());
  EXPECT_EQ(s.outer_iterations, 2);
  EXPECT_EQ(s.large_motion_restarts, 0);
}

TEST(TrackingLoss, NeverLostWhenSwitchedOff) {
  const TetMesh mesh = Box();
  auto tracker = MakeTracker(0.0);
  FrameSummary s;
  ASSERT_TRUE(tracker->Track(SurfaceCloud(mesh, Eigen::Vector3d::Zero()), &s).ok());
  ASSERT_TRUE(tracker->Track(SurfaceCloud(mesh, Eigen::Vector3d(0.5, 0.0, 0.0)), &s).ok());
  EXPECT_FALSE(s.lost);
  EXPECT_LT(s.confidence.confidence, 0.3);
}

// Junk near the object pulls the fit: the residual score drops the confidence, while the
// object is still there (not lost).
TEST(TrackingLoss, OutliersLowerTheConfidenceButDoNotLoseTheObject) {
  const TetMesh mesh = Box();
  auto tracker = MakeTracker(0.3);
  FrameSummary s;
  const PointCloud clean = SurfaceCloud(mesh, Eigen::Vector3d::Zero());
  ASSERT_TRUE(tracker->Track(clean, &s).ok());
  const double before = s.confidence.confidence;
  PointCloud noisy = clean;
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> u(-0.02, 0.02);
  const int n = static_cast<int>(clean.points.rows());
  noisy.points.conservativeResize(2 * n, 3);
  for (int i = 0; i < n; ++i) {
    noisy.points.row(n + i) = clean.points.row(i) + Eigen::RowVector3d(u(rng), u(rng), u(rng));
  }
  ASSERT_TRUE(tracker->Track(noisy, &s).ok());
  EXPECT_FALSE(s.lost);
  EXPECT_LT(s.confidence.confidence, 0.6 * before) << s.confidence.residual << " " << s.confidence.fit;
  EXPECT_GE(s.confidence.confidence, 0.0);
  EXPECT_LE(s.confidence.fit, 1.0);
}

// A fit among uniform junk (as many points as the object's, spread over its box and 3 cm
// around): the junk near the surface fills the worse half of the pairs and the object's points
// the better half, over which the residual is taken: it stays within a few times a clean
// frame's (the junk's own distances, up to data.max_distance, are tens of times that). The
// junk all round swells the fit by a few per cent, which the volume score reads.
TEST(TrackingLoss, JunkAroundARightFitKeepsTheResidualScore) {
  const TetMesh mesh = Box();
  std::mt19937 rng(7);
  std::normal_distribution<double> noise(0.0, 0.0005);
  const auto noisy = [&](const Eigen::Vector3d& shift) {
    PointCloud c = SurfaceCloud(mesh, shift);
    for (int i = 0; i < c.size(); ++i) c.points.row(i) += Eigen::RowVector3d(noise(rng), noise(rng), noise(rng));
    return c;
  };
  const auto with_junk = [&](PointCloud c) {
    const int n = c.size();
    const Eigen::RowVector3d lo = c.points.colwise().minCoeff().array() - 0.03;
    const Eigen::RowVector3d hi = c.points.colwise().maxCoeff().array() + 0.03;
    std::uniform_real_distribution<double> u(0.0, 1.0);
    c.points.conservativeResize(2 * n, 3);
    for (int i = 0; i < n; ++i) {
      c.points.row(n + i) = lo + Eigen::RowVector3d(u(rng), u(rng), u(rng)).cwiseProduct(hi - lo);
    }
    return c;
  };
  auto tracker = MakeTracker(0.3);
  FrameSummary s;
  for (int f = 0; f < 3; ++f) ASSERT_TRUE(tracker->Track(noisy(Eigen::Vector3d::Zero()), &s).ok());
  const double clean_residual = s.confidence.residual;
  ASSERT_TRUE(tracker->Track(with_junk(noisy(Eigen::Vector3d::Zero())), &s).ok());
  EXPECT_LT(s.confidence.residual, 5.0 * clean_residual) << clean_residual;
  const double volume_score = std::min(1.0, 0.02 / s.confidence.volume_change);
  // Within 5x the clean residual, the residual score keeps more than 2/5 of what the fit and
  // the swelling leave.
  EXPECT_GT(s.confidence.confidence, 0.4 * s.confidence.fit * volume_score)
      << s.confidence.volume_change;
  EXPECT_FALSE(s.lost);
}

// The strain quantile the confidence reads, against sorting every element's stretch deviation:
// elements near rest, stretched, sheared, turned, flat and inverted, at several shares.
TEST(TrackingLoss, TheStrainQuantileIsTheSortedDeviationsOne) {
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  std::vector<Eigen::Matrix3d> F;
  for (int e = 0; e < 3000; ++e) {
    const int kind = e % 6;
    const double size = kind == 0 ? 1e-4 : kind == 1 ? 1e-2 : kind == 2 ? 0.1 : 0.5;
    Eigen::Matrix3d A;
    for (int i = 0; i < 9; ++i) A(i / 3, i % 3) = size * u(rng);
    Eigen::Matrix3d f = Eigen::Matrix3d::Identity() + A;
    const Eigen::Quaterniond q(Eigen::Vector4d(u(rng), u(rng), u(rng), u(rng)).normalized());
    f = q.toRotationMatrix() * f;  // turned: the deviation does not see it
    if (kind == 4) f.col(2) = f.col(0) + f.col(1);  // flat
    if (kind == 5 && e % 4 == 1) f.col(0) *= -1.0;  // inverted
    F.push_back(f);
    // Stretched along the axes, two stretches nearly equal, turned a little on the right (C
    // near-diagonal with a near-repeated eigenvalue, where the eigenvalues' round-off is the
    // largest).
    const Eigen::Vector3d d(1.0 + 0.7 * u(rng), 1.0 + 0.7 * u(rng), 0.0);
    const Eigen::Vector3d stretch(d(0), d(1), d(1) * (1.0 + 1e-9 * u(rng)));
    const Eigen::Matrix3d turn =
        Eigen::AngleAxisd(std::pow(10.0, -12.0 + 10.0 * (0.5 + 0.5 * u(rng))), Eigen::Vector3d(u(rng), u(rng), u(rng)).normalized())
            .toRotationMatrix();
    F.push_back(Eigen::Matrix3d(stretch.asDiagonal()) * turn);
  }
  // A review's pair (an axial stretch with two equal ones, and one of the same deviation as
  // the first's): the widened bounds of 1e-9 gave the first's value for the second's.
  Eigen::Matrix3d near_repeated;
  near_repeated << 1.6878387382149962, -6.0521750069886492e-12, -4.1866271750517815e-12,
      1.3848829052711969e-12, 0.30554522421359948, -1.4888804587048999e-13, 6.8622152619185927e-13,
      2.1284005559850309e-13, 0.30554522421307934;
  const std::vector<Eigen::Matrix3d> pair = {near_repeated,
                                             Eigen::Vector3d(1.694454778, 1.0, 1.0).asDiagonal().toDenseMatrix()};
  {
    std::vector<double> both = {StretchDeviation(pair[0]), StretchDeviation(pair[1])};
    std::sort(both.begin(), both.end());
    EXPECT_EQ(StretchDeviationQuantile(2, 0.5, [&](int64_t e) { return pair[static_cast<size_t>(e)]; }), both[1]);
  }
  for (const double share : {0.0, 0.5, 0.95, 0.99, 1.0}) {
    for (const int n : {1, 7, 100, 6000}) {
      std::vector<double> all;
      for (int e = 0; e < n; ++e) all.push_back(StretchDeviation(F[static_cast<size_t>(e)]));
      std::sort(all.begin(), all.end());
      const size_t at = std::min(static_cast<size_t>(n) - 1, static_cast<size_t>(share * n));
      const double q = StretchDeviationQuantile(n, share, [&](int64_t e) { return F[static_cast<size_t>(e)]; }, 2);
      EXPECT_EQ(q, all[at]) << "share " << share << ", " << n << " elements";
    }
  }
}

}  // namespace
}  // namespace femreg
