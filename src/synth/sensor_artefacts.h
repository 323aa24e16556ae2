// The artefacts of real depth sensors that DepthSensor::Sample applies (femreg/synth.h,
// SensorArtefacts): the per-pixel tests and depth changes, each a pure function of the
// rendered image, the surfaces and the draws it is given.
#ifndef FEMREG_SYNTH_SENSOR_ARTEFACTS_H_
#define FEMREG_SYNTH_SENSOR_ARTEFACTS_H_

#include <Eigen/Core>
#include <cstdint>
#include <vector>

#include "femreg/synth.h"

namespace femreg {
namespace synth_internal {

// The image's seen points and their unit normals (turned towards the camera), in the
// world frame; zero where nothing was hit.
struct ImageGeometry {
  std::vector<Eigen::Vector3d> point, normal;
};
ImageGeometry ComputeImageGeometry(const DepthImage& image,
                                   const std::vector<RenderSurface>& surfaces,
                                   const CameraOptions& camera, const Eigen::Matrix3d& rotation);

// Dark discs on one surface: their centres at this frame (points on the surface drawn per
// triangle index, so they move with it), as many as cover `fraction` of its area with discs
// of `radius` (before overlaps).
std::vector<Eigen::Vector3d> DarkCentres(const Vertices& positions, const Triangles& triangles,
                                         double fraction, double radius, uint64_t salt);

// A smooth noise field over the image, values in [0, 1): bilinear between hashed lattice
// values `cell` pixels apart (the grazing holes' blobs).
double SmoothNoise(double x, double y, double cell);

// The fraction of the seen points within `radius` of pixel (px, py)'s point that lie in
// front of its tangent plane (by more than 15 degrees) and face it: 0 on a plane or a convex
// surface, towards 1 deep in a concave corner (the multipath bias's weight).
double ConcaveFraction(const DepthImage& image, const ImageGeometry& geometry,
                       const CameraOptions& camera, int px, int py, double radius);

// The depth of the 8-neighbour of (px, py) that differs most from its own, if it differs
// by more than `jump` (m); 0 when none does (not at a depth discontinuity).
double EdgeNeighbourDepth(const DepthImage& image, int px, int py, double jump);

// Depth z quantised in disparity: d = fx * baseline / z rounded to a multiple of `step` px.
double QuantiseDepth(double z, double fx, double baseline, double step);

}  // namespace synth_internal
}  // namespace femreg

#endif  // FEMREG_SYNTH_SENSOR_ARTEFACTS_H_
