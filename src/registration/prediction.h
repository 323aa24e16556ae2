// The frame's starting shape: the last result carried on at constant velocity
// (solver.predict_motion), without the turns the data cannot see.
#ifndef FEMREG_REGISTRATION_PREDICTION_H_
#define FEMREG_REGISTRATION_PREDICTION_H_

#include <Eigen/Core>
#include <vector>

#include "registration/embedded_surface.h"
#include "registration/tracker_state.h"

namespace femreg {

// How much of a turn about each axis shows in the data: for the surface tris (rows of
// vertex indices into x) about the point c, the generalised eigenvalues lambda of
//   M v = lambda N v,  M = sum A g g^T,  g = (p - c) x n,  N = sum A (|r|^2 I - r r^T),  r = p - c,
// over the triangles (area A, unit normal n, centroid p). lambda in [0, 1] is the share of the
// surface's squared motion under a turn about v that is along its normals, the only part a
// point-to-plane fit sees: 0 about a sphere's centre or a cylinder's axis, 0.2 for a cube.
// Eigenvalues ascending, the axes (N-orthonormal) in the columns of *axes. `offset` is added to
// each index: an object's own triangles on the positions of all objects, with no copy.
Eigen::Vector3d TurnVisibility(const Vertices& x, const Eigen::Ref<const Triangles>& tris, const Eigen::Vector3d& c,
                               Eigen::Matrix3d* axes, int offset = 0);

// The part of object o's move from `from` to `to` that is a turn its surface does not show:
// the least-squares rigid velocity (velocity, and the rotation vector w about the mass centre
// of `to`), and w's components along the axes of TurnVisibility at `to`, each scaled by
// 1 - min(1, lambda / kVisibleTurn), in `turn` (rad). Zero when the object has no mass. With
// `data` (may be null), an object's embedded surface is the one whose visibility counts: it is
// what the data see, and a coarse cage may be rounder than its scan.
struct HiddenTurn {
  Eigen::Vector3d centre = Eigen::Vector3d::Zero();
  Eigen::Vector3d velocity = Eigen::Vector3d::Zero();
  Eigen::Vector3d turn = Eigen::Vector3d::Zero();
};
HiddenTurn FindHiddenTurn(const TrackerState& state, int o, const Vertices& from, const Vertices& to,
                          DataSurface* data = nullptr);

// Turns each object that nothing holds back by the hidden turn of its move from `from` to
// *x, about its mass centre at *x, as PredictMotion does with the prediction: each outer
// iteration's move keeps only the turns the data can see (docs/theory/stopping.md#hidden-turns).
// Nothing with fracture live. True when some object was turned.
bool HoldHiddenTurns(const TrackerState& state, const Vertices& from, Vertices* x, DataSurface* data = nullptr);

// The turns of object o at x that its surface shows by less than half of kVisibleTurn
// (TurnVisibility about its mass centre; the embedded surface's with `data`): turns the hold
// above would take back more than half of, which the physical mode's step does not make
// (docs/theory/stopping.md#hidden-turns). One vector c per such turn, for the step's
// constraint sum_v (c x (x_v - centroid)) . d_v = 0: on a rigid move d it holds exactly when
// FindHiddenTurn finds no turn about that axis (c = I^-1 axes^-T e_k, I the vertices'
// unweighted inertia about their centroid). None for an object an anchor holds, or with
// fracture live.
std::vector<Eigen::Vector3d> HiddenTurnAxes(const TrackerState& state, int o, const Vertices& x,
                                            DataSurface* data = nullptr);

// 2 x - x_before, except that for each object that nothing holds (no anchor), the predicted
// turn about an axis of visibility lambda < kVisibleTurn is scaled by lambda / kVisibleTurn:
// a turn the surface does not show is not carried on, since no later data will correct it
// (docs/theory/energy.md#the-prediction).
Vertices PredictMotion(const TrackerState& state, DataSurface* data = nullptr);

// How far the cloud `points` lie from the surface at x: the mean over the points of
// min(d, gate)^2, d a point's distance to the nearest surface vertex (of the data surface's
// subsample when `data` is set, else of the meshes' surfaces). Two starts of a frame on the
// same surface compare by it: the sampling's share of d is the same for both.
double StartMisfit(const TrackerState& state, const Vertices& x, const Vertices& points, double gate,
                   DataSurface* data = nullptr);

// A cube's faces show a fifth of its turns; a faceted sphere, a hundredth.
constexpr double kVisibleTurn = 0.1;

}  // namespace femreg

#endif  // FEMREG_REGISTRATION_PREDICTION_H_
