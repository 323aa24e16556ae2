// femreg/datasets.h - the sequence generators: sequences with ground truth made by the
// forward simulator (with contacts or fracture where the scenario calls for them), seen by
// the virtual depth camera of femreg/synth.h, each written with its tracking scene
// (WriteScene, femreg/scene.h) beside it. `femreg synth`, `femreg contact-data` and
// `femreg fracture-data` run them; tools/make_datasets.sh makes the bundled datasets.
//
// Every generator is deterministic: the forward solves run on one thread and every random
// draw comes from a per-frame seed, so a rerun writes the same bytes.
#ifndef FEMREG_DATASETS_H_
#define FEMREG_DATASETS_H_

#include <cstdint>
#include <iosfwd>
#include <string>
#include <vector>

#include "femreg/fem.h"
#include "femreg/forward.h"
#include "femreg/scene.h"
#include "femreg/status.h"

namespace femreg {

// ---------------------------------------------------------------------------------------
// femreg synth: a scene's synth section.

// What GenerateSynthSequence made.
struct SynthReport {
  int frames = 0;
  int tracked_vertices = 0, tracked_tets = 0;
  int truth_vertices = 0, truth_tets = 0;
  int min_points = 0, max_points = 0;  // cloud sizes
  double mean_seen_fraction = 0.0;     // tracked vertices the camera saw, mean over frames
  std::string note;                    // a choice made for the user (the truth's element), or empty
};

// femreg synth: simulates the scene's synth section (scene.synth.enabled) frame by frame
// with SolveQuasiStatic on the ground truth mesh, renders it with the virtual camera and
// writes DIR/scene.yaml (the tracking scene, SynthTrackingScene), DIR/clouds/frame_NNNN.pcd,
// DIR/ground_truth/frame_NNNN.csv, DIR/truth/frame_NNNN.vtu (the ground truth surface) and
// DIR/README.md. `frames` <= 0 means synth.frames; the motion script's timeline does not
// depend on it, so the first frames of a shorter run are bit-identical to a longer one's.
// `progress` (may be null) is called after each frame.
Status GenerateSynthSequence(const Scene& scene, const std::string& dir, int frames,
                             SynthReport* report,
                             void (*progress)(int done, int total) = nullptr);

// The tracking scene GenerateSynthSequence writes into `dir`: the scene's objects,
// registration, anchors, effects and collision (the simulation-only gravity, boundary,
// loads, forward and synth left out), the object's mesh file by its name in `dir` (where
// the generator copies it), and an anchor per motion track the robot knows (`anchor: hard`
// or `soft`) following the track's translations frame by frame (9 significant digits,
// repeated last frames dropped: a frame past the list holds the last entry).
Scene SynthTrackingScene(const Scene& scene, const std::string& dir);

// ---------------------------------------------------------------------------------------
// femreg contact-data: the bundled contact sequences.

// Bundled contact sequences with ground truth: "contact_pair" (a soft block pressed and
// sheared onto another one, clamped at its base) and "tool_table" (a soft cantilever pushed
// onto a table by a rigid tool, an STL written beside the scene). Corotational FEM with the
// penalty on meshes twice as fine as the tracked ones, a virtual depth camera (the tool and
// the table occlude but return no points). Writes DIR/scene.yaml, DIR/clouds/frame_NNNN.pcd,
// DIR/ground_truth/frame_NNNN.csv (one row per tracked vertex of all objects in scene order)
// and DIR/README.md; deterministic.
// Also writes DIR/truth_contacts.csv: per frame, the ground-truth solve's Newton
// iterations, active contacts and deepest penetration; and for tool_table DIR/forces.csv:
// per frame, the resultant of the contact forces on the slab (tool and table) and its torque
// about the slab's centroid (femreg/ground_truth.h's ForceFrame).
std::vector<std::string> ContactScenarios();
Status GenerateContactSequence(const std::string& scenario, const std::string& dir,
                               void (*progress)(int done, int total) = nullptr);

// ---------------------------------------------------------------------------------------
// femreg fracture-data: the bundled fracture sequences.

// The bundled fracture sequences: "beam_break" (a beam bent until it breaks) and
// "slab_tear" (a slab torn by two grippers). Writes DIR/scene.yaml, DIR/clouds/*.pcd,
// DIR/ground_truth/frame_NNNN.csv (+ _pieces.csv after the break, events.csv) and
// DIR/README.md; `progress` (may be null) is called after each frame.
std::vector<std::string> FractureScenarios();
Status GenerateFractureSequence(const std::string& scenario, const std::string& dir,
                                void (*progress)(int done, int total) = nullptr);
// A cut scenario ("beam_cut") with its ground truth given: per frame the displacements of the
// ground truth's mesh (its vertices as created, #V by 3), from the deck below solved by another
// simulator; `truth_source` names it in README.md. Writes the sequence as "<scenario>_calculix".
Status GenerateFractureSequence(const std::string& scenario, const std::string& dir,
                                const std::vector<Vertices>& truth, const std::string& truth_source,
                                void (*progress)(int done, int total) = nullptr);
// The CalculiX deck of a cut scenario's ground truth: its mesh as C3D4 with *ELASTIC under
// NLGEOM, one static step per frame (ending at total time frame + 1) with the grippers'
// displacements, the slab's elements removed by *MODEL CHANGE, TYPE=ELEMENT, REMOVE in the cut
// frame's step, U printed.
Status WriteFractureSequenceDeck(const std::string& scenario, std::ostream& out);

// ---------------------------------------------------------------------------------------
// femreg organ-data: the bundled partial-view sequence.

// "organ_patch": an organ-like body clamped at one end and pushed by a tool, seen as
// 500-point patches on ~15% of its surface, no camera and no viewpoint. Writes
// DIR/organ.vtu (the tracked mesh), DIR/scene.yaml, DIR/clouds/frame_NNNN.pcd,
// DIR/ground_truth/frame_NNNN.csv (visible = in the patch), DIR/forces.csv (the tool's true
// force per frame on the body, with its torque about the body's centroid;
// femreg/ground_truth.h's ForceFrame) and DIR/README.md; deterministic.
// `divisions` (2 to truth_divisions - 1) divides the tracked mesh: (2 n + 1)^3 vertices,
// 48 n^3 tetrahedra (the bundled sequence: 4, 729 / 3072; 7: 3375 / 16464). The clouds and
// the ground truth's solve, and so forces.csv, do not depend on it. `truth_divisions` (up to
// 16) divides the ground truth's mesh (the bundled sequence: 10, 9261 vertices); a finer one
// shows how far that truth is from converged.
// `tool` says how the tool holds the body (OrganTool below); the bundled sequence's pushes by
// contact, a force a camera can see.
enum class OrganTool {
  // The upper-surface vertices within the tool's radius of its axis follow it without slip;
  // its force is their reaction, with a part along the surface as large as the push.
  kGlued,
  // A rigid, frictionless flat-ended cylinder of the same radius with a rounded edge, posed per
  // frame along the same path, pressing by the contact penalty of femreg/collision.h; its
  // force is the contacts' resultant on the body, normal to the surface it touches. The frames
  // are solved in order, each from the last.
  kContact,
};
// "glued", "contact": organ-data's --tool names.
const char* ToString(OrganTool tool);
bool FromString(const std::string& name, OrganTool* tool);
Status GenerateOrganPatchSequence(const std::string& dir,
                                  void (*progress)(int done, int total) = nullptr,
                                  int divisions = 4, int truth_divisions = 10,
                                  OrganTool tool = OrganTool::kContact);
// The organ_patch body's tracked mesh at `divisions` (above).
TetMesh OrganPatchMesh(int divisions);
// The ground truth's material: E 5 kPa, nu 0.47 (the tracking scene says 0.45), density
// 1000, the neo-Hookean element with the nodal volume (locking-free at this nu).
ObjectMaterial OrganPatchTruthMaterial();

// One frame of the organ_patch ground truth's solve.
struct OrganTruthFrame {
  Vertices positions;  // the solved vertices of OrganPatchMesh(truth divisions)
  // The forces on the body, with their torques about its lumped-mass centroid: by the tool
  // (the reactions at the vertices it moves, or its contacts' forces; forces.csv) and by the
  // clamp. With no gravity they sum to zero up to the solve's tolerance.
  ForceResultant tool, clamp;
  ForwardSummary summary;
  // The contact tool's touching contacts and their deepest penetration (m; the penalty lets
  // a contact in by its force / k); 0 for the glued tool.
  int contacts = 0;
  double max_penetration = 0.0;
};
// Solves frame `frame` (0-11) of organ_patch's ground truth on OrganPatchMesh(divisions)
// with `material` (OrganPatchTruthMaterial() for the bundled sequence, which uses
// divisions 10) and `tool`, from rest (the contact tool: through the frames before it), on
// one thread.
Status SolveOrganPatchTruth(int frame, int divisions, const ObjectMaterial& material,
                            OrganTruthFrame* out, OrganTool tool = OrganTool::kContact);

// ---------------------------------------------------------------------------------------
// femreg hand-press-data: the bundled hand_press sequence.

// What GenerateHandPressSequence made, and the balance it checked.
struct HandPressReport {
  int frames = 0;
  int tracked_vertices = 0, truth_vertices = 0;
  double mass_kg = 0.0;                 // the ground truth mesh's lumped masses
  int min_points = 0, max_points = 0;   // cloud sizes
  double mean_seen_fraction = 0.0;      // tracked vertices the camera saw, mean over frames
  // Largest |external forces + M g| (N) and |their torque about the centre of mass| (N m)
  // over the frames: zero in equilibrium, up to the solve's tolerance.
  double max_force_imbalance_N = 0.0, max_torque_imbalance_Nm = 0.0;
  double max_hand_force_N = 0.0;        // largest |resultant of the hand's contacts|
  double rest_top_m = 0.0, min_top_m = 0.0;  // the ball's top at frame 0 and its lowest
  double max_lift_m = 0.0;              // the ball's bottom at its highest
};

// What can be varied in hand_press, to check that registration holds on data like it but not
// the same (the defaults make the bundled sequence).
struct HandPressOptions {
  // The ball's Young's modulus in the ground truth (Pa).
  double youngs_modulus = 2.0e4;
  // The one the tracking scene says (Pa); 0: the truth's. A user rarely knows it exactly.
  double scene_youngs_modulus = 0.0;
  // The camera turned about the vertical through the ball's rest centre (degrees; 0: in
  // front, -y; 90: at +x, the side the ball is carried to), at the same height and distance.
  double camera_azimuth_deg = 0.0;
  // The depth noise's draws; 0: the bundled sequence's.
  uint64_t seed = 0;
  // The palm's press, as a multiple of the bundled one (15 mm into the ball's top).
  double press_scale = 1.0;
};

// "hand_press" (issue 38): a soft foam ball (radius 5 cm; E 20 kPa, nu 0.4, 80 kg/m^3)
// resting on a table under gravity, pressed 15 mm from above by a rigid palm, grasped from
// two sides, lifted 4 cm, tilted 0.3 rad, set down 2 cm aside, let go; 30 frames from one
// 320x240 depth camera above and in front of it. The hand's points are in the clouds, the
// table's are not. Ground truth: corotational FEM on a finer sphere (4913 vertices) with
// sticking unilateral contacts with the table and the hand (an active set of held
// vertices; their reactions are the contact forces). Writes DIR/scene.yaml (the tracking
// scene), DIR/clouds/frame_NNNN.pcd, DIR/clouds_without_hand/frame_NNNN.pcd (the same
// clouds less the hand's points), DIR/ground_truth/frame_NNNN.csv (1331 tracked
// vertices), DIR/truth/frame_NNNN.vtu, DIR/forces.csv (per frame: the resultant and torque
// about the centre of mass of the external forces other than gravity, the table's normal
// force and the hand's force), DIR/truth_solve.csv (the solve per frame) and
// DIR/README.md. Fails when a frame's forces do not balance gravity. `frames` <= 0 makes all
// 30; fewer makes the first frames of the same timeline (the same bytes as a full run's).
// Deterministic.
Status GenerateHandPressSequence(const std::string& dir, int frames = 0,
                                 HandPressReport* report = nullptr,
                                 void (*progress)(int done, int total) = nullptr,
                                 const HandPressOptions& options = {});

}  // namespace femreg

#endif  // FEMREG_DATASETS_H_
