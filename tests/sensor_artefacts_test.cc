// The virtual camera's artefacts of real sensors (femreg/synth.h, SensorArtefacts) and the
// sequence's (occluder, leaving the view): each changes the cloud the way it should, only
// when it is switched on, and reproducibly from the seed.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <set>
#include <utility>

#include "femreg/datasets.h"
#include "femreg/ground_truth.h"
#include "femreg/io.h"
#include "femreg/point_cloud.h"
#include "femreg/scene.h"
#include "femreg/synth.h"
#include "synth_samples.h"
#include "test_util.h"

namespace fs = std::filesystem;

namespace femreg {
namespace {

const double kDeg = M_PI / 180.0;

// The shared axis camera without noise: what each artefact does is all that changes.
DepthSensorOptions AxisSensor() {
  DepthSensorOptions s = testing_util::AxisSensor();
  s.noise_coefficient = 0.0;
  return s;
}

// A quad with corners a, b, c, d (two triangles).
struct Quad {
  Vertices points;
  Triangles triangles;
  Quad(const Eigen::Vector3d& a, const Eigen::Vector3d& b, const Eigen::Vector3d& c,
       const Eigen::Vector3d& d) {
    points.resize(4, 3);
    points << a.transpose(), b.transpose(), c.transpose(), d.transpose();
    triangles.resize(2, 3);
    triangles << 0, 1, 2, 0, 2, 3;
  }
  RenderSurface surface() const { return {&points, &triangles, true}; }
};

// A square of half-size h at depth z, tilted by `tilt` about the y axis.
Quad Square(double z, double h, double tilt) {
  const Eigen::Vector3d a(std::cos(tilt) * h, 0, std::sin(tilt) * h);
  return Quad(Eigen::Vector3d(-a.x(), -h, z - a.z()), Eigen::Vector3d(a.x(), -h, z + a.z()),
              Eigen::Vector3d(a.x(), h, z + a.z()), Eigen::Vector3d(-a.x(), h, z - a.z()));
}

PointCloud Shoot(const DepthSensorOptions& options, const std::vector<RenderSurface>& surfaces,
                 uint64_t seed) {
  const DepthSensor sensor(options);
  return sensor.Sample(sensor.Render(surfaces), surfaces, seed);
}

// The pixels of a cloud's points (each back-projected point lies on its pixel's ray).
std::set<std::pair<int, int>> Pixels(const DepthSensor& sensor, const PointCloud& cloud) {
  std::set<std::pair<int, int>> pixels;
  for (int i = 0; i < cloud.size(); ++i) {
    double u, v, z;
    if (sensor.Project(cloud.points.row(i), &u, &v, &z)) {
      pixels.insert({static_cast<int>(std::lround(u)), static_cast<int>(std::lround(v))});
    }
  }
  return pixels;
}

TEST(SensorArtefactsTest, QuantisationPutsDepthsOnTheDisparityGrid) {
  DepthSensorOptions options = AxisSensor();
  options.noise_coefficient = 2.85e-3;
  const Quad plane = Square(1.5, 1.5, 40 * kDeg);  // depths from about 0.54 to 2.46 m
  const std::vector<RenderSurface> surfaces = {plane.surface()};
  const double fb = options.camera.fx * 0.075, step = 0.125;
  const auto off_grid = [&](const PointCloud& cloud) {
    int off = 0;
    for (int i = 0; i < cloud.size(); ++i) {
      const double d = fb / cloud.points(i, 2) / step;
      off += std::abs(d - std::round(d)) > 1e-6;
    }
    return off;
  };
  const PointCloud clean = Shoot(options, surfaces, 3);
  ASSERT_GT(clean.size(), 5000);
  EXPECT_GT(off_grid(clean), clean.size() * 9 / 10);
  options.artefacts.disparity_step = step;
  const PointCloud quantised = Shoot(options, surfaces, 3);
  ASSERT_EQ(quantised.size(), clean.size());
  EXPECT_EQ(off_grid(quantised), 0);
  // Each depth moved by at most half a step of the grid there: z^2 step / (2 fb) plus noise.
  for (int i = 0; i < clean.size(); ++i) {
    const double z = clean.points(i, 2);
    EXPECT_LE(std::abs(quantised.points(i, 2) - z), z * z * step / (2 * fb) * 1.05 + 1e-9);
  }
  // The step between neighbouring levels grows as z^2 (docs/notes/2026-11-29-sensor-artefacts.md).
  const auto level_gap = [&](double z) {
    const double d = std::round(fb / z / step) * step;
    return fb / (d - step) - fb / d;
  };
  EXPECT_NEAR(level_gap(2.0) / level_gap(1.0), 4.0, 0.2);
}

TEST(SensorArtefactsTest, FlyingPixelsAppearOnlyAtSilhouettes) {
  DepthSensorOptions options = AxisSensor();
  const Quad front = Square(0.8, 0.15, 0.0), back = Square(1.2, 5.0, 0.0);
  const std::vector<RenderSurface> surfaces = {front.surface(), back.surface()};
  const auto between = [](const PointCloud& cloud) {
    std::vector<int> out;
    for (int i = 0; i < cloud.size(); ++i) {
      const double z = cloud.points(i, 2);
      if (z > 0.8 + 1e-6 && z < 1.2 - 1e-6) out.push_back(i);
    }
    return out;
  };
  const PointCloud clean = Shoot(options, surfaces, 5);
  EXPECT_TRUE(between(clean).empty());
  options.artefacts.flying_fraction = 1.0;
  const DepthSensor sensor(options);
  const DepthImage image = sensor.Render(surfaces);
  const PointCloud flying = sensor.Sample(image, surfaces, 5);
  ASSERT_EQ(flying.size(), clean.size());  // moved along their rays, none added or lost
  const std::vector<int> moved = between(flying);
  // The front square's outline is about 4 * 30 = 120 pixels long, edge pixels on both sides.
  EXPECT_GT(moved.size(), 150u);
  for (int i : moved) {
    double u, v, z;
    ASSERT_TRUE(sensor.Project(flying.points.row(i), &u, &v, &z));
    const int px = static_cast<int>(std::lround(u)), py = static_cast<int>(std::lround(v));
    float lo = 10, hi = 0;
    for (int dy = -1; dy <= 1; ++dy) {
      for (int dx = -1; dx <= 1; ++dx) {
        const float d = image.depth[static_cast<size_t>(py + dy) * image.width + px + dx];
        lo = std::min(lo, d);
        hi = std::max(hi, d);
      }
    }
    EXPECT_LT(lo, 0.81) << "pixel " << px << ", " << py << " is not at the silhouette";
    EXPECT_GT(hi, 1.19) << "pixel " << px << ", " << py << " is not at the silhouette";
  }
  // A smaller jump than the threshold makes no flying pixels.
  options.artefacts.flying_jump = 0.5;
  EXPECT_TRUE(between(Shoot(options, surfaces, 5)).empty());
}

TEST(SensorArtefactsTest, DarkHolesAreDiscsFixedOnTheSurfaceAndKeepTheCleanNoise) {
  DepthSensorOptions options = AxisSensor();
  options.noise_coefficient = 2.85e-3;
  const Quad plane = Square(1.0, 5.0, 0.0);
  const std::vector<RenderSurface> surfaces = {plane.surface()};
  const PointCloud clean = Shoot(options, surfaces, 1);
  options.artefacts.dark_fraction = 0.2;
  options.artefacts.dark_radius = 0.05;
  // The plane is 10 x 10 m, the view about 1.2 x 0.9 m: dark discs cover some of the view.
  const PointCloud dark = Shoot(options, surfaces, 1);
  EXPECT_LT(dark.size(), clean.size());
  EXPECT_GT(dark.size(), clean.size() / 3);
  // The kept pixels keep their clean points exactly (the noise stream is unchanged).
  int j = 0;
  for (int i = 0; i < clean.size() && j < dark.size(); ++i) {
    if (clean.points.row(i) == dark.points.row(j)) ++j;
  }
  EXPECT_EQ(j, dark.size());
  // Another frame (another seed): the same pixels are dark.
  const DepthSensor sensor(options);
  EXPECT_EQ(Pixels(sensor, Shoot(options, surfaces, 2)), Pixels(sensor, dark));
}

TEST(SensorArtefactsTest, SpecularHolesAtTheMirrorAngleOnly) {
  DepthSensorOptions options = AxisSensor();
  const Quad plane = Square(1.0, 5.0, 0.0);  // facing the camera: incidence = ray angle
  const std::vector<RenderSurface> surfaces = {plane.surface()};
  const auto min_angle = [](const PointCloud& cloud) {
    double lo = 90;
    for (int i = 0; i < cloud.size(); ++i) {
      const Eigen::Vector3d p = cloud.points.row(i);
      lo = std::min(lo, std::acos(p.z() / p.norm()) / kDeg);
    }
    return lo;
  };
  const PointCloud clean = Shoot(options, surfaces, 1);
  EXPECT_LT(min_angle(clean), 1.0);
  options.artefacts.specular_angle_deg = 10;
  const PointCloud specular = Shoot(options, surfaces, 1);
  EXPECT_GE(min_angle(specular), 10.0 - 1e-9);
  // A disc of 10 degrees is about 17.6 pixels in radius: about 980 of 10800 pixels.
  EXPECT_NEAR(clean.size() - specular.size(), M_PI * 17.6 * 17.6, 60);
}

TEST(SensorArtefactsTest, GrazingHolesAreBlobsOnObliqueSurfacesOnly) {
  DepthSensorOptions options = AxisSensor();
  options.artefacts.grazing_holes_deg = 50;
  options.artefacts.hole_blob_px = 6;
  const DepthSensor sensor(options);
  DepthSensorOptions clean_options = options;
  clean_options.artefacts.grazing_holes_deg = 0;
  const Quad facing = Square(1.0, 5.0, 10 * kDeg);
  EXPECT_EQ(Shoot(options, {facing.surface()}, 1).size(),
            Shoot(clean_options, {facing.surface()}, 1).size());
  const Quad oblique = Square(1.0, 0.6, 68 * kDeg);  // about 60-76 degrees of incidence
  const std::vector<RenderSurface> surfaces = {oblique.surface()};
  const std::set<std::pair<int, int>> all = Pixels(sensor, Shoot(clean_options, surfaces, 1));
  const std::set<std::pair<int, int>> kept = Pixels(sensor, Shoot(options, surfaces, 1));
  ASSERT_GT(all.size(), 1000u);
  EXPECT_LT(kept.size(), all.size() * 9 / 10);
  EXPECT_GT(kept.size(), all.size() / 10);
  // Blobs, not salt and pepper: a dropped pixel's right neighbour is mostly dropped too.
  int pairs = 0, both = 0;
  for (const auto& p : all) {
    const std::pair<int, int> right{p.first + 1, p.second};
    if (kept.count(p) || !all.count(right)) continue;
    ++pairs;
    both += !kept.count(right);
  }
  ASSERT_GT(pairs, 100);
  EXPECT_GT(both, pairs * 8 / 10);
}

TEST(SensorArtefactsTest, MultipathLengthensDepthsInConcaveCornersOnly) {
  DepthSensorOptions options = AxisSensor();
  // A wall at z = 0.7 and a floor at y = 0.3 in front of it: a concave corner along
  // y = 0.3, z = 0.7, seen from above the floor.
  const Quad wall(Eigen::Vector3d(-0.8, -0.6, 0.7), Eigen::Vector3d(0.8, -0.6, 0.7),
                  Eigen::Vector3d(0.8, 0.3, 0.7), Eigen::Vector3d(-0.8, 0.3, 0.7));
  const Quad floor(Eigen::Vector3d(-0.8, 0.3, 0.3), Eigen::Vector3d(0.8, 0.3, 0.3),
                   Eigen::Vector3d(0.8, 0.3, 0.7), Eigen::Vector3d(-0.8, 0.3, 0.7));
  const std::vector<RenderSurface> surfaces = {wall.surface(), floor.surface()};
  const PointCloud clean = Shoot(options, surfaces, 1);
  options.artefacts.multipath_bias = 0.02;
  options.artefacts.multipath_radius = 0.05;
  const PointCloud biased = Shoot(options, surfaces, 1);
  ASSERT_EQ(biased.size(), clean.size());
  double most = 0;
  int far_moved = 0, near_moved = 0;
  for (int i = 0; i < clean.size(); ++i) {
    const Eigen::Vector3d p = clean.points.row(i), q = biased.points.row(i);
    const double lengthened = q.norm() - p.norm();
    EXPECT_GE(lengthened, -1e-12);  // only ever longer
    EXPECT_LT((q.normalized() - p.normalized()).norm(), 1e-9);  // along the ray
    most = std::max(most, lengthened);
    const double to_corner = std::hypot(p.y() - 0.3, p.z() - 0.7);
    if (to_corner > 0.05) far_moved += lengthened > 0;
    if (to_corner < 0.02) near_moved += lengthened > 1e-3;
  }
  EXPECT_EQ(far_moved, 0);
  EXPECT_GT(near_moved, 100);
  EXPECT_GT(most, 0.2 * 0.02);
  EXPECT_LE(most, 0.02 * 1.2);  // the bias is along the axis, the ray up to 1.2 times longer
  // A single plane: nothing faces it.
  const Quad plane = Square(1.0, 5.0, 20 * kDeg);
  DepthSensorOptions flat = options;
  flat.artefacts.multipath_bias = 0;
  EXPECT_TRUE(Shoot(options, {plane.surface()}, 1).points.isApprox(
      Shoot(flat, {plane.surface()}, 1).points, 1e-12));
}

TEST(SensorArtefactsTest, FlickerDiffersBetweenFramesAndRepeatsWithTheSeed) {
  DepthSensorOptions options = AxisSensor();
  const Quad plane = Square(1.0, 5.0, 0.0);
  const std::vector<RenderSurface> surfaces = {plane.surface()};
  // Off: frames of a still scene are the same without noise.
  EXPECT_EQ(Shoot(options, surfaces, 1).points, Shoot(options, surfaces, 2).points);
  options.artefacts.flicker_offset = 0.002;
  const PointCloud a = Shoot(options, surfaces, 1), b = Shoot(options, surfaces, 2);
  EXPECT_EQ(a.points, Shoot(options, surfaces, 1).points);
  ASSERT_EQ(a.size(), b.size());
  const double za = a.points.col(2).mean(), zb = b.points.col(2).mean();
  EXPECT_GT(std::abs(za - zb), 1e-5);
  // One offset for every pixel of a frame.
  EXPECT_NEAR(a.points.col(2).maxCoeff(), a.points.col(2).minCoeff(), 1e-12);
  // Offsets over 200 frames have the given spread.
  double sum = 0, sum2 = 0;
  const Quad small = Square(1.0, 0.01, 0.0);
  for (uint64_t seed = 0; seed < 200; ++seed) {
    const double offset = Shoot(options, {small.surface()}, seed).points(0, 2) - 1.0;
    sum += offset;
    sum2 += offset * offset;
  }
  EXPECT_NEAR(std::sqrt(sum2 / 200 - (sum / 200) * (sum / 200)), 0.002, 0.0004);

  options.artefacts.flicker_offset = 0;
  options.artefacts.flicker_dropout = 0.1;
  const DepthSensor sensor(options);
  const auto one = Pixels(sensor, Shoot(options, surfaces, 1));
  const auto two = Pixels(sensor, Shoot(options, surfaces, 2));
  EXPECT_EQ(one, Pixels(sensor, Shoot(options, surfaces, 1)));
  EXPECT_NE(one, two);
  const double n = options.camera.width * options.camera.height;
  EXPECT_NEAR(one.size() / n, 0.9, 0.02);
  EXPECT_NEAR(two.size() / n, 0.9, 0.02);
}

TEST(SensorArtefactsTest, OptionsAreChecked) {
  DepthSensorOptions options = AxisSensor();
  std::string why;
  EXPECT_TRUE(options.IsValid(&why)) << why;
  options.artefacts.flying_fraction = 1.5;
  EXPECT_FALSE(options.IsValid(&why));
  EXPECT_NE(why.find("flying_pixels"), std::string::npos) << why;
  options.artefacts.flying_fraction = 0.5;
  options.artefacts.baseline = 0;
  EXPECT_FALSE(options.IsValid(&why));
  EXPECT_NE(why.find("quantisation"), std::string::npos) << why;
}

}  // namespace
}  // namespace femreg
