#include "registration/occluders.h"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <limits>

#include "femreg/point_cloud.h"  // CameraRotation
#include "geometry/zbuffer.h"
#include "parallel/pool.h"
#include "parallel/threads.h"
#include "registration/confidence.h"  // StretchDeviation

namespace femreg {

namespace {

constexpr double kNear = 1e-4;          // m; the z-buffer's near plane
constexpr int kMaxImageSide = 1024;     // pixels
constexpr int kNeighbours = 12;         // the occluder grows through this many nearest points
constexpr double kReach = 3.0;          // ... within this many point spacings
constexpr double kWholeView = 0.5;      // seeds beyond this share of the points on the model
constexpr double kBoundMargin = 1e-9;   // relative: distance bounds against the closest point's round-off

// Whether `query`, whose distance to a surface is within [lower, upper]
// (SurfaceIndex::DistanceBounds), lies within `radius` of it for certain: 1 within, 0 beyond,
// -1 undecided (the closest point to search). The margin allows for the search's round-off
// against the radius and the coordinates.
int Within(double lower, double upper, double radius, const Eigen::Vector3d& query) {
  const double slack = kBoundMargin * (radius + query.norm());
  if (upper <= radius - slack) return 1;
  if (lower > radius + slack) return 0;
  return -1;
}

// Grows the marked points in `queue` (already set to `value` in *marks) through the cloud,
// breadth first in the points' order (the same set for any thread count): each point's
// kNeighbours nearest within three spacings that are unmarked and off(k).
template <typename Off>
void Grow(const Vertices& points, const PointIndex& cloud_index, double spacing, char value, Off off,
          std::vector<int>* queue, std::vector<char>* marks) {
  const double radius2 = kReach * kReach * spacing * spacing;
  int indices[kNeighbours];
  double squared[kNeighbours];
  for (size_t head = 0; head < queue->size(); ++head) {
    const int found = cloud_index.KNearest(points.row((*queue)[head]), kNeighbours, indices, squared);
    for (int j = 0; j < found; ++j) {
      const int k = indices[j];
      if (squared[j] > radius2 || (*marks)[static_cast<size_t>(k)] || !off(k)) continue;
      (*marks)[static_cast<size_t>(k)] = value;
      queue->push_back(k);
    }
  }
}

// Clears the strained surface vertices that faced the sensor at `start` (`faces` is given
// the vertex's unit normal there, rings: the surface's) and have no cloud point within
// `reach` of where they were, in an object at least half of whose surface vertices facing the
// sensor still have one: the rest of the body stayed, and nothing of the cloud is at that
// part's place, so the points that pulled it are most likely the part itself, moved faster
// than the frame's first outer iteration followed, and not a hand beside it, which leaves the
// body's own points around. Where most of the object left its place (a hand carried it), an
// empty place tells nothing. The coverage counts every cloud point (other objects', occluders').
void LeaveCarriedOff(const TrackerState& state, const Vertices& start, const SurfaceRings& rings,
                     const PointIndex& cloud_index, double reach,
                     const std::function<bool(const Eigen::Vector3d&, const Eigen::Vector3d&)>& faces,
                     std::vector<char>* strained) {
  std::vector<int> vertices, empty;  // an object's surface vertices; those strained, facing, empty
  for (const ObjectState& o : state.objects) {
    vertices.clear();
    bool any = false;
    for (int v : o.mesh.surface_vertices) {
      vertices.push_back(o.offset + v);
      any = any || (*strained)[static_cast<size_t>(o.offset + v)];
    }
    if (!any) continue;  // nothing of this object to clear: no queries for it
    const Eigen::MatrixXd normal = VertexNormalsAt(start, state.surface, rings, vertices);
    int facing = 0, covered = 0;
    empty.clear();
    for (size_t k = 0; k < vertices.size(); ++k) {
      const Eigen::Vector3d p = start.row(vertices[k]).transpose();
      if (!faces(p, normal.row(static_cast<Eigen::Index>(k)).transpose())) continue;  // also off every triangle
      ++facing;
      if (cloud_index.AnyWithin(p, reach)) {
        ++covered;
      } else if ((*strained)[static_cast<size_t>(vertices[k])]) {
        empty.push_back(vertices[k]);
      }
    }
    if (2 * covered < facing) continue;
    for (int v : empty) (*strained)[static_cast<size_t>(v)] = 0;
  }
}

// The unit normal of triangle f at x.
Eigen::Vector3d FaceNormal(const Vertices& x, const Triangles& tris, int f) {
  const Eigen::Vector3d a = x.row(tris(f, 0)), b = x.row(tris(f, 1)), c = x.row(tris(f, 2));
  return (b - a).cross(c - a).normalized();
}

// Whether p lies on the outer side of the surface (x, tris; rings its vertices' triangles) at
// its closest point `hit`. The normal is the closest feature's (Baerentzen and Aanaes): the
// face's inside a triangle, the sum of its two faces' on an edge, the angle-weighted sum at a
// corner. On a closed surface turned outwards the side is then right at any distance, where a
// face's or an interpolated vertex normal can point the wrong way beyond a sharp edge.
bool Outside(const Eigen::Vector3d& p, const SurfaceIndex::Hit& hit, const Vertices& x, const Triangles& tris,
             const SurfaceRings& rings) {
  constexpr double kOnFeature = 1e-9;  // a barycentric coordinate this small: on the opposite edge
  const int f = hit.triangle;
  int corners[3], on = 0;
  for (int k = 0; k < 3; ++k) {
    if (hit.barycentric[k] > kOnFeature) corners[on++] = tris(f, k);
  }
  Eigen::Vector3d n = Eigen::Vector3d::Zero();
  if (on == 3 || on == 0) {
    n = FaceNormal(x, tris, f);
  } else {
    const int v = corners[0];
    for (int j = rings.offsets[static_cast<size_t>(v)]; j < rings.offsets[static_cast<size_t>(v) + 1]; ++j) {
      const int g = rings.list[static_cast<size_t>(j)];
      int at = 0;
      while (at < 3 && tris(g, at) != v) ++at;
      if (at == 3) continue;
      if (on == 2) {  // the edge (v, corners[1]): its two faces
        if (tris(g, (at + 1) % 3) == corners[1] || tris(g, (at + 2) % 3) == corners[1]) n += FaceNormal(x, tris, g);
      } else {  // the corner v: each face by its angle there
        const Eigen::Vector3d a = x.row(v), b = x.row(tris(g, (at + 1) % 3)), c = x.row(tris(g, (at + 2) % 3));
        const double angle = std::atan2((b - a).cross(c - a).norm(), (b - a).dot(c - a));
        n += angle * FaceNormal(x, tris, g);
      }
    }
  }
  return (p - hit.point).dot(n) > 0.0;
}

// Whether cloud point i lies off the model: farther than sqrt(grow2) from `surface`, and where
// `positions` is given (the surface's, with its `triangles`) also on its outer side. Each
// point is asked once (memo: -1 not yet, 0 on, 1 off).
struct OffModel {
  const SurfaceIndex* surface;
  const Vertices* points;
  double grow2;
  std::vector<signed char>* memo;
  const Vertices* positions = nullptr;
  const Triangles* triangles = nullptr;
  bool operator()(int i) const {
    signed char& o = (*memo)[static_cast<size_t>(i)];
    if (o < 0) {
      // The bounds where they leave no doubt, else the closest point.
      const Eigen::Vector3d p = points->row(i);
      const SurfaceIndex::Candidates near = surface->Nearby(p);
      double lower = 0.0, upper = 0.0;
      surface->DistanceBounds(p, near, &lower, &upper);
      const int within = Within(lower, upper, std::sqrt(grow2), p);
      if (within == 1) {
        o = 0;
      } else if (positions == nullptr) {
        o = within == 0 ? 1 : (surface->Closest(p, near).squared_distance > grow2 ? 1 : 0);
      } else {
        const SurfaceIndex::Hit hit = surface->Closest(p, near);
        o = hit.triangle >= 0 && hit.squared_distance > grow2 &&
                    Outside(p, hit, *positions, *triangles, surface->rings())
                ? 1
                : 0;
      }
    }
    return o == 1;
  }
};

}  // namespace

OccluderCounts MarkOccluders(const TrackerState& state, const SurfaceIndex& surface,
                             const Vertices& points, const PointIndex& cloud_index, double spacing,
                             std::vector<char>* occluder, const std::vector<int>& seeds, int seed_rings) {
  OccluderCounts counts;
  const int n = static_cast<int>(points.rows());
  occluder->assign(static_cast<size_t>(n), 0);
  const RegistrationOptions& options = state.options;
  if (n == 0 || state.surface.rows() == 0 || !options.camera.enabled) return counts;
  const double margin = options.data.occluder_margin;
  const double grow = std::max(options.data.loss_scale, 2.0 * spacing);

  // A pinhole on the user's camera pose whose image just covers the model, with pixels a
  // quarter of a surface edge wide at the model's depth: the model's depth along each ray.
  const Eigen::Matrix3d R = CameraRotation(options.camera);
  const Eigen::Vector3d eye = options.camera.position;
  double lo_u = std::numeric_limits<double>::infinity(), hi_u = -lo_u, lo_v = lo_u, hi_v = -lo_u;
  std::vector<double> depths;
  for (int v : state.surface_vertices) {
    const Eigen::Vector3d q = R * (state.x.row(v).transpose() - eye);
    if (q.z() <= kNear) continue;
    lo_u = std::min(lo_u, q.x() / q.z());
    hi_u = std::max(hi_u, q.x() / q.z());
    lo_v = std::min(lo_v, q.y() / q.z());
    hi_v = std::max(hi_v, q.y() / q.z());
    depths.push_back(q.z());
  }
  if (depths.empty()) return counts;
  std::nth_element(depths.begin(), depths.begin() + depths.size() / 2, depths.end());
  const double edge = state.mean_edge_length > 0 ? state.mean_edge_length : spacing;
  double pixel = std::max(0.25 * edge / depths[depths.size() / 2], 1e-6);  // rad
  pixel = std::max({pixel, (hi_u - lo_u) / (kMaxImageSide - 4), (hi_v - lo_v) / (kMaxImageSide - 4)});
  PinholeCamera camera;
  camera.rotation = R;
  camera.position = eye;
  camera.near = kNear;
  camera.fx = camera.fy = 1.0 / pixel;
  camera.cx = 1.0 - lo_u / pixel;
  camera.cy = 1.0 - lo_v / pixel;
  camera.width = static_cast<int>(std::ceil((hi_u - lo_u) / pixel)) + 3;
  camera.height = static_cast<int>(std::ceil((hi_v - lo_v) / pixel)) + 3;
  ZBuffer image;
  image.Reset(camera.width, camera.height);
  Rasterize(camera, state.x, state.surface, 0, &image);

  // Per point: in front of the model (or beside it) and off its surface.
  std::vector<char> off(static_cast<size_t>(n), 0), seed(static_cast<size_t>(n), 0);
  std::atomic<int> on_model{0}, seeds_found{0};
  const bool seeded = static_cast<int>(seeds.size()) == n && seed_rings > 0;
  // Each point on its own (counts of integers): the same on any thread count.
  ParallelFor(0, n, 1024, [&](int64_t i) {
    double u = 0, v = 0, z = 0;
    if (!camera.Project(points.row(i), &u, &v, &z)) return;
    const int px = static_cast<int>(std::lround(u)), py = static_cast<int>(std::lround(v));
    double model_z = std::numeric_limits<double>::infinity();
    if (px >= 0 && py >= 0 && px < image.width && py < image.height) {
      const size_t idx = static_cast<size_t>(py) * static_cast<size_t>(image.width) + static_cast<size_t>(px);
      model_z = image.depth[idx];
    }
    const bool hit = std::isfinite(model_z);
    if (hit) on_model.fetch_add(1, std::memory_order_relaxed);
    if (!(z < model_z - grow)) return;
    // Without seeds, the bounds decide where they leave no doubt (the same marks). Not with
    // them: a settled walk may stop farther than the bounds' upper end, and the marks go by
    // the walk's distance (below); the walks also spare the k-d tree of every vertex.
    const Eigen::Vector3d p = points.row(i);
    SurfaceIndex::Candidates near;
    double lower = 0.0, upper = std::numeric_limits<double>::infinity();
    if (!seeded) {
      near = surface.Nearby(p);
      surface.DistanceBounds(p, near, &lower, &upper);
    }
    if (Within(lower, upper, grow, p) == 1) return;
    double d = Within(lower, upper, std::max(grow, margin), p) == 0
                   ? lower
                   : std::sqrt((seeded ? surface.ClosestSeeded(p, seeds[static_cast<size_t>(i)], seed_rings)
                                       : surface.Closest(p, near))
                                   .squared_distance);
    // A walk from the nearest subsample vertex can stop on a thin part's far side: its distance
    // exceeds the true one by at most the subsample's spacing (under a mesh edge), so a point
    // within that of the limit is searched in full.
    if (seeded && d > grow && d <= grow + state.mean_edge_length) {
      d = std::sqrt(surface.Closest(points.row(i)).squared_distance);
    }
    if (d <= grow) return;
    off[static_cast<size_t>(i)] = 1;
    if (hit && z < model_z - margin && d > margin) {
      seed[static_cast<size_t>(i)] = 1;
      seeds_found.fetch_add(1, std::memory_order_relaxed);
    }
  });
  counts.seeds = seeds_found.load();
  if (counts.seeds == 0) return counts;
  if (counts.seeds > kWholeView * on_model.load()) {
    counts.whole_view = true;
    return counts;
  }

  // Grown from the seeds, in the points' order: the same set for any thread count.
  std::vector<int> queue;
  for (int i = 0; i < n; ++i) {
    if (seed[static_cast<size_t>(i)]) {
      (*occluder)[static_cast<size_t>(i)] = 1;
      queue.push_back(i);
    }
  }
  const auto is_off = [&](int k) { return off[static_cast<size_t>(k)] != 0; };
  Grow(points, cloud_index, spacing, 1, is_off, &queue, occluder);
  counts.occluders = static_cast<int>(queue.size());
  return counts;
}

OccluderCounts ReleaseReached(const TrackerState& state, const SurfaceIndex& surface,
                             const Vertices& points, double spacing, std::vector<char>* occluder) {
  OccluderCounts counts;
  const double grow = std::max(state.options.data.loss_scale, 2.0 * spacing);
  for (size_t i = 0; i < occluder->size(); ++i) {
    if ((*occluder)[i] != 1 && (*occluder)[i] != 3) {
      counts.occluders += (*occluder)[i] != 0;
      continue;
    }
    // Decided by the bounds where they leave no doubt, else by the closest point: the same
    // marks.
    const Eigen::Vector3d p = points.row(static_cast<Eigen::Index>(i));
    const SurfaceIndex::Candidates near = surface.Nearby(p);
    double lower = 0.0, upper = 0.0;
    surface.DistanceBounds(p, near, &lower, &upper);
    const int within = Within(lower, upper, grow, p);
    if (within == 1 || (within < 0 && surface.Closest(p, near).squared_distance <= grow * grow)) {
      (*occluder)[i] = 0;
    } else {
      ++counts.occluders;
    }
  }
  return counts;
}

int MarkImplausible(const TrackerState& state, const Vertices& start, const Vertices& points,
                    const PointIndex& cloud_index, double spacing,
                    const std::function<bool(const Eigen::Vector3d&, const Eigen::Vector3d&)>& faces,
                    std::vector<char>* marks, bool outside_only) {
  const double limit = state.options.data.max_strain_step;
  const int n = static_cast<int>(points.rows());
  if (!(limit > 0) || n == 0 || start.rows() != state.x.rows() || state.surface.rows() == 0) return 0;
  // |sigma^2 - 1| <= |F^T F - I|_2 <= its Frobenius norm, for every singular value sigma of F.
  const double stretch_bound = (1.0 + limit) * (1.0 + limit) - 1.0;
  const double bound =
      limit >= 1.0 ? stretch_bound : std::min(stretch_bound, 1.0 - (1.0 - limit) * (1.0 - limit));
  std::vector<char> strained(static_cast<size_t>(state.x.rows()), 0);
  bool any = false;
  const int threads = state.options.solver.num_threads;
  std::vector<char> over;  // per element: strained past the limit
  for (const ObjectState& o : state.objects) {
    const auto& tets = o.model.tets();
    const int ne = o.model.num_elements();
    over.assign(static_cast<size_t>(ne), 0);
    ParallelFor(threads, ne, 2048, [&](int64_t e) {
      Eigen::Matrix3d Dm, Ds;
      const int a = o.offset + tets(e, 0);
      for (int k = 0; k < 3; ++k) {
        const int b = o.offset + tets(e, k + 1);
        Dm.col(k) = (start.row(b) - start.row(a)).transpose();
        Ds.col(k) = (state.x.row(b) - state.x.row(a)).transpose();
      }
      const double det = Dm.determinant();
      if (!(std::abs(det) > 0.0)) return;  // flat at the start: no strain to measure from
      const Eigen::Matrix3d F = Ds * Dm.inverse();
      // Upright with |F^T F - I| below `bound`: every principal stretch is within `limit` of 1.
      const double strain = (F.transpose() * F - Eigen::Matrix3d::Identity()).norm();
      if (F.determinant() > 0.0 && strain < bound) return;
      if (!(StretchDeviation(F) > limit)) return;
      // A move below the cloud's spacing is not resolved by it, and on a sliver reads as a large strain.
      double moved = 0.0;
      for (int i = 0; i < 4; ++i) {
        for (int j = i + 1; j < 4; ++j) {
          const int p = o.offset + tets(e, i), q = o.offset + tets(e, j);
          moved = std::max(moved, std::abs((state.x.row(p) - state.x.row(q)).norm() -
                                           (start.row(p) - start.row(q)).norm()));
        }
      }
      over[static_cast<size_t>(e)] = moved > spacing ? 1 : 0;
    });
    for (int e = 0; e < ne; ++e) {
      if (!over[static_cast<size_t>(e)]) continue;
      for (int k = 0; k < 4; ++k) strained[static_cast<size_t>(o.offset + tets(e, k))] = 1;
      any = true;
    }
  }
  if (!any) return 0;
  if (marks->size() != static_cast<size_t>(n)) marks->assign(static_cast<size_t>(n), 0);
  const double grow = std::max(state.options.data.loss_scale, 2.0 * spacing);
  // The meshes' own surfaces (an embedded surface's pairs act through the same elements).
  const SurfaceIndex surface(state.x, state.surface), at_start(start, state.surface);
  if (faces) {
    LeaveCarriedOff(state, start, at_start.rings(), cloud_index, grow, faces, &strained);
    if (std::find(strained.begin(), strained.end(), 1) == strained.end()) return 0;
  }
  std::vector<signed char> memo(static_cast<size_t>(n), -1), seed_memo(static_cast<size_t>(n), -1);
  const OffModel Off{&at_start, &points, grow * grow, &memo};
  // With outside_only, a seed also lies outside the body at the start: a hand's point cannot
  // be inside the body's material, and the body's own points are there where the start
  // overshot a motion that stopped (docs/notes/2026-12-08-marks-from-the-side.md).
  const OffModel Seed{&at_start, &points, grow * grow, &seed_memo, outside_only ? &start : nullptr, &state.surface};
  std::vector<int> queue;
  // A point's closest triangle touches a strained vertex only if that vertex is within the
  // point's distance to the surface (at most its nearest vertex's) and a triangle's longest
  // edge: the others skip the search, with the same marks.
  std::vector<char> corner(static_cast<size_t>(state.x.rows()), 0);
  std::vector<int> strained_corners;
  double longest2 = 0.0;
  for (int f = 0; f < state.surface.rows(); ++f) {
    for (int k = 0; k < 3; ++k) {
      const int a = state.surface(f, k), b = state.surface(f, (k + 1) % 3);
      longest2 = std::max(longest2, (state.x.row(a) - state.x.row(b)).squaredNorm());
      if (corner[static_cast<size_t>(a)] || !strained[static_cast<size_t>(a)]) continue;
      corner[static_cast<size_t>(a)] = 1;
      strained_corners.push_back(a);
    }
  }
  Vertices strained_points(static_cast<Eigen::Index>(strained_corners.size()), 3);
  for (size_t k = 0; k < strained_corners.size(); ++k) {
    strained_points.row(static_cast<Eigen::Index>(k)) = state.x.row(strained_corners[k]);
  }
  const PointIndex strained_index(strained_points);
  const double longest = std::sqrt(longest2);
  // Each point's closest triangle on the workers (the search is most of the cost); the marks
  // then in the points' order, as on one thread.
  std::vector<int> closest(static_cast<size_t>(n), -1);
  ParallelFor(threads, n, 2048, [&](int64_t i) {
    if ((*marks)[static_cast<size_t>(i)] || strained_corners.empty()) return;
    const Eigen::Vector3d p = points.row(i);
    const SurfaceIndex::Candidates near = surface.Nearby(p);
    double lower = 0.0, upper = 0.0;
    surface.DistanceBounds(p, near, &lower, &upper);
    const double reach = upper + longest;
    if (!strained_index.AnyWithin(p, reach + kBoundMargin * (reach + p.norm()))) return;
    closest[static_cast<size_t>(i)] = surface.Closest(p, near).triangle;
  });
  for (int i = 0; i < n; ++i) {
    const int triangle = closest[static_cast<size_t>(i)];
    if (triangle < 0) continue;
    bool touches = false;
    for (int k = 0; k < 3; ++k) {
      touches |= strained[static_cast<size_t>(state.surface(triangle, k))] != 0;
    }
    if (!touches || !Seed(i)) continue;
    (*marks)[static_cast<size_t>(i)] = 2;
    queue.push_back(i);
  }
  Grow(points, cloud_index, spacing, 2, Off, &queue, marks);
  return static_cast<int>(queue.size());
}

int CarryImplausible(const TrackerState& state, const Vertices& before, const Vertices& points,
                     const PointIndex& cloud_index, double spacing, std::vector<char>* marks) {
  const int n = static_cast<int>(points.rows());
  if (before.rows() == 0 || n == 0 || state.surface.rows() == 0) return 0;
  if (marks->size() != static_cast<size_t>(n)) marks->assign(static_cast<size_t>(n), 0);
  const double grow = std::max(state.options.data.loss_scale, 2.0 * spacing);
  const SurfaceIndex surface(state.x, state.surface);
  const PointIndex last(before);
  std::vector<signed char> memo(static_cast<size_t>(n), -1);
  const OffModel Off{&surface, &points, grow * grow, &memo};
  std::vector<int> queue;
  for (int i = 0; i < n; ++i) {
    if ((*marks)[static_cast<size_t>(i)]) continue;
    double d2 = 0.0;
    last.Nearest(points.row(i), &d2);
    if (d2 > grow * grow || !Off(i)) continue;
    (*marks)[static_cast<size_t>(i)] = 3;
    queue.push_back(i);
  }
  Grow(points, cloud_index, spacing, 3, Off, &queue, marks);
  return static_cast<int>(queue.size());
}

Vertices ImplausiblePoints(const TrackerState& state, const Vertices& points, const std::vector<char>& marks) {
  std::vector<int> rows;
  for (size_t i = 0; i < marks.size(); ++i) {
    if (marks[i] == 2 || marks[i] == 3) rows.push_back(static_cast<int>(i));
  }
  // Most frames with marks have only occluders: no surface index to build for them.
  if (rows.empty() || state.surface.rows() == 0) return Vertices(0, 3);
  const double far = state.options.data.max_strain_step * state.mean_edge_length;
  const SurfaceIndex surface(state.x, state.surface);
  Vertices out(static_cast<Eigen::Index>(rows.size()), 3);
  Eigen::Index kept = 0;
  for (const int i : rows) {
    if (surface.Closest(points.row(i)).squared_distance > far * far) out.row(kept++) = points.row(i);
  }
  return out.topRows(kept);
}

int TouchingOccluderPoints(const Vertices& points, const PointIndex& cloud_index, double spacing,
                           const std::vector<char>& occluder, int enough) {
  const double radius2 = kReach * kReach * spacing * spacing;  // Grow's
  int indices[kNeighbours];
  double squared[kNeighbours];
  int touching = 0;
  for (int i = 0; i < static_cast<int>(occluder.size()) && touching < enough; ++i) {
    if (!occluder[static_cast<size_t>(i)]) continue;
    const int found = cloud_index.KNearest(points.row(i), kNeighbours, indices, squared);
    for (int j = 0; j < found; ++j) {
      if (squared[j] <= radius2 && !occluder[static_cast<size_t>(indices[j])]) {
        ++touching;
        break;
      }
    }
  }
  return touching;
}

}  // namespace femreg
