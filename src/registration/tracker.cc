// The Tracker: one frame is a few outer iterations of (rotations, correspondences, contacts,
// solve, fracture); see docs/theory/energy.md#one-frame. The parts live beside this file
// (registration/tracker_state.h lists them); this file holds the outer loop and the API, and
// outer_iteration.cc the set-up of an outer iteration and its backtracking, frame_restarts.cc
// a frame's restarts, tracker_forces.cc the forces after a frame.
#include "femreg/tracker.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <sstream>

#include "femreg/forward.h"
#include "femreg/point_cloud.h"
#include "registration/correspondences.h"
#include "registration/confidence.h"
#include "registration/depth_offset.h"
#include "registration/fracture_step.h"
#include "registration/flying_pixels.h"
#include "registration/force_weight.h"
#include "registration/frame_problem.h"
#include "registration/global_pose.h"
#include "geometry/nearest.h"
#include "registration/prealign.h"
#include "registration/prediction.h"
#include "registration/tracker_impl.h"
#include "registration/tracker_state.h"
#include "parallel/pool.h"
#include "parallel/threads.h"
#include "solvers/backend.h"

namespace femreg {

namespace {

using Clock = std::chrono::steady_clock;
// A large motion: the first outer iteration moved the bulk of the free vertices (all but the 1 %
// that moved most) farther than this many mean edges.
// The nearest-point pairs of a surface that far from its cloud mislead (back faces, a twist
// by a symmetry of the cross-section), so the frame starts again with the elastic weight
// scaled stage by stage for one outer iteration each (the smooth part of the motion first,
// RestartStiff), then the ordinary schedule (docs/theory/stopping.md#large-motions).
constexpr double kLargeMotionEdges = 3.0;
// A frame after held or lost ones makes up for at most this many frames' motion in its
// budget of outer iterations: the cost of one catch-up frame stays bounded.
constexpr int kMaxCatchUpFrames = 4;

BackendOptions MakeBackendOptions(const SolverOptions& solver, double mean_edge_length) {
  BackendOptions b;
  b.type = solver.backend;
  b.max_iterations = solver.max_inner_iterations;
  b.relative_tolerance = solver.inner_tolerance;
  b.step_tolerance = 0.1 * solver.step_tolerance * mean_edge_length;
  // A quarter of the outer iterations' settle move: the next step would move less, and the
  // next outer iteration pairs anew anyway (docs/notes/2026-12-01-equilibrium-inexact-solves.md).
  b.equilibrium_step_tolerance = 0.25 * solver.bulk_step_tolerance * mean_edge_length;
  b.max_pcg_iterations = solver.max_pcg_iterations;
  b.preconditioner = solver.preconditioner;
  b.num_threads = solver.num_threads;  // 0: the frame's count (Track), chosen per frame
  b.trust_region = solver.trust_region;
  b.linear_solver = solver.linear_solver;
  return b;
}

// The mean length of the surface edges of all objects at rest (m).
double MeanSurfaceEdge(const TrackerState& state) {
  double sum = 0.0;
  long long count = 0;
  for (const ObjectState& o : state.objects) {
    const Triangles& t = o.mesh.surface;
    for (Eigen::Index f = 0; f < t.rows(); ++f) {
      for (int k = 0; k < 3; ++k) {
        sum += (o.mesh.rest.row(t(f, k)) - o.mesh.rest.row(t(f, (k + 1) % 3))).norm();
        ++count;
      }
    }
  }
  return count > 0 ? sum / static_cast<double>(count) : 0.0;
}

}  // namespace


Status Tracker::Impl::Init(std::vector<TetMesh> meshes, const std::vector<ObjectMaterial>& materials) {
  const RegistrationOptions& options = state.options;
  std::string error;
  if (!options.IsValid(&error)) return Status::Error("registration options: " + error);
  if (meshes.empty()) return Status::Error("the scene has no object");
  if (materials.size() != meshes.size()) return Status::Error("one material per mesh is needed");
  state.objects.resize(meshes.size());
  const ElasticModelType type = options.regularizer == Regularizer::kLinear
                                    ? ElasticModelType::kLinear
                                    : ElasticModelType::kCorotational;
  for (size_t i = 0; i < meshes.size(); ++i) {
    const std::string name = "object " + std::to_string(i);
    if (!materials[i].IsValid(&error)) return Status::Error(name + " material: " + error);
    if (materials[i].model == MaterialModel::kNeoHookean) {
      if (options.regularizer != Regularizer::kCorotational) {
        return Status::Error(name + ": material.model neo_hookean needs registration.regularizer "
                             "corotational (the FEM regularizer; got " +
                             std::string(ToString(options.regularizer)) + ")");
      }
    }
    ObjectState& o = state.objects[i];
    o.mesh = std::move(meshes[i]);
    o.material = materials[i];
    if (o.mesh.num_tets() == 0) return Status::Error(name + " has no tetrahedra");
    if (o.mesh.x.rows() != o.mesh.rest.rows()) o.mesh.x = o.mesh.rest;
    if (o.mesh.mass.size() != o.mesh.num_vertices() || o.mesh.mass.sum() <= 0) {
      ComputeLumpedMasses(&o.mesh, o.material.material.density, RegionDensities(o.material));
    }
    o.model.Build(o.mesh, type, o.material);
  }
  state.RebuildGlobalArrays();
  state.x.resize(state.num_vertices, 3);
  for (const ObjectState& o : state.objects) state.x.middleRows(o.offset, o.mesh.num_vertices()) = o.mesh.x;
  mean_edge = MeanSurfaceEdge(state);
  frame_problem.BuildElastic(state);
  backend = MakeBackend(MakeBackendOptions(options.solver, state.mean_edge_length));
  return Status::Ok();
}

void PrepareCloudForTracking(const RegistrationOptions& options, PointCloud* cloud, int* nonfinite_dropped,
                             int* flying_pixels, RemovedPlane* plane) {
  TransformCloud(options.preprocess, cloud);
  // Before the plane and the outliers: a depth edge's mixed pixels are judged in the image.
  const int flying = options.camera.enabled && options.preprocess.flying_pixels > 0
                         ? RemoveFlyingPixels(options.camera, options.preprocess.flying_pixels, cloud)
                         : 0;
  if (flying_pixels != nullptr) *flying_pixels = std::max(0, flying);
  PreprocessPointCloud(options.preprocess, cloud, nonfinite_dropped,
                       options.camera.enabled ? options.camera.position
                       : cloud->has_viewpoint ? cloud->viewpoint
                                              : Eigen::Vector3d::Zero(),
                       plane);
}

void Tracker::Impl::PrepareCloud(const PointCloud& input, FrameCloud* fc, FrameSummary* s) {
  const PreprocessOptions& pre = state.options.preprocess;
  const auto t0 = Clock::now();
  fc->cloud = input;
  const CameraOptions& camera = state.options.camera;
  const bool offset = pre.depth_offset && camera.enabled && pre.plane_distance > 0;
  const bool keep_plane = state.options.free_space.enabled && pre.plane_distance > 0;
  RemovedPlane plane;
  PrepareCloudForTracking(state.options, &fc->cloud, &s->nonfinite_dropped, &s->flying_pixels,
                          offset || keep_plane ? &plane : nullptr);
  if (offset) s->depth_offset = depth_offset.Correct(camera, pre.plane_distance, plane, &fc->cloud);
  fc->plane_points.resize(0, 3);
  if (keep_plane && plane.points.rows() > 0) {
    PointCloud table;
    table.points = std::move(plane.points);
    if (s->depth_offset != 0.0) ShiftDepth(camera, s->depth_offset, &table);
    fc->plane_points = std::move(table.points);
  }
  prepared_cloud = fc->cloud;
  // The cloud is thinned to the surface the data terms see (an embedded one's).
  const TrackerState& pair_state = PairState();
  const double dense = pre.auto_voxel_min_ratio * static_cast<double>(pair_state.surface_vertices.size());
  if (pre.voxel_size == 0 && pre.auto_voxel > 0 && fc->cloud.size() > dense) {
    s->voxel_size = pre.auto_voxel * (data_surface ? data_surface->surface_edge() : mean_edge);
    // Weighing as much as a cloud of exactly that density: points closer than the mesh can
    // follow add no information, and their stiffness would crush its elements
    // (docs/notes/2026-11-30-dense-clouds.md).
    SubsampleCloud(s->voxel_size, &fc->cloud, &fc->weights,
                   dense > 0 ? dense : std::numeric_limits<double>::infinity());
  } else {
    fc->weights.setOnes(fc->cloud.size());
  }
  s->points_used = fc->cloud.size();
  s->time.preprocess = Seconds(t0);
}

void Tracker::Impl::Hold(TerminationType t, const std::string& message, const PointIndex* index,
                         Clock::time_point t_frame, FrameSummary* s) {
  s->termination = t;
  s->message = message;
  s->lost = state.options.data.lost_coverage > 0.0;  // nothing found to track
  state.x_before = state.x;  // held: no velocity to carry on
  state.held_before = true;
  state.lost_before = s->lost;
  implausible_before.resize(0, 3);
  switched_before = false;
  MeasureForces(s);  // none: the shape was held
  ++missed_frames;
  Outputs(index, {});
  s->time.total = Seconds(t_frame);
  ++state.frame;
}

Status Tracker::Impl::Track(const PointCloud& input, FrameSummary* summary) {
  const auto t_frame = Clock::now();
  const RegistrationOptions& options = state.options;
  // Every parallel part of the frame (element loops, correspondences, the BLAS under
  // CHOLMOD) on solver.num_threads threads, whatever the environment says; 0: the cores
  // other processes leave free now (docs/guide/busy-machines.md).
  const ScopedThreads threads(AdaptiveThreadCount(options.solver.num_threads));
  FrameSummary& s = *summary;
  s = FrameSummary();
  s.frame = state.frame;
  // Only the frame right after a quiet one may start quietly: not after a held or invalid one.
  const bool after_quiet = quiet_next;
  quiet_next = false;
  s.backend = backend->type();
  s.cloud_points = input.size();
  prepared_cloud = PointCloud();  // this frame's, once prepared
  if (input.normals.rows() != 0 && input.normals.rows() != input.points.rows()) {
    // Held as a frame whose every point was dropped: the next frame catches up two frames' motion.
    Hold(TerminationType::kInvalidInput,
         "the cloud's normals must be empty or one per point; the shape was held at the previous frame",
         nullptr, t_frame, &s);
    return Status::Ok();
  }
  FrameCloud fc;
  PrepareCloud(input, &fc, &s);
  if (fc.cloud.size() == 0) {
    const bool dropped = s.cloud_points > 0;
    Hold(dropped ? TerminationType::kInvalidInput : TerminationType::kNoCorrespondences,
         dropped ? "every point of the cloud was dropped (" + std::to_string(s.nonfinite_dropped) +
                       " non-finite, " + std::to_string(s.flying_pixels) +
                       " flying pixels, the rest by the preprocess: plane, crop or filters); the shape was "
                       "held at the previous frame"
                 : "empty cloud; the shape was held at the previous frame",
         nullptr, t_frame, &s);
    return Status::Ok();
  }

  // The first frame, and the first after a lost one (the object may be back anywhere): there
  // the local rigid pre-alignment has its go first, and the search runs only if the pose it
  // leaves explains the cloud badly (a symmetric body's global poses are as good as the
  // right one, and only continuity tells them apart).
  const bool reacquire = state.frame > 0 && state.lost_before;
  if ((state.frame == 0 || reacquire) && options.initial_pose == InitialPose::kAuto && fc.cloud.size() >= 3) {
    const auto t_pose = Clock::now();
    if (reacquire && options.solver.rigid_prealign) RigidPrealign(fc.cloud, &state, data_surface.get());
    ChooseInitialPose(fc.cloud, &state, &s, data_surface.get());
    s.time.prealign += Seconds(t_pose);
  }
  // Constant-velocity prediction from the last two results, without the turns the surface
  // does not show.
  Vertices previous = state.x;
  if (options.solver.predict_motion && state.frame >= 2 && state.x_before.rows() == state.x.rows()) {
    const Vertices predicted = PredictMotion(state, data_surface.get());
    // Not through a flat element: the inversion barrier's energy is infinite there.
    if (predicted.allFinite() && (options.weights.barrier == 0 || NoFlatElement(state, predicted)) &&
        PredictionFits(predicted, fc, &s)) {
      state.x = predicted;
    }
  }
  const int min_points = std::max(
      options.data.min_points,
      static_cast<int>(std::ceil(options.data.min_points_per_surface_vertex *
                                 static_cast<double>(state.surface_vertices.size()))));
  auto t0 = Clock::now();
  fc.index = std::make_unique<PointIndex>(fc.cloud.points);
  s.time.correspondences += Seconds(t0);
  if (fc.cloud.size() < min_points) {
    Hold(TerminationType::kTooFewPoints,
         std::to_string(fc.cloud.size()) + " cloud points cannot constrain " +
             std::to_string(state.surface_vertices.size()) + " surface vertices (at least " +
             std::to_string(min_points) + " needed: data.min_points, "
             "data.min_points_per_surface_vertex); the shape was kept at the prediction",
         fc.index.get(), t_frame, &s);
    return Status::Ok();
  }
  if (options.solver.rigid_prealign) {
    t0 = Clock::now();
    RigidPrealign(fc.cloud, &state, data_surface.get());
    s.time.prealign += Seconds(t0);
  }
  if (state.fracture) {  // after a break: each piece its own rigid step
    t0 = Clock::now();
    PiecePrealign(fc.cloud, &state);
    s.time.prealign += Seconds(t0);
  }
  t0 = Clock::now();
  if (data_surface) {
    // An embedded surface: the frame's first closest-point queries (the occluders', the first
    // outer iteration's) walk from its subsample, not from a k-d tree of every scan vertex
    // built again each frame.
    fc.seeds = SubsampleStarts(PairState(), Surface().rings(), fc.cloud.points, 1, options.solver.num_threads);
  }
  PrepareFrameCloud(PairState(), Surface(), &fc);
  BuildObservedDepth(state, &fc);
  if (options.data.max_strain_step > 0 && implausible_before.rows() > 0 && !FractureLive(state)) {
    s.implausible_carried =
        CarryImplausible(state, implausible_before, fc.cloud.points, *fc.index, fc.spacing, &fc.occluder);
    fc.occluders.occluders += s.implausible_carried;
    s.implausible_points = s.implausible_carried;
  }
  // An embedded surface's subsample: its vertices facing away are not searched (FindPairs).
  fc.skip_facing_away = data_surface != nullptr;
  s.time.correspondences += Seconds(t0);
  s.visibility = fc.Describe();
  s.occluded_points = fc.occluders.occluders;
  estimate_forces = options.forces.estimate;  // forces.when_occluded decides after the first outer iteration
  // Not the last frame's equilibrium, if this frame's first outer iteration finds no pairs.
  if (!estimate_forces) frame_problem.SetEquilibrium(state, false, nullptr, false);
  s.trim_distance = std::isfinite(fc.trim) ? fc.trim : 0.0;
  // The temporal springs hold to where the frame starts (the prediction, moved by the rigid
  // pre-alignment, so that inertia does not fight the rigid step) and the anchors.
  state.frame_start = state.x;
  t0 = Clock::now();
  frame_problem.BuildFrameTerms(&state);
  s.time.build += Seconds(t0);

  std::vector<DataPair> pairs;
  warm_triangles.clear();  // a new cloud
  if (data_surface && options.data.cloud_to_model) {
    const int stride = options.data.cloud_stride;
    for (size_t i = 0; i < fc.seeds.size(); i += static_cast<size_t>(stride)) warm_triangles.push_back(fc.seeds[i]);
    fc.seeded_rings = FrameCloud::kSeedRings;
  }
  paired_vertices.clear();
  rise_from = std::max(1, options.data.hold_pairs_after);
  merit = std::numeric_limits<double>::infinity();
  double previous_energy = std::numeric_limits<double>::infinity();
  iteration_base = 0;
  warm_until = 0;
  smooth_after_split = -1;
  ResetStartReferences();
  multipliers_at_start = state.contact_multipliers;
  iteration_budget = options.solver.max_outer_iterations * (1 + std::min(missed_frames, kMaxCatchUpFrames - 1));
  iteration_limit = iteration_budget;
  stepping_in = false;
  fc.facing_only = false;
  const Vertices start = state.x;
  // MarkImplausible's view, once a frame; none on an embedded surface's cage: it stands off the
  // data, and its empty places say nothing.
  const auto faces = data_surface ? nullptr : fc.FacesFunction();
  implausible_at_start = 0.0;
  stiff_stages = 0;
  stiff_from = 1;
  redecide_until = options.data.hold_pairs_after;
  quiet_start = after_quiet && QuietStart();
  for (int k = 0; k < iteration_limit; ++k) {
    StepIn(k, &previous_energy);
    // Until the pair set is held (after a stiff restart too, whose start marked them), the
    // occluders are decided again where the model now is: a lagging part has caught up.
    if (k > 0 && k < redecide_until && !fc.occluder.empty()) {
      t0 = Clock::now();
      fc.occluders.occluders =
          ReleaseReached(PairState(), Surface(), fc.cloud.points, fc.spacing, &fc.occluder).occluders;
      BuildOccluderDepth(state, &fc);
      s.time.correspondences += Seconds(t0);
      s.occluded_points = fc.occluders.occluders;
    }
    SwitchToForcesWhereHeld(k, fc, &previous_energy, &s);
    const bool was_live = FractureLive(state);
    const bool go_on = OuterIteration(k, fc, t_frame, &pairs, &previous_energy, &previous, &s);
    if (FractureLive(state) && !was_live) {
      // Fracture has its say from here: what it turns off goes off for the rest of the frame.
      fc.trim = std::numeric_limits<double>::infinity();
      fc.occluder.clear();
      fc.occluder_depth.Clear();
      fc.occluders = OccluderCounts();
      s.occluded_points = 0;
      s.trim_distance = 0.0;
    }
    fc.seeded_rings = 0;  // from here on, from the last outer iteration's hits
    // Where asked, the solves before the pair set is held are watched for a crushed element,
    // also one that would have ended the frame as converged.
    const bool can_restart = options.regularizer != Regularizer::kNone && options.weights.elastic > 0 &&
                             !FractureLive(state);
    const double restart_volume = StiffRestartVolume(options, estimate_forces);
    const bool crushed = can_restart && restart_volume > 0 && iteration_base == 0 &&
                         k < std::max(1, options.data.hold_pairs_after) && iteration_budget > 1 &&
                         (go_on || s.termination == TerminationType::kConverged) &&
                         CrushedVolumeRatio(state, start, state.x) < restart_volume;
    if (!go_on && !crushed) break;
    const bool large_motion = can_restart && k == 0 && iteration_limit > 1 &&
                              (first_bulk_move > kLargeMotionEdges * state.mean_edge_length || missed_frames > 0);
    if (large_motion || crushed) {
      RestartStiff(k, large_motion, go_on, start, &fc, &s);
    } else {
      MarkImplausibleOrRestart(k, start, faces, &fc, &previous_energy, &s);
    }
  }
  if (iteration_base > 0) frame_problem.SetElasticScale(state, 1.0);  // a frame stopped while stiff
  if (s.termination == TerminationType::kNotRun) {
    s.termination = TerminationType::kMaxIterations;
    s.message = "no outer iteration ran";
  }
  if (s.termination == TerminationType::kNoCorrespondences) state.x = previous;
  if (s.termination == TerminationType::kConverged && !s.iterations.empty() && s.iterations.back().stalled) {
    s.termination = TerminationType::kStalled;  // docs/theory/stopping.md#stalled
    s.message += "; but the last solve refused most of its steps and left the forces unbalanced: stalled";
  }
  if (state.collision) MeasureContacts(&s);
  s.forces_estimated = estimate_forces;
  if (estimate_forces) {
    s.force_weight = options.forces.weight * state.force_weight_scale;
    if (misfit_reference > 0.0 && s.rms_residual > 0.0) s.misfit_ratio = s.rms_residual / misfit_reference;
  }
  s.free_space_vertices = frame_problem.FreeSpaceHeld(state.x);
  if (s.stopped_by.empty()) s.stopped_by = ToString(s.termination);
  last_frame_rms = s.rms_residual;
  s.quiet_start = quiet_start;
  CountQuietCost(quiet_start, s);
  state.x_before = previous;
  const auto t_outputs = Clock::now();
  Outputs(fc.index.get(), pairs);
  if (s.IsSolutionUsable()) {
    const double tolerance = std::max(options.data.loss_scale, 2.0 * fc.spacing);
    const SurfaceRings& rings = data_surface ? data_index.Rings(data_surface->view()) : model_index.Rings(state);
    s.confidence = MeasureConfidence(state, fc, pairs, tolerance, data_surface.get(), &rings);
    s.lost = state.coverage_reference > 0.0 &&
             s.confidence.coverage < options.data.lost_coverage * state.coverage_reference;
    if (!s.lost) UpdateReferences(s.confidence, pairs, &state);
  } else {
    s.lost = options.data.lost_coverage > 0.0;
  }
  if (s.lost && state.last_good.rows() == state.x.rows()) {
    // Lost: back to the last good shape, with no velocity to carry on.
    state.x = state.last_good;
    state.x_before = state.x;
    Outputs(fc.index.get(), {});
  } else if (!s.lost) {
    // Converged without a restart, not catching up, nothing came apart, and it moved little (only
    // where the next frame could start quietly: forces.estimate with forces.pushing_only).
    quiet_next = options.forces.estimate && options.forces.pushing_only &&
                 s.termination == TerminationType::kConverged && s.large_motion_restarts == 0 &&
                 s.crushed_restarts == 0 && s.implausible_restarts == 0 && !state.held_before &&
                 !(state.fracture && state.fracture->frame_separated) && MovedLittle(previous);
    state.last_good = state.x;
    // The first frame after a held or lost one caught up with a motion it did not see, and a
    // large motion's frame jumped: neither is a velocity to carry on.
    // Nor is the jump of pieces that came apart in this frame.
    if (state.held_before || s.large_motion_restarts > 0 || (state.fracture && state.fracture->frame_separated)) {
      state.x_before = state.x;
    }
  }
  state.held_before = s.lost || !s.IsSolutionUsable();
  const double solve_before_probe = s.time.solve;  // the weight's probe is a solve, not an output
  // forces.when_occluded: the weight adapts over consecutive frames with the forces estimated.
  if (!estimate_forces) state.misfit_ratios.clear();
  if (estimate_forces && options.forces.adaptive_weight && !state.held_before) {
    AdaptForceWeight(s.misfit_ratio, &state,
                     [&](double lower) { return LowerForceWeightPays(lower, pairs, t_frame, &s); });
  }
  implausible_before = state.held_before || FractureLive(state) || fc.occluder.empty()
                           ? Vertices(0, 3)
                           : ImplausiblePoints(state, fc.cloud.points, fc.occluder);
  switched_before = estimate_forces && !options.forces.estimate && !state.held_before;
  state.lost_before = s.lost;
  missed_frames = state.held_before ? missed_frames + 1 : 0;
  MeasureForces(&s);
  s.time.outputs = Seconds(t_outputs) - (s.time.solve - solve_before_probe);
  s.time.total = Seconds(t_frame);
  ++state.frame;
  return Status::Ok();
}

bool Tracker::Impl::PredictionFits(const Vertices& predicted, const FrameCloud& fc, FrameSummary* s) {
  if (!data_surface) return true;
  const auto t0 = Clock::now();
  const double gate = state.options.data.max_distance;
  const bool fits = StartMisfit(state, predicted, fc.cloud.points, gate, data_surface.get()) <=
                    StartMisfit(state, state.x, fc.cloud.points, gate, data_surface.get());
  s->time.correspondences += Seconds(t0);
  return fits;
}

void Tracker::Impl::Outputs(const PointIndex* cloud_index, const std::vector<DataPair>& pairs) {
  const int threads = state.options.solver.num_threads;
  if (!data_surface) {
    UpdateOutputs(cloud_index, pairs, &state, threads);
    return;
  }
  // The coarse vertices observed: those that carry most of a paired data-surface vertex.
  std::vector<DataPair> coarse;
  coarse.reserve(pairs.size());
  for (const DataPair& p : pairs) {
    for (int k = 0; k < p.num_vertices; ++k) {
      if (p.num_vertices == 3 && p.barycentric[k] < 0.2) continue;
      DataPair c;
      c.vertices[0] = data_surface->Dominant(p.vertices[k]);
      coarse.push_back(c);
    }
  }
  UpdateOutputs(cloud_index, coarse, &state, threads);
  PairState();  // the data surface at the result: the confidence reads it
}

Tracker::Tracker() : impl_(new Impl) {}
Tracker::~Tracker() = default;

Status Tracker::Create(const std::vector<TetMesh>& meshes, const std::vector<ObjectMaterial>& materials,
                       const RegistrationOptions& options, std::unique_ptr<Tracker>* tracker) {
  std::unique_ptr<Tracker> t(new Tracker);
  t->impl_->state.options = options;
  Status status = t->impl_->Init(meshes, materials);
  if (!status.ok()) return status;
  *tracker = std::move(t);
  return Status::Ok();
}

Status Tracker::Track(const PointCloud& cloud, FrameSummary* summary) {
  if (summary == nullptr) return Status::Error("Tracker::Track: summary must not be null");
  return impl_->Track(cloud, summary);
}

int Tracker::num_objects() const { return static_cast<int>(impl_->state.objects.size()); }
const TetMesh& Tracker::mesh(int object) const { return impl_->state.objects.at(object).mesh; }
const Vertices& Tracker::vertices(int object) const { return impl_->state.objects.at(object).mesh.x; }
const Eigen::VectorXd& Tracker::vertex_residuals(int object) const {
  return impl_->state.residuals.at(object);
}
const std::vector<char>& Tracker::vertex_observed(int object) const {
  return impl_->state.observed.at(object);
}
int Tracker::frame() const { return impl_->state.frame; }

Status Tracker::SetVertices(int object, const Vertices& x) {
  TrackerState& state = impl_->state;
  if (object < 0 || object >= num_objects()) return Status::Error("no object " + std::to_string(object));
  ObjectState& o = state.objects[object];
  if (x.rows() != o.mesh.num_vertices() || !x.allFinite()) {
    return Status::Error("SetVertices: expected " + std::to_string(o.mesh.num_vertices()) +
                         " finite rows for object " + std::to_string(object));
  }
  state.x.middleRows(o.offset, x.rows()) = x;
  o.mesh.x = x;
  // The caller's shape starts afresh: no velocity, no catch-up or search after a held or lost
  // frame, no quiet start, no marks carried from the last frame's cloud, and a lost frame goes
  // back to this shape.
  state.x_before.resize(0, 3);
  if (state.last_good.rows() == state.x.rows()) {
    state.last_good.middleRows(o.offset, x.rows()) = x;
  } else {
    state.last_good = state.x;
  }
  state.held_before = false;
  state.lost_before = false;
  impl_->missed_frames = 0;
  impl_->quiet_next = false;
  impl_->implausible_before.resize(0, 3);
  impl_->switched_before = false;
  return Status::Ok();
}
const RegistrationOptions& Tracker::options() const { return impl_->state.options; }
const PointCloud& Tracker::prepared_cloud() const { return impl_->prepared_cloud; }
const CollisionWorld* Tracker::collision() const { return impl_->state.collision.get(); }

}  // namespace femreg
