#include "registration/flying_pixels.h"

#include <cmath>
#include <vector>

#include "femreg/point_cloud.h"
#include "registration/cloud_subset.h"

namespace femreg {
namespace {
constexpr long kMaxPixelStep = 4;
}  // namespace

int RemoveFlyingPixels(const CameraOptions& camera, double tolerance, PointCloud* cloud) {
  const int n = cloud->size();
  if (n == 0 || !(tolerance > 0) || camera.width <= 0 || camera.height <= 0) return 0;
  const Eigen::Matrix3d r = CameraRotation(camera);
  const size_t w = static_cast<size_t>(camera.width), h = static_cast<size_t>(camera.height);
  std::vector<int> pixel_point(w * h, -1);
  std::vector<double> depth(static_cast<size_t>(n), 0.0);
  std::vector<long> pixel_of(static_cast<size_t>(n), -1);
  int misplaced = 0;
  for (int i = 0; i < n; ++i) {
    if (!cloud->points.row(i).allFinite()) continue;  // dropped later, and not judged
    const Eigen::Vector3d q = r * (cloud->points.row(i).transpose() - camera.position);
    const long u = q.z() > 0 ? std::lround(camera.fx * q.x() / q.z() + camera.cx) : -1;
    const long v = q.z() > 0 ? std::lround(camera.fy * q.y() / q.z() + camera.cy) : -1;
    if (u < 0 || v < 0 || u >= camera.width || v >= camera.height) {
      ++misplaced;
      continue;
    }
    const size_t p = static_cast<size_t>(v) * w + static_cast<size_t>(u);
    if (pixel_point[p] >= 0) {
      ++misplaced;
      continue;
    }
    pixel_point[p] = i;
    pixel_of[static_cast<size_t>(i)] = static_cast<long>(p);
    depth[static_cast<size_t>(i)] = q.z();
  }
  if (10 * misplaced > n) return -1;
  const auto occupied = [&](long u, long v) {
    return u >= 0 && v >= 0 && u < camera.width && v < camera.height &&
           pixel_point[static_cast<size_t>(v) * w + static_cast<size_t>(u)] >= 0;
  };
  // The image's sampling step (a sensor or a writer may keep every k-th pixel): the smallest
  // k at which half of the points have a neighbour k pixels right or down (a depth image's
  // interior points all have one; a cloud projected with the wrong intrinsics is irregular).
  long step = 0;
  for (long k = 1; k <= kMaxPixelStep && step == 0; ++k) {
    int paired = 0;
    for (int i = 0; i < n; ++i) {
      const long p = pixel_of[static_cast<size_t>(i)];
      if (p < 0) continue;
      const long u = p % static_cast<long>(w), v = p / static_cast<long>(w);
      if (occupied(u + k, v) || occupied(u, v + k)) ++paired;
    }
    if (2 * paired >= n - misplaced) step = k;
  }
  if (step == 0) return 0;  // no image structure to judge by

  std::vector<char> drop(static_cast<size_t>(n), 0);
  int removed = 0;
  for (int i = 0; i < n; ++i) {
    const long p = pixel_of[static_cast<size_t>(i)];
    if (p < 0) continue;
    const long u = p % static_cast<long>(w), v = p / static_cast<long>(w);
    const double z = depth[static_cast<size_t>(i)];
    const double within = tolerance * static_cast<double>(step) * z / camera.fx;
    int neighbours = 0, support = 0;
    long su = 0, sv = 0;  // the first supporting neighbour's offset
    bool spread = false;  // two supporting neighbours off one line through the pixel
    bool nearer = false, farther = false;  // a neighbour in front of it, and one behind
    for (long dv = -1; dv <= 1; ++dv) {
      for (long du = -1; du <= 1; ++du) {
        const long uu = u + step * du, vv = v + step * dv;
        if ((du == 0 && dv == 0) || !occupied(uu, vv)) continue;
        const int j = pixel_point[static_cast<size_t>(vv) * w + static_cast<size_t>(uu)];
        ++neighbours;
        const double dz = depth[static_cast<size_t>(j)] - z;
        nearer |= dz < -within;
        farther |= dz > within;
        if (std::abs(dz) > within) continue;
        if (support++ == 0) {
          su = du;
          sv = dv;
        } else if (su * dv - sv * du != 0) {
          spread = true;
        }
      }
    }
    // A mixed pixel lies between the surfaces around it; a sample in front of all its
    // neighbours (an object sampled more sparsely than its background) is not one.
    if (neighbours >= 2 && !spread && nearer && farther) {
      drop[static_cast<size_t>(i)] = 1;
      ++removed;
    }
  }
  if (removed == 0) return 0;
  KeepPoints([&](int i) { return !drop[static_cast<size_t>(i)]; }, cloud);
  return removed;
}

}  // namespace femreg
