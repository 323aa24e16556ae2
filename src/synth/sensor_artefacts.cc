#include "synth/sensor_artefacts.h"

#include <algorithm>
#include <cmath>
#include <random>

namespace femreg {
namespace synth_internal {

namespace {

// splitmix64: a well-mixed hash of the lattice coordinates, the same on every platform.
uint64_t Mix(uint64_t x) {
  x += 0x9e3779b97f4a7c15ull;
  x = (x ^ (x >> 30)) * 0xbf58476d1ce4e5b9ull;
  x = (x ^ (x >> 27)) * 0x94d049bb133111ebull;
  return x ^ (x >> 31);
}

double LatticeValue(int64_t i, int64_t j) {
  const uint64_t h =
      Mix(static_cast<uint64_t>(i) * 0x100000001b3ull ^ Mix(static_cast<uint64_t>(j)));
  return static_cast<double>(h >> 11) * (1.0 / 9007199254740992.0);  // 53 bits in [0, 1)
}

double Smoothstep(double t) { return t * t * (3.0 - 2.0 * t); }

}  // namespace

ImageGeometry ComputeImageGeometry(const DepthImage& image,
                                   const std::vector<RenderSurface>& surfaces,
                                   const CameraOptions& camera, const Eigen::Matrix3d& rotation) {
  ImageGeometry g;
  const size_t n = image.depth.size();
  g.point.assign(n, Eigen::Vector3d::Zero());
  g.normal.assign(n, Eigen::Vector3d::Zero());
  for (int py = 0; py < image.height; ++py) {
    for (int px = 0; px < image.width; ++px) {
      const size_t idx = static_cast<size_t>(py) * image.width + px;
      if (image.triangle[idx] < 0) continue;
      const Eigen::Vector3d ray_c((px - camera.cx) / camera.fx, (py - camera.cy) / camera.fy, 1.0);
      g.point[idx] = camera.position + rotation.transpose() * (image.depth[idx] * ray_c);
      const RenderSurface& s = surfaces[static_cast<size_t>(image.surface[idx])];
      const int f = image.triangle[idx];
      const Eigen::Vector3d a = s.positions->row((*s.triangles)(f, 0));
      const Eigen::Vector3d b = s.positions->row((*s.triangles)(f, 1));
      const Eigen::Vector3d c = s.positions->row((*s.triangles)(f, 2));
      Eigen::Vector3d normal = (b - a).cross(c - a).normalized();
      if (normal.dot(camera.position - g.point[idx]) < 0) normal = -normal;
      g.normal[idx] = normal;
    }
  }
  return g;
}

std::vector<Eigen::Vector3d> DarkCentres(const Vertices& positions, const Triangles& triangles,
                                         double fraction, double radius, uint64_t salt) {
  std::vector<Eigen::Vector3d> centres;
  if (!(fraction > 0)) return centres;
  std::uniform_real_distribution<double> uni(0.0, 1.0);
  const double disc = M_PI * radius * radius;
  for (int f = 0; f < triangles.rows(); ++f) {
    const Eigen::Vector3d a = positions.row(triangles(f, 0));
    const Eigen::Vector3d b = positions.row(triangles(f, 1));
    const Eigen::Vector3d c = positions.row(triangles(f, 2));
    // A generator per triangle: its centres stay put when the deformation changes the areas
    // (and so the counts) of other triangles.
    std::mt19937_64 rng(Mix(salt ^ Mix(static_cast<uint64_t>(f))));
    const double expected = fraction * 0.5 * (b - a).cross(c - a).norm() / disc;
    const double u = uni(rng);
    const double whole = std::floor(expected);
    const int count = static_cast<int>(whole) + (u < expected - whole ? 1 : 0);
    for (int k = 0; k < count; ++k) {
      const double r = std::sqrt(uni(rng)), t = uni(rng);  // uniform on the triangle
      centres.push_back((1 - r) * a + r * (1 - t) * b + r * t * c);
    }
  }
  return centres;
}

double SmoothNoise(double x, double y, double cell) {
  const double gx = x / cell, gy = y / cell;
  const double fx = std::floor(gx), fy = std::floor(gy);
  const int64_t i = static_cast<int64_t>(fx), j = static_cast<int64_t>(fy);
  const double tx = Smoothstep(gx - fx), ty = Smoothstep(gy - fy);
  const double top = LatticeValue(i, j) * (1 - tx) + LatticeValue(i + 1, j) * tx;
  const double bottom = LatticeValue(i, j + 1) * (1 - tx) + LatticeValue(i + 1, j + 1) * tx;
  return top * (1 - ty) + bottom * ty;
}

double ConcaveFraction(const DepthImage& image, const ImageGeometry& geometry,
                       const CameraOptions& camera, int px, int py, double radius) {
  const size_t idx = static_cast<size_t>(py) * image.width + px;
  const double z = image.depth[idx];
  if (!(z > 0)) return 0.0;
  const Eigen::Vector3d& x = geometry.point[idx];
  const Eigen::Vector3d& n = geometry.normal[idx];
  const int reach = static_cast<int>(std::ceil(radius * camera.fx / z));
  // At most about 15 x 15 samples of the disc: the fraction, not every pixel, is needed.
  const int step = std::max(1, reach / 7);
  const double cos_front = std::sin(15.0 * M_PI / 180.0);
  int total = 0, facing = 0;
  for (int dy = -reach; dy <= reach; dy += step) {
    const int qy = py + dy;
    if (qy < 0 || qy >= image.height) continue;
    for (int dx = -reach; dx <= reach; dx += step) {
      const int qx = px + dx;
      if (qx < 0 || qx >= image.width || (dx == 0 && dy == 0)) continue;
      const size_t q = static_cast<size_t>(qy) * image.width + qx;
      if (image.triangle[q] < 0) continue;
      const Eigen::Vector3d d = geometry.point[q] - x;
      const double dist = d.norm();
      if (!(dist > 0) || dist > radius) continue;
      ++total;
      if (d.dot(n) > cos_front * dist && geometry.normal[q].dot(-d) > 0) ++facing;
    }
  }
  return total > 0 ? static_cast<double>(facing) / total : 0.0;
}

double EdgeNeighbourDepth(const DepthImage& image, int px, int py, double jump) {
  const double z = image.depth[static_cast<size_t>(py) * image.width + px];
  double best = 0.0, best_gap = jump;
  for (int dy = -1; dy <= 1; ++dy) {
    for (int dx = -1; dx <= 1; ++dx) {
      const int qx = px + dx, qy = py + dy;
      if ((dx == 0 && dy == 0) || qx < 0 || qy < 0 || qx >= image.width || qy >= image.height) {
        continue;
      }
      const double zq = image.depth[static_cast<size_t>(qy) * image.width + qx];
      if (!(zq > 0)) continue;  // nothing behind the silhouette to mix with
      if (std::abs(zq - z) > best_gap) {
        best_gap = std::abs(zq - z);
        best = zq;
      }
    }
  }
  return best;
}

double QuantiseDepth(double z, double fx, double baseline, double step) {
  if (!(z > 0) || !(step > 0)) return z;
  const double fb = fx * baseline;
  const double d = std::max(1.0, std::round(fb / z / step)) * step;
  return fb / d;
}

}  // namespace synth_internal
}  // namespace femreg
