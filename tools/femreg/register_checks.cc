// femreg register's checks beside the tracking (register_checks.h).
#include "register_checks.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <string>
#include <vector>

namespace femreg {
namespace cli {
namespace register_checks {

Status CheckRegisterKeys(const Scene& scene) {
  const std::string file = scene.path.empty() ? "scene" : scene.path;
  for (size_t i = 0; i < scene.boundary_conditions.size(); ++i) {
    const BoundaryConditionSpec& b = scene.boundary_conditions[i];
    if (b.type == BoundaryConditionSpec::Type::kDisplacement) {
      return Status::Error(b.selection.where + ": boundary[" + std::to_string(i) +
                           "].displacement is not used by register (clamps are held as hard "
                           "anchors); for a support that moves, use anchors with translations");
    }
  }
  return Status::Ok();
}

double MeshExtent(const Tracker& tracker) {
  Eigen::Vector3d lo = Eigen::Vector3d::Constant(1e300), hi = -lo;
  for (int i = 0; i < tracker.num_objects(); ++i) {
    lo = lo.cwiseMin(tracker.mesh(i).rest.colwise().minCoeff().transpose());
    hi = hi.cwiseMax(tracker.mesh(i).rest.colwise().maxCoeff().transpose());
  }
  return (hi - lo).norm();
}

double MeshMeanEdge(const Tracker& tracker) {
  double sum = 0.0;
  long count = 0;
  for (int i = 0; i < tracker.num_objects(); ++i) {
    const TetMesh& m = tracker.mesh(i);
    for (int f = 0; f < m.num_surface_triangles(); ++f) {
      for (int k = 0; k < 3; ++k) {
        sum += (m.rest.row(m.surface(f, k)) - m.rest.row(m.surface(f, (k + 1) % 3))).norm();
        ++count;
      }
    }
  }
  return count > 0 ? sum / static_cast<double>(count) : 0.0;
}

double MedianSpacing(const PointCloud& cloud) {
  const int n = cloud.size();
  if (n < 2) return 0.0;
  // Up to 200 points spread over the cloud, each against all: a few ms on a depth image.
  const int samples = std::min(n, 200);
  std::vector<double> nearest;
  for (int s = 0; s < samples; ++s) {
    const int i = static_cast<int>(static_cast<long>(s) * n / samples);
    double best = std::numeric_limits<double>::infinity();
    for (int j = 0; j < n; ++j) {
      const double d = (cloud.points.row(j) - cloud.points.row(i)).squaredNorm();
      if (j != i && d > 0.0 && d < best) best = d;
    }
    if (std::isfinite(best)) nearest.push_back(std::sqrt(best));
  }
  if (nearest.empty()) return 0.0;
  std::nth_element(nearest.begin(), nearest.begin() + nearest.size() / 2, nearest.end());
  return nearest[nearest.size() / 2];
}

void WarnUnits(const std::string& file, const PointCloud& used, const Tracker& tracker) {
  const double mesh_extent = MeshExtent(tracker);
  const double extent = (used.points.colwise().maxCoeff() - used.points.colwise().minCoeff()).norm();
  if (!(mesh_extent > 0) || !(extent > 0)) return;
  const double ratio = extent / mesh_extent;
  if (ratio <= 10.0 && ratio >= 0.1) return;
  // A cloud much larger than the meshes is either in other units (every length in it larger,
  // the spacing of its points too) or holds more than the objects (a room around them, its
  // points as close as the meshes' edges). The spacing tells which.
  const double spacing = MedianSpacing(used), edge = MeshMeanEdge(tracker);
  const bool units_fit = ratio > 10.0 && spacing > 0.0 && edge > 0.0 && spacing < 10.0 * edge;
  std::fprintf(stderr,
               "femreg register: %s: the first cloud (%s) spans %.4g (bounding box diagonal "
               "of the %d points used, after masks and preprocessing) and the meshes %.4g m: "
               "%.3g times %s; its points are %.3g apart (median nearest neighbour) against "
               "the meshes' edges of %.3g. ",
               units_fit ? "note" : "warning", file.c_str(), extent, used.size(), mesh_extent,
               ratio > 1 ? ratio : 1.0 / ratio, ratio > 1 ? "larger" : "smaller", spacing, edge);
  if (units_fit) {
    std::fprintf(stderr,
                 "The units look right (the points are as close as the edges): the cloud holds "
                 "more than the objects. Mask it (--mask-dir, registration.preprocess.mask_dir) "
                 "or crop it (preprocess.crop) so that the rest does not pull the meshes.\n");
  } else {
    std::fprintf(stderr,
                 "Different units? Scale the clouds with registration.preprocess.scale (e.g. "
                 "0.001 for mm) or the meshes with objects[].scale.%s\n",
                 ratio > 1 ? " If the cloud holds more than the objects, mask it (--mask-dir, "
                             "registration.preprocess.mask_dir) or crop it (preprocess.crop)."
                           : "");
  }
}

}  // namespace register_checks
}  // namespace cli
}  // namespace femreg
