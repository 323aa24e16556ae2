// The global pose search's verifier (registration/global_pose.cc): scores rigid pose
// hypotheses by how well they explain the cloud against the object's surface in its given
// pose, and refines them by a trimmed point-to-plane ICP.
#ifndef FEMREG_REGISTRATION_POSE_VERIFIER_H_
#define FEMREG_REGISTRATION_POSE_VERIFIER_H_

#include <Eigen/Core>
#include <limits>
#include <memory>
#include <vector>

#include "femreg/mesh.h"
#include "geometry/nearest.h"
#include "registration/global_pose.h"

namespace pcl {
template <typename PointT>
class PointCloud;
struct PointNormal;
}  // namespace pcl

namespace femreg {

class PoseVerifier {
 public:
  // y, tris: the object's surface in its given pose; points: the cloud (at most a few
  // thousand of them scored); eye: the sensor's position, if known; voxel: the search's
  // sampling voxel (m), which scales the penalty of a point explained by the far side and
  // ICP's stop.
  PoseVerifier(const Vertices& y, const Triangles& tris, const Vertices& points,
               const Eigen::Vector3d* eye, double voxel);

  // The trimmed mean distance of the cloud, mapped by h, to the surface (m).
  double Fit(const PoseHypothesis& h) const;
  // With an eye: the surface samples (model, in the given pose) that free space is checked
  // at.
  void SetSurfaceSamples(const pcl::PointCloud<pcl::PointNormal>& model);
  // With surface samples, the trimmed mean distance from the surface facing the eye to the
  // cloud (the closest 70 %: self-occlusion hides some of it): how well the cloud covers what
  // the camera should see of the body in pose h (m). 0 without samples.
  double Coverage(const PoseHypothesis& h) const;
  // Fit plus Coverage: a pose that puts the view on the wrong part of a smooth body explains
  // the cloud, but not where nothing was seen.
  double Score(const PoseHypothesis& h) const { return Fit(h) + Coverage(h); }
  // Trimmed point-to-plane ICP from h (it slides along flat parts, where point-to-point
  // crawls), at most max_iterations; h->fit set. True if it stopped on its own (settled, or
  // nothing to refine with) within them.
  bool Refine(PoseHypothesis* h, int max_iterations) const;
  // Refines every hypothesis of *batch (on up to `threads`), in rounds; one still moving whose
  // fit is far worse than the best so far (of the batch, and best_seen: an earlier batch's) is
  // dropped after a round, with the fit it has. The same on any number of threads.
  void RefineAll(std::vector<PoseHypothesis>* batch, int threads,
                 double best_seen = std::numeric_limits<double>::infinity()) const;

 private:
  // The kept (trimmed) pairs: the mapped cloud points, their closest surface points and those
  // points' triangle normals. A point whose closest surface point faces away from the eye
  // counts at least `penalty_` away (a pose that explains a view by the far side of the
  // object) and pairs with nothing.
  double Pairs(const PoseHypothesis& h, std::vector<Eigen::Vector3d>* a,
               std::vector<Eigen::Vector3d>* b, std::vector<Eigen::Vector3d>* n) const;

  const Vertices& y_;
  const Triangles& tris_;
  SurfaceIndex index_;
  Eigen::MatrixXd face_normals_;
  std::vector<Eigen::Vector3d> points_;  // the scored cloud
  Vertices all_points_;                  // the whole cloud, with an eye
  std::vector<Eigen::Vector3d> samples_, sample_normals_;
  std::unique_ptr<PointIndex> cloud_index_;
  bool has_eye_;
  Eigen::Vector3d eye_ = Eigen::Vector3d::Zero();
  double penalty_;
  double settled_;     // an ICP step that moves no point more than this ends Refine
  double drop_floor_;  // RefineAll's best fit at least this (m)
};

}  // namespace femreg

#endif  // FEMREG_REGISTRATION_POSE_VERIFIER_H_
