// Geometry: exact closest points (point-triangle against dense sampling, triangle-triangle
// against a brute-force convex QP), the AABB hierarchy against brute force, and the
// nearest-neighbour and closest-surface-point queries against brute force.
#include <gtest/gtest.h>

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <array>
#include <cmath>
#include <functional>
#include <limits>
#include <string>
#include <random>
#include <set>
#include <utility>
#include <vector>

#include "femreg/geometry.h"
#include "femreg/io.h"
#include "geometry/nearest.h"

namespace femreg {
namespace {

using V3 = Eigen::Vector3d;

// Euclidean projection onto the probability simplex.
Eigen::Vector3d ProjectSimplex(const Eigen::Vector3d& y) {
  std::array<double, 3> u = {y[0], y[1], y[2]};
  std::sort(u.begin(), u.end(), std::greater<double>());
  double css = 0, theta = 0;
  for (int i = 0; i < 3; ++i) {
    css += u[i];
    const double t = (css - 1) / (i + 1);
    if (u[i] - t > 0) theta = t;
  }
  return (y.array() - theta).max(0.0);
}

// Reference: min |A u - B v| over u, v in the simplex, a convex QP solved by accelerated
// projected gradient (FISTA) to convergence. Independent of the feature enumeration.
double BruteForceDistance(const V3* t1, const V3* t2) {
  Eigen::Matrix<double, 3, 6> M;
  for (int k = 0; k < 3; ++k) {
    M.col(k) = t1[k];
    M.col(3 + k) = -t2[k];
  }
  const double L = 2.0 * (M.transpose() * M).eigenvalues().real().maxCoeff() + 1e-12;
  Eigen::Matrix<double, 6, 1> z, y, z_prev;
  z << 1, 1, 1, 1, 1, 1;
  z /= 3.0;
  y = z;
  double t = 1.0;
  double best = (M * z).norm();
  for (int it = 0; it < 30000; ++it) {
    const Eigen::Matrix<double, 6, 1> g = 2.0 * M.transpose() * (M * y);
    Eigen::Matrix<double, 6, 1> w = y - g / L;
    z_prev = z;
    z.head<3>() = ProjectSimplex(w.head<3>());
    z.tail<3>() = ProjectSimplex(w.tail<3>());
    const double t_next = 0.5 * (1 + std::sqrt(1 + 4 * t * t));
    y = z + ((t - 1) / t_next) * (z - z_prev);
    t = t_next;
    best = std::min(best, (M * z).norm());
  }
  return best;
}

void ExpectConsistent(const TrianglePairDistance& d, const V3* t1, const V3* t2) {
  EXPECT_NEAR(d.bary_p.sum(), 1.0, 1e-12);
  EXPECT_NEAR(d.bary_q.sum(), 1.0, 1e-12);
  EXPECT_GE(d.bary_p.minCoeff(), -1e-12);
  EXPECT_GE(d.bary_q.minCoeff(), -1e-12);
  const V3 p = d.bary_p[0] * t1[0] + d.bary_p[1] * t1[1] + d.bary_p[2] * t1[2];
  const V3 q = d.bary_q[0] * t2[0] + d.bary_q[1] * t2[1] + d.bary_q[2] * t2[2];
  EXPECT_LT((p - d.p).norm(), 1e-9);
  EXPECT_LT((q - d.q).norm(), 1e-9);
  EXPECT_NEAR((d.p - d.q).norm(), d.distance, 1e-9);
}

TEST(TriangleDistance, MatchesBruteForceOnRandomPairs) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> u(-1, 1);
  int intersecting = 0;
  for (int trial = 0; trial < 600; ++trial) {
    V3 t1[3], t2[3];
    const V3 shift(u(rng), u(rng), u(rng));
    for (int k = 0; k < 3; ++k) {
      t1[k] = V3(u(rng), u(rng), u(rng));
      t2[k] = V3(u(rng), u(rng), u(rng)) + 0.8 * shift;
    }
    const TrianglePairDistance d = TriangleTriangleDistance(t1, t2);
    const double ref = BruteForceDistance(t1, t2);
    intersecting += d.intersecting;
    ASSERT_NEAR(d.distance, ref, 2e-6) << "trial " << trial;
    ExpectConsistent(d, t1, t2);
  }
  EXPECT_GT(intersecting, 10);  // the random set exercises the intersection branch
  EXPECT_LT(intersecting, 590);
}

TEST(TriangleDistance, ParallelCoplanarAndTouchingCases) {
  const V3 a[3] = {V3(0, 0, 0), V3(1, 0, 0), V3(0, 1, 0)};
  // Parallel planes, overlapping in projection: distance is the offset.
  const V3 b[3] = {V3(0.1, 0.1, 0.3), V3(0.9, 0.05, 0.3), V3(0.1, 0.7, 0.3)};
  TrianglePairDistance d = TriangleTriangleDistance(a, b);
  EXPECT_NEAR(d.distance, 0.3, 1e-12);
  EXPECT_FALSE(d.intersecting);
  ExpectConsistent(d, a, b);
  // Parallel edges (edge-edge with a 1-D family of closest pairs).
  const V3 c[3] = {V3(0.2, -0.5, 0), V3(0.8, -0.5, 0), V3(0.5, -1.5, 0)};
  d = TriangleTriangleDistance(a, c);
  EXPECT_NEAR(d.distance, 0.5, 1e-12);
  ExpectConsistent(d, a, c);
  // Coplanar, disjoint: nearest vertex to edge.
  const V3 e[3] = {V3(1, 1, 0), V3(2, 1, 0), V3(1, 2, 0)};
  d = TriangleTriangleDistance(a, e);
  EXPECT_NEAR(d.distance, std::sqrt(0.5), 1e-12);
  ExpectConsistent(d, a, e);
  // Coplanar, overlapping: distance 0.
  const V3 f[3] = {V3(0.2, 0.2, 0), V3(1.2, 0.2, 0), V3(0.2, 1.2, 0)};
  EXPECT_NEAR(TriangleTriangleDistance(a, f).distance, 0.0, 1e-12);
  // Touching at a shared vertex, at a vertex on a face, along an edge.
  const V3 g[3] = {V3(0, 0, 0), V3(-1, 0, 1), V3(0, -1, 1)};
  EXPECT_NEAR(TriangleTriangleDistance(a, g).distance, 0.0, 1e-12);
  const V3 h[3] = {V3(0.2, 0.2, 0), V3(0.2, 0.2, 1), V3(0.5, 0.1, 1)};
  EXPECT_NEAR(TriangleTriangleDistance(a, h).distance, 0.0, 1e-12);
  const V3 i[3] = {V3(0, 0, 0), V3(1, 0, 0), V3(0.5, 0, 1)};
  EXPECT_NEAR(TriangleTriangleDistance(a, i).distance, 0.0, 1e-12);
  // Piercing: an edge of b through the face of a.
  const V3 j[3] = {V3(0.2, 0.2, -1), V3(0.2, 0.2, 1), V3(3, 3, 0)};
  d = TriangleTriangleDistance(a, j);
  EXPECT_TRUE(d.intersecting);
  EXPECT_EQ(d.distance, 0.0);
  // Degenerate triangle (a segment).
  const V3 k[3] = {V3(0.3, 0.3, 0.5), V3(0.6, 0.3, 0.5), V3(0.9, 0.3, 0.5)};
  d = TriangleTriangleDistance(a, k);
  EXPECT_NEAR(d.distance, BruteForceDistance(a, k), 2e-6);
}

TEST(TriangleDistance, SegmentsParallelAndDegenerate) {
  double s, t;
  EXPECT_NEAR(ClosestSegmentSegment(V3(0, 0, 0), V3(1, 0, 0), V3(2, 1, 0), V3(3, 1, 0), &s, &t),
              std::sqrt(2.0), 1e-12);
  EXPECT_NEAR(ClosestSegmentSegment(V3(0, 0, 0), V3(1, 0, 0), V3(0.5, 1, 0), V3(1.5, 1, 0), &s, &t),
              1.0, 1e-12);
  EXPECT_NEAR(ClosestSegmentSegment(V3(0, 0, 0), V3(0, 0, 0), V3(1, 1, 0), V3(1, -1, 0), &s, &t),
              1.0, 1e-12);
}

// A random closed surface: a sphere's surface, jittered.
void RandomSurface(std::mt19937* rng, const V3& centre, Vertices* x, Triangles* tris) {
  TetMesh m = MakeSphere(0.1, 3);
  std::normal_distribution<double> n(0, 0.01);
  *x = m.rest;
  for (int v = 0; v < x->rows(); ++v) x->row(v) += (centre + V3(n(*rng), n(*rng), n(*rng))).transpose();
  *tris = m.surface;
}

std::set<std::pair<int, int>> BruteForcePairs(const Vertices& xa, const Triangles& ta,
                                              const Vertices& xb, const Triangles& tb,
                                              double margin) {
  std::set<std::pair<int, int>> out;
  auto box = [](const Vertices& x, const Triangles& t, int f) {
    Eigen::AlignedBox3d b(V3(x.row(t(f, 0))));
    b.extend(V3(x.row(t(f, 1))));
    b.extend(V3(x.row(t(f, 2))));
    return b;
  };
  for (int i = 0; i < ta.rows(); ++i)
    for (int j = 0; j < tb.rows(); ++j) {
      const auto a = box(xa, ta, i), b = box(xb, tb, j);
      if ((a.min().array() <= b.max().array() + margin).all() &&
          (b.min().array() <= a.max().array() + margin).all())
        out.emplace(i, j);
    }
  return out;
}

TEST(AabbTree, QueriesEqualBruteForceBeforeAndAfterRefit) {
  std::mt19937 rng(3);
  for (int trial = 0; trial < 4; ++trial) {
    Vertices xa, xb;
    Triangles ta, tb;
    RandomSurface(&rng, V3(0, 0, 0), &xa, &ta);
    RandomSurface(&rng, V3(0.15 + 0.02 * trial, 0.03, 0), &xb, &tb);
    AabbTree a, b;
    a.Build(xa, ta);
    b.Build(xb, tb);
    EXPECT_EQ(a.num_nodes(), 2 * ta.rows() - 1);
    for (int pass = 0; pass < 2; ++pass) {
      const double margin = 0.004;
      std::vector<std::pair<int, int>> found;
      a.Overlapping(b, margin, &found);
      const std::set<std::pair<int, int>> got(found.begin(), found.end());
      EXPECT_EQ(got.size(), found.size()) << "no duplicates";
      const auto ref = BruteForcePairs(xa, ta, xb, tb, margin);
      EXPECT_EQ(got, ref);
      EXPECT_GT(ref.size(), 0u);
      // Move b towards a and refit.
      std::normal_distribution<double> n(0, 0.003);
      for (int v = 0; v < xb.rows(); ++v) xb.row(v) += V3(-0.02 + n(rng), n(rng), n(rng)).transpose();
      b.Refit(xb);
    }
  }
}


TEST(PointIndex, NearestMatchesBruteForce) {
  std::mt19937 rng(1);
  std::uniform_real_distribution<double> u(-1, 1);
  Vertices pts(2000, 3);
  for (int i = 0; i < pts.rows(); ++i) pts.row(i) << u(rng), u(rng), u(rng);
  PointIndex index(pts);
  for (int q = 0; q < 500; ++q) {
    const Eigen::Vector3d p(u(rng), u(rng), u(rng));
    int best = -1;
    double best_d2 = 1e30;
    for (int i = 0; i < pts.rows(); ++i) {
      const double d2 = (Eigen::Vector3d(pts.row(i)) - p).squaredNorm();
      if (d2 < best_d2) {
        best_d2 = d2;
        best = i;
      }
    }
    double d2 = 0;
    EXPECT_EQ(index.Nearest(p, &d2), best);
    EXPECT_NEAR(d2, best_d2, 1e-12);
  }
}

TEST(PointIndex, EmptyIndexFindsNothing) {
  PointIndex index(Vertices(0, 3));
  double d2 = 0;
  EXPECT_EQ(index.Nearest(Eigen::Vector3d::Zero(), &d2), -1);
  EXPECT_FALSE(index.AnyWithin(Eigen::Vector3d::Zero(), 1.0));
}

TEST(PointIndex, AnyWithinIsTheNearestDistanceAgainstTheBound) {
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> u(-1, 1);
  Vertices pts(500, 3);
  for (int i = 0; i < pts.rows(); ++i) pts.row(i) << u(rng), u(rng), u(rng);
  const PointIndex index(pts);
  for (int q = 0; q < 300; ++q) {
    const Eigen::Vector3d p(2 * u(rng), 2 * u(rng), 2 * u(rng));  // some far outside the points
    double d2 = 0;
    index.Nearest(p, &d2);
    const double d = std::sqrt(d2);
    EXPECT_TRUE(index.AnyWithin(p, d * (1 + 1e-12)));
    EXPECT_FALSE(index.AnyWithin(p, d * (1 - 1e-9)));
  }
  EXPECT_FALSE(index.AnyWithin(Eigen::Vector3d::Zero(), -1.0));
  // At the last bit: one point, bounds at and next to its distance; the answer is
  // sqrt(squared distance) <= bound, as a test of the nearest distance would give.
  Vertices one(1, 3);
  one << 0.1, -0.2, 0.3;
  const PointIndex single(one);
  const double inf = std::numeric_limits<double>::infinity();
  for (int q = 0; q < 200; ++q) {
    const Eigen::Vector3d p(u(rng), u(rng), u(rng));
    double d2 = 0;
    single.Nearest(p, &d2);
    const double d = std::sqrt(d2);
    for (double bound : {std::nextafter(d, 0.0), d, std::nextafter(d, inf)}) {
      EXPECT_EQ(single.AnyWithin(p, bound), std::sqrt(d2) <= bound) << "bound " << bound;
    }
  }
}

TEST(TriangleClosestPoint, MatchesDenseSampling) {
  std::mt19937 rng(2);
  std::uniform_real_distribution<double> u(-1, 1);
  for (int trial = 0; trial < 200; ++trial) {
    const Eigen::Vector3d a(u(rng), u(rng), u(rng)), b(u(rng), u(rng), u(rng)),
        c(u(rng), u(rng), u(rng)), p(2 * u(rng), 2 * u(rng), 2 * u(rng));
    Eigen::Vector3d bary;
    const Eigen::Vector3d closest = TriangleClosestPoint(p, a, b, c, &bary);
    EXPECT_NEAR(bary.sum(), 1.0, 1e-12);
    EXPECT_GE(bary.minCoeff(), -1e-12);
    const double d = (bary[0] * a + bary[1] * b + bary[2] * c - p).norm();
    EXPECT_LT((closest - (bary[0] * a + bary[1] * b + bary[2] * c)).norm(), 1e-12);
    double brute = 1e30;
    const int n = 200;
    for (int i = 0; i <= n; ++i) {
      for (int j = 0; i + j <= n; ++j) {
        const double s = double(i) / n, t = double(j) / n;
        brute = std::min(brute, ((1 - s - t) * a + s * b + t * c - p).norm());
      }
    }
    EXPECT_LE(d, brute + 1e-12);
    EXPECT_GT(d, brute - 0.02);  // the sampling's resolution
  }
}

// A UV sphere of radius 1 (24 by 12): positions and triangles.
void UvSphere(Vertices* out_pos, Triangles* out_T) {
  const int nu = 24, nv = 12;
  Vertices pos((nv - 1) * nu + 2, 3);
  int k = 0;
  for (int i = 1; i < nv; ++i) {
    for (int j = 0; j < nu; ++j) {
      const double th = M_PI * i / nv, ph = 2 * M_PI * j / nu;
      pos.row(k++) << std::sin(th) * std::cos(ph), std::sin(th) * std::sin(ph), std::cos(th);
    }
  }
  pos.row(k++) << 0, 0, 1;
  pos.row(k++) << 0, 0, -1;
  std::vector<Eigen::Vector3i> tris;
  auto id = [&](int i, int j) { return (i - 1) * nu + (j % nu); };
  for (int i = 1; i < nv - 1; ++i) {
    for (int j = 0; j < nu; ++j) {
      tris.emplace_back(id(i, j), id(i + 1, j), id(i + 1, j + 1));
      tris.emplace_back(id(i, j), id(i + 1, j + 1), id(i, j + 1));
    }
  }
  for (int j = 0; j < nu; ++j) {
    tris.emplace_back(k - 2, id(1, j), id(1, j + 1));
    tris.emplace_back(k - 1, id(nv - 1, j + 1), id(nv - 1, j));
  }
  Triangles T(static_cast<int>(tris.size()), 3);
  for (size_t f = 0; f < tris.size(); ++f) T.row(static_cast<int>(f)) = tris[f].transpose();
  *out_pos = pos;
  *out_T = T;
}

// The squared distance from p to the closest triangle f of T over positions pos (those with
// (*keep)[f] != 0 if given; infinity: none).
double BruteForceSquaredDistance(const Eigen::Vector3d& p, const Vertices& pos, const Triangles& T,
                                 const std::vector<char>* keep = nullptr) {
  double brute = std::numeric_limits<double>::infinity();
  for (int f = 0; f < T.rows(); ++f) {
    if (keep != nullptr && !(*keep)[static_cast<size_t>(f)]) continue;
    const Eigen::Vector3d a = pos.row(T(f, 0)), b = pos.row(T(f, 1)), c = pos.row(T(f, 2));
    brute = std::min(brute, (TriangleClosestPoint(p, a, b, c) - p).squaredNorm());
  }
  return brute;
}

TEST(SurfaceIndex, ClosestMatchesBruteForceOnAClosedSurface) {
  Vertices pos;
  Triangles T;
  UvSphere(&pos, &T);
  SurfaceIndex index(pos, T);
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> u(-1.5, 1.5);
  for (int q = 0; q < 300; ++q) {
    const Eigen::Vector3d p(u(rng), u(rng), u(rng));
    const double brute = BruteForceSquaredDistance(p, pos, T);
    const SurfaceIndex::Hit hit = index.Closest(p);
    ASSERT_GE(hit.triangle, 0);
    EXPECT_NEAR(hit.squared_distance, brute, 1e-9) << "query " << p.transpose();
  }
  // On and just off the surface, where the candidates' bounding spheres all reach the query
  // and the closest triangle is found by its distance alone.
  std::uniform_real_distribution<double> unit(0.0, 1.0), off(-1e-6, 1e-6);
  for (int q = 0; q < 300; ++q) {
    const int f = static_cast<int>(unit(rng) * static_cast<double>(T.rows())) % static_cast<int>(T.rows());
    double s = unit(rng), t = unit(rng);
    if (s + t > 1) s = 1 - s, t = 1 - t;
    const Eigen::Vector3d a = pos.row(T(f, 0)), b = pos.row(T(f, 1)), c = pos.row(T(f, 2));
    const Eigen::Vector3d p = a + s * (b - a) + t * (c - a) + Eigen::Vector3d(off(rng), off(rng), off(rng));
    const SurfaceIndex::Hit hit = index.Closest(p);
    ASSERT_GE(hit.triangle, 0);
    EXPECT_NEAR(hit.squared_distance, BruteForceSquaredDistance(p, pos, T), 1e-15) << "query " << p.transpose();
  }
}

// An index kept while its surface moves (the tracker keeps one while no vertex has moved a
// tenth of an edge; here more, so that the move matters): told the move, its walks still find
// the closest point on the surface where it is now, although its triangles' bounding spheres
// were made where it was.
TEST(SurfaceIndex, KeptWhileTheSurfaceMovesItFindsTheClosestPointWhereItIsNow) {
  Vertices pos;
  Triangles T;
  UvSphere(&pos, &T);
  SurfaceIndex index(pos, T);
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> u(-1.5, 1.5), unit(0.0, 1.0);
  std::vector<Eigen::Vector3d> queries;
  std::vector<int> starts;
  for (int q = 0; q < 300; ++q) {
    // Near the surface, where a small move changes which triangle is closest.
    const Eigen::Vector3d p = Eigen::Vector3d(u(rng), u(rng), u(rng)).normalized() * (0.97 + 0.06 * unit(rng));
    queries.push_back(p);
    starts.push_back(index.Closest(p).triangle);  // the spheres are made here
  }
  // Shifted by about an edge (~0.26), each vertex by up to a tenth of one more on its own.
  double moved = 0.0;
  for (int v = 0; v < pos.rows(); ++v) {
    const Eigen::Vector3d d =
        Eigen::Vector3d(0.2, 0.1, -0.15) + Eigen::Vector3d(u(rng), u(rng), u(rng)).normalized() * 0.03 * unit(rng);
    pos.row(v) += d.transpose();
    moved = std::max(moved, d.norm());
  }
  index.SetMoved(moved);
  int walked = 0;
  for (size_t q = 0; q < queries.size(); ++q) {
    const SurfaceIndex::Hit hit = index.ClosestFrom(queries[q], starts[q], 32);
    walked += hit.triangle != starts[q];
    ASSERT_GE(hit.triangle, 0);
    EXPECT_NEAR(hit.squared_distance, BruteForceSquaredDistance(queries[q], pos, T), 1e-12)
        << "query " << queries[q].transpose();
  }
  EXPECT_GT(walked, 200);  // most queries' closest triangle moved away
}

// The distance bounds hold the closest point's distance, and Closest's own, with queries on,
// near and far from the surface: on a whole surface and on a kept half of it (a facing
// index), before and after a kept index's surface moves by about an edge, with its spheres
// made before the move and after it. They decide most far queries (the occluder passes skip
// the search there).
TEST(SurfaceIndex, DistanceBoundsHoldTheClosestPointsDistance) {
  Vertices rest;
  Triangles T;
  UvSphere(&rest, &T);
  std::vector<char> all(static_cast<size_t>(T.rows()), 1), half(static_cast<size_t>(T.rows()), 0);
  for (int f = 0; f < T.rows(); ++f) half[static_cast<size_t>(f)] = rest(T(f, 0), 2) > 0.0;
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> u(-1.0, 1.0), radius(0.0, 3.0);
  for (const bool halved : {false, true}) {
    for (const bool spheres_after_move : {false, true}) {
      Vertices pos = rest;
      const std::vector<char>& keep = halved ? half : all;
      SurfaceIndex index = halved ? SurfaceIndex(pos, T, half) : SurfaceIndex(pos, T);
      auto check = [&](const std::string& when, int min_decided) {
        int decided = 0;
        for (int q = 0; q < 400; ++q) {
          const Eigen::Vector3d p = q % 50 == 0 ? Eigen::Vector3d(pos.row(q % pos.rows()))  // on a vertex
                                                : Eigen::Vector3d(u(rng), u(rng), u(rng)).normalized() * radius(rng);
          double lower = -1.0, upper = -1.0;
          index.DistanceBounds(p, index.Nearby(p), &lower, &upper);
          const double d = std::sqrt(BruteForceSquaredDistance(p, pos, T, &keep));
          const double found = std::sqrt(index.Closest(p).squared_distance);
          ASSERT_GE(lower, 0.0);
          ASSERT_LE(lower, d * (1.0 + 1e-12)) << when << ", query " << p.transpose();
          ASSERT_LE(lower, found * (1.0 + 1e-12)) << when << ", query " << p.transpose();
          // Closest's distance is within them too: the occluder passes compare it with them.
          ASSERT_GE(upper, d * (1.0 - 1e-12)) << when << ", query " << p.transpose();
          ASSERT_LE(found, upper * (1.0 + 1e-12)) << when << ", query " << p.transpose();
          decided += lower > 0.5;  // half a radius off the surface at least, said without a search
        }
        EXPECT_GE(decided, min_decided) << when;
      };
      const std::string name = std::string(halved ? "half" : "whole") + (spheres_after_move ? ", spheres after" : "");
      if (!spheres_after_move) check(name + ", as made", 100);
      double moved = 0.0;
      for (int v = 0; v < pos.rows(); ++v) {
        const Eigen::Vector3d d = Eigen::Vector3d(0.2, -0.1, 0.15) + 0.03 * Eigen::Vector3d(u(rng), u(rng), u(rng));
        pos.row(v) += d.transpose();
        moved = std::max(moved, d.norm());
      }
      index.SetMoved(moved);
      check(name + ", moved", 40);  // the move widens the bounds: fewer decided
    }
  }
  // An index with no triangle: nothing known.
  const std::vector<char> none(static_cast<size_t>(T.rows()), 0);
  const SurfaceIndex empty(rest, T, none);
  double lower = -1.0, upper = -1.0;
  empty.DistanceBounds(Eigen::Vector3d(0.1, 0.2, 0.3), empty.Nearby(Eigen::Vector3d(0.1, 0.2, 0.3)), &lower, &upper);
  EXPECT_EQ(lower, 0.0);
  EXPECT_EQ(upper, std::numeric_limits<double>::infinity());
}

// A triangle touches vertex v's closed one-ring when a corner is v or shares a triangle with
// v: every (vertex, triangle) pair of a closed surface against that definition.
TEST(SurfaceIndex, TouchesRingIsSharingACornerWithTheOneRing) {
  Vertices pos;
  Triangles T;
  UvSphere(&pos, &T);
  const SurfaceIndex index(pos, T);
  int touching = 0;
  for (int v = 0; v < pos.rows(); ++v) {
    std::set<int> ring = {v};
    for (int f = 0; f < T.rows(); ++f) {
      if (T(f, 0) == v || T(f, 1) == v || T(f, 2) == v) ring.insert({T(f, 0), T(f, 1), T(f, 2)});
    }
    for (int f = 0; f < T.rows(); ++f) {
      const bool expected = ring.count(T(f, 0)) || ring.count(T(f, 1)) || ring.count(T(f, 2));
      ASSERT_EQ(index.TouchesRing(v, f), expected) << "vertex " << v << ", triangle " << f;
      touching += expected;
    }
  }
  EXPECT_GT(touching, 0);
  EXPECT_LT(touching, pos.rows() * T.rows() / 4);  // a ring is a small part of the sphere
  EXPECT_FALSE(index.TouchesRing(0, -1));
  EXPECT_FALSE(index.TouchesRing(0, static_cast<int>(T.rows())));
  EXPECT_FALSE(index.TouchesRing(static_cast<int>(pos.rows()), 0));
}

// Warm-started from the hit of an earlier surface (moved by up to a third of an edge, as
// between outer iterations), or from a triangle two rings away, the walk finds the closest
// point; from a start < 0 it is Closest.
TEST(SurfaceIndex, ClosestFromAnEarlierHitMatchesBruteForce) {
  Vertices rest;
  Triangles T;
  UvSphere(&rest, &T);
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> u(-1.5, 1.5), jitter(-0.04, 0.04);  // edge ~0.26
  Vertices moved = rest;
  for (int v = 0; v < moved.rows(); ++v) {
    for (int c = 0; c < 3; ++c) moved(v, c) += jitter(rng);
  }
  moved.col(0) *= 1.1;  // and stretched
  const SurfaceIndex before(rest, T), after(moved, T);
  int walked = 0;
  for (int q = 0; q < 300; ++q) {
    const Eigen::Vector3d p(u(rng), u(rng), u(rng));
    const double brute = BruteForceSquaredDistance(p, moved, T);
    const int start = before.Closest(p).triangle;
    ASSERT_GE(start, 0);
    const SurfaceIndex::Hit hit = after.ClosestFrom(p, start);
    ASSERT_GE(hit.triangle, 0);
    EXPECT_NEAR(hit.squared_distance, brute, 1e-9) << "query " << p.transpose();
    walked += hit.triangle != start;
    // From two rings away (a triangle sharing a vertex with one that shares a vertex with
    // the closest, but none with the closest).
    auto share = [&](int f, int g) {
      for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j)
          if (T(f, i) == T(g, j)) return true;
      return false;
    };
    int far = -1;
    for (int g = 0; g < T.rows() && far < 0; ++g) {
      if (!share(g, hit.triangle)) continue;
      for (int f = 0; f < T.rows() && far < 0; ++f) {
        if (share(f, g) && !share(f, hit.triangle)) far = f;
      }
    }
    ASSERT_GE(far, 0);
    EXPECT_NEAR(after.ClosestFrom(p, far).squared_distance, brute, 1e-9) << "query " << p.transpose();
    EXPECT_NEAR(after.ClosestFrom(p, -1).squared_distance, after.Closest(p).squared_distance, 1e-12);
  }
  EXPECT_GT(walked, 10);  // the walk, not only the start, found them
}

// A point inside a large element whose centroid is far, among many small elements just
// beyond its face whose centroids are nearer: the large element is found, not the nearest
// small one with extrapolated coordinates (a cage of a scan has such large elements).
TEST(Embedding, APointInALargeElementIsFoundAmongNearerSmallOnes) {
  TetMesh mesh;
  std::vector<Eigen::Vector3d> v = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
  std::vector<std::array<int, 4>> tets = {{0, 1, 2, 3}};
  // 64 smaller elements just beyond the face x + y + z = 1, from (0.34, 0.34, 0.34) on: p is
  // outside each by less than its size (barycentric coordinates above -1).
  for (int i = 0; i < 64; ++i) {
    const Eigen::Vector3d c = Eigen::Vector3d(0.34, 0.34, 0.34) + 0.025 * Eigen::Vector3d(i % 4, (i / 4) % 4, i / 16);
    const int b = static_cast<int>(v.size());
    v.push_back(c);
    v.push_back(c + Eigen::Vector3d(0.02, 0, 0));
    v.push_back(c + Eigen::Vector3d(0, 0.02, 0));
    v.push_back(c + Eigen::Vector3d(0, 0, 0.02));
    tets.push_back({b, b + 1, b + 2, b + 3});
  }
  mesh.rest.resize(static_cast<Eigen::Index>(v.size()), 3);
  for (size_t i = 0; i < v.size(); ++i) mesh.rest.row(static_cast<Eigen::Index>(i)) = v[i].transpose();
  mesh.tets.resize(static_cast<Eigen::Index>(tets.size()), 4);
  for (size_t t = 0; t < tets.size(); ++t) {
    for (int k = 0; k < 4; ++k) mesh.tets(static_cast<Eigen::Index>(t), k) = tets[t][static_cast<size_t>(k)];
  }
  mesh.x = mesh.rest;
  Vertices p(1, 3);
  p << 0.33, 0.33, 0.33;  // inside the large element, 0.006 from its face
  for (bool clamp : {false, true}) {
    const EmbeddedPoints e = EmbedPoints(mesh, p, clamp);
    EXPECT_EQ(e.element[0], 0) << "clamp " << clamp;
    EXPECT_GE(e.barycentric[0].minCoeff(), 0.0) << "clamp " << clamp;
  }
}

}  // namespace
}  // namespace femreg
