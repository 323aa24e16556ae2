// An outer iteration: its set-up at the current shape (rotations, pairs, loads, contacts, the
// equilibrium terms), the backtracking that holds its start against the last one's
// (docs/theory/stopping.md#backtracking), the solve and the stopping rules, and the contacts'
// multipliers. The frame loop that runs them is in tracker.cc.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <map>
#include <sstream>
#include <string>
#include <vector>

#include "registration/correspondences.h"
#include "registration/fracture_step.h"
#include "registration/frame_problem.h"
#include "registration/prediction.h"
#include "registration/tracker_impl.h"
#include "registration/tracker_state.h"

namespace femreg {

namespace {

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
// ... and by no more than this fraction of the previous energy: a larger rise is a change of the
// problem (the rotations of nearly flat elements turning over, a new contact set), not a cycle
// among nearly equal pairings, and the next solve may use it (the 1:1000 flat plate of
// tests/hard_cases_test.cc gains by going on)
// (docs/notes/2026-11-28-figures-from-code-comments.md). With solver.relative_energy_tolerance at
// this limit or above, no rise stops a frame.
constexpr double kRiseEnergyLimit = 0.1;
// Halvings of an outer iteration's move tried when the energy it reached, with its new pairs,
// is more than kRiseEnergyLimit above its start's (Backtrack): down to an eighth of the move.
constexpr int kBacktrackHalvings = 3;
// An outer iteration's move whose cosine with the last one's is below this reverses it: the
// iterations are caught in a two-cycle (CutReversal).
constexpr double kReversalCosine = -0.5;
// The shortest share of a reversing move that CutReversal keeps.
constexpr double kShortestReversalCut = 0.25;
// With the forces estimated, a hidden-turn hold after a solve of the frame's own energy (not a warm
// or smooth start's) that raises it by more than this share turns a body its contacts and its
// balance see: the turn is not hidden, and is undone (docs/theory/stopping.md#hidden-turns).
constexpr double kSeenTurnRise = 0.1;
// forces.when_occluded: a frame is registered with the forces estimated where at least this
// many occluder points touch the body's points (TouchingOccluderPoints): a hand or a tool in the
// mask that holds the body, not one passing in front of it nor a few noisy points.
constexpr int kTouchingOccluderPoints = 5;

}  // namespace

void Tracker::Impl::UpdateElementRotations(FrameSummary* s) {
  const auto t0 = Clock::now();
  // Only the corotational element reads rotations: what is off costs nothing (neo-Hookean
  // objects have none to hold; the fracture step refreshes its own).
  if (state.options.regularizer == Regularizer::kCorotational) {
    for (ObjectState& o : state.objects) {
      if (o.model.type() == ElasticModelType::kNeoHookean) continue;
      o.model.UpdateRotations(state.x.middleRows(o.offset, o.mesh.num_vertices()));
    }
  }
  s->time.rotations += Seconds(t0);
}

bool Tracker::Impl::PrepareIteration(int k, const FrameCloud& fc, const Vertices& previous,
                                     std::vector<DataPair>* pairs, PairCounts* counts_out, femreg::OuterIteration* row_out,
                                     FrameSummary* s) {
  const RegistrationOptions& options = state.options;
  femreg::OuterIteration& row = *row_out;
  PairCounts& counts = *counts_out;
  counts = PairCounts();
  auto t0 = Clock::now();
  const int hold = options.data.hold_pairs_after;
  FindPairs(PairState(), fc, Surface(), options.solver.num_threads, pairs, &counts, &warm_triangles,
            &paired_vertices, hold > 0 && k - iteration_base >= hold);
  s->time.correspondences += Seconds(t0);
  if (k == 0 && quiet_start) quiet_start = QuietPairs(*pairs);
  row.model_to_cloud = counts.model_to_cloud;
  row.cloud_to_model = counts.cloud_to_model;
  row.rejected = counts.rejected;
  const std::vector<int>& surface_vertices = PairState().surface_vertices;
  if (!surface_vertices.empty()) {
    s->coverage = static_cast<double>(counts.covered) / static_cast<double>(surface_vertices.size());
  }
  if (pairs->empty()) {
    s->rejected = counts.rejected;
    if (k == 0) {
      s->termination = TerminationType::kNoCorrespondences;
      s->message = "no correspondence within data.max_distance (" + std::to_string(counts.rejected) +
                   " rejected); the shape was held at the previous frame";
    }
    return false;
  }

  // Contacts at the current x, normals held for the solve; the margin D keeps pairs that
  // the solve may bring within D.
  t0 = Clock::now();
  frame_problem.SetData(*pairs, options);
  // Free space from the second outer iteration on (of the frame, or after a large motion's
  // stiff start): the first starts from the prediction, which may be off sideways, and the
  // pairs bring it near before the rays can tell which way is out.
  static const ObservedDepth kNothing;
  frame_problem.SetFreeSpace(state, k - iteration_base >= 1 ? fc.observed : kNothing);
  frame_problem.SetLoads(state);
  s->time.build += Seconds(t0);
  if (state.collision) {
    const auto t_collision = Clock::now();
    state.collision->SetFrame(state.frame);
    const Vertices& y = CollisionPositions();
    state.collision->Detect(y, state.collision->distance(), &state.contacts);
    row.contacts = static_cast<int>(state.contacts.size());
    frame_problem.SetContacts(state.contacts, *state.collision, state.contact_multipliers);
    // Friction's slip is from the previous frame's result, where the contacts last rested.
    frame_problem.SetFriction(state.contacts, *state.collision, state.contact_multipliers, y,
                              previous, std::max(0, state.frame - 1));
    s->time.collision += Seconds(t_collision);
  }
  // Equilibrium registration starts each frame (and a large motion's restart) with the
  // energy without it: Gauss-Newton on the force residual converges slowly from far away (its
  // curvature grows with the residual), and those iterations bring the shape near
  // (docs/theory/equilibrium.md).
  const bool warm_start = WarmStart(k);
  frame_problem.SetEquilibrium(state, estimate_forces && !warm_start, data_surface.get(), PushingOnly(), SmoothStart(k));
  return true;
}

namespace {

// Whether the marks hold an occluder proper (in front of the visible surface, 1), or the last
// frame's implausible points carried over (3, CarryImplausible) where that frame was switched
// (`after_switch`): the hand that held the body then most likely still does. Points found
// implausible alone are also a fast motion's or a crushed element's, where the physical mode
// does no better (tests/hard_cases_test.cc).
bool HeldMarks(const std::vector<char>& marks, bool after_switch) {
  return std::any_of(marks.begin(), marks.end(), [&](char m) { return m == 1 || (after_switch && m == 3); });
}

}  // namespace

void Tracker::Impl::SwitchToForcesWhereHeld(int k, const FrameCloud& fc, double* previous_energy,
                                            FrameSummary* s) {
  const RegistrationOptions& options = state.options;
  // Decided once an outer iteration from the frame's start (or from a restart's, after its
  // stiff stages: the physical mode's warm start too) has brought the model to the cloud, on
  // the marks less the points it reached, so that a part that lagged behind a fast motion is
  // not taken for a hand. Switched on only, never off, in a frame.
  if (estimate_forces || k != iteration_base + 1 || !options.forces.when_occluded ||
      options.regularizer == Regularizer::kNone || fc.occluders.occluders == 0 ||
      !HeldMarks(fc.occluder, switched_before)) {
    return;  // without a hand's marks, not even the release below: the frame stays as it was
  }
  const auto t0 = Clock::now();
  std::vector<char> marks = fc.occluder;  // the frame's own are released on its schedule
  ReleaseReached(PairState(), Surface(), fc.cloud.points, fc.spacing, &marks);
  estimate_forces = HeldMarks(marks, switched_before) &&
                    TouchingOccluderPoints(fc.cloud.points, *fc.index, fc.spacing, marks,
                                           kTouchingOccluderPoints) >= kTouchingOccluderPoints;
  s->time.correspondences += Seconds(t0);
  if (estimate_forces) {
    // As after the physical mode's warm start: another energy from here, and the stall test's
    // reference is the first equilibrium solve's.
    state.contact_multipliers = multipliers_at_start;
    merit = std::numeric_limits<double>::infinity();
    *previous_energy = merit;
    stall_reference = 0.0;
  }
}

bool Tracker::Impl::TimeBudgetUsed(Clock::time_point t_frame, FrameSummary* s) const {
  const double budget = state.options.solver.time_budget_s;
  if (!(budget > 0) || Seconds(t_frame) < budget) return false;
  s->termination = TerminationType::kTimeBudget;
  s->message = "time budget of " + std::to_string(budget) + " s used";
  return true;
}

EnergyTerms Tracker::Impl::Energy(const Vertices& x) const {
  return frame_problem.problem().Evaluate(x, state.options.solver.num_threads);
}

double Tracker::Impl::RmsResidual(const std::vector<DataPair>& pairs) {
  if (pairs.empty()) return 0.0;
  // The pairs index the surface they were found on: the data surface's vertices if there is one.
  const Vertices& paired = data_surface ? PairState().x : state.x;
  double sum2 = 0.0;
  for (const DataPair& p : pairs) sum2 += (p.Point(paired) - p.target).squaredNorm();
  return std::sqrt(sum2 / static_cast<double>(pairs.size()));
}

bool Tracker::Impl::WarmStart(int k) const {
  if (quiet_start) return false;
  return estimate_forces && k <= warm_until;
}

bool Tracker::Impl::PushingOnly() const {
  const ForceOptions& forces = state.options.forces;
  return estimate_forces && (forces.pushing_only || (!forces.estimate && forces.when_occluded_pushing_only));
}

bool Tracker::Impl::SmoothStart(int k) const {
  // Never a frame's last outer iteration: the frame's result is the pushing-only problem's.
  if (quiet_start) return k == smooth_after_split && k + 1 < iteration_limit;
  return PushingOnly() && k + 1 < iteration_limit &&
         (k == warm_until + 1 || k == smooth_after_split);
}

bool Tracker::Impl::Backtracks(int k, bool warm_start) const {
  // Not with fracture live: a piece coming apart raises the energy of the pairs it leaves, and
  // its move is the progress (as for the occluders and the reciprocity trim).
  return state.options.solver.backtrack && !warm_start && !FractureLive(state) && k >= rise_from &&
         std::isfinite(merit) && merit_x.rows() == state.x.rows();
}

bool Tracker::Impl::Backtrack(int k, const FrameCloud& fc, const Vertices& previous,
                              std::vector<DataPair>* pairs, PairCounts* counts,
                              femreg::OuterIteration* row, double* previous_energy, FrameSummary* s) {
  const RegistrationOptions& options = state.options;
  auto t0 = Clock::now();
  const double allowed = merit + options.solver.relative_energy_tolerance * std::abs(merit);
  double at = Energy(state.x).total();
  s->time.evaluation += Seconds(t0);
  s->time.solve += Seconds(t0);
  if (at <= allowed) return true;
  const double rose_to = at;
  const Vertices reached = state.x;
  for (int h = 1; h <= kBacktrackHalvings; ++h) {
    state.x = merit_x + std::ldexp(1.0, -h) * (reached - merit_x);
    UpdateElementRotations(s);
    if (!PrepareIteration(k, fc, previous, pairs, counts, row, s)) return false;
    t0 = Clock::now();
    at = Energy(state.x).total();
    s->time.evaluation += Seconds(t0);
    s->time.solve += Seconds(t0);
    ++s->backtracks;
    if (at <= allowed) {
      *previous_energy = std::numeric_limits<double>::infinity();  // that of another step
      return true;
    }
  }
  // No shorter step lowers it: the outer iterations cannot do better than that start (an
  // energy criterion: with relative_energy_tolerance 0, none stops a frame), unless a contact
  // there is deeper than the tolerance (its multiplier was lower). Else on from the move's
  // end, held against nothing.
  auto go_on = [&] {
    state.x = reached;
    merit = std::numeric_limits<double>::infinity();
    UpdateElementRotations(s);
    return PrepareIteration(k, fc, previous, pairs, counts, row, s);
  };
  if (!(options.solver.relative_energy_tolerance > 0)) return go_on();
  state.x = merit_x;
  UpdateElementRotations(s);
  if (!PrepareIteration(k, fc, previous, pairs, counts, row, s)) return false;
  if (state.collision &&
      state.collision->Evaluate(state.contacts, CollisionPositions()).max_penetration > state.collision->tolerance()) {
    return go_on();
  }
  // The frame's result is that start: its pairs and misfit (the next frame's quiet start and
  // the misfit ratio read them), not those of the move it gave up.
  s->final = Energy(state.x);
  s->model_to_cloud = counts->model_to_cloud;
  s->cloud_to_model = counts->cloud_to_model;
  s->rejected = counts->rejected;
  s->rms_residual = RmsResidual(*pairs);
  s->termination = TerminationType::kConverged;
  s->stopped_by = "backtrack";
  std::ostringstream os;
  os << "the energy with the pairs found after the last outer iteration rose from " << merit << " to "
     << rose_to << ", and along 1/" << (1 << kBacktrackHalvings)
     << " of its move it still rose: the frame keeps that iteration's start";
  s->message = os.str();
  return false;
}

bool Tracker::Impl::CutReversal(int k, bool comparable, const Vertices& before_solve, double start_energy,
                                femreg::OuterIteration* row, FrameSummary* s) {
  // While the last outer iteration's energy compares with this one's, merit_x is its start.
  if (!state.options.solver.cut_reversals || !comparable || k < rise_from || stepping_in || FractureLive(state) ||
      merit_x.rows() != state.x.rows()) {
    return false;
  }
  // Where the fixed-point map of the outer iterations turns a mode over (its factor lambda
  // near -1: a body that slides to and fro along a cloud denser than its mesh), each move
  // undoes the last and the frame never settles. With d_k = lambda d_(k-1) along that mode,
  // the fixed point is d_k / (1 - lambda) from this start: half the move at lambda = -1
  // (docs/theory/stopping.md#reversals). The last move runs from the last start to this one
  // (a backtrack's halving and a cut included).
  const Vertices move = state.x - before_solve;
  const double along = move.cwiseProduct(before_solve - merit_x).sum();
  const double last2 = (before_solve - merit_x).squaredNorm(), move2 = move.squaredNorm();
  if (!(last2 > 0 && move2 > 0 && along < kReversalCosine * std::sqrt(last2 * move2))) return false;
  const double share = std::clamp(1.0 / (1.0 - along / last2), kShortestReversalCut, 1.0);
  state.x = before_solve + share * move;
  const auto t0 = Clock::now();
  const EnergyTerms at = Energy(state.x);
  s->time.evaluation += Seconds(t0);
  s->time.solve += Seconds(t0);
  // Only a cut that keeps the solve's descent from its start (with its pairs, along the
  // segment the energy is all but convex).
  if (!(at.total() <= start_energy)) {
    state.x = before_solve + move;
    return false;
  }
  row->after = at;
  ++s->reversals;
  return true;
}

namespace {

// The augmented-Lagrangian update after a solve (docs/theory/contact.md#response): each
// contact's multiplier takes in the force its penetration still asks for, lambda <-
// max(0, lambda + k (-g)), and a contact still deeper than the tolerance that did not at
// least halve its penetration since the last outer iteration (or is new) gets 4 times its
// stiffness (the data's pull can be far stiffer than k, and the inner solve is truncated), kept
// while the contact is detected, so that one that flickers open and shut does not leak again.
// Contacts no longer detected drop both. True while a contact is deeper than the tolerance
// or held open wider than it: the frame goes on. Without `update_within_tolerance` (the
// physical mode, where the penalty is part of the potential, whose balance an update would
// upset by k p) a multiplier moves only outside the tolerance, or to release a contact open
// past its standoff, whose force is zero either way (docs/notes/2026-12-01-held-turns-in-the-step.md).
bool UpdateContactMultipliers(TrackerState* state, const Vertices& y, bool update_within_tolerance) {
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
    const double penetration = world.Penetration(c, y);
    const bool stalled = penetration > tolerance && penetration > 0.5 * m.penetration;
    if (update_within_tolerance || std::abs(penetration) > tolerance || -penetration * m.stiffness >= m.lambda) {
      m.lambda = std::max(0.0, m.lambda + m.stiffness * penetration);
    }
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
  UpdateElementRotations(s);
  if (!PrepareIteration(k, fc, *previous, pairs, &counts, &row, s)) return false;
  const bool warm_start = WarmStart(k);  // after the first pairs: QuietPairs
  // Its energy is not the next outer iteration's either: nothing to hold that one against.
  const bool another_energy = warm_start || SmoothStart(k);
  // The classic fit's misfit (forces.adaptive_weight): its warm start's shape, with the pairs
  // found there; none where a restart started the frame again after it (k - 1 was no fit).
  if (!warm_start && k > iteration_base && WarmStart(k - 1)) {
    misfit_reference = RmsResidual(*pairs);
    misfit_reference_x = state.x;
  }
  // Vertices in the seen-through space: free space pushes them out, a change of the problem
  // like new contact multipliers, which the last start's energy is not to undo.
  if (frame_problem.FreeSpaceHeld(state.x) > 0) merit = std::numeric_limits<double>::infinity();
  if (Backtracks(k, warm_start) && !Backtrack(k, fc, *previous, pairs, &counts, &row, previous_energy, s)) {
    return false;
  }
  // The last outer iteration's energy and this one's compare (no new contact multipliers, held
  // free space or another energy since): so do their moves (CutReversal).
  const bool comparable = std::isfinite(merit);
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
  s->time.assembly += report.assemble_s;
  s->time.factorization += report.factorize_s;
  s->time.linear_solve += report.linear_solve_s;
  s->time.evaluation += report.evaluate_s;
  s->factorizations += report.factorizations + report.hierarchies;
  s->linear_solves += report.linear_solves;
  s->pcg_iterations += report.pcg_iterations;
  row.inner_iterations = report.iterations;
  // Against the first solve of the frame's energy (a warm start's is another).
  if (!another_energy && !(stall_reference > 0.0)) stall_reference = report.largest_force_before;
  row.stalled = !another_energy && report.mostly_refused && stall_reference > 0.0 &&
                report.largest_force_after > 0.5 * stall_reference;
  if (!report.success) {
    s->termination = TerminationType::kSolverFailure;
    s->message = report.message + "; the shape before this iteration was kept";
    s->iterations.push_back(row);
    return false;
  }
  row.after = report.after;
  if (options.solver.hold_hidden_turns) {
    const bool balanced = estimate_forces && !another_energy;  // the energy the frame is judged by
    const Vertices solved = balanced ? state.x : Vertices();
    if (HoldHiddenTurns(state, before_solve, &state.x, data_surface.get())) {
      row.after = Energy(state.x);  // docs/theory/stopping.md#hidden-turns
      if (balanced && !(row.after.total() <= (1.0 + kSeenTurnRise) * report.after.total())) {
        state.x = solved;
        row.after = report.after;
      }
    }
  }
  CutReversal(k, comparable, before_solve, report.before.total(), &row, s);
  // The next outer iteration's energy, with what it finds, is held against this start's.
  merit = another_energy ? std::numeric_limits<double>::infinity() : report.before.total();
  merit_x = before_solve;
  // With the forces estimated, not after a warm or smooth start: their energy is not the one
  // whose balance the contact forces enter, and a classic fit's data springs press the body into
  // the table (docs/theory/contact.md#response).
  const bool contacts_pending =
      state.collision && state.collision->augmented() && !(estimate_forces && another_energy) &&
      UpdateContactMultipliers(&state, CollisionPositions(), /*update_within_tolerance=*/!estimate_forces);
  // New multipliers change the energy: the next start is not held against this one.
  if (contacts_pending) merit = std::numeric_limits<double>::infinity();
  // The largest vertex move of this outer iteration and the one 99 % of the free vertices
  // stay within (compared below with the mesh's edge and the cloud's sampling distance).
  const Eigen::VectorXd moves = (state.x - before_solve).rowwise().norm();
  double moved = moves.size() > 0 ? moves.maxCoeff() : 0.0;
  double bulk = BulkMove(state, moves, frame_problem.problem().fixed());
  row.max_move = moved;
  row.bulk_move = bulk;
  first_bulk_move = k == 0 ? bulk : first_bulk_move;
  row.rms_residual = RmsResidual(*pairs);
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
      // A piece just freed is not held to where the whole body started the frame: its
      // temporal springs start from here.
      if (state.fracture->separated) state.frame_start = state.x;
      frame_problem.BuildElastic(state);
      frame_problem.BuildFrameTerms(&state);
      state.contact_multipliers.clear();  // keyed by the old vertex numbering
      merit = std::numeric_limits<double>::infinity();  // another mesh
      model_index.Reset();
      warm_triangles.clear();  // a new surface
      paired_vertices.clear();
      FindPairs(PairState(), fc, Surface(), options.solver.num_threads, pairs, &counts);  // for the outputs
      moved = std::numeric_limits<double>::infinity();  // a new topology: not converged
      bulk = moved;
      // The next outer iteration forms a new pair set, held from the one after.
      rise_from = std::max(k + 2, std::max(1, options.data.hold_pairs_after));
      smooth_after_split = k + 1;  // the pieces' pushing-only equilibrium is far: SmoothStart
    }
  }

  // Compare with the previous outer iteration's result (its pairs were different, so the
  // energy before this iteration's solve is not comparable; after a split, with nothing).
  // The frame stops when the outer iteration changed the energy by less than the tolerance,
  // or raised it by more (stopped_by "energy_rise") unless the rise goes on: before the pair
  // set is held (rise_from: pairs still join as the surface reaches the cloud), during a move
  // of more than kRiseMoveLimit mean edges, or by more than kRiseEnergyLimit of the previous
  // energy (see there).
  if (another_energy) {  // nothing to compare with
    *previous_energy = std::numeric_limits<double>::infinity();
    return !TimeBudgetUsed(t_frame, s) && k + 1 < iteration_limit;
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
  // A bulk move larger than what the fit still misses by is one the cloud resolves: the
  // next outer iteration would change the fit (docs/theory/stopping.md).
  const bool resolved = pairs->empty() || bulk <= row.rms_residual;
  const bool settled = bulk_limit > 0 && bulk <= bulk_limit && resolved;
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
         << bulk_reference * 1e3 << " mm and the fit's RMS residual " << row.rms_residual * 1e3
         << " mm (the largest move " << moved * 1e3 << " mm)";
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
  if (TimeBudgetUsed(t_frame, s)) return false;
  if (k + 1 == iteration_limit) {
    s->termination = TerminationType::kMaxIterations;
    s->message = "reached solver.max_outer_iterations = " + std::to_string(options.solver.max_outer_iterations);
    if (iteration_budget != options.solver.max_outer_iterations) {
      s->message += " x " + std::to_string(iteration_budget / options.solver.max_outer_iterations) +
                    " (catching up after " + std::to_string(missed_frames) + " held or lost frames)";
    }
    if (s->large_motion_restarts > 0) s->message += " after a large motion's " + std::to_string(iteration_base) + " stiff start";
    if (s->crushed_restarts > 0) s->message += " after a crushed element's " + std::to_string(iteration_base) + " stiff start";
    if (s->implausible_restarts > 0 && s->large_motion_restarts == 0 && s->crushed_restarts == 0) {
      s->message += " since the frame started again without implausible points (" +
                    std::to_string(iteration_base) + " outer iterations before)";
    }
  }
  return true;
}

void Tracker::Impl::MeasureContacts(FrameSummary* s) {
  const auto t0 = Clock::now();
  state.collision->SetFrame(state.frame);
  const Vertices& y = CollisionPositions();
  state.collision->Detect(y, 0.0, &state.contacts);
  const ContactStats cs = state.collision->Evaluate(state.contacts, y);
  s->contacts = cs.contacts;
  s->object_contacts = cs.object_contacts;
  s->obstacle_contacts = cs.obstacle_contacts;
  s->max_penetration = cs.max_penetration;
  s->min_gap = cs.min_gap;
  s->contact_forces = frame_problem.ContactForces(state.x);
  s->time.collision += Seconds(t0);
}

}  // namespace femreg
