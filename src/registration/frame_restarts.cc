// A frame's restarts: a large motion's or a crushed element's, stiff and stepping in
// (docs/theory/stopping.md#large-motions), and one without the cloud points found
// implausible (docs/guide/partial-views.md#implausible-points); and a pushing-only frame's
// quiet start, without the warm start (docs/theory/equilibrium.md#where-a-pushing-only-frame-starts).
// The frame loop that calls them is in tracker.cc.
#include <algorithm>
#include <chrono>
#include <limits>

#include "parallel/stopwatch.h"
#include "registration/correspondences.h"
#include "registration/fracture_step.h"
#include "registration/occluders.h"
#include "registration/tracker_impl.h"

namespace femreg {

namespace {

// Restarts for implausible points per frame (data.max_strain_step): each removes what it found.
constexpr int kMaxImplausibleRestarts = 2;
// Implausible points below this share of the cloud's weight (those marked since the frame
// last started) strained a few elements (single points of a dense cloud at a fine mesh's
// small elements), not the shape: the frame goes on from where it is without them. From it
// on (a hand's fingers: 5-60 % of hand_press's points) it starts again
// (docs/notes/2026-12-02-fine-box-stalls.md).
constexpr double kImplausibleRestartShare = 0.001;
// The elastic weight's scales of a stiff start, one outer iteration each.
constexpr double kStiffScales[] = {100.0, 30.0, 10.0, 3.0};

// The weight of the cloud's points (SubsampleCloud's: what each stands for), and of those
// marked implausible.
double CloudWeight(const FrameCloud& fc) {
  return fc.weights.size() == fc.cloud.points.rows() ? fc.weights.sum() : static_cast<double>(fc.cloud.points.rows());
}
double ImplausibleWeight(const FrameCloud& fc) {
  const bool weighted = fc.weights.size() == fc.cloud.points.rows();
  double sum = 0.0;
  for (size_t i = 0; i < fc.occluder.size(); ++i) {
    if (fc.occluder[i] == 2) sum += weighted ? fc.weights[static_cast<Eigen::Index>(i)] : 1.0;
  }
  return sum;
}

// QuietStart's limits (docs/notes/2026-12-07-quiet-pushing-only-starts.md): the last frame's
// move in mean edges, on average and at most, within which its equilibrium is near enough to
// start from (the beams' bending frames move more, and started so made more factorizations);
// and the first pairs' RMS residual against the last frame's final one, above which the
// cloud jumped and the warm start is needed.
constexpr double kQuietMeanMove = 0.25;
constexpr double kQuietLargestMove = 0.75;
constexpr double kQuietMisfit = 1.25;
// A frame's cost for QuietStart's choice: its factorizations and its PCG iterations at this many
// a factorization (about what one costs in time in the physical mode), counts rather than a time
// so that the choice is the same on any machine. A quiet start that cost more than the last warm
// start leaves kQuietBackoff frames to the warm start before QuietStart may choose again.
constexpr double kPcgPerFactorization = 8.0;
constexpr int kQuietBackoff = 3;

}  // namespace

void Tracker::Impl::StartAgain(const Vertices& start, int base) {
  state.x = start;
  iteration_base = base;
  iteration_limit = base + iteration_budget;
  rise_from = base + std::max(1, state.options.data.hold_pairs_after);
  warm_triangles.clear();
  paired_vertices.clear();
  ResetStartReferences();
}

void Tracker::Impl::StepIn(int k, double* previous_energy) {
  if (!stepping_in) return;
  const int stage = k - stiff_from;
  stepping_in = stage < stiff_stages;
  frame_problem.SetElasticScale(state, stepping_in ? kStiffScales[stage] : 1.0);
  merit = std::numeric_limits<double>::infinity();  // another energy
  *previous_energy = merit;
}

void Tracker::Impl::RestartStiff(int k, bool large_motion, bool go_on, const Vertices& start, FrameCloud* fc,
                                 FrameSummary* s) {
  // Back to the start, stiff, then softer stage by stage, pairing only surface that faces
  // the sensor (docs/theory/stopping.md#large-motions). A frame catching up after held or
  // lost ones starts so too: its held shape is several frames' motion away, and its
  // pairs can twist a symmetric cross-section into the wrong turn as a large motion's do.
  // So does a frame whose first solves crushed an element, where asked
  // (solver.stiff_restart_volume): their pairs were wrong at that distance too. Only a
  // large motion's restart drops the velocity (Track, after the loop): a crushed frame did not jump.
  stiff_stages = static_cast<int>(sizeof(kStiffScales) / sizeof(kStiffScales[0]));
  stepping_in = true;
  fc->facing_only = true;
  stiff_from = k + 1;
  StartAgain(start, stiff_from + stiff_stages);
  warm_until = iteration_base;
  quiet_start = false;
  const int hold = state.options.data.hold_pairs_after;
  if (hold > 0) redecide_until = iteration_base + hold;  // 0: never held, never decided again
  ++(large_motion ? s->large_motion_restarts : s->crushed_restarts);
  if (!go_on) {  // a crushed frame that had stopped goes on
    s->termination = TerminationType::kNotRun;
    s->stopped_by.clear();
    s->message.clear();
  }
}

void Tracker::Impl::MarkImplausibleOrRestart(
    int k, const Vertices& start, const std::function<bool(const Eigen::Vector3d&, const Eigen::Vector3d&)>& faces,
    FrameCloud* fc, double* previous_energy, FrameSummary* s) {
  if (stepping_in || FractureLive(state) || s->implausible_restarts >= kMaxImplausibleRestarts ||
      k + 1 >= iteration_limit || !(state.options.data.max_strain_step > 0)) {
    return;
  }
  const auto t0 = Clock::now();
  // A cage around an embedded surface holds more than the body: no side test there.
  const int marked = MarkImplausible(state, start, fc->cloud.points, *fc->index, fc->spacing, faces, &fc->occluder,
                                     data_surface == nullptr);
  s->time.correspondences += Seconds(t0);
  if (marked > 0) {
    fc->occluders.occluders += marked;
    s->occluded_points = fc->occluders.occluders;
    s->implausible_points += marked;
  }
  if (marked > 0 && ImplausibleWeight(*fc) - implausible_at_start < kImplausibleRestartShare * CloudWeight(*fc)) {
    // Another energy from here: not compared with the last.
    merit = std::numeric_limits<double>::infinity();
    *previous_energy = merit;
  } else if (marked > 0) {
    // Back to the start without them: the shape they pulled into is no starting point.
    ++s->implausible_restarts;
    implausible_at_start = ImplausibleWeight(*fc);
    StartAgain(start, k + 1);
    // After a large motion's restart the frame's start is far: with the forces estimated,
    // one outer iteration without the equilibrium terms first again (WarmStart).
    if (warm_until > 0) warm_until = iteration_base;
    merit = std::numeric_limits<double>::infinity();
    *previous_energy = merit;
  }
}

bool Tracker::Impl::QuietStart() const {
  if (quiet_backoff > 0 || !estimate_forces || !PushingOnly() || state.options.forces.adaptive_weight ||
      state.frame == 0 || FractureLive(state)) {
    return false;
  }
  // The fast back end's steps only: Ceres's trust region, without held turns, ended further from
  // the truth from such a start (docs/notes/2026-12-07-quiet-pushing-only-starts.md).
  if (backend->type() != SolverBackend::kFast) return false;
  // Every object clamped (three vertices or more fixed by hard anchors): a free body's
  // equilibrium is flat along the rigid motions that cheap forces explain, and the warm start's
  // classic fit places it (docs/notes/2026-12-07-quiet-pushing-only-starts.md).
  const std::vector<char>& fixed = frame_problem.problem().fixed();
  for (const ObjectState& o : state.objects) {
    const auto first = fixed.begin() + std::min<size_t>(fixed.size(), static_cast<size_t>(o.offset));
    const auto last = fixed.begin() + std::min<size_t>(fixed.size(), static_cast<size_t>(o.offset + o.mesh.num_vertices()));
    if (std::count(first, last, 1) < 3) return false;
  }
  return true;
}

bool Tracker::Impl::MovedLittle(const Vertices& previous) const {
  if (previous.rows() != state.x.rows() || previous.rows() == 0 || !(state.mean_edge_length > 0)) return false;
  const Eigen::VectorXd moves = (state.x - previous).rowwise().norm();
  return moves.mean() <= kQuietMeanMove * state.mean_edge_length &&
         moves.maxCoeff() <= kQuietLargestMove * state.mean_edge_length;
}

void Tracker::Impl::CountQuietCost(bool quiet, const FrameSummary& s) {
  if (quiet_backoff > 0) --quiet_backoff;
  if (!estimate_forces || !PushingOnly()) return;
  const double cost = s.factorizations + s.pcg_iterations / kPcgPerFactorization;
  if (!quiet) {
    last_warm_cost = cost;
  } else if (last_warm_cost >= 0.0 && cost > last_warm_cost) {
    quiet_backoff = kQuietBackoff;
  }
}

bool Tracker::Impl::QuietPairs(const std::vector<DataPair>& pairs) {
  return !pairs.empty() && last_frame_rms > 0.0 && RmsResidual(pairs) <= kQuietMisfit * last_frame_rms;
}

}  // namespace femreg
