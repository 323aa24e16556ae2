#include <Eigen/LU>
#include <algorithm>
#include <limits>
#include <vector>

#include "femreg/geometry.h"
#include "geometry/nearest.h"

namespace femreg {

namespace {
// Barycentric coordinates of p in tet t of `mesh` at `positions`.
Eigen::Vector4d Barycentric(const TetMesh& mesh, const Vertices& positions, int t,
                            const Eigen::Vector3d& p) {
  const Eigen::Vector3d a = positions.row(mesh.tets(t, 0));
  Eigen::Matrix3d D;
  for (int k = 0; k < 3; ++k) D.col(k) = positions.row(mesh.tets(t, k + 1)).transpose() - a;
  const Eigen::Vector3d l = D.partialPivLu().solve(p - a);
  return Eigen::Vector4d(1.0 - l.sum(), l.x(), l.y(), l.z());
}
}  // namespace

EmbeddedPoints EmbedPoints(const TetMesh& fine, const Vertices& points, bool clamp) {
  EmbeddedPoints out;
  out.element.assign(static_cast<size_t>(points.rows()), -1);
  out.barycentric.assign(static_cast<size_t>(points.rows()), Eigen::Vector4d::Zero());
  Vertices centroids(fine.num_tets(), 3);
  for (int t = 0; t < fine.num_tets(); ++t) {
    centroids.row(t).setZero();
    for (int k = 0; k < 4; ++k) centroids.row(t) += 0.25 * fine.rest.row(fine.tets(t, k));
  }
  const PointIndex index(centroids);
  constexpr int kCandidates = 32;
  int ids[kCandidates];
  double d2[kCandidates];
  constexpr int kWideCandidates = 256;
  std::vector<int> wide_ids(kWideCandidates);
  std::vector<double> wide_d2(kWideCandidates);
  for (int i = 0; i < points.rows(); ++i) {
    const Eigen::Vector3d p = points.row(i);
    const int n = index.KNearest(p, kCandidates, ids, d2);
    int best = -1;
    double best_min = -std::numeric_limits<double>::infinity();
    Eigen::Vector4d best_bary = Eigen::Vector4d::Zero();
    auto consider = [&](int t) {
      const Eigen::Vector4d b = Barycentric(fine, fine.rest, t, p);
      if (b.minCoeff() > best_min) {
        best_min = b.minCoeff();
        best = t;
        best_bary = b;
      }
    };
    for (int j = 0; j < n; ++j) consider(ids[j]);
    // Not inside any of them: a wider ring of candidates, since beside large or flat elements
    // the one that holds p need not have one of the nearest centroids.
    if (best_min < -1e-9 && n == kCandidates) {
      const int wide = index.KNearest(p, kWideCandidates, wide_ids.data(), wide_d2.data());
      for (int j = 0; j < wide; ++j) consider(wide_ids[static_cast<size_t>(j)]);
    }
    // Still not inside any: search them all (rare; points outside the mesh). An embedded
    // surface has thousands of points just outside its cage, and for those the nearby
    // elements hold the nearest one; only one far outside searches them all.
    if (best_min < (clamp ? -1e-9 : -1.0)) {
      for (int t = 0; t < fine.num_tets(); ++t) consider(t);
    }
    if (clamp && best_min < 0) {
      best_bary = best_bary.cwiseMax(0.0);
      best_bary /= best_bary.sum();
    }
    out.element[static_cast<size_t>(i)] = best;
    out.barycentric[static_cast<size_t>(i)] = best_bary;
  }
  return out;
}

Vertices InterpolateEmbedded(const TetMesh& fine, const Vertices& fine_positions,
                             const EmbeddedPoints& embedded) {
  Vertices out(static_cast<Eigen::Index>(embedded.element.size()), 3);
  for (size_t i = 0; i < embedded.element.size(); ++i) {
    const int t = embedded.element[i];
    Eigen::RowVector3d p = Eigen::RowVector3d::Zero();
    for (int k = 0; k < 4; ++k) p += embedded.barycentric[i][k] * fine_positions.row(fine.tets(t, k));
    out.row(static_cast<Eigen::Index>(i)) = p;
  }
  return out;
}

}  // namespace femreg
