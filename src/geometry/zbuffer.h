// A pinhole camera's z-buffer of triangle surfaces: which surface and triangle each pixel sees
// first, and at what depth. The virtual depth sensor renders with it (femreg/synth.h), and the
// registration asks it where the model is along a cloud point's ray (registration/occluders.h).
#ifndef FEMREG_GEOMETRY_ZBUFFER_H_
#define FEMREG_GEOMETRY_ZBUFFER_H_

#include <Eigen/Core>
#include <vector>

#include "femreg/mesh.h"

namespace femreg {

// Camera frame: x right, y down, z forward (OpenCV); p_camera = rotation (p - position).
struct PinholeCamera {
  Eigen::Matrix3d rotation = Eigen::Matrix3d::Identity();
  Eigen::Vector3d position = Eigen::Vector3d::Zero();
  double fx = 1.0, fy = 1.0, cx = 0.0, cy = 0.0;  // pixels; pixel centres at integers
  int width = 0, height = 0;
  double near = 0.0;  // m: closer points are not projected
  // Pixel coordinates (u, v) and depth z along the axis of p; false when z <= near.
  bool Project(const Eigen::Vector3d& p, double* u, double* v, double* z) const;
};

struct ZBuffer {
  int width = 0, height = 0;
  std::vector<double> depth;   // row-major; +inf where nothing was hit
  std::vector<int> surface;    // the surface id hit, -1 for none
  std::vector<int> triangle;   // the triangle hit, -1 for none
  void Reset(int w, int h);
};

// Rasterizes the triangles (rows of positions) into *zbuffer (exact, perspective-correct
// depth at the pixel centres; a triangle with a corner at or before `near` is skipped), keeping
// the nearest hit per pixel and tagging it with surface_id.
void Rasterize(const PinholeCamera& camera, const Vertices& positions, const Triangles& triangles,
               int surface_id, ZBuffer* zbuffer);

}  // namespace femreg

#endif  // FEMREG_GEOMETRY_ZBUFFER_H_
