// The Tracker's state and parts behind its public face (femreg/tracker.h): the frame loop
// lives in tracker.cc, the set-up calls (labels, effects, anchors, loads, force regions) in
// tracker_setup.cc, the forces after a frame in tracker_forces.cc.
#ifndef FEMREG_REGISTRATION_TRACKER_IMPL_H_
#define FEMREG_REGISTRATION_TRACKER_IMPL_H_

#include <chrono>
#include <functional>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include "femreg/tracker.h"
#include "geometry/nearest.h"
#include "parallel/stopwatch.h"
#include "registration/correspondences.h"
#include "registration/depth_offset.h"
#include "registration/embedded_surface.h"
#include "registration/frame_problem.h"
#include "registration/tracker_state.h"
#include "solvers/backend.h"

namespace femreg {

struct Tracker::Impl {
  using Clock = std::chrono::steady_clock;

  TrackerState state;
  FrameProblem frame_problem;
  std::unique_ptr<Backend> backend;
  ModelIndex model_index;
  double mean_edge = 0.0;  // m, at rest: the auto voxel and the model index's tolerance
  DepthOffset depth_offset;  // preprocess.depth_offset, over the frames tracked

  Status Init(std::vector<TetMesh> meshes, const std::vector<ObjectMaterial>& materials);
  Status Track(const PointCloud& input, FrameSummary* summary);
  // The frame's cloud: transformed, preprocessed and subsampled (s: counts, voxel, time).
  void PrepareCloud(const PointCloud& input, FrameCloud* fc, FrameSummary* s);
  // A frame that cannot be solved: the shape stays at state.x (held or predicted).
  void Hold(TerminationType t, const std::string& message, const PointIndex* index,
            Clock::time_point t_frame, FrameSummary* s);
  // The corotational elements' rotations at state.x.
  void UpdateElementRotations(FrameSummary* s);
  // Pairs, loads, contacts and the equilibrium terms at state.x for outer iteration k; false
  // when no pair is left (at k = 0 the summary says so).
  // `previous`: the last frame's result (friction's slip is from there).
  bool PrepareIteration(int k, const FrameCloud& fc, const Vertices& previous, std::vector<DataPair>* pairs,
                        PairCounts* counts, femreg::OuterIteration* row, FrameSummary* s);
  // Whether outer iteration k solves the energy without the equilibrium terms though the
  // forces are estimated (up to warm_until): the frame's first (not in a QuietStart's frame),
  // and after a large motion's (or a crushed element's) restart its stiff stages and the first
  // outer iteration after them, so that the force residual's Gauss-Newton starts near
  // (docs/theory/equilibrium.md#solving-it).
  bool WarmStart(int k) const;
  // Whether a frame with forces.pushing_only, right after a quiet one (quiet_next), solves the
  // pushing-only problem from its first outer iteration, at its predicted start, without the
  // warm start and the smooth start, on the fast back end: every object is clamped, nothing is
  // breaking, the weight does not adapt (its reference is the warm start's fit), and no back-off
  // is running. The frame's first pairs then decide (QuietPairs). Near the last frame's
  // equilibrium the two starts cost more than they bring
  // (docs/theory/equilibrium.md#where-a-pushing-only-frame-starts).
  bool QuietStart() const;
  // ... whose first pairs' RMS residual is at most kQuietMisfit times the last frame's final one:
  // the cloud did not jump.
  bool QuietPairs(const std::vector<DataPair>& pairs);
  // Whether this frame moved its vertices from `previous` (its start before the prediction) by
  // little: at most kQuietMeanMove mean edges on average and kQuietLargestMove at most.
  bool MovedLittle(const Vertices& previous) const;
  // After a frame: its cost (factorizations, and PCG iterations at kPcgPerFactorization
  // a factorization); a quiet start that cost more than the last warm start backs off.
  void CountQuietCost(bool quiet, const FrameSummary& s);
  // Whether outer iteration k, the first after a warm start or after a fracture split, solves
  // the equilibrium without forces.pushing_only's penalty (two steps at most): from the warm
  // start's shape, which the data pulled where they liked, that penalty's kinks and stiffness
  // held Gauss-Newton back for many steps and left it at shapes that only pulling forces hold;
  // from the unrestricted equilibrium only the pulls are left to undo
  // (docs/theory/equilibrium.md#where-a-pushing-only-frame-starts).
  bool SmoothStart(int k) const;
  // Whether this frame's estimated forces push only: forces.pushing_only, or
  // forces.when_occluded_pushing_only in a frame forces.when_occluded switched.
  bool PushingOnly() const;
  // The frame problem's energy at x on the frame's threads (the sum does not depend on them).
  EnergyTerms Energy(const Vertices& x) const;
  // The pairs' RMS distance (m) at state.x (on the data surface where there is one).
  double RmsResidual(const std::vector<DataPair>& pairs);
  // forces.adaptive_weight's check before a lower weight (kLowerWeightKeeps): the frame's last
  // solve again at `lower_scale`, from its result with its pairs; the frame's result and the
  // problem are left as they were.
  bool LowerForceWeightPays(double lower_scale, const std::vector<DataPair>& pairs, Clock::time_point t_frame,
                            FrameSummary* s);
  // Whether the frame has used solver.time_budget_s (then *s says so).
  bool TimeBudgetUsed(Clock::time_point t_frame, FrameSummary* s) const;
  // forces.when_occluded: after outer iteration k - 1, whether the frame goes on with the forces
  // estimated (an occluder touches the body; docs/guide/forces.md#when-a-hand-holds-the-body).
  void SwitchToForcesWhereHeld(int k, const FrameCloud& fc, double* previous_energy, FrameSummary* s);
  // Back to `start`, the ordinary schedule from outer iteration `base` (iteration_base, the
  // cap, where an energy rise may stop it), no warm pairs, no misfit or stall reference.
  void StartAgain(const Vertices& start, int base);
  // A stiff start's stages (stepping_in): before outer iteration k, the elastic weight's scale.
  void StepIn(int k, double* previous_energy);
  // After outer iteration k, a large motion's restart (or a crushed element's): back to `start`,
  // stiff, then softer stage by stage (docs/theory/stopping.md#large-motions).
  void RestartStiff(int k, bool large_motion, bool go_on, const Vertices& start, FrameCloud* fc, FrameSummary* s);
  // The contacts' multipliers at the frame's start: a frame that switches to the forces
  // estimated (forces.when_occluded) takes them back, undoing its classic first outer
  // iteration's update as a warm start's is not made (docs/theory/contact.md#response).
  std::map<std::pair<int, int>, TrackerState::ContactMultiplier> multipliers_at_start;
  // After outer iteration k (not stepping in): the cloud points that pulled elements past
  // data.max_strain_step are marked (MarkImplausible, from `faces`' view); the frame goes on
  // without them, or starts again from `start` when they are many.
  void MarkImplausibleOrRestart(
      int k, const Vertices& start, const std::function<bool(const Eigen::Vector3d&, const Eigen::Vector3d&)>& faces,
      FrameCloud* fc, double* previous_energy, FrameSummary* s);
  // Whether outer iteration k holds its start against the last one's (Backtrack).
  bool Backtracks(int k, bool warm_start) const;
  // From the held pair set on, the energy at state.x with the rotations, pairs and contacts it
  // finds must not rise above the last solve's start (merit): else the move is halved back
  // towards that start (docs/theory/stopping.md#backtracking). False: the frame stops (the
  // summary says why).
  bool Backtrack(int k, const FrameCloud& fc, const Vertices& previous, std::vector<DataPair>* pairs,
                 PairCounts* counts, femreg::OuterIteration* row, double* previous_energy, FrameSummary* s);
  // After outer iteration k's solve from before_solve (energy start_energy with its pairs), before
  // merit_x takes this start: a move that reverses the last one is cut to where the two-cycle's
  // fixed point is estimated (docs/theory/stopping.md#reversals), *row's energy then the cut's.
  // `comparable`: the last outer iteration's energy (merit) compares with this one's. True when
  // it was cut; the stopping rules then measure the cut move.
  bool CutReversal(int k, bool comparable, const Vertices& before_solve, double start_energy,
                   femreg::OuterIteration* row, FrameSummary* s);
  // One outer iteration k; false when the frame stops (the summary says why).
  bool OuterIteration(int k, const FrameCloud& fc, Clock::time_point t_frame,
                      std::vector<DataPair>* pairs, double* previous_energy, Vertices* previous,
                      FrameSummary* s);
  // The contacts the result keeps and the deepest penetration (collision on).
  void MeasureContacts(FrameSummary* s);
  // The external forces on the result: per vertex (state.external_forces) and their resultant.
  void MeasureForces(FrameSummary* s);
  // Embedded surfaces (SetEmbeddedSurface): per object, none while its rest has no rows; the
  // data surface made of them (null: none) and its closest-point index.
  std::vector<EmbeddedSurface> embedded;
  std::unique_ptr<DataSurface> data_surface;
  ModelIndex data_index;
  // The surface the pairs, the visibility and the occluders are found on: the data surface at
  // state.x, or the meshes' own (state).
  const TrackerState& PairState() { return data_surface ? data_surface->Update(state.x) : state; }
  const SurfaceIndex& Surface() {
    if (data_surface) return data_index.Get(PairState(), 0.1 * data_surface->view().mean_edge_length);
    return model_index.Get(state, 0.1 * mean_edge);
  }
  // Contacts: the spec and names EnableCollision was given (an embedded surface set later
  // builds the world again), and the positions the world detects on: the meshes' vertices,
  // then the data surface's when there is one (an embedded surface meets the obstacles there;
  // docs/theory/embedded-surfaces.md#contacts).
  CollisionSpec collision_spec;
  std::vector<std::string> collision_names;
  Vertices collision_x;
  Status BuildCollision();
  const Vertices& CollisionPositions();
  // UpdateOutputs with the frame's pairs (on the data surface if there is one, updated to
  // state.x for the confidence).
  void Outputs(const PointIndex* cloud_index, const std::vector<DataPair>& pairs);
  // Per cloud query of this frame, the triangle of its last cloud->model hit (FindPairs).
  std::vector<int> warm_triangles;
  // With an embedded surface, whether the frame starts from the prediction: not where the
  // new cloud lies farther from it than from the last result (the motion stopped or turned
  // back; docs/notes/2026-11-30-fine-scans.md). Without one, always.
  bool PredictionFits(const Vertices& predicted, const FrameCloud& fc, FrameSummary* s);
  std::vector<char> paired_vertices;
  // The first outer iteration of this frame whose energy rise may stop it: where the pair
  // set is held (data.hold_pairs_after), again after a fracture split.
  int rise_from = 1;
  // The frame's outer iterations: the ordinary schedule's first (after a large motion's stiff
  // start), the cap, and whether the elastic weight is still stepping down
  // (docs/theory/stopping.md#large-motions).
  int iteration_base = 0;
  int iteration_limit = 0;
  int warm_until = 0;            // WarmStart's last outer iteration
  // This frame solves the pushing-only problem from its first outer iteration (QuietStart),
  // unless its first pairs or a stiff restart decide otherwise.
  bool quiet_start = false;
  // The last frame converged without a restart and moved little (MovedLittle), and its pairs'
  // RMS residual (m).
  bool quiet_next = false;
  double last_frame_rms = 0.0;
  // The cost (CountQuietCost) of the last frame that made the warm start (< 0: none yet), and
  // the frames left before QuietStart may choose again after a quiet start cost more.
  double last_warm_cost = -1.0;
  int quiet_backoff = 0;
  // This frame's mode: forces.estimate, or forces.when_occluded and an occluder in its cloud.
  bool estimate_forces = false;
  // The last frame was solved with the forces estimated by forces.when_occluded's switch
  // (SwitchToForcesWhereHeld): its implausible points, carried, are a hand's.
  bool switched_before = false;
  int smooth_after_split = -1;   // the outer iteration after a fracture split, or -1 (SmoothStart)
  // The RMS residual (m) at the end of the frame's last warm start, with the pairs found there
  // (0: none yet this frame): the classic fit's misfit (FrameSummary::misfit_ratio).
  double misfit_reference = 0.0;
  Vertices misfit_reference_x;  // that warm start's shape
  // The largest force (gradient entry, N) where the frame's first solve started (0: none yet):
  // a later solve that refused most of its steps and left more than half of it stalled
  // (docs/theory/stopping.md#stalled).
  double stall_reference = 0.0;
  // A frame's start, and a restart's: the misfit and the forces of another shape or pair set
  // are no reference.
  void ResetStartReferences() {
    misfit_reference = 0.0;
    misfit_reference_x.resize(0, 3);
    stall_reference = 0.0;
  }
  // Frames held or lost since the last one solved: the next solved frame catches up with
  // their motion too, and has iteration_budget outer iterations from each start (a restart
  // counts again): solver.max_outer_iterations per frame it makes up for, up to
  // kMaxCatchUpFrames (docs/guide/tracking-loss.md#coming-back).
  int missed_frames = 0;
  int iteration_budget = 0;
  bool stepping_in = false;
  int stiff_stages = 0;  // of a stiff start (RestartStiff), 0 before one
  int stiff_from = 1;    // the outer iteration of the first stiff stage
  // The occluders are decided again before this outer iteration (ReleaseReached): until the
  // pair set is held, counted again from a stiff start's end.
  int redecide_until = 0;
  // The weight of the points marked implausible when the frame last started (again): what is
  // marked since is held against kImplausibleRestartShare, in one go or a few at a time.
  double implausible_at_start = 0.0;
  double first_bulk_move = 0.0;  // m, of the frame's first outer iteration (BulkMove)
  // The last solved frame's implausible cloud points (CarryImplausible); none after a held or
  // lost frame, or with fracture live.
  Vertices implausible_before;
  // The last outer iteration's start and its energy with what it found (Backtrack).
  Vertices merit_x;
  PointCloud prepared_cloud;  // Tracker::prepared_cloud
  double merit = 0.0;
};

}  // namespace femreg

#endif  // FEMREG_REGISTRATION_TRACKER_IMPL_H_
