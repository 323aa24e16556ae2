// The tracker's forces after a frame: the estimated external forces and their resultant, and
// forces.adaptive_weight's check before the weight falls (docs/guide/forces.md#choosing-the-weight).
#include <chrono>
#include <vector>

#include "femreg/forward.h"
#include "parallel/stopwatch.h"
#include "registration/force_weight.h"
#include "registration/frame_problem.h"
#include "registration/tracker_impl.h"
#include "registration/tracker_state.h"
#include "solvers/backend.h"

namespace femreg {

bool Tracker::Impl::LowerForceWeightPays(double lower_scale, const std::vector<DataPair>& pairs,
                                         Clock::time_point t_frame, FrameSummary* s) {
  if (misfit_reference_x.rows() != state.x.rows() || pairs.empty()) return true;
  // Within solver.time_budget_s: a frame that used it up does not check, and keeps the weight.
  const double budget = state.options.solver.time_budget_s;
  if (budget > 0 && Seconds(t_frame) >= budget) return false;
  const Vertices result = state.x;
  const double scale = state.force_weight_scale;
  const double reference = frame_problem.problem().Evaluate(misfit_reference_x).data;
  state.force_weight_scale = lower_scale;
  frame_problem.SetEquilibrium(state, true, data_surface.get());
  const auto t0 = Clock::now();
  const SolveReport report = backend->Solve(frame_problem.problem(), budget > 0 ? budget - Seconds(t_frame) : 0.0, &state.x);
  s->time.solve += Seconds(t0);
  // The frame keeps its result and the problem its weight: only the next frames' weight moves.
  state.x = result;
  state.force_weight_scale = scale;
  frame_problem.SetEquilibrium(state, true, data_surface.get());
  if (!report.success) return false;
  return report.after.data - reference <= kLowerWeightKeeps * (report.before.data - reference);
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

}  // namespace femreg
