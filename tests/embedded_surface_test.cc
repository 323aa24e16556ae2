// Embedded surfaces (objects[i].surface): the mapping of a fine surface into coarse
// tetrahedra, its data blocks, and tracking with the data terms on the fine surface.
#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <memory>
#include <random>
#include <set>
#include <vector>

#include "bending_beam.h"
#include "embedded_helpers.h"
#include "femreg/collision_spec.h"
#include "femreg/experiment.h"
#include "femreg/forward.h"
#include "femreg/ground_truth.h"
#include "femreg/io.h"
#include "femreg/meshing.h"
#include "femreg/point_cloud.h"
#include "femreg/scene.h"
#include "femreg/synth.h"
#include "femreg/tracker.h"
#include "geometry/nearest.h"
#include "registration/confidence.h"
#include "registration/embedded_surface.h"
#include "registration/tracker_state.h"

namespace femreg {
namespace {

using bending_beam::Foam;
using bending_beam::kLength;
using bending_beam::kWidth;
using bending_beam::Sensor;

TEST(EmbeddedSurfaceTest, VerticesOutsideTheCageAreExtrapolatedNotClamped) {
  const TetMesh cage = MakeBox(Eigen::Vector3d(0.1, 0.1, 0.1), 2, 2, 2);
  Vertices points(3, 3);
  points << 0.05, 0.05, 0.05,   // inside
      0.1 + 2e-3, 0.03, 0.07,   // 2 mm outside the face x = 0.1
      -1e-3, -1e-3, 0.02;       // just outside an edge
  Triangles triangles(1, 3);
  triangles << 0, 1, 2;
  EmbeddedSurface surface;
  ASSERT_TRUE(MakeEmbeddedSurface(cage, points, triangles, &surface).ok());
  EXPECT_NEAR(surface.outside, 2e-3, 1e-9);
  // The rest shape is reproduced exactly, also outside.
  const Vertices back = InterpolateEmbedded(cage, cage.rest, surface.embedding);
  EXPECT_LT((back - points).cwiseAbs().maxCoeff(), 1e-14);
  EXPECT_LT(surface.embedding.barycentric[1].minCoeff(), 0.0);
  // The generators' embedding still clamps (their ground truth is inside the body).
  const EmbeddedPoints clamped = EmbedPoints(cage, points);
  EXPECT_GE(clamped.barycentric[1].minCoeff(), 0.0);
}

TEST(EmbeddedSurfaceTest, RefusesBadSurfaces) {
  const TetMesh cage = MakeBox(Eigen::Vector3d(0.1, 0.1, 0.1), 1, 1, 1);
  EmbeddedSurface surface;
  Vertices v(3, 3);
  v.setZero();
  Triangles bad(1, 3);
  bad << 0, 1, 3;
  EXPECT_FALSE(MakeEmbeddedSurface(cage, v, bad, &surface).ok());
  EXPECT_FALSE(MakeEmbeddedSurface(cage, Vertices(0, 3), Triangles(0, 3), &surface).ok());
}

// An affine motion of the cage moves every embedded vertex, and every point on an embedded
// triangle as the data blocks see it, by the same affine map: exactly, inside or not.
TEST(EmbeddedSurfaceTest, DataSurfaceFollowsAnAffineMotionExactly) {
  const TetMesh cage = MakeBox(Eigen::Vector3d(0.2, 0.1, 0.1), 4, 2, 2);
  const TetMesh fine = MakeBox(Eigen::Vector3d(0.204, 0.104, 0.104), 20, 10, 10, Eigen::Vector3d(-2e-3, -2e-3, -2e-3));
  Vertices rest;
  Triangles triangles;
  SurfaceOf(fine, fine.rest, &rest, &triangles);
  EmbeddedSurface surface;
  ASSERT_TRUE(MakeEmbeddedSurface(cage, rest, triangles, &surface).ok());
  EXPECT_GT(surface.outside, 1e-3);  // the fine box is 2 mm larger
  TrackerState state;
  OneObject(cage, &state);
  DataSurface data;
  data.Build(state, {&surface});
  ASSERT_TRUE(data.embedded(0));
  EXPECT_EQ(data.view().num_vertices, rest.rows());
  // The model->cloud vertices: one per voxel of a third of the cage's mean edge (about 20 mm
  // here, against the fine surface's 10 mm), standing for all the surface's area.
  EXPECT_LT(data.view().surface_vertices.size(), static_cast<size_t>(rest.rows()) / 2);
  double area = 0.0, picked = 0.0;
  for (Eigen::Index f = 0; f < triangles.rows(); ++f) {
    const Eigen::Vector3d a = rest.row(triangles(f, 0)), b = rest.row(triangles(f, 1)), c = rest.row(triangles(f, 2));
    area += 0.5 * (b - a).cross(c - a).norm();
  }
  for (int v : data.view().surface_vertices) picked += data.pair_area()[static_cast<size_t>(v)];
  EXPECT_NEAR(picked, area, 1e-12 * area);
  Eigen::Matrix3d A;
  A << 1.1, 0.05, 0.0, -0.02, 0.95, 0.1, 0.03, 0.0, 1.02;
  const Eigen::Vector3d t(0.01, -0.02, 0.005);
  const Vertices x = ((cage.rest * A.transpose()).rowwise() + t.transpose()).eval();
  const TrackerState& view = data.Update(x);
  // The view holds the surface in its own order (source(): the given vertex of each row), with
  // the given triangles renumbered.
  ASSERT_EQ(data.source().size(), static_cast<size_t>(rest.rows()));
  std::vector<int> row_of(static_cast<size_t>(rest.rows()), -1);
  for (size_t i = 0; i < data.source().size(); ++i) row_of[static_cast<size_t>(data.source()[i])] = static_cast<int>(i);
  EXPECT_EQ(std::count(row_of.begin(), row_of.end(), -1), 0);  // a permutation
  std::set<std::array<int, 3>> given, viewed;
  auto rotated = [](int a, int b, int c) {  // a triangle from its smallest corner, orientation kept
    if (a < b && a < c) return std::array<int, 3>{{a, b, c}};
    if (b < c) return std::array<int, 3>{{b, c, a}};
    return std::array<int, 3>{{c, a, b}};
  };
  for (Eigen::Index f = 0; f < triangles.rows(); ++f) given.insert(rotated(triangles(f, 0), triangles(f, 1), triangles(f, 2)));
  for (Eigen::Index f = 0; f < view.surface.rows(); ++f) {
    viewed.insert(rotated(data.source()[static_cast<size_t>(view.surface(f, 0))], data.source()[static_cast<size_t>(view.surface(f, 1))],
                          data.source()[static_cast<size_t>(view.surface(f, 2))]));
  }
  EXPECT_EQ(viewed, given);
  const Vertices expected = ((rest * A.transpose()).rowwise() + t.transpose()).eval();
  for (Eigen::Index i = 0; i < view.x.rows(); ++i) {
    EXPECT_LT((view.x.row(i) - expected.row(data.source()[static_cast<size_t>(i)])).cwiseAbs().maxCoeff(), 1e-13);
  }
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  for (int k = 0; k < 200; ++k) {
    const int f = static_cast<int>(rng() % static_cast<unsigned>(triangles.rows()));
    Eigen::Vector3d b(u(rng), u(rng), u(rng));
    b /= b.sum();
    DataPair pair;
    pair.num_vertices = 3;
    for (int j = 0; j < 3; ++j) pair.vertices[j] = row_of[static_cast<size_t>(triangles(f, j))];
    pair.barycentric = b;
    const DataSurface::Stencil st = data.Map(pair);
    ASSERT_EQ(st.n, 4);
    Eigen::Vector3d p = Eigen::Vector3d::Zero();
    double sum = 0.0;
    for (int j = 0; j < 4; ++j) {
      p += st.weights[static_cast<size_t>(j)] * x.row(st.vertices[static_cast<size_t>(j)]).transpose();
      sum += st.weights[static_cast<size_t>(j)];
    }
    EXPECT_NEAR(sum, 1.0, 1e-12);
    // Four distinct vertices of one element (a Ceres parameter block once each).
    std::array<int, 4> sorted = st.vertices;
    std::sort(sorted.begin(), sorted.end());
    EXPECT_TRUE(std::adjacent_find(sorted.begin(), sorted.end()) == sorted.end());
    EXPECT_LT((p - pair.Point(view.x)).norm(), 1e-13);
  }
}

// The bending beam (bending_beam.h, tracker_test.cc's sequence), tracked by a coarse cage that
// carries the fine mesh's surface; the ground truth is that surface's vertices.
struct Sequence {
  Vertices surface_rest;
  Triangles surface_triangles;
  std::vector<PointCloud> clouds;
  std::vector<GroundTruthFrame> surface_truth;
};

const Sequence& BendingSequence() {
  static const Sequence* seq = [] {
    auto* s = new Sequence;
    const TetMesh fine = bending_beam::FineBeam();
    SurfaceOf(fine, fine.rest, &s->surface_rest, &s->surface_triangles);
    bending_beam::BendFineBeam(8, 0.04, 100, [&](const bending_beam::BeamFrame& frame) {
      s->clouds.push_back(frame.cloud);
      GroundTruthFrame gt;
      Triangles unused;
      SurfaceOf(frame.fine, frame.fine.x, &gt.positions, &unused);
      gt.visible = frame.sensor.Visible(frame.image, gt.positions, 2e-3);
      s->surface_truth.push_back(gt);
    });
    return s;
  }();
  return *seq;
}

TetMesh Cage() {
  // 10 by 2 by 2 cells, 1 mm larger than the beam on every side (the fine mesh has 20 by 4 by 4).
  return MakeBox(Eigen::Vector3d(kLength + 2e-3, kWidth + 2e-3, kWidth + 2e-3), 10, 2, 2,
                 Eigen::Vector3d(-1e-3, -1e-3, -1e-3));
}

std::unique_ptr<Tracker> CageTracker(int threads, bool embed = true,
                                     SolverBackend backend = SolverBackend::kFast) {
  RegistrationOptions o;
  o.solver.backend = backend;
  o.camera = Sensor().camera;
  o.data.visibility = true;
  o.solver.max_outer_iterations = 8;
  o.solver.num_threads = threads;
  const TetMesh cage = Cage();
  std::unique_ptr<Tracker> tracker;
  Status status = Tracker::Create({cage}, {Foam()}, o, &tracker);
  EXPECT_TRUE(status.ok()) << status.message();
  std::vector<int> clamped;
  for (int v = 0; v < cage.num_vertices(); ++v) {
    if (cage.rest(v, 0) < 0.0) clamped.push_back(v);
  }
  EXPECT_TRUE(tracker->AddAnchor("clamp", 0, clamped, /*hard=*/true).ok());
  const Sequence& seq = BendingSequence();
  if (embed) {
    status = tracker->SetEmbeddedSurface(0, seq.surface_rest, seq.surface_triangles);
    EXPECT_TRUE(status.ok()) << status.message();
  }
  return tracker;
}

// The mean over the frames of the fine surface's errors, tracked with the data on the fine
// surface (embed) or on the cage's own surface (the fine surface then carried along).
struct SurfaceErrors {
  double seen = 0.0, hidden = 0.0, max = 0.0;
};
SurfaceErrors TrackBeam(bool embed) {
  const Sequence& seq = BendingSequence();
  std::unique_ptr<Tracker> tracker = CageTracker(1, embed);
  const EmbeddedPoints carried = EmbedPoints(Cage(), seq.surface_rest, /*clamp=*/false);
  SurfaceErrors out;
  for (size_t f = 0; f < seq.clouds.size(); ++f) {
    FrameSummary summary;
    EXPECT_TRUE(tracker->Track(seq.clouds[f], &summary).ok());
    EXPECT_TRUE(summary.IsSolutionUsable()) << summary.FullReport();
    const Vertices surface = embed ? tracker->surface_vertices(0)
                                   : InterpolateEmbedded(Cage(), tracker->vertices(0), carried);
    const VertexErrors e = ComputeVertexErrors(surface, seq.surface_truth[f]);
    out.seen += e.seen.mean / static_cast<double>(seq.clouds.size());
    out.hidden += e.hidden.mean / static_cast<double>(seq.clouds.size());
    out.max = std::max(out.max, e.all.max);
  }
  return out;
}

TEST(EmbeddedSurfaceTrackingTest, TheFineSurfaceFollowsTheBendingBeam) {
  const Sequence& seq = BendingSequence();
  std::unique_ptr<Tracker> tracker = CageTracker(1);
  ASSERT_TRUE(tracker->has_embedded_surface(0));
  EXPECT_EQ(tracker->surface_vertices(0).rows(), seq.surface_rest.rows());
  EXPECT_EQ(tracker->surface_triangles(0).rows(), seq.surface_triangles.rows());
  EXPECT_EQ(tracker->surface_outside(0), 0.0);  // the cage is larger
  double worst_move = 0.0;
  for (const GroundTruthFrame& t : seq.surface_truth) {
    worst_move = std::max(worst_move, (t.positions - seq.surface_rest).rowwise().norm().maxCoeff());
  }
  EXPECT_GT(worst_move, 0.035);  // the end dropped 4 cm and turned
  const SurfaceErrors embedded = TrackBeam(true), cage = TrackBeam(false);
  // tracker_test.cc's bounds for this sequence tracked by a mesh of this resolution.
  EXPECT_LT(embedded.seen, 1.0e-3);
  EXPECT_LT(embedded.hidden, 1.2e-3);
  EXPECT_LT(embedded.max, 8e-3);
  // The cage's own surface, 1 mm outside the beam, fits the cloud 1 mm off: the data on the
  // fine surface do better where it is seen.
  EXPECT_LT(embedded.seen, cage.seen - 0.3e-3);
  std::printf("surface errors (mm): embedded seen %.3f hidden %.3f max %.3f; cage seen %.3f hidden %.3f max %.3f\n",
              1e3 * embedded.seen, 1e3 * embedded.hidden, 1e3 * embedded.max, 1e3 * cage.seen, 1e3 * cage.hidden,
              1e3 * cage.max);
}

TEST(EmbeddedSurfaceTrackingTest, TheSameAnswerOnOneAndTwoThreads) {
  const Sequence& seq = BendingSequence();
  std::unique_ptr<Tracker> one = CageTracker(1), two = CageTracker(2);
  for (size_t f = 0; f < seq.clouds.size(); ++f) {
    FrameSummary a, b;
    ASSERT_TRUE(one->Track(seq.clouds[f], &a).ok());
    ASSERT_TRUE(two->Track(seq.clouds[f], &b).ok());
    const Vertices pa = one->surface_vertices(0), pb = two->surface_vertices(0);
    EXPECT_LT((pa - pb).cwiseAbs().maxCoeff(), 1e-9 * (1.0 + pa.cwiseAbs().maxCoeff())) << "frame " << f;
    // The pairs' residual is measured on the fine surface they were found on.
    EXPECT_TRUE(std::isfinite(a.rms_residual)) << "frame " << f;
    EXPECT_LT(a.rms_residual, 5e-3) << "frame " << f;
    EXPECT_NEAR(a.rms_residual, b.rms_residual, 1e-9) << "frame " << f;
  }
}

// The four-vertex data blocks through Ceres' generic cost: the same fit as the fast back end.
TEST(EmbeddedSurfaceTrackingTest, TheCeresBackEndTakesTheEmbeddedSurface) {
  const Sequence& seq = BendingSequence();
  std::unique_ptr<Tracker> ceres = CageTracker(1, true, SolverBackend::kCeres), fast = CageTracker(1);
  for (size_t f = 0; f < 3; ++f) {
    FrameSummary a, b;
    ASSERT_TRUE(ceres->Track(seq.clouds[f], &a).ok());
    ASSERT_TRUE(fast->Track(seq.clouds[f], &b).ok());
    EXPECT_TRUE(a.IsSolutionUsable()) << a.FullReport();
    EXPECT_GT(a.cloud_to_model, 0);
    const double ec = ComputeVertexErrors(ceres->surface_vertices(0), seq.surface_truth[f]).seen.mean;
    const double ef = ComputeVertexErrors(fast->surface_vertices(0), seq.surface_truth[f]).seen.mean;
    EXPECT_LT(ec, ef + 0.2e-3) << "frame " << f;
  }
}

TEST(EmbeddedSurfaceTrackingTest, RefusesLabelsAndFracture) {
  std::unique_ptr<Tracker> tracker = CageTracker(1);
  EXPECT_FALSE(tracker->SetObjectLabel(0, 3).ok());
  EXPECT_FALSE(tracker->EnableFracture({FractureOptions()}).ok());
  EXPECT_FALSE(tracker->SetEmbeddedSurface(1, Vertices(0, 3), Triangles(0, 3)).ok());
}

// femreg mesh --cage: about the vertex count asked for, every surface vertex inside.
// Contacts on the fine surface: a stiff block's scan rests on a table plane while its cage
// stops 1 mm above the table (the scan's bottom sticks out of the cage, its coordinates
// extrapolated). Contacts on the cage's surface would let the scan sink 1 mm into the table
// under its weight; on the scan they hold it there and carry the weight.
struct TableRun {
  FrameSummary rest, pulled;
  double weight = 0.0;                          // N
  double lowest_rest = 0.0, lowest_pulled = 0.0;  // the scan's lowest z (m)
  double cage_lowest = 0.0;                     // the cage's lowest z at rest (m)
  double mu = 0.0;
};

// Points every 2 mm on the top face of the scan (z = 21 mm), 4 mm in from its edges, with
// its normal; `drop` moves them down.
PointCloud TopOfTheScan(double drop) {
  PointCloud cloud;
  const int n = 17;
  cloud.points.resize(n * n, 3);
  cloud.normals.resize(n * n, 3);
  for (int i = 0; i < n; ++i)
    for (int j = 0; j < n; ++j) {
      cloud.points.row(i * n + j) << 0.004 + 0.002 * i, 0.004 + 0.002 * j, 0.021 - drop;
      cloud.normals.row(i * n + j) << 0, 0, 1;
    }
  return cloud;
}

// collision_first: contacts enabled before the surface is set (the world is then rebuilt).
TableRun RestOnATable(int threads, double mu = 0.0, bool collision_first = false) {
  TableRun run;
  run.mu = mu;
  Material stiff;
  stiff.youngs_modulus = 1e8;
  stiff.poisson_ratio = 0.3;
  stiff.density = 1000;
  RegistrationOptions o;
  o.weights.temporal = 1000;
  o.solver.num_threads = threads;
  o.solver.max_outer_iterations = 20;
  const TetMesh cage = MakeBox(Eigen::Vector3d(0.04, 0.04, 0.02), 4, 4, 2, Eigen::Vector3d(0, 0, 0.001));
  const TetMesh fine = MakeBox(Eigen::Vector3d(0.04, 0.04, 0.021), 16, 16, 7);
  Vertices scan;
  Triangles triangles;
  SurfaceOf(fine, fine.rest, &scan, &triangles);
  std::unique_ptr<Tracker> tracker;
  Status status = Tracker::Create({cage}, {stiff}, o, &tracker);
  EXPECT_TRUE(status.ok()) << status.message();
  if (!tracker) return run;
  CollisionSpec spec;
  spec.friction = mu;
  ObstacleSpec table;
  table.name = "table";
  spec.obstacles.push_back(table);  // the plane z = 0
  if (collision_first) {
    EXPECT_TRUE(tracker->EnableCollision(spec, {"block"}).ok());
  }
  status = tracker->SetEmbeddedSurface(0, scan, triangles);
  EXPECT_TRUE(status.ok()) << status.message();
  EXPECT_NEAR(tracker->surface_outside(0), 1e-3, 1e-9);
  if (!collision_first) {
    status = tracker->EnableCollision(spec, {"block"});
    EXPECT_TRUE(status.ok()) << status.message();
  }
  EXPECT_TRUE(tracker->SetExternalLoads(0, Eigen::Vector3d(0, 0, -9.81), {}).ok());
  run.weight = tracker->mesh(0).mass.sum() * 9.81;
  for (int f = 0; f < 4; ++f) EXPECT_TRUE(tracker->Track(TopOfTheScan(0.0), &run.rest).ok());
  run.lowest_rest = tracker->surface_vertices(0).col(2).minCoeff();
  run.cage_lowest = tracker->vertices(0).col(2).minCoeff();
  // A cloud 5 mm lower pulls the block into the table.
  for (int f = 0; f < 3; ++f) EXPECT_TRUE(tracker->Track(TopOfTheScan(0.005), &run.pulled).ok());
  run.lowest_pulled = tracker->surface_vertices(0).col(2).minCoeff();
  return run;
}

TEST(EmbeddedSurfaceContactTest, TheScanRestsOnTheTableWhereTheCageDoesNotTouchIt) {
  const TableRun run = RestOnATable(1);
  ASSERT_TRUE(run.rest.IsSolutionUsable()) << run.rest.FullReport();
  // The scan touches the table (gap within the tolerance, 0.2 mm) and does not sink into it;
  // the cage stays about 1 mm above it.
  EXPECT_GE(run.lowest_rest, -0.25e-3) << run.rest.FullReport();
  EXPECT_LE(run.lowest_rest, 0.25e-3) << run.rest.FullReport();
  EXPECT_LE(run.rest.max_penetration, 0.25e-3);
  EXPECT_NEAR(run.cage_lowest, 1e-3, 0.3e-3);
  EXPECT_GT(run.rest.contacts, 0);
  // The table carries the weight: its force balances the load (the data's pull is small).
  ASSERT_EQ(run.rest.contact_forces.size(), 1u);
  const ContactForce& f = run.rest.contact_forces[0];
  EXPECT_EQ(f.object, 0);
  EXPECT_EQ(f.other, -1);
  EXPECT_NEAR(f.force.z(), run.weight, 0.01 * run.weight) << run.rest.FullReport();
  EXPECT_LT(f.force.head<2>().norm(), 0.01 * run.weight);
  EXPECT_NEAR(run.rest.force.z(), run.weight, 0.01 * run.weight);
  // Pulled 5 mm into the table by the cloud: the scan holds within the tolerance.
  ASSERT_TRUE(run.pulled.IsSolutionUsable()) << run.pulled.FullReport();
  EXPECT_GE(run.lowest_pulled, -0.25e-3) << run.pulled.FullReport();
  EXPECT_NEAR(-std::min(0.0, run.lowest_pulled), run.pulled.max_penetration, 1e-9);
  std::printf("scan lowest at rest %.4f mm (cage %.4f mm), pulled %.4f mm; table force / weight %.4f\n",
              1e3 * run.lowest_rest, 1e3 * run.cage_lowest, 1e3 * run.lowest_pulled, f.force.z() / run.weight);
  // The same with contacts enabled before the surface was set.
  const TableRun first = RestOnATable(1, 0.0, true);
  EXPECT_NEAR(first.lowest_pulled, run.lowest_pulled, 1e-12);
  EXPECT_NEAR(first.lowest_rest, run.lowest_rest, 1e-12);
}

TEST(EmbeddedSurfaceContactTest, FrictionOnTheScanAndTheSameAnswerOnOneAndTwoThreads) {
  const TableRun one = RestOnATable(1, 0.5), two = RestOnATable(2, 0.5);
  ASSERT_TRUE(one.pulled.IsSolutionUsable()) << one.pulled.FullReport();
  EXPECT_GE(one.lowest_pulled, -0.25e-3);
  ASSERT_EQ(one.rest.contact_forces.size(), 1u);
  EXPECT_NEAR(one.rest.contact_forces[0].force.z(), one.weight, 0.01 * one.weight);
  EXPECT_NEAR(one.lowest_pulled, two.lowest_pulled, 1e-9);
  EXPECT_NEAR(one.lowest_rest, two.lowest_rest, 1e-9);
  ASSERT_EQ(two.rest.contact_forces.size(), 1u);
  EXPECT_NEAR(one.rest.contact_forces[0].force.z(), two.rest.contact_forces[0].force.z(), 1e-6 * one.weight);
}

TEST(CageTest, EnclosesTheSurfaceWithAboutTheVerticesAsked) {
  const TetMesh sphere = MakeSphere(0.05, 10);
  Vertices surface;
  Triangles triangles;
  SurfaceOf(sphere, sphere.rest, &surface, &triangles);
  TetMesh cage;
  CageReport report;
  const Status status = MakeCage(surface, triangles, 150, MeshingOptions(), &cage, &report, "sphere");
  ASSERT_TRUE(status.ok()) << status.message();
  EXPECT_NEAR(cage.num_vertices(), 150, 0.3 * 150);
  EXPECT_LT(cage.num_vertices(), surface.rows() / 2);
  // The coarse remesh cuts chords: most of the sphere is outside it before the move.
  EXPECT_GT(report.outside_before, surface.rows() / 4);
  EXPECT_EQ(report.outside_vertices, 0);
  EmbeddedSurface embedded;
  ASSERT_TRUE(MakeEmbeddedSurface(cage, surface, triangles, &embedded).ok());
  EXPECT_LT(embedded.outside, 1e-9);
  // The move is local and small: the cage's volume stays within 15 % of the sphere's.
  EXPECT_LT(RestVolume(cage), 1.15 * RestVolume(sphere));
}

// objects[i].surface in a scene file: read, posed with the object, handed to the tracker,
// written back, overridable with --set; a missing file or another format is refused with the
// field's name.
TEST(EmbeddedSurfaceSceneTest, TheSceneKeyIsParsedWrittenAndOverridden) {
  namespace fs = std::filesystem;
  const fs::path dir = fs::temp_directory_path() / ("femreg_embedded_scene_" + std::to_string(::getpid()));
  fs::create_directories(dir);
  const TetMesh fine = MakeBox(Eigen::Vector3d(0.1, 0.04, 0.04), 10, 4, 4);
  ASSERT_TRUE(WriteObjSurface((dir / "scan.obj").string(), fine, fine.rest).ok());
  const std::string text =
      "objects:\n"
      "  - name: body\n"
      "    generate: {shape: box, size: [0.102, 0.042, 0.042], cells: [4, 2, 2], origin: [-0.001, -0.001, -0.001]}\n"
      "    surface: scan.obj\n"
      "    pose: {translation: [0, 0, 0.5]}\n"
      "    material: {youngs_modulus: 50000, poisson_ratio: 0.35, density: 200}\n";
  Scene scene;
  Status status = ParseScene(text, "scene.yaml", dir.string(), &scene);
  ASSERT_TRUE(status.ok()) << status.message();
  EXPECT_EQ(fs::path(scene.objects[0].surface_path).filename(), "scan.obj");
  std::unique_ptr<Tracker> tracker;
  status = Tracker::Create(scene, &tracker);
  ASSERT_TRUE(status.ok()) << status.message();
  ASSERT_TRUE(tracker->has_embedded_surface(0));
  const Vertices at = tracker->surface_vertices(0);
  EXPECT_NEAR(at.col(2).minCoeff(), 0.5, 1e-12);  // the object's pose applies to the surface too
  EXPECT_EQ(tracker->surface_outside(0), 0.0);
  // Written back and read again.
  const std::string yaml = SceneToYaml(scene, dir.string());
  EXPECT_NE(yaml.find("surface: scan.obj"), std::string::npos) << yaml;
  Scene again;
  ASSERT_TRUE(ParseScene(yaml, "again.yaml", dir.string(), &again).ok());
  EXPECT_EQ(again.objects[0].surface_path, scene.objects[0].surface_path);
  // --set reaches it.
  {
    std::ofstream(dir / "scene.yaml") << text;
    SceneOverride o;
    ASSERT_TRUE(ParseSceneOverride("objects[0].surface=missing.ply", &o).ok());
    Scene overridden;
    status = LoadSceneWithOverrides((dir / "scene.yaml").string(), {o}, &overridden);
    ASSERT_FALSE(status.ok());
    EXPECT_NE(status.message().find("objects[0].surface"), std::string::npos) << status.message();
    EXPECT_NE(status.message().find("not found"), std::string::npos) << status.message();
  }
  // Another format.
  std::ofstream(dir / "scan.vtu") << "not a surface";
  std::string bad = text;
  bad.replace(bad.find("scan.obj"), 8, "scan.vtu");
  status = ParseScene(bad, "scene.yaml", dir.string(), &again);
  ASSERT_FALSE(status.ok());
  EXPECT_NE(status.message().find(".ply, .obj or .stl"), std::string::npos) << status.message();
  fs::remove_all(dir);
}

#ifdef FEMREG_CLI_PATH
// femreg register with an embedded surface: its VTP (and PLY) per frame, and its errors
// against GROUND_TRUTH/surface/ while the vertex truth is another mesh's.
TEST(EmbeddedSurfaceCliTest, RegisterWritesTheSurfaceAndItsErrors) {
  namespace fs = std::filesystem;
  const fs::path dir = fs::temp_directory_path() / ("femreg_embedded_cli_" + std::to_string(::getpid()));
  fs::create_directories(dir / "clouds");
  fs::create_directories(dir / "data" / "ground_truth" / "surface");
  const TetMesh fine = MakeBox(Eigen::Vector3d(0.1, 0.04, 0.04), 10, 4, 4);
  ASSERT_TRUE(WriteObjSurface((dir / "scan.obj").string(), fine, fine.rest).ok());
  Vertices scan;  // as the scene will read it (the writer's vertex order)
  Triangles faces;
  ASSERT_TRUE(ReadSurface((dir / "scan.obj").string(), &scan, &faces).ok());
  const Eigen::RowVector3d shift(0.002, -0.001, 0.0);
  for (int f = 0; f < 2; ++f) {
    PointCloud cloud;
    cloud.points = (scan.rowwise() + shift).eval();
    const std::string name = "frame_000" + std::to_string(f);
    ASSERT_TRUE(WritePointCloud((dir / "clouds" / (name + ".pcd")).string(), cloud).ok());
    GroundTruthFrame surface_truth, other;
    surface_truth.positions = cloud.points;
    surface_truth.visible.assign(static_cast<size_t>(scan.rows()), 1);
    other.positions = Vertices::Zero(3, 3);  // another mesh's vertices: skipped
    other.visible.assign(3, 1);
    ASSERT_TRUE(WriteGroundTruthFrame((dir / "data" / "ground_truth" / "surface" / (name + ".csv")).string(), surface_truth).ok());
    ASSERT_TRUE(WriteGroundTruthFrame((dir / "data" / "ground_truth" / (name + ".csv")).string(), other).ok());
  }
  std::ofstream(dir / "scene.yaml") << "objects:\n"
                                       "  - name: body\n"
                                       "    generate: {shape: box, size: [0.102, 0.042, 0.042], cells: [4, 2, 2], origin: [-0.001, -0.001, -0.001]}\n"
                                       "    surface: scan.obj\n"
                                       "    material: {youngs_modulus: 50000, poisson_ratio: 0.35, density: 200}\n"
                                       "registration:\n"
                                       "  solver: {max_outer_iterations: 10}\n";
  const std::string command = std::string(FEMREG_CLI_PATH) + " register --scene " + (dir / "scene.yaml").string() +
                              " --frames " + (dir / "clouds").string() + " --ground-truth " + (dir / "data" / "ground_truth").string() +
                              " --out " + (dir / "out").string() + " --surface-ply --no-progress --threads 1 > " +
                              (dir / "log").string() + " 2>&1";
  ASSERT_EQ(std::system(command.c_str()), 0) << std::ifstream(dir / "log").rdbuf();
  EXPECT_TRUE(fs::exists(dir / "out" / "frames" / "body_surface_0001.vtp"));
  EXPECT_TRUE(fs::exists(dir / "out" / "body_surface.pvd"));
  Vertices ply;
  Triangles ply_faces;
  ASSERT_TRUE(ReadSurface((dir / "out" / "frames" / "body_surface_0001.ply").string(), &ply, &ply_faces).ok());
  EXPECT_EQ(ply_faces.rows(), faces.rows());
  EXPECT_LT((ply.colwise().mean() - (scan.colwise().mean() + shift)).norm(), 2e-4);
  std::ifstream stats(dir / "out" / "stats.csv");
  std::string header, row;
  std::getline(stats, header);
  std::getline(stats, row);
  std::getline(stats, row);  // the second frame
  const auto column = [&](const std::string& name) {
    std::vector<std::string> names, values;
    std::stringstream h(header), r(row);
    for (std::string c; std::getline(h, c, ',');) names.push_back(c);
    for (std::string c; std::getline(r, c, ',');) values.push_back(c);
    for (size_t i = 0; i < names.size() && i < values.size(); ++i) {
      if (names[i] == name) return values[i];
    }
    return std::string("missing");
  };
  EXPECT_EQ(column("err_mean_mm"), "");  // the vertex truth was another mesh's
  const std::string error = column("err_surface_mean_mm");
  ASSERT_FALSE(error.empty());
  EXPECT_LT(std::stod(error), 0.2);  // mm: the scan follows the 2.2 mm shift
  // femreg eval reads the surfaces' VTPs and gives the same errors.
  const std::string eval = std::string(FEMREG_CLI_PATH) + " eval " + (dir / "out").string() + " " +
                           (dir / "data").string() + " --csv " + (dir / "eval.csv").string() + " > " +
                           (dir / "eval_log").string() + " 2>&1";
  ASSERT_EQ(std::system(eval.c_str()), 0) << std::ifstream(dir / "eval_log").rdbuf();
  std::ifstream eval_csv(dir / "eval.csv");
  std::getline(eval_csv, header);
  std::getline(eval_csv, row);
  std::getline(eval_csv, row);  // the second frame
  ASSERT_NE(column("err_surface_mean_mm"), "missing") << header;
  EXPECT_NEAR(std::stod(column("err_surface_mean_mm")), std::stod(error), 1e-3);
  EXPECT_EQ(column("all_mean_mm"), "");  // the vertex truth was another mesh's
  // A VTP that is not the register's own is refused with its name.
  std::ofstream(dir / "out" / "frames" / "body_surface_0001.vtp") << "<VTKFile type=\"UnstructuredGrid\"/>\n";
  EXPECT_NE(std::system(eval.c_str()), 0);
  std::stringstream log;
  log << std::ifstream(dir / "eval_log").rdbuf();
  EXPECT_NE(log.str().find("body_surface_0001.vtp"), std::string::npos) << log.str();
  fs::remove_all(dir);
}
#endif  // FEMREG_CLI_PATH

}  // namespace
}  // namespace femreg
