// Data correspondences of one outer iteration: model->cloud (each surface vertex to its
// nearest cloud point) and cloud->model (each cloud point to its closest point on the
// surface triangles), gated by distance, optionally only for vertices facing the camera,
// with labelled clouds split by object. Also the per-vertex outputs of a frame and the
// fracture's evidence from the data (FractureOptions::data_gap).
#ifndef FEMREG_REGISTRATION_CORRESPONDENCES_H_
#define FEMREG_REGISTRATION_CORRESPONDENCES_H_

#include <Eigen/Core>
#include <vector>

#include "femreg/registration.h"
#include "geometry/nearest.h"
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
  Eigen::Vector3d Point(const Vertices& x) const;    // the model point at x
};

struct PairCounts {
  int model_to_cloud = 0, cloud_to_model = 0;  // kept
  int rejected = 0;                            // gated out by data.max_distance
};

// The pairs at state.x (#V by 3). A point whose label names an object pairs with that
// object only; the other points of a labelled cloud pair only with the objects that have no
// label, and are ignored when every object has one.
void FindPairs(const TrackerState& state, const PointCloud& cloud, const PointIndex& cloud_index,
               std::vector<DataPair>* pairs, PairCounts* counts);

// The frame's per-vertex outputs (state.residuals, state.observed) and each object's
// mesh.x from state.x. cloud_index may be null (no data).
void UpdateOutputs(const PointIndex* cloud_index, const std::vector<DataPair>& pairs,
                   TrackerState* state);

// Per vertex of object i: by how much a camera-facing surface vertex's distance to its
// nearest cloud point exceeds twice the median of that distance (other vertices: the mean
// distance over the camera-facing vertices of their elements; 0 without such).
Eigen::VectorXd DataGap(const TrackerState& state, int object, const PointIndex& cloud_index);

}  // namespace femreg

#endif  // FEMREG_REGISTRATION_CORRESPONDENCES_H_
