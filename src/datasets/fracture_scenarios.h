// What the fracture sequence generator's files share (fracture_sequences.cc: the ground
// truth's simulation, the frames and the README.md; fracture_scenarios.cc: each scenario's
// settings and its tracking scene).
#ifndef FEMREG_DATASETS_FRACTURE_SCENARIOS_H_
#define FEMREG_DATASETS_FRACTURE_SCENARIOS_H_

#include <Eigen/Core>
#include <functional>
#include <string>

#include "femreg/fem.h"
#include "femreg/registration.h"
#include "femreg/scene.h"

namespace femreg {
namespace fracture_scenarios {

// A gripper's rigid motion at frame f: rotation R about the held set's centre, then shift t.
using GripperMotion = std::function<void(int f, Eigen::Matrix3d* R, Eigen::Vector3d* t)>;

struct Scenario {
  std::string name, title, description;
  Eigen::Vector3d size;
  Eigen::Vector3i cells;  // tracked mesh
  Material material;
  double toughness = 0.0;       // tracked scene and the ground truth's strong part (Pa)
  double weak_toughness = 0.0;  // the ground truth's weak band (Pa)
  double tracked_toughness = 0.0;
  // The tracking scene's effects.fracture.max_cracks and data_gap (FractureOptions).
  int tracked_max_cracks = 0;
  bool tracked_data_gap = false;
  // Whether the tracking scene lets the camera decide which surface vertices pull
  // (registration.data.visibility and auto_visibility: with a camera in the scene,
  // auto_visibility alone turns the camera's test on). Off, every surface vertex is pulled
  // to its nearest point, so the silhouette's end edges pin the sliding along a box's axis
  // that point-to-plane pairs on the faces the camera sees leave free.
  bool tracked_visibility = true;
  double weak_half_width = 0.0;  // |x - x_mid| below this (centroid) is weak
  int frames = 0;
  CameraOptions camera;
  int pixel_stride = 2;
  // Rigid motions of the grippers: the set of vertices with rest x <= left_x follows
  // left(f); x >= right_x follows right(f). Rotation about the set's centre, then shift.
  double left_x = 0.0, right_x = 0.0;
  GripperMotion left, right;
  bool left_anchor_tracked = true, right_anchor_tracked = false;  // tracker knows them
  // The ground truth's mesh (0: `refinement` times the tracked one's cells).
  Eigen::Vector3i fine_cells = Eigen::Vector3i::Zero();
  // A cut instead of a weak band: at frame cut_frame the ground truth's elements whose rest
  // centroid has cut_lo < x < cut_hi are removed (the body comes apart there, whatever its
  // stress), and its toughness is off.
  int cut_frame = -1;
  double cut_lo = 0.0, cut_hi = 0.0;
  bool cut_through = false;  // the tracking scene's effects.fracture.cut_through
};

Scenario BeamBreak();
Scenario SlabTear();
Scenario BeamCut();

// The tracking scene: the coarse box with the tracked toughness, the camera, the fracture
// limits and the grippers the robot knows as hard anchors.
Scene TrackingScene(const Scenario& s);

}  // namespace fracture_scenarios
}  // namespace femreg

#endif  // FEMREG_DATASETS_FRACTURE_SCENARIOS_H_
