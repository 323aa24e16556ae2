#include "registration/embedded_surface.h"

#include <Eigen/LU>
#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <string>

#include "geometry/morton.h"
#include "parallel/pool.h"
#include "parallel/threads.h"

namespace femreg {

Status MakeEmbeddedSurface(const TetMesh& mesh, const Vertices& rest, const Triangles& triangles,
                           EmbeddedSurface* out) {
  if (rest.rows() == 0 || triangles.rows() == 0) return Status::Error("the embedded surface is empty");
  if (!rest.allFinite()) return Status::Error("the embedded surface has non-finite vertices");
  if (triangles.minCoeff() < 0 || triangles.maxCoeff() >= rest.rows()) {
    return Status::Error("the embedded surface has a triangle with a vertex index out of range");
  }
  if (mesh.num_tets() == 0) return Status::Error("the mesh has no tetrahedra to embed a surface in");
  out->rest = rest;
  out->triangles = triangles;
  out->embedding = EmbedPoints(mesh, rest, /*clamp=*/false);
  out->outside = 0.0;
  for (Eigen::Index i = 0; i < rest.rows(); ++i) {
    const Eigen::Vector4d& b = out->embedding.barycentric[static_cast<size_t>(i)];
    if (b.minCoeff() >= 0.0) continue;
    // The distance to the element: to the closest of its faces (the point is outside it).
    const int t = out->embedding.element[static_cast<size_t>(i)];
    const Eigen::Vector3d q = rest.row(i).transpose();
    double d2 = std::numeric_limits<double>::infinity();
    for (int k = 0; k < 4; ++k) {
      const Eigen::Vector3d a = mesh.rest.row(mesh.tets(t, k)), b1 = mesh.rest.row(mesh.tets(t, (k + 1) % 4)),
                            c1 = mesh.rest.row(mesh.tets(t, (k + 2) % 4));
      d2 = std::min(d2, (TriangleClosestPoint(q, a, b1, c1) - q).squaredNorm());
    }
    out->outside = std::max(out->outside, std::sqrt(d2));
  }
  return Status::Ok();
}

namespace {
// A copy of `s` with its vertices along a Morton curve and its triangles along the curve of
// their centroids: the pair search, the normals and the depth image walk a scan's rings and
// triangles in the order they lie in space, not in its file's (the view's numbering is the
// tracker's own; the API and the outputs keep the file's).
EmbeddedSurface SpatiallyOrdered(const EmbeddedSurface& s, std::vector<int>* order_out) {
  const Eigen::Index n = s.rest.rows(), nf = s.triangles.rows();
  const std::vector<int> order = MortonOrder(s.rest);  // new index -> old
  *order_out = order;
  std::vector<int> new_index(static_cast<size_t>(n));
  EmbeddedSurface out;
  out.outside = s.outside;
  out.rest.resize(n, 3);
  out.embedding.element.resize(static_cast<size_t>(n));
  out.embedding.barycentric.resize(static_cast<size_t>(n));
  for (Eigen::Index i = 0; i < n; ++i) {
    const int old = order[static_cast<size_t>(i)];
    new_index[static_cast<size_t>(old)] = static_cast<int>(i);
    out.rest.row(i) = s.rest.row(old);
    out.embedding.element[static_cast<size_t>(i)] = s.embedding.element[static_cast<size_t>(old)];
    out.embedding.barycentric[static_cast<size_t>(i)] = s.embedding.barycentric[static_cast<size_t>(old)];
  }
  Vertices centroids(nf, 3);
  for (Eigen::Index f = 0; f < nf; ++f) {
    centroids.row(f) = (s.rest.row(s.triangles(f, 0)) + s.rest.row(s.triangles(f, 1)) + s.rest.row(s.triangles(f, 2))) / 3.0;
  }
  const std::vector<int> face_order = MortonOrder(centroids);
  out.triangles.resize(nf, 3);
  for (Eigen::Index f = 0; f < nf; ++f) {
    for (int k = 0; k < 3; ++k) {
      out.triangles(f, k) = new_index[static_cast<size_t>(s.triangles(face_order[static_cast<size_t>(f)], k))];
    }
  }
  return out;
}
}  // namespace

void DataSurface::Build(const TrackerState& state, const std::vector<const EmbeddedSurface*>& surfaces) {
  const size_t n_objects = state.objects.size();
  offset_.assign(n_objects, 0);
  count_.assign(n_objects, 0);
  embedded_.assign(n_objects, 0);
  first_triangle_.assign(n_objects, 0);
  num_triangles_.assign(n_objects, 0);
  vertex_.clear();
  element_.clear();
  elements_.clear();
  origin_.clear();
  inverse_.clear();
  int rows = 0, triangles = 0;
  for (size_t i = 0; i < n_objects; ++i) {
    const EmbeddedSurface* s = i < surfaces.size() ? surfaces[i] : nullptr;
    offset_[i] = rows;
    count_[i] = s != nullptr ? static_cast<int>(s->rest.rows()) : state.objects[i].mesh.num_vertices();
    embedded_[i] = s != nullptr;
    rows += count_[i];
    first_triangle_[i] = triangles;
    num_triangles_[i] = s != nullptr ? static_cast<int>(s->triangles.rows()) : state.objects[i].mesh.num_surface_triangles();
    triangles += num_triangles_[i];
  }
  updated_at_.resize(0, 3);
  rest_.resize(rows, 3);
  pair_area_.assign(static_cast<size_t>(rows), 0.0);
  source_.assign(static_cast<size_t>(rows), 0);
  vertex_.resize(static_cast<size_t>(rows));
  element_.assign(static_cast<size_t>(rows), -1);
  view_.options = state.options;
  view_.num_vertices = rows;
  view_.vertex_object.assign(static_cast<size_t>(rows), 0);
  view_.surface.resize(triangles, 3);
  view_.surface_vertices.clear();
  int row = 0;
  for (size_t i = 0; i < n_objects; ++i) {
    const ObjectState& o = state.objects[i];
    const EmbeddedSurface* s = i < surfaces.size() ? surfaces[i] : nullptr;
    const int base = offset_[i];
    for (int v = 0; v < count_[i]; ++v) view_.vertex_object[static_cast<size_t>(base + v)] = static_cast<int>(i);
    if (s == nullptr) {
      rest_.middleRows(base, count_[i]) = o.mesh.rest;
      for (int v = 0; v < count_[i]; ++v) {
        source_[static_cast<size_t>(base + v)] = v;
        Stencil& st = vertex_[static_cast<size_t>(base + v)];
        st.n = 1;
        st.vertices = {{o.offset + v, 0, 0, 0}};
        st.weights = {{1.0, 0.0, 0.0, 0.0}};
      }
      const int nf = o.mesh.num_surface_triangles();
      view_.surface.middleRows(row, nf) = o.mesh.surface.array() + base;
      row += nf;
      for (int v : o.mesh.surface_vertices) view_.surface_vertices.push_back(base + v);
      for (int f = 0; f < nf; ++f) {
        const int a = o.mesh.surface(f, 0), b = o.mesh.surface(f, 1), c = o.mesh.surface(f, 2);
        const Eigen::Vector3d ab = o.mesh.rest.row(b) - o.mesh.rest.row(a), ac = o.mesh.rest.row(c) - o.mesh.rest.row(a);
        for (int v : {a, b, c}) pair_area_[static_cast<size_t>(base + v)] += ab.cross(ac).norm() / 6.0;
      }
      continue;
    }
    std::vector<int> order;
    const EmbeddedSurface ordered = SpatiallyOrdered(*s, &order);
    s = &ordered;
    for (int v = 0; v < count_[i]; ++v) source_[static_cast<size_t>(base + v)] = order[static_cast<size_t>(v)];
    rest_.middleRows(base, count_[i]) = s->rest;
    const int first_element = static_cast<int>(elements_.size());
    for (int e = 0; e < o.mesh.num_tets(); ++e) {
      std::array<int, 4> t;
      for (int k = 0; k < 4; ++k) t[static_cast<size_t>(k)] = o.mesh.tets(e, k) + o.offset;
      elements_.push_back(t);
      const Eigen::Vector3d a = o.mesh.rest.row(o.mesh.tets(e, 0));
      Eigen::Matrix3d D;
      for (int k = 0; k < 3; ++k) D.col(k) = o.mesh.rest.row(o.mesh.tets(e, k + 1)).transpose() - a;
      origin_.push_back(a);
      inverse_.push_back(D.inverse());
    }
    for (int v = 0; v < count_[i]; ++v) {
      const int e = s->embedding.element[static_cast<size_t>(v)];
      const Eigen::Vector4d& b = s->embedding.barycentric[static_cast<size_t>(v)];
      Stencil& st = vertex_[static_cast<size_t>(base + v)];
      st.n = 4;
      for (int k = 0; k < 4; ++k) {
        st.vertices[static_cast<size_t>(k)] = o.mesh.tets(e, k) + o.offset;
        st.weights[static_cast<size_t>(k)] = b[k];
      }
      element_[static_cast<size_t>(base + v)] = first_element + e;
    }
    const int nf = static_cast<int>(s->triangles.rows());
    view_.surface.middleRows(row, nf) = s->triangles.array() + base;
    row += nf;
    // The vertices that pair with the cloud (model->cloud): one per voxel of a third of the
    // mesh's mean surface edge, each standing for the area of the vertices in its voxel. The
    // mesh cannot deform at a finer scale than its elements, and the cloud->model pairs, on
    // every embedded triangle, keep the surface's detail; so the model->cloud pairs, the search
    // and its cost do not grow with the embedded surface's resolution.
    std::vector<double> area(static_cast<size_t>(count_[i]), 0.0);
    for (int f = 0; f < nf; ++f) {
      const int a = s->triangles(f, 0), b = s->triangles(f, 1), c = s->triangles(f, 2);
      const Eigen::Vector3d ab = s->rest.row(b) - s->rest.row(a), ac = s->rest.row(c) - s->rest.row(a);
      for (int v : {a, b, c}) area[static_cast<size_t>(v)] += ab.cross(ac).norm() / 6.0;
    }
    double mesh_edge = 0.0;
    for (int f = 0; f < o.mesh.num_surface_triangles(); ++f) {
      for (int k = 0; k < 3; ++k) {
        mesh_edge += (o.mesh.rest.row(o.mesh.surface(f, k)) - o.mesh.rest.row(o.mesh.surface(f, (k + 1) % 3))).norm();
      }
    }
    mesh_edge /= std::max(1, 3 * o.mesh.num_surface_triangles());
    const double voxel = mesh_edge / 3.0;
    std::map<std::array<long long, 3>, std::vector<int>> voxels;  // ordered: the same pick on every run
    for (int v = 0; v < count_[i]; ++v) {
      if (!(area[static_cast<size_t>(v)] > 0.0)) continue;  // on no triangle
      std::array<long long, 3> key;
      for (int k = 0; k < 3; ++k) key[static_cast<size_t>(k)] = static_cast<long long>(std::floor(s->rest(v, k) / voxel));
      voxels[key].push_back(v);
    }
    std::vector<int> picked;
    for (const auto& [key, members] : voxels) {
      Eigen::Vector3d centroid = Eigen::Vector3d::Zero();
      double total = 0.0;
      for (int v : members) {
        centroid += s->rest.row(v).transpose();
        total += area[static_cast<size_t>(v)];
      }
      centroid /= static_cast<double>(members.size());
      int best = members.front();
      for (int v : members) {
        if ((s->rest.row(v).transpose() - centroid).squaredNorm() <
            (s->rest.row(best).transpose() - centroid).squaredNorm()) {
          best = v;
        }
      }
      pair_area_[static_cast<size_t>(base + best)] = total;
      picked.push_back(best);
    }
    std::sort(picked.begin(), picked.end());
    for (int v : picked) view_.surface_vertices.push_back(base + v);
  }
  double length = 0.0;
  for (Eigen::Index f = 0; f < view_.surface.rows(); ++f) {
    for (int k = 0; k < 3; ++k) length += (rest_.row(view_.surface(f, k)) - rest_.row(view_.surface(f, (k + 1) % 3))).norm();
  }
  surface_edge_ = view_.surface.rows() > 0 ? length / (3.0 * static_cast<double>(view_.surface.rows())) : 0.0;
  // The view's length scale is the meshes' (the state's): the scale the surface deforms on,
  // which the occluders' depth image and the closest-point index's refit follow; a fine
  // surface would make them cost as much as it is fine.
  view_.mean_edge_length = state.mean_edge_length;
  view_.x.resize(rows, 3);
  Update(state.x);
}

const TrackerState& DataSurface::Update(const Vertices& x) {
  // The tracker asks for the data surface several times per outer iteration at the same x:
  // computed once (the whole scan: the cost grows with it).
  if (updated_at_.rows() == x.rows() && updated_at_.cols() == x.cols() && updated_at_ == x) return view_;
  const int n = static_cast<int>(vertex_.size());
  ParallelFor(0, n, 4096, [&](int64_t v) {  // each row on its own: the same on any thread count
    const Stencil& st = vertex_[static_cast<size_t>(v)];
    Eigen::RowVector3d p = st.weights[0] * x.row(st.vertices[0]);
    for (int k = 1; k < st.n; ++k) p += st.weights[static_cast<size_t>(k)] * x.row(st.vertices[static_cast<size_t>(k)]);
    view_.x.row(v) = p;
  });
  updated_at_ = x;
  return view_;
}

Vertices DataSurface::PairVerticesAt(const Vertices& x) const {
  const std::vector<int>& picked = view_.surface_vertices;
  Vertices out(static_cast<Eigen::Index>(picked.size()), 3);
  for (size_t i = 0; i < picked.size(); ++i) {  // Update's sum, term by term
    const Stencil& st = vertex_[static_cast<size_t>(picked[i])];
    Eigen::RowVector3d p = st.weights[0] * x.row(st.vertices[0]);
    for (int k = 1; k < st.n; ++k) p += st.weights[static_cast<size_t>(k)] * x.row(st.vertices[static_cast<size_t>(k)]);
    out.row(static_cast<Eigen::Index>(i)) = p;
  }
  return out;
}

DataSurface::Stencil DataSurface::Map(const DataPair& pair) const {
  if (pair.num_vertices == 1) return vertex_[static_cast<size_t>(pair.vertices[0])];
  Stencil out;
  if (vertex_[static_cast<size_t>(pair.vertices[0])].n == 1) {
    out.n = 3;
    for (int k = 0; k < 3; ++k) {
      out.vertices[static_cast<size_t>(k)] = vertex_[static_cast<size_t>(pair.vertices[k])].vertices[0];
      out.weights[static_cast<size_t>(k)] = pair.barycentric[k];
    }
    return out;
  }
  // The corners by weight, largest first: the element of the first whose coordinates of the
  // point are least outside it wins (a sliver's element extrapolates far).
  std::array<int, 3> corners = {{0, 1, 2}};
  std::stable_sort(corners.begin(), corners.end(),
                   [&](int a, int b) { return pair.barycentric[a] > pair.barycentric[b]; });
  Eigen::Vector3d p = Eigen::Vector3d::Zero();
  for (int k = 0; k < 3; ++k) p += pair.barycentric[k] * rest_.row(pair.vertices[k]).transpose();
  double best = -std::numeric_limits<double>::infinity();
  for (int corner : corners) {
    const int e = element_[static_cast<size_t>(pair.vertices[corner])];
    const Eigen::Vector3d l = inverse_[static_cast<size_t>(e)] * (p - origin_[static_cast<size_t>(e)]);
    const std::array<double, 4> w = {{1.0 - l.sum(), l.x(), l.y(), l.z()}};
    const double least = std::min(std::min(w[0], w[1]), std::min(w[2], w[3]));
    if (least > best) {
      best = least;
      out.vertices = elements_[static_cast<size_t>(e)];
      out.weights = w;
    }
  }
  out.n = 4;
  return out;
}

Triangles DataSurface::ObjectSurface(int object) const {
  const auto i = static_cast<size_t>(object);
  return view_.surface.middleRows(first_triangle_[i], num_triangles_[i]).array() - offset_[i];
}

int DataSurface::Dominant(int vertex) const {
  const Stencil& st = vertex_[static_cast<size_t>(vertex)];
  int best = 0;
  for (int k = 1; k < st.n; ++k) {
    if (st.weights[static_cast<size_t>(k)] > st.weights[static_cast<size_t>(best)]) best = k;
  }
  return st.vertices[static_cast<size_t>(best)];
}

}  // namespace femreg
