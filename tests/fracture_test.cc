// Fracture: the separation tensor (seed eqs. 7-14), node splitting (Section 4.2), mesh
// validity after splits, and tracking through the bundled break and tear sequences.
#include "femreg/fracture.h"

#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <filesystem>
#include <memory>
#include <numeric>
#include <random>

#include "femreg/forward.h"
#include "femreg/io.h"
#include "femreg/point_cloud.h"
#include "femreg/scene.h"
#include "femreg/tracker.h"
#include "femreg_test_config.h"

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
  // Zero up to roundoff in both compressions.
  EXPECT_LT(confined, 1e-12 * sep.measure.maxCoeff());
  EXPECT_LT(uniaxial, 1e-12 * sep.measure.maxCoeff());
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
    if (mesh.rest(v, 0) < 0.035) EXPECT_EQ(piece[v], piece[0]);
    if (mesh.rest(v, 0) > 0.065) EXPECT_NE(piece[v], piece[0]);
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

}  // namespace
}  // namespace femreg
