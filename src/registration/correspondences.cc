#include "registration/correspondences.h"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <limits>
#include <memory>
#include <unordered_map>

#include "femreg/geometry.h"
#include "parallel/pool.h"
#include "parallel/threads.h"

namespace femreg {

Eigen::Vector3d DataPair::Point(const Vertices& x) const {
  Eigen::Vector3d p = Eigen::Vector3d::Zero();
  for (int j = 0; j < num_vertices; ++j) p += barycentric[j] * x.row(vertices[j]).transpose();
  return p;
}

namespace {

// A cloud point closer to the surface than this fraction of the triangle's longest edge is on
// it: the direction to it is round-off, and the face normal is used.
constexpr double kOnSurface = 1e-9;

// Closest-point queries per thread from which a loop of them runs on a team (~1 us each).
constexpr long long kQueriesPerThread = 64;

// A labelled cloud split by object: per labelled object its points (k-d tree) and its
// surface (closest-point index); the points no label claims ("free"), which pair only with
// the objects without a label, and those objects' surfaces.
struct LabelSplit {
  std::vector<int> point_object;                 // cloud point -> object, -1 = free
  std::vector<std::vector<int>> object_points;   // labelled object -> its cloud points
  std::vector<std::unique_ptr<PointIndex>> object_index;
  std::vector<Triangles> object_surface;
  std::vector<std::unique_ptr<SurfaceIndex>> object_surface_index;
  std::vector<int> free_points;
  std::unique_ptr<PointIndex> free_index;
  Triangles free_surface;
  std::unique_ptr<SurfaceIndex> free_surface_index;

  bool active() const { return !point_object.empty(); }

  LabelSplit(const TrackerState& state, const PointCloud& cloud) {
    const int num_objects = static_cast<int>(state.objects.size());
    const bool any_label = std::any_of(state.objects.begin(), state.objects.end(),
                                       [](const ObjectState& o) { return o.label >= 0; });
    if (!cloud.has_labels() || !any_label) return;
    point_object.assign(cloud.size(), -1);
    for (int i = 0; i < cloud.size(); ++i) {
      for (int o = 0; o < num_objects; ++o) {
        if (state.objects[o].label >= 0 && cloud.labels(i) == state.objects[o].label) point_object[i] = o;
      }
    }
    object_points.resize(num_objects);
    object_index.resize(num_objects);
    object_surface.resize(num_objects);
    object_surface_index.resize(num_objects);
    for (int o = 0; o < num_objects; ++o) {
      if (state.objects[o].label < 0) continue;
      for (int i = 0; i < cloud.size(); ++i) {
        if (point_object[i] == o) object_points[o].push_back(i);
      }
      object_index[o] = std::make_unique<PointIndex>(Rows(cloud.points, object_points[o]));
      object_surface[o] = state.ObjectSurface(o);
      object_surface_index[o] = std::make_unique<SurfaceIndex>(state.x, object_surface[o]);
    }
    for (int i = 0; i < cloud.size(); ++i) {
      if (point_object[i] < 0) free_points.push_back(i);
    }
    free_index = std::make_unique<PointIndex>(Rows(cloud.points, free_points));
    int rows = 0;
    for (int o = 0; o < num_objects; ++o) {
      if (state.objects[o].label < 0) rows += state.objects[o].mesh.num_surface_triangles();
    }
    free_surface.resize(rows, 3);
    rows = 0;
    for (int o = 0; o < num_objects; ++o) {
      if (state.objects[o].label >= 0) continue;
      const int nf = state.objects[o].mesh.num_surface_triangles();
      free_surface.middleRows(rows, nf) = state.ObjectSurface(o);
      rows += nf;
    }
    if (rows > 0) free_surface_index = std::make_unique<SurfaceIndex>(state.x, free_surface);
  }

  static Vertices Rows(const Vertices& points, const std::vector<int>& rows) {
    Vertices out(static_cast<Eigen::Index>(rows.size()), 3);
    for (size_t j = 0; j < rows.size(); ++j) out.row(static_cast<Eigen::Index>(j)) = points.row(rows[j]);
    return out;
  }
};

// A face turned up to this angle away from the sensor can still hold a cloud point: a
// grazing face of a model a little off its pose, a silhouette, the sensor's noise.
constexpr double kMaxFacingAngleCos = -0.3;  // cos(107 deg)

// A face turned less than this from a vertex's normal (cos 30 deg) is on the vertex's side of
// the model: a corner's normal, between two faces, is 45 deg from each.
constexpr double kSameSide = 0.866;

// The closest-point index over the triangles of `surface` that face fc's sensor.
std::unique_ptr<SurfaceIndex> FacingIndex(const Vertices& x, const Triangles& surface, const FrameCloud& fc) {
  std::vector<char> keep(static_cast<size_t>(surface.rows()), 0);
  for (int f = 0; f < surface.rows(); ++f) {
    const Eigen::Vector3d a = x.row(surface(f, 0)), b = x.row(surface(f, 1)), c = x.row(surface(f, 2));
    const Eigen::Vector3d n = (b - a).cross(c - a);
    const Eigen::Vector3d to_eye =
        fc.view == FrameCloud::View::kDirection ? fc.eye : Eigen::Vector3d(fc.eye - (a + b + c) / 3.0);
    const double scale = n.norm() * to_eye.norm();
    keep[static_cast<size_t>(f)] = scale == 0.0 || n.dot(to_eye) > kMaxFacingAngleCos * scale;
  }
  return std::make_unique<SurfaceIndex>(x, surface, keep);
}

}  // namespace

void FindPairs(const TrackerState& state, const FrameCloud& fc, const SurfaceIndex& surface,
               int num_threads, std::vector<DataPair>* pairs, PairCounts* counts,
               std::vector<int>* warm, std::vector<char>* paired, bool freeze) {
  pairs->clear();
  *counts = PairCounts();
  const PointCloud& cloud = fc.cloud;
  const PointIndex& cloud_index = *fc.index;
  const RegistrationOptions& options = state.options;
  const DataTermOptions& data = options.data;
  const Vertices& x = state.x;
  const double gate2 = data.max_distance > 0 ? data.max_distance * data.max_distance
                                             : std::numeric_limits<double>::infinity();
  const double trim2 = std::isfinite(fc.trim) ? fc.trim * fc.trim : std::numeric_limits<double>::infinity();
  const bool plane = data.metric == DataMetric::kPointToPlane;
  const bool view = fc.view != FrameCloud::View::kNone;
  // The normals of the vertices that may pair with the cloud (model->cloud), row i for
  // state.surface_vertices[i]: over their rings, not the whole surface (an embedded scan's
  // subsample is a few percent of its vertices).
  const Eigen::MatrixXd normals = (view || plane) && data.model_to_cloud
                                      ? VertexNormalsAt(x, state.surface, surface.rings(), state.surface_vertices)
                                      : Eigen::MatrixXd();
  const LabelSplit labels(state, cloud);
  const int threads = ResolveThreadCount(num_threads);
  // After a break, the surface at a crack pairs with nothing (docs/theory/fracture.md#pieces).
  const std::vector<char>* crack =
      state.fracture && static_cast<int>(state.fracture->crack.size()) == state.num_vertices ? &state.fracture->crack : nullptr;

  // Each cloud point's closest surface point (every cloud_stride-th point), first: the
  // cloud->model pairs, and the model->cloud pairs' reciprocity. Points without an
  // object's label search every surface, or with labels the unlabelled objects' surfaces
  // (none: the point is no one's).
  const bool cloud_to_model = data.cloud_to_model && state.surface.rows() > 0;
  const Triangles& other_surface = labels.active() ? labels.free_surface : state.surface;
  const SurfaceIndex* other_index = labels.active() ? labels.free_surface_index.get() : &surface;
  // Seen from a sensor, a cloud point lies on surface that faces it: in a large motion's
  // frame its closest point is searched among the triangles turned less than
  // kMaxFacingAngleCos away from the sensor, so that a model far from its cloud is not
  // fitted back side first (docs/theory/stopping.md#large-motions).
  std::unique_ptr<SurfaceIndex> facing_index;
  if (fc.facing_only && view && cloud_to_model && !labels.active()) {
    facing_index = FacingIndex(x, state.surface, fc);
    other_index = facing_index.get();
  }
  auto index_of = [&](int i) {  // the closest-point index cloud point i searches
    const int labelled = labels.active() ? labels.point_object[i] : -1;
    return labelled >= 0 ? labels.object_surface_index[labelled].get() : other_index;
  };
  auto ring_index_of = [&](int i) {  // the same surface, every triangle: the one-ring test
    const int labelled = labels.active() ? labels.point_object[i] : -1;
    return labelled >= 0 ? labels.object_surface_index[labelled].get()
                         : (labels.active() ? labels.free_surface_index.get() : &surface);
  };
  const int nq = cloud_to_model ? (cloud.size() + data.cloud_stride - 1) / data.cloud_stride : 0;
  std::vector<SurfaceIndex::Hit> hits(static_cast<size_t>(nq));
  if (cloud_to_model) {
    // From the last outer iteration's triangles (each query always uses the same index: its
    // label's): faster, the same pairs (docs/notes/2026-11-28-figures-from-code-comments.md).
    const bool warm_start = warm != nullptr && static_cast<int>(warm->size()) == nq;
    ParallelFor(threads, nq, kQueriesPerThread, [&](int64_t jj) {
      const int j = static_cast<int>(jj);
      const int i = j * data.cloud_stride;
      const SurfaceIndex* index = index_of(i);
      if (index == nullptr) return;
      const Eigen::Vector3d q = cloud.points.row(i);
      SurfaceIndex::Hit& hit = hits[static_cast<size_t>(j)];
      if (!warm_start) {
        hit = index->Closest(q);
      } else if (fc.seeded_rings > 0) {
        bool settled = true;
        hit = index->ClosestFrom(q, (*warm)[static_cast<size_t>(j)], fc.seeded_rings, &settled);
        if (!settled) hit = index->Closest(q);
      } else {
        hit = index->ClosestFrom(q, (*warm)[static_cast<size_t>(j)]);
      }
    });
    if (warm != nullptr) {
      warm->resize(static_cast<size_t>(nq));
      for (int j = 0; j < nq; ++j) (*warm)[static_cast<size_t>(j)] = hits[static_cast<size_t>(j)].triangle;
    }
  }

  if (data.model_to_cloud && cloud_index.size() > 0) {
    const int ns = static_cast<int>(state.surface_vertices.size());
    std::vector<int> nearest(static_cast<size_t>(ns), -1);
    std::vector<double> dist2(static_cast<size_t>(ns), 0.0);
    // Reciprocity (with the trim: data.reciprocity > 0, no fracture): a vertex pulls towards its
    // nearest cloud point only if that point's own closest surface point is next to the vertex (on
    // a triangle touching the vertex's one-ring). Where another part of the model is closer to the
    // point (a thin, partly seen hand beside the body it is nearest to, another object), the point
    // is that part's: its cloud->model pair pulls there, and the vertex is not pulled across
    // (docs/guide/partial-views.md). A ring of the mesh, not a distance: a distance that rejected a
    // thin part's pairs also rejected pairs of a model still an edge away from its cloud, and two
    // rings lost most of the gain (docs/notes/2026-11-28-figures-from-code-comments.md).
    const bool mutual = std::isfinite(fc.trim);  // the frame's reciprocity is on
    std::vector<char> foreign(static_cast<size_t>(mutual ? ns : 0), 0);
    const bool hold = paired != nullptr && freeze && static_cast<int>(paired->size()) == ns;
    // A vertex facing away pairs with nothing unless the held set keeps it (below); its
    // nearest cloud point and the ring test decide nothing else.
    std::vector<char> away(static_cast<size_t>(view ? ns : 0), 0);
    constexpr int kFacingAway = -2;
    ParallelFor(threads, ns, kQueriesPerThread, [&](int64_t ii) {
      const int i = static_cast<int>(ii);
      const int v = state.surface_vertices[static_cast<size_t>(i)];
      const Eigen::Vector3d p = x.row(v);
      if (view) {
        away[static_cast<size_t>(i)] = !fc.Faces(p, normals.row(i)) && !(hold && (*paired)[static_cast<size_t>(i)]);
        if (away[static_cast<size_t>(i)] && fc.skip_facing_away) {
          nearest[static_cast<size_t>(i)] = kFacingAway;
          return;
        }
      }
      int q = -1;
      double d2 = 0.0;
      if (!labels.active()) {
        q = cloud_index.Nearest(p, &d2);
      } else {
        const int o = state.vertex_object[v];
        const bool labelled = state.objects[o].label >= 0;
        const PointIndex& index = labelled ? *labels.object_index[o] : *labels.free_index;
        q = index.Nearest(p, &d2);
        if (q >= 0) q = labelled ? labels.object_points[o][q] : labels.free_points[q];
      }
      if (mutual && q >= 0 && !(view && away[static_cast<size_t>(i)])) {
        const SurfaceIndex* index = index_of(q);
        const SurfaceIndex* ring = ring_index_of(q);
        int triangle = -1;
        if (cloud_to_model && q % data.cloud_stride == 0) {
          triangle = hits[static_cast<size_t>(q / data.cloud_stride)].triangle;
        } else if (index != nullptr) {
          triangle = index->Closest(cloud.points.row(q)).triangle;
        }
        foreign[static_cast<size_t>(i)] = triangle >= 0 && ring != nullptr && !ring->TouchesRing(v, triangle);
      }
      nearest[static_cast<size_t>(i)] = q;
      dist2[static_cast<size_t>(i)] = d2;
    });
    if (paired != nullptr && !hold) paired->assign(static_cast<size_t>(ns), 0);
    // A vertex hidden behind an occluder pairs with a point across an edge of the model only
    // this near: within its own ring (a mean edge), the noise or the sampling.
    const double hidden = std::max({data.loss_scale, 2.0 * fc.spacing, state.mean_edge_length});
    const double hidden2 = hidden * hidden;
    // Whether cloud point q's closest surface point lies on a face turned within kSameSide of
    // the unit normal n: on the vertex's own side of the model, not across an edge.
    auto same_side = [&](int q, const Eigen::Vector3d& n) {
      const SurfaceIndex* ring = ring_index_of(q);
      if (ring == nullptr) return true;
      const int labelled = labels.active() ? labels.point_object[q] : -1;
      const Triangles& tris = labelled >= 0 ? labels.object_surface[labelled]
                                            : (labels.active() ? labels.free_surface : state.surface);
      const SurfaceIndex::Hit hit = ring->Closest(cloud.points.row(q));
      if (hit.triangle < 0) return true;
      const Eigen::Vector3d a = x.row(tris(hit.triangle, 0)), b = x.row(tris(hit.triangle, 1)),
                            c = x.row(tris(hit.triangle, 2));
      const Eigen::Vector3d fn = (b - a).cross(c - a);
      return !(fn.norm() > 0) || fn.dot(n) >= kSameSide * fn.norm() * n.norm();
    };
    for (int i = 0; i < ns; ++i) {
      const int q = nearest[static_cast<size_t>(i)];
      const bool was_paired = hold && (*paired)[static_cast<size_t>(i)];
      if (hold) (*paired)[static_cast<size_t>(i)] = 0;
      if (q == kFacingAway) {
        ++counts->trimmed;
        continue;
      }
      if (q < 0) continue;
      const double d2 = dist2[static_cast<size_t>(i)];
      const int v = state.surface_vertices[static_cast<size_t>(i)];
      if (d2 <= trim2) ++counts->covered;
      if (d2 > gate2) {
        ++counts->rejected;
        continue;
      }
      if (crack != nullptr && (*crack)[static_cast<size_t>(v)]) {
        ++counts->crack;
        continue;
      }
      if ((mutual && foreign[static_cast<size_t>(i)]) || fc.Occluder(q)) {  // also from a held set
        ++counts->trimmed;
        continue;
      }
      if (d2 > hidden2 && normals.rows() == ns && fc.BehindOccluder(x.row(v), hidden) &&
          !same_side(q, normals.row(i).transpose())) {
        // Behind an occluder the camera did not see the vertex: a point beyond its ring on a
        // face turned away from its normal is the surface beside the occluder's shadow, across
        // an edge, whose plane pulls a hidden corner across (docs/notes/2026-11-30-artefacts.md).
        // Also from a held set, as the occluders' own marks: a vertex that moves behind the
        // occluder lets go. Needs the vertex normals (a view or point-to-plane).
        ++counts->trimmed;
        continue;
      }
      if (hold) {
        // The set is held: the trim and the visibility are not asked again.
        if (!was_paired) {
          ++counts->trimmed;
          continue;
        }
      } else if (d2 > trim2 || (view && !fc.Faces(x.row(v), normals.row(i)))) {
        // Reciprocity: a vertex with no cloud point near it was not seen (or not yet
        // reached); the cloud->model pairs bring it closer, and it pulls once within the trim.
        ++counts->trimmed;
        continue;
      }
      if (paired != nullptr) (*paired)[static_cast<size_t>(i)] = 1;
      DataPair pair;
      pair.num_vertices = 1;
      pair.vertices[0] = v;
      pair.target = cloud.points.row(q);
      // Point-to-plane on the cloud's normal when it has one, else on the model's: either
      // way no tangential pull towards the discrete samples (which would shrink the seen
      // surface towards the inside of its silhouette).
      if (plane) {
        pair.normal = cloud.has_normals() ? Eigen::Vector3d(cloud.normals.row(q).normalized())
                                          : Eigen::Vector3d(normals.row(i));
      }
      pairs->push_back(pair);
      ++counts->model_to_cloud;
    }
  }
  if (cloud_to_model) {
    for (int j = 0; j < nq; ++j) {
      const int i = j * data.cloud_stride;
      const SurfaceIndex::Hit& hit = hits[static_cast<size_t>(j)];
      if (hit.triangle < 0) continue;
      if (fc.Occluder(i)) {
        ++counts->occluded;
        continue;
      }
      if (hit.squared_distance > gate2) {
        ++counts->rejected;
        continue;
      }
      const int labelled = labels.active() ? labels.point_object[i] : -1;
      const Triangles& tris = labelled >= 0 ? labels.object_surface[labelled] : other_surface;
      if (crack != nullptr && ((*crack)[static_cast<size_t>(tris(hit.triangle, 0))] ||
                               (*crack)[static_cast<size_t>(tris(hit.triangle, 1))] ||
                               (*crack)[static_cast<size_t>(tris(hit.triangle, 2))])) {
        ++counts->crack;
        continue;
      }
      DataPair pair;
      pair.num_vertices = 3;
      for (int k = 0; k < 3; ++k) pair.vertices[k] = tris(hit.triangle, k);
      pair.barycentric = hit.barycentric;
      pair.target = cloud.points.row(i);
      if (fc.weights.size() == cloud.size()) pair.weight = fc.weights(i);
      if (plane) {
        // Inside a triangle the distance to the surface changes along the face normal. On
        // an edge or a corner (a zero barycentric coordinate) it changes along the line from
        // the closest point to the cloud point, which turns continuously from one face's
        // normal to the next: taking a face normal there pulls an edge out along one face in
        // one outer iteration and lets it go in the next, a cycle that never converges.
        const Eigen::Vector3d to_point = pair.target - pair.Point(x);
        const Eigen::Vector3d a = x.row(pair.vertices[0]), b = x.row(pair.vertices[1]),
                              c = x.row(pair.vertices[2]);
        const Eigen::Vector3d fn = (b - a).cross(c - a);
        const double edge2 = std::max({(b - a).squaredNorm(), (c - b).squaredNorm(), (a - c).squaredNorm()});
        if (hit.barycentric.minCoeff() <= 0.0 && to_point.squaredNorm() > kOnSurface * kOnSurface * edge2) {
          pair.normal = to_point.normalized();
        } else if (fn.norm() > 0) {
          pair.normal = fn.normalized();
        }
      }
      pairs->push_back(pair);
      ++counts->cloud_to_model;
    }
  }
}

std::vector<int> SubsampleStarts(const TrackerState& view, const SurfaceRings& rings, const Vertices& points,
                                 int stride, int num_threads) {
  const int nq = static_cast<int>((points.rows() + stride - 1) / stride);
  std::vector<int> starts(static_cast<size_t>(nq), -1);
  std::vector<int> seeds;
  for (int v : view.surface_vertices) {
    if (v >= 0 && v < rings.num_vertices() && rings.has(v)) seeds.push_back(v);
  }
  if (seeds.empty()) return starts;
  Vertices at(static_cast<Eigen::Index>(seeds.size()), 3);
  for (size_t i = 0; i < seeds.size(); ++i) at.row(static_cast<Eigen::Index>(i)) = view.x.row(seeds[i]);
  const PointIndex index(at);
  ParallelFor(num_threads, nq, kQueriesPerThread, [&](int64_t j) {
    double d2 = 0.0;
    const int i = index.Nearest(points.row(static_cast<Eigen::Index>(j) * stride), &d2);
    if (i >= 0) starts[static_cast<size_t>(j)] = rings.list[static_cast<size_t>(rings.offsets[static_cast<size_t>(seeds[static_cast<size_t>(i)])])];
  });
  return starts;
}

void UpdateOutputs(const PointIndex* cloud_index, const std::vector<DataPair>& pairs,
                   TrackerState* state, int num_threads) {
  for (size_t i = 0; i < state->objects.size(); ++i) {
    ObjectState& o = state->objects[i];
    o.mesh.x = state->x.middleRows(o.offset, o.mesh.num_vertices());
    state->residuals[i].setConstant(std::numeric_limits<double>::quiet_NaN());
    std::fill(state->observed[i].begin(), state->observed[i].end(), 0);
    if (cloud_index != nullptr && cloud_index->size() > 0) {
      const int ns = static_cast<int>(o.mesh.surface_vertices.size());
      Eigen::VectorXd& residuals = state->residuals[i];
      ParallelFor(num_threads, ns, kQueriesPerThread, [&](int64_t j) {
        const int v = o.mesh.surface_vertices[static_cast<size_t>(j)];
        double d2 = 0.0;
        cloud_index->Nearest(o.mesh.x.row(v), &d2);
        residuals(v) = std::sqrt(d2);
      });
    }
  }
  for (const DataPair& p : pairs) {
    for (int k = 0; k < p.num_vertices; ++k) {
      if (p.num_vertices == 3 && p.barycentric[k] < 0.2) continue;
      const int g = p.vertices[k];
      const int object = state->vertex_object[g];
      state->observed[object][g - state->objects[object].offset] = 1;
    }
  }
}

Eigen::VectorXd DataGap(const TrackerState& state, int object, const PointIndex& cloud_index) {
  const ObjectState& o = state.objects[object];
  const int nv = o.mesh.num_vertices();
  Eigen::VectorXd distance = Eigen::VectorXd::Zero(nv);
  std::vector<char> seen(nv, 0);
  std::vector<double> seen_distances;
  const Eigen::MatrixXd normals = state.VertexNormals();
  for (int v : o.mesh.surface_vertices) {
    const Eigen::Vector3d p = state.x.row(o.offset + v);
    if (normals.row(o.offset + v).dot(state.options.camera.position - p) <= 0.0) continue;
    double d2 = 0.0;
    if (cloud_index.Nearest(p, &d2) >= 0) {
      distance(v) = std::sqrt(d2);
      seen[v] = 1;
      seen_distances.push_back(distance(v));
    }
  }
  Eigen::VectorXd gap = Eigen::VectorXd::Zero(nv);
  if (seen_distances.empty()) return gap;
  // The sampling and noise level: twice the median distance.
  std::nth_element(seen_distances.begin(), seen_distances.begin() + seen_distances.size() / 2,
                   seen_distances.end());
  const double noise = 2.0 * seen_distances[seen_distances.size() / 2];
  // Vertices the camera does not see: the mean over the seen vertices of their elements.
  Eigen::VectorXd sum = Eigen::VectorXd::Zero(nv), count = Eigen::VectorXd::Zero(nv);
  for (int e = 0; e < o.mesh.num_tets(); ++e) {
    for (int a = 0; a < 4; ++a) {
      const int u = o.mesh.tets(e, a);
      if (seen[u]) continue;
      for (int b = 0; b < 4; ++b) {
        const int w = o.mesh.tets(e, b);
        if (!seen[w]) continue;
        sum(u) += distance(w);
        count(u) += 1;
      }
    }
  }
  for (int v = 0; v < nv; ++v) {
    const double d = seen[v] ? distance(v) : count(v) > 0 ? sum(v) / count(v) : 0.0;
    gap(v) = std::max(0.0, d - noise);
  }
  return gap;
}

}  // namespace femreg
