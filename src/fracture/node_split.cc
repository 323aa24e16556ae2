// Node splitting (docs/theory/fracture.md#splitting): SplitNodes and the working state's
// queries (cracks, fronts, manifold vertices, pieces); see femreg/fracture.h.
#include "femreg/fracture.h"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <map>
#include <numeric>

#include "fracture/split_state.h"
#include "mesh/disjoint_sets.h"

namespace femreg {

Vertices RemapRows(const Vertices& values, const std::vector<int>& source) {
  Vertices out(static_cast<Eigen::Index>(source.size()), 3);
  for (size_t i = 0; i < source.size(); ++i) out.row(static_cast<Eigen::Index>(i)) = values.row(source[i]);
  return out;
}

namespace fracture_internal {

int SplitState::AddReplica(int v) {
  const int r = static_cast<int>(rest.size());
  rest.push_back(rest[v]);
  x.push_back(x[v]);
  source.push_back(source[v]);
  star.emplace_back();
  crack[v] = 1;
  crack.push_back(1);
  return r;
}

void SplitState::FindCracks() {
  crack.assign(rest.size(), 0);
  std::map<std::array<double, 3>, int> first;
  for (size_t v = 0; v < rest.size(); ++v) {
    const std::array<double, 3> key = {rest[v].x(), rest[v].y(), rest[v].z()};
    auto it = first.emplace(key, static_cast<int>(v)).first;
    if (it->second != static_cast<int>(v)) crack[v] = crack[it->second] = 1;
  }
}

int SplitState::CountCracks() const {
  const int nv = static_cast<int>(rest.size());
  DisjointSets sets(nv);
  std::map<std::array<double, 3>, int> first;
  for (int v = 0; v < nv; ++v) {
    if (!crack[v]) continue;
    const std::array<double, 3> key = {rest[v].x(), rest[v].y(), rest[v].z()};
    auto it = first.emplace(key, v).first;
    sets.Unite(it->second, v);
  }
  for (size_t e = 0; e < tets.size(); ++e) {
    if (removed[e]) continue;
    for (int a = 0; a < 4; ++a)
      for (int b = a + 1; b < 4; ++b)
        if (crack[tets[e][a]] && crack[tets[e][b]]) sets.Unite(tets[e][a], tets[e][b]);
  }
  int count = 0;
  for (int v = 0; v < nv; ++v) count += crack[v] && sets.Find(v) == v;
  return count;
}

bool SplitState::OnFront(int j, const Eigen::Vector3d& n, const ElasticModel& model,
                         Eigen::Vector3d* split_normal) const {
  if (crack[j] || star[j].empty()) return false;
  bool adjacent = false;
  double h = 0.0;
  int edges = 0;
  for (int e : star[j]) {
    for (int a = 0; a < 4; ++a) {
      const int u = tets[e][a];
      for (int b = a + 1; b < 4; ++b, ++edges) h += (rest[u] - rest[tets[e][b]]).norm();
      if (u != j && crack[u]) adjacent = true;
    }
  }
  if (!adjacent) return false;
  h /= std::max(edges, 1);
  // The crack's rest positions near j (copies counted once).
  std::map<std::array<double, 3>, Eigen::Vector3d> near;
  for (size_t u = 0; u < rest.size(); ++u) {
    if (!crack[u] || (rest[u] - rest[j]).norm() > 2.5 * h) continue;
    near.emplace(std::array<double, 3>{rest[u].x(), rest[u].y(), rest[u].z()}, rest[u]);
  }
  // The crack's surface near j: a plane through them, a line (the plane through it
  // closest to j's), or a point (j's plane through it).
  const Eigen::Matrix3d& R = model.rotation(star[j][0]);
  const Eigen::Vector3d own = R.transpose() * n;
  Eigen::Vector3d centroid = Eigen::Vector3d::Zero();
  for (const auto& kv : near) centroid += kv.second / static_cast<double>(near.size());
  Eigen::Matrix3d cov = Eigen::Matrix3d::Zero();
  for (const auto& kv : near) cov += (kv.second - centroid) * (kv.second - centroid).transpose();
  cov /= static_cast<double>(near.size());
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eig(cov);
  const double spread = 0.0625 * h * h;  // (h/4)^2
  Eigen::Vector3d plane = own;
  if (eig.eigenvalues()(1) > spread) {
    plane = eig.eigenvectors().col(0);
  } else if (eig.eigenvalues()(2) > spread) {
    const Eigen::Vector3d line = eig.eigenvectors().col(2);
    plane = own - own.dot(line) * line;
    if (plane.norm() < 0.5) return false;
    plane.normalize();
  }
  if (std::abs(plane.dot(rest[j] - centroid)) > 0.5 * h) return false;
  if (std::abs(plane.dot(own)) < 0.707) return false;
  *split_normal = CanonicalSign(R * plane);
  return true;
}

void SplitState::Reassign(int e, int from, int to) {
  for (int& v : tets[e]) {
    if (v == from) v = to;
  }
  touched[e] = 1;
}

void SplitState::Remove(int e) {
  removed[e] = 1;
  for (int v : tets[e]) {
    auto& s = star[v];
    s.erase(std::remove(s.begin(), s.end(), e), s.end());
  }
}

bool SplitState::ManifoldAt(int u) const {
  static constexpr int kFaces[4][3] = {{0, 2, 1}, {0, 1, 3}, {0, 3, 2}, {1, 2, 3}};
  std::map<std::array<int, 3>, std::pair<int, std::array<int, 3>>> faces;
  for (int e : star[u]) {
    for (const auto& f : kFaces) {
      std::array<int, 3> t = {tets[e][f[0]], tets[e][f[1]], tets[e][f[2]]};
      if (t[0] != u && t[1] != u && t[2] != u) continue;
      std::array<int, 3> key = t;
      std::sort(key.begin(), key.end());
      auto it = faces.find(key);
      if (it == faces.end()) {
        faces.emplace(key, std::make_pair(1, t));
      } else {
        ++it->second.first;
      }
    }
  }
  std::map<int, int> next;  // link edge b -> c of the boundary triangles (u, b, c)
  for (const auto& kv : faces) {
    if (kv.second.first != 1) continue;
    const auto& t = kv.second.second;
    const int k = t[0] == u ? 0 : t[1] == u ? 1 : 2;
    const int b = t[(k + 1) % 3], c = t[(k + 2) % 3];
    if (!next.emplace(b, c).second) return false;  // two triangles leave b: non-manifold
  }
  if (next.empty()) return true;  // interior vertex
  int b = next.begin()->first;
  size_t steps = 0;
  do {
    auto it = next.find(b);
    if (it == next.end()) return false;  // open fan
    b = it->second;
    ++steps;
  } while (b != next.begin()->first && steps <= next.size());
  return steps == next.size();
}

int SplitState::SmallestPiece() const {
  DisjointSets sets(static_cast<int>(rest.size()));
  for (size_t e = 0; e < tets.size(); ++e) {
    if (removed[e]) continue;
    for (int k = 1; k < 4; ++k) sets.Unite(tets[e][0], tets[e][k]);
  }
  std::map<int, int> size;
  for (size_t e = 0; e < tets.size(); ++e) {
    if (!removed[e]) ++size[sets.Find(tets[e][0])];
  }
  int smallest = std::numeric_limits<int>::max();
  for (const auto& kv : size) smallest = std::min(smallest, kv.second);
  return smallest;
}

int SplitState::CountPieces() const {
  DisjointSets sets(static_cast<int>(rest.size()));
  for (size_t e = 0; e < tets.size(); ++e) {
    if (removed[e]) continue;
    for (int k = 1; k < 4; ++k) sets.Unite(tets[e][0], tets[e][k]);
  }
  std::vector<char> root(rest.size(), 0);
  int count = 0;
  for (size_t e = 0; e < tets.size(); ++e) {
    if (removed[e]) continue;
    const int r = sets.Find(tets[e][0]);
    if (!root[r]) ++count;
    root[r] = 1;
  }
  return count;
}

Eigen::Vector3d SplitState::RestCentroid(int e) const {
  Eigen::Vector3d c = Eigen::Vector3d::Zero();
  for (int v : tets[e]) c += 0.25 * rest[v];
  return c;
}

int SplitState::SplitPinched(int v) {
  auto& s = star[v];
  const int n = static_cast<int>(s.size());
  if (n < 2) return 0;
  DisjointSets sets(n);  // elements of v's star joined across their shared faces
  for (int a = 0; a < n; ++a) {
    for (int b = a + 1; b < n; ++b) {
      int shared = 0;
      for (int p : tets[s[a]])
        for (int q : tets[s[b]]) shared += (p == q);
      if (shared >= 3) sets.Unite(a, b);
    }
  }
  std::map<int, std::vector<int>> groups;  // root -> elements, ordered by first element
  for (int a = 0; a < n; ++a) groups[sets.Find(a)].push_back(s[a]);
  if (groups.size() < 2) return 0;
  // Keep the group with the smallest element on v, deterministic whatever the star order.
  std::vector<std::vector<int>> list;
  for (auto& g : groups) {
    std::sort(g.second.begin(), g.second.end());
    list.push_back(g.second);
  }
  std::sort(list.begin(), list.end());
  for (size_t g = 1; g < list.size(); ++g) {
    const int r = AddReplica(v);
    for (int e : list[g]) {
      Reassign(e, v, r);
      star[r].push_back(e);
    }
  }
  s = list[0];
  return static_cast<int>(list.size()) - 1;
}

}  // namespace fracture_internal

using fracture_internal::SplitState;

void SplitNodes(const NodeSeparation& sep, const FractureOptions& options, int max_splits,
                TetMesh* mesh, ElasticModel* model, TopologyChange* change) {
  *change = TopologyChange();
  const int nv = mesh->num_vertices();
  const int nt = mesh->num_tets();
  change->source.resize(nv);
  std::iota(change->source.begin(), change->source.end(), 0);
  if (max_splits <= 0 || sep.measure.size() != nv) return;

  // Candidates: measure (times weight) above toughness, highest ratio first (ties: lower
  // index).
  const bool weighted = sep.weight.size() == nv;
  std::vector<std::pair<double, int>> candidates;
  for (int j = 0; j < nv; ++j) {
    const double t = sep.toughness(j);
    const double m = weighted ? sep.weight(j) * sep.measure(j) : sep.measure(j);
    if (t > 0 && m > t) candidates.emplace_back(-m / t, j);
  }
  if (candidates.empty()) return;
  std::sort(candidates.begin(), candidates.end());

  SplitState st;
  st.mesh = mesh;
  st.tets.resize(nt);
  st.removed.assign(nt, 0);
  st.touched.assign(nt, 0);
  st.star.assign(nv, {});
  for (int e = 0; e < nt; ++e) {
    for (int k = 0; k < 4; ++k) {
      st.tets[e][k] = mesh->tets(e, k);
      st.star[mesh->tets(e, k)].push_back(e);
    }
  }
  st.source = change->source;
  st.crack.assign(nv, 0);
  for (int v = 0; v < nv; ++v) {
    st.rest.push_back(mesh->rest.row(v).transpose());
    st.x.push_back(mesh->x.row(v).transpose());
  }

  // With max_cracks: the candidates allowed change with every split, so each split takes
  // the first allowed candidate not tried yet (without: simply the candidates in order).
  const bool limit_cracks = options.max_cracks > 0;
  if (limit_cracks) st.FindCracks();
  std::vector<char> tried(candidates.size(), 0);
  int splits = 0;
  while (splits < max_splits) {
    const bool nucleate = !limit_cracks || st.CountCracks() < options.max_cracks;
    size_t next = candidates.size();
    Eigen::Vector3d n;
    for (size_t i = 0; i < candidates.size() && next == candidates.size(); ++i) {
      if (tried[i]) continue;
      const int j = candidates[i].second;
      n = sep.normal.row(j).transpose();
      if (nucleate || st.OnFront(j, sep.normal.row(j).transpose(), *model, &n)) next = i;
    }
    if (next == candidates.size()) break;
    tried[next] = 1;
    const int j = candidates[next].second;
    // Splits node u by the plane (normal n through q): its elements on the positive side go
    // to a replica, those the plane crosses are removed; pinched vertices around get their
    // own copies. The vertices touched are added to *check. False (nothing done) when the
    // plane leaves every kept element on one side, which separates nothing.
    auto split_node = [&](int u, const Eigen::Vector3d& q, std::vector<int>* check,
                          std::vector<int>* crossed_all) {
      std::vector<int> positive, negative, crossed;
      for (int e : st.star[u]) {
        double lo = 0, hi = 0, h = 0;
        Eigen::Vector3d centroid = Eigen::Vector3d::Zero();
        for (int a = 0; a < 4; ++a) {
          const Eigen::Vector3d xa = st.x[st.tets[e][a]];
          centroid += 0.25 * xa;
          for (int b = a + 1; b < 4; ++b) h += (xa - st.x[st.tets[e][b]]).norm() / 6.0;
          if (st.tets[e][a] == u) continue;
          const double d = n.dot(xa - q);
          lo = std::min(lo, d);
          hi = std::max(hi, d);
        }
        const double tol = options.crossing_tolerance * h;
        if (lo < -tol && hi > tol) {
          crossed.push_back(e);
        } else if (n.dot(centroid - q) > 0) {
          positive.push_back(e);
        } else {
          negative.push_back(e);
        }
      }
      if (positive.empty() || negative.empty()) return false;
      std::vector<int> local = {u};
      for (int e : crossed) {
        for (int v : st.tets[e]) local.push_back(v);
        st.Remove(e);
      }
      const int r = st.AddReplica(u);
      for (int e : positive) {
        st.Reassign(e, u, r);
        st.star[r].push_back(e);
      }
      st.star[u] = negative;
      local.push_back(r);
      std::sort(local.begin(), local.end());
      local.erase(std::unique(local.begin(), local.end()), local.end());
      for (int v : local) st.SplitPinched(v);
      check->insert(check->end(), local.begin(), local.end());
      crossed_all->insert(crossed_all->end(), crossed.begin(), crossed.end());
      return true;
    };
    // Whether the surface stays manifold around everything the splits since `saved` touched
    // (and no piece became a sliver).
    auto still_valid = [&](const SplitState& saved, std::vector<int> check) {
      std::vector<int> around;
      for (int v = static_cast<int>(saved.rest.size()); v < static_cast<int>(st.rest.size()); ++v) check.push_back(v);
      for (int v : check) {
        for (int e : st.star[v])
          for (int u : st.tets[e]) around.push_back(u);
        around.push_back(v);
      }
      std::sort(around.begin(), around.end());
      around.erase(std::unique(around.begin(), around.end()), around.end());
      for (int u : around) {
        if (!st.ManifoldAt(u)) return false;
      }
      return options.min_piece_fraction <= 0 || st.SmallestPiece() >= options.min_piece_fraction * nt;
    };
    SplitState saved = st;  // to undo a split that would leave a non-manifold surface
    std::vector<int> check, crossed;
    std::vector<int> group = {j};
    if (!split_node(j, st.x[j], &check, &crossed)) continue;
    bool valid = still_valid(saved, check);
    if (!valid && limit_cracks) {
      // A crack front through a body one or more elements thick: splitting one front node
      // alone pinches the surface at its neighbours on the same plane (the node above or
      // below it), so the front's nodes on the plane next to j split with it, in one step.
      const Eigen::Vector3d p = saved.x[j];
      double h = 0.0;
      int edges = 0;
      std::vector<int> partners;
      for (int e : saved.star[j]) {
        for (int a = 0; a < 4; ++a) {
          for (int b = a + 1; b < 4; ++b, ++edges) h += (saved.x[saved.tets[e][a]] - saved.x[saved.tets[e][b]]).norm();
          const int u = saved.tets[e][a];
          if (u != j && !saved.crack[u]) partners.push_back(u);
        }
      }
      h /= std::max(edges, 1);
      std::sort(partners.begin(), partners.end());
      partners.erase(std::unique(partners.begin(), partners.end()), partners.end());
      bool any = false;
      for (int u : partners) {
        if (std::abs(n.dot(saved.x[u] - p)) > 0.25 * h) continue;
        if (split_node(u, saved.x[u], &check, &crossed)) {
          group.push_back(u);
          any = true;
        }
      }
      valid = any && still_valid(saved, check);
    }
    if (!valid) {
      st = std::move(saved);
      continue;
    }
    splits += static_cast<int>(group.size());
    change->removed_elements += static_cast<int>(crossed.size());
    for (int e : crossed) change->removed_volume += model->rest(e).volume;
    for (int u : group) {
      FractureEvent event;
      event.node = u;
      event.normal = n;
      event.measure = sep.measure(u);
      event.toughness = sep.toughness(u);
      event.removed_elements = u == j ? static_cast<int>(crossed.size()) : 0;
      change->events.push_back(event);
    }
  }
  if (splits == 0) return;

  if (options.cut_through && !change->events.empty()) {
    fracture_internal::CutThroughSection(sep, options, *model, nv, nt, &st, change);
  }

  // Compaction: drop removed elements and vertices without elements.
  const int nv_work = static_cast<int>(st.rest.size());
  std::vector<int> new_index(nv_work, -1);
  std::vector<int> source;
  for (int v = 0; v < nv_work; ++v) {
    if (st.star[v].empty()) {
      ++change->dropped_vertices;
      continue;
    }
    new_index[v] = static_cast<int>(source.size());
    source.push_back(st.source[v]);
  }
  std::vector<int> old_element, touched;
  for (int e = 0; e < nt; ++e) {
    if (st.removed[e]) continue;
    if (st.touched[e]) touched.push_back(static_cast<int>(old_element.size()));
    old_element.push_back(e);
  }
  TetMesh& m = *mesh;
  const int nt_new = static_cast<int>(old_element.size());
  Tets tets(nt_new, 4);
  Eigen::VectorXi region(nt_new);
  for (int i = 0; i < nt_new; ++i) {
    const int e = old_element[i];
    for (int k = 0; k < 4; ++k) tets(i, k) = new_index[st.tets[e][k]];
    region(i) = e < m.region.size() ? m.region(e) : 0;
  }
  const int nv_new = static_cast<int>(source.size());
  Vertices rest(nv_new, 3), x(nv_new, 3);
  for (int v = 0; v < nv_work; ++v) {
    if (new_index[v] < 0) continue;
    rest.row(new_index[v]) = st.rest[v].transpose();
    x.row(new_index[v]) = st.x[v].transpose();
  }
  m.rest = std::move(rest);
  m.x = std::move(x);
  m.tets = std::move(tets);
  m.region = std::move(region);
  if (m.mass.size() > 0) m.mass = Eigen::VectorXd::Zero(nv_new);
  BuildTopology(&m);
  model->RemapElements(m, old_element, touched);
  change->source = std::move(source);
}

}  // namespace femreg
