// The forward solve with fracture (SolveQuasiStaticWithFracture): solve, detect, split,
// carry the problem to the split mesh, again; see femreg/fracture.h.
#include <algorithm>
#include <numeric>
#include <string>
#include <utility>
#include <vector>

#include "femreg/fracture.h"

namespace femreg {

Status SolveQuasiStaticWithFracture(ForwardProblem* problem, const ForwardOptions& forward,
                                    const FractureOptions& options, int max_rounds,
                                    double density, ElasticModel* model, TetMesh* mesh,
                                    std::vector<int>* original, std::vector<FractureEvent>* events,
                                    ForwardSummary* summary) {
  if (static_cast<int>(original->size()) != mesh->num_vertices()) {
    original->resize(mesh->num_vertices());
    std::iota(original->begin(), original->end(), 0);
  }
  int splits = 0;
  for (int round = 0;; ++round) {
    Status status = SolveQuasiStatic(*problem, forward, model, mesh, summary);
    if (!status.ok()) return status;
    if (!summary->IsSolutionUsable()) {
      return Status::Error("forward solve failed after " + std::to_string(splits) +
                           " splits: " + summary->message);
    }
    if (round >= max_rounds || splits >= options.max_splits_per_frame) break;
    model->UpdateRotations(mesh->x);
    NodeSeparation separation;
    DetectFracture(*mesh, *model, mesh->x, options, &separation);
    TopologyChange change;
    SplitNodes(separation, options,
               std::min(options.max_splits_per_iteration, options.max_splits_per_frame - splits),
               mesh, model, &change);
    if (!change.changed()) break;
    splits += static_cast<int>(change.events.size());
    for (FractureEvent& e : change.events) {
      e.original_node = (*original)[e.node];
      events->push_back(e);
    }
    // Carry the problem: every copy of a clamped or prescribed vertex keeps its condition.
    std::vector<std::vector<int>> copies(change.source.empty() ? 0 : original->size());
    for (size_t v = 0; v < change.source.size(); ++v) copies[change.source[v]].push_back(static_cast<int>(v));
    ForwardProblem carried;
    carried.gravity = problem->gravity;
    for (int v : problem->clamped)
      for (int c : copies[v]) carried.clamped.push_back(c);
    for (const auto& p : problem->prescribed)
      for (int c : copies[p.first]) carried.prescribed.emplace_back(c, p.second);
    for (const auto& p : problem->nodal_loads)
      if (!copies[p.first].empty()) carried.nodal_loads.emplace_back(copies[p.first][0], p.second);
    *problem = std::move(carried);
    std::vector<int> carried_original(change.source.size());
    for (size_t v = 0; v < change.source.size(); ++v) carried_original[v] = (*original)[change.source[v]];
    *original = std::move(carried_original);
    ComputeLumpedMasses(mesh, density);
  }
  return Status::Ok();
}

}  // namespace femreg
