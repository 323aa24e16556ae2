// The global initial pose (registration.initial_pose): a body given 2.5 rad and a few
// centimetres away from where the camera sees it is found on the first frame with auto, and
// not with given; a pose the first frame explains is kept as given; the search gives the same
// result on every run and thread count; a symmetric body is reported as ambiguous; a body of
// five alike arms is found at a pose where the search that kept one RANSAC pose per run was
// wrong.
#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <cmath>
#include <memory>
#include <string>
#include <vector>

#include "femreg/geometry.h"
#include "femreg/io.h"
#include "femreg/synth.h"
#include "femreg/tracker.h"

namespace femreg {
namespace {

// An ellipsoid of 10 x 6 x 4 cm, bent, tapered and with a bump, so that no rotation maps it
// onto itself; symmetric = true leaves the ellipsoid (symmetric under three half-turns).
TetMesh Body(bool symmetric) {
  TetMesh m = MakeSphere(0.03, 4);
  for (Eigen::Index v = 0; v < m.rest.rows(); ++v) {
    Eigen::Vector3d p = m.rest.row(v).transpose().cwiseProduct(Eigen::Vector3d(1.67, 1.0, 0.67));
    if (!symmetric) {
      p.y() += 12.0 * p.x() * p.x();
      p.z() *= 1.0 + 8.0 * p.x();
      const Eigen::Vector3d bump(0.03, 0.02, 0.015);
      p.y() += 0.02 * std::exp(-(p - bump).squaredNorm() / (0.012 * 0.012));
    }
    m.rest.row(v) = p.transpose();
  }
  m.x = m.rest;
  return m;
}

// A 3 cm ball with five alike arms in an irregular arrangement (no rotation maps it onto
// itself, but every arm's features are like the others').
TetMesh Star() {
  TetMesh m = MakeSphere(0.03, 4);
  const Eigen::Vector3d arms[] = {
      {1.0, 0.2, 0.0}, {-0.3, 1.0, 0.1}, {-0.6, -0.5, 0.6}, {0.2, -0.4, -1.0}, {0.1, 0.3, 1.0}};
  for (Eigen::Index v = 0; v < m.rest.rows(); ++v) {
    const Eigen::Vector3d p = m.rest.row(v).transpose();
    double grow = 0.0;
    for (const Eigen::Vector3d& a : arms)
      grow += std::exp(-(1.0 - p.normalized().dot(a.normalized())) / 0.04);
    m.rest.row(v) = (p * (1.0 + 1.2 * grow)).transpose();
  }
  m.x = m.rest;
  return m;
}

// The camera 40 cm from the body, looking at it from the side of the bump.
CameraOptions Camera() {
  CameraOptions c;
  c.enabled = true;
  c.position = Eigen::Vector3d(0.2, 0.15, 0.3);
  c.target = Eigen::Vector3d::Zero();
  c.up = Eigen::Vector3d::UnitY();
  return c;
}

// The body's surface seen by Camera() where it truly is (its rest positions), with noise.
PointCloud View(const TetMesh& body) {
  DepthSensorOptions sensor;
  sensor.camera = Camera();
  sensor.pixel_stride = 2;
  const DepthSensor camera(sensor);
  const RenderSurface s{&body.rest, &body.surface, true};
  return camera.Sample(camera.Render({s}), {s}, 7);
}

struct FirstFrame {
  double error = 0.0;  // m, mean over the vertices
  FrameSummary summary;
  Vertices x;
};

// The body (truth) given rotated by `angle` about `axis` and, when turned, shifted by
// (2, 1, -2) cm, registered to View(truth).
FirstFrame Register(const char* name, const TetMesh& truth, InitialPose pose, double angle,
                    int threads = 1, const Eigen::Vector3d& axis = Eigen::Vector3d(1.0, 2.0, 0.5)) {
  const Eigen::Vector3d shift =
      angle > 0 ? Eigen::Vector3d(0.02, 0.01, -0.02) : Eigen::Vector3d::Zero();
  TetMesh given = truth;
  const Eigen::Matrix3d R = RotationFromVector(angle * axis.normalized());
  for (Eigen::Index v = 0; v < given.x.rows(); ++v) {
    given.x.row(v) = (R * truth.rest.row(v).transpose() + shift).transpose();
  }
  given.rest = given.x;
  RegistrationOptions options;
  options.camera = Camera();
  options.initial_pose = pose;
  options.solver.num_threads = threads;
  std::unique_ptr<Tracker> tracker;
  const Status status = Tracker::Create({given}, {Material{1e5, 0.3, 1000.0}}, options, &tracker);
  EXPECT_TRUE(status.ok()) << status.message();
  FirstFrame f;
  if (!status.ok()) return f;
  EXPECT_TRUE(tracker->Track(View(truth), &f.summary).ok());
  f.x = tracker->vertices(0);
  f.error = (f.x - truth.rest).rowwise().norm().mean();
  std::printf("%s, %s, %.2f rad: mean error %.2f mm, initial pose '%s'%s, %.0f ms\n", name,
              ToString(pose), angle, f.error * 1e3, f.summary.initial_pose.c_str(),
              f.summary.pose_ambiguous ? " (ambiguous)" : "", f.summary.time.total * 1e3);
  return f;
}

TEST(GlobalPose, FindsABodyTurnedBy2Point5RadOnlyWithAuto) {
  const FirstFrame automatic = Register("bent ellipsoid", Body(false), InitialPose::kAuto, 2.5);
  EXPECT_EQ(automatic.summary.initial_pose, "global");
  EXPECT_FALSE(automatic.summary.pose_ambiguous);
  EXPECT_LT(automatic.error, 0.003);
  const FirstFrame given = Register("bent ellipsoid", Body(false), InitialPose::kGiven, 2.5);
  EXPECT_EQ(given.summary.initial_pose, "");
  EXPECT_GT(given.error, 0.02);
}

TEST(GlobalPose, KeepsAPoseTheFirstFrameExplains) {
  // Where the camera sees it: the check runs, finds the given pose good, and the frame is the
  // given run's.
  const FirstFrame automatic = Register("bent ellipsoid", Body(false), InitialPose::kAuto, 0.0);
  const FirstFrame given = Register("bent ellipsoid", Body(false), InitialPose::kGiven, 0.0);
  EXPECT_EQ(automatic.summary.initial_pose, "given");
  EXPECT_LT(automatic.error, 0.003);
  EXPECT_TRUE(automatic.x == given.x);
}

TEST(GlobalPose, KeepsTheGivenPoseOfALargeBodySeenWhole) {
  // A 100 x 75 x 20 cm block seen where it is by a camera 1 m above its top: the top facing
  // the camera is judged against every point of the cloud, not against the few thousand the
  // fit is scored on, whose spacing alone put a large body seen whole beyond loss_scale and
  // searched (docs/notes/2026-11-30-real-frames.md).
  TetMesh block = MakeBox(Eigen::Vector3d(1.0, 0.75, 0.2), 40, 30, 4);
  RegistrationOptions options;
  options.camera.enabled = true;
  options.camera.position = Eigen::Vector3d(0.5, 0.375, 1.2);
  options.camera.target = Eigen::Vector3d(0.5, 0.375, 0.0);
  options.camera.up = Eigen::Vector3d::UnitY();
  options.initial_pose = InitialPose::kAuto;
  DepthSensorOptions sensor;
  sensor.camera = options.camera;
  sensor.noise_coefficient = 1e-3;  // 1 mm at 1 m
  const DepthSensor camera(sensor);
  const RenderSurface s{&block.rest, &block.surface, true};
  const PointCloud cloud = camera.Sample(camera.Render({s}), {s}, 7);
  std::unique_ptr<Tracker> tracker;
  const Status status = Tracker::Create({block}, {Material{1e5, 0.3, 1000.0}}, options, &tracker);
  ASSERT_TRUE(status.ok()) << status.message();
  FrameSummary summary;
  ASSERT_TRUE(tracker->Track(cloud, &summary).ok());
  std::printf("block: %d points read, %d used; initial pose '%s'\n", static_cast<int>(cloud.points.rows()),
              summary.points_used, summary.initial_pose.c_str());
  EXPECT_GT(summary.points_used, 4000);  // more than the fit scores
  EXPECT_EQ(summary.initial_pose, "given");
}

TEST(GlobalPose, SameOnEveryRunAndThreadCount) {
  // Every run: the test binary's runs of the same case (the first test's) agree too.
  const FirstFrame one = Register("bent ellipsoid", Body(false), InitialPose::kAuto, 2.5, 1);
  const FirstFrame two = Register("bent ellipsoid", Body(false), InitialPose::kAuto, 2.5, 2);
  EXPECT_EQ(one.summary.initial_pose, "global");
  EXPECT_TRUE(one.x == two.x);
}

TEST(GlobalPose, ReportsASymmetricBodyAsAmbiguous) {
  const FirstFrame box = Register("ellipsoid", Body(true), InitialPose::kAuto, 2.5);
  EXPECT_EQ(box.summary.initial_pose, "global");
  EXPECT_TRUE(box.summary.pose_ambiguous);
}

TEST(GlobalPose, FindsABodyOfAlikeArms) {
  // Turned by 2.5 rad about y: the search that kept one RANSAC pose per run chose a wrong
  // pose (see the global-pose note); the pairs' RANSAC proposes the true one among many.
  const FirstFrame star =
      Register("star", Star(), InitialPose::kAuto, 2.5, 1, Eigen::Vector3d::UnitY());
  EXPECT_EQ(star.summary.initial_pose, "global");
  EXPECT_FALSE(star.summary.pose_ambiguous);
  EXPECT_LT(star.error, 0.003);
}

}  // namespace
}  // namespace femreg
