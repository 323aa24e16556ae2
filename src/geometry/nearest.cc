#include "geometry/nearest.h"

#include <nanoflann.hpp>

#include <algorithm>
#include <cmath>
#include <limits>
#include <utility>

#include "femreg/geometry.h"
#include "parallel/pool.h"
#include "parallel/threads.h"

namespace femreg {

namespace {
// The relative slack of the triangles' bounding spheres and of the best hit's reach: far above
// the round-off of a distance, far below any gap between two candidates that matters.
constexpr double kSphereMargin = 1e-9;

struct VerticesAdaptor {
  const Vertices* points;
  size_t kdtree_get_point_count() const { return static_cast<size_t>(points->rows()); }
  double kdtree_get_pt(size_t i, size_t d) const {
    return (*points)(static_cast<Eigen::Index>(i), static_cast<Eigen::Index>(d));
  }
  template <class BoundingBox>
  bool kdtree_get_bbox(BoundingBox&) const {
    return false;
  }
};
using KdTree = nanoflann::KDTreeSingleIndexAdaptor<
    nanoflann::L2_Simple_Adaptor<double, VerticesAdaptor>, VerticesAdaptor, 3, uint32_t>;
}  // namespace

struct PointIndex::Tree {
  VerticesAdaptor adaptor;
  KdTree tree;
  explicit Tree(const Vertices* points)
      : adaptor{points}, tree(3, adaptor, nanoflann::KDTreeSingleIndexAdaptorParams(16)) {}
};

PointIndex::PointIndex(const Vertices& points) : points_(points) {
  if (points_.rows() > 0) tree_ = std::make_unique<Tree>(&points_);
}

PointIndex::~PointIndex() = default;

int PointIndex::Nearest(const Eigen::Vector3d& query, double* squared_distance) const {
  if (!tree_) return -1;
  uint32_t index = 0;
  double d2 = 0.0;
  nanoflann::KNNResultSet<double, uint32_t> result(1);
  result.init(&index, &d2);
  tree_->tree.findNeighbors(result, query.data(), nanoflann::SearchParams());
  if (squared_distance) *squared_distance = d2;
  return static_cast<int>(index);
}

bool PointIndex::AnyWithin(const Eigen::Vector3d& query, double max_distance) const {
  if (!tree_ || !(max_distance >= 0.0)) return false;
  uint32_t index = 0;
  double d2 = 0.0;
  nanoflann::KNNResultSet<double, uint32_t> result(1);
  result.init(&index, &d2);
  // The result set's worst distance bounds the search: only points nearer are visited. The
  // bound is a little looser than max_distance^2 and the nearest point found is then tested
  // as sqrt(d2) <= max_distance, which is what the nearest distance itself would say.
  const double inf = std::numeric_limits<double>::infinity();
  const double loose = std::nextafter(max_distance, inf);
  d2 = std::nextafter(loose * loose, inf);
  tree_->tree.findNeighbors(result, query.data(), nanoflann::SearchParams());
  return result.size() > 0 && std::sqrt(d2) <= max_distance;
}

int PointIndex::KNearest(const Eigen::Vector3d& query, int k, int* indices,
                         double* squared_distances) const {
  if (!tree_ || k <= 0) return 0;
  // A small k (the surface queries' 4 to 16) on the stack: this runs per cloud point per
  // outer iteration: no allocation per call.
  constexpr int kOnStack = 32;
  uint32_t on_stack[kOnStack];
  std::vector<uint32_t> on_heap(k > kOnStack ? k : 0);
  uint32_t* idx = k > kOnStack ? on_heap.data() : on_stack;
  nanoflann::KNNResultSet<double, uint32_t> result(k);
  result.init(idx, squared_distances);
  tree_->tree.findNeighbors(result, query.data(), nanoflann::SearchParams());
  const int n = static_cast<int>(result.size());
  for (int i = 0; i < n; ++i) indices[i] = static_cast<int>(idx[i]);
  return n;
}

SurfaceRings::SurfaceRings(int num_vertices, const Triangles& triangles, const std::vector<char>* keep) {
  auto kept = [&](int f) { return keep == nullptr || (*keep)[static_cast<size_t>(f)] != 0; };
  const int nv = num_vertices;
  offsets.assign(static_cast<size_t>(nv) + 1, 0);
  for (int f = 0; f < triangles.rows(); ++f) {
    if (!kept(f)) continue;
    for (int k = 0; k < 3; ++k) ++offsets[static_cast<size_t>(triangles(f, k)) + 1];
  }
  for (int v = 0; v < nv; ++v) offsets[static_cast<size_t>(v) + 1] += offsets[static_cast<size_t>(v)];
  list.assign(static_cast<size_t>(offsets[static_cast<size_t>(nv)]), 0);
  std::vector<int> fill(offsets.begin(), offsets.end() - 1);
  for (int f = 0; f < triangles.rows(); ++f) {
    if (!kept(f)) continue;
    for (int k = 0; k < 3; ++k) list[static_cast<size_t>(fill[static_cast<size_t>(triangles(f, k))]++)] = f;
  }
}

Eigen::MatrixXd VertexNormalsAt(const Vertices& x, const Triangles& triangles, const SurfaceRings& rings,
                                const std::vector<int>& vertices) {
  const int n = static_cast<int>(vertices.size());
  Eigen::MatrixXd normals = Eigen::MatrixXd::Zero(n, 3);
  // Each row on its own: the same on any thread count (an embedded scan's subsample: thousands).
  ParallelFor(0, n, 2048, [&](int64_t i) {
    const int v = vertices[static_cast<size_t>(i)];
    if (v < 0 || v >= rings.num_vertices()) return;
    // As TrackerState::VertexNormals: from zero, each face's (b - a) x (c - a) in face order
    // (a face that lists v twice counts twice), then normalized.
    Eigen::RowVector3d sum = Eigen::RowVector3d::Zero();
    for (int j = rings.offsets[static_cast<size_t>(v)]; j < rings.offsets[static_cast<size_t>(v) + 1]; ++j) {
      const int f = rings.list[static_cast<size_t>(j)];
      const Eigen::Vector3d a = x.row(triangles(f, 0)), b = x.row(triangles(f, 1)), c = x.row(triangles(f, 2));
      sum += (b - a).cross(c - a).transpose();
    }
    const double len = sum.norm();
    if (len > 0) sum /= len;
    normals.row(i) = sum;
  });
  return normals;
}

SurfaceIndex::SurfaceIndex(const Vertices& positions, const Triangles& triangles,
                           int candidate_vertices)
    : positions_(positions), triangles_(triangles), candidate_vertices_(candidate_vertices),
      rings_(std::make_shared<SurfaceRings>(static_cast<int>(positions.rows()), triangles)) {
  Build();
}

SurfaceIndex::SurfaceIndex(const Vertices& positions, const Triangles& triangles,
                           const std::vector<char>& keep, int candidate_vertices)
    : positions_(positions), triangles_(triangles), candidate_vertices_(candidate_vertices), keep_(keep) {
  keep_.resize(static_cast<size_t>(triangles.rows()), 0);
  rings_ = std::make_shared<SurfaceRings>(static_cast<int>(positions.rows()), triangles, &keep_);
  Build();
}

SurfaceIndex::SurfaceIndex(const Vertices& positions, const Triangles& triangles,
                           std::shared_ptr<const SurfaceRings> rings, int candidate_vertices)
    : positions_(positions), triangles_(triangles), candidate_vertices_(candidate_vertices),
      rings_(std::move(rings)) {
  Build();
}

void SurfaceIndex::Build() {
  const int nv = rings_->num_vertices();
  for (int v = 0; v < nv; ++v) {
    if (rings_->has(v)) surface_vertex_ids_.push_back(v);
  }
  Vertices pts(static_cast<Eigen::Index>(surface_vertex_ids_.size()), 3);
  for (size_t i = 0; i < surface_vertex_ids_.size(); ++i) {
    pts.row(static_cast<Eigen::Index>(i)) = positions_.row(surface_vertex_ids_[i]);
  }
  tree_points_ = std::move(pts);
}

const PointIndex& SurfaceIndex::Tree() const {
  std::call_once(tree_once_, [this] {
    index_ = std::make_unique<PointIndex>(tree_points_);
    tree_points_.resize(0, 3);
  });
  return *index_;
}

// The triangles already tested for one query (neighbouring vertices share most of theirs:
// on the demo 4 vertices list ~24 triangles, ~13 of them distinct).
struct SurfaceIndex::Tested {
  static constexpr int kMax = 128;
  int list[kMax];
  int count = 0;
  // A bound on the distance of the best hit so far, a little above it: a triangle whose
  // bounding sphere lies beyond it cannot be closer.
  double reach = std::numeric_limits<double>::infinity();
  // True the first time f is offered (past kMax, every time: tested again, never skipped).
  bool Add(int f) {
    if (std::find(list, list + count, f) != list + count) return false;
    if (count < kMax) list[count++] = f;
    return true;
  }
};

double SurfaceIndex::LargestSphere() const {
  Spheres();  // makes largest_sphere_ once, on any thread
  return largest_sphere_;
}

const std::vector<Eigen::Vector4d>& SurfaceIndex::Spheres() const {
  std::call_once(spheres_once_, [this] {
    spheres_moved_ = moved_;
    spheres_.assign(static_cast<size_t>(triangles_.rows()), Eigen::Vector4d::Zero());
    for (int f = 0; f < triangles_.rows(); ++f) {
      if (!keep_.empty() && !keep_[static_cast<size_t>(f)]) continue;
      const Eigen::Vector3d a = positions_.row(triangles_(f, 0)), b = positions_.row(triangles_(f, 1)),
                            c = positions_.row(triangles_(f, 2));
      const Eigen::Vector3d centre = (a + b + c) / 3.0;
      const double r = std::sqrt(std::max({(a - centre).squaredNorm(), (b - centre).squaredNorm(),
                                           (c - centre).squaredNorm()}));
      // Rounded up, so that the sphere holds the triangle as the closest-point test sees it.
      spheres_[static_cast<size_t>(f)] << centre, r * (1.0 + kSphereMargin) + kSphereMargin * centre.norm();
      largest_sphere_ = std::max(largest_sphere_, spheres_[static_cast<size_t>(f)][3]);
    }
  });
  return spheres_;
}

void SurfaceIndex::TestAround(int v, const Eigen::Vector3d& query, const std::vector<Eigen::Vector4d>& spheres,
                              Tested* tested, Hit* best) const {
  const std::vector<int>& offsets = rings_->offsets;
  const double slack = SphereSlack();
  for (int j = offsets[static_cast<size_t>(v)]; j < offsets[static_cast<size_t>(v) + 1]; ++j) {
    const int f = rings_->list[static_cast<size_t>(j)];
    if (!tested->Add(f)) continue;
    // Beyond the best hit's reach, which only shrinks: skipped for good, with the same hit.
    const Eigen::Vector4d& sphere = spheres[static_cast<size_t>(f)];
    const double far = tested->reach + sphere[3] + slack;
    if ((query - sphere.head<3>()).squaredNorm() > far * far) continue;
    Eigen::Vector3d bary;
    const Eigen::Vector3d point =
        TriangleClosestPoint(query, positions_.row(triangles_(f, 0)), positions_.row(triangles_(f, 1)),
                             positions_.row(triangles_(f, 2)), &bary);
    const double dist2 = (point - query).squaredNorm();
    if (dist2 < best->squared_distance) {
      best->triangle = f;
      best->barycentric = bary;
      best->point = point;
      best->squared_distance = dist2;
      tested->reach = std::min(tested->reach, std::sqrt(dist2) * (1.0 + kSphereMargin));
    }
  }
}

bool SurfaceIndex::TouchesRing(int v, int triangle) const {
  if (v < 0 || v >= rings_->num_vertices() || triangle < 0 || triangle >= triangles_.rows()) {
    return false;
  }
  for (int j = rings_->offsets[static_cast<size_t>(v)]; j < rings_->offsets[static_cast<size_t>(v) + 1]; ++j) {
    const int f = rings_->list[static_cast<size_t>(j)];
    for (int a = 0; a < 3; ++a) {
      for (int b = 0; b < 3; ++b) {
        if (triangles_(f, a) == triangles_(triangle, b)) return true;
      }
    }
  }
  return false;
}

SurfaceIndex::Hit SurfaceIndex::ClosestFrom(const Eigen::Vector3d& query, int start, int max_rings,
                                            bool* settled) const {
  if (settled != nullptr) *settled = true;
  if (start < 0 || start >= triangles_.rows() || (!keep_.empty() && !keep_[static_cast<size_t>(start)])) {
    return Closest(query);
  }
  Hit best;
  best.squared_distance = std::numeric_limits<double>::infinity();
  Tested tested;
  const std::vector<Eigen::Vector4d>& spheres = Spheres();
  // The start is among the triangles of its first ring: its distance bounds the best hit's
  // from the outset, so that the ring's farther triangles are skipped. It is measured again
  // in its turn, so that ties are resolved in the rings' order as before (the same hit).
  {
    Eigen::Vector3d bary;
    const Eigen::Vector3d point =
        TriangleClosestPoint(query, positions_.row(triangles_(start, 0)), positions_.row(triangles_(start, 1)),
                             positions_.row(triangles_(start, 2)), &bary);
    tested.reach = std::sqrt((point - query).squaredNorm()) * (1.0 + kSphereMargin);
  }
  int center = start;
  for (int ring = 0; ring < max_rings; ++ring) {
    for (int k = 0; k < 3; ++k) TestAround(triangles_(center, k), query, spheres, &tested, &best);
    if (best.triangle == center) return best;  // no triangle around it is closer
    center = best.triangle;
  }
  if (settled != nullptr) *settled = false;
  return best;
}

SurfaceIndex::Candidates SurfaceIndex::Nearby(const Eigen::Vector3d& query) const {
  Candidates near;
  near.count = Tree().KNearest(query, std::min(candidate_vertices_, 16), near.ids, near.squared_distances);
  return near;
}

void SurfaceIndex::DistanceBounds(const Eigen::Vector3d& query, const Candidates& near, double* lower,
                                  double* upper) const {
  *lower = 0.0;
  *upper = std::numeric_limits<double>::infinity();
  if (near.count < 1) return;
  for (int i = 0; i < near.count; ++i) {
    *upper = std::min(*upper, (query - positions_.row(surface_vertex_ids_[static_cast<size_t>(near.ids[i])]).transpose()).norm());
  }
  *lower = std::max(0.0, std::sqrt(near.squared_distances[0]) - moved_ - (LargestSphere() + SphereSlack()));
}

SurfaceIndex::Hit SurfaceIndex::Closest(const Eigen::Vector3d& query, const Candidates& near) const {
  Hit best;
  best.squared_distance = std::numeric_limits<double>::infinity();
  // The candidates' triangles, each once, in the order first met.
  Tested tested;
  const std::vector<Eigen::Vector4d>& spheres = Spheres();
  for (int i = 0; i < near.count; ++i) TestAround(surface_vertex_ids_[near.ids[i]], query, spheres, &tested, &best);
  return best;
}

}  // namespace femreg
