// Merging duplicate vertices and checking that a triangle surface bounds a volume.
#include "meshing/surface_check.h"

#include <Eigen/Geometry>
#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <limits>
#include <map>
#include <sstream>
#include <unordered_map>

#include "femreg/geometry.h"  // AabbTree and the exact closest-point queries
#include "mesh/disjoint_sets.h"
#include "meshing/mesh_measures.h"

namespace femreg {
namespace internal {
namespace {

constexpr double kPi = 3.14159265358979323846;
// Triangles closer than this fraction of the bounding box diagonal touch.
constexpr double kTouchTolerance = 1e-10;
// Angles (radians) below this are zero: a fold, an edge lying in another triangle's plane.
constexpr double kAngleTolerance = 1e-9;
// A triangle with 2 * area / (longest edge)^2 below this is degenerate (its corners are
// collinear to about this relative precision).
constexpr double kDegenerateTolerance = 1e-10;
// Examples listed per problem.
constexpr int kMaxExamples = 5;

using internal::Fmt;

std::string Pt(const Eigen::Vector3d& p) {
  return "(" + Fmt(p.x()) + ", " + Fmt(p.y()) + ", " + Fmt(p.z()) + ")";
}

Eigen::Vector3d Row(const Vertices& V, int i) { return V.row(i).transpose(); }

uint64_t EdgeKey(int a, int b) {
  if (a > b) std::swap(a, b);
  return (static_cast<uint64_t>(static_cast<uint32_t>(a)) << 32) | static_cast<uint32_t>(b);
}

// Vertices within `d` of each other are merged (transitively); rep[i] is the smallest index
// of i's group. d <= 0: exact copies only.
std::vector<int> MergeGroups(const Vertices& V, double d, const Eigen::Vector3d& lo,
                             double diagonal) {
  const int n = static_cast<int>(V.rows());
  DisjointSets sets(n);
  if (d > 0.0 && diagonal / d < 1e12) {
    struct CellHash {
      size_t operator()(const std::array<int64_t, 3>& c) const {
        return static_cast<size_t>(c[0] * 73856093LL ^ c[1] * 19349663LL ^ c[2] * 83492791LL);
      }
    };
    std::unordered_map<std::array<int64_t, 3>, std::vector<int>, CellHash> grid;
    grid.reserve(static_cast<size_t>(n));
    for (int i = 0; i < n; ++i) {
      const Eigen::Vector3d p = Row(V, i);
      std::array<int64_t, 3> cell;
      for (int k = 0; k < 3; ++k) cell[k] = static_cast<int64_t>(std::floor((p[k] - lo[k]) / d));
      for (int dx = -1; dx <= 1; ++dx) {
        for (int dy = -1; dy <= 1; ++dy) {
          for (int dz = -1; dz <= 1; ++dz) {
            auto it = grid.find({cell[0] + dx, cell[1] + dy, cell[2] + dz});
            if (it == grid.end()) continue;
            for (int j : it->second) {
              if ((Row(V, j) - p).norm() <= d) sets.Unite(i, j);
            }
          }
        }
      }
      grid[cell].push_back(i);
    }
  } else {
    std::map<std::array<double, 3>, int> seen;
    for (int i = 0; i < n; ++i) {
      auto it = seen.emplace(std::array<double, 3>{V(i, 0), V(i, 1), V(i, 2)}, i);
      if (!it.second) sets.Unite(i, it.first->second);
    }
  }
  std::vector<int> rep(static_cast<size_t>(n));
  for (int i = 0; i < n; ++i) rep[static_cast<size_t>(i)] = sets.Find(i);
  return rep;
}

// Distance from segment pq to triangle t[0..2].
double SegmentTriangleDistance(const Eigen::Vector3d& p, const Eigen::Vector3d& q,
                               const Eigen::Vector3d* t) {
  const Eigen::Vector3d n = (t[1] - t[0]).cross(t[2] - t[0]);
  const double dp = n.dot(p - t[0]), dq = n.dot(q - t[0]);
  double best = std::min((TriangleClosestPoint(p, t[0], t[1], t[2]) - p).norm(),
                         (TriangleClosestPoint(q, t[0], t[1], t[2]) - q).norm());
  if ((dp < 0 && dq > 0) || (dp > 0 && dq < 0)) {
    // Where the segment crosses the plane: ~0 from the triangle (rounding) when inside it.
    const Eigen::Vector3d x = p + dp / (dp - dq) * (q - p);
    best = std::min(best, (TriangleClosestPoint(x, t[0], t[1], t[2]) - x).norm());
  }
  for (int k = 0; k < 3; ++k) {
    double s, u;
    best = std::min(best, ClosestSegmentSegment(p, q, t[k], t[(k + 1) % 3], &s, &u));
  }
  return best;
}

// Whether the edge from v along u lies in the plane of the triangle (v, c, d) and inside its
// corner at v (closed, within kAngleTolerance).
bool EdgeInsideCorner(const Eigen::Vector3d& u, const Eigen::Vector3d& e1,
                      const Eigen::Vector3d& e2) {
  const Eigen::Vector3d n = e1.cross(e2).normalized();
  const double lu = u.norm();
  if (std::abs(n.dot(u)) > kAngleTolerance * lu) return false;
  Eigen::Matrix2d g;
  g << e1.dot(e1), e1.dot(e2), e1.dot(e2), e2.dot(e2);
  const Eigen::Vector2d ab = g.ldlt().solve(Eigen::Vector2d(e1.dot(u), e2.dot(u)));
  const double a = ab[0] * e1.norm() / lu, b = ab[1] * e2.norm() / lu;
  return a >= -kAngleTolerance && b >= -kAngleTolerance;
}

// How triangles ta and tb (rows of F) meet beyond what they share, or null when they do
// not. tol: the touching distance.
const char* HowTheyMeet(const Vertices& V, const Triangles& F, int ta, int tb, double tol) {
  std::array<int, 3> a = {F(ta, 0), F(ta, 1), F(ta, 2)};
  std::array<int, 3> b = {F(tb, 0), F(tb, 1), F(tb, 2)};
  int shared = 0;
  for (int i : a) shared += (i == b[0] || i == b[1] || i == b[2]) ? 1 : 0;
  if (shared == 3) return "coincide";
  if (shared == 2) {
    // Rotate both so that the shared edge is corners 0, 1 and the apex corner 2.
    auto rotate_apex_last = [](std::array<int, 3>* t, const std::array<int, 3>& other) {
      for (int r = 0; r < 3; ++r) {
        const int apex = (*t)[2];
        if (apex != other[0] && apex != other[1] && apex != other[2]) return;
        std::rotate(t->begin(), t->begin() + 1, t->end());
      }
    };
    rotate_apex_last(&a, b);
    rotate_apex_last(&b, a);
    const Eigen::Vector3d p = Row(V, a[0]), e = (Row(V, a[1]) - p).normalized();
    Eigen::Vector3d ra = Row(V, a[2]) - p, rb = Row(V, b[2]) - p;
    ra -= ra.dot(e) * e;
    rb -= rb.dot(e) * e;
    const double sine = ra.cross(rb).norm() / (ra.norm() * rb.norm());
    return (ra.dot(rb) > 0 && sine <= kAngleTolerance) ? "fold onto each other" : nullptr;
  }
  if (shared == 1) {
    // Rotate both so that the shared vertex is corner 0.
    while (a[0] != b[0] && a[0] != b[1] && a[0] != b[2])
      std::rotate(a.begin(), a.begin() + 1, a.end());
    while (b[0] != a[0]) std::rotate(b.begin(), b.begin() + 1, b.end());
    const Eigen::Vector3d ta_[3] = {Row(V, a[0]), Row(V, a[1]), Row(V, a[2])};
    const Eigen::Vector3d tb_[3] = {Row(V, b[0]), Row(V, b[1]), Row(V, b[2])};
    if (SegmentTriangleDistance(ta_[1], ta_[2], tb_) <= tol ||
        SegmentTriangleDistance(tb_[1], tb_[2], ta_) <= tol) {
      return "cross or touch";
    }
    const Eigen::Vector3d v = ta_[0];
    for (int k = 1; k <= 2; ++k) {
      if (EdgeInsideCorner(ta_[k] - v, tb_[1] - v, tb_[2] - v) ||
          EdgeInsideCorner(tb_[k] - v, ta_[1] - v, ta_[2] - v)) {
        return "overlap at a shared vertex";
      }
    }
    return nullptr;
  }
  const Eigen::Vector3d t1[3] = {Row(V, a[0]), Row(V, a[1]), Row(V, a[2])};
  const Eigen::Vector3d t2[3] = {Row(V, b[0]), Row(V, b[1]), Row(V, b[2])};
  // Quick rejection: all of one triangle strictly on one side of the other's plane.
  for (int pass = 0; pass < 2; ++pass) {
    const Eigen::Vector3d* s = pass == 0 ? t1 : t2;
    const Eigen::Vector3d* o = pass == 0 ? t2 : t1;
    const Eigen::Vector3d n = (s[1] - s[0]).cross(s[2] - s[0]).normalized();
    const double d0 = n.dot(o[0] - s[0]), d1 = n.dot(o[1] - s[0]), d2 = n.dot(o[2] - s[0]);
    if ((d0 > tol && d1 > tol && d2 > tol) || (d0 < -tol && d1 < -tol && d2 < -tol)) {
      return nullptr;
    }
  }
  const TrianglePairDistance d = TriangleTriangleDistance(t1, t2);
  if (d.intersecting) return "cross";
  return d.distance <= tol ? "touch" : nullptr;
}

// Where a ray from `origin` along `dir` first meets triangle (a, b, c) beyond `t_min`, or
// infinity.
double RayTriangle(const Eigen::Vector3d& origin, const Eigen::Vector3d& dir,
                   const Eigen::Vector3d& a, const Eigen::Vector3d& b, const Eigen::Vector3d& c,
                   double t_min) {
  const Eigen::Vector3d e1 = b - a, e2 = c - a;
  const Eigen::Vector3d h = dir.cross(e2);
  const double det = e1.dot(h);
  const double inf = std::numeric_limits<double>::infinity();
  if (det == 0.0) return inf;
  const Eigen::Vector3d s = origin - a;
  const double u = s.dot(h) / det;
  if (u < 0.0 || u > 1.0) return inf;
  const Eigen::Vector3d q = s.cross(e1);
  const double v = dir.dot(q) / det;
  if (v < 0.0 || u + v > 1.0) return inf;
  const double t = e2.dot(q) / det;
  return t > t_min ? t : inf;
}

// Collects problems as "N <what>; e.g. <example>" lines.
class Problems {
 public:
  void Add(long long count, const std::string& what, const std::string& example) {
    if (count <= 0) return;
    lines_.push_back(std::to_string(count) + " " + what +
                     (example.empty() ? "" : "; e.g. " + example));
  }
  void AddLine(const std::string& line) { lines_.push_back(line); }
  bool empty() const { return lines_.empty(); }
  Status ToStatus(const std::string& source) const {
    std::string message = source + ": cannot tetrahedralize, the surface does not bound a volume:";
    for (const std::string& line : lines_) message += "\n  - " + line;
    return Status::Error(message);
  }

 private:
  std::vector<std::string> lines_;
};

}  // namespace

double WindingNumber(const Eigen::Vector3d& p, const Vertices& V, const Triangles& F,
                     const std::vector<int>& triangles) {
  double total = 0.0;
  for (int t : triangles) {
    const Eigen::Vector3d a = Row(V, F(t, 0)) - p, b = Row(V, F(t, 1)) - p, c = Row(V, F(t, 2)) - p;
    const double la = a.norm(), lb = b.norm(), lc = c.norm();
    const double num = a.dot(b.cross(c));
    const double den = la * lb * lc + a.dot(b) * lc + a.dot(c) * lb + b.dot(c) * la;
    total += 2.0 * std::atan2(num, den);
  }
  return total / (4.0 * kPi);
}

Status CheckSurface(const Vertices& V, const Triangles& F, double merge_distance,
                    bool check_self_intersections, const std::string& source, CheckedSurface* out) {
  *out = CheckedSurface();
  const int nv = static_cast<int>(V.rows()), nf = static_cast<int>(F.rows());
  if (nf == 0) return Status::Error(source + ": no triangle");
  if (nv == 0) return Status::Error(source + ": no vertex");
  for (int i = 0; i < nv; ++i) {
    if (!V.row(i).allFinite()) {
      return Status::Error(source + ": vertex " + std::to_string(i) + " is not finite");
    }
  }
  for (int t = 0; t < nf; ++t) {
    for (int k = 0; k < 3; ++k) {
      if (F(t, k) < 0 || F(t, k) >= nv) {
        return Status::Error(source + ": triangle " + std::to_string(t) + " refers to vertex " +
                             std::to_string(F(t, k)) + ", outside 0.." + std::to_string(nv - 1));
      }
    }
  }

  // Merge coincident vertices, drop unused vertices (keeping the input's vertex order).
  const Eigen::Vector3d lo = V.colwise().minCoeff().transpose();
  const Eigen::Vector3d hi = V.colwise().maxCoeff().transpose();
  const double diagonal = (hi - lo).norm();
  if (!(diagonal > 0.0)) return Status::Error(source + ": all vertices are at one point");
  out->bounding_box_diagonal = diagonal;
  out->merge_distance = merge_distance < 0.0 ? 1e-9 * diagonal : merge_distance;
  const std::vector<int> rep = MergeGroups(V, out->merge_distance, lo, diagonal);
  std::vector<char> used(static_cast<size_t>(nv), 0);
  for (int t = 0; t < nf; ++t) {
    for (int k = 0; k < 3; ++k) used[static_cast<size_t>(rep[static_cast<size_t>(F(t, k))])] = 1;
  }
  std::vector<int> new_index(static_cast<size_t>(nv), -1);
  int count = 0;
  for (int i = 0; i < nv; ++i) {
    if (rep[static_cast<size_t>(i)] != i) {
      ++out->merged_vertices;
    } else if (used[static_cast<size_t>(i)]) {
      new_index[static_cast<size_t>(i)] = count++;
    } else {
      ++out->unused_vertices;
    }
  }
  Vertices& W = out->vertices;
  Triangles& T = out->triangles;
  W.resize(count, 3);
  for (int i = 0; i < nv; ++i) {
    if (new_index[static_cast<size_t>(i)] >= 0) W.row(new_index[static_cast<size_t>(i)]) = V.row(i);
  }
  T.resize(nf, 3);
  for (int t = 0; t < nf; ++t) {
    for (int k = 0; k < 3; ++k) {
      T(t, k) = new_index[static_cast<size_t>(rep[static_cast<size_t>(F(t, k))])];
    }
  }

  Problems problems;

  // Zero-area triangles.
  std::vector<char> degenerate(static_cast<size_t>(nf), 0);
  {
    long long n = 0;
    std::string example;
    double edge_sum = 0.0;
    for (int t = 0; t < nf; ++t) {
      const Eigen::Vector3d a = Row(W, T(t, 0)), b = Row(W, T(t, 1)), c = Row(W, T(t, 2));
      const double longest = std::max({(b - a).norm(), (c - b).norm(), (a - c).norm()});
      edge_sum += (b - a).norm() + (c - b).norm() + (a - c).norm();
      const double twice_area = (b - a).cross(c - a).norm();
      out->area += 0.5 * twice_area;
      const bool repeats = T(t, 0) == T(t, 1) || T(t, 1) == T(t, 2) || T(t, 0) == T(t, 2);
      if (repeats || !(twice_area > kDegenerateTolerance * longest * longest)) {
        degenerate[static_cast<size_t>(t)] = 1;
        if (n++ == 0) {
          example = "triangle " + std::to_string(t) + " with corners " + Pt(a) + ", " + Pt(b) +
                    ", " + Pt(c) +
                    (repeats ? " (corners closer than the merge distance " +
                                   Fmt(out->merge_distance) + " were merged)"
                             : "");
        }
      }
    }
    out->mean_edge_length = edge_sum / (3.0 * nf);
    problems.Add(n, "zero-area triangles (collinear or coincident corners)", example);
  }

  // Edges: boundary, non-manifold, inconsistent orientation.
  struct EdgeUse {
    int count = 0;
    int t[2] = {-1, -1};
    bool forward[2] = {false, false};
  };
  std::unordered_map<uint64_t, EdgeUse> edges;
  edges.reserve(static_cast<size_t>(3 * nf));
  for (int t = 0; t < nf; ++t) {
    if (degenerate[static_cast<size_t>(t)] &&
        (T(t, 0) == T(t, 1) || T(t, 1) == T(t, 2) || T(t, 0) == T(t, 2))) {
      continue;
    }
    for (int k = 0; k < 3; ++k) {
      const int a = T(t, k), b = T(t, (k + 1) % 3);
      EdgeUse& e = edges[EdgeKey(a, b)];
      if (e.count < 2) {
        e.t[e.count] = t;
        e.forward[e.count] = a < b;
      }
      ++e.count;
    }
  }
  long long boundary = 0, nonmanifold = 0, flipped = 0;
  std::string boundary_example, nonmanifold_example, flipped_example;
  for (int t = 0; t < nf; ++t) {
    for (int k = 0; k < 3; ++k) {
      const int a = T(t, k), b = T(t, (k + 1) % 3);
      if (a == b) continue;
      auto it = edges.find(EdgeKey(a, b));
      if (it == edges.end() || it->second.t[0] != t) continue;  // count each edge once
      const EdgeUse& e = it->second;
      const std::string where = Pt(Row(W, a)) + "-" + Pt(Row(W, b));
      if (e.count == 1) {
        if (boundary++ == 0) {
          boundary_example = "the edge " + where + " of triangle " + std::to_string(t) +
                             " has no triangle on its other side";
        }
      } else if (e.count > 2) {
        if (nonmanifold++ == 0) {
          nonmanifold_example = "the edge " + where + " is in " + std::to_string(e.count) +
                                " triangles, among them " + std::to_string(e.t[0]) + " and " +
                                std::to_string(e.t[1]);
        }
      } else if (e.forward[0] == e.forward[1]) {
        if (flipped++ == 0) {
          flipped_example = "triangles " + std::to_string(e.t[0]) + " and " +
                            std::to_string(e.t[1]) + " run the same way along the edge " + where;
        }
      }
    }
  }
  if (boundary > 0) {
    problems.Add(boundary, "boundary edges: the surface is open (has holes or is a sheet)",
                 boundary_example);
  }
  problems.Add(nonmanifold, "edges shared by more than two triangles (non-manifold)",
               nonmanifold_example);
  problems.Add(flipped,
               "edges whose two triangles are oriented inconsistently (one faces out, the "
               "other in)",
               flipped_example);

  // Vertices where separate fans of triangles meet (two solids touching at a point).
  if (boundary == 0 && nonmanifold == 0) {
    std::vector<int> offsets(static_cast<size_t>(count) + 1, 0), incident;
    for (int t = 0; t < nf; ++t) {
      for (int k = 0; k < 3; ++k) ++offsets[static_cast<size_t>(T(t, k)) + 1];
    }
    for (int i = 0; i < count; ++i)
      offsets[static_cast<size_t>(i) + 1] += offsets[static_cast<size_t>(i)];
    incident.resize(static_cast<size_t>(offsets.back()));
    std::vector<int> fill(offsets.begin(), offsets.end() - 1);
    for (int t = 0; t < nf; ++t) {
      for (int k = 0; k < 3; ++k)
        incident[static_cast<size_t>(fill[static_cast<size_t>(T(t, k))]++)] = t;
    }
    long long n = 0;
    std::string example;
    std::vector<std::pair<int, int>> seen;  // (other vertex, local triangle)
    for (int v = 0; v < count; ++v) {
      const int begin = offsets[static_cast<size_t>(v)], end = offsets[static_cast<size_t>(v) + 1];
      DisjointSets fans(end - begin);
      seen.clear();
      for (int l = 0; l < end - begin; ++l) {
        const int t = incident[static_cast<size_t>(begin + l)];
        for (int k = 0; k < 3; ++k) {
          const int w = T(t, k);
          if (w == v) continue;
          auto it = std::find_if(seen.begin(), seen.end(),
                                 [w](const std::pair<int, int>& s) { return s.first == w; });
          if (it == seen.end()) {
            seen.emplace_back(w, l);
          } else {
            fans.Unite(l, it->second);
          }
        }
      }
      int roots = 0;
      for (int l = 0; l < end - begin; ++l) roots += fans.Find(l) == l ? 1 : 0;
      if (roots > 1 && n++ == 0) {
        example = "the vertex at " + Pt(Row(W, v)) + " joins " + std::to_string(roots) +
                  " separate fans of triangles";
      }
    }
    problems.Add(n, "vertices where separate sheets of the surface meet (non-manifold vertices)",
                 example);
  }

  // Triangles that cross or touch each other.
  if (check_self_intersections) {
    const double tol = kTouchTolerance * diagonal;
    AabbTree tree;
    tree.Build(W, T);
    long long n = 0;
    std::string example, list;
    std::vector<int> candidates;
    for (int t = 0; t < nf; ++t) {
      if (degenerate[static_cast<size_t>(t)]) continue;
      Eigen::AlignedBox3d box;
      for (int k = 0; k < 3; ++k) box.extend(Row(W, T(t, k)));
      tree.Overlapping(box, tol, &candidates);
      std::sort(candidates.begin(), candidates.end());
      for (int u : candidates) {
        if (u <= t || degenerate[static_cast<size_t>(u)]) continue;
        const char* how = HowTheyMeet(W, T, t, u, tol);
        if (how == nullptr) continue;
        if (n == 0) {
          const Eigen::Vector3d c = (Row(W, T(t, 0)) + Row(W, T(t, 1)) + Row(W, T(t, 2))) / 3.0;
          example = "triangles " + std::to_string(t) + " and " + std::to_string(u) + " " + how +
                    " near " + Pt(c);
        }
        if (n < kMaxExamples) list += (n ? ", " : "") + std::to_string(t) + "/" + std::to_string(u);
        ++n;
      }
    }
    if (n > 1) example += " (pairs " + list + (n > kMaxExamples ? ", ..." : "") + ")";
    problems.Add(n, "pairs of triangles that cross, touch or overlap (self-intersections)",
                 example);
  }
  if (!problems.empty()) return problems.ToStatus(source);

  // Shells: the components of triangles connected across edges.
  DisjointSets components(nf);
  for (const auto& e : edges) components.Unite(e.second.t[0], e.second.t[1]);
  std::map<int, int> shell_of_root;
  for (int t = 0; t < nf; ++t) {
    auto it = shell_of_root.emplace(components.Find(t), static_cast<int>(out->shells.size()));
    if (it.second) out->shells.emplace_back();
    out->shells[static_cast<size_t>(it.first->second)].triangles.push_back(t);
  }
  const Eigen::Vector3d center = 0.5 * (lo + hi);
  std::vector<Eigen::AlignedBox3d> boxes;
  for (size_t s = 0; s < out->shells.size(); ++s) {
    SurfaceShell& shell = out->shells[s];
    Eigen::AlignedBox3d box;
    for (int t : shell.triangles) {
      const Eigen::Vector3d a = Row(W, T(t, 0)) - center, b = Row(W, T(t, 1)) - center,
                            c = Row(W, T(t, 2)) - center;
      shell.signed_volume += a.dot(b.cross(c)) / 6.0;
      shell.area += 0.5 * (b - a).cross(c - a).norm();
      box.extend(a + center);
      box.extend(b + center);
      box.extend(c + center);
    }
    boxes.push_back(box);
    if (!(std::abs(shell.signed_volume) > 1e-9 * std::pow(shell.area, 1.5))) {
      const int t = shell.triangles.front();
      problems.AddLine("the closed shell of " + std::to_string(shell.triangles.size()) +
                       " triangles starting at triangle " + std::to_string(t) + " near " +
                       Pt(Row(W, T(t, 0))) + " encloses no volume (" + Fmt(shell.signed_volume) +
                       ")");
    }
  }
  if (!problems.empty()) return problems.ToStatus(source);

  // Nesting: shell j is inside shell i when a vertex of j is (shells neither cross nor touch).
  for (size_t j = 0; j < out->shells.size(); ++j) {
    const Eigen::Vector3d p = Row(W, T(out->shells[j].triangles.front(), 0));
    for (size_t i = 0; i < out->shells.size(); ++i) {
      if (i == j || !boxes[i].contains(boxes[j])) continue;
      if (std::abs(WindingNumber(p, W, T, out->shells[i].triangles)) > 0.5) ++out->shells[j].depth;
    }
  }

  // A point inside each shell: from the centroid of its largest triangle, inwards, half way
  // to the next triangle that ray meets.
  for (SurfaceShell& shell : out->shells) {
    int best = shell.triangles.front();
    double best_area = -1.0;
    for (int t : shell.triangles) {
      const double area =
          (Row(W, T(t, 1)) - Row(W, T(t, 0))).cross(Row(W, T(t, 2)) - Row(W, T(t, 0))).norm();
      if (area > best_area) {
        best_area = area;
        best = t;
      }
    }
    const Eigen::Vector3d a = Row(W, T(best, 0)), b = Row(W, T(best, 1)), c = Row(W, T(best, 2));
    const Eigen::Vector3d origin = (a + b + c) / 3.0;
    const Eigen::Vector3d inward =
        -(shell.signed_volume > 0 ? 1.0 : -1.0) * (b - a).cross(c - a).normalized();
    double hit = std::numeric_limits<double>::infinity();
    for (int t = 0; t < nf; ++t) {
      if (t == best) continue;
      hit = std::min(hit, RayTriangle(origin, inward, Row(W, T(t, 0)), Row(W, T(t, 1)),
                                      Row(W, T(t, 2)), 1e-14 * diagonal));
    }
    if (!std::isfinite(hit)) {
      return Status::Error(source + ": no point found inside the shell of triangle " +
                           std::to_string(best) + " (a ray inwards from it meets no triangle)");
    }
    shell.inside_point = origin + 0.5 * hit * inward;
  }
  return Status::Ok();
}

}  // namespace internal
}  // namespace femreg
