// The frame's cloud before any pair is made: transformed into the scene's frame, subsampled,
// its point spacing and reciprocity trim, the view it was seen from, its occluders and the
// depth it shows along the sensor's rays (free space); and the
// model's closest-point index, rebuilt when the surface moved (correspondences.h).
#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <limits>
#include <memory>
#include <unordered_map>

#include "femreg/point_cloud.h"  // CameraRotation
#include "registration/correspondences.h"
#include "registration/occluders.h"

namespace femreg {

std::function<bool(const Eigen::Vector3d&, const Eigen::Vector3d&)> FrameCloud::FacesFunction() const {
  if (view == View::kNone) return {};
  return [v = view, e = eye](const Eigen::Vector3d& p, const Eigen::Vector3d& n) { return Faces(v, e, p, n); };
}

std::string FrameCloud::Describe() const {
  char buf[128];
  switch (view) {
    case View::kNone:
      return "none";
    case View::kCamera:
      return "camera";
    case View::kViewpoint:
      std::snprintf(buf, sizeof(buf), "viewpoint (%.3g, %.3g, %.3g)", eye.x(), eye.y(), eye.z());
      return buf;
    case View::kDirection:
      std::snprintf(buf, sizeof(buf), "direction (%.2f, %.2f, %.2f)", eye.x(), eye.y(), eye.z());
      return buf;
  }
  return "none";
}

void TransformCloud(const PreprocessOptions& options, PointCloud* cloud) {
  if (options.scale == 1.0 && options.translation.isZero(0) && options.rotation.isZero(0)) return;
  const Eigen::Matrix3d R = RotationFromVector(options.rotation);
  const Eigen::Matrix3d A = options.scale * R;
  if (cloud->points.rows() > 0) {
    cloud->points = (cloud->points * A.transpose()).rowwise() + options.translation.transpose();
  }
  if (cloud->normals.rows() > 0) cloud->normals = cloud->normals * R.transpose();
  if (cloud->has_viewpoint) cloud->viewpoint = A * cloud->viewpoint + options.translation;
}

void SubsampleCloud(double voxel, PointCloud* cloud, Eigen::VectorXd* weights, double max_total) {
  const int n = cloud->size();
  weights->setOnes(n);
  if (!(voxel > 0) || n == 0) return;
  const auto bound = [&] {
    const double total = weights->sum();
    if (total > max_total) *weights *= max_total / total;
  };
  struct Key {
    int64_t i, j, k;
    int label;
    bool operator==(const Key& o) const { return i == o.i && j == o.j && k == o.k && label == o.label; }
  };
  struct KeyHash {
    size_t operator()(const Key& key) const {
      uint64_t h = static_cast<uint64_t>(key.i) * 73856093u;
      h ^= static_cast<uint64_t>(key.j) * 19349663u;
      h ^= static_cast<uint64_t>(key.k) * 83492791u;
      h ^= static_cast<uint64_t>(key.label) * 2654435761u;
      return static_cast<size_t>(h);
    }
  };
  const bool labels = cloud->has_labels(), normals = cloud->has_normals();
  auto cell = [voxel](double v) {  // clamped: far outliers share a cell rather than overflow
    return static_cast<int64_t>(std::floor(std::max(-1e15, std::min(1e15, v / voxel))));
  };
  std::unordered_map<Key, int, KeyHash> cells;
  cells.reserve(static_cast<size_t>(n));
  std::vector<int> first;   // voxel -> its first point
  std::vector<int> voxel_of(static_cast<size_t>(n));
  for (int p = 0; p < n; ++p) {
    const Key key{cell(cloud->points(p, 0)), cell(cloud->points(p, 1)), cell(cloud->points(p, 2)),
                  labels ? cloud->labels(p) : 0};
    const auto it = cells.emplace(key, static_cast<int>(first.size())).first;
    if (it->second == static_cast<int>(first.size())) first.push_back(p);
    voxel_of[static_cast<size_t>(p)] = it->second;
  }
  const int m = static_cast<int>(first.size());
  if (m == n) {
    bound();
    return;
  }
  // Each voxel keeps its point nearest to the voxel's centroid: a measured point, on the
  // surface (a centroid would sit inside the surface wherever it bends within the voxel).
  Vertices centroid = Vertices::Zero(m, 3);
  Eigen::VectorXd count = Eigen::VectorXd::Zero(m);
  for (int p = 0; p < n; ++p) {
    const int v = voxel_of[static_cast<size_t>(p)];
    centroid.row(v) += cloud->points.row(p);
    count(v) += 1.0;
  }
  centroid.array().colwise() /= count.array();
  std::vector<int> keep(first);
  std::vector<double> best(static_cast<size_t>(m), std::numeric_limits<double>::infinity());
  for (int p = 0; p < n; ++p) {
    const int v = voxel_of[static_cast<size_t>(p)];
    const double d2 = (cloud->points.row(p) - centroid.row(v)).squaredNorm();
    if (d2 < best[static_cast<size_t>(v)]) {
      best[static_cast<size_t>(v)] = d2;
      keep[static_cast<size_t>(v)] = p;
    }
  }
  Vertices points(m, 3);
  Vertices normals_kept = normals ? Vertices(m, 3) : Vertices();
  Eigen::VectorXi labels_kept = labels ? Eigen::VectorXi(m) : Eigen::VectorXi();
  for (int v = 0; v < m; ++v) {
    const int p = keep[static_cast<size_t>(v)];
    points.row(v) = cloud->points.row(p);
    if (normals) normals_kept.row(v) = cloud->normals.row(p);
    if (labels) labels_kept(v) = cloud->labels(p);
  }
  cloud->points = points;
  cloud->normals = normals_kept;
  cloud->labels = labels_kept;
  *weights = count;
  bound();
}

bool ModelIndex::SameSurface(const TrackerState& state) const {
  return rings_ != nullptr && x_rows_ == state.x.rows() && surface_data_ == state.surface.data() &&
         surface_rows_ == state.surface.rows();
}

const SurfaceRings& ModelIndex::Rings(const TrackerState& state) {
  if (!SameSurface(state)) {
    index_.reset();  // of another surface: Get builds it again
    rings_ = std::make_shared<SurfaceRings>(static_cast<int>(state.x.rows()), state.surface);
    x_rows_ = state.x.rows();
    surface_data_ = state.surface.data();
    surface_rows_ = state.surface.rows();
  }
  return *rings_;
}

const SurfaceIndex& ModelIndex::Get(const TrackerState& state, double tolerance) {
  Rings(state);
  // The index reads the positions where they are: moved elsewhere, it is made again.
  bool rebuild = index_ == nullptr || x_data_ != state.x.data();
  if (!rebuild) {
    const double tol2 = tolerance * tolerance;
    for (int v : state.surface_vertices) {
      if ((state.x.row(v) - built_at_.row(v)).squaredNorm() > tol2) {
        rebuild = true;
        break;
      }
    }
  }
  if (!rebuild) {
    // The queries' allowance is the move of every vertex on the surface: an embedded surface's
    // surface_vertices are a subsample of them.
    double moved2 = 0.0;
    for (int v = 0; v < rings_->num_vertices(); ++v) {
      if (rings_->has(v)) moved2 = std::max(moved2, (state.x.row(v) - built_at_.row(v)).squaredNorm());
    }
    index_->SetMoved(std::sqrt(moved2));
  }
  if (rebuild) {
    index_ = std::make_unique<SurfaceIndex>(state.x, state.surface, rings_);
    x_data_ = state.x.data();
    built_at_ = state.x;
    ++builds_;
  }
  return *index_;
}

void PrepareFrameCloud(const TrackerState& state, const SurfaceIndex& surface, FrameCloud* fc) {
  const RegistrationOptions& options = state.options;
  const PointCloud& cloud = fc->cloud;
  // The tracker has built it already (to count the usable points): not twice per frame.
  if (fc->index == nullptr || fc->index->size() != cloud.size()) {
    fc->index = std::make_unique<PointIndex>(cloud.points);
  }
  const int n = cloud.size();
  // The spacing: the median distance to the nearest neighbour, over 500-999 evenly spread
  // points (all of them below 1000; the median's relative standard error ~1.25 x the spread
  // of the distances over sqrt(500)): precise enough, at a fraction of the cost of more points
  // (docs/notes/2026-11-28-figures-from-code-comments.md).
  const int stride = std::max(1, n / 500);
  std::vector<double> nearest;
  for (int i = 0; i < n; i += stride) {
    int idx[2];
    double d2[2];
    if (fc->index->KNearest(cloud.points.row(i), 2, idx, d2) == 2) nearest.push_back(std::sqrt(d2[1]));
  }
  fc->spacing = 0.0;
  if (!nearest.empty()) {
    std::nth_element(nearest.begin(), nearest.begin() + nearest.size() / 2, nearest.end());
    fc->spacing = nearest[nearest.size() / 2];
  }
  // The trim never goes below the robust loss's scale: the distance the user calls noise.
  // With fracture live, no trim: an opening crack shows exactly as model vertices with no cloud
  // point near, and their pull is what separates the pieces (beam_break: the break is found
  // 14 frames late with the trim, on time without).
  fc->trim = options.data.reciprocity > 0 && !FractureLive(state)
                 ? std::max(options.data.reciprocity * fc->spacing, options.data.loss_scale)
                 : std::numeric_limits<double>::infinity();

  UpdateOccluders(state, surface, fc);

  fc->view = FrameCloud::View::kNone;
  if (options.camera.enabled && (options.data.visibility || options.data.auto_visibility)) {
    fc->view = FrameCloud::View::kCamera;
    fc->eye = options.camera.position;
    return;
  }
  if (!options.data.auto_visibility || state.x.rows() == 0) return;
  if (cloud.has_viewpoint) {
    const Eigen::Vector3d lo = state.x.colwise().minCoeff().transpose();
    const Eigen::Vector3d hi = state.x.colwise().maxCoeff().transpose();
    const bool inside = (cloud.viewpoint.array() >= lo.array()).all() &&
                        (cloud.viewpoint.array() <= hi.array()).all();
    if (!inside) {
      fc->view = FrameCloud::View::kViewpoint;
      fc->eye = cloud.viewpoint;
      return;
    }
  }
  // The side of the model the cloud lies on: the mean outward normal of the surface
  // triangles closest to the cloud's points (those within the trim). Near zero when the
  // cloud surrounds the model: then no direction is assumed.
  Eigen::Vector3d sum = Eigen::Vector3d::Zero();
  int count = 0;
  const double near2 = std::isfinite(fc->trim) ? fc->trim * fc->trim : options.data.max_distance *
                                                                           options.data.max_distance;
  for (int i = 0; i < n; i += stride) {
    const SurfaceIndex::Hit hit = surface.Closest(cloud.points.row(i));
    if (hit.triangle < 0 || (near2 > 0 && hit.squared_distance > near2)) continue;
    const Eigen::Vector3d a = state.x.row(state.surface(hit.triangle, 0)),
                          b = state.x.row(state.surface(hit.triangle, 1)),
                          c = state.x.row(state.surface(hit.triangle, 2));
    const Eigen::Vector3d fn = (b - a).cross(c - a);
    if (fn.norm() > 0) {
      sum += fn.normalized();
      ++count;
    }
  }
  constexpr double kMinMeanNormal = 0.3;  // |mean of unit normals|: 1 = a flat patch, 0 = all round
  if (count > 0 && sum.norm() / count >= kMinMeanNormal) {
    fc->view = FrameCloud::View::kDirection;
    fc->eye = sum.normalized();
  }
}

void UpdateOccluders(const TrackerState& state, const SurfaceIndex& surface, FrameCloud* fc) {
  const RegistrationOptions& options = state.options;
  fc->occluder.clear();
  fc->occluders = OccluderCounts();
  // Not with fracture live: a piece that comes apart is a displacement no strain bounds.
  if (options.camera.enabled && options.data.occluders && !FractureLive(state)) {
    fc->occluders = MarkOccluders(state, surface, fc->cloud.points, *fc->index, fc->spacing, &fc->occluder,
                                  fc->seeds, FrameCloud::kSeedRings);
    if (fc->occluders.occluders == 0) fc->occluder.clear();
  }
  BuildOccluderDepth(state, fc);
}

void BuildOccluderDepth(const TrackerState& state, FrameCloud* fc) {
  fc->occluder_depth.Clear();
  const CameraOptions& camera = state.options.camera;
  if (!camera.enabled || fc->occluder.empty()) return;
  std::vector<int> rows;
  for (size_t i = 0; i < fc->occluder.size(); ++i) {
    if (fc->occluder[i] == 1) rows.push_back(static_cast<int>(i));
  }
  if (rows.empty()) return;
  Vertices points(static_cast<Eigen::Index>(rows.size()), 3);
  for (size_t j = 0; j < rows.size(); ++j) points.row(static_cast<Eigen::Index>(j)) = fc->cloud.points.row(rows[j]);
  const Eigen::Vector3d axis = CameraRotation(camera).row(2).transpose();
  fc->occluder_depth.Build(points, true, camera.position, axis, fc->spacing);
}

void BuildObservedDepth(const TrackerState& state, FrameCloud* fc) {
  const RegistrationOptions& options = state.options;
  fc->observed.Clear();
  if (!options.free_space.enabled || fc->cloud.size() == 0) return;
  const Vertices& points = fc->cloud.points;
  // The removed table widens the image; the pitch and the view's axis stay the data's.
  const Vertices* table = fc->plane_points.rows() > 0 ? &fc->plane_points : nullptr;
  if (options.camera.enabled) {
    const Eigen::Vector3d axis = CameraRotation(options.camera).row(2).transpose();
    fc->observed.Build(points, true, options.camera.position, axis, fc->spacing, table);
  } else if (fc->view == FrameCloud::View::kViewpoint) {
    const Eigen::Vector3d centroid = points.colwise().mean().transpose();
    const Eigen::Vector3d axis = centroid - fc->eye;
    if (axis.norm() > 0) fc->observed.Build(points, true, fc->eye, axis.normalized(), fc->spacing, table);
  } else if (fc->view == FrameCloud::View::kDirection) {
    fc->observed.Build(points, false, fc->eye, -fc->eye, fc->spacing, table);
  }
}

}  // namespace femreg
