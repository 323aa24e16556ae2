// Flying pixels: a depth edge's mixed pixels go, the surfaces on either side stay
// (registration/flying_pixels.h).
#include "registration/flying_pixels.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <functional>

#include "femreg/point_cloud.h"

namespace femreg {
namespace {

CameraOptions Camera() {
  CameraOptions c;
  c.enabled = true;
  c.position = Eigen::Vector3d(0, 0, 0);
  c.target = Eigen::Vector3d(0, 0, 1);
  c.up = Eigen::Vector3d(0, -1, 0);
  c.fx = c.fy = 150;
  c.width = 160;
  c.height = 120;
  c.cx = 79.5;
  c.cy = 59.5;
  return c;
}

// One point per pixel (every step-th pixel) at the depth depth(u, v) (<= 0: no point), on
// the pixel's ray.
PointCloud Render(const CameraOptions& c, const std::function<double(int, int)>& depth, int step = 1) {
  const Eigen::Matrix3d R = CameraRotation(c);
  std::vector<Eigen::Vector3d> pts;
  for (int v = 0; v < c.height; v += step) {
    for (int u = 0; u < c.width; u += step) {
      const double z = depth(u, v);
      if (!(z > 0)) continue;
      pts.push_back(c.position + R.transpose() * (z * Eigen::Vector3d((u - c.cx) / c.fx, (v - c.cy) / c.fy, 1)));
    }
  }
  PointCloud cloud;
  cloud.points.resize(static_cast<int>(pts.size()), 3);
  for (size_t i = 0; i < pts.size(); ++i) cloud.points.row(static_cast<int>(i)) = pts[i].transpose();
  return cloud;
}

// A depth camera's noise on pixel (u, v): Gaussian, sigma = 2.85e-3 z^2 (a structured-light
// sensor's), from a hash of the pixel, so the same on every platform.
double Noise(int u, int v, double z) {
  auto uniform = [](uint64_t x) {
    x += 0x9e3779b97f4a7c15ull;
    x = (x ^ (x >> 30)) * 0xbf58476d1ce4e5b9ull;
    x = (x ^ (x >> 27)) * 0x94d049bb133111ebull;
    x ^= x >> 31;
    return (static_cast<double>(x >> 11) + 0.5) / 9007199254740992.0;  // (0, 1)
  };
  const uint64_t key = static_cast<uint64_t>(v) * 100003ull + static_cast<uint64_t>(u);
  const double a = uniform(2 * key), b = uniform(2 * key + 1);
  return 2.85e-3 * z * z * std::sqrt(-2.0 * std::log(a)) * std::cos(2.0 * M_PI * b);
}

// The points of `cloud` at depth (along the optical axis) within [lo, hi].
int CountDepths(const CameraOptions& c, const PointCloud& cloud, double lo, double hi) {
  const Eigen::Matrix3d R = CameraRotation(c);
  int count = 0;
  for (int i = 0; i < cloud.size(); ++i) {
    const double z = (R * (cloud.points.row(i).transpose() - c.position)).z();
    count += z >= lo && z <= hi;
  }
  return count;
}

TEST(FlyingPixels, MixedPixelsOnADepthEdgeGoAndBothSurfacesStay) {
  const CameraOptions c = Camera();
  // A near wall (0.5 m) left of column 80, a far one (0.6 m) right of it; column 80 mixes
  // them, smoothly along the edge (a curtain whose pixels support each other up and down).
  const auto depth = [&](int u, int v) {
    if (u < 80) return 0.5;
    if (u > 80) return 0.6 + 0.0005 * (u - 80);  // a little slanted
    return 0.5 + (0.3 + 0.4 * v / c.height) * 0.1;
  };
  PointCloud cloud = Render(c, depth);
  const int before = cloud.size();
  EXPECT_EQ(RemoveFlyingPixels(c, 3.0, &cloud), c.height);
  EXPECT_EQ(cloud.size(), before - c.height);
  const Eigen::Matrix3d R = CameraRotation(c);
  for (int i = 0; i < cloud.size(); ++i) {
    const double z = (R * cloud.points.row(i).transpose()).z();
    EXPECT_TRUE(std::abs(z - 0.5) < 1e-9 || z >= 0.6 - 1e-9) << "a mixed pixel at depth " << z << " stayed";
  }
  // The same image sampled at every other pixel (a sensor's pixel stride): the same judgement.
  PointCloud sampled = Render(c, depth, 2);
  EXPECT_EQ(RemoveFlyingPixels(c, 3.0, &sampled), c.height / 2);
}

// A plane seen at up to 68 degrees of incidence changes its depth by less than 2.5 footprints
// a pixel: it is supported, and nothing of it goes.
TEST(FlyingPixels, ObliqueSurfacesStay) {
  const CameraOptions c = Camera();
  const double slope = std::tan(60.0 * M_PI / 180.0);  // the plane z = 0.5 + slope X
  const Eigen::Vector3d normal = Eigen::Vector3d(-slope, 0, 1).normalized();
  const auto depth = [&](int u, int v) {
    const Eigen::Vector3d ray((u - c.cx) / c.fx, (v - c.cy) / c.fy, 1);
    const double incidence = std::acos(std::abs(normal.dot(ray.normalized())));
    if (incidence > 68.0 * M_PI / 180.0) return 0.0;
    return 0.5 / (1.0 - slope * ray.x());
  };
  PointCloud cloud = Render(c, depth);
  const int before = cloud.size();
  ASSERT_GT(before, 1000);
  EXPECT_EQ(RemoveFlyingPixels(c, 3.0, &cloud), 0);
  EXPECT_EQ(cloud.size(), before);
}

// A noisy sensor written at every other pixel (as the robustness sequences are): the mixed
// pixels of an edge that lie a few footprints behind the near surface, well beyond its noise,
// go; both surfaces, noise and all, stay.
TEST(FlyingPixels, MixedPixelsCloseToTheNearSurfaceGo) {
  const CameraOptions c = Camera();
  // Near wall 0.5 m left of column 80, far wall 0.7 m right of it. Column 80 mixes them, 2.7
  // to 3.9 sample footprints (2 z / fx: 6.7 mm here) behind the near wall, varying along the
  // edge: within the 4 footprints of the filter's first version, which did not judge them.
  const auto depth = [&](int u, int v) {
    const double z = u < 80 ? 0.5 : u > 80 ? 0.7 : 0.5 + 0.018 + 0.008 * (v % 7) / 6.0;
    return z + Noise(u, v, z);
  };
  PointCloud cloud = Render(c, depth, 2);
  const int near = CountDepths(c, cloud, 0.49, 0.505), far = CountDepths(c, cloud, 0.69, 0.71);
  ASSERT_EQ(near + far + c.height / 2, cloud.size());
  RemoveFlyingPixels(c, 4.0, &cloud);
  EXPECT_EQ(CountDepths(c, cloud, 0.505, 0.69), 0) << "mixed pixels stayed";
  // Of the walls' 4,740 points, noise may cost a handful, not more.
  EXPECT_GE(CountDepths(c, cloud, 0.49, 0.505), near - 5);
  EXPECT_GE(CountDepths(c, cloud, 0.69, 0.71), far - 5);
}

// A plane so steep that its depth changes by up to five footprints a pixel, with the sensor's
// noise on it: every pixel lies between nearer and farther ones, but the plane through its
// neighbours, continued, predicts it. It stays whole, and so does the far wall it ends in
// front of; the mixed pixels of the edge between them go.
TEST(FlyingPixels, SteepNoisySurfacesStayBesideAnEdge) {
  const CameraOptions c = Camera();
  // The plane z = 0.6 + 5.67 Y (Y the camera's y: 80 degrees from fronto-parallel) in the
  // image's upper half; a wall at 1 m below it, with a row of mixed pixels between them.
  const double slope = std::tan(80.0 * M_PI / 180.0);
  const auto plane = [&](int v) { return 0.6 / (1.0 - slope * (v - c.cy) / c.fy); };
  const auto depth = [&](int u, int v) {
    const double z = v <= 60 ? plane(v) : v == 61 ? plane(61) + 0.3 * (1.0 - plane(61)) : 1.0;
    return z + Noise(u, v, z);
  };
  PointCloud cloud = Render(c, depth);
  const double edge = plane(60) + 0.01;
  const int steep = CountDepths(c, cloud, 0.1, edge), wall = CountDepths(c, cloud, 0.98, 1.02);
  ASSERT_EQ(steep + wall + c.width, cloud.size());
  RemoveFlyingPixels(c, 4.0, &cloud);
  EXPECT_EQ(CountDepths(c, cloud, edge, 0.98), 0) << "mixed pixels stayed";
  EXPECT_GE(CountDepths(c, cloud, 0.1, edge), steep - 10);
  EXPECT_GE(CountDepths(c, cloud, 0.98, 1.02), wall - 10);
}

// A tool masked out of the image (its pixels hold no point) in front of a wall: the wall's
// samples beside it that mixed in the tool's depth lie 15-25 mm in front of the wall, with no
// nearer neighbour left in the cloud to show they are between surfaces. Beside the hole, a
// farther neighbour is enough to judge them: they go. The wall, up to the hole, stays; so does
// the same wall with the hole and no mixed pixels.
TEST(FlyingPixels, MixedPixelsBesideAMaskedToolGo) {
  const CameraOptions c = Camera();
  const auto tool = [](int u, int v) { return u >= 80 && u <= 110 && v >= 30 && v <= 90; };
  const auto wall = [&](int u, int v) {
    return tool(u, v) ? 0.0 : 0.5 + Noise(u, v, 0.5);
  };
  // Written at every other pixel, as the robustness sequences are: the samples beside the hole
  // are in columns 78 and 112.
  const auto mixed = [&](int u, int v) {
    if ((u == 78 || u == 112) && v >= 30 && v <= 90) return 0.5 - 0.015 - 0.01 * (v % 5) / 4.0;
    return wall(u, v);
  };
  PointCloud cloud = Render(c, mixed, 2);
  const int in_front = CountDepths(c, cloud, 0.47, 0.49), behind = CountDepths(c, cloud, 0.49, 0.51);
  ASSERT_EQ(in_front, 2 * 31);
  ASSERT_EQ(in_front + behind, cloud.size());
  RemoveFlyingPixels(c, 4.0, &cloud);
  EXPECT_EQ(CountDepths(c, cloud, 0.47, 0.49), 0) << "mixed pixels beside the hole stayed";
  EXPECT_GE(CountDepths(c, cloud, 0.49, 0.51), behind - 5);

  PointCloud clean = Render(c, wall, 2);
  const int points = clean.size();
  EXPECT_EQ(RemoveFlyingPixels(c, 4.0, &clean), 0);
  EXPECT_EQ(clean.size(), points);
}

// Mixed pixels that hold each other up: a near wall (0.5 m) left of column 81, a far one
// right of it, and three mixed pixels on the edge. X (80, 60) lies within the tolerance of W
// below it and of Z up and right: two directions off one line, so X alone would stay. W and Z
// have one direction each and go; support comes only from points that stay, so X goes too.
// Both walls stay whole.
TEST(FlyingPixels, MixedPixelsThatOnlySupportEachOtherGo) {
  const CameraOptions c = Camera();
  const auto depth = [&](int u, int v) {
    if (u == 80 && v == 60) return 0.55;   // X
    if (u == 80 && v == 61) return 0.552;  // W
    if (u == 81 && v == 59) return 0.551;  // Z
    return u <= 80 ? 0.5 : 0.6 + 0.0005 * (u - 80);
  };
  PointCloud cloud = Render(c, depth);
  const int near = CountDepths(c, cloud, 0.49, 0.51), far = CountDepths(c, cloud, 0.59, 0.7);
  ASSERT_EQ(near + far + 3, cloud.size());
  EXPECT_EQ(RemoveFlyingPixels(c, 3.0, &cloud), 3);
  EXPECT_EQ(CountDepths(c, cloud, 0.51, 0.59), 0) << "mixed pixels stayed";
  EXPECT_EQ(CountDepths(c, cloud, 0.49, 0.51), near);
  EXPECT_EQ(CountDepths(c, cloud, 0.59, 0.7), far);
}

// A clean object's silhouette, where another camera would put mixed pixels: a ball in front
// of a table seen obliquely, with the sensor's noise and its grazing limit, written at every
// other pixel. Its limb's last samples step steeply away, between the ball's nearer samples
// and the table behind (or a hole), but they lie on the ball: every point of the ball stays,
// and so does the table.
TEST(FlyingPixels, TheSilhouetteOfACleanObjectStays) {
  const CameraOptions c = Camera();
  const Eigen::Vector3d centre(0.0, 0.0, 0.5);
  const double radius = 0.08;
  const auto depth = [&](int u, int v) {
    const Eigen::Vector3d ray((u - c.cx) / c.fx, (v - c.cy) / c.fy, 1.0);
    // The ball: the nearer root of |t ray - centre| = radius (z = t, the ray's z being 1).
    const double a = ray.squaredNorm(), b = -2.0 * ray.dot(centre), k = centre.squaredNorm() - radius * radius;
    const double disc = b * b - 4.0 * a * k;
    // The table: the plane z = 0.7 + 0.5 y, seen at about 27 degrees.
    double z = 0.7 / (1.0 - 0.5 * ray.y());
    if (disc >= 0) {
      z = (-b - std::sqrt(disc)) / (2.0 * a);
      // No return beyond 80 degrees of incidence (a sensor's grazing limit).
      const Eigen::Vector3d normal = (z * ray - centre) / radius;
      if (std::abs(normal.dot(ray.normalized())) < std::cos(80.0 * M_PI / 180.0)) return 0.0;
    }
    return z + Noise(u, v, z);
  };
  PointCloud cloud = Render(c, depth, 2);
  const int ball = CountDepths(c, cloud, 0.4, 0.6), table = cloud.size() - ball;
  ASSERT_GT(ball, 500);
  ASSERT_GE(RemoveFlyingPixels(c, 4.0, &cloud), 0) << "the filter did not run";
  EXPECT_EQ(CountDepths(c, cloud, 0.4, 0.6), ball) << "the ball's own points went";
  EXPECT_GE(cloud.size() - CountDepths(c, cloud, 0.4, 0.6), table - 5);
}

// A cloud that is not one depth image of the camera (fused from two views: two points on
// many pixels) is left as it is.
TEST(FlyingPixels, OtherCloudsAreLeftAlone) {
  const CameraOptions c = Camera();
  PointCloud a = Render(c, [](int, int) { return 0.5; });
  PointCloud b = Render(c, [](int u, int) { return u % 2 ? 0.55 : 0.0; });
  PointCloud both;
  both.points.resize(a.size() + b.size(), 3);
  both.points << a.points, b.points;
  const int before = both.size();
  EXPECT_EQ(RemoveFlyingPixels(c, 3.0, &both), -1);
  EXPECT_EQ(both.size(), before);
  // An object sampled at every other pixel in front of a wall seen at every pixel (a depth
  // image whose holes were filled): its samples are in front of all their neighbours, not
  // between surfaces, and stay.
  PointCloud interleaved = Render(c, [](int u, int v) { return u % 2 == 0 && v % 2 == 0 && u < 80 ? 0.5 : 2.5; });
  const int samples = interleaved.size();
  EXPECT_EQ(RemoveFlyingPixels(c, 4.0, &interleaved), 0);
  EXPECT_EQ(interleaved.size(), samples);
  // Off: nothing judged.
  PointCloud edge = Render(c, [](int u, int) { return u == 80 ? 0.55 : u < 80 ? 0.5 : 0.6; });
  EXPECT_EQ(RemoveFlyingPixels(c, 0.0, &edge), 0);
}

}  // namespace
}  // namespace femreg
