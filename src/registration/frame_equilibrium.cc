// The frame problem's equilibrium terms (registration.forces) and the external forces it
// reports (docs/guide/forces.md).
#include <algorithm>
#include <cmath>
#include <memory>
#include <vector>

#include "energy/equilibrium.h"
#include "registration/frame_problem.h"
#include "registration/prediction.h"

namespace femreg {

using energy::TermGroup;

namespace {
// The smooth start's steps: it brings the shape near the pushing-only equilibrium. One cost
// hand_press 1.2 times the time a frame, no cap (up to 10) the 3,375-vertex organ 1.3 times
// (docs/notes/2026-12-05-pushing-only-smooth-start.md).
constexpr int kSmoothStartSteps = 2;
}  // namespace

void FrameProblem::SetEquilibrium(const TrackerState& state, bool on, DataSurface* data, bool pushing_only,
                                  bool smooth_start) {
  const ForceOptions& options = state.options.forces;
  if (!on) {
    problem_.SetEquilibrium(nullptr);
    return;
  }
  const int n = state.num_vertices;
  auto eq = std::make_shared<energy::Equilibrium>();
  eq->site.assign(n, energy::ForceSite::kBalanced);
  eq->force_weight.assign(n, 0.0);
  eq->strong_weight.assign(n, 0.0);
  if (options.sparsity > 0) eq->sparsity.assign(n, 0.0);
  eq->pushing_only = pushing_only && !smooth_start;
  // Without the pushing-only penalty that was asked for: the smooth start, two steps.
  if (pushing_only && smooth_start) eq->max_steps = kSmoothStartSteps;
  eq->friction = options.friction;
  if (eq->pushing_only) {
    const Eigen::MatrixXd normals = state.VertexNormals();
    eq->normal.resize(n);
    for (int v = 0; v < n; ++v) eq->normal[v] = normals.row(v).transpose();
  }
  const double data_per_area = state.options.weights.data_per_area;
  double floor_sum = 0.0;
  int floor_count = 0;
  for (size_t i = 0; i < state.objects.size(); ++i) {
    const ObjectState& o = state.objects[i];
    // The traction scale c = k_d (L / E)^2 (ForceOptions::weight), L the cube root of the
    // body's volume: a traction t over the body deforms it by about t L / E, which the data
    // term prices at k_d (t L / E)^2 per area.
    double volume = 0.0;
    for (int e = 0; e < o.model.num_elements(); ++e) volume += o.model.rest(e).volume;
    const double L = std::cbrt(std::max(volume, 1e-300));
    const double E = o.material.material.youngs_modulus;
    const double c = data_per_area * (L / E) * (L / E);
    const double alpha = options.weight * state.force_weight_scale * c;
    double area_sum = 0.0;
    for (int v : o.mesh.surface_vertices) area_sum += vertex_area_[static_cast<size_t>(o.offset + v)];
    const double mean_area =
        o.mesh.surface_vertices.empty() ? 1.0 : area_sum / static_cast<double>(o.mesh.surface_vertices.size());
    const double traction = 0.01 * E;
    const std::vector<char>* region =
        i < state.force_region.size() && !state.force_region[i].empty() ? &state.force_region[i] : nullptr;
    for (int v = 0; v < o.mesh.num_vertices(); ++v) {
      const int g = o.offset + v;
      eq->strong_weight[g] = options.balance * alpha / mean_area;  // a balanced vertex's
    }
    for (int v : o.mesh.surface_vertices) {
      const int g = o.offset + v;
      if (region != nullptr) {
        // After fracture splits, a replica is in the region where its source vertex was.
        int source = v;
        if (static_cast<int>(region->size()) != o.mesh.num_vertices() && state.fracture) {
          source = state.fracture->original[i][static_cast<size_t>(v)];
        }
        if (source < 0 || source >= static_cast<int>(region->size()) || !(*region)[static_cast<size_t>(source)]) continue;
      }
      const double area = std::max(vertex_area_[static_cast<size_t>(g)], 1e-3 * mean_area);
      eq->site[g] = energy::ForceSite::kFree;
      eq->force_weight[g] = alpha / area;
      eq->strong_weight[g] = options.balance * alpha / area;
      if (!eq->sparsity.empty()) eq->sparsity[g] = options.sparsity * alpha * traction;
    }
    floor_sum += 1e-3 * traction * mean_area;
    ++floor_count;
  }
  eq->sparsity_floor = floor_count > 0 ? floor_sum / floor_count : 1.0;
  // The hold of the outer iterations (docs/theory/stopping.md#hidden-turns) inside the solve:
  // its steps along a turn the data do not show gained little and were taken back after it.
  if (state.options.solver.hold_hidden_turns) {
    for (size_t i = 0; i < state.objects.size(); ++i) {
      const ObjectState& o = state.objects[i];
      for (const Eigen::Vector3d& axis : HiddenTurnAxes(state, static_cast<int>(i), state.x, data)) {
        eq->held_turns.push_back({o.offset, o.mesh.num_vertices(), axis});
      }
    }
  }
  // Clamps and anchors: their reaction is whatever holds them.
  for (const auto& kv : state.anchors) {
    for (int g : kv.second.vertices) eq->site[g] = energy::ForceSite::kSupport;
  }
  for (int v = 0; v < n; ++v) {
    if (problem_.is_fixed(v)) eq->site[v] = energy::ForceSite::kSupport;
    // The preconditioner's weight for a balanced or supported vertex (Equilibrium: a support's
    // reaction is free; its force_weight only scales the step's preconditioner).
    if (eq->force_weight[v] == 0.0) eq->force_weight[v] = eq->strong_weight[v] / std::max(options.balance, 1.0);
  }
  problem_.SetEquilibrium(std::move(eq));
}

Vertices FrameProblem::ExternalForces(const TrackerState& state) const {
  auto bit = [](TermGroup g) { return 1u << static_cast<int>(g); };
  Eigen::VectorXd f;
  if (problem_.equilibrium() != nullptr) {
    // What the elastic forces and the loads leave unbalanced: the estimated forces and the contacts'.
    energy::ForceResidual(problem_, state.x, &f,
                          bit(TermGroup::kElastic) | bit(TermGroup::kBarrier) | bit(TermGroup::kLoad));
  } else {
    // The data term's pull and the contacts' push, from their blocks alone (the elastic
    // elements' would cost a pass over the mesh every frame).
    energy::ForceResidual(problem_, state.x, &f, bit(TermGroup::kData) | bit(TermGroup::kCollision),
                          energy::Curvature::kGaussNewton);
    f = -f;
  }
  Vertices forces = Eigen::Map<const Eigen::Matrix<double, Eigen::Dynamic, 3, Eigen::RowMajor>>(f.data(), state.num_vertices, 3);
  for (const auto& kv : state.anchors) {
    for (int g : kv.second.vertices) forces.row(g).setZero();
  }
  return forces;
}

}  // namespace femreg
