// Occluders in the cloud: with a known camera, the cloud points of something in front of the
// model (a hand, a gripper, a tool the segmentation kept). The camera saw them before the
// model along their rays, so the model may hide behind them but is not pulled to them
// (docs/guide/partial-views.md#occluders).
#ifndef FEMREG_REGISTRATION_OCCLUDERS_H_
#define FEMREG_REGISTRATION_OCCLUDERS_H_

#include <functional>
#include <vector>

#include "geometry/nearest.h"
#include "registration/tracker_state.h"

namespace femreg {

struct OccluderCounts {
  int seeds = 0;      // points in front of the rendered model by more than data.occluder_margin
  int occluders = 0;  // the seeds and the points connected to them off the model
  bool whole_view = false;  // most points in front: the object moved, nothing is an occluder
};

// Marks (*occluder)[i] = 1 for the cloud points of an occluder, at the model's shape state.x
// (the frame's start): the model's surface is rendered with a z-buffer from the camera
// (state.options.camera, which must be enabled). Seeds are points whose ray meets the model
// more than data.occluder_margin behind them and that lie farther than that from the
// surface. From the seeds the occluder grows through the cloud (neighbours within three
// point spacings) over points that are off the model: in front of it or beside its
// silhouette, and farther from its surface than the loss scale (or two spacings). When the
// seeds are most of the points in front of the model, the object itself came closer, and
// nothing is marked. `cloud_index` indexes `points`; `spacing` is the cloud's point spacing.
// `seeds` (per point a triangle of `surface` near it, or empty): the distances to the surface
// are walked from there (SurfaceIndex::ClosestSeeded, seed_rings rings).
OccluderCounts MarkOccluders(const TrackerState& state, const SurfaceIndex& surface,
                             const Vertices& points, const PointIndex& cloud_index, double spacing,
                             std::vector<char>* occluder, const std::vector<int>& seeds = {},
                             int seed_rings = 0);

// After the model moved (an outer iteration): the occluder points it now reaches (within the
// loss scale, or two spacings) are released, and so are the points carried from the last
// frame's implausible ones (CarryImplausible), not those this frame found implausible
// (MarkImplausible): a part that lagged behind a fast motion and looked like an occluder has
// caught up. No point is marked anew. Returns the occluders and implausible points left.
OccluderCounts ReleaseReached(const TrackerState& state, const SurfaceIndex& surface,
                             const Vertices& points, double spacing, std::vector<char>* occluder);

// Points the body cannot explain at a plausible strain (data.max_strain_step > 0): the
// elements stretched or compressed from `start` (the frame's start) to state.x by more than
// data.max_strain_step, with an edge whose length changed by more than `spacing` (a sliver's
// strain below that is not evidence), mark the cloud points whose closest point on the meshes' surface at
// state.x is on a triangle touching them and that lay off the model at `start` (farther than
// the loss scale, or two spacings, from its surface); the marks grow through the cloud (neighbours within
// three spacings) over points off the model at `start`. Marked points get 2 in *marks
// (#P; assigned zeros when empty), which ReleaseReached keeps. Returns how many were marked.
// A strained surface vertex that faced the sensor at `start` (`faces`: position and outward
// normal; empty without a view) with no cloud point within that distance of
// where it was, in an object at least half of whose surface vertices facing the sensor still
// have one there, no longer counts as strained: what pulled it is most likely the body's own
// part that a fast motion carried off while the rest stayed, not a hand beside it. A point is
// marked only if its closest triangle touches a vertex that still counts. With outside_only,
// the points that seed the marks must also lie outside the body at `start` (on the outer side
// of its surface): a hand's points cannot be inside the body's material, and the body's own
// are where the start overshot a motion that stopped. Not for a coarse cage around an
// embedded surface, whose inside holds more than the body.
int MarkImplausible(const TrackerState& state, const Vertices& start, const Vertices& points,
                    const PointIndex& cloud_index, double spacing,
                    const std::function<bool(const Eigen::Vector3d&, const Eigen::Vector3d&)>& faces,
                    std::vector<char>* marks, bool outside_only = true);

// The last frame's implausible points, at a frame's start: the hand that pulled them is
// most likely still there, and a frame that lets it pull first must start again without it
// (docs/guide/partial-views.md#implausible-points). The cloud points within the loss scale (or
// two spacings) of a point in `before` that lie off the model at state.x by more than that,
// grown through the cloud over points off the model, get 3 in *marks (#P; assigned zeros when
// empty). ReleaseReached releases them when the model reaches them. Returns how many were marked.
int CarryImplausible(const TrackerState& state, const Vertices& before, const Vertices& points,
                     const PointIndex& cloud_index, double spacing, std::vector<char>* marks);

// The occluder points (marked in `occluder`) that have an unmarked cloud point among their
// nearest within three spacings, where the occluder's growth stopped at the model: an occluder
// that touches the body's points, as a hand that holds it does, and not one that passes in front
// of it. Counts up to `enough` and stops there.
int TouchingOccluderPoints(const Vertices& points, const PointIndex& cloud_index, double spacing,
                           const std::vector<char>& occluder, int enough);

// The points of `points` marked implausible in `marks` (2 or 3), in their order, that are still
// farther from the meshes' surface at state.x than data.max_strain_step mean edges: the frame
// did not reach them, and only a strain beyond that could in the next. Marks nearer (a part
// of the object that lagged and was swept in with the hand's points) are not carried on.
Vertices ImplausiblePoints(const TrackerState& state, const Vertices& points, const std::vector<char>& marks);

}  // namespace femreg

#endif  // FEMREG_REGISTRATION_OCCLUDERS_H_
