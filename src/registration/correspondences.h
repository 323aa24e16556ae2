// Data correspondences of one outer iteration: model->cloud (each surface vertex to its
// nearest cloud point) and cloud->model (each cloud point to its closest point on the
// surface triangles), gated by distance, optionally only for vertices facing the camera,
// with labelled clouds split by object. Also the per-vertex outputs of a frame and the
// fracture's evidence from the data (FractureOptions::data_gap).
#ifndef FEMREG_REGISTRATION_CORRESPONDENCES_H_
#define FEMREG_REGISTRATION_CORRESPONDENCES_H_

#include <Eigen/Core>
#include <functional>
#include <limits>
#include <memory>
#include <string>
#include <vector>

#include "femreg/registration.h"
#include "geometry/nearest.h"
#include "registration/free_space.h"
#include "registration/occluders.h"
#include "registration/tracker_state.h"

namespace femreg {

// A point on the model tied to a cloud point. Model->cloud pairs have one vertex;
// cloud->model pairs three (a surface triangle) with barycentric weights.
struct DataPair {
  int num_vertices = 1;
  int vertices[3] = {0, 0, 0};  // global indices
  Eigen::Vector3d barycentric = Eigen::Vector3d(1, 0, 0);
  Eigen::Vector3d target = Eigen::Vector3d::Zero();  // the cloud point
  Eigen::Vector3d normal = Eigen::Vector3d::Zero();  // unit for point-to-plane; zero: point-to-point
  double weight = 1.0;  // multiplies weights.data: a thinned cloud's points behind it, scaled (SubsampleCloud)
  Eigen::Vector3d Point(const Vertices& x) const;    // the model point at x
};

struct PairCounts {
  int model_to_cloud = 0, cloud_to_model = 0;  // kept
  int rejected = 0;                            // gated out by data.max_distance
  int trimmed = 0;   // model->cloud: beyond the reciprocity trim, or facing away
  int covered = 0;   // surface vertices with a cloud point within the trim (the coverage)
  int occluded = 0;  // cloud points of an occluder (FrameCloud::occluder), paired with nothing
  int crack = 0;     // pairs dropped at the crack of an object in pieces (FractureState::crack)
};

// One frame's cloud, prepared once per frame: scaled and transformed, preprocessed,
// subsampled, its k-d tree, its spacing and how visibility is decided.
struct FrameCloud {
  enum class View { kNone, kCamera, kViewpoint, kDirection };
  PointCloud cloud;
  Eigen::VectorXd weights;  // #P: SubsampleCloud's weights (all 1 unless subsampled)
  std::unique_ptr<PointIndex> index;
  double spacing = 0.0;     // m: median distance from a point to its nearest other point
  // m: the reciprocity trim; inf = reciprocity off (data.reciprocity 0, or fracture on), also
  // its one-ring test (FindPairs).
  double trim = std::numeric_limits<double>::infinity();
  View view = View::kNone;
  // Cloud->model pairs only with surface facing the sensor (a large motion's frame;
  // docs/theory/stopping.md#large-motions). No effect without a view or with labels.
  bool facing_only = false;
  // > 0: the warm starts FindPairs is given are SubsampleStarts, not the last outer
  // iteration's hits: each walk may go this many rings, and one that has not settled by then
  // is searched in full.
  int seeded_rings = 0;
  // An embedded surface's walk starts at the frame's start shape: per cloud point a triangle
  // around the nearest subsample vertex (SubsampleStarts), or empty. The occluders' queries
  // walk from them (at most kSeedRings rings, else searched in full), as the first outer
  // iteration's do, and no k-d tree of every surface vertex is built for them.
  std::vector<int> seeds;
  static constexpr int kSeedRings = 16;
  // Surface vertices facing away from the sensor are not searched for a nearest cloud point
  // (model->cloud): they pair with none (unless held), and an embedded surface's subsample
  // need not say how near the cloud they are. They count as trimmed, not covered nor rejected.
  bool skip_facing_away = false;
  // kCamera, kViewpoint: the sensor's position; kDirection: the unit direction towards it.
  Eigen::Vector3d eye = Eigen::Vector3d::Zero();
  // #P, or empty: the points of an occluder (registration/occluders.h), which pull nothing
  // and are no vertex's nearest point to pull to.
  std::vector<char> occluder;
  OccluderCounts occluders;
  // The depth the sensor observed along its rays (registration.free_space): empty without a
  // view, or with free space off.
  ObservedDepth observed;
  // The points preprocess.plane removed (the table): not data, but seen, so the space in
  // front of them is free too.
  Vertices plane_points;
  // The depth of the occluders' points (occluder == 1) along the camera's rays: empty without
  // them (BuildOccluderDepth).
  ObservedDepth occluder_depth;
  bool Occluder(int i) const { return !occluder.empty() && occluder[static_cast<size_t>(i)]; }
  // Whether p lies behind an occluder's point along its ray by more than `tolerance`: the
  // camera did not see it there.
  bool BehindOccluder(const Eigen::Vector3d& p, double tolerance) const {
    Eigen::Vector3d ray, origin;
    double depth = 0.0;
    return occluder_depth.Observed(p, &ray, &origin, &depth) && (p - origin).norm() > depth + tolerance;
  }

  // Whether a surface point p with outward normal n faces the sensor.
  bool Faces(const Eigen::Vector3d& p, const Eigen::Vector3d& n) const { return Faces(view, eye, p, n); }
  static bool Faces(View view, const Eigen::Vector3d& eye, const Eigen::Vector3d& p, const Eigen::Vector3d& n) {
    switch (view) {
      case View::kNone:
        return true;
      case View::kDirection:
        return n.dot(eye) > 0.0;
      default:
        return n.dot(eye - p) > 0.0;
    }
  }
  // Faces as a function (MarkImplausible's), holding a copy of the view; empty without one,
  // where no vertex can be said to face the sensor.
  std::function<bool(const Eigen::Vector3d&, const Eigen::Vector3d&)> FacesFunction() const;
  std::string Describe() const;  // "camera", "viewpoint (x, y, z)", "direction (x, y, z)", "none"
};

// preprocess.scale and the rigid preprocess.transform applied to the points, normals and
// viewpoint of *cloud.
void TransformCloud(const PreprocessOptions& options, PointCloud* cloud);

// One point per occupied voxel of edge `voxel` (m): its point nearest to the voxel's
// centroid, with that point's normal and label (labelled points only share a voxel with
// points of the same label), in the order the voxels are first met. *weights: the points
// each kept point stands for, scaled down together where they sum to more than max_total
// (voxel > 0; otherwise all 1).
void SubsampleCloud(double voxel, PointCloud* cloud, Eigen::VectorXd* weights,
                    double max_total = std::numeric_limits<double>::infinity());

// A closest-point index over the whole surface at state.x, kept across outer iterations
// and frames and rebuilt only when a surface vertex moved more than `tolerance` (m) from
// where it was at the last build, or the topology changed. A rebuild that only follows the
// motion keeps the surface's rings (its topology): it copies the positions for the k-d tree,
// which the first query that needs it builds.
class ModelIndex {
 public:
  const SurfaceIndex& Get(const TrackerState& state, double tolerance);
  // The rings of state's surface (no rebuild of the index, whatever moved).
  const SurfaceRings& Rings(const TrackerState& state);
  void Reset() {
    index_.reset();
    rings_.reset();
  }
  int builds() const { return builds_; }

 private:
  bool SameSurface(const TrackerState& state) const;
  std::unique_ptr<SurfaceIndex> index_;
  std::shared_ptr<const SurfaceRings> rings_;
  const double* x_data_ = nullptr;     // the positions the index refers to
  const int* surface_data_ = nullptr;  // the triangles the rings (and the index) are of
  Eigen::Index x_rows_ = 0, surface_rows_ = 0;
  Vertices built_at_;  // state.x when built
  int builds_ = 0;
};

// Builds fc->index (unless it is set, of fc->cloud's points), fc->spacing and fc->trim, and
// decides the visibility (at state.x):
// the camera when known (data.visibility or data.auto_visibility), else with
// data.auto_visibility the cloud's viewpoint when usable, else the side of the model the
// cloud lies on (the mean outward normal at the cloud points' closest surface points), else
// none. With a camera and data.occluders, also marks the occluders (MarkOccluders).
// fc->cloud and fc->weights must be set.
void PrepareFrameCloud(const TrackerState& state, const SurfaceIndex& surface, FrameCloud* fc);

// The occluders at state.x (MarkOccluders): fc->occluder and fc->occluders. With a camera,
// data.occluders and no fracture; else none. fc->index and fc->spacing must be set.
void UpdateOccluders(const TrackerState& state, const SurfaceIndex& surface, FrameCloud* fc);

// fc->occluder_depth from the points fc->occluder marks as occluders (1; not the implausible
// ones): empty when there are none or the camera is not known. After UpdateOccluders and after
// each change of the marks.
void BuildOccluderDepth(const TrackerState& state, FrameCloud* fc);

// The observed depth (fc->observed) of registration.free_space: from the camera's position
// when it is known, else from the view PrepareFrameCloud decided (a viewpoint: perspective; a
// direction: orthographic); empty with free space off or no view. After PrepareFrameCloud.
void BuildObservedDepth(const TrackerState& state, FrameCloud* fc);

// The pairs at state.x (#V by 3), with queries on num_threads OpenMP threads (0: the
// machine's hardware threads, as solver.num_threads). A point
// whose label names an object pairs with that object only; the other points of a labelled
// cloud pair only with the objects that have no label, and are ignored when every object
// has one. `surface` indexes the whole surface at state.x (ModelIndex). `warm`, if not
// null, holds per cloud query the triangle of its last hit (empty: none): the cloud->model
// queries start from it (SurfaceIndex::ClosestFrom) and it is updated. It belongs to one
// frame's cloud and one surface topology: the caller empties it for a new frame or after
// a fracture edit.
// `paired`, if not null, is set to which surface vertices got a model->cloud pair. With
// `freeze` (and `paired` from the last call on this frame), that set is held instead: a
// vertex pairs, with its nearest point now, iff it was paired before and is within
// data.max_distance, whatever the trim and the visibility say now. The pair set then no
// longer switches between outer iterations, and the energy they minimize changes
// continuously.
void FindPairs(const TrackerState& state, const FrameCloud& fc, const SurfaceIndex& surface,
               int num_threads, std::vector<DataPair>* pairs, PairCounts* counts,
               std::vector<int>* warm = nullptr, std::vector<char>* paired = nullptr,
               bool freeze = false);

// Starts for the first outer iteration's cloud->model walks on an embedded surface: per query
// of `points` (every stride-th row), a triangle around the nearest of view's surface vertices
// (an embedded surface's pair subsample) at view.x; -1 where there is none. The walk from
// there (FrameCloud::seeded_rings) ends where the search over a k-d tree of every surface
// vertex would, without building that tree each frame (docs/notes/2026-11-30-fine-scans.md).
std::vector<int> SubsampleStarts(const TrackerState& view, const SurfaceRings& rings, const Vertices& points,
                                 int stride, int num_threads);

// The frame's per-vertex outputs (state.residuals, state.observed) and each object's
// mesh.x from state.x. cloud_index may be null (no data). num_threads as in FindPairs.
void UpdateOutputs(const PointIndex* cloud_index, const std::vector<DataPair>& pairs,
                   TrackerState* state, int num_threads = 1);

// Per vertex of object i: by how much a camera-facing surface vertex's distance to its
// nearest cloud point exceeds twice the median of that distance (other vertices: the mean
// distance over the camera-facing vertices of their elements; 0 without such).
Eigen::VectorXd DataGap(const TrackerState& state, int object, const PointIndex& cloud_index);

}  // namespace femreg

#endif  // FEMREG_REGISTRATION_CORRESPONDENCES_H_
