// A frame's common depth offset (flicker) measured on a static plane and taken off
// (registration/depth_offset.h).
#include "registration/depth_offset.h"

#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <vector>

#include "femreg/io.h"
#include "femreg/point_cloud.h"
#include "femreg/tracker.h"

namespace femreg {
namespace {

// A camera 0.6 m above a table (z = 0), looking down at it obliquely.
CameraOptions Camera() {
  CameraOptions c;
  c.enabled = true;
  c.position = Eigen::Vector3d(0, -0.4, 0.6);
  c.target = Eigen::Vector3d(0, 0, 0);
  c.up = Eigen::Vector3d(0, 0, 1);
  c.fx = c.fy = 150;
  c.width = 160;
  c.height = 120;
  c.cx = 79.5;
  c.cy = 59.5;
  return c;
}

using Points = Eigen::Matrix<double, Eigen::Dynamic, 3>;

// Every step-th pixel's ray meets the table (z = 0) or the box above it; each point's depth
// is then moved by `offset` plus Gaussian noise of `sigma`. Table points first, then the box's.
void Render(const CameraOptions& c, double offset, double sigma, uint64_t seed, Points* table,
            PointCloud* box) {
  const Eigen::Matrix3d R = CameraRotation(c);
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> gauss(0.0, 1.0);
  std::vector<Eigen::Vector3d> on_table, on_box;
  for (int v = 0; v < c.height; v += 2) {
    for (int u = 0; u < c.width; u += 2) {
      const Eigen::Vector3d ray = R.transpose() * Eigen::Vector3d((u - c.cx) / c.fx, (v - c.cy) / c.fy, 1);
      if (!(ray.z() < 0)) continue;
      double z = -c.position.z() / ray.z();  // depth at the table
      Eigen::Vector3d p = c.position + z * ray;
      const bool boxed = std::abs(p.x()) < 0.05 && std::abs(p.y()) < 0.05;
      if (boxed) {  // the box's top, 3 cm up
        z = (0.03 - c.position.z()) / ray.z();
        p = c.position + z * ray;
      }
      const double depth = z + offset + sigma * gauss(rng);
      (boxed ? on_box : on_table).push_back(c.position + depth * ray);
    }
  }
  table->resize(static_cast<Eigen::Index>(on_table.size()), 3);
  for (size_t i = 0; i < on_table.size(); ++i) table->row(static_cast<Eigen::Index>(i)) = on_table[i].transpose();
  box->points.resize(static_cast<Eigen::Index>(on_box.size()), 3);
  for (size_t i = 0; i < on_box.size(); ++i) box->points.row(static_cast<Eigen::Index>(i)) = on_box[i].transpose();
}

double Depth(const CameraOptions& c, const Eigen::Vector3d& p) {
  return (CameraRotation(c) * (p - c.position)).z();
}

RemovedPlane Table(const Points& points, double offset = 0.0) {
  RemovedPlane plane;
  plane.normal = Eigen::Vector3d::UnitZ();
  plane.offset = offset;
  plane.points = points;
  return plane;
}

TEST(DepthOffset, APlaneMovedAlongTheRaysMeasuresTheOffset) {
  const CameraOptions c = Camera();
  Points table;
  PointCloud box;
  Render(c, 0.002, 0.0, 1, &table, &box);
  ASSERT_GT(table.rows(), 1000);
  double error = -1;
  EXPECT_NEAR(PlaneDepthOffset(c, Eigen::Vector3d::UnitZ(), 0.0, table, &error), 0.002, 1e-12);
  EXPECT_NEAR(error, 0.0, 1e-12);
  // The normal's sign does not matter.
  EXPECT_NEAR(PlaneDepthOffset(c, -Eigen::Vector3d::UnitZ(), 0.0, table), 0.002, 1e-12);
  // With noise: the median is within its standard error's reach, which says so.
  Render(c, -0.001, 0.0005, 2, &table, &box);
  const double noisy = PlaneDepthOffset(c, Eigen::Vector3d::UnitZ(), 0.0, table, &error);
  EXPECT_GT(error, 0.0);
  EXPECT_LT(error, 5e-5);
  EXPECT_NEAR(noisy, -0.001, 4 * error);
  // Too few points: nothing to say.
  EXPECT_TRUE(std::isnan(PlaneDepthOffset(c, Eigen::Vector3d::UnitZ(), 0.0, table.topRows(10))));
}

TEST(DepthOffset, ShiftDepthMovesPointsAlongTheirRays) {
  const CameraOptions c = Camera();
  Points table;
  PointCloud shifted, clean;
  Render(c, 0.004, 0.0, 1, &table, &shifted);
  Render(c, 0.0, 0.0, 1, &table, &clean);
  ShiftDepth(c, 0.004, &shifted);
  ASSERT_EQ(shifted.size(), clean.size());
  ASSERT_GT(clean.size(), 20);
  EXPECT_LT((shifted.points - clean.points).cwiseAbs().maxCoeff(), 1e-12);
}

TEST(DepthOffset, EachFramesOffsetFromTheMeanIsTakenOff) {
  const CameraOptions c = Camera();
  const std::vector<double> offsets = {0.0008, -0.0012, 0.0003, 0.0015, -0.0009, -0.0005};
  DepthOffset correction;
  double sum = 0.0;
  for (size_t t = 0; t < offsets.size(); ++t) {
    Points table, true_table;
    PointCloud box, truth;
    Render(c, offsets[t], 0.0, 3, &table, &box);
    Render(c, 0.0, 0.0, 3, &true_table, &truth);
    // The plane as fitted at its true place (RANSAC's fit of the first frame is offsets[0]
    // deep; the mean makes up for that the same way).
    const RemovedPlane plane = Table(table);
    sum += offsets[t];
    const double expected = offsets[t] - sum / static_cast<double>(t + 1);
    const double taken = correction.Correct(c, 0.005, plane, &box);
    EXPECT_NEAR(taken, expected, 1e-9) << "frame " << t;
    // What is left of each box point's offset is the mean's (the plane's unknown place).
    for (Eigen::Index i = 0; i < box.points.rows(); ++i) {
      EXPECT_NEAR(Depth(c, box.points.row(i)) - Depth(c, truth.points.row(i)), offsets[t] - expected, 1e-9);
    }
  }
}

TEST(DepthOffset, AMovedOrTurnedPlaneOrNoiseIsNotCorrected) {
  const CameraOptions c = Camera();
  DepthOffset correction;
  Points table;
  PointCloud box;
  Render(c, 0.0, 0.0, 4, &table, &box);
  EXPECT_EQ(correction.Correct(c, 0.005, Table(table), &box), 0.0);  // the reference
  // Another plane 2 cm off (the box's top, say): not flicker.
  Render(c, 0.02, 0.0, 4, &table, &box);
  const PointCloud before = box;
  EXPECT_EQ(correction.Correct(c, 0.005, Table(table), &box), 0.0);
  EXPECT_EQ(box.points, before.points);
  // A plane turned by 5 deg.
  RemovedPlane turned = Table(table);
  turned.normal = Eigen::Vector3d(std::sin(5 * M_PI / 180), 0, std::cos(5 * M_PI / 180));
  EXPECT_EQ(correction.Correct(c, 0.005, turned, &box), 0.0);
  // Noise alone (no common offset): within three standard errors, left alone.
  Render(c, 0.0, 0.001, 5, &table, &box);
  const PointCloud noisy = box;
  EXPECT_EQ(correction.Correct(c, 0.005, Table(table), &box), 0.0);
  EXPECT_EQ(box.points, noisy.points);
  // And an offset of 1 mm on top of that noise is found again.
  Render(c, 0.001, 0.001, 6, &table, &box);
  EXPECT_NEAR(correction.Correct(c, 0.005, Table(table), &box), 0.001 * 2.0 / 3.0, 1e-4);
}

// The tracker: a box standing on a table, both seen by the camera, each frame moved in depth
// by its own offset. With preprocess.depth_offset the offset from the mean is measured and
// taken off; without, nothing is.
TEST(DepthOffset, TheTrackerTakesEachFramesOffsetOff) {
  const CameraOptions c = Camera();
  const TetMesh box = MakeBox(Eigen::Vector3d(0.1, 0.1, 0.03), 4, 4, 1, Eigen::Vector3d(-0.05, -0.05, 0.0));
  const std::vector<double> offsets = {0.0, 0.0015, -0.001, 0.002};
  for (const bool on : {true, false}) {
    RegistrationOptions options;
    options.camera = c;
    options.preprocess.plane_distance = 0.004;
    options.preprocess.depth_offset = on;
    std::unique_ptr<Tracker> tracker;
    ASSERT_TRUE(Tracker::Create({box}, {ObjectMaterial()}, options, &tracker).ok());
    double sum = 0.0;
    for (size_t t = 0; t < offsets.size(); ++t) {
      Points table;
      PointCloud cloud;
      Render(c, offsets[t], 0.0, 7, &table, &cloud);
      const Eigen::Index n = cloud.points.rows();
      cloud.points.conservativeResize(n + table.rows(), 3);
      cloud.points.bottomRows(table.rows()) = table;
      FrameSummary s;
      ASSERT_TRUE(tracker->Track(cloud, &s).ok());
      ASSERT_TRUE(s.IsSolutionUsable()) << s.message;
      sum += offsets[t];
      if (!on) {
        EXPECT_EQ(s.depth_offset, 0.0);
        continue;
      }
      // RANSAC's plane of the first frame is the reference; a noiseless table makes it exact.
      EXPECT_NEAR(s.depth_offset, offsets[t] - sum / static_cast<double>(t + 1), 1e-5) << "frame " << t;
    }
  }
}

}  // namespace
}  // namespace femreg
