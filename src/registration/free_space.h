// Free space: the depth the sensor observed along its rays, from the frame's cloud
// (docs/theory/data-terms.md#free-space). A ray from the sensor to an observed point passed
// through empty space, so no part of the model may be in front of that point: a surface
// vertex nearer to the sensor than the observed depth at its pixel, by more than
// registration.free_space.tolerance, is held back by the energy's free-space penalty
// (energy/free_space.h). Where nothing was observed (outside the cloud's image, a pixel no
// point covers) the sensor says nothing, and nothing is held.
#ifndef FEMREG_REGISTRATION_FREE_SPACE_H_
#define FEMREG_REGISTRATION_FREE_SPACE_H_

#include <Eigen/Core>
#include <vector>

#include "femreg/mesh.h"

namespace femreg {

class ObservedDepth {
 public:
  // The points seen from a sensor at `eye` (perspective) or, when `perspective` is false,
  // along the unit direction -`eye` (`eye` points towards the sensor: an orthographic view),
  // with optical axis `axis` (unit, away from the sensor; ignored for the orthographic view,
  // whose axis is -eye). `spacing`: the cloud's point spacing (m), which sets the pixel
  // pitch at the points' median depth. Each point covers its pixel and the 8 around it with
  // its depth, the nearest depth winning: between sparse points, and across a depth
  // discontinuity, the depth that is kept is the one nearer to the sensor, so that the
  // space said to be free is never more than what was seen through.
  // `also` (optional): more points seen (a table the preprocessing removed), written the same
  // way and widening the image, while the pitch stays the one `points` set.
  void Build(const Vertices& points, bool perspective, const Eigen::Vector3d& eye,
             const Eigen::Vector3d& axis, double spacing, const Vertices* also = nullptr);
  void Clear() { depth_.clear(); width_ = height_ = 0; }
  bool empty() const { return depth_.empty(); }
  // For position p: the unit ray n from the sensor through p, a point e on the ray's line
  // (the sensor's position, or the origin for the orthographic view) and the observed depth
  // along n at p's pixel, n . (q - e) for the observed point q. False when p's pixel has no
  // observation, lies outside the image, or p is behind the sensor.
  bool Observed(const Eigen::Vector3d& p, Eigen::Vector3d* ray, Eigen::Vector3d* origin,
                double* depth) const;
  // The shortest sideways way out of the seen-through space for p: the distance (m, at p's
  // depth) to the nearest pixel whose observation allows p's depth (observed depth minus
  // `tolerance` not nearer than p) or that has none; +inf if there is none within `limit` (m).
  // A surface off sideways from where it was seen (lagging behind a motion across the rays) is
  // in front of what was seen beyond its edge, and its way out is across the rays, not along
  // them.
  double SidewaysExit(const Eigen::Vector3d& p, double tolerance, double limit) const;
  int width() const { return width_; }
  int height() const { return height_; }

 private:
  // Image coordinates (pixels) and depth along the ray of p; false behind the sensor.
  bool Project(const Eigen::Vector3d& p, double* u, double* v, double* depth) const;
  bool perspective_ = true;
  Eigen::Matrix3d rotation_ = Eigen::Matrix3d::Identity();  // rows: image x, image y, axis
  Eigen::Vector3d eye_ = Eigen::Vector3d::Zero();
  double pitch_ = 1.0;  // rad (perspective) or m (orthographic) per pixel
  double u0_ = 0.0, v0_ = 0.0;
  int width_ = 0, height_ = 0;
  std::vector<double> depth_;  // row-major; +inf: no observation
};

}  // namespace femreg

#endif  // FEMREG_REGISTRATION_FREE_SPACE_H_
