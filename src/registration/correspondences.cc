#include "registration/correspondences.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <memory>

namespace femreg {

Eigen::Vector3d DataPair::Point(const Vertices& x) const {
  Eigen::Vector3d p = Eigen::Vector3d::Zero();
  for (int j = 0; j < num_vertices; ++j) p += barycentric[j] * x.row(vertices[j]).transpose();
  return p;
}

namespace {

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

}  // namespace

void FindPairs(const TrackerState& state, const PointCloud& cloud, const PointIndex& cloud_index,
               std::vector<DataPair>* pairs, PairCounts* counts) {
  pairs->clear();
  *counts = PairCounts();
  const RegistrationOptions& options = state.options;
  const DataTermOptions& data = options.data;
  const Vertices& x = state.x;
  const double gate2 = data.max_distance > 0 ? data.max_distance * data.max_distance
                                             : std::numeric_limits<double>::infinity();
  const bool plane = data.metric == DataMetric::kPointToPlane;
  const Eigen::MatrixXd normals =
      (data.visibility || plane) ? state.VertexNormals() : Eigen::MatrixXd();
  const LabelSplit labels(state, cloud);

  if (data.model_to_cloud) {
    for (int v : state.surface_vertices) {
      const Eigen::Vector3d p = x.row(v);
      if (data.visibility && options.camera.enabled) {
        const Eigen::Vector3d n = normals.row(v);
        if (n.dot(options.camera.position - p) <= 0.0) continue;
      }
      double d2 = 0.0;
      int q = -1;
      if (!labels.active()) {
        q = cloud_index.Nearest(p, &d2);
        if (q < 0) break;
      } else {
        const int o = state.vertex_object[v];
        const bool labelled = state.objects[o].label >= 0;
        const PointIndex& index = labelled ? *labels.object_index[o] : *labels.free_index;
        q = index.Nearest(p, &d2);
        if (q < 0) continue;
        q = labelled ? labels.object_points[o][q] : labels.free_points[q];
      }
      if (d2 > gate2) {
        ++counts->rejected;
        continue;
      }
      DataPair pair;
      pair.num_vertices = 1;
      pair.vertices[0] = v;
      pair.target = cloud.points.row(q);
      // Point-to-plane on the cloud's normal when it has one, else on the model's: either
      // way no tangential pull towards the discrete samples (which would shrink the seen
      // surface towards the inside of its silhouette).
      if (plane) {
        pair.normal = cloud.has_normals() ? Eigen::Vector3d(cloud.normals.row(q).normalized())
                                          : Eigen::Vector3d(normals.row(v));
      }
      pairs->push_back(pair);
      ++counts->model_to_cloud;
    }
  }
  if (data.cloud_to_model && state.surface.rows() > 0) {
    // Points without an object's label: every surface, or with labels the unlabelled
    // objects' surfaces (none: the point is no one's).
    std::unique_ptr<SurfaceIndex> whole_index;
    if (!labels.active()) whole_index = std::make_unique<SurfaceIndex>(x, state.surface);
    const Triangles& other_surface = labels.active() ? labels.free_surface : state.surface;
    const SurfaceIndex* other_index =
        labels.active() ? labels.free_surface_index.get() : whole_index.get();
    for (int i = 0; i < cloud.size(); i += data.cloud_stride) {
      const Eigen::Vector3d q = cloud.points.row(i);
      const int labelled = labels.active() ? labels.point_object[i] : -1;
      if (labelled < 0 && other_index == nullptr) continue;
      const Triangles& tris = labelled >= 0 ? labels.object_surface[labelled] : other_surface;
      const SurfaceIndex::Hit hit = labelled >= 0 ? labels.object_surface_index[labelled]->Closest(q)
                                                  : other_index->Closest(q);
      if (hit.triangle < 0) continue;
      if (hit.squared_distance > gate2) {
        ++counts->rejected;
        continue;
      }
      DataPair pair;
      pair.num_vertices = 3;
      for (int k = 0; k < 3; ++k) pair.vertices[k] = tris(hit.triangle, k);
      pair.barycentric = hit.barycentric;
      pair.target = q;
      if (plane) {
        const Eigen::Vector3d a = x.row(pair.vertices[0]), b = x.row(pair.vertices[1]),
                              c = x.row(pair.vertices[2]);
        const Eigen::Vector3d fn = (b - a).cross(c - a);
        if (fn.norm() > 0) pair.normal = fn.normalized();
      }
      pairs->push_back(pair);
      ++counts->cloud_to_model;
    }
  }
}

void UpdateOutputs(const PointIndex* cloud_index, const std::vector<DataPair>& pairs,
                   TrackerState* state) {
  for (size_t i = 0; i < state->objects.size(); ++i) {
    ObjectState& o = state->objects[i];
    o.mesh.x = state->x.middleRows(o.offset, o.mesh.num_vertices());
    state->residuals[i].setConstant(std::numeric_limits<double>::quiet_NaN());
    std::fill(state->observed[i].begin(), state->observed[i].end(), 0);
    if (cloud_index != nullptr && cloud_index->size() > 0) {
      for (int v : o.mesh.surface_vertices) {
        double d2 = 0.0;
        cloud_index->Nearest(o.mesh.x.row(v), &d2);
        state->residuals[i](v) = std::sqrt(d2);
      }
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
