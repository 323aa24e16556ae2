// How far a frame's result can be trusted (FrameSummary::confidence; docs/guide/tracking-loss.md):
// the product of four scores in [0, 1], each from what the frame has, no ground truth:
//   fit       the share of the cloud's points (occluders left out) within `tolerance` of the
//             model's surface: the points the result explains;
//   coverage  the share of the surface vertices facing the sensor that have a cloud point
//             within `tolerance`, against what the sequence's trusted frames reach
//             (state.coverage_reference; a partial view covers little of what faces the
//             sensor in every frame, a lost object nothing): the result is where the cloud is;
//   residual  the rms distance from the surface of the better-fitting half of those points
//             (by weight), against twice what the trusted frames reach
//             (state.residual_reference): a fit pulled by what is not the object misses its
//             own points too, while junk around a right fit fills only the worse half;
//   strain    1 / (1 + s^4), s the 95th percentile over the elements of the largest
//             principal stretch's distance from 1 (infinite if inverted): a shape no
//             material takes;
//   volume    min(1, 0.02 / c), c the largest relative change over the objects of the
//             volume against what the trusted frames keep (state.volume_reference): junk
//             all round a fit pulls its surface outwards in one frame, which no element's
//             strain singles out, while an object squeezed or stretched gets there slowly;
//   pairs     min(1, (m / 0.6 m_ref)^2), m the model->cloud pairs (the surface that faces the
//             sensor and has a cloud point that pairs back), m_ref what the trusted frames
//             keep (state.pairs_reference): a model sat on part of another object's cloud,
//             or on the half of its own that is still in view, has points near most of it
//             (the coverage) but pairs little of it.
// The fit leaves out the points gated by data.max_distance: another object's, or the
// background's; where the object went missing, the coverage says so.
#ifndef FEMREG_REGISTRATION_CONFIDENCE_H_
#define FEMREG_REGISTRATION_CONFIDENCE_H_

#include <Eigen/Core>
#include <cstdint>
#include <functional>
#include <vector>

#include "femreg/registration.h"
#include "registration/correspondences.h"
#include "registration/embedded_surface.h"
#include "registration/tracker_state.h"

namespace femreg {

// The largest principal stretch's distance from 1 of the deformation gradient F (infinite
// when F is inverted or flat).
double StretchDeviation(const Eigen::Matrix3d& F);
// The value at rank min(n - 1, floor(share n)) of StretchDeviation(F(e)) over e = 0 .. n - 1 in
// ascending order: the same number as sorting them all, with the eigenvalues found only for
// the elements that bounds cannot place below it. On `threads` (0: all), the same on any count.
double StretchDeviationQuantile(int64_t n, double share, const std::function<Eigen::Matrix3d(int64_t)>& F,
                                int threads = 0);

// The scores of state.x against the frame's cloud: `pairs` are the last outer iteration's
// (their cloud->model pairs stand for the points they were made from), and state.residuals
// hold each surface vertex's distance to the nearest cloud point (UpdateOutputs). With a data
// surface, the pairs are on it, and its fit and coverage are that surface's (its facing
// subsample vertices with a point of fc.index within the tolerance).
// `rings`, if not null, are the rings of the surface the coverage is on (the data surface's,
// else state.surface's): the normals are then found over the covered vertices' rings only.
FrameConfidence MeasureConfidence(const TrackerState& state, const FrameCloud& fc,
                                  const std::vector<DataPair>& pairs, double tolerance,
                                  const DataSurface* surface = nullptr, const SurfaceRings* rings = nullptr);
// Takes a trusted frame's coverage, residual, model->cloud pairs and object volumes into
// the references (running means); the first solved frame sets them.
void UpdateReferences(const FrameConfidence& confidence, const std::vector<DataPair>& pairs,
                      TrackerState* state);
// Per object, its volume at state.objects' mesh.x over its rest volume.
std::vector<double> VolumeRatios(const TrackerState& state);

}  // namespace femreg

#endif  // FEMREG_REGISTRATION_CONFIDENCE_H_
