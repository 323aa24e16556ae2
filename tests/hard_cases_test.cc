// The hard-case suite (ctest -L hard_cases): materials near their limits, degenerate meshes,
// bad clouds, jumps, pieces and penetrations, with both back ends. Each case must end finite
// and bounded with a termination that says what happened. With FEMREG_HARD_CASES_CSV set,
// every case appends a row (case, back end, termination, errors, time) to that file:
// tools/hard_cases.sh makes docs/hard_cases.md from it.
#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <functional>
#include <limits>
#include <memory>
#include <random>
#include <string>

#include "femreg/collision.h"
#include "femreg/ground_truth.h"
#include "femreg/io.h"
#include "femreg/tracker.h"
#include "surface_samples.h"

namespace femreg {
namespace {

constexpr double kLength = 0.2, kWidth = 0.04;

Material Foam(double E = 5e4, double nu = 0.35) {
  Material m;
  m.youngs_modulus = E;
  m.poisson_ratio = nu;
  m.density = 200;
  return m;
}

// The bent beam: z drops by drop * (x / L)^2 (a smooth bend, exact for the test's purpose).
Vertices Bend(const Vertices& rest, double drop) {
  Vertices x = rest;
  for (int v = 0; v < x.rows(); ++v) x(v, 2) -= drop * std::pow(rest(v, 0) / kLength, 2);
  return x;
}

// n points spread over the surface triangles of `mesh` at positions x (area-weighted), with
// Gaussian noise of sigma (m); one seed, one cloud.
PointCloud SampleSurface(const TetMesh& mesh, const Vertices& x, int n, double sigma, uint64_t seed) {
  std::mt19937_64 rng(seed);
  return testing_util::SampleSurfaceByArea(mesh, x, n, sigma, &rng);
}

std::vector<int> Clamped(const TetMesh& mesh) {
  std::vector<int> v;
  for (int i = 0; i < mesh.num_vertices(); ++i) {
    if (mesh.rest(i, 0) < 1e-9) v.push_back(i);
  }
  return v;
}

struct Outcome {
  TerminationType termination = TerminationType::kNotRun;
  double mean_error = 0.0;   // m, against the truth of the last frame (NaN: no truth)
  double nothing_error = 0.0;  // m, the same for the rest shape (doing nothing)
  double max_motion = 0.0;   // m, largest vertex displacement from rest
  double ms_per_frame = 0.0;
  int inverted = 0;  // elements with det F <= 0 at the end
  double forces_before_last = 0.0;  // N, the norm of the per-vertex external forces before the last frame
  double last_forces = 0.0;         // N, the same after it
  bool finite = true;
  std::string message;
};

void Record(const std::string& name, SolverBackend backend, const Outcome& o) {
  const char* path = std::getenv("FEMREG_HARD_CASES_CSV");
  if (path == nullptr) return;
  FILE* f = std::fopen(path, "a");
  if (f == nullptr) return;
  std::fprintf(f, "\"%s\",%s,%s,%.3f,%.3f,%.3f,%.2f,\"%s\"\n", name.c_str(), ToString(backend),
               ToString(o.termination), o.mean_error * 1e3, o.nothing_error * 1e3,
               o.max_motion * 1e3, o.ms_per_frame, o.message.substr(0, 120).c_str());
  std::fclose(f);
}

// Tracks `clouds` with a fresh tracker over `mesh` (clamped at x = 0 unless free) and
// compares the last frame with `truth` (when not empty).
Outcome RunCase(const TetMesh& mesh, const ObjectMaterial& material, RegistrationOptions options,
            const std::vector<PointCloud>& clouds, const Vertices& truth, bool clamp = true,
            const std::function<void(Tracker*)>& setup = nullptr) {
  Outcome out;
  std::unique_ptr<Tracker> tracker;
  Status status = Tracker::Create({mesh}, {material}, options, &tracker);
  EXPECT_TRUE(status.ok()) << status.message();
  if (!status.ok()) return out;
  if (clamp) {
    EXPECT_TRUE(tracker->AddAnchor("clamp", 0, Clamped(mesh), true).ok());
  }
  if (setup) setup(tracker.get());
  const auto t0 = std::chrono::steady_clock::now();
  FrameSummary s;
  for (const PointCloud& c : clouds) {
    out.forces_before_last = tracker->external_forces(0).norm();
    EXPECT_TRUE(tracker->Track(c, &s).ok());
    out.finite = out.finite && tracker->vertices(0).allFinite();
  }
  out.ms_per_frame =
      1e3 * std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count() / clouds.size();
  out.termination = s.termination;
  out.message = s.message;
  out.last_forces = tracker->external_forces(0).norm();
  const Vertices& x = tracker->vertices(0);
  for (int t = 0; t < mesh.num_tets(); ++t) {
    if (SignedTetVolume(x.row(mesh.tets(t, 0)), x.row(mesh.tets(t, 1)), x.row(mesh.tets(t, 2)),
                        x.row(mesh.tets(t, 3))) <= 0) {
      ++out.inverted;
    }
  }
  out.max_motion = (x - mesh.rest).rowwise().norm().maxCoeff();
  if (truth.rows() == x.rows()) {
    out.mean_error = (x - truth).rowwise().norm().mean();
    out.nothing_error = (mesh.rest - truth).rowwise().norm().mean();
  } else {
    out.mean_error = out.nothing_error = std::numeric_limits<double>::quiet_NaN();
  }
  return out;
}

class HardCases : public ::testing::TestWithParam<SolverBackend> {
 protected:
  RegistrationOptions Options() const {
    RegistrationOptions o;
    o.solver.backend = GetParam();
    o.solver.max_outer_iterations = 8;
    return o;
  }
  TetMesh Beam() const { return MakeBox(Eigen::Vector3d(kLength, kWidth, kWidth), 10, 2, 2); }
  // Three frames bending the beam's end down to `drop`, full-surface clouds of 2000 points
  // with `noise` (m, standard deviation).
  std::vector<PointCloud> BendClouds(const TetMesh& mesh, double drop, Vertices* truth,
                                     double noise = 2e-4) const {
    std::vector<PointCloud> clouds;
    for (int f = 1; f <= 3; ++f) {
      *truth = Bend(mesh.rest, drop * f / 3.0);
      clouds.push_back(SampleSurface(mesh, *truth, 2000, noise, 11 + f));
    }
    return clouds;
  }
  std::string Name() const { return ToString(GetParam()); }
};

// Error bounds: the bend moves the end 20 mm and the mean vertex ~7 mm (doing nothing). A
// tracker that follows the data ends within a few millimetres
// (docs/notes/2026-11-28-figures-from-code-comments.md); the 1:1000 flat plate has
// its own bound (NearlyFlatElements). 5 mm means "followed the data", well below doing
// nothing (the bend is 20 mm).
constexpr double kFollowed = 5e-3;

TEST_P(HardCases, PoissonRatioUpToTheIncompressibleLimit) {
  for (double nu : {0.45, 0.49, 0.499}) {
    const TetMesh mesh = Beam();
    Vertices truth;
    const auto clouds = BendClouds(mesh, 0.02, &truth);
    const Outcome o = RunCase(mesh, Foam(5e4, nu), Options(), clouds, truth);
    Record("nu = " + std::to_string(nu).substr(0, 5), GetParam(), o);
    EXPECT_TRUE(o.finite);
    EXPECT_TRUE(o.termination == TerminationType::kConverged ||
                o.termination == TerminationType::kMaxIterations) << o.message;
    // Near-incompressible linear tetrahedra lock: the error grows, but stays below doing nothing.
    EXPECT_LT(o.mean_error, o.nothing_error) << "nu " << nu;
  }
}

TEST_P(HardCases, YoungsModulusFromVerySoftToSteel) {
  for (double E : {1e2, 1e9}) {
    const TetMesh mesh = Beam();
    Vertices truth;
    const auto clouds = BendClouds(mesh, 0.02, &truth);
    const Outcome o = RunCase(mesh, Foam(E), Options(), clouds, truth);
    char name[32];
    std::snprintf(name, sizeof(name), "E = %.0e Pa", E);
    Record(name, GetParam(), o);
    EXPECT_TRUE(o.finite);
    // Steel against 200 N/m per pair cannot bend: it stays near rest (bounded), it does not explode.
    EXPECT_LT(o.max_motion, 0.05) << E;
    if (E < 1e3) {
      EXPECT_LT(o.mean_error, kFollowed) << o.message;
    }
  }
}

TEST_P(HardCases, InvertedStartRecovers) {
  const TetMesh mesh = Beam();
  Vertices truth;
  const auto clouds = BendClouds(mesh, 0.02, &truth);
  const Outcome o = RunCase(mesh, Foam(), Options(), clouds, truth, true, [&](Tracker* t) {
    Vertices x = mesh.rest;  // the free half mirrored through its mid-plane: inverted elements
    for (int v = 0; v < x.rows(); ++v) {
      if (x(v, 0) > kLength / 2) x(v, 2) = kWidth - x(v, 2);
    }
    ASSERT_TRUE(t->SetVertices(0, x).ok());
  });
  Record("inverted start", GetParam(), o);
  EXPECT_TRUE(o.finite);
  EXPECT_LT(o.mean_error, kFollowed) << o.message;
}

// The stable neo-Hookean element follows the bend up to the incompressible limit
// (docs/notes/2026-11-28-figures-from-code-comments.md).
TEST_P(HardCases, NeoHookeanUpToTheIncompressibleLimit) {
  for (double nu : {0.3, 0.499}) {
    const TetMesh mesh = Beam();
    Vertices truth;
    const auto clouds = BendClouds(mesh, 0.02, &truth);
    ObjectMaterial material(Foam(5e4, nu));
    material.model = MaterialModel::kNeoHookean;
    const Outcome o = RunCase(mesh, material, Options(), clouds, truth);
    Record("neo-Hookean, nu = " + std::to_string(nu).substr(0, 5), GetParam(), o);
    EXPECT_TRUE(o.finite);
    EXPECT_LT(o.mean_error, kFollowed) << "nu " << nu << ": " << o.message;
  }
}

// From InvertedStartRecovers' mirrored half, the neo-Hookean element (finite and pushing
// back for J <= 0) un-inverts every element and stays finite. It does not come back to the
// truth: the mirrored half's surface matches the clouds as well as the truth's, and its
// energy leads to another state without inverted elements, off by several millimetres, where the
// corotational element's sign convention recovers
// (docs/notes/2026-11-28-figures-from-code-comments.md).
TEST_P(HardCases, NeoHookeanInvertedStartUnfolds) {
  const TetMesh mesh = Beam();
  Vertices truth;
  const auto clouds = BendClouds(mesh, 0.02, &truth);
  ObjectMaterial material(Foam());
  material.model = MaterialModel::kNeoHookean;
  const Outcome o = RunCase(mesh, material, Options(), clouds, truth, true, [&](Tracker* t) {
    Vertices x = mesh.rest;  // as InvertedStartRecovers
    for (int v = 0; v < x.rows(); ++v) {
      if (x(v, 0) > kLength / 2) x(v, 2) = kWidth - x(v, 2);
    }
    ASSERT_TRUE(t->SetVertices(0, x).ok());
  });
  Record("neo-Hookean, inverted start", GetParam(), o);
  EXPECT_TRUE(o.finite);
  EXPECT_EQ(o.inverted, 0) << o.message;
  EXPECT_LT(o.max_motion, 0.1) << o.message;  // bounded: the beam is 0.2 m long
}

TEST_P(HardCases, NearlyFlatElements) {
  // A 0.2 x 0.04 x 0.00004 m plate: every element 1000 times flatter than it is wide.
  TetMesh mesh = MakeBox(Eigen::Vector3d(kLength, kWidth, 4e-5), 10, 2, 1);
  Vertices truth;
  // Clouds with noise below the plate's thickness: the data are well posed, and what is tested
  // is the elements' numerics (docs/notes/2026-11-28-figures-from-code-comments.md).
  {
    const auto clouds = BendClouds(mesh, 0.02, &truth, 1e-5);
    const Outcome o = RunCase(mesh, Foam(), Options(), clouds, truth);
    Record("flat elements (1:1000)", GetParam(), o);
    EXPECT_TRUE(o.finite);
    EXPECT_LT(o.mean_error, kFollowed) << o.message;
  }
  // With the usual 0.2 mm of noise, five times the thickness, the top and bottom faces take each
  // other's points and the rim's edges pull along the distance direction: the outer iterations do
  // not settle, and where they end is chaotic (it moves with the PCG tolerance, the thread count
  // and the back end (docs/notes/2026-11-28-figures-from-code-comments.md)). So here only stability
  // is asserted: finite, and no vertex moved more than 1.5 times the bend's 20 mm.
  {
    const auto clouds = BendClouds(mesh, 0.02, &truth);
    const Outcome o = RunCase(mesh, Foam(), Options(), clouds, truth);
    Record("flat elements (1:1000), noise 5x the thickness", GetParam(), o);
    EXPECT_TRUE(o.finite);
    EXPECT_LT(o.max_motion, 0.03) << o.message;
  }
}

TEST_P(HardCases, TinyCornerCell) {
  // The beam's last layer of cells along x, y and z 0.05 mm thick: at the free end a cell
  // 0.05 mm across, needles along the three edges that meet there, slabs under three faces.
  // The noise (0.2 mm) pulls their vertices apart or through each other, which would invert
  // them. The fast back end's line search cuts such steps inside the barrier's zone; Ceres
  // refuses them and its trust region shrinks to nothing: the frame must then say "stalled",
  // not "converged" (docs/theory/stopping.md#stalled). The fast back end's later solves also
  // end on cuts too short to move, and say so, since the strain test no longer takes the
  // points at the cell for implausible (docs/notes/2026-12-07-sliver-strains.md); the shape
  // must follow the bend all the same.
  TetMesh mesh = Beam();
  for (int v = 0; v < mesh.num_vertices(); ++v) {
    if (mesh.rest(v, 0) > kLength - 1e-9) mesh.rest(v, 0) = 0.9 * kLength + 5e-5;
    if (mesh.rest(v, 1) > kWidth - 1e-9) mesh.rest(v, 1) = 0.5 * kWidth + 5e-5;
    if (mesh.rest(v, 2) > kWidth - 1e-9) mesh.rest(v, 2) = 0.5 * kWidth + 5e-5;
  }
  ASSERT_TRUE(FinalizeMesh(&mesh).ok());
  Vertices truth;
  const auto clouds = BendClouds(mesh, 0.02, &truth);
  const Outcome o = RunCase(mesh, Foam(), Options(), clouds, truth);
  Record("a cell 0.05 mm across at the free end", GetParam(), o);
  EXPECT_TRUE(o.finite);
  EXPECT_EQ(o.inverted, 0);
  if (GetParam() == SolverBackend::kCeres) {
    EXPECT_EQ(o.termination, TerminationType::kStalled) << o.message;
  } else {
    EXPECT_TRUE(o.termination == TerminationType::kConverged || o.termination == TerminationType::kStalled)
        << o.message;
    EXPECT_LT(o.mean_error, kFollowed) << o.message;
  }
}

TEST_P(HardCases, BadClouds) {
  const TetMesh mesh = Beam();
  Vertices truth;
  auto clouds = BendClouds(mesh, 0.02, &truth);
  struct Bad {
    const char* name;
    PointCloud cloud;
    TerminationType expected;
    bool held;  // no force measured (the shape held at the last frame's, or its prediction)
  };
  PointCloud nan;
  nan.points = Vertices::Constant(100, 3, std::numeric_limits<double>::quiet_NaN());
  PointCloud one;
  one.points = clouds.back().points.topRows(1);
  PointCloud far;
  far.points = Vertices::Constant(50, 3, 10.0);
  PointCloud mismatched = clouds.back();
  mismatched.normals = Vertices::Constant(mismatched.size() / 2, 3, 1.0);
  for (const Bad& bad : {Bad{"empty cloud", PointCloud(), TerminationType::kNoCorrespondences, true},
                         Bad{"all-NaN cloud", nan, TerminationType::kInvalidInput, true},
                         Bad{"normals not matching the points", mismatched, TerminationType::kInvalidInput, true},
                         Bad{"single point", one, TerminationType::kTooFewPoints, true},
                         Bad{"cloud 10 m away", far, TerminationType::kNoCorrespondences, true}}) {
    std::vector<PointCloud> seq = clouds;
    seq.push_back(bad.cloud);
    const Outcome o = RunCase(mesh, Foam(), Options(), seq, truth);
    Record(bad.name, GetParam(), o);
    EXPECT_TRUE(o.finite) << bad.name;
    EXPECT_EQ(o.termination, bad.expected) << bad.name << ": " << o.message;
    // The shape stays where the data put it (held, or the prediction of a still object).
    EXPECT_LT(o.mean_error, kFollowed) << bad.name;
    if (bad.held) {
      EXPECT_GT(o.forces_before_last, 0.0) << bad.name;  // the data's pull in the last good frame
      EXPECT_EQ(o.last_forces, 0.0) << bad.name;
    }
  }
}

TEST_P(HardCases, ThirtyPercentOutliers) {
  const TetMesh mesh = Beam();
  Vertices truth;
  auto clouds = BendClouds(mesh, 0.02, &truth);
  std::mt19937_64 rng(5);
  std::uniform_real_distribution<double> box(-0.05, 0.25);
  for (PointCloud& c : clouds) {
    const int n = c.size(), extra = n * 3 / 7;  // 30% of the result
    c.points.conservativeResize(n + extra, 3);
    for (int i = n; i < n + extra; ++i) c.points.row(i) = Eigen::RowVector3d(box(rng), box(rng) * 0.3, box(rng) * 0.3);
  }
  // With the default Huber loss every outlier within data.max_distance keeps pulling with a
  // constant force (w x loss_scale), and outliers around an edge or a corner pull towards
  // themselves: the shape is dragged ~1 cm. Gross outliers need a redescending loss, which
  // docs/theory/data-terms.md#pairs recommends for them; with it the beam is followed.
  const Outcome huber = RunCase(mesh, Foam(), Options(), clouds, truth);
  Record("30% outliers (default loss: huber)", GetParam(), huber);
  EXPECT_TRUE(huber.finite);
  EXPECT_LT(huber.max_motion, 0.05) << huber.message;  // bounded: no runaway
  RegistrationOptions cauchy = Options();
  cauchy.data.loss = RobustLoss::kCauchy;
  const Outcome o = RunCase(mesh, Foam(), cauchy, clouds, truth);
  Record("30% outliers (data.loss: cauchy)", GetParam(), o);
  EXPECT_TRUE(o.finite);
  EXPECT_LT(o.mean_error, kFollowed) << o.message;
}

TEST_P(HardCases, HalfAMillionPoints) {
  const TetMesh mesh = Beam();
  const Vertices truth = Bend(mesh.rest, 0.01);
  const std::vector<PointCloud> clouds = {SampleSurface(mesh, truth, 500000, 2e-4, 3)};
  const Outcome o = RunCase(mesh, Foam(), Options(), clouds, truth);
  Record("500k-point cloud", GetParam(), o);
  EXPECT_TRUE(o.finite);
  EXPECT_LT(o.mean_error, kFollowed) << o.message;
}

TEST_P(HardCases, TenCentimetreRigidJump) {
  // A free block seen at rest, then 10 cm away: beyond data.max_distance (3 cm), so the frame
  // has no correspondences and says so, holding the shape; with the rigid pre-alignment the
  // jump is followed.
  const Eigen::Vector3d size(0.1, 0.06, 0.04);
  const TetMesh mesh = MakeBox(size, 5, 3, 2);
  // Up by 10 cm: a 6 cm gap between the 4 cm thick block and where it was.
  const Vertices moved = mesh.rest.rowwise() + Eigen::RowVector3d(0.0, 0.0, 0.1);
  const std::vector<PointCloud> clouds = {SampleSurface(mesh, mesh.rest, 3000, 2e-4, 1),
                                          SampleSurface(mesh, moved, 3000, 2e-4, 2)};
  Outcome o = RunCase(mesh, Foam(), Options(), clouds, moved, /*clamp=*/false);
  Record("10 cm rigid jump", GetParam(), o);
  EXPECT_TRUE(o.finite);
  EXPECT_EQ(o.termination, TerminationType::kNoCorrespondences) << o.message;
  EXPECT_LT(o.max_motion, 1e-3);  // held
  RegistrationOptions prealign = Options();
  prealign.solver.rigid_prealign = true;
  prealign.data.max_distance = 0.2;
  o = RunCase(mesh, Foam(), prealign, clouds, moved, /*clamp=*/false);
  Record("10 cm rigid jump, rigid_prealign", GetParam(), o);
  EXPECT_TRUE(o.finite);
  EXPECT_LT(o.mean_error, kFollowed) << o.message;
}

TEST_P(HardCases, StrongModelToCloudShareHoldsAFreeBlockWhenCapped) {
  // A free block (5 x 3 x 2 cells of 2 cm) on three clouds of its rest surface, per-area
  // weights with a strong model->cloud share. Each vertex pulls to its nearest cloud point
  // along its normal; at the block's edges and corners that point lies on a face and the
  // pull is biased, by up to about an edge's area of weight per vertex when uncapped. Capped
  // at twice the cloud's area per point (weights.model_to_cloud_area_cap), the block stays
  // put within 1 mm, as the rigid-jump case asks of the defaults.
  const TetMesh mesh = MakeBox(Eigen::Vector3d(0.1, 0.06, 0.04), 5, 3, 2);
  std::vector<PointCloud> clouds;
  for (int f = 0; f < 3; ++f) clouds.push_back(SampleSurface(mesh, mesh.rest, 3000, 2e-4, 30 + f));
  RegistrationOptions options = Options();
  options.weights.data = -1;
  options.weights.data_per_area = 1.15e7;
  options.weights.model_to_cloud_share = 0.3;
  double motion[2];
  for (int capped = 0; capped < 2; ++capped) {
    options.weights.model_to_cloud_area_cap = capped ? 2.0 : 0.0;
    const Outcome o = RunCase(mesh, Foam(), options, clouds, mesh.rest, /*clamp=*/false);
    Record(capped ? "free block, share 0.3, capped" : "free block, share 0.3, uncapped", GetParam(), o);
    EXPECT_TRUE(o.finite);
    motion[capped] = o.max_motion;
    std::printf("%s: max motion %.3f mm\n", capped ? "capped" : "uncapped", 1e3 * o.max_motion);
  }
  EXPECT_LT(motion[1], 1e-3);
  EXPECT_LT(motion[1], motion[0]);
}

TEST_P(HardCases, BrokenOffPieceWithoutData) {
  // Two disjoint bars in one mesh (a piece broken off); the cloud shows only the first.
  TetMesh a = MakeBox(Eigen::Vector3d(kLength, kWidth, kWidth), 10, 2, 2);
  TetMesh b = MakeBox(Eigen::Vector3d(0.05, kWidth, kWidth), 3, 2, 2, Eigen::Vector3d(0.25, 0, 0));
  TetMesh mesh;
  mesh.rest.resize(a.num_vertices() + b.num_vertices(), 3);
  mesh.rest << a.rest, b.rest;
  mesh.tets.resize(a.num_tets() + b.num_tets(), 4);
  mesh.tets << a.tets, (b.tets.array() + a.num_vertices()).matrix();
  ASSERT_TRUE(FinalizeMesh(&mesh, "two pieces").ok());
  Vertices truth = mesh.rest;
  truth.topRows(a.num_vertices()) = Bend(a.rest, 0.02);
  std::vector<PointCloud> clouds;
  for (int f = 0; f < 3; ++f) clouds.push_back(SampleSurface(a, truth.topRows(a.num_vertices()), 2000, 2e-4, 20 + f));
  const Outcome o = RunCase(mesh, Foam(), Options(), clouds, truth);
  Record("broken-off piece, no data", GetParam(), o);
  EXPECT_TRUE(o.finite);
  EXPECT_LT(o.mean_error, kFollowed) << o.message;
}

TEST_P(HardCases, DeepPenetration) {
  // Two blocks starting 1 cm into each other (half the upper one's thickness), collision on.
  TetMesh base = MakeBox(Eigen::Vector3d(0.06, 0.06, 0.03), 4, 4, 2);
  TetMesh top = MakeBox(Eigen::Vector3d(0.04, 0.04, 0.02), 3, 3, 2, Eigen::Vector3d(0.01, 0.01, 0.02));
  RegistrationOptions options = Options();
  std::unique_ptr<Tracker> tracker;
  ASSERT_TRUE(Tracker::Create({base, top}, {Foam(), Foam()}, options, &tracker).ok());
  CollisionSpec spec;
  spec.stiffness = 1e4;
  spec.distance = 0.002;
  ASSERT_TRUE(tracker->EnableCollision(spec, {"base", "top"}).ok());
  std::vector<int> bottom;
  for (int v = 0; v < base.num_vertices(); ++v) {
    if (base.rest(v, 2) < 1e-9) bottom.push_back(v);
  }
  ASSERT_TRUE(tracker->AddAnchor("support", 0, bottom, true).ok());
  PointCloud cloud = SampleSurface(base, base.rest, 1500, 2e-4, 4);
  const PointCloud upper = SampleSurface(top, top.rest, 1000, 2e-4, 5);
  cloud.points.conservativeResize(cloud.size() + upper.size(), 3);
  cloud.points.bottomRows(upper.size()) = upper.points;
  Outcome o;
  const auto t0 = std::chrono::steady_clock::now();
  FrameSummary s;
  for (int f = 0; f < 3; ++f) {
    ASSERT_TRUE(tracker->Track(cloud, &s).ok());
    o.finite = o.finite && tracker->vertices(0).allFinite() && tracker->vertices(1).allFinite();
  }
  o.ms_per_frame = 1e3 * std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count() / 3;
  o.termination = s.termination;
  o.message = s.message;
  o.max_motion = std::max((tracker->vertices(0) - base.rest).rowwise().norm().maxCoeff(),
                          (tracker->vertices(1) - top.rest).rowwise().norm().maxCoeff());
  o.mean_error = o.nothing_error = std::numeric_limits<double>::quiet_NaN();
  Record("deep penetration (1 cm), collision on", GetParam(), o);
  EXPECT_TRUE(o.finite);
  EXPECT_TRUE(s.IsSolutionUsable()) << s.FullReport();
  // The data hold both blocks where they are; the contact term pushes them apart. This case
  // does not converge in either back end: bottom vertices of the upper block slide 10-15
  // mm to and fro from one outer iteration to the next (pushed out of the base towards its
  // nearest face, then pulled back by the data), so where the last frame stops within that
  // cycle changes with any change of the steps (max motion 13-22 mm over the solver changes
  // of 2026-11-26, Ceres 13 mm). What holds: the motion stays within the overlap plus the
  // cycle's amplitude.
  EXPECT_LT(o.max_motion, 0.03);
}

INSTANTIATE_TEST_SUITE_P(BothBackEnds, HardCases,
                         ::testing::Values(SolverBackend::kCeres, SolverBackend::kFast),
                         [](const ::testing::TestParamInfo<SolverBackend>& info) {
                           return std::string(ToString(info.param));
                         });

}  // namespace
}  // namespace femreg
