#include "registration/fracture_step.h"

#include <algorithm>
#include <chrono>

#include "parallel/stopwatch.h"
#include "fracture/measure_bound.h"
#include "registration/correspondences.h"
#include "registration/prealign.h"

namespace femreg {

namespace {

// FractureOptions::data_gap: the data's evidence at most triples the measure.
constexpr double kMaxDataGapWeight = 3.0;

// Whether the outer iterations keep object i's element rotations current (the corotational
// regularizer updates them at the start of each; the neo-Hookean element reads none).
bool RotationsKept(const TrackerState& state, int i) {
  return state.options.regularizer == Regularizer::kCorotational &&
         state.objects[i].model.type() != ElasticModelType::kNeoHookean;
}

// Object i's positions for the detection, which the outputs' measure is taken at.
void DetectAt(int i, TrackerState* state) {
  FractureState& f = *state->fracture;
  ObjectState& o = state->objects[i];
  o.mesh.x = state->x.middleRows(o.offset, o.mesh.num_vertices());
  f.detected_at[i] = o.mesh.x;
  f.full_measure[i].resize(0);
}

// The measure in full at object i's current positions, the model's rotations brought there
// (unless they are already).
void DetectAll(int i, bool rotate, TrackerState* state) {
  FractureState& f = *state->fracture;
  ObjectState& o = state->objects[i];
  if (rotate) o.model.UpdateRotations(o.mesh.x);
  DetectFracture(o.mesh, o.model, o.mesh.x, f.options[i], &f.separation[i]);
  f.partial[i] = 0;
}

// Whether some node's measure (times the data's weight, if any) reaches `ratio` of its
// toughness (exceeds it, if strictly: SplitNodes' test).
bool Reaches(const NodeSeparation& sep, double ratio, bool strictly = false) {
  const bool weighted = sep.weight.size() == sep.measure.size();
  for (int v = 0; v < sep.measure.size(); ++v) {
    const double m = weighted ? sep.weight(v) * sep.measure(v) : sep.measure(v);
    const double t = ratio * sep.toughness(v);
    if (sep.toughness(v) > 0 && (strictly ? m > t : m >= t)) return true;
  }
  return false;
}

// Object i's detection, and the weights of the data's evidence where a node could break.
// The measure is evaluated only where its bound reaches what fracture acts on: the live
// threshold until fracture is live, then the toughness, each over the data's largest weight
// (docs/theory/fracture.md#before-the-break); every decision below reads it only there. A
// detection with a node to split is done again in full, so that the splits see the measure
// as before.
void Detect(int i, const PointIndex& cloud_index, TrackerState* state) {
  FractureState& f = *state->fracture;
  ObjectState& o = state->objects[i];
  DetectAt(i, state);
  NodeSeparation& sep = f.separation[i];
  const bool weigh = f.options[i].data_gap, confirm = f.options[i].cut_through;
  const double floor = (f.live ? 1.0 : kFractureLiveRatio) / (weigh ? kMaxDataGapWeight : 1.0);
  // The bound needs no rotation; the nodes evaluated find theirs from the model's, which the
  // next outer iteration brings here itself (so an intact frame's rotations are fracture off's).
  const bool kept = RotationsKept(*state, i);
  if (!kept) o.model.UpdateRotations(o.mesh.x);  // nothing else does
  fracture_internal::BoundData& bound = f.bound[i];
  if (!bound.Fits(o.mesh, o.model)) fracture_internal::BuildBoundData(o.mesh, o.model, f.options[i], &bound);
  fracture_internal::DetectFractureAbove(o.mesh, o.model, o.mesh.x, floor, !kept, bound, &sep);
  f.partial[i] = 1;
  sep.weight.resize(0);
  sep.gap.resize(0);
  if ((weigh || confirm) && state->options.camera.enabled && cloud_index.size() > 0) {
    double top = 0.0;
    for (int v = 0; v < sep.measure.size(); ++v) {
      if (sep.toughness(v) > 0) top = std::max(top, sep.measure(v) / sep.toughness(v));
    }
    // Only where a node could break (the data's gap costs a search per surface vertex).
    if (top * (weigh ? kMaxDataGapWeight : 1.0) > 1.0) {
      const double scale = state->options.data.loss_scale > 0 ? state->options.data.loss_scale : 0.005;
      sep.gap = DataGap(*state, i, cloud_index) / scale;
      if (weigh) sep.weight = (Eigen::VectorXd::Ones(sep.gap.size()) + sep.gap).cwiseMin(kMaxDataGapWeight);
    }
  }
  if (!f.live && Reaches(sep, kFractureLiveRatio)) f.live = true;
  if (Reaches(sep, 1.0, /*strictly=*/true)) {
    const Eigen::VectorXd weight = sep.weight, gap = sep.gap;  // they do not depend on the measure
    DetectAll(i, /*rotate=*/kept, state);
    sep.weight = weight;
    sep.gap = gap;
  }
}

// Carries the state's global arrays to the new numbering: new global vertex v comes from
// old global vertex source[v].
void Renumber(const std::vector<int>& source, TrackerState* state) {
  const int old_count = state->num_vertices;
  state->x = RemapRows(state->x, source);
  if (state->x_before.rows() == old_count) state->x_before = RemapRows(state->x_before, source);
  if (state->frame_start.rows() == old_count) state->frame_start = RemapRows(state->frame_start, source);
  state->RebuildGlobalArrays();
  // Anchors hold every copy of their vertices.
  std::vector<std::vector<int>> copies(old_count);
  for (size_t v = 0; v < source.size(); ++v) copies[source[v]].push_back(static_cast<int>(v));
  for (auto& kv : state->anchors) {
    Anchor& a = kv.second;
    std::vector<int> vertices, rows;
    for (size_t r = 0; r < a.vertices.size(); ++r) {
      for (int c : copies[a.vertices[r]]) {
        vertices.push_back(c);
        rows.push_back(static_cast<int>(r));
      }
    }
    a.vertices = vertices;
    a.targets = RemapRows(a.targets, rows);
    a.origin = RemapRows(a.origin, rows);
  }
  if (state->collision) {
    for (size_t i = 0; i < state->objects.size(); ++i) {
      state->collision->Rebuild(static_cast<int>(i), state->ObjectSurface(static_cast<int>(i)), state->x);
    }
  }
}

// The pieces of object i just parted, each back in its rest shape (the strain the whole body
// held is released by the break) at the rigid pose that best fits where it is: the pose of
// its hard-anchored vertices if it has three or more, else of all its vertices. Anchored
// vertices stay on their targets.
void RelaxPieces(int i, TrackerState* state) {
  const ObjectState& o = state->objects[i];
  const int nv = o.mesh.num_vertices();
  std::vector<int> piece;
  const int pieces = ConnectedPieces(o.mesh, &piece);
  std::vector<char> anchored(static_cast<size_t>(nv), 0);
  for (const auto& kv : state->anchors) {
    if (!kv.second.hard || kv.second.object != i) continue;
    for (int g : kv.second.vertices) {
      if (g >= o.offset && g < o.offset + nv) anchored[static_cast<size_t>(g - o.offset)] = 1;
    }
  }
  for (int p = 0; p < pieces; ++p) {
    // A piece nothing holds keeps its shape: a rest pose fitted to the body still strained by
    // the break is off along the piece's length, where its data hold it least; the outer
    // iterations relax it (docs/theory/fracture.md#pieces).
    int size = 0;
    std::vector<Eigen::Vector3d> held_rest, held_x;
    for (int v = 0; v < nv; ++v) {
      if (piece[v] != p) continue;
      ++size;
      if (anchored[static_cast<size_t>(v)]) {
        held_rest.push_back(o.mesh.rest.row(v).transpose());
        held_x.push_back(state->x.row(o.offset + v).transpose());
      }
    }
    if (size < 4 || held_rest.size() < 3) continue;
    Eigen::Matrix3d R;
    Eigen::Vector3d t;
    Kabsch(held_rest, held_x, &R, &t);
    for (int v = 0; v < nv; ++v) {
      if (piece[v] != p || anchored[static_cast<size_t>(v)]) continue;
      state->x.row(o.offset + v) = (R * o.mesh.rest.row(v).transpose() + t).transpose();
    }
  }
}

// FractureState::crack, for the objects in pieces. The tracked mesh parts along its own nodes
// and faces, up to a cell away from where the body really broke, so each piece may lack or
// carry material at its crack end that the data does not show: pulled to the data's end, a
// soft piece stretches or slides along its axis. Its pose comes from the rest of its surface.
void MarkCracks(TrackerState* state) {
  FractureState& f = *state->fracture;
  f.crack.clear();
  std::vector<char> crack;
  for (size_t i = 0; i < state->objects.size(); ++i) {
    const ObjectState& o = state->objects[i];
    std::vector<int> piece;
    if (ConnectedPieces(o.mesh, &piece) < 2) continue;
    const std::vector<int>& original = f.original[i];
    const std::vector<char>& was_surface = f.initial_surface[i];
    std::vector<int> copies(was_surface.size(), 0);
    for (int id : original) ++copies[static_cast<size_t>(id)];
    if (crack.empty()) crack.assign(static_cast<size_t>(state->num_vertices), 0);
    for (int v = 0; v < o.mesh.num_vertices(); ++v) {
      const int id = original[static_cast<size_t>(v)];
      if (copies[static_cast<size_t>(id)] > 1) crack[static_cast<size_t>(o.offset + v)] = 1;
    }
    for (int v : o.mesh.surface_vertices) {
      if (!was_surface[static_cast<size_t>(original[static_cast<size_t>(v)])]) crack[static_cast<size_t>(o.offset + v)] = 1;
    }
  }
  f.crack = std::move(crack);
}

}  // namespace

std::vector<int> FractureStep(int k, const PointIndex& cloud_index, TrackerState* state,
                              FrameSummary* summary) {
  const auto t0 = std::chrono::steady_clock::now();
  FractureState& f = *state->fracture;
  if (k == 0) {
    f.frame_splits = 0;
    f.frame_separated = false;
  }
  f.separated = false;
  std::vector<std::vector<int>> sources(state->objects.size());
  std::vector<char> parted(state->objects.size(), 0);
  bool changed = false;
  for (size_t i = 0; i < state->objects.size(); ++i) {
    ObjectState& o = state->objects[i];
    const int budget = std::min(f.options[i].max_splits_per_iteration,
                                f.options[i].max_splits_per_frame - f.frame_splits);
    if (budget <= 0) {  // still detect: the measure is an output
      DetectAt(static_cast<int>(i), state);
      DetectAll(static_cast<int>(i), /*rotate=*/true, state);
      continue;
    }
    Detect(static_cast<int>(i), cloud_index, state);
    TopologyChange change;
    std::vector<int> piece;
    // Only a detection with a node to split (evaluated in full) can change the mesh.
    const int pieces_before = f.live && !f.partial[i] ? ConnectedPieces(o.mesh, &piece) : 1;
    SplitNodes(f.separation[i], f.options[i], budget, &o.mesh, &o.model, &change);
    if (!change.changed()) continue;
    changed = true;
    f.bound[i] = fracture_internal::BoundData();  // another topology
    if (ConnectedPieces(o.mesh, &piece) > pieces_before) {
      f.separated = f.frame_separated = true;
      parted[i] = 1;
    }
    f.frame_splits += static_cast<int>(change.events.size());
    for (FractureEvent e : change.events) {
      e.frame = state->frame;
      e.object = static_cast<int>(i);
      e.iteration = k + 1;
      e.original_node = f.original[i][e.node];
      summary->fractures.push_back(e);
    }
    std::vector<int> original(change.source.size());
    Eigen::VectorXd measure(static_cast<Eigen::Index>(change.source.size()));
    for (size_t v = 0; v < change.source.size(); ++v) {
      original[v] = f.original[i][change.source[v]];
      measure(static_cast<Eigen::Index>(v)) = f.separation[i].measure(change.source[v]);
    }
    f.original[i] = std::move(original);
    f.separation[i].measure = std::move(measure);
    f.separation[i].weight.resize(0);
    f.separation[i].gap.resize(0);
    if (o.loads.rows() > 0) {  // a split node's load, shared evenly among its copies
      std::vector<int> copies(static_cast<size_t>(o.loads.rows()), 0);
      for (int src : change.source) ++copies[static_cast<size_t>(src)];
      Vertices loads(static_cast<Eigen::Index>(change.source.size()), 3);
      for (size_t v = 0; v < change.source.size(); ++v) {
        const int src = change.source[v];
        loads.row(static_cast<Eigen::Index>(v)) = o.loads.row(src) / copies[static_cast<size_t>(src)];
      }
      o.loads = std::move(loads);
    }
    ComputeLumpedMasses(&o.mesh, o.material.material.density, RegionDensities(o.material));
    sources[i] = std::move(change.source);
  }
  summary->time.fracture += Seconds(t0);
  if (!changed) return {};

  // The new global numbering: objects in order, each from its new mesh.
  std::vector<int> source;
  for (size_t i = 0; i < state->objects.size(); ++i) {
    const int old_offset = state->objects[i].offset;
    const int nv = state->objects[i].mesh.num_vertices();
    for (int v = 0; v < nv; ++v) source.push_back(old_offset + (sources[i].empty() ? v : sources[i][v]));
  }
  Renumber(source, state);
  for (size_t i = 0; i < state->objects.size(); ++i) {
    if (parted[i] && f.options[i].relax_pieces) RelaxPieces(static_cast<int>(i), state);
  }
  MarkCracks(state);
  return source;
}

}  // namespace femreg
