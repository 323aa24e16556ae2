// Nearest-neighbour and closest-point queries against brute force.
#include <gtest/gtest.h>

#include <random>

#include "registration/nearest.h"

namespace femreg {
namespace {

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
}

TEST(ClosestPointOnTriangle, MatchesDenseSampling) {
  std::mt19937 rng(2);
  std::uniform_real_distribution<double> u(-1, 1);
  for (int trial = 0; trial < 200; ++trial) {
    const Eigen::Vector3d a(u(rng), u(rng), u(rng)), b(u(rng), u(rng), u(rng)),
        c(u(rng), u(rng), u(rng)), p(2 * u(rng), 2 * u(rng), 2 * u(rng));
    const Eigen::Vector3d bary = ClosestPointOnTriangle(p, a, b, c);
    EXPECT_NEAR(bary.sum(), 1.0, 1e-12);
    EXPECT_GE(bary.minCoeff(), -1e-12);
    const double d = (bary[0] * a + bary[1] * b + bary[2] * c - p).norm();
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

TEST(SurfaceIndex, ClosestMatchesBruteForceOnAClosedSurface) {
  // An octahedron-like closed surface with some refinement: a UV sphere.
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
  SurfaceIndex index(pos, T);
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> u(-1.5, 1.5);
  for (int q = 0; q < 300; ++q) {
    const Eigen::Vector3d p(u(rng), u(rng), u(rng));
    double brute = 1e30;
    for (int f = 0; f < T.rows(); ++f) {
      const Eigen::Vector3d a = pos.row(T(f, 0)), b = pos.row(T(f, 1)), c = pos.row(T(f, 2));
      const Eigen::Vector3d bary = ClosestPointOnTriangle(p, a, b, c);
      brute = std::min(brute, (bary[0] * a + bary[1] * b + bary[2] * c - p).squaredNorm());
    }
    const SurfaceIndex::Hit hit = index.Closest(p);
    ASSERT_GE(hit.triangle, 0);
    EXPECT_NEAR(hit.squared_distance, brute, 1e-9) << "query " << p.transpose();
  }
}

}  // namespace
}  // namespace femreg
