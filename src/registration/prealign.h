// The rigid pre-alignment of a frame (solver.rigid_prealign): a fast rigid jump brought
// within reach of the non-rigid solve.
#ifndef FEMREG_REGISTRATION_PREALIGN_H_
#define FEMREG_REGISTRATION_PREALIGN_H_

#include <Eigen/Core>
#include <vector>

#include "femreg/registration.h"
#include "registration/embedded_surface.h"
#include "registration/tracker_state.h"

namespace femreg {

// Best rigid transform (R, t) with R a_i + t ~ b_i, by the SVD of the cross-covariance.
void Kabsch(const std::vector<Eigen::Vector3d>& a, const std::vector<Eigen::Vector3d>& b,
            Eigen::Matrix3d* R, Eigen::Vector3d* t);

// Rigid ICP per object on state->x, from the translation that matches the centroid of the
// cloud with that of the surface facing the camera, then cloud->surface pairs trimmed to
// the closest 80%. Kept only if it brings the surface closer to the cloud. An object with an
// embedded surface in `surface` is fitted by that surface (the mesh moves with it).
void RigidPrealign(const PointCloud& cloud, TrackerState* state, DataSurface* surface = nullptr);

// After a break (FractureOptions::piece_prealign): rigid ICP per piece of each object in more
// than one piece, from where the piece is. Each cloud point (within data.max_distance) goes to
// the piece whose surface is nearest it, pairs trimmed to the closest 80%, the association
// renewed every iteration. A piece with hard anchors is left to them. A piece's move is kept
// only if it brings its surface closer to its points.
void PiecePrealign(const PointCloud& cloud, TrackerState* state);

}  // namespace femreg

#endif  // FEMREG_REGISTRATION_PREALIGN_H_
