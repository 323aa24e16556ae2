// femreg/registration.h - options and results of registering meshes to point clouds.
// No PCL or Ceres type appears here: a caller includes femreg/tracker.h and links
// femreg::femreg.
#ifndef FEMREG_REGISTRATION_H_
#define FEMREG_REGISTRATION_H_

#include <Eigen/Core>
#include <string>
#include <vector>

#include "femreg/collision_spec.h"  // ContactForce, for FrameSummary::contact_forces
#include "femreg/energy.h"
#include "femreg/fem.h"
#include "femreg/fracture.h"  // FractureEvent, for FrameSummary::fractures
#include "femreg/mesh.h"
#include "femreg/solver.h"

namespace femreg {

// A point cloud in metres, in the same frame as the scene.
struct PointCloud {
  Vertices points;   // #P by 3
  Vertices normals;  // #P by 3, or empty when the source has none
  // #P per-point labels (a PCD "label" field: which object a point belongs to), or empty.
  Eigen::VectorXi labels;
  // Where the sensor was (a PCD file's VIEWPOINT origin), in the cloud's own frame before
  // preprocess.scale / transform. has_viewpoint false: unknown. The PCL default
  // "VIEWPOINT 0 0 0 1 0 0 0" counts as unknown (writers put it whatever the camera was).
  bool has_viewpoint = false;
  Eigen::Vector3d viewpoint = Eigen::Vector3d::Zero();
  bool has_normals() const { return normals.rows() == points.rows() && points.rows() > 0; }
  bool has_labels() const { return labels.size() == points.rows() && points.rows() > 0; }
  int size() const { return static_cast<int>(points.rows()); }
};

enum class DataMetric { kPointToPoint, kPointToPlane };
enum class Regularizer {
  kCorotational,  // corotational linear FEM (the default)
  kLinear,        // small-strain linear FEM
  kMassSpring,    // springs on the mesh edges, k = E V_edge / L^2 (for comparison)
  kNone,          // no elastic term: temporal (and anchors) only
};
// Where the first frame starts (registration.initial_pose). kGiven: the meshes as given.
// kAuto: the given pose unless it explains the first cloud badly; then a global search.
enum class InitialPose { kGiven, kAuto };
const char* ToString(RobustLoss v);
const char* ToString(DataMetric v);
const char* ToString(Regularizer v);
const char* ToString(TrustRegion v);
const char* ToString(SolverBackend v);
const char* ToString(LinearSolver v);
const char* ToString(Preconditioner v);
const char* ToString(InitialPose v);
bool FromString(const std::string& s, RobustLoss* v);
bool FromString(const std::string& s, DataMetric* v);
bool FromString(const std::string& s, Regularizer* v);
bool FromString(const std::string& s, TrustRegion* v);
bool FromString(const std::string& s, SolverBackend* v);
bool FromString(const std::string& s, LinearSolver* v);
bool FromString(const std::string& s, Preconditioner* v);
bool FromString(const std::string& s, InitialPose* v);

struct CameraOptions {
  bool enabled = false;                                 // known camera: enables visibility
  Eigen::Vector3d position = Eigen::Vector3d::Zero();   // camera centre in the scene frame (m)
  Eigen::Vector3d target = Eigen::Vector3d::UnitZ();    // the point the optical axis goes through
  Eigen::Vector3d up = -Eigen::Vector3d::UnitY();       // roughly "up" in the image (-y pixels)
  // Pinhole intrinsics (pixels), used by the virtual camera; not needed for registration.
  double fx = 525.0, fy = 525.0, cx = 319.5, cy = 239.5;
  int width = 640, height = 480;
  bool IsValid(std::string* error) const;
};

struct PreprocessOptions {
  // Applied first, to the points (and normals, viewpoint) as read: p' = R * scale * p + t,
  // R = rotation (axis * angle, rad). For clouds in other units (scale 0.001 for mm) or
  // another frame than the scene's.
  double scale = 1.0;                                   // > 0
  Eigen::Vector3d translation = Eigen::Vector3d::Zero();  // m
  Eigen::Vector3d rotation = Eigen::Vector3d::Zero();     // axis * angle (rad)
  bool crop = false;                                    // keep points inside [crop_min, crop_max]
  Eigen::Vector3d crop_min = Eigen::Vector3d::Constant(-1e30);
  Eigen::Vector3d crop_max = Eigen::Vector3d::Constant(1e30);
  double voxel_size = 0.0;                              // m; 0 = no downsampling
  // With voxel_size 0: clouds much denser than the mesh (more than auto_voxel_min_ratio
  // points per surface vertex) are subsampled on a voxel grid of auto_voxel * (the mean
  // surface edge length of the meshes at rest), one point per voxel (the one nearest the
  // voxel's centroid), weighted by the points it stands for, and all the weights scaled so
  // that (with the weight per pair, weights.data) the data term weighs what a cloud of
  // auto_voxel_min_ratio points per surface vertex would: a denser cloud adds no stiffness
  // (docs/theory/data-weight.md). auto_voxel_min_ratio 0 thins every cloud and keeps the
  // counts; auto_voxel 0 = off. The summary reports the voxel used (FrameSummary::voxel_size).
  // (Coarser voxels, or subsampling clouds of 3-10 points per surface vertex, cost accuracy
  // on the bundled datasets (docs/notes/2026-11-28-figures-from-code-comments.md).)
  double auto_voxel = 0.25;                             // >= 0, in mean surface edges
  double auto_voxel_min_ratio = 20.0;                   // >= 0
  // Flying pixels (docs/guide/depth-images.md#flying-pixels): with a camera
  // (registration.camera), the points of a depth image that lie between surfaces and that no
  // surface around them predicts within this many standard deviations of the depth's noise
  // (estimated from the image's second differences of depth; never below a sample footprint,
  // z / fx) are removed, before everything below.
  // 0 = off. Clouds that are not one depth image of the camera are left as they are.
  double flying_pixels = 4.0;                           // >= 0
  int outlier_neighbors = 0;                            // statistical outlier removal; 0 = off
  double outlier_stddev = 1.0;                          // ... threshold in standard deviations
  int normal_neighbors = 0;                             // estimate normals from k neighbours; 0 = off
  // Removes the dominant plane (a table) found by RANSAC: points within plane_distance (m)
  // of it are dropped, after cropping and before downsampling. 0 = off.
  double plane_distance = 0.0;
  int plane_iterations = 200;                           // RANSAC iterations (>= 1)
  // A depth offset common to a frame's pixels (a sensor's temporal flicker or drift;
  // docs/guide/depth-images.md#depth-offset): with a camera and the plane above, the plane is
  // taken as static, each frame's offset along the camera's rays is measured on the points it
  // removed, against its mean over the frames so far, and taken off every point left. Frames
  // whose plane turned or moved by more than plane_distance are not corrected.
  bool depth_offset = true;
  // A folder of segmentation masks for depth-image frames, one per frame named like it
  // (mask_dir/<frame name>.png; nonzero = the object): applied when a frame is read, before
  // everything above (ReadFrame with DepthImageOptions::mask_dir; `femreg register`).
  // PreprocessPointCloud does not use it. Empty: no masks. A scene file's relative path is
  // relative to the scene file's folder.
  std::string mask_dir;
  bool IsValid(std::string* error) const;
};

struct DataTermOptions {
  bool model_to_cloud = true;     // each surface vertex to its nearest cloud point
  bool cloud_to_model = true;     // each cloud point to its closest surface point
  double max_distance = 0.03;     // m; pairs farther apart are rejected; <= 0 disables gating
  RobustLoss loss = RobustLoss::kHuber;
  double loss_scale = 0.005;      // m; where the robust loss bends
  // Point-to-plane lets surfaces slide along each other, which converges in far fewer
  // outer iterations; model->cloud pairs use the cloud's normals, or the model's without.
  DataMetric metric = DataMetric::kPointToPlane;
  bool visibility = false;        // model->cloud only for vertices facing the camera
  int cloud_stride = 1;           // use every k-th cloud point for cloud->model (>= 1)
  // Safe partial views. Without a camera (camera.enabled false), model->cloud pairs are
  // only made for surface vertices facing the sensor: its position from the cloud file
  // (PCD VIEWPOINT, when not the default and outside the model's bounds), else a viewing
  // direction estimated from the side of the model the cloud lies on (none when the cloud
  // surrounds the model). auto_visibility false: no such test.
  bool auto_visibility = true;
  // Reciprocity, with or without a camera: a model vertex whose nearest cloud point is
  // farther than max(reciprocity * (the cloud's median point spacing), loss_scale) does not
  // pull (model->cloud); the cloud still pulls the model (cloud->model). Nor does a vertex
  // whose nearest cloud point has its own closest surface point away from the vertex (not
  // on a triangle touching the vertex's one-ring): another part of the model is that
  // point's. 0 = both off. Not applied while fracture is on (effects.fracture): an opening
  // crack is model surface with no cloud point near, and its pull is what separates the
  // pieces.
  double reciprocity = 5.0;
  // From this outer iteration on (counting from 0), the set of surface vertices with a model->cloud
  // pair is held for the rest of the frame: each keeps pulling to its nearest cloud point (within
  // max_distance) and no other vertex starts, whatever the trim and the visibility say. The pair
  // set then stops switching, and the outer iterations converge instead of cycling as vertices hop
  // across the trim (docs/theory/stopping.md, docs/notes/2026-11-28-figures-from-code-comments.md).
  // A rise of the energy stops a frame only from here on (solver.relative_energy_tolerance). 0 =
  // never held (rises then count from the second).
  int hold_pairs_after = 2;
  // Occluders (with a known camera): the cloud points of something in front of the model,
  // a hand or a tool the mask kept, pull nothing. A point whose camera ray meets the model
  // more than occluder_margin behind it, and that lies farther than that from the surface,
  // starts an occluder; the occluder takes in the points connected to it that are off the
  // model (docs/guide/partial-views.md#occluders). Each frame decides at its start. Not
  // with fracture on (a piece coming apart is a displacement no strain bounds).
  bool occluders = true;
  double occluder_margin = 0.02;  // m, > 0
  // Points the body cannot explain at a plausible strain: after an outer iteration, an
  // element stretched or compressed by more than this (the largest principal stretch's
  // distance from 1) against the frame's start, with an edge whose length changed by more
  // than the cloud's point spacing, marks the cloud points that pull on it and
  // lay off the model at the frame's start (a hand's fingers beside the object); they pull
  // nothing for the rest of the frame, which starts again without them
  // (docs/guide/partial-views.md#implausible-points). Not once fracture is live. 0 = off.
  double max_strain_step = 1.0;
  // Lost (FrameSummary::lost): a frame whose surface facing the sensor has cloud points near
  // on less than this share of what the sequence's trusted frames reach (FrameConfidence's
  // coverage), or that could not be solved, keeps the last good shape and is flagged
  // (docs/guide/tracking-loss.md). In [0, 1]; 0 = never lost.
  double lost_coverage = 0.3;
  // A cloud with fewer points (after preprocessing) than max(min_points,
  // min_points_per_surface_vertex * surface vertices) cannot constrain the object: the
  // frame keeps the prediction (TerminationType::kTooFewPoints).
  int min_points = 10;                      // >= 0
  double min_points_per_surface_vertex = 0.01;  // >= 0
  bool IsValid(std::string* error) const;
};

struct WeightOptions {
  // The data term's stiffness per unit of observed surface (N/m per m^2 = N/m^3): a point on
  // the model pulled d metres from the cloud over an area A stores 0.5 data_per_area A d^2.
  // Each cloud->model pair gets the rest area of its surface triangle shared among the
  // triangle's pairs, each model->cloud pair its vertex's third of the areas of the surface
  // triangles around it, so that a denser or sparser cloud of the same surface gives the
  // same energy (docs/theory/data-weight.md#per-area).
  double data_per_area = 2.0e7;
  // Model->cloud pairs weigh this fraction of data_per_area per unit area: they pair a
  // vertex with its nearest cloud point, which lies up to half the cloud's spacing off the
  // closest surface point, so at full weight a sparser cloud would bias the fit.
  double model_to_cloud_share = 0.03;
  // > 0: a model->cloud pair stands for at most this many times the cloud's area per point
  // (its vertex's nearest cloud point vouches for about its own patch of surface, not for
  // all of a coarse mesh's vertex area). With a strong share (0.3) a cap of 2 keeps coarse
  // meshes from being pulled off by their edges' and corners' biased pairs; it also makes the
  // model->cloud pull weaker on dense clouds, so the fit is no longer the same from a
  // denser or sparser cloud (docs/theory/data-weight.md#per-area). 0 = no cap (the default).
  double model_to_cloud_area_cap = 0.0;
  // A stiffness per correspondence (N/m), whatever the cloud's density: the default, while
  // the per-area weight costs accuracy on occluded sequences and under many outliers
  // (docs/theory/data-weight.md, docs/notes/2026-11-data-weight.md). < 0: data_per_area is used
  // instead (a scene that sets data_per_area).
  double data = 200.0;
  // With the weight per pair (data >= 0): where an object has more model->cloud pairs than
  // cloud points behind its cloud->model pairs (its mesh is finer than the cloud; a voxel
  // counts its weight, preprocess.auto_voxel's, a cloud_stride its stride), each of its model->cloud
  // pairs weighs data times (those points / model->cloud pairs), so that the model->cloud
  // term pulls no harder in all than one pair per cloud point, however fine the mesh. Each
  // surface vertex pairs with its nearest cloud point, which on a sparse cloud lies up to
  // half the cloud's spacing off the surface; without the balance a mesh refined under the
  // same cloud is pulled ever harder towards those points (docs/performance/scaling.md).
  // Where the cloud is the denser (every bundled dataset), nothing changes; nor for an object
  // with no cloud->model pair (data.cloud_to_model off).
  bool model_to_cloud_balance = true;
  double elastic = 1.0;    // w_elastic, multiplies the FEM energy (J)
  // The inversion barrier (docs/theory/inversion.md): every element compressed below
  // barrier_volume of its rest volume stores w_elastic barrier V mu (j - J)^2 log(j / J),
  // which no step can cross to a flat or inverted element. 0 = off.
  double barrier = 1.0;          // >= 0, in units of each element's shear modulus
  double barrier_volume = 0.2;   // j, in (0, 1)
  double temporal = 1.0;   // w_temporal, multiplies 0.5 sum m_i |x_i - x_i^prev|^2 (kg m^2)
  double anchor = 1.0e4;   // soft anchors: 0.5 w |x_i - target_i|^2 per vertex (N/m)
  bool IsValid(std::string* error) const;
};

struct SolverOptions {
  int max_outer_iterations = 8;          // correspondences and rotations refreshed per outer iteration
  int max_inner_iterations = 10;         // Ceres iterations / fast Gauss-Newton steps per outer iteration
  // An inner solve stops when a step changes the energy by less than this fraction (Ceres' function
  // tolerance). Steps smaller than that are worth less than new rotations and pairs: a tighter
  // tolerance costs inner iterations for the same vertex errors with either back end, a looser one
  // costs Ceres accuracy (docs/notes/2026-11-28-figures-from-code-comments.md).
  double inner_tolerance = 1e-3;
  // The frame stops when an outer iteration changed the energy by less than this fraction
  // of it from the previous outer iteration (stopped_by "energy"), or raised it by more
  // (stopped_by "energy_rise") once the model->cloud pair set is held (hold_pairs_after),
  // by at most 10 % and with no vertex moving as far as a mean surface edge: the outer
  // iterations then cycle among nearly equal pairings (docs/theory/stopping.md). 0: neither...
  double relative_energy_tolerance = 1e-3;
  // ... or moved no vertex farther than this fraction of the mesh's mean surface edge length.
  // Inner solves of the fast back end stop at a tenth of it.
  double step_tolerance = 0.01;
  // ... or moved 99 % of each object's free vertices (those not held by a hard anchor) no
  // farther than this fraction of the coarser of the two resolutions, the mean surface edge
  // length and the cloud's sampling distance (twice its median point spacing), and no
  // farther than the fit's RMS residual (stopped_by "bulk_step"): the largest move alone
  // never settles where a few vertices hop between nearly equal pairings (a sparse cloud on
  // a fine mesh), and the outer iterations then go on creeping for no gain in the fit; nor
  // does the fit resolve the shape finer than the cloud samples it, nor than it misses the
  // cloud by (docs/theory/stopping.md, docs/notes/2026-11-28-bulk-step.md). 0 = off.
  double bulk_step_tolerance = 0.05;
  // A frame whose outer iterations before the pair set is held (data.hold_pairs_after) leave
  // an element with less than this fraction of the volume it had at the frame's start starts
  // again stiff, as after a large motion (docs/theory/stopping.md#large-motions): the pairs
  // were wrong at that distance. An element counts where it is below the fraction of both its
  // start and its rest volume (FrameSummary::crushed_restarts). 0 = off. Negative (the
  // default): automatic, 0.1 with the forces estimated and off otherwise. The classic energy
  // goes on past a crushed element, and the restart helps a soft or fine mesh bent a few mm
  // but costs hand_press time and accuracy (docs/notes/2026-12-01-crushed-first-steps.md);
  // an equilibrium solve that starts from one is held by the inversion barrier's force and
  // stops without getting out (docs/notes/2026-12-01-soft-modes.md).
  double stiff_restart_volume = -1.0;
  double time_budget_s = 0.0;            // per frame; 0 = none
  // Which back end minimizes each outer iteration (both take every term, contacts included,
  // and reach the same minimum). The fast one by default: the same vertex errors in much less
  // time (docs/performance/accuracy.md). A scene that sets trust_region or linear_solver
  // (Ceres' settings) without a backend gets Ceres.
  SolverBackend backend = SolverBackend::kFast;
  TrustRegion trust_region = TrustRegion::kLevenbergMarquardt;
  LinearSolver linear_solver = LinearSolver::kSparseNormalCholesky;
  // Threads of every parallel part (element loops, correspondences, CHOLMOD's BLAS, Ceres);
  // 0: per frame, the hardware threads that other processes leave free (at least 1;
  // docs/guide/busy-machines.md). The fast back end's results are the same on any count.
  int num_threads = 0;
  // Fast back end: conjugate-gradient iterations preconditioned by the kept factorization
  // before a step factorizes anew (0: factorize every step).
  int max_pcg_iterations = 20;
  // Fast back end: what preconditions those iterations. auto: smoothed-aggregation
  // multigrid where the sparse factor would hold 6 or more entries per entry of the system
  // (large, compact meshes: ~3k vertices and up), else the kept factorization
  // (docs/dev/fast-backend.md); factor; multigrid. With multigrid a step runs up to 100 iterations
  // with the kept hierarchy and 100 with a new one, whatever max_pcg_iterations says (0 still
  // means: factorize every step, no multigrid).
  Preconditioner preconditioner = Preconditioner::kAuto;
  // Start each frame from a constant-velocity extrapolation of the last two frames.
  bool predict_motion = true;
  // From the held pair set on, halve an outer iteration's move while the energy with the pairs
  // it finds rose (docs/theory/stopping.md#backtracking). Not with fracture on.
  bool backtrack = true;
  // From the held pair set on, cut an outer iteration's move that reverses the last one to
  // where the two-cycle's fixed point is estimated (docs/theory/stopping.md#reversals). Not
  // once fracture is live.
  bool cut_reversals = true;
  // Each outer iteration's move leaves out the turn of an object nothing holds about the axes
  // its surface does not show (a ball's about its centre, a cylinder's about its axis): no
  // data decides it, so the registration does not make it (docs/theory/stopping.md#hidden-turns).
  bool hold_hidden_turns = true;
  bool rigid_prealign = false;           // rigid ICP step before the non-rigid solve
  int rigid_iterations = 30;
  bool IsValid(std::string* error) const;
};

// Equilibrium registration (docs/theory/equilibrium.md): the shape is held in equilibrium
// under its elastic forces, gravity and loads, its clamps and anchors, its contacts, and
// external forces estimated every frame, which act only on the free surface (or a region of
// it: Tracker::SetForceRegion) and are penalized; the data pull it only through them. Both
// back ends solve it.
struct ForceOptions {
  bool estimate = false;
  // Without `estimate`: a frame whose cloud holds an occluder (points in front of the visible
  // surface, found with a camera: a hand or a tool that the mask kept) that touches the body's
  // points after its first outer iteration, itself or through the points found implausible
  // beside the body (data.max_strain_step; also the last frame's, carried, after a frame so
  // registered), is registered with the forces estimated, the others without
  // (FrameSummary::forces_estimated). Where the hand holds the body, its points
  // beside the silhouette look like the body's, and the classic energy pulls the surface into
  // them; with the forces estimated that pull needs a force nobody applies there
  // (docs/guide/forces.md#when-a-hand-holds-the-body).
  bool when_occluded = true;
  // In the frames when_occluded registers with the forces estimated, the forces push only, as
  // with pushing_only (friction as set there): what holds the body is a hand, which pushes and
  // grips but cannot pull (docs/guide/forces.md#when-a-hand-holds-the-body).
  bool when_occluded_pushing_only = true;
  // The penalty on the surface tractions, 1/2 weight * c * integral |t|^2 dA, with c the scale
  // at which a traction costs about as much as the data misfit it removes (the data stiffness
  // per area times (L / E)^2, L the body's size, E its Young's modulus): smaller lets larger
  // forces act, larger holds the shape nearer its unforced equilibrium. > 0.
  double weight = 1.0;
  // The weight adapts from frame to frame to the misfit the forces leave: where the cloud's
  // RMS residual exceeds the classic fit's (the frame's warm start) by more than
  // misfit_ratio over recent frames, the forces are held too tightly and the weight falls
  // (down to 1/100 of `weight`); where they leave almost none, it rises back, never above
  // `weight` (docs/guide/forces.md#choosing-the-weight).
  bool adaptive_weight = false;
  double misfit_ratio = 1.2;  // > 1
  // A group-L1 term on the nodal forces, in the same scale times a traction of 1% of E:
  // > 0 makes the forces localise to few vertices (the contact area finds itself). >= 0.
  double sparsity = 0.0;
  // Forces only push (point into the body): a hand cannot pull.
  bool pushing_only = false;
  // With pushing_only: the tangential force is at most friction times the normal one
  // (Coulomb's cone); < 0: any tangential force.
  double friction = -1.0;
  // The weight where no force may act (inside the body, off the region) and on a pushing-only
  // force's pulling part, over `weight`: large enough to hold equilibrium there to a fraction
  // of the forces elsewhere, and no larger: a stiffer penalty takes more Gauss-Newton steps
  // (docs/notes/2026-12-01-equilibrium-balance.md). >= 1.
  double balance = 1e3;
  bool IsValid(std::string* error) const;
};

// Free space (docs/theory/data-terms.md#free-space): with a sensor position or direction (the
// camera, a file's viewpoint, or the direction estimated for visibility), the rays to the
// cloud's points passed through empty space. A surface vertex nearer to the sensor than the
// observed depth at its pixel by more than `tolerance` is pushed back along its ray by a
// one-sided penalty of stiffness `weight` (N/m per vertex). Pixels where nothing was observed
// hold nothing. Re-decided every outer iteration, with the pairs.
struct FreeSpaceOptions {
  bool enabled = true;
  double tolerance = 0.01;  // m, > 0
  double weight = 1.0e4;    // N/m per vertex, > 0 (as a contact's penalty)
  bool IsValid(std::string* error) const;
};

struct RegistrationOptions {
  Regularizer regularizer = Regularizer::kCorotational;
  CameraOptions camera;
  PreprocessOptions preprocess;
  DataTermOptions data;
  WeightOptions weights;
  SolverOptions solver;
  ForceOptions forces;
  FreeSpaceOptions free_space;
  // The scene's gravity (on the lumped masses) and nodal loads act in the registration
  // energy as they do in simulate (Tracker::Create(scene); Tracker::SetExternalLoads).
  bool loads = true;
  // auto: on the first frame (and the first after a lost one: data.lost_coverage, the last good
  // shape standing for the given pose), an object without anchors whose given pose leaves the cloud
  // farther from its surface than data.loss_scale (the trimmed mean of the cloud->surface
  // distances, plus with a sensor position that of the surface facing it to the cloud) is
  // posed by a global search (FPFH features, RANSAC over pairs of oriented points from a fixed
  // seed, the best hypotheses refined by rigid ICP), if that explains the cloud at least twice
  // as well
  // (docs/guide/scene-files.md#initial-pose). A pose that explains it well is kept, so that
  // aligned scenes run as with given.
  InitialPose initial_pose = InitialPose::kAuto;
  bool IsValid(std::string* error) const;  // names the first bad field, e.g. "data.loss_scale"
};

enum class TerminationType {
  kNotRun,
  kConverged,          // relative energy change below tolerance
  kMaxIterations,      // outer iteration limit reached
  kTimeBudget,         // the frame's time budget ran out
  kNoCorrespondences,  // no usable data: the shape was held by the temporal term
  kSolverFailure,      // Ceres failed; the previous shape was kept
  kInvalidInput,       // e.g. every cloud point was NaN
  kTooFewPoints,       // too few points to constrain the object: the prediction was kept
  kStalled,            // a stop rule held, but the last solve could not move (its steps refused)
};  // kStalled last: register's count of terminations runs up to it
const char* ToString(TerminationType t);

struct OuterIteration {
  int iteration = 0;
  EnergyTerms before, after;
  int model_to_cloud = 0;       // pairs kept this iteration
  int cloud_to_model = 0;
  int rejected = 0;             // pairs gated out by distance
  int inner_iterations = 0;
  int contacts = 0;             // contact residuals added (collision on)
  double rms_residual = 0.0;    // m, over kept pairs, after the solve
  double max_move = 0.0;        // m, the largest vertex move of the solve
  double bulk_move = 0.0;       // m, the move 99 % of each object's free vertices stay within
  double time_s = 0.0;
  // The solve refused most of its steps and left the largest force (the energy's gradient)
  // above half of where the frame's first solve started (docs/theory/stopping.md#stalled).
  bool stalled = false;
};

// Wall time per stage of one frame (s). prealign: solver.rigid_prealign and, on the first
// frame, registration.initial_pose auto's check and search.
struct StageTimes {
  double preprocess = 0.0, prealign = 0.0, rotations = 0.0, correspondences = 0.0,
         build = 0.0, solve = 0.0, total = 0.0;
  // Inside solve: assembling gradient and system, factorizations (with the multigrid
  // preconditioner: building its hierarchies), linear solves (PCG with the factor's
  // triangular solves or multigrid V-cycles; Ceres: its whole linear solver), energy
  // evaluations.
  double assembly = 0.0, factorization = 0.0, linear_solve = 0.0, evaluation = 0.0;
  double collision = 0.0;  // contact detection (refit, broad and narrow phase)
  double fracture = 0.0;  // detection and splits (0 when effects.fracture is off)
  // After the outer iterations: the per-vertex outputs (residuals, observed), the confidence,
  // the implausible points carried to the next frame and the external forces.
  double outputs = 0.0;
};

// How far a frame's result can be trusted, from what the frame has (no ground truth;
// docs/guide/tracking-loss.md): `confidence` = fit x coverage score x residual score x
// 1 / (1 + strain^4) x volume score x pairs score, in [0, 1]; 0 when the frame could not be
// solved (held or predicted). The coverage score is min(1, coverage / what the sequence's
// trusted frames reach), the residual score min(1, 2 x their residual / residual), the
// volume score min(1, 0.02 / volume_change), the pairs score min(1, (model->cloud pairs /
// 0.6 x what the trusted frames keep)^2); the first solved frame sets all four references.
struct FrameConfidence {
  double confidence = 0.0;
  double fit = 0.0;       // share of the cloud's points near the model (within data.max_distance,
                          // occluders left out) within the tolerance of its surface
  double coverage = 0.0;  // share of the sensor-facing surface vertices with a cloud point within it
  double residual = 0.0;  // m: rms distance from the surface of the better-fitting half of them
  double strain = 0.0;    // 95th percentile over the elements of max |principal stretch - 1|
  // The largest relative change over the objects of the volume against what the sequence's
  // trusted frames keep (|V / V_reference - 1|): junk all round a fit inflates it in one frame.
  double volume_change = 0.0;
};

struct FrameSummary {
  int frame = -1;
  SolverBackend backend = SolverBackend::kCeres;  // the back end that solved the frame
  TerminationType termination = TerminationType::kNotRun;
  std::string message = "Tracker::Track was not called.";
  int cloud_points = 0;           // as given
  int nonfinite_dropped = 0;      // NaN / inf points removed
  int flying_pixels = 0;          // removed as flying pixels (preprocess.flying_pixels)
  double depth_offset = 0.0;      // m taken off every point's depth (preprocess.depth_offset)
  int points_used = 0;            // after preprocessing
  double voxel_size = 0.0;        // m: the automatic subsampling's voxel (0: not applied)
  int occluded_points = 0;        // points of an occluder in front of the model (data.occluders)
  // Surface vertices held back by free space at the result (registration.free_space): in
  // front of the observed depth by more than its tolerance.
  int free_space_vertices = 0;
  // How model->cloud pairs were restricted to what the sensor could see: "camera",
  // "viewpoint" (from the file), "direction (x, y, z)" (estimated), "none"; plus the
  // reciprocity trim's distance (m; 0 = off) and the fraction of the surface vertices
  // that have a cloud point within it (the coverage; 1 without a trim).
  std::string visibility = "none";
  double trim_distance = 0.0;
  double coverage = 1.0;
  // The first frame with registration.initial_pose auto, and the first after a lost one (the
  // last good pose is then the given one): "given" (the given pose explained
  // the cloud), "given, searched" (it did not, and no global pose did better), "global" (a
  // global pose replaced it); empty otherwise. pose_ambiguous: a global pose replaced the
  // given one, and the two best distinct poses (rotations more than 20 deg apart) explained
  // the cloud about equally well, as a symmetric object's do.
  std::string initial_pose;
  bool pose_ambiguous = false;
  EnergyTerms initial, final;
  // The resultant of the external forces on the objects (N) and its moment about their
  // centroid (the mass-weighted mean of the vertices; N m): the forces estimated
  // (registration.forces.estimate) and the contacts', without gravity, the loads and the
  // clamps' and anchors' reactions; without forces.estimate, the data term's pull and the
  // contacts' push. Per
  // vertex: Tracker::external_forces.
  Eigen::Vector3d force = Eigen::Vector3d::Zero(), torque = Eigen::Vector3d::Zero();
  // With the forces estimated: the forces.weight this frame's penalty used (adapted with
  // forces.adaptive_weight), and the cloud's RMS residual over the classic fit's that started
  // the frame (its warm start's shape, with the pairs found there; 0: not measured).
  double force_weight = 0.0, misfit_ratio = 0.0;
  bool forces_estimated = false;  // this frame's mode (forces.estimate or forces.when_occluded)
  // With forces.pushing_only: the frame solved the pushing-only problem from its first outer
  // iteration, without the warm start and the smooth start
  // (docs/theory/equilibrium.md#where-a-pushing-only-frame-starts).
  bool quiet_start = false;
  int outer_iterations = 0, inner_iterations = 0;
  int backtracks = 0;  // outer-iteration moves halved because the energy rose (stopped_by)
  // Outer-iteration moves cut short because they reversed the last one (a two-cycle:
  // docs/theory/stopping.md#reversals).
  int reversals = 0;
  // 1 when the first outer iteration moved the bulk of the vertices (99 %) more than 3 mean
  // edges, or the frame came after held or lost ones, and the frame started again, stiff and
  // stepping down (docs/theory/stopping.md#large-motions).
  int large_motion_restarts = 0;
  // 1 when, with solver.stiff_restart_volume, an outer iteration before the pair set was held
  // crushed an element and the frame started again in the same way.
  int crushed_restarts = 0;
  // Cloud points found implausible (data.max_strain_step) and the frame's restarts for them;
  // of those points, the ones near the last frame's implausible ones, left out from the start.
  int implausible_points = 0, implausible_restarts = 0, implausible_carried = 0;
  FrameConfidence confidence;
  // The object was not found (data.lost_coverage): the result is the last good frame's shape.
  bool lost = false;
  // Fast back end: factorizations (or multigrid hierarchies built), preconditioner
  // applications, conjugate-gradient iterations.
  int factorizations = 0, linear_solves = 0, pcg_iterations = 0;
  // Which criterion ended the frame: "step" (solver.step_tolerance), "bulk_step"
  // (solver.bulk_step_tolerance), "energy" or
  // "energy_rise" (solver.relative_energy_tolerance: the energy changed by less than it, or
  // rose by more without motion, see there), "backtrack" (the energy with the pairs found
  // after an outer iteration rose, and so it did along an eighth of its move: the frame keeps
  // that iteration's start; docs/theory/stopping.md), or the termination's name otherwise.
  std::string stopped_by;
  int model_to_cloud = 0, cloud_to_model = 0, rejected = 0;  // last outer iteration
  double rms_residual = 0.0;      // m
  // Collision (effects.collision), from the signed gaps g of the contacts detected within D
  // at the result (femreg/collision.h): touching contacts (g < collision.tolerance), split
  // into object-object and object-obstacle; the deepest penetration max(0, -min g) and the
  // smallest gap min g (m; D when nothing is within D).
  int contacts = 0, object_contacts = 0, obstacle_contacts = 0;
  double max_penetration = 0.0;
  double min_gap = 0.0;
  // The contact forces at the result per object pair and obstacle (N; normal and friction
  // parts; a pair's on its lower-numbered object), from the penalty and friction blocks the
  // last solve minimized (docs/theory/contact.md#what-is-reported).
  std::vector<ContactForce> contact_forces;
  StageTimes time;
  std::vector<OuterIteration> iterations;
  std::vector<FractureEvent> fractures;  // node splits this frame (effects.fracture)

  std::string BriefReport() const;  // one line
  std::string FullReport() const;   // a row per outer iteration and the stage times
  bool IsSolutionUsable() const;
};

}  // namespace femreg

#endif  // FEMREG_REGISTRATION_H_
