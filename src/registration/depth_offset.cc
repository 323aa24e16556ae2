#include "registration/depth_offset.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <vector>

namespace femreg {
namespace {
constexpr int kMinPoints = 20;
constexpr double kMinSine = 0.2;  // sin(12 deg): nearer grazing, a depth error barely moves off the plane
constexpr double kMaxTurnDeg = 2.0;
constexpr double kSignificance = 3.0;  // standard errors

double Median(std::vector<double>* v) {
  const size_t mid = v->size() / 2;
  std::nth_element(v->begin(), v->begin() + static_cast<std::ptrdiff_t>(mid), v->end());
  return (*v)[mid];
}
}  // namespace

double PlaneDepthOffset(const CameraOptions& camera, const Eigen::Vector3d& normal, double offset,
                        const Eigen::Matrix<double, Eigen::Dynamic, 3>& points,
                        double* standard_error) {
  const double nan = std::numeric_limits<double>::quiet_NaN();
  if (standard_error != nullptr) *standard_error = nan;
  const Eigen::Matrix3d r = CameraRotation(camera);
  const Eigen::Vector3d axis = r.row(2).transpose();  // the optical axis: depth is along it
  std::vector<double> offsets;
  offsets.reserve(static_cast<size_t>(points.rows()));
  for (Eigen::Index i = 0; i < points.rows(); ++i) {
    const Eigen::Vector3d p = points.row(i).transpose();
    const Eigen::Vector3d d = p - camera.position;
    const double z = d.dot(axis);
    const double along = normal.dot(d);
    if (!(z > 0) || !(std::abs(along) > kMinSine * d.norm())) continue;
    offsets.push_back((normal.dot(p) - offset) * z / along);
  }
  if (static_cast<int>(offsets.size()) < kMinPoints) return nan;
  const double median = Median(&offsets);
  if (standard_error != nullptr) {
    std::vector<double> deviation(offsets.size());
    for (size_t i = 0; i < offsets.size(); ++i) deviation[i] = std::abs(offsets[i] - median);
    // 1.4826 MAD: a normal spread's sigma; a median's error is 1.2533 sigma / sqrt(n).
    *standard_error = 1.2533 * 1.4826 * Median(&deviation) / std::sqrt(static_cast<double>(offsets.size()));
  }
  return median;
}

void ShiftDepth(const CameraOptions& camera, double delta, PointCloud* cloud) {
  const Eigen::Vector3d axis = CameraRotation(camera).row(2).transpose();
  for (Eigen::Index i = 0; i < cloud->points.rows(); ++i) {
    const Eigen::Vector3d d = cloud->points.row(i).transpose() - camera.position;
    const double z = d.dot(axis);
    if (!(z > 0)) continue;
    cloud->points.row(i) = (camera.position + d * ((z - delta) / z)).transpose();
  }
}

double DepthOffset::Correct(const CameraOptions& camera, double tolerance, const RemovedPlane& plane,
                            PointCloud* cloud) {
  if (plane.points.rows() == 0 || !(plane.normal.norm() > 0)) return 0.0;
  if (!has_reference_) {
    // Its own plane: the first frame's offset against it is its points' noise about the fit.
    has_reference_ = true;
    normal_ = plane.normal;
    offset_ = plane.offset;
  }
  const double cos_turn = std::abs(plane.normal.dot(normal_));
  if (cos_turn < std::cos(kMaxTurnDeg * M_PI / 180.0)) return 0.0;
  double error = 0.0;
  const double measured = PlaneDepthOffset(camera, normal_, offset_, plane.points, &error);
  if (!std::isfinite(measured)) return 0.0;
  if (count_ > 0 && std::abs(measured - sum_ / count_) > tolerance) return 0.0;
  sum_ += measured;
  ++count_;
  const double correction = measured - sum_ / count_;
  if (!(std::abs(correction) > kSignificance * error)) return 0.0;
  ShiftDepth(camera, correction, cloud);
  return correction;
}

}  // namespace femreg
