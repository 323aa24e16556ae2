// The cut through a section (FractureOptions::cut_through): once a crack opens, the band of
// elements near its plane is parted in the same step; see femreg/fracture.h.
#include <algorithm>
#include <cmath>
#include <vector>

#include "fracture/split_state.h"

namespace femreg {
namespace fracture_internal {

namespace {

// The cut through's evidence: a gap of half the data's loss scale beyond the noise level
// near the crack (the tracker's fit of a still whole mesh to a cloud in two pieces leaves
// less than the whole gap at any one vertex).
constexpr double kCutEvidence = 0.5;

}  // namespace

std::vector<int> SplitState::CutThrough(int j, const Eigen::Vector3d& m) {
  double h = 0.0;
  int edges = 0;
  for (int e : star[j]) {
    for (int a = 0; a < 4; ++a)
      for (int b = a + 1; b < 4; ++b, ++edges) h += (rest[tets[e][a]] - rest[tets[e][b]]).norm();
  }
  if (edges == 0) return {};
  h /= edges;
  const Eigen::Vector3d q = rest[j];
  auto side = [&](int e) { return m.dot(RestCentroid(e) - q); };
  // The band: grown from j's elements (and the crack's copies of j) through shared vertices.
  std::vector<char> in_band(tets.size(), 0), visited(rest.size(), 0);
  std::vector<int> queue;
  for (size_t v = 0; v < rest.size(); ++v) {
    if (rest[v] == q && !star[v].empty()) {
      queue.push_back(static_cast<int>(v));
      visited[v] = 1;
    }
  }
  std::vector<int> band_vertices;
  for (size_t i = 0; i < queue.size(); ++i) {
    const int v = queue[i];
    band_vertices.push_back(v);
    for (int e : star[v]) {
      if (in_band[e] || std::abs(side(e)) > h) continue;
      in_band[e] = 1;
      for (int u : tets[e]) {
        if (!visited[u]) {
          visited[u] = 1;
          queue.push_back(u);
        }
      }
    }
  }
  std::sort(band_vertices.begin(), band_vertices.end());
  std::vector<int> replicated;
  for (int v : band_vertices) {
    std::vector<int> positive, negative;
    for (int e : star[v]) (side(e) > 0 ? positive : negative).push_back(e);
    if (positive.empty() || negative.empty()) continue;
    const int r = AddReplica(v);
    for (int e : positive) {
      Reassign(e, v, r);
      star[r].push_back(e);
    }
    star[v] = negative;
    replicated.push_back(v);
  }
  std::vector<int> local = replicated;
  for (int v : replicated) {
    for (int e : star[v])
      for (int u : tets[e]) local.push_back(u);
  }
  std::sort(local.begin(), local.end());
  local.erase(std::unique(local.begin(), local.end()), local.end());
  for (int v : local) SplitPinched(v);
  return replicated;
}

void CutThroughSection(const NodeSeparation& sep, const FractureOptions& options,
                       const ElasticModel& model, int nv, int nt, SplitState* state,
                       TopologyChange* change) {
  SplitState& st = *state;
  // The crack's first node, whose plane the splits followed, taken to the rest frame by
  // one of its elements' rotations.
  const FractureEvent& first = change->events.front();
  const int j = first.node;
  bool evidence = sep.gap.size() != nv;
  if (!evidence) {
    // The data's gap anywhere within two mean edges of the crack's node (rest frame): a
    // snapped cut runs along the nearest face loop, where the gap itself need not be.
    double h = 0.0;
    for (int e : st.star[j])
      for (int a = 0; a < 4; ++a) h += (st.rest[st.tets[e][a]] - st.rest[j]).norm();
    h /= std::max<size_t>(1, 3 * st.star[j].size());
    for (int v = 0; v < nv && !evidence; ++v) {
      evidence = sep.gap(v) >= kCutEvidence && (st.rest[v] - st.rest[j]).norm() <= 2.0 * h;
    }
  }
  if (evidence && !st.star[j].empty()) {
    const int before = st.CountPieces();
    SplitState saved = st;
    const Eigen::Vector3d m = CanonicalSign(model.rotation(st.star[j][0]).transpose() * first.normal);
    const std::vector<int> replicated = st.CutThrough(j, m.normalized());
    bool valid = !replicated.empty() && st.CountPieces() > before &&
                 (options.min_piece_fraction <= 0 || st.SmallestPiece() >= options.min_piece_fraction * nt);
    for (size_t v = 0; valid && v < st.rest.size(); ++v) {
      if (!st.star[v].empty() && !st.ManifoldAt(static_cast<int>(v))) valid = false;
    }
    if (!valid) {
      st = std::move(saved);
    } else {
      for (int u : replicated) {
        FractureEvent event;
        event.node = u < nv ? u : st.source[u];
        event.normal = first.normal;
        event.measure = sep.measure(event.node);
        event.toughness = sep.toughness(event.node);
        event.cut = true;
        change->events.push_back(event);
      }
    }
  }
}

}  // namespace fracture_internal
}  // namespace femreg
