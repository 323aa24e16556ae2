#include "registration/prealign.h"

#include <Eigen/SVD>
#include <algorithm>
#include <cmath>
#include <limits>
#include <utility>

#include "femreg/mesh.h"
#include "geometry/nearest.h"

namespace femreg {

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

namespace {

// The trimmed mean distance (the nearest 80 %) of every stride-th cloud point to the surface
// `tris` at pos, and optionally the rigid transform that best moves those closest surface
// points onto their cloud points.
double TrimmedFit(const PointCloud& cloud, int stride, const Vertices& pos, const Triangles& tris,
                  Eigen::Matrix3d* R, Eigen::Vector3d* t) {
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
}

// RigidPrealign for an object with an embedded surface: fitted by that surface (positions f,
// triangles tris), the same rigid motion applied to its mesh.
void EmbeddedPrealign(const PointCloud& cloud, int stride, int object, const Eigen::MatrixXd& normals,
                      const DataSurface& surface, TrackerState* state) {
  const CameraOptions& camera = state->options.camera;
  const ObjectState& o = state->objects[static_cast<size_t>(object)];
  const int base = surface.offset(object), ns = surface.count(object), nv = o.mesh.num_vertices();
  Vertices f = surface.ObjectPositions(object);
  Vertices y = state->x.middleRows(o.offset, nv);
  const Triangles tris = surface.ObjectSurface(object);
  std::vector<char> on(static_cast<size_t>(ns), 0);
  for (Eigen::Index t = 0; t < tris.rows(); ++t) {
    for (int k = 0; k < 3; ++k) on[static_cast<size_t>(tris(t, k))] = 1;
  }
  Eigen::Vector3d cm = Eigen::Vector3d::Zero();
  int facing = 0;
  for (int v = 0; v < ns; ++v) {
    if (!on[static_cast<size_t>(v)]) continue;
    if (camera.enabled) {
      const Eigen::Vector3d n = normals.row(base + v);
      if (n.dot(camera.position - Eigen::Vector3d(f.row(v))) <= 0.0) continue;
    }
    cm += f.row(v).transpose();
    ++facing;
  }
  if (facing < 3 || cloud.size() < 3) return;
  cm /= static_cast<double>(facing);
  auto trimmed_mean = [&](const Vertices& pos, Eigen::Matrix3d* R, Eigen::Vector3d* t) {
    return TrimmedFit(cloud, stride, pos, tris, R, t);
  };
  const double before = trimmed_mean(f, nullptr, nullptr);
  const Eigen::RowVector3d shift = (cloud.points.colwise().mean().transpose() - cm).transpose();
  f.rowwise() += shift;
  y.rowwise() += shift;
  for (int it = 0; it < state->options.solver.rigid_iterations; ++it) {
    Eigen::Matrix3d R = Eigen::Matrix3d::Identity();
    Eigen::Vector3d t = Eigen::Vector3d::Zero();
    trimmed_mean(f, &R, &t);
    f = ((f * R.transpose()).rowwise() + t.transpose()).eval();
    y = ((y * R.transpose()).rowwise() + t.transpose()).eval();
    if ((R - Eigen::Matrix3d::Identity()).norm() < 1e-7 && t.norm() < 1e-7) break;
  }
  if (trimmed_mean(f, nullptr, nullptr) < before) state->x.middleRows(o.offset, nv) = y;
}

}  // namespace

void RigidPrealign(const PointCloud& cloud, TrackerState* state, DataSurface* surface) {
  // Cloud->surface pairs: every seen point has a partner, hidden parts do not bias.
  const CameraOptions& camera = state->options.camera;
  Vertices& x = state->x;
  const Eigen::MatrixXd normals = state->VertexNormals();
  const int stride = std::max(1, cloud.size() / 2000);
  if (surface != nullptr) surface->Update(x);
  const Eigen::MatrixXd surface_normals = surface != nullptr ? surface->view().VertexNormals() : Eigen::MatrixXd();
  for (size_t i = 0; i < state->objects.size(); ++i) {
    const ObjectState& o = state->objects[i];
    if (surface != nullptr && surface->embedded(static_cast<int>(i))) {
      EmbeddedPrealign(cloud, stride, static_cast<int>(i), surface_normals, *surface, state);
      continue;
    }
    std::vector<int> facing;
    for (int v : o.mesh.surface_vertices) {
      const int g = v + o.offset;
      if (camera.enabled) {
        const Eigen::Vector3d n = normals.row(g);
        if (n.dot(camera.position - Eigen::Vector3d(x.row(g))) <= 0.0) continue;
      }
      facing.push_back(g);
    }
    if (facing.size() < 3 || cloud.size() < 3) continue;
    const int nv = o.mesh.num_vertices();
    Vertices y = x.middleRows(o.offset, nv);
    const Triangles& tris = o.mesh.surface;
    auto trimmed_mean = [&](const Vertices& pos, Eigen::Matrix3d* R, Eigen::Vector3d* t) {
      return TrimmedFit(cloud, stride, pos, tris, R, t);
    };
    const double before = trimmed_mean(y, nullptr, nullptr);
    Eigen::Vector3d cm = Eigen::Vector3d::Zero();
    for (int g : facing) cm += x.row(g).transpose();
    cm /= static_cast<double>(facing.size());
    const Eigen::RowVector3d shift = (cloud.points.colwise().mean().transpose() - cm).transpose();
    y.rowwise() += shift;
    for (int it = 0; it < state->options.solver.rigid_iterations; ++it) {
      Eigen::Matrix3d R = Eigen::Matrix3d::Identity();
      Eigen::Vector3d t = Eigen::Vector3d::Zero();
      trimmed_mean(y, &R, &t);
      for (int v = 0; v < nv; ++v) y.row(v) = (R * y.row(v).transpose() + t).transpose();
      if ((R - Eigen::Matrix3d::Identity()).norm() < 1e-7 && t.norm() < 1e-7) break;
    }
    if (trimmed_mean(y, nullptr, nullptr) < before) x.middleRows(o.offset, nv) = y;
  }
}

void PiecePrealign(const PointCloud& cloud, TrackerState* state) {
  if (!state->fracture || cloud.size() < 3) return;
  const double reach = state->options.data.max_distance > 0 ? state->options.data.max_distance
                                                            : std::numeric_limits<double>::infinity();
  const int stride = std::max(1, cloud.size() / 1000);
  for (size_t i = 0; i < state->objects.size(); ++i) {
    const ObjectState& o = state->objects[i];
    if (!state->fracture->options[i].piece_prealign) continue;
    std::vector<int> piece;
    const int pieces = ConnectedPieces(o.mesh, &piece);
    if (pieces < 2) continue;
    const int nv = o.mesh.num_vertices();
    std::vector<char> held(static_cast<size_t>(pieces), 0);
    for (const auto& kv : state->anchors) {
      if (!kv.second.hard || kv.second.object != static_cast<int>(i)) continue;
      for (int g : kv.second.vertices) {
        const int v = g - o.offset;
        if (v >= 0 && v < nv) held[static_cast<size_t>(piece[v])] = 1;
      }
    }
    Vertices y = state->x.middleRows(o.offset, nv);
    const Triangles& tris = o.mesh.surface;
    // Per piece: its pairs (surface point, cloud point) at positions pos, sorted by distance.
    auto associate = [&](const Vertices& pos, std::vector<std::vector<std::pair<double, int>>>* dist,
                         std::vector<Eigen::Vector3d>* model_points) {
      SurfaceIndex index(pos, tris);
      dist->assign(static_cast<size_t>(pieces), {});
      model_points->assign(static_cast<size_t>(cloud.size()), Eigen::Vector3d::Zero());
      for (int c = 0; c < cloud.size(); c += stride) {
        const SurfaceIndex::Hit hit = index.Closest(cloud.points.row(c));
        if (hit.triangle < 0 || hit.squared_distance > reach * reach) continue;
        (*model_points)[static_cast<size_t>(c)] = hit.point;
        (*dist)[static_cast<size_t>(piece[tris(hit.triangle, 0)])].emplace_back(hit.squared_distance, c);
      }
      for (auto& d : *dist) std::sort(d.begin(), d.end());
    };
    auto trimmed = [](const std::vector<std::pair<double, int>>& d) {
      return d.size() * 4 / 5;
    };
    std::vector<std::vector<std::pair<double, int>>> dist;
    std::vector<Eigen::Vector3d> model_points;
    associate(y, &dist, &model_points);
    // Trimmed mean distance per piece at the start, to keep only moves that help.
    std::vector<double> before(static_cast<size_t>(pieces), std::numeric_limits<double>::infinity());
    for (int p = 0; p < pieces; ++p) {
      const auto& d = dist[static_cast<size_t>(p)];
      const size_t keep = trimmed(d);
      if (keep < 3) continue;
      double sum = 0.0;
      for (size_t j = 0; j < keep; ++j) sum += std::sqrt(d[j].first);
      before[static_cast<size_t>(p)] = sum / static_cast<double>(keep);
    }
    const Vertices start = y;
    // A piece is near its pose (it was tracked in the last frame): a few iterations do.
    constexpr int kPieceIterations = 8;
    for (int it = 0; it < std::min(kPieceIterations, state->options.solver.rigid_iterations); ++it) {
      bool moved = false;
      for (int p = 0; p < pieces; ++p) {
        const auto& d = dist[static_cast<size_t>(p)];
        const size_t keep = trimmed(d);
        if (held[static_cast<size_t>(p)] || keep < 3) continue;
        std::vector<Eigen::Vector3d> a, b;
        for (size_t j = 0; j < keep; ++j) {
          a.push_back(model_points[static_cast<size_t>(d[j].second)]);
          b.push_back(cloud.points.row(d[j].second).transpose());
        }
        Eigen::Matrix3d R;
        Eigen::Vector3d t;
        Kabsch(a, b, &R, &t);
        if ((R - Eigen::Matrix3d::Identity()).norm() < 1e-7 && t.norm() < 1e-7) continue;
        moved = true;
        for (int v = 0; v < nv; ++v) {
          if (piece[v] == p) y.row(v) = (R * y.row(v).transpose() + t).transpose();
        }
      }
      if (!moved) break;
      associate(y, &dist, &model_points);
    }
    // Each piece keeps its move only if its points came closer.
    for (int p = 0; p < pieces; ++p) {
      const auto& d = dist[static_cast<size_t>(p)];
      const size_t keep = trimmed(d);
      double after = std::numeric_limits<double>::infinity();
      if (keep >= 3) {
        double sum = 0.0;
        for (size_t j = 0; j < keep; ++j) sum += std::sqrt(d[j].first);
        after = sum / static_cast<double>(keep);
      }
      const bool better = after < before[static_cast<size_t>(p)];
      for (int v = 0; v < nv; ++v) {
        if (piece[v] == p && !better) y.row(v) = start.row(v);
      }
    }
    state->x.middleRows(o.offset, nv) = y;
  }
}

}  // namespace femreg
