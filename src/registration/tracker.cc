// The Tracker: one frame is a few outer iterations of (rotations, correspondences, Ceres
// solve); see DESIGN.md "One frame, step by step".
#include "femreg/tracker.h"

#include <ceres/ceres.h>

#include <Eigen/Geometry>
#include <Eigen/SVD>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <map>
#include <sstream>

#include "femreg/collision.h"
#include "femreg/fracture.h"
#include "femreg/point_cloud.h"
#include "geometry/nearest.h"
#include "solvers/ceres/contact_cost.h"
#include "solvers/fast/gauss_newton.h"
#include "solvers/ceres/cost_functions.h"

namespace femreg {

namespace {

using Clock = std::chrono::steady_clock;
double Seconds(Clock::time_point since) {
  return std::chrono::duration<double>(Clock::now() - since).count();
}

struct Object {
  TetMesh mesh;
  ElasticModel model;
  int offset = 0;  // first global vertex index
};

struct Anchor {
  int object = 0;
  std::vector<int> vertices;  // global indices
  bool hard = false;
  double weight = 0.0;
  Vertices targets;           // one row per vertex
  Vertices origin;            // positions when the anchor was added
  // Per-frame translations from origin (frame beyond the list: the last one); empty: the
  // targets stay as set.
  std::vector<Eigen::Vector3d> translations;
};

// One kept data pair. Model->cloud pairs have one vertex; cloud->model pairs three.
struct DataPair {
  int num_vertices = 1;
  int vertices[3] = {0, 0, 0};
  Eigen::Vector3d barycentric = Eigen::Vector3d(1, 0, 0);
  Eigen::Vector3d target = Eigen::Vector3d::Zero();
  Eigen::Vector3d normal = Eigen::Vector3d::Zero();  // zero: point-to-point
};

ceres::LossFunction* MakeLoss(const DataTermOptions& data, double weight) {
  ceres::LossFunction* loss = nullptr;
  const double a = data.loss_scale;
  switch (data.loss) {
    case RobustLoss::kNone:
      loss = nullptr;
      break;
    case RobustLoss::kHuber:
      loss = new ceres::HuberLoss(a);
      break;
    case RobustLoss::kCauchy:
      loss = new ceres::CauchyLoss(a);
      break;
    case RobustLoss::kTukey:
      loss = new ceres::TukeyLoss(a);
      break;
  }
  if (loss == nullptr) return new ceres::ScaledLoss(nullptr, weight, ceres::TAKE_OWNERSHIP);
  return new ceres::ScaledLoss(loss, weight, ceres::TAKE_OWNERSHIP);
}

// Best rigid transform (R, t) with R * a + t ~ b, by the SVD of the cross-covariance.
void Kabsch(const std::vector<Eigen::Vector3d>& a, const std::vector<Eigen::Vector3d>& b,
            Eigen::Matrix3d* R, Eigen::Vector3d* t) {
  Eigen::Vector3d ca = Eigen::Vector3d::Zero(), cb = Eigen::Vector3d::Zero();
  for (size_t i = 0; i < a.size(); ++i) {
    ca += a[i];
    cb += b[i];
  }
  ca /= static_cast<double>(a.size());
  cb /= static_cast<double>(b.size());
  Eigen::Matrix3d H = Eigen::Matrix3d::Zero();
  for (size_t i = 0; i < a.size(); ++i) H += (a[i] - ca) * (b[i] - cb).transpose();
  Eigen::JacobiSVD<Eigen::Matrix3d> svd(H, Eigen::ComputeFullU | Eigen::ComputeFullV);
  Eigen::Matrix3d D = Eigen::Matrix3d::Identity();
  if ((svd.matrixV() * svd.matrixU().transpose()).determinant() < 0) D(2, 2) = -1.0;
  *R = svd.matrixV() * D * svd.matrixU().transpose();
  *t = cb - *R * ca;
}

}  // namespace

struct Tracker::Impl {
  RegistrationOptions options;
  std::vector<Object> objects;
  int num_vertices = 0;
  Vertices x;          // #V by 3, all objects
  Vertices x_before;   // the result of the frame before the last (for the prediction)
  Eigen::VectorXd mass;
  Triangles surface;   // global indices
  std::vector<int> surface_vertices;
  std::vector<int> vertex_object;
  std::map<std::string, Anchor> anchors;
  std::vector<Material> material_of;  // per object
  // Contacts (effects.collision): null when off or when nothing can collide, so an effect
  // that is off builds no hierarchy and adds no residual. After a topology change of object
  // i call collision->Rebuild(i, its surface in global numbering, x).
  std::unique_ptr<CollisionWorld> collision;
  std::vector<Contact> contacts;
  std::vector<int> object_label;  // per object: its cloud label, -1 = none
  // Fracture (effects.fracture): null when off, so nothing is computed or allocated.
  struct FractureData {
    std::vector<FractureOptions> options;       // per object
    std::vector<std::vector<int>> original;     // per object: vertex -> vertex at creation
    std::vector<NodeSeparation> separation;     // per object: the last detection
    int frame_splits = 0;
  };
  std::unique_ptr<FractureData> fracture;
  Vertices frame_start;  // x when the frame's temporal springs were made (fracture only)
  int frame = 0;
  std::vector<Eigen::VectorXd> residuals;
  std::vector<std::vector<char>> observed;
  // Elastic residual blocks: built once per topology, rotations read through pointers.
  // (Or edge springs for the mass-spring regularizer.)
  std::vector<std::unique_ptr<ceres::CostFunction>> elastic_costs;
  std::vector<std::vector<int>> elastic_vertices;  // global indices per elastic cost
  // The same terms for the fast back end, and its solver (pattern set per topology).
  std::vector<fast_backend::ElasticTerm> fast_elastic;
  std::vector<fast_backend::EdgeSpringTerm> fast_edges;
  std::unique_ptr<fast_backend::Solver> fast_solver;
  bool fast_pattern_dirty = true;

  Status Init(std::vector<TetMesh> meshes, const std::vector<Material>& materials);
  void BuildGlobalSurface();
  void BuildElasticCosts();
  Eigen::MatrixXd VertexNormals() const;
  void FindPairs(const PointCloud& cloud, const PointIndex& cloud_index,
                 std::vector<DataPair>* pairs, int* m2c, int* c2m, int* rejected) const;
  void RigidPrealign(const PointCloud& cloud, const PointIndex& cloud_index);
  void UpdateOutputs(const PointCloud& cloud, const PointIndex* cloud_index,
                     const std::vector<DataPair>& pairs);
  Status Track(const PointCloud& input, FrameSummary* summary);
  // Detection and splits after outer iteration k's solve; on a topology change rebuilds
  // every global array and returns, per new global vertex, its old global index.
  std::vector<int> ApplyFracture(int k, const PointIndex& cloud_index, FrameSummary* summary);
  // Per vertex of object i: by how much a camera-facing surface vertex's distance to its
  // nearest cloud point exceeds twice the median of that distance (other vertices: the
  // mean distance over the camera-facing vertices of their elements; 0 without such).
  Eigen::VectorXd DataGap(int i, const PointIndex& cloud_index) const;
};

Status Tracker::Impl::Init(std::vector<TetMesh> meshes, const std::vector<Material>& materials) {
  std::string error;
  if (!options.IsValid(&error)) return Status::Error("registration options: " + error);
  if (meshes.empty()) return Status::Error("the scene has no object");
  if (materials.size() != meshes.size()) {
    return Status::Error("one material per mesh is needed");
  }
  objects.resize(meshes.size());
  material_of = materials;
  num_vertices = 0;
  for (size_t i = 0; i < meshes.size(); ++i) {
    if (!materials[i].IsValid(&error)) {
      return Status::Error("object " + std::to_string(i) + " material: " + error);
    }
    Object& o = objects[i];
    o.mesh = std::move(meshes[i]);
    if (o.mesh.num_tets() == 0) return Status::Error("object " + std::to_string(i) + " has no tetrahedra");
    if (o.mesh.x.rows() != o.mesh.rest.rows()) o.mesh.x = o.mesh.rest;
    if (o.mesh.mass.size() != o.mesh.num_vertices() || o.mesh.mass.sum() <= 0) {
      ComputeLumpedMasses(&o.mesh, materials[i].density);
    }
    const ElasticModelType type = options.regularizer == Regularizer::kLinear
                                      ? ElasticModelType::kLinear
                                      : ElasticModelType::kCorotational;
    o.model.Build(o.mesh, type, materials[i]);
    o.offset = num_vertices;
    num_vertices += o.mesh.num_vertices();
  }
  x.resize(num_vertices, 3);
  mass.resize(num_vertices);
  vertex_object.resize(num_vertices);
  residuals.resize(objects.size());
  observed.resize(objects.size());
  for (size_t i = 0; i < objects.size(); ++i) {
    const Object& o = objects[i];
    x.middleRows(o.offset, o.mesh.num_vertices()) = o.mesh.x;
    mass.segment(o.offset, o.mesh.num_vertices()) = o.mesh.mass;
    for (int v = 0; v < o.mesh.num_vertices(); ++v) vertex_object[o.offset + v] = static_cast<int>(i);
    residuals[i] = Eigen::VectorXd::Constant(o.mesh.num_vertices(), std::numeric_limits<double>::quiet_NaN());
    observed[i].assign(o.mesh.num_vertices(), 0);
  }
  BuildGlobalSurface();
  BuildElasticCosts();
  return Status::Ok();
}

void Tracker::Impl::BuildGlobalSurface() {
  int nf = 0;
  for (const Object& o : objects) nf += o.mesh.num_surface_triangles();
  surface.resize(nf, 3);
  surface_vertices.clear();
  int row = 0;
  for (const Object& o : objects) {
    for (int f = 0; f < o.mesh.num_surface_triangles(); ++f, ++row) {
      surface.row(row) = o.mesh.surface.row(f).array() + o.offset;
    }
    for (int v : o.mesh.surface_vertices) surface_vertices.push_back(v + o.offset);
  }
}

void Tracker::Impl::BuildElasticCosts() {
  elastic_costs.clear();
  elastic_vertices.clear();
  fast_elastic.clear();
  fast_edges.clear();
  fast_pattern_dirty = true;
  if (options.regularizer == Regularizer::kNone) return;
  for (const Object& o : objects) {
    if (options.regularizer == Regularizer::kMassSpring) {
      // One spring per tet edge: k = E V_edge / L^2, with V_edge the volume share of the
      // edge (a sixth of each element around it), so that a uniform stretch of the mesh
      // costs about as much as in the FEM model.
      std::map<std::pair<int, int>, double> edges;
      for (int e = 0; e < o.model.num_elements(); ++e) {
        const double share = o.model.rest(e).volume / 6.0;
        for (int i = 0; i < 4; ++i) {
          for (int j = i + 1; j < 4; ++j) {
            int a = o.model.tets()(e, i), b = o.model.tets()(e, j);
            if (a > b) std::swap(a, b);
            edges[{a, b}] += share;
          }
        }
      }
      for (const auto& edge : edges) {
        const int a = edge.first.first, b = edge.first.second;
        const double length = (o.mesh.rest.row(a) - o.mesh.rest.row(b)).norm();
        const double k = material_of[&o - &objects[0]].youngs_modulus * edge.second / (length * length);
        elastic_costs.push_back(std::make_unique<ceres_backend::EdgeSpringCost>(
            length, options.weights.elastic * k));
        elastic_vertices.push_back({a + o.offset, b + o.offset});
        fast_edges.push_back({a + o.offset, b + o.offset, length, options.weights.elastic * k});
      }
      continue;
    }
    for (int e = 0; e < o.model.num_elements(); ++e) {
      elastic_costs.push_back(std::make_unique<ceres_backend::ElasticCost>(
          &o.model.rest(e), &o.model.rotation(e), options.weights.elastic));
      std::vector<int> v(4);
      for (int k = 0; k < 4; ++k) v[k] = o.model.tets()(e, k) + o.offset;
      elastic_vertices.push_back(v);
      fast_backend::ElasticTerm term;
      for (int k = 0; k < 4; ++k) term.vertices[k] = v[k];
      term.rest = &o.model.rest(e);
      term.rotation = &o.model.rotation(e);
      term.weight = options.weights.elastic;
      fast_elastic.push_back(term);
    }
  }
}

Eigen::MatrixXd Tracker::Impl::VertexNormals() const {
  Eigen::MatrixXd n = Eigen::MatrixXd::Zero(num_vertices, 3);
  for (int f = 0; f < surface.rows(); ++f) {
    const Eigen::Vector3d a = x.row(surface(f, 0)), b = x.row(surface(f, 1)), c = x.row(surface(f, 2));
    const Eigen::Vector3d fn = (b - a).cross(c - a);  // area weighted
    for (int k = 0; k < 3; ++k) n.row(surface(f, k)) += fn.transpose();
  }
  for (int v = 0; v < num_vertices; ++v) {
    const double len = n.row(v).norm();
    if (len > 0) n.row(v) /= len;
  }
  return n;
}

void Tracker::Impl::FindPairs(const PointCloud& cloud, const PointIndex& cloud_index,
                              std::vector<DataPair>* pairs, int* m2c, int* c2m,
                              int* rejected) const {
  pairs->clear();
  *m2c = *c2m = *rejected = 0;
  const DataTermOptions& data = options.data;
  const double gate2 = data.max_distance > 0 ? data.max_distance * data.max_distance
                                             : std::numeric_limits<double>::infinity();
  const bool plane = data.metric == DataMetric::kPointToPlane;
  const Eigen::MatrixXd normals = (data.visibility || plane) ? VertexNormals() : Eigen::MatrixXd();
  // Labelled clouds: a point whose label names an object pairs with that object only
  // (per-object k-d trees and surfaces). The other points (labels that name no object: a
  // hand, the table) pair only with the objects that have no label, and are ignored when
  // every object has one; an object without a label never takes another object's points.
  const int num_objects = static_cast<int>(objects.size());
  std::vector<std::vector<int>> label_points(num_objects);  // object -> its cloud points
  std::vector<std::unique_ptr<PointIndex>> label_index(num_objects);
  std::vector<Triangles> object_surface(num_objects);
  std::vector<std::unique_ptr<SurfaceIndex>> object_surface_index(num_objects);
  std::vector<int> point_object;  // cloud point -> object, -1 = unassigned
  std::vector<int> free_points;   // with labels: the unassigned points
  std::unique_ptr<PointIndex> free_index;
  Triangles free_surface;         // with labels: the surfaces of the objects without one
  std::unique_ptr<SurfaceIndex> free_surface_index;
  if (cloud.has_labels() &&
      std::any_of(object_label.begin(), object_label.end(), [](int l) { return l >= 0; })) {
    point_object.assign(cloud.size(), -1);
    for (int i = 0; i < cloud.size(); ++i)
      for (int o = 0; o < num_objects; ++o)
        if (object_label[o] >= 0 && cloud.labels(i) == object_label[o]) point_object[i] = o;
    for (int o = 0; o < num_objects; ++o) {
      if (object_label[o] < 0) continue;
      for (int i = 0; i < cloud.size(); ++i)
        if (point_object[i] == o) label_points[o].push_back(i);
      Vertices pts(static_cast<Eigen::Index>(label_points[o].size()), 3);
      for (size_t j = 0; j < label_points[o].size(); ++j) pts.row(j) = cloud.points.row(label_points[o][j]);
      label_index[o] = std::make_unique<PointIndex>(pts);
      const Object& ob = objects[o];
      object_surface[o] = ob.mesh.surface.array() + ob.offset;
      object_surface_index[o] = std::make_unique<SurfaceIndex>(x, object_surface[o]);
    }
    for (int i = 0; i < cloud.size(); ++i)
      if (point_object[i] < 0) free_points.push_back(i);
    Vertices pts(static_cast<Eigen::Index>(free_points.size()), 3);
    for (size_t j = 0; j < free_points.size(); ++j) pts.row(j) = cloud.points.row(free_points[j]);
    free_index = std::make_unique<PointIndex>(pts);
    int rows = 0;
    for (int o = 0; o < num_objects; ++o)
      if (object_label[o] < 0) rows += static_cast<int>(objects[o].mesh.surface.rows());
    free_surface.resize(rows, 3);
    rows = 0;
    for (int o = 0; o < num_objects; ++o) {
      if (object_label[o] >= 0) continue;
      const Object& ob = objects[o];
      free_surface.middleRows(rows, ob.mesh.surface.rows()) = ob.mesh.surface.array() + ob.offset;
      rows += static_cast<int>(ob.mesh.surface.rows());
    }
    if (rows > 0) free_surface_index = std::make_unique<SurfaceIndex>(x, free_surface);
  }
  if (data.model_to_cloud) {
    for (int v : surface_vertices) {
      const Eigen::Vector3d p = x.row(v);
      if (data.visibility && options.camera.enabled) {
        const Eigen::Vector3d n = normals.row(v);
        if (n.dot(options.camera.position - p) <= 0.0) continue;
      }
      double d2 = 0.0;
      int q = -1;
      if (point_object.empty()) {
        q = cloud_index.Nearest(p, &d2);
        if (q < 0) break;
      } else if (!label_index[vertex_object[v]]) {  // an object without a label
        q = free_index->Nearest(p, &d2);
        if (q < 0) continue;
        q = free_points[q];
      } else {
        const int o = vertex_object[v];
        q = label_index[o]->Nearest(p, &d2);
        if (q < 0) continue;
        q = label_points[o][q];
      }
      if (d2 > gate2) {
        ++*rejected;
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
      ++*m2c;
    }
  }
  if (data.cloud_to_model && surface.rows() > 0) {
    // Points without an object's label: every surface, or with labels the unlabelled
    // objects' surfaces (none: the point is no one's).
    std::unique_ptr<SurfaceIndex> whole_index;
    if (point_object.empty()) whole_index = std::make_unique<SurfaceIndex>(x, surface);
    const Triangles& other_surface = point_object.empty() ? surface : free_surface;
    const SurfaceIndex* other_index = point_object.empty() ? whole_index.get() : free_surface_index.get();
    for (int i = 0; i < cloud.size(); i += data.cloud_stride) {
      const Eigen::Vector3d q = cloud.points.row(i);
      const int labelled = point_object.empty() ? -1 : point_object[i];
      if (labelled < 0 && other_index == nullptr) continue;
      const Triangles& tris = labelled >= 0 ? object_surface[labelled] : other_surface;
      const SurfaceIndex::Hit hit =
          labelled >= 0 ? object_surface_index[labelled]->Closest(q) : other_index->Closest(q);
      if (hit.triangle < 0) continue;
      if (hit.squared_distance > gate2) {
        ++*rejected;
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
      ++*c2m;
    }
  }
}

void Tracker::Impl::RigidPrealign(const PointCloud& cloud, const PointIndex& cloud_index) {
  // Rigid ICP per object, from the translation that matches the centroid of the cloud with
  // that of the surface facing the camera (so that a fast jump is within reach), then
  // cloud->surface pairs (every seen point has a partner, hidden parts do not bias),
  // trimmed to the closest 80%. Kept only if it brings the surface closer to the cloud.
  const Eigen::MatrixXd normals = VertexNormals();
  const int stride = std::max(1, cloud.size() / 2000);
  for (const Object& o : objects) {
    std::vector<int> facing;
    for (int v : o.mesh.surface_vertices) {
      const int g = v + o.offset;
      if (options.camera.enabled) {
        const Eigen::Vector3d n = normals.row(g);
        if (n.dot(options.camera.position - Eigen::Vector3d(x.row(g))) <= 0.0) continue;
      }
      facing.push_back(g);
    }
    if (facing.size() < 3 || cloud.size() < 3) continue;
    const int nv = o.mesh.num_vertices();
    Vertices y = x.middleRows(o.offset, nv);
    Triangles tris = o.mesh.surface;
    auto trimmed_mean = [&](const Vertices& pos, Eigen::Matrix3d* R, Eigen::Vector3d* t) {
      SurfaceIndex surface_index(pos, tris);
      std::vector<std::pair<double, int>> dist;
      std::vector<Eigen::Vector3d> model_points;
      for (int i = 0; i < cloud.size(); i += stride) {
        const SurfaceIndex::Hit hit = surface_index.Closest(cloud.points.row(i));
        if (hit.triangle < 0) continue;
        dist.emplace_back(hit.squared_distance, static_cast<int>(model_points.size()));
        model_points.push_back(hit.point);
      }
      std::sort(dist.begin(), dist.end());
      const size_t keep = std::max<size_t>(std::min<size_t>(3, dist.size()), dist.size() * 4 / 5);
      std::vector<Eigen::Vector3d> a, b;
      double sum = 0.0;
      for (size_t j = 0; j < keep; ++j) {
        const int m = dist[j].second;
        a.push_back(model_points[m]);
        b.push_back(cloud.points.row(m * stride).transpose());
        sum += std::sqrt(dist[j].first);
      }
      if (R != nullptr && a.size() >= 3) Kabsch(a, b, R, t);
      return keep > 0 ? sum / keep : std::numeric_limits<double>::infinity();
    };
    const double before = trimmed_mean(y, nullptr, nullptr);
    Eigen::Vector3d cm = Eigen::Vector3d::Zero();
    for (int g : facing) cm += x.row(g).transpose();
    cm /= static_cast<double>(facing.size());
    const Eigen::RowVector3d shift = (cloud.points.colwise().mean().transpose() - cm).transpose();
    y.rowwise() += shift;
    double mean = std::numeric_limits<double>::infinity();
    for (int it = 0; it < options.solver.rigid_iterations; ++it) {
      Eigen::Matrix3d R = Eigen::Matrix3d::Identity();
      Eigen::Vector3d t = Eigen::Vector3d::Zero();
      mean = trimmed_mean(y, &R, &t);
      for (int v = 0; v < nv; ++v) y.row(v) = (R * y.row(v).transpose() + t).transpose();
      if ((R - Eigen::Matrix3d::Identity()).norm() < 1e-7 && t.norm() < 1e-7) break;
    }
    mean = trimmed_mean(y, nullptr, nullptr);
    if (mean < before) x.middleRows(o.offset, nv) = y;
  }
}

void Tracker::Impl::UpdateOutputs(const PointCloud& cloud, const PointIndex* cloud_index,
                                  const std::vector<DataPair>& pairs) {
  for (size_t i = 0; i < objects.size(); ++i) {
    Object& o = objects[i];
    o.mesh.x = x.middleRows(o.offset, o.mesh.num_vertices());
    residuals[i].setConstant(std::numeric_limits<double>::quiet_NaN());
    std::fill(observed[i].begin(), observed[i].end(), 0);
    if (cloud_index != nullptr && cloud_index->size() > 0) {
      for (int v : o.mesh.surface_vertices) {
        double d2 = 0.0;
        cloud_index->Nearest(o.mesh.x.row(v), &d2);
        residuals[i](v) = std::sqrt(d2);
      }
    }
  }
  for (const DataPair& p : pairs) {
    for (int k = 0; k < p.num_vertices; ++k) {
      if (p.num_vertices == 3 && p.barycentric[k] < 0.2) continue;
      const int g = p.vertices[k];
      const Object& o = objects[vertex_object[g]];
      observed[vertex_object[g]][g - o.offset] = 1;
    }
  }
}

Status Tracker::Impl::Track(const PointCloud& input, FrameSummary* summary) {
  const auto t_frame = Clock::now();
  FrameSummary& s = *summary;
  s = FrameSummary();
  s.frame = frame;
  s.backend = options.solver.backend;
  s.cloud_points = input.size();
  if (input.points.cols() != 3 || (input.normals.rows() != 0 && input.normals.rows() != input.points.rows())) {
    s.termination = TerminationType::kInvalidInput;
    s.message = "the cloud's points must be #P by 3 and its normals empty or #P by 3";
    ++frame;
    return Status::Ok();
  }

  // Preprocess.
  auto t0 = Clock::now();
  PointCloud cloud = input;
  PreprocessPointCloud(options.preprocess, &cloud, &s.nonfinite_dropped,
                       options.camera.enabled ? options.camera.position : Eigen::Vector3d::Zero());
  s.points_used = cloud.size();
  s.time.preprocess = Seconds(t0);
  Vertices previous = x;

  std::vector<DataPair> pairs;
  if (cloud.size() == 0) {
    s.termination = s.cloud_points > 0 ? TerminationType::kInvalidInput
                                       : TerminationType::kNoCorrespondences;
    s.message = s.cloud_points > 0
                    ? "every point of the cloud was dropped (" + std::to_string(s.nonfinite_dropped) +
                          " non-finite); the shape was held at the previous frame"
                    : "empty cloud; the shape was held at the previous frame";
    x_before = x;  // held: no velocity to carry on
    UpdateOutputs(cloud, nullptr, pairs);
    s.time.total = Seconds(t_frame);
    ++frame;
    return Status::Ok();
  }
  const PointIndex cloud_index(cloud.points);

  // Constant-velocity prediction from the last two results.
  if (options.solver.predict_motion && frame >= 2 && x_before.rows() == x.rows()) {
    const Vertices predicted = 2.0 * x - x_before;
    if (predicted.allFinite()) x = predicted;
  }

  if (options.solver.rigid_prealign) {
    t0 = Clock::now();
    RigidPrealign(cloud, cloud_index);
    s.time.prealign = Seconds(t0);
  }

  // Per-frame residuals: temporal springs to the previous frame (the rigid pre-alignment
  // moves that target too, so inertia does not fight the rigid step) and anchors.
  std::vector<std::unique_ptr<ceres::CostFunction>> frame_costs;
  std::vector<std::pair<ceres::CostFunction*, int>> temporal;
  std::vector<char> fixed;
  std::vector<std::pair<ceres::CostFunction*, int>> anchor_costs;
  std::vector<fast_backend::SpringTerm> fast_temporal, fast_anchors;
  if (fracture) frame_start = x;
  // Made again after a fracture changed the topology (springs to frame_start's copies).
  auto build_frame_costs = [&]() {
  frame_costs.clear();
  temporal.clear();
  anchor_costs.clear();
  fast_temporal.clear();
  fast_anchors.clear();
  const double wt = options.weights.temporal;
  if (wt > 0) {
    for (int v = 0; v < num_vertices; ++v) {
      const double w = wt * mass(v);
      if (!(w > 0)) continue;
      const Eigen::Vector3d target =
          fracture ? frame_start.row(v).transpose() : x.row(v).transpose();
      frame_costs.push_back(std::make_unique<ceres_backend::SpringCost>(target, w));
      temporal.emplace_back(frame_costs.back().get(), v);
      fast_temporal.push_back({v, target, w});
    }
  }
  fixed.assign(num_vertices, 0);
  for (auto& kv : anchors) {
    Anchor& a = kv.second;
    if (!a.translations.empty()) {
      const size_t i = std::min(static_cast<size_t>(frame), a.translations.size() - 1);
      a.targets = a.origin.rowwise() + a.translations[i].transpose();
    }
    for (size_t i = 0; i < a.vertices.size(); ++i) {
      const int g = a.vertices[i];
      if (a.hard) {
        x.row(g) = a.targets.row(static_cast<Eigen::Index>(i));
        fixed[g] = 1;
      } else {
        const double w = a.weight > 0 ? a.weight : options.weights.anchor;
        frame_costs.push_back(std::make_unique<ceres_backend::SpringCost>(
            a.targets.row(static_cast<Eigen::Index>(i)).transpose(), w));
        anchor_costs.emplace_back(frame_costs.back().get(), g);
        fast_anchors.push_back({g, a.targets.row(static_cast<Eigen::Index>(i)).transpose(), w});
      }
    }
  }
  };
  build_frame_costs();

  ceres::Solver::Options solver_options;
  solver_options.max_num_iterations = options.solver.max_inner_iterations;
  solver_options.num_threads = options.solver.num_threads;
  solver_options.logging_type = ceres::SILENT;
  solver_options.minimizer_progress_to_stdout = false;
  solver_options.trust_region_strategy_type =
      options.solver.trust_region == TrustRegion::kDogleg ? ceres::DOGLEG : ceres::LEVENBERG_MARQUARDT;
  if (options.solver.linear_solver == LinearSolver::kConjugateGradients) {
    solver_options.linear_solver_type = ceres::CGNR;
    solver_options.preconditioner_type = ceres::JACOBI;
  } else {
    solver_options.linear_solver_type = ceres::SPARSE_NORMAL_CHOLESKY;
    solver_options.sparse_linear_algebra_library_type = ceres::SUITE_SPARSE;
  }

  int m2c = 0, c2m = 0, rejected = 0;
  bool have_initial = false;
  double previous_energy = std::numeric_limits<double>::infinity();
  for (int k = 0; k < options.solver.max_outer_iterations; ++k) {
    const auto t_outer = Clock::now();
    OuterIteration row;
    row.iteration = k + 1;
    t0 = Clock::now();
    for (Object& o : objects) {
      // Only the corotational regularizer reads rotations: what is off costs nothing.
      if (options.regularizer == Regularizer::kCorotational) {
        o.model.UpdateRotations(x.middleRows(o.offset, o.mesh.num_vertices()));
      }
    }
    s.time.rotations += Seconds(t0);

    t0 = Clock::now();
    FindPairs(cloud, cloud_index, &pairs, &m2c, &c2m, &rejected);
    s.time.correspondences += Seconds(t0);
    row.model_to_cloud = m2c;
    row.cloud_to_model = c2m;
    row.rejected = rejected;
    if (pairs.empty()) {
      s.rejected = rejected;
      if (k == 0) {
        s.termination = TerminationType::kNoCorrespondences;
        s.message = "no correspondence within data.max_distance (" +
                    std::to_string(rejected) + " rejected); the shape was held at the previous frame";
      }
      break;
    }

    // Contacts at the current x (refit, broad and narrow phase), normals held for the solve
    // of either back end; margin D keeps pairs that the solve may bring within D.
    if (collision) {
      const auto t_collision = Clock::now();
      collision->SetFrame(frame);
      collision->Detect(x, collision->distance(), &contacts);
      row.contacts = static_cast<int>(contacts.size());
      s.time.collision += Seconds(t_collision);
    }

    // The fast back end.
    if (options.solver.backend == SolverBackend::kFast) {
      t0 = Clock::now();
      if (!fast_solver) fast_solver = std::make_unique<fast_backend::Solver>();
      if (fast_pattern_dirty) {
        std::vector<std::array<int, 4>> all_tets;
        for (const Object& o : objects) {
          for (int e = 0; e < o.mesh.num_tets(); ++e) {
            std::array<int, 4> t;
            for (int k = 0; k < 4; ++k) t[k] = o.mesh.tets(e, k) + o.offset;
            all_tets.push_back(t);
          }
        }
        fast_solver->SetPattern(num_vertices, all_tets);
        fast_pattern_dirty = false;
      }
      fast_backend::Problem fp;
      fp.elastic = fast_elastic;
      fp.edges = fast_edges;
      fp.data.reserve(pairs.size());
      for (const DataPair& p : pairs) {
        fast_backend::PointTerm t;
        t.num_vertices = p.num_vertices;
        for (int j = 0; j < 3; ++j) t.vertices[j] = p.vertices[j];
        t.barycentric = p.barycentric;
        t.target = p.target;
        t.normal = p.normal;
        fp.data.push_back(t);
      }
      fp.data_weight = options.weights.data;
      fp.loss = options.data.loss;
      fp.loss_scale = options.data.loss_scale;
      fp.temporal = fast_temporal;
      fp.anchors = fast_anchors;
      fp.fixed = fixed;
      s.time.build += Seconds(t0);
      if (collision) {
        fp.contact_stiffness = collision->stiffness();
        fp.contacts.reserve(contacts.size());
        for (const Contact& c : contacts) {
          fast_backend::ContactTerm t;
          t.normal = c.normal;
          t.offset = collision->distance();
          for (int j = 0; j < 3; ++j) {
            t.vertices[j] = c.vertices_a[j];
            t.weights[j] = c.bary_a[j];
          }
          if (c.obstacle()) {
            t.num_vertices = 3;
            t.offset += c.normal.dot(c.point_b);
          } else {
            t.num_vertices = 6;
            for (int j = 0; j < 3; ++j) {
              t.vertices[3 + j] = c.vertices_b[j];
              t.weights[3 + j] = -c.bary_b[j];
            }
          }
          fp.contacts.push_back(t);
        }
      }
      row.before = fast_backend::Evaluate(fp, x);
      if (!have_initial) {
        s.initial = row.before;
        have_initial = true;
      }
      t0 = Clock::now();
      const Vertices before_solve = x;
      const fast_backend::SolveSummary fs =
          fast_solver->Solve(fp, options.solver.max_inner_iterations, &x);
      s.time.solve += Seconds(t0);
      row.inner_iterations = fs.iterations;
      if (!fs.success || !x.allFinite()) {
        x = before_solve;
        s.termination = TerminationType::kSolverFailure;
        s.message = "fast back end: " + fs.message + "; the shape before this iteration was kept";
        s.iterations.push_back(row);
        break;
      }
      row.after = fast_backend::Evaluate(fp, x);
    } else {
      // Build the problem. Residual blocks reference vertex rows of x directly.
      t0 = Clock::now();
      ceres::Problem::Options problem_options;
      problem_options.cost_function_ownership = ceres::DO_NOT_TAKE_OWNERSHIP;
      problem_options.loss_function_ownership = ceres::TAKE_OWNERSHIP;
      problem_options.enable_fast_removal = false;
      ceres::Problem problem(problem_options);
      auto block = [&](int v) { return x.data() + 3 * v; };
      std::vector<ceres::ResidualBlockId> ids_data, ids_elastic, ids_temporal, ids_anchor;
      for (size_t e = 0; e < elastic_costs.size(); ++e) {
        std::vector<double*> blocks;
        for (int v : elastic_vertices[e]) blocks.push_back(block(v));
        ids_elastic.push_back(problem.AddResidualBlock(elastic_costs[e].get(), nullptr, blocks));
      }
      for (const auto& tv : temporal) {
        ids_temporal.push_back(problem.AddResidualBlock(tv.first, nullptr, block(tv.second)));
      }
      for (const auto& av : anchor_costs) {
        ids_anchor.push_back(problem.AddResidualBlock(av.first, nullptr, block(av.second)));
      }
      std::vector<std::unique_ptr<ceres::CostFunction>> data_costs;
      data_costs.reserve(pairs.size());
      const double wd = options.weights.data;
      for (const DataPair& p : pairs) {
        const bool plane = p.normal.squaredNorm() > 0;
        ceres::CostFunction* cost;
        if (p.num_vertices == 1) {
          cost = plane ? static_cast<ceres::CostFunction*>(
                             new ceres_backend::PointToPlaneCost1(p.target, p.normal, 1.0))
                       : new ceres_backend::PointToPointCost1(p.target, 1.0);
        } else {
          cost = plane ? static_cast<ceres::CostFunction*>(new ceres_backend::PointToPlaneCost3(
                             p.barycentric, p.target, p.normal, 1.0))
                       : new ceres_backend::PointToPointCost3(p.barycentric, p.target, 1.0);
        }
        data_costs.emplace_back(cost);
        std::vector<double*> blocks;
        for (int j = 0; j < p.num_vertices; ++j) blocks.push_back(block(p.vertices[j]));
        ids_data.push_back(problem.AddResidualBlock(cost, MakeLoss(options.data, wd), blocks));
      }
      std::vector<ceres::ResidualBlockId> ids_collision;
      if (collision) {
        const double D = collision->distance(), kc = collision->stiffness();
        for (const Contact& c : contacts) {
          ceres::CostFunction* cost;
          std::vector<double*> blocks;
          for (int j = 0; j < 3; ++j) blocks.push_back(block(c.vertices_a[j]));
          if (c.obstacle()) {
            cost = new ceres_backend::ContactObstacleCost(c.bary_a, c.point_b, c.normal, D, kc);
          } else {
            cost = new ceres_backend::ContactPairCost(c.bary_a, c.bary_b, c.normal, D, kc);
            for (int j = 0; j < 3; ++j) blocks.push_back(block(c.vertices_b[j]));
          }
          data_costs.emplace_back(cost);
          ids_collision.push_back(problem.AddResidualBlock(cost, nullptr, blocks));
        }
      }
      for (int v = 0; v < num_vertices; ++v) {
        if (fixed[v] && problem.HasParameterBlock(block(v))) problem.SetParameterBlockConstant(block(v));
      }
      s.time.build += Seconds(t0);

      auto energy = [&](const std::vector<ceres::ResidualBlockId>& ids) {
        if (ids.empty()) return 0.0;
        ceres::Problem::EvaluateOptions eo;
        eo.residual_blocks = ids;
        eo.apply_loss_function = true;
        double cost = 0.0;
        problem.Evaluate(eo, &cost, nullptr, nullptr, nullptr);
        return cost;
      };
      auto terms = [&]() {
        EnergyTerms e;
        e.data = energy(ids_data);
        e.elastic = energy(ids_elastic);
        e.temporal = energy(ids_temporal);
        e.anchor = energy(ids_anchor);
        e.collision = energy(ids_collision);
        return e;
      };
      row.before = terms();
      if (!have_initial) {
        s.initial = row.before;
        have_initial = true;
      }

      t0 = Clock::now();
      if (options.solver.time_budget_s > 0) {
        solver_options.max_solver_time_in_seconds =
            std::max(1e-3, options.solver.time_budget_s - Seconds(t_frame));
      }
      const Vertices before_solve = x;
      ceres::Solver::Summary ceres_summary;
      ceres::Solve(solver_options, &problem, &ceres_summary);
      s.time.solve += Seconds(t0);
      row.inner_iterations = static_cast<int>(ceres_summary.iterations.size()) - 1;
      if (!ceres_summary.IsSolutionUsable() || !x.allFinite()) {
        x = before_solve;
        s.termination = TerminationType::kSolverFailure;
        s.message = "Ceres: " + ceres_summary.message + "; the shape before this iteration was kept";
        s.iterations.push_back(row);
        break;
      }
      row.after = terms();
    }
    double sum2 = 0.0;
    int count = 0;
    for (const DataPair& p : pairs) {
      Eigen::Vector3d q = Eigen::Vector3d::Zero();
      for (int j = 0; j < p.num_vertices; ++j) q += p.barycentric[j] * x.row(p.vertices[j]).transpose();
      sum2 += (q - p.target).squaredNorm();
      ++count;
    }
    row.rms_residual = count > 0 ? std::sqrt(sum2 / count) : 0.0;
    row.time_s = Seconds(t_outer);
    s.iterations.push_back(row);
    s.inner_iterations += row.inner_iterations;
    s.outer_iterations = k + 1;
    s.final = row.after;
    s.model_to_cloud = m2c;
    s.cloud_to_model = c2m;
    s.rejected = rejected;
    s.rms_residual = row.rms_residual;

    if (fracture) {  // seed Section 4: between outer iterations
      const std::vector<int> source = ApplyFracture(k, cloud_index, &s);
      if (!source.empty()) {
        previous = RemapRows(previous, source);
        build_frame_costs();
        FindPairs(cloud, cloud_index, &pairs, &m2c, &c2m, &rejected);  // for the outputs
        previous_energy = std::numeric_limits<double>::infinity();
      }
    }

    // Compare with the previous outer iteration's result (its pairs were different, so
    // the energy before this iteration's solve is not comparable).
    const double e1 = row.after.total();
    const double change = std::abs(previous_energy - e1) / std::max(e1, 1e-300);
    previous_energy = e1;
    if (k > 0 && change < options.solver.relative_energy_tolerance) {
      s.termination = TerminationType::kConverged;
      std::ostringstream os;
      os << "relative energy change " << change << " < " << options.solver.relative_energy_tolerance;
      s.message = os.str();
      break;
    }
    if (options.solver.time_budget_s > 0 && Seconds(t_frame) >= options.solver.time_budget_s) {
      s.termination = TerminationType::kTimeBudget;
      s.message = "time budget of " + std::to_string(options.solver.time_budget_s) + " s used";
      break;
    }
    if (k + 1 == options.solver.max_outer_iterations) {
      s.termination = TerminationType::kMaxIterations;
      s.message = "reached solver.max_outer_iterations = " +
                  std::to_string(options.solver.max_outer_iterations);
    }
  }
  if (s.termination == TerminationType::kNotRun) {
    s.termination = TerminationType::kMaxIterations;
    s.message = "no outer iteration ran";
  }
  if (s.termination == TerminationType::kNoCorrespondences) x = previous;
  if (collision) {  // the contacts the result keeps, and the deepest penetration
    const auto t_collision = Clock::now();
    collision->SetFrame(frame);
    collision->Detect(x, 0.0, &contacts);
    const ContactStats cs = collision->Evaluate(contacts, x);
    s.contacts = cs.contacts;
    s.object_contacts = cs.object_contacts;
    s.obstacle_contacts = cs.obstacle_contacts;
    s.max_penetration = cs.max_penetration;
    s.time.collision += Seconds(t_collision);
  }
  x_before = previous;
  UpdateOutputs(cloud, &cloud_index, pairs);
  s.time.total = Seconds(t_frame);
  ++frame;
  return Status::Ok();
}

Eigen::VectorXd Tracker::Impl::DataGap(int i, const PointIndex& cloud_index) const {
  const Object& o = objects[i];
  const int nv = o.mesh.num_vertices();
  Eigen::VectorXd distance = Eigen::VectorXd::Zero(nv);
  std::vector<char> seen(nv, 0);
  std::vector<double> seen_distances;
  const Eigen::MatrixXd normals = VertexNormals();
  for (int v : o.mesh.surface_vertices) {
    const Eigen::Vector3d p = x.row(o.offset + v);
    if (normals.row(o.offset + v).dot(options.camera.position - p) <= 0.0) continue;
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

// FractureOptions::data_gap: the data's evidence at most triples the measure.
constexpr double kMaxDataGapWeight = 3.0;

std::vector<int> Tracker::Impl::ApplyFracture(int k, const PointIndex& cloud_index,
                                              FrameSummary* summary) {
  const auto t0 = Clock::now();
  FractureData& f = *fracture;
  if (k == 0) f.frame_splits = 0;
  std::vector<std::vector<int>> sources(objects.size());
  bool changed = false;
  for (size_t i = 0; i < objects.size(); ++i) {
    Object& o = objects[i];
    o.mesh.x = x.middleRows(o.offset, o.mesh.num_vertices());
    o.model.UpdateRotations(o.mesh.x);
    NodeSeparation& sep = f.separation[i];
    DetectFracture(o.mesh, o.model, o.mesh.x, f.options[i], &sep);
    const int budget = std::min(f.options[i].max_splits_per_iteration,
                                f.options[i].max_splits_per_frame - f.frame_splits);
    if (budget <= 0) continue;
    // Evidence from the data (FractureOptions::data_gap), only when a node could break.
    sep.weight.resize(0);
    if (f.options[i].data_gap && options.camera.enabled && cloud_index.size() > 0) {
      double top = 0.0;
      for (int v = 0; v < sep.measure.size(); ++v) {
        if (sep.toughness(v) > 0) top = std::max(top, sep.measure(v) / sep.toughness(v));
      }
      if (top * kMaxDataGapWeight > 1.0) {
        const Eigen::VectorXd gap = DataGap(static_cast<int>(i), cloud_index);
        const double scale = options.data.loss_scale > 0 ? options.data.loss_scale : 0.005;
        sep.weight = (Eigen::VectorXd::Ones(gap.size()) + gap / scale).cwiseMin(kMaxDataGapWeight);
      }
    }
    const double density = o.mesh.mass.sum() / std::max(RestVolume(o.mesh), 1e-300);
    TopologyChange change;
    SplitNodes(f.separation[i], f.options[i], budget, &o.mesh, &o.model, &change);
    if (!change.changed()) continue;
    changed = true;
    f.frame_splits += static_cast<int>(change.events.size());
    for (FractureEvent e : change.events) {
      e.frame = frame;
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
    ComputeLumpedMasses(&o.mesh, density);
    sources[i] = std::move(change.source);
  }
  summary->time.fracture += Seconds(t0);
  if (!changed) return {};

  // The new global numbering: objects in order, each from its new mesh.
  std::vector<int> source;
  for (size_t i = 0; i < objects.size(); ++i) {
    const int old_offset = objects[i].offset;
    const int nv = objects[i].mesh.num_vertices();
    for (int v = 0; v < nv; ++v) source.push_back(old_offset + (sources[i].empty() ? v : sources[i][v]));
  }
  const int old_count = num_vertices;
  num_vertices = 0;
  for (Object& o : objects) {
    o.offset = num_vertices;
    num_vertices += o.mesh.num_vertices();
  }
  x = RemapRows(x, source);
  if (x_before.rows() == old_count) x_before = RemapRows(x_before, source);
  if (frame_start.rows() == old_count) frame_start = RemapRows(frame_start, source);
  mass.resize(num_vertices);
  vertex_object.resize(num_vertices);
  for (size_t i = 0; i < objects.size(); ++i) {
    const Object& o = objects[i];
    mass.segment(o.offset, o.mesh.num_vertices()) = o.mesh.mass;
    for (int v = 0; v < o.mesh.num_vertices(); ++v) vertex_object[o.offset + v] = static_cast<int>(i);
    residuals[i] = Eigen::VectorXd::Constant(o.mesh.num_vertices(), std::numeric_limits<double>::quiet_NaN());
    observed[i].assign(o.mesh.num_vertices(), 0);
  }
  // Anchors hold every copy of their vertices.
  std::vector<std::vector<int>> copies(old_count);
  for (size_t v = 0; v < source.size(); ++v) copies[source[v]].push_back(static_cast<int>(v));
  for (auto& kv : anchors) {
    Anchor& a = kv.second;
    std::vector<int> vertices;
    std::vector<int> rows;
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
  BuildGlobalSurface();
  BuildElasticCosts();
  if (collision) {
    for (size_t i = 0; i < objects.size(); ++i) {
      collision->Rebuild(static_cast<int>(i), objects[i].mesh.surface.array() + objects[i].offset, x);
    }
  }
  return source;
}

Tracker::Tracker() : impl_(new Impl) {}
Tracker::~Tracker() = default;

Status Tracker::Create(const std::vector<TetMesh>& meshes, const std::vector<Material>& materials,
                       const RegistrationOptions& options, std::unique_ptr<Tracker>* tracker) {
  std::unique_ptr<Tracker> t(new Tracker);
  t->impl_->options = options;
  Status status = t->impl_->Init(meshes, materials);
  if (!status.ok()) return status;
  *tracker = std::move(t);
  return Status::Ok();
}

Status Tracker::Create(const Scene& scene, std::unique_ptr<Tracker>* tracker) {
  std::vector<TetMesh> meshes(scene.objects.size());
  std::vector<Material> materials;
  for (size_t i = 0; i < scene.objects.size(); ++i) {
    Status status = LoadObjectMesh(scene, static_cast<int>(i), &meshes[i]);
    if (!status.ok()) return status;
    materials.push_back(scene.objects[i].material);
  }
  std::unique_ptr<Tracker> t;
  Status status = Create(meshes, materials, scene.registration, &t);
  if (!status.ok()) return status;
  for (const ObjectSpec& o : scene.objects) t->impl_->object_label.push_back(o.label);
  if (scene.effects.fracture) {
    std::vector<FractureOptions> fracture;
    for (const ObjectSpec& o : scene.objects) {
      FractureOptions f = scene.effects.fracture_options;
      f.toughness = o.toughness;
      f.region_toughness = o.region_toughness;
      fracture.push_back(f);
    }
    status = t->EnableFracture(fracture);
    if (!status.ok()) return Status::Error(scene.path + ": effects.fracture: " + status.message());
  }
  if (scene.effects.collision) {
    Tracker::Impl& impl = *t->impl_;
    std::vector<std::string> names;
    std::vector<Triangles> surfaces;
    for (size_t i = 0; i < scene.objects.size(); ++i) {
      names.push_back(scene.objects[i].name);
      surfaces.push_back(impl.objects[i].mesh.surface.array() + impl.objects[i].offset);
    }
    auto world = std::make_unique<CollisionWorld>();
    status = world->Init(scene.collision, names, surfaces, impl.x);  // no pairs: every pair
    if (!status.ok()) return Status::Error(scene.path + ": " + status.message());
    if (world->enabled()) impl.collision = std::move(world);
  }
  for (const AnchorSpec& a : scene.anchors) {
    int object = 0;
    for (size_t i = 0; i < scene.objects.size(); ++i) {
      if (scene.objects[i].name == a.object) object = static_cast<int>(i);
    }
    std::vector<int> verts;
    status = SelectVertices(a.selection, t->mesh(object).rest, &verts);
    if (!status.ok()) return status;
    status = t->AddAnchor(a.name, object, verts, a.hard, a.weight);
    if (!status.ok()) return status;
    if (!a.translations.empty()) {
      status = t->SetAnchorTrajectory(a.name, a.translations);
      if (!status.ok()) return status;
    }
  }
  *tracker = std::move(t);
  return Status::Ok();
}

Status Tracker::Track(const PointCloud& cloud, FrameSummary* summary) {
  if (summary == nullptr) return Status::Error("Tracker::Track: summary must not be null");
  return impl_->Track(cloud, summary);
}

int Tracker::num_objects() const { return static_cast<int>(impl_->objects.size()); }
const TetMesh& Tracker::mesh(int object) const { return impl_->objects.at(object).mesh; }
const Vertices& Tracker::vertices(int object) const { return impl_->objects.at(object).mesh.x; }
const Eigen::VectorXd& Tracker::vertex_residuals(int object) const {
  return impl_->residuals.at(object);
}
const std::vector<char>& Tracker::vertex_observed(int object) const {
  return impl_->observed.at(object);
}
int Tracker::frame() const { return impl_->frame; }

Status Tracker::EnableFracture(const std::vector<FractureOptions>& options) {
  if (options.size() != impl_->objects.size()) {
    return Status::Error("one FractureOptions per object is needed");
  }
  std::string error;
  for (size_t i = 0; i < options.size(); ++i) {
    if (!options[i].IsValid(&error)) return Status::Error("object " + std::to_string(i) + ": " + error);
  }
  auto f = std::make_unique<Impl::FractureData>();
  f->options = options;
  for (const Object& o : impl_->objects) {
    std::vector<int> ids(o.mesh.num_vertices());
    for (int v = 0; v < o.mesh.num_vertices(); ++v) ids[v] = v;
    f->original.push_back(std::move(ids));
    NodeSeparation sep;
    sep.measure = Eigen::VectorXd::Zero(o.mesh.num_vertices());
    f->separation.push_back(std::move(sep));
  }
  impl_->fracture = std::move(f);
  return Status::Ok();
}

const Eigen::VectorXd& Tracker::fracture_measure(int object) const {
  static const Eigen::VectorXd kEmpty;
  return impl_->fracture ? impl_->fracture->separation.at(object).measure : kEmpty;
}

const std::vector<int>& Tracker::original_vertices(int object) const {
  static const std::vector<int> kEmpty;
  return impl_->fracture ? impl_->fracture->original.at(object) : kEmpty;
}
const RegistrationOptions& Tracker::options() const { return impl_->options; }
const CollisionWorld* Tracker::collision() const { return impl_->collision.get(); }

Status Tracker::AddAnchor(const std::string& name, int object, const std::vector<int>& vertices,
                          bool hard, double weight) {
  if (object < 0 || object >= num_objects()) {
    return Status::Error("anchor '" + name + "': no object " + std::to_string(object));
  }
  if (vertices.empty()) return Status::Error("anchor '" + name + "': no vertex");
  if (impl_->anchors.count(name)) return Status::Error("anchor '" + name + "' exists already");
  const Object& o = impl_->objects[object];
  Anchor a;
  a.object = object;
  a.hard = hard;
  a.weight = weight;
  a.targets.resize(static_cast<Eigen::Index>(vertices.size()), 3);
  for (size_t i = 0; i < vertices.size(); ++i) {
    if (vertices[i] < 0 || vertices[i] >= o.mesh.num_vertices()) {
      return Status::Error("anchor '" + name + "': vertex " + std::to_string(vertices[i]) +
                           " out of range");
    }
    a.vertices.push_back(vertices[i] + o.offset);
    a.targets.row(static_cast<Eigen::Index>(i)) = o.mesh.x.row(vertices[i]);
  }
  a.origin = a.targets;
  impl_->anchors[name] = std::move(a);
  return Status::Ok();
}

Status Tracker::SetAnchorTargets(const std::string& name, const Vertices& targets) {
  auto it = impl_->anchors.find(name);
  if (it == impl_->anchors.end()) return Status::Error("no anchor named '" + name + "'");
  if (targets.rows() != it->second.targets.rows() || !targets.allFinite()) {
    return Status::Error("anchor '" + name + "': expected " +
                         std::to_string(it->second.targets.rows()) + " finite targets");
  }
  it->second.targets = targets;
  it->second.translations.clear();
  return Status::Ok();
}

Status Tracker::SetAnchorTrajectory(const std::string& name,
                                    const std::vector<Eigen::Vector3d>& translations) {
  auto it = impl_->anchors.find(name);
  if (it == impl_->anchors.end()) return Status::Error("no anchor named '" + name + "'");
  for (const auto& t : translations) {
    if (!t.allFinite()) return Status::Error("anchor '" + name + "': non-finite translation");
  }
  it->second.translations = translations;
  return Status::Ok();
}

}  // namespace femreg
