// The bundled fracture sequences' scenarios (beam_break, slab_tear, beam_cut): the body, its
// material, the camera, the grippers' motions and the tracking scene's settings; the
// generator is fracture_sequences.cc.
#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <string>

#include "datasets/fracture_scenarios.h"
#include "datasets/scene_numbers.h"

namespace femreg {
namespace fracture_scenarios {

namespace {

// The bundled sequences' depth camera: 320 x 240 pixels, the principal point at the centre,
// focal length `focal` (pixels), at `position` looking at `target`.
CameraOptions Camera320(const Eigen::Vector3d& position, const Eigen::Vector3d& target,
                        const Eigen::Vector3d& up, double focal) {
  CameraOptions c;
  c.enabled = true;
  c.position = position;
  c.target = target;
  c.up = up;
  c.width = 320;
  c.height = 240;
  c.fx = c.fy = focal;
  c.cx = 159.5;
  c.cy = 119.5;
  return c;
}

// The beams' foam.
Material BeamFoam() {
  Material m;
  m.youngs_modulus = 5e4;
  m.poisson_ratio = 0.35;
  m.density = 200;
  return m;
}

// A clamp: held where it is.
void Still(int, Eigen::Matrix3d* R, Eigen::Vector3d* t) {
  R->setIdentity();
  t->setZero();
}

// A gripper `length` from the clamp (its centre) that bends a beam down along a circular arc,
// the curvature ramping up to kappa_max (1/m) over the first `ramp` frames (pure bending: the
// end follows the arc of the centre line, rotated by kappa length); after frame carry_from it
// moves on by `carry` per frame.
GripperMotion ArcGripper(double length, double kappa_max, int ramp, int carry_from,
                         const Eigen::Vector3d& carry) {
  return [=](int f, Eigen::Matrix3d* R, Eigen::Vector3d* t) {
    const double L = length;
    const double kappa = kappa_max * std::min(f, ramp) / static_cast<double>(ramp) + 1e-9;
    const double theta = kappa * L;
    *R = Eigen::AngleAxisd(theta, Eigen::Vector3d::UnitY()).toRotationMatrix();
    const Eigen::Vector3d end(std::sin(theta) / kappa, 0, -(1 - std::cos(theta)) / kappa);
    *t = end - Eigen::Vector3d(L, 0, 0);
    if (f > carry_from) *t += carry * (f - carry_from);
  };
}

}  // namespace

Scenario BeamBreak() {
  Scenario s;
  s.name = "beam_break";
  s.title = "a foam beam bent until it breaks";
  s.size = Eigen::Vector3d(0.3, 0.045, 0.045);
  s.cells = Eigen::Vector3i(20, 3, 3);
  s.material = BeamFoam();
  s.toughness = 1e9;  // the ground truth breaks only in its weak band
  s.weak_toughness = 2500;
  s.tracked_toughness = 6000;
  s.weak_half_width = 0.008;
  s.frames = 24;
  s.camera = Camera320(Eigen::Vector3d(0.15, -0.36, 0.30), Eigen::Vector3d(0.15, 0.02, -0.02),
                       Eigen::Vector3d::UnitZ(), 262.5);
  s.left_x = 1e-9;
  s.right_x = 0.3 - 0.0225 - 1e-9;
  s.description =
      "clamped at x = 0; the free end, held by a gripper, is bent down along a circular "
      "arc (pure bending) until the beam breaks in its weaker middle, then lifted and "
      "pulled away";
  s.left = Still;
  // Bent over the first 16 frames, then the gripper rises and pulls away.
  s.right = ArcGripper(s.size.x() - 0.01125, 3.2, 16, 16, Eigen::Vector3d(0.004, 0, 0.004));
  s.left_anchor_tracked = true;
  s.right_anchor_tracked = false;
  // The camera's visibility test on (the default): the free piece, seen only on its side and
  // top, slid along its axis while the data at its crack pulled it (before the crack's surface
  // paired with nothing: docs/notes/2026-11-29-fracture-pieces.md).
  // One crack that grows from its front: with every node free to split, a change in the last
  // bit of the solve (another thread count, another CPU) could break the tracked beam into
  // more pieces (docs/notes/2026-11-28-figures-from-code-comments.md).
  s.tracked_max_cracks = 1;
  return s;
}

Scenario SlabTear() {
  Scenario s;
  s.name = "slab_tear";
  s.title = "a soft slab torn by two grippers";
  s.size = Eigen::Vector3d(0.2, 0.1, 0.012);
  s.cells = Eigen::Vector3i(20, 10, 1);
  s.material.youngs_modulus = 3e4;
  s.material.poisson_ratio = 0.3;
  s.material.density = 300;
  s.toughness = 1e9;
  s.weak_toughness = 1500;
  s.tracked_toughness = 4000;
  // Pulled evenly, the tracked slab's measure is nearly uniform and exceeds the toughness
  // everywhere at once: one crack, placed where the camera sees the slab open.
  s.tracked_max_cracks = 1;
  s.tracked_data_gap = true;
  s.weak_half_width = 0.004;
  s.frames = 24;
  s.camera = Camera320(Eigen::Vector3d(0.1, -0.12, 0.3), Eigen::Vector3d(0.1, 0.05, 0.0),
                       Eigen::Vector3d::UnitY(), 300);
  s.left_x = 0.02 + 1e-9;
  s.right_x = 0.18 - 1e-9;
  s.description =
      "the left and right strips (2 cm) are held by grippers that pull apart along x, the "
      "right one also sliding along +y, so the slab tears along its weaker middle";
  s.left = [](int f, Eigen::Matrix3d* R, Eigen::Vector3d* t) {
    R->setIdentity();
    *t = Eigen::Vector3d(-0.0015 * f, 0, 0);
  };
  s.right = [](int f, Eigen::Matrix3d* R, Eigen::Vector3d* t) {
    R->setIdentity();
    *t = Eigen::Vector3d(0.0015 * f, 0.001 * f, 0.0);
  };
  s.left_anchor_tracked = true;
  s.right_anchor_tracked = true;
  return s;
}

Scenario BeamCut() {
  Scenario s;
  s.name = "beam_cut";
  s.title = "a soft beam bent, then cut";
  s.size = Eigen::Vector3d(0.2, 0.03, 0.03);
  // The tracked cells straddle the cut, so no face lies in it (docs/notes/2026-11-29-fracture.md).
  s.cells = Eigen::Vector3i(12, 2, 2);
  s.fine_cells = Eigen::Vector3i(40, 6, 6);  // the truth has faces on both sides of the cut
  s.material = BeamFoam();
  s.tracked_toughness = 6000;
  s.tracked_max_cracks = 1;
  s.cut_through = true;
  s.cut_frame = 7;
  s.cut_lo = 0.070;
  s.cut_hi = 0.075;
  s.frames = 12;
  s.camera = Camera320(Eigen::Vector3d(0.11, -0.26, 0.20), Eigen::Vector3d(0.11, 0.01, -0.02),
                       Eigen::Vector3d::UnitZ(), 262.5);
  s.left_x = 1e-9;
  s.right_x = 0.2 - 0.015 - 1e-9;
  s.description =
      "clamped at x = 0; the free end, held by a gripper, is bent down along a circular arc "
      "for 6 frames; at frame 7 a 5 mm slab 70 mm from the clamp is cut out (the elements "
      "removed), and the gripper then carries the free piece away";
  s.left = Still;
  // Bent over the first 6 frames; after the cut (frame 7) the gripper carries the free piece
  // away.
  s.right = ArcGripper(s.size.x() - 0.0075, 2.5, 6, 7, Eigen::Vector3d(0.008, 0, 0.006));
  s.left_anchor_tracked = true;
  s.right_anchor_tracked = false;
  return s;
}

// The tracking scene: the coarse box with the tracked toughness, the camera, the fracture
// limits and the grippers the robot knows as hard anchors. Computed numbers (the boxes just
// past the grippers' faces, their paths) keep the 10 significant digits the scene has
// always been written with; a path's repeated last frames are dropped (a frame past the
// list holds the last entry).
Scene TrackingScene(const Scenario& s) {
  Scene scene;
  scene.description = s.name + ", " + std::to_string(s.frames) + " frames";
  ObjectSpec object;
  object.name = s.name == "slab_tear" ? "slab" : "beam";
  object.generate.shape = MeshGeneratorSpec::Shape::kBox;
  object.generate.size = s.size;
  object.generate.cells = s.cells;
  object.material = s.material;
  object.toughness = s.tracked_toughness;
  scene.objects.push_back(object);
  RegistrationOptions& r = scene.registration;
  r.camera = s.camera;
  r.data.max_distance = 0.03;
  r.data.visibility = s.tracked_visibility;
  r.data.auto_visibility = s.tracked_visibility;
  r.weights.data = 200;  // the tracked toughness was tuned with the per-pair data weight
  r.solver.max_inner_iterations = 10;
  scene.effects.fracture = true;
  FractureOptions& f = scene.effects.fracture_options;
  f.max_splits_per_iteration = 8;
  f.max_splits_per_frame = 48;
  f.crossing_tolerance = 0.2;
  f.max_cracks = s.tracked_max_cracks;
  f.data_gap = s.tracked_data_gap;
  f.cut_through = s.cut_through;
  auto anchor = [&](const std::string& name, bool left,
                    const std::function<void(int, Eigen::Matrix3d*, Eigen::Vector3d*)>& motion) {
    AnchorSpec a;
    a.name = name;
    a.object = object.name;
    a.hard = true;
    a.selection.kind = VertexSelection::Kind::kBox;
    const double x = datasets_internal::RoundSignificant(left ? s.left_x : s.right_x, 10);
    a.selection.box_min = left ? Eigen::Vector3d(-1, -1, -1) : Eigen::Vector3d(x, -1, -1);
    a.selection.box_max = left ? Eigen::Vector3d(x, 1, 1) : Eigen::Vector3d(1, 1, 1);
    for (int frame = 0; frame < s.frames; ++frame) {
      Eigen::Matrix3d R;
      Eigen::Vector3d t;
      motion(frame, &R, &t);
      a.translations.push_back(datasets_internal::RoundSignificant(t, 10));
    }
    while (a.translations.size() > 1 && a.translations.back() == a.translations[a.translations.size() - 2]) {
      a.translations.pop_back();
    }
    scene.anchors.push_back(a);
  };
  if (s.left_anchor_tracked) anchor("left_gripper", true, s.left);
  if (s.right_anchor_tracked) anchor("right_gripper", false, s.right);
  return scene;
}

}  // namespace fracture_scenarios
}  // namespace femreg
