#include "registration/flying_pixels.h"

#include <Eigen/Dense>
#include <algorithm>
#include <array>
#include <cmath>
#include <utility>
#include <vector>

#include "femreg/point_cloud.h"
#include "registration/cloud_subset.h"

namespace femreg {
namespace {

constexpr long kMaxPixelStep = 4;
// The tolerance never goes below one sample footprint (k z / fx): a depth that close to a
// surface is also a point up to a sample beside it, and a silhouette's last samples (a limb)
// step by about that much.
constexpr double kMinFootprints = 1.0;
// A window's plane needs this many samples (of its 8 or 10).
constexpr int kMinWindowSamples = 5;
// A window's plane fits its samples within this share of the tolerance (RMS; at the default
// tolerance one sigma of the depth, where a plane over 5-8 samples leaves sqrt((n-3)/n) of it
// from noise alone): a plane tilted to take in a step of mixed pixels does not.
constexpr double kWindowFit = 0.25;
// Of the second differences along rows and columns, this share is within one standard
// deviation of a Gaussian's; their noise is taken from that quantile.
constexpr double kOneSigmaQuantile = 0.683;

struct Offset {
  long du, dv;
};

// The windows a surface through a point may come from, in samples: the four half-windows of
// its 5 x 5 neighbourhood (left, right, above, below) and its four 3 x 3 corner quadrants.
std::vector<std::vector<Offset>> Windows() {
  std::vector<std::vector<Offset>> w(8);
  for (long dv = -2; dv <= 2; ++dv) {
    for (long du = -2; du <= 2; ++du) {
      if (du < 0) w[0].push_back({du, dv});
      if (du > 0) w[1].push_back({du, dv});
      if (dv < 0) w[2].push_back({du, dv});
      if (dv > 0) w[3].push_back({du, dv});
    }
  }
  int q = 4;
  for (long sx : {-1L, 1L}) {
    for (long sy : {-1L, 1L}) {
      for (long dv = 0; dv <= 2; ++dv) {
        for (long du = 0; du <= 2; ++du) {
          if (du != 0 || dv != 0) w[static_cast<size_t>(q)].push_back({sx * du, sy * dv});
        }
      }
      ++q;
    }
  }
  return w;
}

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
  // The point on pixel (u, v), or -1.
  const auto at = [&](long u, long v) {
    if (u < 0 || v < 0 || u >= camera.width || v >= camera.height) return -1;
    return pixel_point[static_cast<size_t>(v) * w + static_cast<size_t>(u)];
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
      if (at(u + k, v) >= 0 || at(u, v + k) >= 0) ++paired;
    }
    if (2 * paired >= n - misplaced) step = k;
  }
  if (step == 0) return 0;  // no image structure to judge by
  const auto z_of = [&](int j) { return depth[static_cast<size_t>(j)]; };

  // The depth's noise, from the image itself: the spread of the second differences along rows
  // and columns (sqrt(6) times the depth's own noise on a plane), over z^2 (a triangulating
  // sensor's noise law). Edges are a minority of them; a quantile, not a mean, keeps them out.
  std::vector<double> second;
  for (int i = 0; i < n; ++i) {
    const long p = pixel_of[static_cast<size_t>(i)];
    if (p < 0) continue;
    const long u = p % static_cast<long>(w), v = p / static_cast<long>(w);
    const double z = z_of(i);
    for (const Offset d : {Offset{1, 0}, Offset{0, 1}}) {
      const int a = at(u - step * d.du, v - step * d.dv), b = at(u + step * d.du, v + step * d.dv);
      if (a >= 0 && b >= 0) second.push_back(std::abs(z_of(a) - 2.0 * z + z_of(b)) / (z * z));
    }
  }
  double sigma_over_z2 = 0.0;  // of the depth
  if (!second.empty()) {
    const size_t q = std::min(second.size() - 1, static_cast<size_t>(kOneSigmaQuantile * second.size()));
    std::nth_element(second.begin(), second.begin() + static_cast<std::ptrdiff_t>(q), second.end());
    sigma_over_z2 = second[q] / std::sqrt(6.0);
  }

  static const std::vector<std::vector<Offset>> windows = Windows();
  // The image as given: a pixel whose point is removed below is not a hole (a masked tool).
  const std::vector<int> given = pixel_point;
  // Whether point i lies between surfaces and no surface around it supports it.
  const auto unsupported = [&](int i) {
    const long p = pixel_of[static_cast<size_t>(i)];
    const long u = p % static_cast<long>(w), v = p / static_cast<long>(w);
    const double z = z_of(i);
    const double tau = std::max(tolerance * sigma_over_z2 * z * z,
                                kMinFootprints * static_cast<double>(step) * z / camera.fx);
    // A mixed pixel lies between the surfaces around it; a sample in front of (or behind)
    // all its neighbours, an object sampled more sparsely than its background, is not one.
    // A sample missing inside the image may be a masked tool or hand in front: a point beside
    // one, in front of a neighbour by more than the tolerance, may be its mixed pixel. (Behind a
    // neighbour beside a hole is a slanted face's far edge as often: not judged.)
    int neighbours = 0;
    bool nearer = false, farther = false, missing = false;
    for (long dv = -1; dv <= 1; ++dv) {
      for (long du = -1; du <= 1; ++du) {
        if (du == 0 && dv == 0) continue;
        const long nu = u + step * du, nv = v + step * dv;
        const int j = at(nu, nv);
        if (j < 0) {
          missing |= nu >= 0 && nv >= 0 && nu < camera.width && nv < camera.height &&
                     given[static_cast<size_t>(nv) * w + static_cast<size_t>(nu)] < 0;
          continue;
        }
        ++neighbours;
        nearer |= z_of(j) - z < -tau;
        farther |= z_of(j) - z > tau;
      }
    }
    if (neighbours < 2 || (!(nearer && farther) && !(missing && farther))) return false;

    // Supported from a direction: the neighbour there at its depth, or the surface through
    // that neighbour and the next one continued to it (a slanted plane: inverse depth is
    // linear along the image). Two directions off one line: a surface, not the one-pixel
    // curtain of mixed pixels along an edge, which only supports itself along the edge.
    bool supported = false;
    long su = 0, sv = 0;
    int directions = 0;
    for (long dv = -1; dv <= 1 && !supported; ++dv) {
      for (long du = -1; du <= 1 && !supported; ++du) {
        const int a = (du == 0 && dv == 0) ? -1 : at(u + step * du, v + step * dv);
        if (a < 0) continue;
        bool ok = std::abs(z_of(a) - z) <= tau;
        const int b = at(u + 2 * step * du, v + 2 * step * dv);
        if (!ok && b >= 0) {
          const double inverse = 2.0 / z_of(a) - 1.0 / z_of(b);
          ok = inverse > 0 && std::abs(z - 1.0 / inverse) <= tau;
        }
        // A curved surface (a limb, where the depth's slope grows): the parabola through
        // three samples in a row.
        const int c = at(u + 3 * step * du, v + 3 * step * dv);
        if (!ok && b >= 0 && c >= 0) {
          const double inverse = 3.0 / z_of(a) - 3.0 / z_of(b) + 1.0 / z_of(c);
          ok = inverse > 0 && std::abs(z - 1.0 / inverse) <= tau;
        }
        if (!ok) continue;
        if (directions++ == 0) {
          su = du;
          sv = dv;
        } else if (su * dv - sv * du != 0) {
          supported = true;
        }
      }
    }
    // Or a plane fitted to one side of the neighbourhood (a half or a corner of it, the
    // surface there whole: at a silhouette's corner, or a face beside an edge of the object)
    // fits its samples and the point, within the tolerance.
    for (size_t k = 0; k < windows.size() && !supported; ++k) {
      Eigen::Matrix3d normal = Eigen::Matrix3d::Zero();
      Eigen::Vector3d rhs = Eigen::Vector3d::Zero();
      std::array<std::pair<Eigen::Vector3d, double>, 10> samples;
      int count = 0;
      for (const Offset d : windows[k]) {
        const int j = at(u + step * d.du, v + step * d.dv);
        if (j < 0) continue;
        const Eigen::Vector3d f(1.0, static_cast<double>(d.du), static_cast<double>(d.dv));
        normal += f * f.transpose();
        rhs += f / z_of(j);
        samples[static_cast<size_t>(count++)] = {f, z_of(j)};
      }
      if (count < kMinWindowSamples) continue;
      // An integer matrix: singular (the samples on one line) exactly when this is 0.
      if (std::abs(normal.determinant()) < 0.5) continue;
      const Eigen::Vector3d plane = normal.ldlt().solve(rhs);  // inverse depth = plane . (1, du, dv)
      if (!(plane(0) > 0) || !plane.allFinite()) continue;
      double squares = 0.0;
      for (int s = 0; s < count; ++s) {
        const double zj = samples[static_cast<size_t>(s)].second;
        const double off = (plane.dot(samples[static_cast<size_t>(s)].first) - 1.0 / zj) * zj * zj;
        squares += off * off;
      }
      supported = squares <= kWindowFit * kWindowFit * tau * tau * count &&
                  std::abs(z - 1.0 / plane(0)) <= tau;
    }
    return !supported;
  };
  // Support must come from points that stay. A sensor that mixes at every pixel, written at
  // every other one, leaves mixed pixels two samples deep along an edge, and they hold each
  // other up; so the points around those removed are judged again without them, until none
  // goes. (Removing points only takes support away, never adds it; each pass removes some.)
  std::vector<char> drop(static_cast<size_t>(n), 0);
  std::vector<int> judge;
  for (int i = 0; i < n; ++i) {
    if (pixel_of[static_cast<size_t>(i)] >= 0) judge.push_back(i);
  }
  std::vector<char> queued(static_cast<size_t>(n), 0);
  int removed = 0;
  while (!judge.empty()) {
    std::vector<int> go;
    for (const int i : judge) {
      if (unsupported(i)) go.push_back(i);
    }
    for (const int i : go) {
      drop[static_cast<size_t>(i)] = 1;
      pixel_point[static_cast<size_t>(pixel_of[static_cast<size_t>(i)])] = -1;
    }
    removed += static_cast<int>(go.size());
    // Judged again: the points whose judgement looked at a removed one (within three
    // samples, the parabola's reach; the windows reach two).
    for (const int j : judge) queued[static_cast<size_t>(j)] = 0;  // only those this pass set
    judge.clear();
    for (const int i : go) {
      const long p = pixel_of[static_cast<size_t>(i)];
      const long u = p % static_cast<long>(w), v = p / static_cast<long>(w);
      for (long dv = -3; dv <= 3; ++dv) {
        for (long du = -3; du <= 3; ++du) {
          const int j = at(u + step * du, v + step * dv);
          if (j >= 0 && !queued[static_cast<size_t>(j)]) {
            queued[static_cast<size_t>(j)] = 1;
            judge.push_back(j);
          }
        }
      }
    }
    std::sort(judge.begin(), judge.end());
  }
  if (removed == 0) return 0;
  KeepPoints([&](int i) { return !drop[static_cast<size_t>(i)]; }, cloud);
  return removed;
}

}  // namespace femreg
