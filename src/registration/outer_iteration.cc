// An outer iteration's set-up at the current shape (rotations, pairs, loads, contacts, the
// equilibrium terms) and the backtracking that holds its start against the last one's
// (docs/theory/stopping.md#backtracking). The loop that runs them is in tracker.cc.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <sstream>
#include <string>
#include <vector>

#include "registration/correspondences.h"
#include "registration/frame_problem.h"
#include "registration/tracker_impl.h"
#include "registration/tracker_state.h"

namespace femreg {

namespace {

// Halvings of an outer iteration's move tried when the energy it reached, with its new pairs,
// is more than kRiseEnergyLimit above its start's (Backtrack): down to an eighth of the move.
constexpr int kBacktrackHalvings = 3;

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
  FindPairs(state, fc, Surface(), options.solver.num_threads, pairs, &counts, &warm_triangles,
            &paired_vertices, hold > 0 && k - iteration_base >= hold);
  s->time.correspondences += Seconds(t0);
  row.model_to_cloud = counts.model_to_cloud;
  row.cloud_to_model = counts.cloud_to_model;
  row.rejected = counts.rejected;
  if (!state.surface_vertices.empty()) {
    s->coverage = static_cast<double>(counts.covered) / static_cast<double>(state.surface_vertices.size());
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
  frame_problem.SetLoads(state);
  s->time.build += Seconds(t0);
  if (state.collision) {
    const auto t_collision = Clock::now();
    state.collision->SetFrame(state.frame);
    state.collision->Detect(state.x, state.collision->distance(), &state.contacts);
    row.contacts = static_cast<int>(state.contacts.size());
    frame_problem.SetContacts(state.contacts, *state.collision, state.contact_multipliers);
    // Friction's slip is from the previous frame's result, where the contacts last rested.
    frame_problem.SetFriction(state.contacts, *state.collision, state.contact_multipliers, state.x,
                              previous, std::max(0, state.frame - 1));
    s->time.collision += Seconds(t_collision);
  }
  // Equilibrium registration starts each frame with one outer iteration of the energy without
  // it: Gauss-Newton on the force residual converges slowly from far away (its curvature
  // grows with the residual), and that iteration brings the shape near (docs/theory/equilibrium.md).
  const bool warm_start = options.forces.estimate && k == 0;
  frame_problem.SetEquilibrium(state, options.forces.estimate && !warm_start);
  return true;
}

bool Tracker::Impl::Backtracks(int k, bool warm_start) const {
  // Not with fracture on: a piece coming apart raises the energy of the pairs it leaves, and
  // its move is the progress (as for the occluders and the reciprocity trim).
  return state.options.solver.backtrack && !warm_start && !state.fracture && k >= rise_from &&
         std::isfinite(merit) && merit_x.rows() == state.x.rows();
}

bool Tracker::Impl::Backtrack(int k, const FrameCloud& fc, const Vertices& previous,
                              std::vector<DataPair>* pairs, PairCounts* counts,
                              femreg::OuterIteration* row, double* previous_energy, FrameSummary* s) {
  const RegistrationOptions& options = state.options;
  auto t0 = Clock::now();
  const double allowed = merit + options.solver.relative_energy_tolerance * std::abs(merit);
  double at = frame_problem.problem().Evaluate(state.x).total();
  s->time.evaluation += Seconds(t0);
  if (at <= allowed) return true;
  const double rose_to = at;
  const Vertices reached = state.x;
  for (int h = 1; h <= kBacktrackHalvings; ++h) {
    state.x = merit_x + std::ldexp(1.0, -h) * (reached - merit_x);
    UpdateElementRotations(s);
    if (!PrepareIteration(k, fc, previous, pairs, counts, row, s)) return false;
    t0 = Clock::now();
    at = frame_problem.problem().Evaluate(state.x).total();
    s->time.evaluation += Seconds(t0);
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
      state.collision->Evaluate(state.contacts, state.x).max_penetration > state.collision->tolerance()) {
    return go_on();
  }
  s->final = frame_problem.problem().Evaluate(state.x);
  s->termination = TerminationType::kConverged;
  s->stopped_by = "backtrack";
  std::ostringstream os;
  os << "the energy with the pairs found after the last outer iteration rose from " << merit << " to "
     << rose_to << ", and along 1/" << (1 << kBacktrackHalvings)
     << " of its move it still rose: the frame keeps that iteration's start";
  s->message = os.str();
  return false;
}

}  // namespace femreg
