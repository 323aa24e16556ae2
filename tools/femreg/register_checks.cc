// femreg register's checks beside the tracking (register_checks.h).
#include "register_checks.h"

#include <cstdio>
#include <string>

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

void WarnUnits(const std::string& file, const PointCloud& used, double mesh_extent) {
  const double extent = (used.points.colwise().maxCoeff() - used.points.colwise().minCoeff()).norm();
  if (!(mesh_extent > 0) || !(extent > 0)) return;
  const double ratio = extent / mesh_extent;
  if (ratio <= 10.0 && ratio >= 0.1) return;
  std::fprintf(stderr,
               "femreg register: warning: the first cloud (%s) spans %.4g (bounding box diagonal "
               "of the %d points used, after masks and preprocessing) and the meshes %.4g m: %.3g "
               "times %s. Different units? Scale the clouds with registration.preprocess.scale "
               "(e.g. 0.001 for mm) or the meshes with objects[].scale.%s\n",
               file.c_str(), extent, used.size(), mesh_extent, ratio > 1 ? ratio : 1.0 / ratio,
               ratio > 1 ? "larger" : "smaller",
               ratio > 1 ? " If the cloud holds more than the objects, mask it (--mask-dir, "
                           "registration.preprocess.mask_dir) or crop it (preprocess.crop)."
                         : "");
}

}  // namespace register_checks
}  // namespace cli
}  // namespace femreg
