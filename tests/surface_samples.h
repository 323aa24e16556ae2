// Clouds sampled on a mesh's surface, shared by the tests that make their own.
#ifndef FEMREG_TESTS_SURFACE_SAMPLES_H_
#define FEMREG_TESTS_SURFACE_SAMPLES_H_

#include <Eigen/Geometry>
#include <algorithm>
#include <random>
#include <vector>

#include "femreg/mesh.h"
#include "femreg/point_cloud.h"

namespace femreg {
namespace testing_util {

// `points` points uniform by area over the surface triangles of `mesh` at positions x, with
// Gaussian noise of sigma (m) on each coordinate (none at 0), drawn from *rng: per point a
// triangle, two barycentric draws, then the noise.
template <class Rng>
PointCloud SampleSurfaceByArea(const TetMesh& mesh, const Vertices& x, int points, double sigma, Rng* rng) {
  std::uniform_real_distribution<double> uniform(0.0, 1.0);
  std::normal_distribution<double> normal(0.0, sigma > 0 ? sigma : 1.0);
  std::vector<double> cumulative;
  double total = 0.0;
  for (int f = 0; f < mesh.num_surface_triangles(); ++f) {
    const Eigen::Vector3d a = x.row(mesh.surface(f, 0)), b = x.row(mesh.surface(f, 1)), c = x.row(mesh.surface(f, 2));
    cumulative.push_back(total += 0.5 * (b - a).cross(c - a).norm());
  }
  PointCloud cloud;
  cloud.points.resize(points, 3);
  for (int i = 0; i < points; ++i) {
    const auto f = std::min(cumulative.size() - 1,
                            static_cast<size_t>(std::lower_bound(cumulative.begin(), cumulative.end(),
                                                                 uniform(*rng) * total) -
                                                cumulative.begin()));
    double u = uniform(*rng), w = uniform(*rng);
    if (u + w > 1.0) u = 1.0 - u, w = 1.0 - w;
    const Eigen::Vector3d a = x.row(mesh.surface(f, 0)), b = x.row(mesh.surface(f, 1)), c = x.row(mesh.surface(f, 2));
    Eigen::Vector3d p = a + u * (b - a) + w * (c - a);
    if (sigma > 0) p += Eigen::Vector3d(normal(*rng), normal(*rng), normal(*rng));
    cloud.points.row(i) = p.transpose();
  }
  return cloud;
}

}  // namespace testing_util
}  // namespace femreg

#endif  // FEMREG_TESTS_SURFACE_SAMPLES_H_
