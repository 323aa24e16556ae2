// The global initial pose (registration.initial_pose auto): on the first frame, an object
// whose given pose explains the cloud badly is posed by a global rigid search of its surface
// against the cloud, wherever the camera sees it.
#ifndef FEMREG_REGISTRATION_GLOBAL_POSE_H_
#define FEMREG_REGISTRATION_GLOBAL_POSE_H_

#include <Eigen/Core>
#include <vector>

#include "femreg/registration.h"
#include "registration/embedded_surface.h"
#include "registration/tracker_state.h"

namespace femreg {

// One rigid pose hypothesis of an object, as the map from the cloud into the frame of the
// object's given pose (q = R p + t), and how badly it explains the cloud (fit, m: the trimmed
// cloud->surface distance plus, with an eye, the trimmed distance from the surface facing it
// to the cloud).
struct PoseHypothesis {
  Eigen::Matrix3d R = Eigen::Matrix3d::Identity();
  Eigen::Vector3d t = Eigen::Vector3d::Zero();
  double fit = 0.0;
};

// What the search found for one object.
struct GlobalPoseResult {
  bool searched = false;  // the given pose explained the cloud badly
  bool moved = false;     // a global pose replaced it
  // A global pose replaced the given one, and another pose rotated more than 20 deg from it
  // explains the cloud about equally well.
  bool ambiguous = false;
  double given_fit = 0.0;                  // m, the given pose's PoseHypothesis::fit
  // Refined (or dropped mid-way, with the fit they had), best first (searched only).
  std::vector<PoseHypothesis> hypotheses;
};

// The search for object `object` of *state against `points` (its cloud points, #P by 3, in
// the scene frame; eye: where the sensor was, or null when unknown): FPFH features of the
// surface and of the cloud, a RANSAC over oriented point pairs that keeps the distinct poses
// with the most inliers, each hypothesis (and the given pose, and the best one's half-turns
// about the body's principal axes) refined by a trimmed point-to-plane ICP and scored as
// PoseHypothesis::fit says (a point whose closest surface point faces away from the eye counts
// as unexplained). Moves the object's vertices in state->x when a global pose wins. The same
// result on any thread count and every run (the draws come from a fixed-seed generator). With a data
// surface (updated at state->x) that embeds a surface in the object, the pose is that of its
// embedded surface, the one the cloud shows; the mesh moves with it.
GlobalPoseResult GlobalPose(const Vertices& points, const Eigen::Vector3d* eye, int object,
                            TrackerState* state, const DataSurface* surface = nullptr);

// registration.initial_pose auto on the first frame: GlobalPose for every object that has no
// anchor and whose cloud points are known (the only object, or a labelled one); fills
// summary->initial_pose and pose_ambiguous.
void ChooseInitialPose(const PointCloud& cloud, TrackerState* state, FrameSummary* summary,
                       DataSurface* surface = nullptr);

}  // namespace femreg

#endif  // FEMREG_REGISTRATION_GLOBAL_POSE_H_
