// Fine scans (docs/notes/2026-11-29-fine-scans.md): what a frame computes over the whole scan
// is computed once, or only where it is used, with the same numbers.
#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <cmath>
#include <random>
#include <vector>

#include "embedded_helpers.h"
#include "femreg/io.h"
#include "femreg/mesh.h"
#include "geometry/nearest.h"
#include "registration/confidence.h"
#include "registration/correspondences.h"
#include "registration/embedded_surface.h"
#include "registration/tracker_state.h"

namespace femreg {
namespace {

// A box's surface bent and twisted: normals that differ from vertex to vertex.
Vertices BentBox(const TetMesh& box) {
  Vertices x = box.rest;
  for (Eigen::Index v = 0; v < x.rows(); ++v) {
    const double s = x(v, 0);
    x(v, 1) += 0.3 * s * s + 0.01 * std::sin(40.0 * x(v, 2));
    x(v, 2) += 0.2 * s * x(v, 1);
  }
  return x;
}

// A 12 x 6 x 6 box's surface embedded in a 4 x 2 x 2 cage of the same box, one object.
struct ScanOnCage {
  TetMesh cage = MakeBox(Eigen::Vector3d(0.2, 0.1, 0.1), 4, 2, 2);
  Vertices rest;
  Triangles triangles;
  EmbeddedSurface surface;
  TrackerState state;
  ScanOnCage() {
    const TetMesh fine = MakeBox(Eigen::Vector3d(0.2, 0.1, 0.1), 12, 6, 6);
    SurfaceOf(fine, fine.rest, &rest, &triangles);
    EXPECT_TRUE(MakeEmbeddedSurface(cage, rest, triangles, &surface).ok());
    OneObject(cage, &state);
  }
};

TEST(FineScanTest, NormalsOverTheRingsAreTheWholeSurfacesNormals) {
  const TetMesh box = MakeBox(Eigen::Vector3d(0.2, 0.1, 0.05), 8, 5, 3);
  TrackerState state;
  OneObject(box, &state);
  state.x = BentBox(box);
  const Eigen::MatrixXd all = state.VertexNormals();
  const SurfaceRings rings(static_cast<int>(state.x.rows()), state.surface);
  // Every other surface vertex, an interior vertex (on no triangle: zero) and out of range.
  std::vector<int> vertices;
  for (size_t i = 0; i < state.surface_vertices.size(); i += 2) vertices.push_back(state.surface_vertices[i]);
  int interior = -1;
  for (int v = 0; v < state.num_vertices && interior < 0; ++v) {
    if (!rings.has(v)) interior = v;
  }
  ASSERT_GE(interior, 0);
  vertices.push_back(interior);
  const Eigen::MatrixXd at = VertexNormalsAt(state.x, state.surface, rings, vertices);
  ASSERT_EQ(at.rows(), static_cast<Eigen::Index>(vertices.size()));
  for (size_t i = 0; i < vertices.size(); ++i) {
    // The same sums in the same order: the same numbers, not just close ones.
    EXPECT_EQ(at.row(static_cast<Eigen::Index>(i)), all.row(vertices[i])) << "vertex " << vertices[i];
  }
  EXPECT_EQ(at.row(static_cast<Eigen::Index>(vertices.size()) - 1).norm(), 0.0);
  EXPECT_NEAR(at.row(0).norm(), 1.0, 1e-12);
}

TEST(FineScanTest, AnIndexRebuiltWithTheSameRingsFindsTheSameClosestPoints) {
  const TetMesh box = MakeBox(Eigen::Vector3d(0.2, 0.1, 0.05), 8, 5, 3);
  TrackerState state;
  OneObject(box, &state);
  ModelIndex model;
  const SurfaceRings* rings = &model.Rings(state);
  const SurfaceIndex* first = &model.Get(state, 1e-3);
  EXPECT_EQ(model.builds(), 1);
  EXPECT_EQ(&first->rings(), rings);
  // A move below the tolerance keeps the index; one beyond it rebuilds it on the same rings.
  state.x.array() += 1e-4;
  model.Get(state, 1e-3);
  EXPECT_EQ(model.builds(), 1);
  state.x = BentBox(box);
  const SurfaceIndex& moved = model.Get(state, 1e-3);
  EXPECT_EQ(model.builds(), 2);
  EXPECT_EQ(&moved.rings(), rings);
  EXPECT_EQ(&model.Rings(state), rings);
  const SurfaceIndex fresh(state.x, state.surface);
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> u(-0.05, 0.25);
  for (int k = 0; k < 300; ++k) {
    const Eigen::Vector3d q(u(rng), 0.5 * u(rng), 0.3 * u(rng));
    const SurfaceIndex::Hit a = moved.Closest(q), b = fresh.Closest(q);
    EXPECT_EQ(a.triangle, b.triangle);
    EXPECT_EQ(a.squared_distance, b.squared_distance);
    const int v = state.surface(b.triangle, 0);
    EXPECT_EQ(moved.TouchesRing(v, b.triangle), fresh.TouchesRing(v, b.triangle));
  }
  // Another surface (a new topology) gets new rings.
  TrackerState other;
  OneObject(MakeBox(Eigen::Vector3d(0.1, 0.1, 0.1), 2, 2, 2), &other);
  EXPECT_EQ(model.Rings(other).num_vertices(), other.num_vertices);
  EXPECT_EQ(model.Get(other, 1e-3).rings().num_vertices(), other.num_vertices);
}

TEST(FineScanTest, TheDataSurfaceFollowsEveryChangeOfTheCageAndOnlyThose) {
  ScanOnCage scan;
  const TetMesh& cage = scan.cage;
  const Vertices& rest = scan.rest;
  const EmbeddedSurface& surface = scan.surface;
  const TrackerState& state = scan.state;
  DataSurface data;
  data.Build(state, {&surface});
  const Vertices bent = BentBox(cage);
  auto expected = [&](const Vertices& x) {
    Vertices out(rest.rows(), 3);
    for (Eigen::Index v = 0; v < rest.rows(); ++v) {
      const int e = surface.embedding.element[static_cast<size_t>(v)];
      const Eigen::Vector4d& b = surface.embedding.barycentric[static_cast<size_t>(v)];
      out.row(v).setZero();
      for (int k = 0; k < 4; ++k) out.row(v) += b[k] * x.row(cage.tets(e, k));
    }
    return out;
  };
  Vertices x = cage.rest;
  EXPECT_LT((data.Update(x).x - rest).cwiseAbs().maxCoeff(), 1e-15);
  x = bent;
  EXPECT_LT((data.Update(x).x - expected(bent)).cwiseAbs().maxCoeff(), 1e-15);
  // In place, as the tracker moves state.x: one vertex changed is seen.
  x(5, 1) += 0.01;
  EXPECT_LT((data.Update(x).x - expected(x)).cwiseAbs().maxCoeff(), 1e-15);
  EXPECT_LT((data.Update(x).x - expected(x)).cwiseAbs().maxCoeff(), 1e-15);
  EXPECT_LT((data.Update(cage.rest).x - rest).cwiseAbs().maxCoeff(), 1e-15);
}

TEST(FineScanTest, TheCoverageOverTheRingsIsTheWholeSurfaces) {
  ScanOnCage scan;
  const EmbeddedSurface& surface = scan.surface;
  TrackerState& state = scan.state;
  state.x = BentBox(scan.cage);
  FrameCloud fc;
  fc.view = FrameCloud::View::kCamera;
  fc.eye = Eigen::Vector3d(0.1, 0.3, 0.4);  // sees some faces, not others
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> u(0.0, 2e-3);
  for (Eigen::Index v = 0; v < state.residuals[0].size(); ++v) state.residuals[0](v) = u(rng);
  // The mesh's own surface.
  const SurfaceRings rings(static_cast<int>(state.x.rows()), state.surface);
  const FrameConfidence whole = MeasureConfidence(state, fc, {}, 1e-3);
  const FrameConfidence ringed = MeasureConfidence(state, fc, {}, 1e-3, nullptr, &rings);
  EXPECT_GT(whole.coverage, 0.1);
  EXPECT_LT(whole.coverage, 0.9);
  EXPECT_EQ(ringed.coverage, whole.coverage);
  // An embedded surface's subsample.
  DataSurface data;
  data.Build(state, {&surface});
  const TrackerState& view = data.Update(state.x);
  for (Eigen::Index v = 0; v < data.residuals.size(); ++v) data.residuals(v) = u(rng);
  const SurfaceRings view_rings(static_cast<int>(view.x.rows()), view.surface);
  const FrameConfidence embedded = MeasureConfidence(state, fc, {}, 1e-3, &data);
  const FrameConfidence embedded_ringed = MeasureConfidence(state, fc, {}, 1e-3, &data, &view_rings);
  EXPECT_GT(embedded.coverage, 0.1);
  EXPECT_LT(embedded.coverage, 0.9);
  EXPECT_EQ(embedded_ringed.coverage, embedded.coverage);
}

}  // namespace
}  // namespace femreg
