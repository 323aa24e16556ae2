// Fine scans (docs/notes/2026-11-29-fine-scans.md): what a frame computes over the whole scan
// is computed once, or only where it is used, with the same numbers.
#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <cmath>
#include <memory>
#include <random>
#include <vector>

#include "embedded_helpers.h"
#include "femreg/io.h"
#include "femreg/mesh.h"
#include "geometry/nearest.h"
#include "registration/confidence.h"
#include "registration/correspondences.h"
#include "registration/embedded_surface.h"
#include "registration/occluders.h"
#include "registration/prediction.h"
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
  // Row i of the view is the given surface's vertex source()[i].
  auto expected = [&](const Vertices& x) {
    Vertices out(rest.rows(), 3);
    for (Eigen::Index i = 0; i < rest.rows(); ++i) {
      const auto v = static_cast<size_t>(data.source()[static_cast<size_t>(i)]);
      const int e = surface.embedding.element[v];
      const Eigen::Vector4d& b = surface.embedding.barycentric[v];
      out.row(i).setZero();
      for (int k = 0; k < 4; ++k) out.row(i) += b[k] * x.row(cage.tets(e, k));
    }
    return out;
  };
  Vertices x = cage.rest;
  EXPECT_LT((data.Update(x).x - expected(cage.rest)).cwiseAbs().maxCoeff(), 1e-15);
  EXPECT_LT((data.Update(x).x - data.rest()).cwiseAbs().maxCoeff(), 1e-15);
  x = bent;
  EXPECT_LT((data.Update(x).x - expected(bent)).cwiseAbs().maxCoeff(), 1e-15);
  // In place, as the tracker moves state.x: one vertex changed is seen.
  x(5, 1) += 0.01;
  EXPECT_LT((data.Update(x).x - expected(x)).cwiseAbs().maxCoeff(), 1e-15);
  EXPECT_LT((data.Update(x).x - expected(x)).cwiseAbs().maxCoeff(), 1e-15);
  EXPECT_LT((data.Update(cage.rest).x - data.rest()).cwiseAbs().maxCoeff(), 1e-15);
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
  // An embedded surface's subsample, covered where a cloud point lies within the tolerance:
  // about half of its vertices get one (0.2-0.9 mm off; the vertices are 17 mm apart).
  DataSurface data;
  data.Build(state, {&surface});
  const TrackerState& view = data.Update(state.x);
  std::bernoulli_distribution half(0.5);
  std::vector<Eigen::RowVector3d> near;
  for (Eigen::Index v = 0; v < view.x.rows(); ++v) {
    if (half(rng)) near.push_back(view.x.row(v) + Eigen::RowVector3d(u(rng), u(rng), u(rng)).cwiseMin(4e-4) + Eigen::RowVector3d::Constant(1e-4));
  }
  Vertices cloud(static_cast<Eigen::Index>(near.size()), 3);
  for (size_t i = 0; i < near.size(); ++i) cloud.row(static_cast<Eigen::Index>(i)) = near[i];
  fc.index = std::make_unique<PointIndex>(cloud);
  const SurfaceRings view_rings(static_cast<int>(view.x.rows()), view.surface);
  const FrameConfidence embedded = MeasureConfidence(state, fc, {}, 1e-3, &data);
  const FrameConfidence embedded_ringed = MeasureConfidence(state, fc, {}, 1e-3, &data, &view_rings);
  EXPECT_GT(embedded.coverage, 0.1);
  EXPECT_LT(embedded.coverage, 0.9);
  EXPECT_EQ(embedded_ringed.coverage, embedded.coverage);
  // The share of the facing subsample vertices whose nearest point is within the tolerance.
  const Eigen::MatrixXd normals = VertexNormalsAt(view.x, view.surface, view_rings, view.surface_vertices);
  int facing = 0, near_enough = 0;
  for (size_t i = 0; i < view.surface_vertices.size(); ++i) {
    const Eigen::Vector3d p = view.x.row(view.surface_vertices[i]).transpose();
    if (!fc.Faces(p, normals.row(static_cast<Eigen::Index>(i)).transpose())) continue;
    ++facing;
    double d2 = 0;
    fc.index->Nearest(p, &d2);
    near_enough += std::sqrt(d2) <= 1e-3 ? 1 : 0;
  }
  ASSERT_GT(facing, 0);
  EXPECT_EQ(embedded.coverage, static_cast<double>(near_enough) / facing);
  // Every vertex within the tolerance of a point, and none.
  fc.index = std::make_unique<PointIndex>(view.x);
  EXPECT_EQ(MeasureConfidence(state, fc, {}, 1e-3, &data).coverage, 1.0);
  fc.index = std::make_unique<PointIndex>(Vertices(view.x.array() + 2e-3));
  EXPECT_EQ(MeasureConfidence(state, fc, {}, 1e-3, &data).coverage, 0.0);
}

// A sphere of radius r, `rings` x 2 rings of latitude: #F by 3 outward triangles.
void Sphere(double r, int rings, Vertices* x, Triangles* t) {
  const int lat = rings, lon = 2 * rings;
  x->resize(2 + (lat - 1) * lon, 3);
  x->row(0) << 0, 0, r;
  x->row(1) << 0, 0, -r;
  for (int i = 1; i < lat; ++i) {
    for (int j = 0; j < lon; ++j) {
      const double th = M_PI * i / lat, ph = 2 * M_PI * j / lon;
      x->row(2 + (i - 1) * lon + j) << r * std::sin(th) * std::cos(ph), r * std::sin(th) * std::sin(ph), r * std::cos(th);
    }
  }
  auto at = [&](int i, int j) { return 2 + (i - 1) * lon + (j % lon); };
  std::vector<Eigen::Vector3i> f;
  for (int j = 0; j < lon; ++j) {
    f.emplace_back(0, at(1, j), at(1, j + 1));
    f.emplace_back(1, at(lat - 1, j + 1), at(lat - 1, j));
    for (int i = 1; i + 1 < lat; ++i) {
      f.emplace_back(at(i, j), at(i + 1, j), at(i + 1, j + 1));
      f.emplace_back(at(i, j), at(i + 1, j + 1), at(i, j + 1));
    }
  }
  t->resize(static_cast<Eigen::Index>(f.size()), 3);
  for (size_t k = 0; k < f.size(); ++k) t->row(static_cast<Eigen::Index>(k)) = f[k].transpose();
}

// A cloud of n points on the half of surface (x, t) facing +z, a little off it.
Vertices SeenHalf(const Vertices& x, const Triangles& t, int n, std::mt19937* rng) {
  std::uniform_int_distribution<int> face(0, static_cast<int>(t.rows()) - 1);
  std::uniform_real_distribution<double> u(0.0, 1.0), noise(-5e-4, 5e-4);
  Vertices cloud(n, 3);
  for (int i = 0; i < n;) {
    const int f = face(*rng);
    const Eigen::Vector3d a = x.row(t(f, 0)), b = x.row(t(f, 1)), c = x.row(t(f, 2));
    if ((b - a).cross(c - a).z() <= 0) continue;
    double s = u(*rng), r = u(*rng);
    if (s + r > 1) s = 1 - s, r = 1 - r;
    cloud.row(i++) = (a + s * (b - a) + r * (c - a) + Eigen::Vector3d(noise(*rng), noise(*rng), noise(*rng))).transpose();
  }
  return cloud;
}

// The first outer iteration's cloud->model queries of an embedded surface walk from a
// triangle of the nearest subsample vertex (SubsampleStarts): they find the pairs the k-d tree
// search over every surface vertex finds, on a deformed sphere with a subsample of one vertex
// in 9. A walk that has not settled within FrameCloud::seeded_rings is searched in full: with
// one ring most do not, and the pairs are still the same.
TEST(FineScanTest, WalksFromTheSubsampleFindTheTreeSearchsPairs) {
  TrackerState state;
  Sphere(0.05, 40, &state.x, &state.surface);  // edges of about 4 mm
  state.num_vertices = static_cast<int>(state.x.rows());
  const Eigen::Matrix3d turn = Eigen::AngleAxisd(0.3, Eigen::Vector3d(1, 2, 0).normalized()).toRotationMatrix();
  for (int v = 0; v < state.num_vertices; ++v) {
    Eigen::Vector3d p = turn * state.x.row(v).transpose();
    p.x() *= 1.3;
    p.z() += 0.2 * p.x() * p.x() / 0.05;  // bent
    state.x.row(v) = p.transpose();
  }
  for (int v = 0; v < state.num_vertices; v += 9) state.surface_vertices.push_back(v);
  state.vertex_object.assign(static_cast<size_t>(state.num_vertices), 0);
  state.options.data.model_to_cloud = false;  // the cloud->model pairs only
  const SurfaceIndex index(state.x, state.surface);
  std::mt19937 rng(7);
  for (const int stride : {1, 2}) {
    state.options.data.cloud_stride = stride;
    FrameCloud fc;
    fc.cloud.points = SeenHalf(state.x, state.surface, 3000, &rng);
    fc.index = std::make_unique<PointIndex>(fc.cloud.points);
    const int nq = (3000 + stride - 1) / stride;
    std::vector<DataPair> from_tree;
    PairCounts counts;
    FindPairs(state, fc, index, 1, &from_tree, &counts);
    ASSERT_EQ(static_cast<int>(from_tree.size()), nq);
    for (const int rings : {16, 1}) {
      std::vector<int> starts = SubsampleStarts(state, index.rings(), fc.cloud.points, stride, 2);
      ASSERT_EQ(static_cast<int>(starts.size()), nq);
      const std::vector<int> started = starts;
      fc.seeded_rings = rings;
      std::vector<DataPair> seeded;
      FindPairs(state, fc, index, 1, &seeded, &counts, &starts);
      ASSERT_EQ(seeded.size(), from_tree.size());
      int moved_on = 0, unsettled = 0, other = 0;
      for (size_t j = 0; j < seeded.size(); ++j) {
        // The same closest point (on a shared edge either triangle may name it), or a closer
        // one: the tree search tests the triangles around the 4 vertices nearest the query,
        // which on a stretched surface may miss the closest.
        const double d_seeded = (seeded[j].Point(state.x) - seeded[j].target).norm();
        const double d_tree = (from_tree[j].Point(state.x) - from_tree[j].target).norm();
        EXPECT_LE(d_seeded, d_tree + 1e-12) << "query " << j;
        if ((seeded[j].Point(state.x) - from_tree[j].Point(state.x)).norm() > 1e-12) {
          ++other;
          continue;
        }
        EXPECT_LT((seeded[j].normal - from_tree[j].normal).norm(), 1e-9) << "query " << j;
        moved_on += starts[j] != started[j];
        bool settled = true;
        index.ClosestFrom(fc.cloud.points.row(static_cast<Eigen::Index>(j) * stride), started[j], rings, &settled);
        unsettled += !settled;
      }
      EXPECT_LE(other, nq / 500);
      if (rings == 16) {
        EXPECT_GT(moved_on, nq / 2);  // the walks, not the starts, found most of them
        EXPECT_EQ(unsettled, 0);
      } else {
        EXPECT_GT(unsettled, nq / 4);  // searched in full
      }
    }
  }
  // No subsample vertex on a triangle: no starts.
  state.surface_vertices.clear();
  EXPECT_EQ(SubsampleStarts(state, index.rings(), Vertices::Zero(4, 3), 1, 1), std::vector<int>(4, -1));
}

// The occluders' distances walk from the subsample's starts (FrameCloud::seeds), as the first
// outer iteration's queries do: the same points are marked as with the k-d tree search over
// every surface vertex, on a turned sphere seen from a camera with a patch of points in front
// of it (an occluder) and a few beside it; with one ring most walks do not settle and are
// searched in full, the marks again the same.
TEST(FineScanTest, OccludersFromTheSubsampleStartsAreTheTreeSearchs) {
  TrackerState state;
  Sphere(0.05, 40, &state.x, &state.surface);
  state.num_vertices = static_cast<int>(state.x.rows());
  const Eigen::Matrix3d turn = Eigen::AngleAxisd(0.3, Eigen::Vector3d(1, 2, 0).normalized()).toRotationMatrix();
  for (int v = 0; v < state.num_vertices; ++v) state.x.row(v) = (turn * state.x.row(v).transpose()).transpose();
  for (int v = 0; v < state.num_vertices; v += 9) state.surface_vertices.push_back(v);
  state.vertex_object.assign(static_cast<size_t>(state.num_vertices), 0);
  state.mean_edge_length = 0.004;
  state.options.camera.enabled = true;
  state.options.camera.position = Eigen::Vector3d(0, 0, 0.3);
  state.options.camera.target = Eigen::Vector3d::Zero();
  state.options.data.occluders = true;
  const SurfaceIndex index(state.x, state.surface);
  std::mt19937 rng(11);
  // Seeds from 5 mm in front and off the surface: the points lifted off it are decided by
  // their distances to it, some each way.
  state.options.data.occluder_margin = 0.005;
  const Vertices seen = SeenHalf(state.x, state.surface, 2000, &rng);
  const Vertices lifted = SeenHalf(state.x, state.surface, 400, &rng);
  std::uniform_real_distribution<double> u(-0.015, 0.015), lift(0.002, 0.012);
  Vertices points(2000 + 400 + 300 + 40, 3);
  points.topRows(2000) = seen;
  for (int i = 0; i < 400; ++i) {
    const Eigen::Vector3d p = lifted.row(i).transpose();
    points.row(2000 + i) = (p + lift(rng) * p.normalized()).transpose();  // off the sphere
  }
  for (int i = 0; i < 300; ++i) points.row(2400 + i) << u(rng), u(rng), 0.12;  // in front, 7 cm
  for (int i = 0; i < 40; ++i) points.row(2700 + i) << 0.07 + 0.1 * u(rng), u(rng), 0.0;  // beside
  const PointIndex cloud_index(points);
  const double spacing = 0.002;
  std::vector<char> from_tree;
  const OccluderCounts tree = MarkOccluders(state, index, points, cloud_index, spacing, &from_tree);
  ASSERT_GT(tree.seeds, 400);  // the patch in front and part of the lifted points
  ASSERT_LT(tree.seeds, 700);
  ASSERT_FALSE(tree.whole_view);
  const std::vector<int> seeds = SubsampleStarts(state, index.rings(), points, 1, 2);
  for (const int rings : {FrameCloud::kSeedRings, 1}) {
    std::vector<char> seeded;
    const OccluderCounts walked = MarkOccluders(state, index, points, cloud_index, spacing, &seeded, seeds, rings);
    EXPECT_EQ(walked.seeds, tree.seeds) << rings;
    EXPECT_EQ(walked.occluders, tree.occluders) << rings;
    EXPECT_EQ(seeded, from_tree) << rings;
  }
  int unsettled = 0;
  for (int i = 0; i < points.rows(); ++i) {
    bool settled = true;
    index.ClosestFrom(points.row(i), seeds[static_cast<size_t>(i)], 1, &settled);
    unsettled += !settled;
  }
  EXPECT_GT(unsettled, 100);  // with one ring, the full search decided those
}

// Model->cloud: vertices facing away from the sensor are not searched with
// FrameCloud::skip_facing_away, and the pairs are the same, also from a held set whose
// vertices turned away since (those are searched: the set keeps them). They count as trimmed.
TEST(FineScanTest, VerticesFacingAwayAreNotSearchedAndThePairsAreTheSame) {
  TrackerState state;
  Vertices sphere;
  Sphere(0.05, 30, &sphere, &state.surface);
  state.x = sphere;
  state.num_vertices = static_cast<int>(state.x.rows());
  for (int v = 0; v < state.num_vertices; v += 2) state.surface_vertices.push_back(v);
  state.vertex_object.assign(static_cast<size_t>(state.num_vertices), 0);
  std::mt19937 rng(9);
  FrameCloud fc;
  fc.cloud.points = SeenHalf(state.x, state.surface, 2000, &rng);
  fc.index = std::make_unique<PointIndex>(fc.cloud.points);
  fc.view = FrameCloud::View::kCamera;
  fc.eye = Eigen::Vector3d(0.0, 0.0, 0.4);
  fc.trim = 0.004;
  const Eigen::Matrix3d turn = Eigen::AngleAxisd(0.35, Eigen::Vector3d::UnitX()).toRotationMatrix();
  Vertices turned = sphere;
  for (int v = 0; v < state.num_vertices; ++v) turned.row(v) = (turn * sphere.row(v).transpose()).transpose();
  auto pairs_of = [&](bool skip, PairCounts* first_counts, PairCounts* held_counts) {
    fc.skip_facing_away = skip;
    state.x = sphere;
    std::vector<DataPair> first, held;
    std::vector<char> paired;
    {
      const SurfaceIndex index(state.x, state.surface);
      FindPairs(state, fc, index, 1, &first, first_counts, nullptr, &paired);
    }
    state.x = turned;  // some paired vertices now face away: the held set keeps them
    const SurfaceIndex index(state.x, state.surface);
    FindPairs(state, fc, index, 1, &held, held_counts, nullptr, &paired, true);
    first.insert(first.end(), held.begin(), held.end());
    return first;
  };
  PairCounts searched_first, searched_held, skipped_first, skipped_held;
  const std::vector<DataPair> searched = pairs_of(false, &searched_first, &searched_held);
  const std::vector<DataPair> skipped = pairs_of(true, &skipped_first, &skipped_held);
  ASSERT_EQ(searched.size(), skipped.size());
  for (size_t j = 0; j < searched.size(); ++j) {
    EXPECT_EQ(searched[j].num_vertices, skipped[j].num_vertices);
    EXPECT_EQ(searched[j].vertices[0], skipped[j].vertices[0]);
    EXPECT_EQ(searched[j].target, skipped[j].target);
    EXPECT_EQ(searched[j].normal, skipped[j].normal);
  }
  EXPECT_EQ(searched_first.model_to_cloud, skipped_first.model_to_cloud);
  EXPECT_EQ(searched_held.model_to_cloud, skipped_held.model_to_cloud);
  EXPECT_GT(searched_first.model_to_cloud, 100);
  // The held set kept vertices that turned away: more pairs than facing vertices near the cloud.
  int facing_paired = 0;
  {
    const Eigen::MatrixXd n = state.VertexNormals();
    for (size_t j = static_cast<size_t>(searched_first.model_to_cloud + searched_first.cloud_to_model); j < skipped.size(); ++j) {
      const DataPair& p = skipped[j];
      if (p.num_vertices != 1) continue;
      const Eigen::Vector3d x = turned.row(p.vertices[0]);
      facing_paired += fc.Faces(x, n.row(p.vertices[0]).transpose());
    }
  }
  EXPECT_LT(facing_paired, skipped_held.model_to_cloud);
  // Not searched: trimmed, neither covered nor rejected.
  EXPECT_LT(skipped_first.covered + skipped_first.rejected, searched_first.covered + searched_first.rejected);
  EXPECT_GT(skipped_first.trimmed, searched_first.trimmed);
}

// A frame's two starts compare by how far the new cloud lies from them (StartMisfit): one
// short of the body by more than the subsample's spacing fits worse than the body's place, a
// prediction past it worse still, and one that went the other way too; the gate caps each
// distance. On an embedded surface its subsample is what is measured.
TEST(FineScanTest, TheStartNearerTheCloudHasTheSmallerMisfit) {
  ScanOnCage scan;
  TrackerState& state = scan.state;
  DataSurface data;
  data.Build(state, {&scan.surface});
  std::mt19937 rng(11);
  const Vertices rest = state.x;
  auto shifted = [&](double dx) {
    Vertices x = rest;
    x.col(0).array() += dx;
    return x;
  };
  // The cloud: the scan's top face (y = 0.1) and its end (x = 0.2) where the body is, 3 cm
  // along x (the end shows the move along its normal).
  const double at_x = 0.03;
  const Vertices fine = data.Update(shifted(at_x)).x;
  std::vector<int> seen;
  for (Eigen::Index v = 0; v < fine.rows(); ++v) {
    if (std::abs(fine(v, 1) - 0.1) < 1e-9 || std::abs(fine(v, 0) - 0.2 - at_x) < 1e-9) seen.push_back(static_cast<int>(v));
  }
  ASSERT_GT(seen.size(), 20u);
  std::uniform_real_distribution<double> noise(-2e-4, 2e-4);
  Vertices cloud(static_cast<Eigen::Index>(seen.size()), 3);
  for (size_t i = 0; i < seen.size(); ++i) {
    cloud.row(static_cast<Eigen::Index>(i)) = fine.row(seen[i]) + Eigen::RowVector3d(noise(rng), noise(rng), noise(rng));
  }
  const double gate = 0.1;
  const double at = StartMisfit(state, shifted(at_x), cloud, gate, &data);
  const double last = StartMisfit(state, shifted(at_x - 0.02), cloud, gate, &data);    // short of it
  const double past = StartMisfit(state, shifted(at_x + 0.04), cloud, gate, &data);    // overshot
  const double behind = StartMisfit(state, shifted(at_x - 0.05), cloud, gate, &data);  // went back
  EXPECT_LT(at, last);
  EXPECT_LT(last, past);
  EXPECT_LT(last, behind);
  // The mesh's own surface measures too.
  EXPECT_LT(StartMisfit(state, shifted(at_x), cloud, gate), StartMisfit(state, shifted(at_x + 0.04), cloud, gate));
  // Every point beyond the gate counts the gate; no points, nothing.
  const Vertices far = cloud.array() + 1.0;
  EXPECT_NEAR(StartMisfit(state, rest, far, 0.03, &data), 0.03 * 0.03, 1e-15);
  EXPECT_LT(StartMisfit(state, shifted(at_x + 0.04), cloud, 0.01, &data), 0.01 * 0.01 + 1e-15);
  EXPECT_EQ(StartMisfit(state, rest, Vertices(0, 3), gate, &data), 0.0);
}

}  // namespace
}  // namespace femreg
