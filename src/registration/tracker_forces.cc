// The tracker's forces after a frame: the estimated external forces and their resultant, and
// forces.adaptive_weight's check before the weight falls (docs/guide/forces.md#choosing-the-weight).
#include <algorithm>
#include <chrono>
#include <memory>
#include <vector>

#include "femreg/forward.h"
#include "parallel/stopwatch.h"
#include "energy/equilibrium.h"
#include "registration/force_weight.h"
#include "registration/frame_problem.h"
#include "registration/tracker_impl.h"
#include "registration/tracker_state.h"
#include "solvers/backend.h"

namespace femreg {

bool Tracker::Impl::LowerForceWeightPays(double lower_scale, const std::vector<DataPair>& pairs,
                                         Clock::time_point t_frame, FrameSummary* s) {
  // A lower weight must pay: with no classic fit to compare (a restart dropped it, the mesh
  // changed), no pairs, or a frame that ended without its equilibrium terms, it does not.
  const std::shared_ptr<const energy::Equilibrium> solved = frame_problem.problem().shared_equilibrium();
  if (misfit_reference_x.rows() != state.x.rows() || pairs.empty() || !solved) return false;
  // Within solver.time_budget_s: a frame that used it up does not check, and keeps the weight.
  const double budget = state.options.solver.time_budget_s;
  if (budget > 0 && Seconds(t_frame) >= budget) return false;
  const double reference = Energy(misfit_reference_x).data;
  // The frame's own terms with the lower penalty, solved aside: the frame keeps its result,
  // the problem its terms and the back end what it carries on; only the weight may move.
  auto probe = std::make_shared<energy::Equilibrium>(*solved);
  probe->ScaleWeights(lower_scale / state.force_weight_scale);
  frame_problem.SetEquilibrium(std::move(probe));
  Vertices x = state.x;
  const auto t0 = Clock::now();
  const double time_left = budget > 0 ? std::max(1e-3, budget - Seconds(t_frame)) : 0.0;
  const SolveReport report = backend->SolveAside(frame_problem.problem(), time_left, &x);
  s->time.solve += Seconds(t0);
  frame_problem.SetEquilibrium(solved);
  s->factorizations += report.factorizations + report.hierarchies;
  s->linear_solves += report.linear_solves;
  s->pcg_iterations += report.pcg_iterations;
  if (!report.success) return false;
  // The misfit the forces leave beyond the classic fit's: none, nothing for a lower weight to explain.
  const double excess = report.before.data - reference;
  if (!(excess > 0.0)) return false;
  return report.after.data - reference <= kLowerWeightKeeps * excess;
}

void Tracker::Impl::MeasureForces(FrameSummary* s) {
  // A frame held at the last one's shape (no usable cloud, no pairs) measures none: its
  // FrameSummary::force and torque stay zero, and so do the per-vertex forces.
  const TerminationType t = s->termination;
  if (t == TerminationType::kInvalidInput || t == TerminationType::kTooFewPoints ||
      t == TerminationType::kNoCorrespondences) {
    for (Vertices& f : state.external_forces) f.setZero();
    return;
  }
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
