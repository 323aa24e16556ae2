// A depth offset common to all the pixels of a frame (a sensor's temporal flicker or drift),
// measured on a static plane and taken off (docs/guide/depth-images.md#depth-offset).
#ifndef FEMREG_REGISTRATION_DEPTH_OFFSET_H_
#define FEMREG_REGISTRATION_DEPTH_OFFSET_H_

#include "femreg/point_cloud.h"
#include "femreg/registration.h"

namespace femreg {

// How far the points of a plane lie beyond the plane normal . x = offset along the rays of
// `camera`, in depth (m): the median over the points of (normal . p - offset) / (normal . r),
// r = the ray through p scaled to unit depth. Points seen within 12 deg of grazing the plane
// do not count. NaN when fewer than 20 points count; *standard_error (when given) is the
// median's, from the points' spread about it.
double PlaneDepthOffset(const CameraOptions& camera, const Eigen::Vector3d& normal, double offset,
                        const Eigen::Matrix<double, Eigen::Dynamic, 3>& points,
                        double* standard_error = nullptr);

// Moves every point along its camera ray by -delta in depth (points behind the camera stay).
void ShiftDepth(const CameraOptions& camera, double delta, PointCloud* cloud);

// The correction over a sequence. The first plane is the reference; each later frame's plane
// is measured against it (PlaneDepthOffset). The plane does not move, so the mean of those
// offsets over the frames so far is the plane's own place and a frame's offset from that mean
// is the sensor's: it is taken off the frame's points when it exceeds three standard errors
// (on clean data a correction within the noise would only add noise). A frame whose plane
// turned by more than 2 deg or lies more than `tolerance` from the mean is another plane
// or a moved one, not flicker: it is left as it is and not counted.
class DepthOffset {
 public:
  // Returns the offset taken off this frame's points (m; 0: none).
  double Correct(const CameraOptions& camera, double tolerance, const RemovedPlane& plane,
                 PointCloud* cloud);

 private:
  bool has_reference_ = false;
  Eigen::Vector3d normal_ = Eigen::Vector3d::Zero();
  double offset_ = 0.0;
  double sum_ = 0.0;  // of the counted frames' offsets against the reference
  int count_ = 0;
};

}  // namespace femreg

#endif  // FEMREG_REGISTRATION_DEPTH_OFFSET_H_
