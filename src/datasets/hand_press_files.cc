// The hand_press dataset's fixed parts (hand_press_internal.h): the ball's material, the
// camera, and the files written beside the frames (the tracking scene, README.md).
#include <cmath>
#include <cstdio>
#include <sstream>
#include <string>

#include "datasets/hand_press_internal.h"
#include "scene/scene_writer_internal.h"  // Number: the shortest decimal that reads back

namespace femreg {
namespace hand_press_internal {

Material Foam(const HandPressOptions& options) {
  Material m;
  m.youngs_modulus = options.youngs_modulus;
  m.poisson_ratio = 0.4;
  m.density = 80.0;
  return m;
}

CameraOptions Camera(const HandPressOptions& options) {
  CameraOptions c;
  c.enabled = true;
  c.position = Eigen::Vector3d(0.0, -0.39, 0.44);  // 45 deg above the table, in front (-y)
  if (options.camera_azimuth_deg != 0.0) {
    const double a = options.camera_azimuth_deg * M_PI / 180.0;
    // To the micrometre, so that the scene file says 0 where the turn leaves round-off.
    auto um = [](double v) { return std::round(v * 1e6) / 1e6 + 0.0; };
    c.position = Eigen::Vector3d(um(0.39 * std::sin(a)), um(-0.39 * std::cos(a)), 0.44);
  }
  c.target = Eigen::Vector3d(0.0, 0.0, kRadius);
  c.up = Eigen::Vector3d::UnitZ();
  c.width = 320;
  c.height = 240;
  c.fx = c.fy = 262.5;
  c.cx = 159.5;
  c.cy = 119.5;
  return c;
}

std::string Format(const char* format, double a) {
  char buf[64];
  std::snprintf(buf, sizeof(buf), format, a);
  return buf;
}

std::string VariantArguments(const HandPressOptions& options) {
  using internal::scene_writer::Number;  // the same variant again from the printed options
  const HandPressOptions bundled;
  std::ostringstream os;
  if (options.youngs_modulus != bundled.youngs_modulus)
    os << " --youngs-modulus " << Number(options.youngs_modulus);
  if (options.scene_youngs_modulus != bundled.scene_youngs_modulus)
    os << " --scene-youngs-modulus " << Number(options.scene_youngs_modulus);
  if (options.camera_azimuth_deg != bundled.camera_azimuth_deg)
    os << " --camera-azimuth " << Number(options.camera_azimuth_deg);
  if (options.seed != bundled.seed) os << " --seed " << options.seed;
  if (options.press_scale != bundled.press_scale) os << " --press-scale " << Number(options.press_scale);
  return os.str();
}

std::string TrackingScene(const HandPressOptions& options) {
  const CameraOptions c = Camera(options);
  const Material foam = Foam(options);
  const double scene_e =
      options.scene_youngs_modulus > 0 ? options.scene_youngs_modulus : foam.youngs_modulus;
  std::ostringstream os;
  os << "# hand_press: a foam ball on a table, pressed by a hand and handled (made by\n"
        "# `femreg hand-press-data`; README.md beside this file). Written as a new user would "
        "from\n"
        "# datasets/README.md: the ball, its material, the camera, the table and gravity; nothing\n"
     << (VariantArguments(options).empty()
             ? std::string("# about the hand, whose points are in the clouds. Run\n")
             : "# about the hand, whose points are in the clouds. A variant of the bundled\n"
               "# sequence (hand-press-data" + VariantArguments(options) + "). Run\n")
     << "#   femreg register --scene scene.yaml --frames clouds --ground-truth ground_truth --out "
        "OUT\n"
        "objects:\n"
        "  - name: ball\n"
        "    generate: {shape: sphere, radius: "
     << kRadius << ", cells: " << kTrackedCells << "}\n"
     << "    pose: {translation: [0, 0, " << kRadius << "]}   # resting on the table\n"
     << "    material: {youngs_modulus: " << internal::scene_writer::Number(scene_e)
     << ", poisson_ratio: " << foam.poisson_ratio << ", density: " << foam.density
     << "}   # foam\n"
     << "gravity: [0, 0, -" << kGravity << "]\n"
     << "registration:\n"
     << "  camera: {position: [" << c.position.x() << ", " << c.position.y() << ", "
     << c.position.z() << "], target: [" << c.target.x() << ", " << c.target.y() << ", "
     << c.target.z() << "], up: [0, 0, 1],\n"
     << "           fx: " << c.fx << ", fy: " << c.fy << ", cx: " << c.cx << ", cy: " << c.cy
     << ", width: " << c.width << ", height: " << c.height << "}\n"
     << "effects:\n"
     << "  collision: true\n"
     << "collision:\n"
     << "  obstacles:\n"
     << "    - {name: table, plane: {point: [0, 0, 0], normal: [0, 0, 1]}}   # free side: z > 0\n";
  return os.str();
}

std::string Readme(const HandPressReport& r, const TetMesh& fine, const HandPressOptions& options) {
  const Material foam = Foam(options);
  std::ostringstream md;
  md << "# hand_press: a foam ball pressed by a hand, then handled\n\n"
     << "Made by `femreg hand-press-data --out datasets/hand_press` (tools/make_datasets.sh; "
        "deterministic: the same command rewrites the same bytes on the same machine). The "
        "data to develop issue 38 against: of the kind of a recording where femreg failed.\n\n"
     << (VariantArguments(options).empty()
             ? std::string()
             : "**A variant** of the bundled sequence, made with `" + VariantArguments(options).substr(1) +
                   "` (the tracking scene's Young's modulus: " +
                   Format("%g", options.scene_youngs_modulus > 0 ? options.scene_youngs_modulus
                                                                 : foam.youngs_modulus) +
                   " Pa; the camera's azimuth: " + Format("%g", options.camera_azimuth_deg) +
                   " deg from the front; the palm's press: " + Format("%g", options.press_scale) +
                   " times the bundled one). The text below describes the bundled sequence's "
                   "script; the figures are this variant's.\n\n")
     << "A soft foam ball (radius " << kRadius * 1e3 << " mm; E = " << foam.youngs_modulus
     << " Pa, nu = " << foam.poisson_ratio << ", " << foam.density << " kg/m^3, "
     << Format("%.1f", r.mass_kg * 1e3) << " g) rests on a table (the plane z = 0) under gravity. "
     << "A rigid hand (a rounded-box palm, 9 x 8 x 3 cm, and two rounded finger pads, "
        "2 x 5.2 x 3.6 cm) comes down from above, its palm tilted 0.1 rad towards the camera, "
        "and presses the ball (frames 3-8); it lets go (9-11), closes its pads 8 mm into the "
        "ball's sides (12-14), lifts it 4 cm while turning it 0.3 rad about the grasp axis (x) "
        "and carrying it 2 cm along +x (15-19), sets it down there (20-24), opens and leaves "
        "(25-29). "
     << r.frames << " frames";
  if (r.frames == kFrames) {
    md << "; the top of the ball goes down by "
       << Format("%.1f", (r.rest_top_m - r.min_top_m) * 1e3)
       << " mm under the palm, its bottom rises to " << Format("%.1f", r.max_lift_m * 1e3)
       << " mm above the table";
  }
  md << ".\n\n"
     << "One depth camera (320x240, fx = fy = 262.5, every pixel; depth noise sigma = 2.85e-3 "
        "z^2, no returns beyond 80 deg incidence) looks down at 45 deg from above and in front "
        "(-y): the side away from it and the bottom are never seen. The clouds are what a "
        "segmentation mask that keeps the ball and the hand gives: **the hand's visible "
        "surface is in them** (occlusions respected), the table's is not (it occludes only; "
        "no `preprocess.plane` is needed). "
     << r.min_points << " to " << r.max_points << " points per cloud; the camera sees "
     << Format("%.1f", 100 * r.mean_seen_fraction) << "% of the tracked vertices on average.\n\n"
     << "## Files\n\n"
     << "- `scene.yaml`: the tracking scene as a new user writes it from datasets/README.md: "
        "the generated sphere ("
     << r.tracked_vertices
     << " vertices), the foam, the camera, "
        "the table as a collision plane (free side z > 0) and gravity. Nothing about the hand.\n"
     << "- `clouds/frame_NNNN.pcd`: the clouds.\n"
     << "- `clouds_without_hand/frame_NNNN.pcd`: the same clouds less the hand's points, what a "
        "mask that leaves the hand out gives (the hand still hides the ball behind it). Issue 39 "
        "asks that the clouds with the hand track within 10 % of these.\n"
     << "- `ground_truth/frame_NNNN.csv`: per tracked vertex, its true position (x,y,z in m) "
        "and whether the camera saw it (the hand and the table hide).\n"
     << "- `truth/frame_NNNN.vtu`: the ground truth mesh's surface (for `femreg eval`).\n"
     << "- `forces.csv`: per frame, the resultant of the external forces on the ball other "
        "than gravity (`force_x_N, force_y_N, force_z_N`: the table's and the hand's) and "
        "their torque about the ball's centre of mass (`torque_*_Nm`; the lumped-mass-weighted "
        "mean of the vertex positions), the table's normal force `table_force_N`, the "
        "hand's force `hand_force_*_N` (palm and pads), and the table's push "
        "`contact_force_*_N` (the scene's obstacle: `femreg eval` compares it with the "
        "contact force in stats.csv). In equilibrium the resultant is the "
        "weight, "
     << Format("%.4f", r.mass_kg * kGravity)
     << " N upwards, and the torque is zero (gravity has none about the centre of mass); "
        "the largest deviations over the frames are "
     << Format("%.1e", r.max_force_imbalance_N) << " N and "
     << Format("%.1e", r.max_torque_imbalance_Nm)
     << " N m (the generator refuses a frame beyond a millionth of the weight).\n"
     << "- `truth_solve.csv`: per frame, the ground truth's active-set rounds and Newton "
        "iterations, the largest force left on a free vertex, the vertices held by the table, "
        "the palm, the thumb and the fingers, the force and torque imbalance, the ball's lowest "
        "point (mm) and its inverted elements.\n\n"
     << "## How the ground truth is made\n\n"
     << "Quasi-static corotational FEM on a finer sphere (" << fine.num_vertices() << " vertices, "
     << fine.num_tets()
     << " tetrahedra), interpolated at the tracked vertices. Contacts stick "
        "and only push: a surface vertex that crosses the table or a part of the hand is held "
        "(a prescribed displacement) at the nearest point of that surface and moves with it; "
        "held vertices whose reactions pull on their surface are let go, the hardest-pulling "
        "first; per frame (in substeps that move the hand at most 2 mm) this repeats "
        "until nothing changes. The reactions of the held vertices (the elastic force they "
        "transmit less their weight) are the contact forces. Sticking is infinite friction: "
        "the ball neither slides on the table nor slips in the grasp.\n\n"
     << "## Register and measure\n\n"
     << "    femreg register --scene datasets/hand_press/scene.yaml --frames "
        "datasets/hand_press/clouds \\\n"
     << "        --ground-truth datasets/hand_press/ground_truth --out /tmp/hp\n"
     << "    femreg eval /tmp/hp datasets/hand_press\n"
     << "    python3 tools/hand_press_report.py /tmp/hp datasets/hand_press\n\n"
     << "`tools/hand_press_report.py` (python3 and numpy) reads the registered meshes "
        "(`OUT/frames/ball_NNNN.vtu`), `OUT/stats.csv` and this folder, and prints per frame, "
        "with totals:\n\n"
        "- `seen_mm`, `hidden_mm`: the mean error of the seen and the hidden vertices (as "
        "`femreg eval`);\n"
        "- `shape_mm`: the mean error after the best rigid fit of the tracked vertices onto the "
        "true ones: the shape's error alone, without the pose's (a ball's turn about its centre "
        "barely changes what the camera sees);\n"
        "- `inverted`: the tracked elements with signed volume <= 0;\n"
        "- `min_z_mm`, `truth_min_z_mm`, `base_gap_mm`: the tracked mesh's lowest point, the "
        "truth's, and the difference (> 0: the base lifted off where the truth rests);\n"
        "- `penetration_mm`: how far the tracked mesh reaches below the table;\n"
        "- `top_gap_mm`: the tracked top above the truth's (the mesh climbing into the hand);\n"
        "- `rot_deg`, `truth_rot_deg`, `rot_err_deg`: the rotation from rest of the best rigid "
        "fit to the tracked and to the true vertices, and the angle between the two (a rolled "
        "body);\n"
        "- `fit_rms_mm`: the data pairs' rms residual (`stats.csv`; the fit to the cloud, the "
        "hand's points included);\n"
        "- `capped`, `lost`: the frame stopped at the outer-iteration cap, or found no "
        "correspondence;\n"
        "- `ms`: the frame's time.\n\n"
        "`--csv FILE` writes the rows. Run it before and after a change and compare. The "
        "figures of today's tracker on this sequence are in "
        "docs/notes/2026-11-28-hand-press-data.md.\n";
  return md.str();
}

}  // namespace hand_press_internal
}  // namespace femreg
