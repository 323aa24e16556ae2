// Fracture: the separation tensor (docs/theory/fracture.md#detection), node splitting
// (#splitting), the cut through a section, and mesh validity after splits. Tracking through the
// bundled sequences: fracture_tracking_test.cc; the command line: fracture_cli_test.cc.
#include "femreg/fracture.h"

#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <numeric>
#include <random>
#include <string>
#include <vector>

#include "femreg/forward.h"
#include "femreg/io.h"
#include "fracture/measure_bound.h"
#include "mesh/disjoint_sets.h"

namespace femreg {
namespace {

Material Soft() {
  Material m;
  m.youngs_modulus = 5e4;
  m.poisson_ratio = 0.3;
  m.density = 200;
  return m;
}

double MaxNorm(const std::vector<Eigen::Matrix3d>& tensors) {
  double m = 0.0;
  for (const auto& t : tensors) m = std::max(m, t.norm());
  return m;
}

std::vector<Eigen::Matrix3d> Tensors(const TetMesh& mesh, ElasticModel* model, const Vertices& x) {
  model->UpdateRotations(x);
  return SeparationTensors(mesh, *model, x);
}

// A bent beam: the centre line on an arc of curvature kappa (pure bending) plus a stretch.
Vertices Bend(const Vertices& rest, double kappa, double stretch) {
  Vertices x = rest;
  for (int v = 0; v < rest.rows(); ++v) {
    const double s = rest(v, 0) * (1 + stretch), z = rest(v, 2) - 0.01;
    x(v, 0) = std::sin(kappa * s) * (1.0 / kappa - z);
    x(v, 2) = (1.0 / kappa) - std::cos(kappa * s) * (1.0 / kappa - z) + 0.01;
  }
  return x;
}

// The one union-find (mesh/disjoint_sets.h; fracture, meshing and ConnectedPieces use it):
// a set is named by its smallest member whatever the order of the unions.
TEST(DisjointSets, ASetIsNamedByItsSmallestMember) {
  DisjointSets sets(7);
  sets.Unite(5, 3);
  sets.Unite(6, 5);
  sets.Unite(4, 1);
  sets.Unite(6, 4);
  EXPECT_EQ(sets.size(), 7);
  for (int i : {1, 3, 4, 5, 6}) EXPECT_EQ(sets.Find(i), 1) << i;
  EXPECT_EQ(sets.Find(0), 0);
  EXPECT_EQ(sets.Find(2), 2);
  sets.Unite(2, 0);
  EXPECT_EQ(sets.Find(2), 0);
}

TEST(SeparationTensor, ZeroAtRestAndUnderRigidMotion) {
  TetMesh mesh = MakeBox(Eigen::Vector3d(0.1, 0.02, 0.02), 10, 2, 2);
  ElasticModel model;
  model.Build(mesh, ElasticModelType::kCorotational, Soft());
  EXPECT_LT(MaxNorm(Tensors(mesh, &model, mesh.rest)), 1e-12);
  const Eigen::Matrix3d R =
      Eigen::AngleAxisd(1.1, Eigen::Vector3d(1, -2, 0.5).normalized()).toRotationMatrix();
  Vertices moved = mesh.rest;
  for (int v = 0; v < moved.rows(); ++v) {
    moved.row(v) = (R * mesh.rest.row(v).transpose() + Eigen::Vector3d(0.3, -0.1, 2.0)).transpose();
  }
  // Forces are of order E * h^2 * strain ~ 5e4 * 1e-4 = 5 N per unit strain.
  EXPECT_LT(MaxNorm(Tensors(mesh, &model, moved)), 1e-9);
  // Not trivially zero: the same beam bent has separating nodes.
  EXPECT_GT(MaxNorm(Tensors(mesh, &model, Bend(mesh.rest, 8.0, 0.0))), 1e-2);
}

TEST(SeparationTensor, NoSeparationUnderPureCompression) {
  TetMesh mesh = MakeBox(Eigen::Vector3d(0.1, 0.02, 0.02), 10, 2, 2);
  ElasticModel model;
  model.Build(mesh, ElasticModelType::kCorotational, Soft());
  FractureOptions options;
  options.toughness = 1.0;
  NodeSeparation sep;
  // Uniaxial compression (laterally confined: every principal stress is compressive).
  Vertices x = mesh.rest;
  x.col(0) *= 0.97;
  model.UpdateRotations(x);
  DetectFracture(mesh, model, x, options, &sep);
  const double confined = sep.measure.maxCoeff();
  // Uniaxial stress state (free lateral expansion by nu).
  x = mesh.rest;
  x.col(0) *= 0.97;
  x.col(1) *= 1.0 + 0.3 * 0.03;
  x.col(2) *= 1.0 + 0.3 * 0.03;
  model.UpdateRotations(x);
  DetectFracture(mesh, model, x, options, &sep);
  const double uniaxial = sep.measure.maxCoeff();
  // The same stretch instead of compression separates (of the order of the stress).
  x = mesh.rest;
  x.col(0) *= 1.03;
  model.UpdateRotations(x);
  DetectFracture(mesh, model, x, options, &sep);
  const double stress = 1.03e-2 * 5e4 * 0.7 / (1.3 * 0.4) * 3;  // ~ (lambda + 2 mu) * strain
  EXPECT_GT(sep.measure.maxCoeff(), 0.1 * stress);
  EXPECT_LT(sep.measure.maxCoeff(), 20 * stress);
  // Zero up to roundoff in both compressions (that of the closed-form 3x3 eigen-solver, some
  // 1e-9 of the stress).
  EXPECT_LT(confined, 1e-8 * sep.measure.maxCoeff());
  EXPECT_LT(uniaxial, 1e-8 * sep.measure.maxCoeff());
}

TEST(SeparationTensor, IndependentOfVertexAndElementNumbering) {
  TetMesh mesh = MakeBox(Eigen::Vector3d(0.1, 0.02, 0.02), 10, 2, 2);
  ElasticModel model;
  model.Build(mesh, ElasticModelType::kCorotational, Soft());
  const Vertices x = Bend(mesh.rest, 8.0, 0.02);
  FractureOptions options;
  model.UpdateRotations(x);
  NodeSeparation a;
  DetectFracture(mesh, model, x, options, &a);
  options.toughness = 0.5 * a.measure.maxCoeff();

  // Permute vertices and elements, and rotate each element's vertex list evenly.
  std::mt19937 rng(7);
  std::vector<int> vperm(mesh.num_vertices()), eperm(mesh.num_tets());
  std::iota(vperm.begin(), vperm.end(), 0);
  std::iota(eperm.begin(), eperm.end(), 0);
  std::shuffle(vperm.begin(), vperm.end(), rng);  // new vertex i is old vperm[i]
  std::shuffle(eperm.begin(), eperm.end(), rng);
  std::vector<int> inverse(vperm.size());
  for (size_t i = 0; i < vperm.size(); ++i) inverse[vperm[i]] = static_cast<int>(i);
  TetMesh permuted;
  permuted.rest.resize(mesh.num_vertices(), 3);
  Vertices xp(mesh.num_vertices(), 3);
  for (int i = 0; i < mesh.num_vertices(); ++i) {
    permuted.rest.row(i) = mesh.rest.row(vperm[i]);
    xp.row(i) = x.row(vperm[i]);
  }
  permuted.tets.resize(mesh.num_tets(), 4);
  const int even[3][4] = {{0, 1, 2, 3}, {1, 2, 0, 3}, {0, 2, 3, 1}};
  for (int e = 0; e < mesh.num_tets(); ++e) {
    const int* p = even[e % 3];
    for (int k = 0; k < 4; ++k) permuted.tets(e, k) = inverse[mesh.tets(eperm[e], p[k])];
  }
  ASSERT_TRUE(FinalizeMesh(&permuted).ok());
  ElasticModel permuted_model;
  permuted_model.Build(permuted, ElasticModelType::kCorotational, Soft());
  permuted_model.UpdateRotations(xp);
  NodeSeparation b;
  DetectFracture(permuted, permuted_model, xp, options, &b);
  DetectFracture(mesh, model, x, options, &a);
  int breaking_a = 0, breaking_b = 0;
  for (int i = 0; i < mesh.num_vertices(); ++i) {
    const int o = vperm[i];
    EXPECT_NEAR(b.measure(i), a.measure(o), 1e-9 * a.measure.maxCoeff()) << "vertex " << o;
    if (a.measure(o) > 1e-6 * a.measure.maxCoeff()) {
      EXPECT_GT(std::abs(b.normal.row(i).dot(a.normal.row(o))), 1 - 1e-6) << "vertex " << o;
    }
    breaking_a += a.measure(o) > options.toughness;
    breaking_b += b.measure(i) > options.toughness && (a.measure(o) > options.toughness);
  }
  EXPECT_GT(breaking_a, 0);
  EXPECT_EQ(breaking_a, breaking_b);
}

// Random stress states of a beam with a weak region: a random rotation of a random
// homogeneous strain (stretch, compression, shear, up to 6 %), a bend, and per-vertex noise.
struct RandomStates {
  RandomStates() : mesh(MakeBox(Eigen::Vector3d(0.1, 0.02, 0.02), 10, 2, 2)) {
    for (int e = 0; e < mesh.num_tets(); ++e) {
      double cx = 0;
      for (int k = 0; k < 4; ++k) cx += 0.25 * mesh.rest(mesh.tets(e, k), 0);
      if (cx > 0.06) mesh.region(e) = 1;
    }
    Material stiff = Soft();
    stiff.youngs_modulus = 2e5;
    model.Build(mesh, ElasticModelType::kCorotational, Soft(), {{1, stiff}});
  }
  Vertices Draw(std::mt19937* rng) {
    std::uniform_real_distribution<double> u(-1.0, 1.0);
    Eigen::Matrix3d strain;
    for (int a = 0; a < 3; ++a)
      for (int b = 0; b < 3; ++b) strain(a, b) = 0.06 * u(*rng);
    strain = 0.5 * (strain + strain.transpose()).eval();
    const Eigen::Matrix3d R =
        Eigen::AngleAxisd(3.0 * u(*rng), Eigen::Vector3d(u(*rng), u(*rng), u(*rng)).normalized()).toRotationMatrix();
    const double kappa = 10.0 * u(*rng), noise = 0.001 * std::abs(u(*rng));
    Vertices x = std::abs(kappa) > 0.5 ? Bend(mesh.rest, kappa, 0.0) : mesh.rest;
    for (int v = 0; v < x.rows(); ++v) {
      const Eigen::Vector3d p = x.row(v).transpose();
      const Eigen::Vector3d q = R * (p + strain * p) + Eigen::Vector3d(u(*rng), u(*rng), u(*rng)) * noise;
      x.row(v) = q.transpose();
    }
    model.UpdateRotations(x);
    return x;
  }
  TetMesh mesh;
  ElasticModel model;
};

// The bound the detection skips by is never below the measure it stands for.
TEST(MeasureBound, NeverBelowTheMeasure) {
  RandomStates states;
  std::mt19937 rng(11);
  FractureOptions options;
  std::vector<double> ratios;
  for (int trial = 0; trial < 200; ++trial) {
    const Vertices x = states.Draw(&rng);
    NodeSeparation full;
    DetectFracture(states.mesh, states.model, x, options, &full);
    const Eigen::VectorXd bound = fracture_internal::MeasureBound(states.mesh, states.model, x);
    ASSERT_EQ(bound.size(), full.measure.size());
    for (int j = 0; j < bound.size(); ++j) {
      EXPECT_GE(bound(j), full.measure(j)) << "trial " << trial << " node " << j;
    }
    ratios.push_back(bound.maxCoeff() / full.measure.maxCoeff());
  }
  // And not so loose that it would skip nothing: its largest value is within a small factor of
  // the measure's in most states (those under compression, with a measure near 0, are the
  // exceptions).
  std::sort(ratios.begin(), ratios.end());
  EXPECT_LT(ratios[ratios.size() / 2], 4.0);
  // At rest it is 0 up to its margin for round-off (a millionth of the modulus), as the
  // measure.
  EXPECT_LT(fracture_internal::MeasureBound(states.mesh, states.model, states.mesh.rest).maxCoeff(), 1.0);
}

// The detection that evaluates only where the bound reaches a fraction of the toughness finds
// every node the full detection puts there, with the same measure and plane; the others read 0.
TEST(MeasureBound, DetectionAboveAFloorMissesNoNodeAboveIt) {
  RandomStates states;
  std::mt19937 rng(5);
  int skipped = 0, evaluated = 0, above = 0;
  ElasticModel stale = states.model;  // rotations of the state before
  for (int trial = 0; trial < 200; ++trial) {
    if (trial > 0) stale = states.model;
    const Vertices x = states.Draw(&rng);
    FractureOptions options;
    NodeSeparation full;
    DetectFracture(states.mesh, states.model, x, options, &full);
    // Toughness about the measure's scale, weaker where the beam is stiff.
    std::vector<double> sorted(full.measure.data(), full.measure.data() + full.measure.size());
    std::sort(sorted.begin(), sorted.end());
    options.toughness = sorted[sorted.size() * (trial % 10) / 10] + 1e-3;
    options.region_toughness = {{1, 0.5 * options.toughness}};
    DetectFracture(states.mesh, states.model, x, options, &full);
    for (double floor : {0.1, 0.3, 1.0}) {
      // With the model's rotations current for x, or found from those of another state.
      const bool current = trial % 2 == 0;
      NodeSeparation some;
      const int n = fracture_internal::DetectFractureAbove(states.mesh, current ? states.model : stale, x, options,
                                                           floor, current, &some);
      ASSERT_EQ(some.measure.size(), full.measure.size());
      evaluated += n;
      skipped += static_cast<int>(full.measure.size()) - n;
      for (int j = 0; j < full.measure.size(); ++j) {
        EXPECT_DOUBLE_EQ(some.toughness(j), full.toughness(j));  // the same region's value
        const double scale = 1e-9 * full.measure.maxCoeff();
        if (full.measure(j) >= floor * full.toughness(j)) {
          ++above;
          EXPECT_NEAR(some.measure(j), full.measure(j), scale) << "trial " << trial << " node " << j;
          EXPECT_GT(std::abs(some.normal.row(j).dot(full.normal.row(j))), 1 - 1e-9);
        } else if (some.measure(j) != 0.0) {  // evaluated all the same: then the same measure
          EXPECT_NEAR(some.measure(j), full.measure(j), scale);
        }
      }
    }
  }
  // Both cases occurred: nodes skipped, and nodes above the floor found.
  EXPECT_GT(skipped, 0);
  EXPECT_GT(above, 0);
  EXPECT_GT(evaluated, above);
}

// With the model's rotations or with the same rotations given: the same detection.
TEST(MeasureBound, RotationsGivenOrTheModels) {
  RandomStates states;
  std::mt19937 rng(3);
  const Vertices x = states.Draw(&rng);
  FractureOptions options;
  NodeSeparation a, b;
  DetectFracture(states.mesh, states.model, x, options, &a);
  // Found from a start far from them (the model's at rest), as the model would.
  ElasticModel at_rest;
  at_rest.Build(states.mesh, ElasticModelType::kCorotational, Soft());
  const std::vector<Eigen::Matrix3d> rotations = fracture_internal::RotationsAt(at_rest, x);
  fracture_internal::DetectFractureWith(states.mesh, states.model, rotations, x, options, &b);
  ASSERT_GT(a.measure.maxCoeff(), 0.0);
  for (int j = 0; j < a.measure.size(); ++j) EXPECT_NEAR(b.measure(j), a.measure(j), 1e-9 * a.measure.maxCoeff());
}

// The detection evaluates exactly the nodes whose bound (MeasureBound's) reaches the floor
// times their toughness, though it refines the bound only around the nodes its coarse part
// (the largest principal stress alone) puts there: a node evaluated has its plane set.
TEST(MeasureBound, DetectionEvaluatesWhereTheBoundReachesTheFloor) {
  RandomStates states;
  std::mt19937 rng(23);
  int evaluated = 0, skipped = 0;
  for (int trial = 0; trial < 100; ++trial) {
    const Vertices x = states.Draw(&rng);
    const Eigen::VectorXd bound = fracture_internal::MeasureBound(states.mesh, states.model, x);
    std::vector<double> sorted(bound.data(), bound.data() + bound.size());
    std::sort(sorted.begin(), sorted.end());
    FractureOptions options;
    options.toughness = sorted[sorted.size() * (trial % 10) / 10] + 1e-3;
    options.region_toughness = {{1, 0.5 * options.toughness}};
    for (double floor : {0.3, 1.0}) {
      NodeSeparation some;
      fracture_internal::DetectFractureAbove(states.mesh, states.model, x, options, floor, true, &some);
      for (int j = 0; j < bound.size(); ++j) {
        const double level = floor * some.toughness(j);
        const bool is_evaluated = some.normal.row(j).norm() > 0.5;
        if (bound(j) > level * (1 + 1e-12)) {
          EXPECT_TRUE(is_evaluated) << "trial " << trial << " node " << j;
        } else if (bound(j) < level * (1 - 1e-12)) {
          EXPECT_FALSE(is_evaluated) << "trial " << trial << " node " << j;
        }
        evaluated += is_evaluated;
        skipped += !is_evaluated;
      }
    }
  }
  EXPECT_GT(evaluated, 0);
  EXPECT_GT(skipped, 0);
}

// The bound's data kept for a topology (as the tracker keeps it between splits) detects as
// the data built at each call: the same nodes evaluated, the same measures and toughness. A
// split changes the counts, and the kept data no longer fits the mesh.
TEST(MeasureBound, KeptDataDetectsAsDataBuiltEachTime) {
  RandomStates states;
  std::mt19937 rng(17);
  FractureOptions options;
  options.toughness = 1500;
  options.region_toughness = {{1, 700}};
  fracture_internal::BoundData kept;
  fracture_internal::BuildBoundData(states.mesh, states.model, options, &kept);
  ASSERT_TRUE(kept.Fits(states.mesh, states.model));
  ElasticModel stale = states.model;
  int evaluated = 0;
  for (int trial = 0; trial < 100; ++trial) {
    if (trial > 0) stale = states.model;
    const Vertices x = states.Draw(&rng);
    for (double floor : {0.1, 0.3, 1.0}) {
      const bool current = trial % 2 == 0;
      const ElasticModel& model = current ? states.model : stale;
      NodeSeparation built, reused;
      const int n = fracture_internal::DetectFractureAbove(states.mesh, model, x, options, floor, current, &built);
      const int m = fracture_internal::DetectFractureAbove(states.mesh, model, x, floor, current, kept, &reused);
      ASSERT_EQ(m, n) << "trial " << trial;
      evaluated += n;
      for (int j = 0; j < built.measure.size(); ++j) {
        EXPECT_DOUBLE_EQ(reused.measure(j), built.measure(j)) << "trial " << trial << " node " << j;
        EXPECT_DOUBLE_EQ(reused.toughness(j), built.toughness(j));
      }
    }
  }
  EXPECT_GT(evaluated, 0);
  // One node over its toughness splits: the mesh has another vertex.
  NodeSeparation sep;
  const int nv = states.mesh.num_vertices();
  sep.measure = Eigen::VectorXd::Zero(nv);
  sep.toughness = Eigen::VectorXd::Constant(nv, 1000.0);
  sep.normal = Vertices::Zero(nv, 3);
  sep.normal.col(0).setOnes();
  int j = -1;
  for (int v = 0; v < nv && j < 0; ++v) {
    if (std::abs(states.mesh.rest(v, 0) - 0.05) < 1e-9) j = v;
  }
  ASSERT_GE(j, 0);
  sep.measure(j) = 5000.0;
  TopologyChange change;
  SplitNodes(sep, FractureOptions(), 1, &states.mesh, &states.model, &change);
  ASSERT_TRUE(change.changed());
  EXPECT_FALSE(kept.Fits(states.mesh, states.model));
}

// Pulls a bar clamped at both ends apart with the forward simulator and fracture on.
TEST(SplitNodes, BarPulledApartBreaksIntoTwoValidPieces) {
  TetMesh mesh = MakeBox(Eigen::Vector3d(0.1, 0.02, 0.02), 10, 2, 2);
  ComputeLumpedMasses(&mesh, 200);
  ElasticModel model;
  model.Build(mesh, ElasticModelType::kCorotational, Soft());
  const double volume = RestVolume(mesh);
  FractureOptions options;
  options.toughness = 1500;
  options.region_toughness = {{1, 600}};
  // A weak slab in the middle.
  for (int e = 0; e < mesh.num_tets(); ++e) {
    double cx = 0;
    for (int k = 0; k < 4; ++k) cx += 0.25 * mesh.rest(mesh.tets(e, k), 0);
    if (std::abs(cx - 0.05) < 0.011) mesh.region(e) = 1;
  }
  std::vector<int> original;
  std::vector<FractureEvent> events;
  double removed = 0;
  int frames_to_break = -1;
  for (int f = 1; f <= 30 && frames_to_break < 0; ++f) {
    ForwardProblem problem;
    for (int v = 0; v < mesh.num_vertices(); ++v) {
      if (mesh.rest(v, 0) < 1e-9) problem.clamped.push_back(v);
      if (mesh.rest(v, 0) > 0.1 - 1e-9) problem.prescribed.emplace_back(v, Eigen::Vector3d(0.0005 * f, 0, 0));
    }
    ForwardSummary summary;
    const size_t before = events.size();
    Status s = SolveQuasiStaticWithFracture(&problem, ForwardOptions(), options, 8, 200, &model,
                                            &mesh, &original, &events, &summary);
    ASSERT_TRUE(s.ok()) << s.message();
    for (size_t i = before; i < events.size(); ++i) removed += events[i].removed_elements;
    const MeshValidity validity = CheckMesh(mesh);
    EXPECT_TRUE(validity.ok()) << "frame " << f << ": " << validity.ToString();
    if (validity.pieces == 2) frames_to_break = f;
  }
  ASSERT_GT(frames_to_break, 0) << events.size() << " splits";
  // The planes are mostly normal to the pull, and the break is in the weak slab.
  int along_pull = 0;
  for (const FractureEvent& e : events) along_pull += std::abs(e.normal.x()) > 0.8;
  EXPECT_GE(along_pull, 0.8 * events.size());
  std::vector<int> piece;
  ASSERT_EQ(ConnectedPieces(mesh, &piece), 2);
  for (int v = 0; v < mesh.num_vertices(); ++v) {
    if (mesh.rest(v, 0) < 0.035) {
      EXPECT_EQ(piece[v], piece[0]);
    } else if (mesh.rest(v, 0) > 0.065) {
      EXPECT_NE(piece[v], piece[0]);
    }
  }
  // Volume: conserved except for the removed elements, which are counted.
  int removed_count = 0;
  for (const FractureEvent& e : events) removed_count += e.removed_elements;
  EXPECT_EQ(removed_count, static_cast<int>(removed));
  EXPECT_EQ(mesh.num_tets(), 10 * 2 * 2 * 6 - removed_count);
  // MakeBox's 6 tetrahedra per cube have equal volumes.
  EXPECT_NEAR(RestVolume(mesh), volume * (1.0 - removed_count / 240.0), 1e-12 * volume);
  std::printf("bar: broke at step %d after %zu splits, %d elements removed\n", frames_to_break,
              events.size(), removed_count);
}

// A strip one element thick pulled apart with a weaker band in its middle (two element
// columns wide). Without a limit, nodes on several sections of the band break; with
// max_cracks = 1 one crack starts and grows in its own plane, across the strip.
// (SplitNodes still refuses a split that leaves the sides joined through a single edge or
// vertex, so the crack's last ligament may hold; and through a body several elements
// thick a crack cannot grow node by node: splitting one interior front node pinches the
// surface.)
std::vector<FractureEvent> PullStrip(int max_cracks, TetMesh* initial) {
  TetMesh mesh = MakeBox(Eigen::Vector3d(0.1, 0.04, 0.01), 10, 4, 1);
  ComputeLumpedMasses(&mesh, 200);
  ElasticModel model;
  model.Build(mesh, ElasticModelType::kCorotational, Soft());
  for (int e = 0; e < mesh.num_tets(); ++e) {
    double cx = 0;
    for (int k = 0; k < 4; ++k) cx += 0.25 * mesh.rest(mesh.tets(e, k), 0);
    if (std::abs(cx - 0.05) < 0.011) mesh.region(e) = 1;
  }
  *initial = mesh;
  FractureOptions options;
  options.toughness = 1500;
  options.region_toughness = {{1, 600}};
  options.max_cracks = max_cracks;
  std::string error;
  EXPECT_TRUE(options.IsValid(&error)) << error;
  std::vector<int> original;
  std::vector<FractureEvent> events;
  const auto start = std::chrono::steady_clock::now();
  int last_split = 0;
  for (int f = 1; f <= 20 && (last_split == 0 || f <= last_split + 2); ++f) {
    const size_t before = events.size();
    ForwardProblem problem;
    for (int v = 0; v < mesh.num_vertices(); ++v) {
      if (mesh.rest(v, 0) < 1e-9) problem.clamped.push_back(v);
      if (mesh.rest(v, 0) > 0.1 - 1e-9) problem.prescribed.emplace_back(v, Eigen::Vector3d(0.0005 * f, 0.0002 * f, 0));
    }
    ForwardSummary summary;
    Status s = SolveQuasiStaticWithFracture(&problem, ForwardOptions(), options, 8, 200, &model,
                                            &mesh, &original, &events, &summary);
    // Without a limit the strip may shatter into a crumb that nothing holds (a singular
    // solve): that ends the pull.
    if (max_cracks > 0) {
      EXPECT_TRUE(s.ok()) << s.message();
    }
    if (!s.ok()) break;
    const MeshValidity validity = CheckMesh(mesh);
    EXPECT_TRUE(validity.ok()) << "step " << f << ": " << validity.ToString();
    if (validity.pieces >= 2) break;
    if (events.size() > before) last_split = f;
  }
  std::printf("strip, max_cracks %d: %.1f s\n", max_cracks,
              std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count());
  return events;
}

std::vector<double> SplitSections(const std::vector<FractureEvent>& events, const TetMesh& initial) {
  std::vector<double> sections;
  for (const FractureEvent& e : events) sections.push_back(initial.rest(e.original_node, 0));
  std::sort(sections.begin(), sections.end());
  sections.erase(std::unique(sections.begin(), sections.end()), sections.end());
  return sections;
}

TEST(SplitNodes, OneCrackGrowsAlongItsPlane) {
  TetMesh initial;
  const std::vector<FractureEvent> free_events = PullStrip(0, &initial);
  EXPECT_GE(SplitSections(free_events, initial).size(), 2u) << free_events.size() << " splits";
  const std::vector<FractureEvent> events = PullStrip(1, &initial);
  // The crack went from its first node across the strip (5 x 2 nodes per section).
  EXPECT_GE(events.size(), 6u);
  ASSERT_EQ(SplitSections(events, initial).size(), 1u);
  for (const FractureEvent& e : events) EXPECT_GT(std::abs(e.normal.x()), 0.9);
  FractureOptions options;
  options.max_cracks = -1;
  std::string error;
  EXPECT_FALSE(options.IsValid(&error));
  std::printf("strip: without a limit %zu splits on %zu sections; one crack: %zu splits at x = %.3f m\n",
              free_events.size(), SplitSections(free_events, initial).size(), events.size(),
              SplitSections(events, initial)[0]);
}

// The cut through (FractureOptions::cut_through): one node over its toughness in a bent beam
// whose faces do not lie on the crack's plane; with the cut the beam is in two valid pieces
// at once, parted along the node's own face loop; without, one node splits and it stays
// whole; with data that shows no gap near the crack, no cut.
TEST(SplitNodes, CutThroughPartsTheSectionInOneStep) {
  auto split = [](bool cut, double gap, TetMesh* mesh, TopologyChange* change) {
    *mesh = MakeBox(Eigen::Vector3d(0.2, 0.03, 0.03), 12, 2, 2);
    ComputeLumpedMasses(mesh, 200);
    ElasticModel model;
    model.Build(*mesh, ElasticModelType::kCorotational, Soft());
    // A node on the top edge of the section at x = 1/3 of the beam, its plane tilted from
    // the section's by 10 degrees (the cut must snap to the section's faces).
    int j = -1;
    for (int v = 0; v < mesh->num_vertices(); ++v) {
      const Eigen::Vector3d X = mesh->rest.row(v);
      if (std::abs(X.x() - 0.2 * 4 / 12) < 1e-9 && std::abs(X.y() - 0.015) < 1e-9 && std::abs(X.z() - 0.03) < 1e-9) j = v;
    }
    NodeSeparation sep;
    sep.measure = Eigen::VectorXd::Zero(mesh->num_vertices());
    sep.toughness = Eigen::VectorXd::Constant(mesh->num_vertices(), 1000.0);
    sep.normal = Vertices::Zero(mesh->num_vertices(), 3);
    sep.normal.col(0).setOnes();
    const double a = 10.0 * 3.14159265358979 / 180.0;
    sep.normal.row(j) << std::cos(a), 0, std::sin(a);
    sep.measure(j) = 5000.0;
    // The section's other top nodes over the toughness too: a surface node whose split alone
    // would pinch the surface is undone, and the crack starts at one of them.
    for (int v = 0; v < mesh->num_vertices(); ++v) {
      if (v != j && std::abs(mesh->rest(v, 0) - mesh->rest(j, 0)) < 1e-9 && mesh->rest(v, 2) > 0.02) sep.measure(v) = 1200.0;
    }
    if (gap >= 0) sep.gap = Eigen::VectorXd::Constant(mesh->num_vertices(), gap);
    FractureOptions options;
    options.max_cracks = 1;
    options.cut_through = cut;
    model.UpdateRotations(mesh->x);
    SplitNodes(sep, options, 8, mesh, &model, change);
    return j;
  };
  std::vector<int> piece;
  TetMesh mesh;
  TopologyChange change;
  const int j = split(true, -1, &mesh, &change);
  std::printf("cut: %zu events, %d pieces\n", change.events.size(), ConnectedPieces(mesh, &piece));
  ASSERT_GE(j, 0);
  EXPECT_TRUE(CheckMesh(mesh).ok()) << CheckMesh(mesh).ToString();
  EXPECT_EQ(ConnectedPieces(mesh, &piece), 2);
  // Every vertex of the section's face loop (3 x 3 nodes) has a copy; the pieces hold 5 and
  // 8 cells of the 12.
  int cut = 0;
  for (const FractureEvent& e : change.events) cut += e.cut;
  EXPECT_EQ(static_cast<int>(change.events.size()), 9);
  EXPECT_EQ(cut, 8);
  std::vector<int> vertices(2, 0);
  for (int p : piece) ++vertices[p];
  EXPECT_EQ(std::min(vertices[0], vertices[1]), 5 * 9);
  EXPECT_EQ(change.removed_elements, 0);

  split(false, -1, &mesh, &change);
  EXPECT_EQ(ConnectedPieces(mesh, &piece), 1);
  EXPECT_EQ(change.events.size(), 1u);

  split(true, 0.0, &mesh, &change);  // the data shows the body whole
  EXPECT_EQ(ConnectedPieces(mesh, &piece), 1);
  split(true, 2.0, &mesh, &change);  // ... or open
  EXPECT_EQ(ConnectedPieces(mesh, &piece), 2);
}

}  // namespace
}  // namespace femreg
