// The Tracker: one frame is a few outer iterations of (rotations, correspondences, contacts,
// solve, fracture); see docs/theory/energy.md#one-frame. The parts live beside this file
// (registration/tracker_state.h lists them); this file holds the outer loop and the API, and
// outer_iteration.cc the set-up of an outer iteration and its backtracking.
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
#include "registration/fracture_step.h"
#include "registration/frame_problem.h"
#include "registration/global_pose.h"
#include "geometry/nearest.h"
#include "registration/prealign.h"
#include "registration/tracker_impl.h"
#include "registration/tracker_state.h"
#include "parallel/threads.h"
#include "solvers/backend.h"

namespace femreg {

namespace {

using Clock = std::chrono::steady_clock;
// The outer iterations stop when the energy rose from one to the next (by more than
// solver.relative_energy_tolerance) while no vertex moved farther than this many mean surface
// edges, once the pair set is held: new rotations and pairs no longer lower it. They cycle among
// nearly equal pairings (a vertex between two sparse cloud points, a cloud point between two
// faces), or the held rotations of the corotational step stop being a descent; going on costs time
// and does not help (docs/theory/stopping.md). A rise during a larger move is progress, not a cycle
// (tests/hard_cases_test.cc): the inverted neo-Hookean start would stop while unfolding
// (docs/notes/2026-11-27-stopping-on-a-rise.md,
// docs/notes/2026-11-28-figures-from-code-comments.md). A frame that stops on a rise keeps its last
// iterate, with the pairs and rotations it was solved with.
constexpr double kRiseMoveLimit = 1.0;
// A large motion: the first outer iteration moved the bulk of the free vertices (all but the 1 %
// that moved most) farther than this many mean edges.
// The nearest-point pairs of a surface that far from its cloud mislead (back faces, a twist
// by a symmetry of the cross-section), so the frame starts again with the elastic weight
// scaled by each of kStiffScales for one outer iteration (the smooth part of the motion
// first), then the ordinary schedule (docs/theory/stopping.md#large-motions).
constexpr double kLargeMotionEdges = 3.0;
constexpr double kStiffScales[] = {100.0, 30.0, 10.0, 3.0};
// ... and by no more than this fraction of the previous energy: a larger rise is a change of the
// problem (the rotations of nearly flat elements turning over, a new contact set), not a cycle
// among nearly equal pairings, and the next solve may use it (the 1:1000 flat plate of
// tests/hard_cases_test.cc gains by going on)
// (docs/notes/2026-11-28-figures-from-code-comments.md). With solver.relative_energy_tolerance at
// this limit or above, no rise stops a frame.
constexpr double kRiseEnergyLimit = 0.1;

BackendOptions MakeBackendOptions(const SolverOptions& solver, double mean_edge_length) {
  BackendOptions b;
  b.type = solver.backend;
  b.max_iterations = solver.max_inner_iterations;
  b.relative_tolerance = solver.inner_tolerance;
  b.step_tolerance = 0.1 * solver.step_tolerance * mean_edge_length;
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
      if (materials[i].nodal_volume && options.solver.backend != SolverBackend::kFast) {
        return Status::Error(name + ": material.volume nodal needs solver.backend: fast (the Ceres "
                             "back end has no nodal-volume element; write volume: element)");
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

void PrepareCloudForTracking(const RegistrationOptions& options, PointCloud* cloud, int* nonfinite_dropped) {
  TransformCloud(options.preprocess, cloud);
  PreprocessPointCloud(options.preprocess, cloud, nonfinite_dropped,
                       options.camera.enabled ? options.camera.position
                       : cloud->has_viewpoint ? cloud->viewpoint
                                              : Eigen::Vector3d::Zero());
}

void Tracker::Impl::PrepareCloud(const PointCloud& input, FrameCloud* fc, FrameSummary* s) {
  const PreprocessOptions& pre = state.options.preprocess;
  const auto t0 = Clock::now();
  fc->cloud = input;
  PrepareCloudForTracking(state.options, &fc->cloud, &s->nonfinite_dropped);
  const double dense = pre.auto_voxel_min_ratio * static_cast<double>(state.surface_vertices.size());
  if (pre.voxel_size == 0 && pre.auto_voxel > 0 && fc->cloud.size() > dense) {
    s->voxel_size = pre.auto_voxel * mean_edge;
    SubsampleCloud(s->voxel_size, &fc->cloud, &fc->weights);
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
  UpdateOutputs(index, {}, &state, state.options.solver.num_threads);
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
  s.backend = backend->type();
  s.cloud_points = input.size();
  if (input.points.cols() != 3 ||
      (input.normals.rows() != 0 && input.normals.rows() != input.points.rows())) {
    s.termination = TerminationType::kInvalidInput;
    s.message = "the cloud's points must be #P by 3 and its normals empty or #P by 3";
    ++state.frame;
    return Status::Ok();
  }
  FrameCloud fc;
  PrepareCloud(input, &fc, &s);
  if (fc.cloud.size() == 0) {
    const bool dropped = s.cloud_points > 0;
    Hold(dropped ? TerminationType::kInvalidInput : TerminationType::kNoCorrespondences,
         dropped ? "every point of the cloud was dropped (" + std::to_string(s.nonfinite_dropped) +
                       " non-finite); the shape was held at the previous frame"
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
    if (reacquire && options.solver.rigid_prealign) RigidPrealign(fc.cloud, &state);
    ChooseInitialPose(fc.cloud, &state, &s);
    s.time.prealign += Seconds(t_pose);
  }
  // Constant-velocity prediction from the last two results.
  Vertices previous = state.x;
  if (options.solver.predict_motion && state.frame >= 2 && state.x_before.rows() == state.x.rows()) {
    const Vertices predicted = 2.0 * state.x - state.x_before;
    // Not through a flat element: the inversion barrier's energy is infinite there.
    if (predicted.allFinite() && (options.weights.barrier == 0 || NoFlatElement(state, predicted))) {
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
    RigidPrealign(fc.cloud, &state);
    s.time.prealign += Seconds(t0);
  }
  t0 = Clock::now();
  PrepareFrameCloud(state, Surface(), &fc);
  s.time.correspondences += Seconds(t0);
  s.visibility = fc.Describe();
  s.occluded_points = fc.occluders.occluders;
  s.trim_distance = std::isfinite(fc.trim) ? fc.trim : 0.0;
  // The temporal springs hold to where the frame starts (the prediction, moved by the rigid
  // pre-alignment, so that inertia does not fight the rigid step) and the anchors.
  state.frame_start = state.x;
  frame_problem.BuildFrameTerms(&state);

  std::vector<DataPair> pairs;
  warm_triangles.clear();  // a new cloud
  paired_vertices.clear();
  rise_from = std::max(1, options.data.hold_pairs_after);
  merit = std::numeric_limits<double>::infinity();
  double previous_energy = std::numeric_limits<double>::infinity();
  iteration_base = 0;
  iteration_limit = options.solver.max_outer_iterations;
  stepping_in = false;
  fc.facing_only = false;
  const Vertices start = state.x;
  int stiff_stages = 0;  // of kStiffScales, once a large motion is seen
  for (int k = 0; k < iteration_limit; ++k) {
    if (stepping_in) {
      const int stage = k - 1;
      stepping_in = stage < stiff_stages;
      frame_problem.SetElasticScale(state, stepping_in ? kStiffScales[stage] : 1.0);
      merit = std::numeric_limits<double>::infinity();  // another energy
      previous_energy = merit;
    }
    // Until the pair set is held, the occluders are decided again where the model now is: a
    // part that lagged behind a fast motion and looked like one has caught up.
    if (k > 0 && k < options.data.hold_pairs_after && !fc.occluder.empty()) {
      t0 = Clock::now();
      fc.occluders.occluders = ReleaseReached(state, Surface(), fc.cloud.points, fc.spacing, &fc.occluder).occluders;
      s.time.correspondences += Seconds(t0);
      s.occluded_points = fc.occluders.occluders;
    }
    if (!OuterIteration(k, fc, t_frame, &pairs, &previous_energy, &previous, &s)) break;
    if (k == 0 && iteration_limit > 1 && options.regularizer != Regularizer::kNone &&
        options.weights.elastic > 0 && !options.forces.estimate && !state.fracture &&
        first_bulk_move > kLargeMotionEdges * state.mean_edge_length) {
      // Back to the start, stiff, then softer stage by stage, pairing only surface that faces
      // the sensor (docs/theory/stopping.md#large-motions).
      state.x = start;
      stiff_stages = static_cast<int>(sizeof(kStiffScales) / sizeof(kStiffScales[0]));
      stepping_in = true;
      fc.facing_only = true;
      iteration_base = 1 + stiff_stages;
      iteration_limit = iteration_base + options.solver.max_outer_iterations;
      rise_from = iteration_base + std::max(1, options.data.hold_pairs_after);
      warm_triangles.clear();
      paired_vertices.clear();
      ++s.large_motion_restarts;
    }
  }
  if (iteration_base > 0) frame_problem.SetElasticScale(state, 1.0);  // a frame stopped while stiff
  if (s.termination == TerminationType::kNotRun) {
    s.termination = TerminationType::kMaxIterations;
    s.message = "no outer iteration ran";
  }
  if (s.termination == TerminationType::kNoCorrespondences) state.x = previous;
  if (state.collision) MeasureContacts(&s);
  if (s.stopped_by.empty()) s.stopped_by = ToString(s.termination);
  state.x_before = previous;
  UpdateOutputs(fc.index.get(), pairs, &state, options.solver.num_threads);
  if (s.IsSolutionUsable()) {
    const double tolerance = std::max(options.data.loss_scale, 2.0 * fc.spacing);
    s.confidence = MeasureConfidence(state, fc, pairs, tolerance);
    s.lost = state.coverage_reference > 0.0 &&
             s.confidence.coverage < options.data.lost_coverage * state.coverage_reference;
    if (!s.lost) UpdateReferences(s.confidence, &state);
  } else {
    s.lost = options.data.lost_coverage > 0.0;
  }
  if (s.lost && state.last_good.rows() == state.x.rows()) {
    // Lost: back to the last good shape, with no velocity to carry on.
    state.x = state.last_good;
    state.x_before = state.x;
    UpdateOutputs(fc.index.get(), {}, &state, options.solver.num_threads);
  } else if (!s.lost) {
    state.last_good = state.x;
    // The first frame after a held or lost one caught up with a motion it did not see, and a
    // large motion's frame jumped: neither is a velocity to carry on.
    if (state.held_before || s.large_motion_restarts > 0) state.x_before = state.x;
  }
  state.held_before = s.lost || !s.IsSolutionUsable();
  state.lost_before = s.lost;
  MeasureForces(&s);
  s.time.total = Seconds(t_frame);
  ++state.frame;
  return Status::Ok();
}

namespace {

// The augmented-Lagrangian update after a solve (docs/theory/contact.md#response): each
// contact's multiplier takes in the force its penetration still asks for, lambda <-
// max(0, lambda + k (-g)), and a contact still deeper than the tolerance that did not at
// least halve its penetration since the last update (or is new) gets 4 times its stiffness
// (the data's pull can be far stiffer than k, and the inner solve is truncated), kept while
// the contact is detected, so that one that flickers open and shut does not leak again.
// Contacts no longer detected drop both. True while a contact is deeper than the tolerance
// or held open wider than it: the frame goes on.
bool UpdateContactMultipliers(TrackerState* state) {
  const CollisionWorld& world = *state->collision;
  const double k0 = world.stiffness(), tolerance = world.tolerance();
  const double k_max = 1e3 * k0;  // keeps the stiffest contact within the solvers' reach
  std::map<std::pair<int, int>, TrackerState::ContactMultiplier> next;
  bool pending = false;
  for (const Contact& c : state->contacts) {
    const std::pair<int, int> key(c.source, c.object_b);
    TrackerState::ContactMultiplier m;
    m.stiffness = k0;
    const auto it = state->contact_multipliers.find(key);
    if (it != state->contact_multipliers.end()) m = it->second;
    const double penetration = world.Penetration(c, state->x);
    const bool stalled = penetration > tolerance && penetration > 0.5 * m.penetration;
    m.lambda = std::max(0.0, m.lambda + m.stiffness * penetration);
    if (stalled) m.stiffness = std::min(k_max, 4.0 * m.stiffness);
    m.penetration = penetration;
    if (penetration > tolerance || (m.lambda > 0 && -penetration > tolerance)) pending = true;
    if (m.lambda > 0 || m.stiffness != k0) next[key] = m;
  }
  state->contact_multipliers.swap(next);
  return pending;
}

}  // namespace

bool Tracker::Impl::OuterIteration(int k, const FrameCloud& fc, Clock::time_point t_frame,
                                   std::vector<DataPair>* pairs, double* previous_energy,
                                   Vertices* previous, FrameSummary* s) {
  const RegistrationOptions& options = state.options;
  const auto t_outer = Clock::now();
  femreg::OuterIteration row;
  row.iteration = k + 1;
  PairCounts counts;
  const bool warm_start = options.forces.estimate && k == 0;
  UpdateElementRotations(s);
  if (!PrepareIteration(k, fc, *previous, pairs, &counts, &row, s)) return false;
  if (Backtracks(k, warm_start) && !Backtrack(k, fc, *previous, pairs, &counts, &row, previous_energy, s)) {
    return false;
  }
  const energy::Problem& problem = frame_problem.problem();

  auto t0 = Clock::now();
  const double time_left = options.solver.time_budget_s > 0
                               ? std::max(1e-3, options.solver.time_budget_s - Seconds(t_frame))
                               : 0.0;
  const Vertices before_solve = state.x;
  const SolveReport report = backend->Solve(problem, time_left, &state.x);
  s->time.solve += Seconds(t0);
  row.before = report.before;
  if (k == 0) s->initial = row.before;
  // The next outer iteration's energy, with what it finds, is held against this start's.
  merit = warm_start ? std::numeric_limits<double>::infinity() : report.before.total();
  merit_x = before_solve;
  s->time.assembly += report.assemble_s;
  s->time.factorization += report.factorize_s;
  s->time.linear_solve += report.linear_solve_s;
  s->time.evaluation += report.evaluate_s;
  s->factorizations += report.factorizations + report.hierarchies;
  s->linear_solves += report.linear_solves;
  s->pcg_iterations += report.pcg_iterations;
  row.inner_iterations = report.iterations;
  if (!report.success) {
    s->termination = TerminationType::kSolverFailure;
    s->message = report.message + "; the shape before this iteration was kept";
    s->iterations.push_back(row);
    return false;
  }
  row.after = report.after;
  const bool contacts_pending =
      state.collision && state.collision->augmented() && UpdateContactMultipliers(&state);
  // New multipliers change the energy: the next start is not held against this one.
  if (contacts_pending) merit = std::numeric_limits<double>::infinity();
  // The largest vertex move of this outer iteration and the one 99 % of the free vertices
  // stay within (compared below with the mesh's edge and the cloud's sampling distance).
  const Eigen::VectorXd moves = (state.x - before_solve).rowwise().norm();
  double moved = moves.size() > 0 ? moves.maxCoeff() : 0.0;
  double bulk = BulkMove(state, moves, frame_problem.problem().fixed());
  row.max_move = moved;
  first_bulk_move = k == 0 ? bulk : first_bulk_move;
  double sum2 = 0.0;
  for (const DataPair& p : *pairs) sum2 += (p.Point(state.x) - p.target).squaredNorm();
  row.rms_residual = std::sqrt(sum2 / static_cast<double>(pairs->size()));
  row.time_s = Seconds(t_outer);
  s->iterations.push_back(row);
  s->inner_iterations += row.inner_iterations;
  s->outer_iterations = k + 1;
  s->final = row.after;
  s->model_to_cloud = counts.model_to_cloud;
  s->cloud_to_model = counts.cloud_to_model;
  s->rejected = counts.rejected;
  s->rms_residual = row.rms_residual;

  if (state.fracture) {  // docs/theory/fracture.md: between outer iterations
    const std::vector<int> source = FractureStep(k, *fc.index, &state, s);
    if (!source.empty()) {
      *previous = RemapRows(*previous, source);
      frame_problem.BuildElastic(state);
      frame_problem.BuildFrameTerms(&state);
      state.contact_multipliers.clear();  // keyed by the old vertex numbering
      merit = std::numeric_limits<double>::infinity();  // another mesh
      model_index.Reset();
      warm_triangles.clear();  // a new surface
      paired_vertices.clear();
      FindPairs(state, fc, Surface(), options.solver.num_threads, pairs, &counts);  // for the outputs
      moved = std::numeric_limits<double>::infinity();  // a new topology: not converged
      bulk = moved;
      // The next outer iteration forms a new pair set, held from the one after.
      rise_from = std::max(k + 2, std::max(1, options.data.hold_pairs_after));
    }
  }

  // Compare with the previous outer iteration's result (its pairs were different, so the
  // energy before this iteration's solve is not comparable; after a split, with nothing).
  // The frame stops when the outer iteration changed the energy by less than the tolerance,
  // or raised it by more (stopped_by "energy_rise") unless the rise goes on: before the pair
  // set is held (rise_from: pairs still join as the surface reaches the cloud), during a move
  // of more than kRiseMoveLimit mean edges, or by more than kRiseEnergyLimit of the previous
  // energy (see there).
  if (warm_start) {  // another energy: nothing to compare with
    *previous_energy = std::numeric_limits<double>::infinity();
    return k + 1 < iteration_limit;
  }
  const double e1 = row.after.total();
  const double e0 = *previous_energy;
  const double decrease = (e0 - e1) / std::max(e1, 1e-300);  // < 0: it rose
  const double rise = (e1 - e0) / std::max(e0, 1e-300);      // > 0: it rose, of the previous
  *previous_energy = std::isfinite(moved) ? e1 : std::numeric_limits<double>::infinity();
  const double step_limit = options.solver.step_tolerance * state.mean_edge_length;
  const double tolerance = options.solver.relative_energy_tolerance;
  const bool rise_goes_on = decrease <= -tolerance &&
                            (k < rise_from || moved > kRiseMoveLimit * state.mean_edge_length ||
                             rise > kRiseEnergyLimit);
  // Against the coarser of the mesh's and the cloud's resolutions: the cloud's sampling
  // distance is twice its median point spacing (for points scattered at random over a
  // surface, about the square root of the area per point; for a depth image's grid, two
  // pixels' pitch). On the bundled datasets the mesh is the coarser; on a fine mesh under a
  // sparse cloud the fit cannot resolve moves of a twentieth of an edge anyway. One length
  // for the whole cloud: with several objects, the densest part of a labelled cloud sets it.
  const double bulk_reference = std::max(state.mean_edge_length, 2.0 * fc.spacing);
  const double bulk_limit = options.solver.bulk_step_tolerance * bulk_reference;
  const bool settled = bulk_limit > 0 && bulk <= bulk_limit;
  if (k > iteration_base && !stepping_in && !contacts_pending &&
      (moved <= step_limit || settled || (tolerance > 0 && decrease < tolerance && !rise_goes_on))) {
    s->termination = TerminationType::kConverged;
    std::ostringstream os;
    if (moved <= step_limit) {
      s->stopped_by = "step";
      os << "largest vertex move " << moved * 1e3 << " mm <= " << options.solver.step_tolerance
         << " x mean edge " << state.mean_edge_length * 1e3 << " mm";
    } else if (settled) {
      s->stopped_by = "bulk_step";
      os << "99 % of each object's free vertices moved at most " << bulk * 1e3 << " mm <= "
         << options.solver.bulk_step_tolerance
         << (bulk_reference > state.mean_edge_length ? " x the cloud's sampling distance " : " x mean edge ")
         << bulk_reference * 1e3 << " mm (the largest move " << moved * 1e3 << " mm)";
    } else if (decrease > -tolerance) {
      s->stopped_by = "energy";
      os << "relative energy change " << std::abs(decrease) << " < " << tolerance;
    } else {
      s->stopped_by = "energy_rise";
      os << "energy rose by " << rise * 100 << " % with the largest vertex move "
         << moved / state.mean_edge_length << " mean edges (relative_energy_tolerance " << tolerance
         << "): new rotations and pairs no longer lower it";
    }
    s->message = os.str();
    return false;
  }
  if (options.solver.time_budget_s > 0 && Seconds(t_frame) >= options.solver.time_budget_s) {
    s->termination = TerminationType::kTimeBudget;
    s->message = "time budget of " + std::to_string(options.solver.time_budget_s) + " s used";
    return false;
  }
  if (k + 1 == iteration_limit) {
    s->termination = TerminationType::kMaxIterations;
    s->message = "reached solver.max_outer_iterations = " + std::to_string(options.solver.max_outer_iterations);
    if (iteration_base > 0) s->message += " after a large motion's " + std::to_string(iteration_base) + " stiff start";
  }
  return true;
}

void Tracker::Impl::MeasureForces(FrameSummary* s) {
  const Vertices forces = frame_problem.ExternalForces(state);
  const ForceResultant resultant = ResultantAboutCentroid(forces, state.x, state.mass);
  s->force = resultant.force;
  s->torque = resultant.torque;
  for (size_t i = 0; i < state.objects.size(); ++i) {
    const ObjectState& o = state.objects[i];
    state.external_forces[i] = forces.middleRows(o.offset, o.mesh.num_vertices());
  }
}

void Tracker::Impl::MeasureContacts(FrameSummary* s) {
  const auto t0 = Clock::now();
  state.collision->SetFrame(state.frame);
  state.collision->Detect(state.x, 0.0, &state.contacts);
  const ContactStats cs = state.collision->Evaluate(state.contacts, state.x);
  s->contacts = cs.contacts;
  s->object_contacts = cs.object_contacts;
  s->obstacle_contacts = cs.obstacle_contacts;
  s->max_penetration = cs.max_penetration;
  s->min_gap = cs.min_gap;
  s->contact_forces = frame_problem.ContactForces(state.x);
  s->time.collision += Seconds(t0);
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
  state.x_before.resize(0, 3);
  return Status::Ok();
}
const RegistrationOptions& Tracker::options() const { return impl_->state.options; }
const CollisionWorld* Tracker::collision() const { return impl_->state.collision.get(); }

}  // namespace femreg
