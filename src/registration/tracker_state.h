// What a Tracker holds between frames, shared by its parts: the objects in one global
// vertex numbering, the anchors, and the effects that are on (contacts, fracture).
//
// The parts of a frame (docs/theory/energy.md#one-frame):
//   registration/correspondences  data pairs (model->cloud, cloud->model), normals, data gap
//   registration/prealign         the rigid pre-alignment
//   registration/global_pose      the global initial pose (registration.initial_pose auto)
//   registration/frame_problem    the frame's energy from pairs, springs, anchors, contacts
//   registration/fracture_step    detection and splits between outer iterations
//   registration/tracker          the outer loop, the public API (set-up calls: tracker_setup)
#ifndef FEMREG_REGISTRATION_TRACKER_STATE_H_
#define FEMREG_REGISTRATION_TRACKER_STATE_H_

#include <Eigen/Core>
#include <map>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "femreg/collision.h"
#include "femreg/fem.h"
#include "femreg/fracture.h"
#include "femreg/mesh.h"
#include "femreg/registration.h"
#include "fracture/measure_bound.h"

namespace femreg {

struct ObjectState {
  TetMesh mesh;
  ElasticModel model;
  ObjectMaterial material;
  int offset = 0;  // its first vertex in the global numbering
  int label = -1;  // the cloud label of its points; -1 = none
  // External loads (Tracker::SetExternalLoads): gravity on the lumped masses and nodal
  // forces (#V by 3, N; empty: none).
  Eigen::Vector3d gravity = Eigen::Vector3d::Zero();
  Vertices loads;
};

struct Anchor {
  int object = 0;
  std::vector<int> vertices;  // global indices
  bool hard = false;
  double weight = 0.0;        // soft: N/m per vertex; <= 0: weights.anchor
  Vertices targets;           // one row per vertex
  Vertices origin;            // positions when the anchor was added
  // Per-frame rigid motion from origin (frame beyond the list: the last one): a rotation
  // (axis * angle, rad; empty list: none) about `centre`, then the translation; empty
  // translations: the targets stay as set.
  std::vector<Eigen::Vector3d> translations;
  std::vector<Eigen::Vector3d> rotations;
  Eigen::Vector3d centre = Eigen::Vector3d::Zero();
};

// Fracture (effects.fracture): allocated only when on.
struct FractureState {
  std::vector<FractureOptions> options;      // per object
  std::vector<std::vector<int>> original;    // per object: vertex -> vertex at creation
  std::vector<NodeSeparation> separation;    // per object: the last detection
  int frame_splits = 0;
  // Whether fracture has a say yet: a node split, or a detection's measure reached
  // kFractureLiveRatio of its toughness (then it stays so). Until then the frame runs as
  // with fracture off (the reciprocity trim, the occluders, the backtracking and the
  // large-motion restart, which fracture turns off).
  bool live = false;
  bool separated = false;  // the last fracture step parted an object into more pieces
  bool frame_separated = false;  // one of this frame's did
  // Per object, per vertex as created: on the surface then.
  std::vector<std::vector<char>> initial_surface;
  // #V global, or empty: the vertices on the crack of an object already in pieces (the
  // copies of split vertices, and vertices the split left on the surface that were inside),
  // which pair with no data (docs/theory/fracture.md#pieces).
  std::vector<char> crack;
  // Per object: the positions of the last detection.
  std::vector<Vertices> detected_at;
  // Per object: the last detection evaluated the measure only where a bound of it reaches
  // what fracture acts on (docs/theory/fracture.md#before-the-break), 0 elsewhere;
  // Tracker::fracture_measure then evaluates it in full at detected_at, once (full_measure,
  // empty until asked).
  std::vector<char> partial;
  std::vector<Eigen::VectorXd> full_measure;
  // Per object: what the bound reads of the mesh and the model, kept until a split changes
  // the topology (empty until the first detection).
  std::vector<fracture_internal::BoundData> bound;
};
// Low enough that what fracture turns off is off for the frames that lead up to a break (with
// half the toughness, beam_break's trimmed fits kept its crack from going through).
constexpr double kFractureLiveRatio = 0.3;

struct TrackerState {
  RegistrationOptions options;
  std::vector<ObjectState> objects;
  int num_vertices = 0;
  Vertices x;         // #V by 3, all objects
  Vertices x_before;  // the result of the frame before the last (for the prediction)
  // The coverage and the residual (m) this sequence's trusted frames usually reach (running
  // means; 0: none yet): the confidence's scores are relative to them (registration/confidence.h).
  double coverage_reference = 0.0, residual_reference = 0.0;
  // Likewise the model->cloud pairs the trusted frames keep, and per object its volume over
  // its rest volume (empty: none yet).
  double pairs_reference = 0.0;
  std::vector<double> volume_reference;
  // The last frame's result that was not lost (empty before the first): a lost frame keeps it.
  Vertices last_good;
  bool held_before = false;  // the last frame was held or lost (its successor's move is no velocity)
  bool lost_before = false;  // the last frame was lost: initial_pose auto searches again
  // forces.adaptive_weight: the factor on forces.weight (in [kMinForceWeightScale, 1]) and
  // the misfit ratios of the frames solved at it (registration/force_weight.h).
  double force_weight_scale = 1.0;
  std::vector<double> misfit_ratios;
  Eigen::VectorXd mass;             // #V lumped masses
  Triangles surface;                // #F by 3, global indices
  std::vector<int> surface_vertices;
  std::vector<int> vertex_object;   // #V
  std::map<std::string, Anchor> anchors;
  // Contacts: null when collision is off or nothing can collide (then no hierarchy is built
  // and no contact term added).
  std::unique_ptr<CollisionWorld> collision;
  std::vector<Contact> contacts;
  // Per contact (Contact::source, object_b): its augmented-Lagrangian multiplier and
  // stiffness (docs/theory/contact.md#response), kept while it is detected, across frames.
  struct ContactMultiplier {
    double lambda = 0.0;       // N, the contact's force at zero penetration
    double stiffness = 0.0;    // N/m
    double penetration = 0.0;  // m, after the last solve
  };
  std::map<std::pair<int, int>, ContactMultiplier> contact_multipliers;
  std::unique_ptr<FractureState> fracture;
  // Mean length of the surface triangles' edges at rest (m): the length scale of the
  // step tolerances (solver.step_tolerance).
  double mean_edge_length = 0.0;
  Vertices frame_start;  // x when the frame's temporal springs were made (fracture only)
  int frame = 0;
  // Per object, for the outputs: distance of each surface vertex to the cloud and whether
  // it had a data pair in the last frame.
  std::vector<Eigen::VectorXd> residuals;
  std::vector<std::vector<char>> observed;
  // Per object: the external forces on its vertices in the last frame (N; FrameProblem::
  // ExternalForces), and where estimated forces may act (Tracker::SetForceRegion; per vertex
  // of the object as created, empty: its whole free surface).
  std::vector<Vertices> external_forces;
  std::vector<std::vector<char>> force_region;

  // The per-vertex arrays and the global surface from the objects (after Init and after a
  // topology change).
  void RebuildGlobalArrays();
  // Area-weighted unit normals of the surface vertices at x (#V by 3; zero elsewhere).
  Eigen::MatrixXd VertexNormals() const;
  // Object i's surface in the global numbering.
  Triangles ObjectSurface(int i) const;
};

inline bool FractureLive(const TrackerState& state) { return state.fracture && state.fracture->live; }

// The vertex move (m) that 99 % of each object's free vertices (those not `fixed`, by a hard
// anchor; empty: none) stay within, the largest over the objects; moves: per global vertex.
// A few vertices that hop between nearly equal pairings do not count; a moving part of more
// than 1 % of an object's vertices does, and so does one object moving beside a still one.
// Per object the ceil(0.99 n)-th smallest of its n free vertices' moves (with 100 or fewer,
// the largest); 0 when no vertex is free.
double BulkMove(const TrackerState& state, const Eigen::VectorXd& moves, const std::vector<char>& fixed);

// How crushed the most crushed element is at `to`: the smallest, over every object's elements,
// of the larger of (its volume at `to` / at `from`) and (its volume at `to` / at rest). An
// element counts only where it lost that share both since `from` and since rest (one already
// flat at `from` changes its ratio to `from` by little motions). Elements not positive at
// `from` left out; 1 when there is none.
double CrushedVolumeRatio(const TrackerState& state, const Vertices& from, const Vertices& to);

// solver.stiff_restart_volume with its automatic value (< 0) resolved: 0.1 with the forces
// estimated, where an equilibrium solve that starts from a crushed element stops against the
// inversion barrier's force (docs/notes/2026-12-01-soft-modes.md); else 0 (off).
double StiffRestartVolume(const RegistrationOptions& options, bool estimating_forces);

// Region id -> density of an object's materials (for ComputeLumpedMasses).
std::vector<std::pair<int, double>> RegionDensities(const ObjectMaterial& material);

}  // namespace femreg

#endif  // FEMREG_REGISTRATION_TRACKER_STATE_H_
