// The forward solve's contact potential is the energy layer's ContactPenalty (energy/contact.h)
// evaluated on the detected contacts: its value agrees with the collision world's own
// 1/2 k delta^2 (CollisionWorld::Evaluate, computed from the contacts directly), its Hessian
// is the derivative of its gradient, and the blocks carry the contact's stencil.
#include <gtest/gtest.h>

#include <Eigen/Sparse>
#include <algorithm>
#include <cmath>
#include <random>
#include <vector>

#include "collision/contact_blocks.h"
#include "energy/term.h"
#include "femreg/collision.h"
#include "femreg/io.h"

namespace femreg {
namespace {

// A 6 x 6 x 3 cm block on a floor plane (z = 1 mm, through its bottom), a 4 x 4 x 3 cm block
// pressed 3 mm into its top; every vertex jittered by 0.3 mm so that contacts have
// different depths and normals. D = 2.5 mm, k = 2000 N/m.
struct Pressed {
  TetMesh mesh;
  std::vector<Triangles> surfaces;
  CollisionWorld world;
  Vertices x;
};

void MakePressed(Pressed* p) {
  const TetMesh lower = MakeBox(Eigen::Vector3d(0.06, 0.06, 0.03), 6, 6, 3);
  const TetMesh upper =
      MakeBox(Eigen::Vector3d(0.04, 0.04, 0.03), 4, 4, 3, Eigen::Vector3d(0.01, 0.01, 0.0315));
  std::vector<int> offsets;
  p->mesh = MergeMeshes({lower, upper}, &offsets);
  p->surfaces = {lower.surface, (upper.surface.array() + offsets[1]).matrix()};
  CollisionSpec spec;
  spec.pairs = {{"lower", "upper"}};
  spec.distance = 0.0025;
  spec.stiffness = 2e3;
  ObstacleSpec floor;
  floor.name = "floor";
  floor.kind = ObstacleSpec::Kind::kPlane;
  floor.plane_point = Eigen::Vector3d(0, 0, 0.001);
  floor.plane_normal = Eigen::Vector3d::UnitZ();
  spec.obstacles.push_back(floor);
  const Status status = p->world.Init(spec, {"lower", "upper"}, p->surfaces, p->mesh.x);
  ASSERT_TRUE(status.ok()) << status.message();
  p->x = p->mesh.x;
  for (int v = offsets[1]; v < p->x.rows(); ++v) p->x(v, 2) -= 0.003;
  std::mt19937 rng(3);
  std::normal_distribution<double> jitter(0.0, 3e-4);
  for (int v = 0; v < p->x.rows(); ++v) {
    p->x.row(v) += Eigen::RowVector3d(jitter(rng), jitter(rng), jitter(rng));
  }
}

Eigen::SparseMatrix<double> Hessian(const ContactPotential& potential, const Vertices& x) {
  std::vector<Eigen::Triplet<double>> triplets;
  potential.AddHessian(x, &triplets);
  Eigen::SparseMatrix<double> H(3 * x.rows(), 3 * x.rows());
  H.setFromTriplets(triplets.begin(), triplets.end());
  return H;
}

TEST(ContactPotential, ValueIsTheWorldsPenaltyOverObstacleAndPairContacts) {
  Pressed p;
  ASSERT_NO_FATAL_FAILURE(MakePressed(&p));
  ContactPotential potential(&p.world, 0.0025);
  potential.Refresh(p.x);
  int obstacle = 0, pair = 0;
  for (const Contact& c : potential.contacts()) ++(c.obstacle() ? obstacle : pair);
  ASSERT_GT(obstacle, 0);
  ASSERT_GT(pair, 0);
  const ContactStats stats = p.world.Evaluate(potential.contacts(), p.x);
  ASSERT_GT(stats.contacts, 0);
  ASSERT_GT(stats.energy, 0.0);
  Eigen::VectorXd g = Eigen::VectorXd::Zero(3 * p.x.rows());
  const double with_gradient = potential.Evaluate(p.x, &g);
  const double value_only = potential.Evaluate(p.x, nullptr);
  // The same sum of 1/2 k delta^2 over ~100 contacts, delta computed as -n . (p_a - p_b)
  // by the world and as offset - sum c_i n . x_i by the blocks: round-off alone, ~1e-16
  // relative per term; 1e-12 leaves room for the order of the sums.
  EXPECT_NEAR(with_gradient, stats.energy, 1e-12 * stats.energy);
  EXPECT_NEAR(value_only, stats.energy, 1e-12 * stats.energy);
  EXPECT_GT(g.norm(), 0.0);
  // Every block's stencil is its contact's: side a, then side b with negated barycentrics.
  for (const Contact& c : potential.contacts()) {
    const double delta = p.world.Penetration(c, p.x);
    if (c.obstacle()) {
      const auto block = ObstaclePenaltyBlock(c, 0.0, p.world.stiffness());
      EXPECT_NEAR(block.Penetration(energy::StencilPositions(block, p.x).data()), delta, 1e-15);
    } else {
      const auto block = PairPenaltyBlock(c, 0.0, p.world.stiffness());
      EXPECT_NEAR(block.Penetration(energy::StencilPositions(block, p.x).data()), delta, 1e-15);
      EXPECT_EQ(block.vertices[3], c.vertices_b[0]);
      EXPECT_EQ(block.coefficients[3], -c.bary_b[0]);
    }
  }
}

TEST(ContactPotential, HessianIsTheGradientsDerivativeAndPositiveSemiDefinite) {
  Pressed p;
  ASSERT_NO_FATAL_FAILURE(MakePressed(&p));
  ContactPotential potential(&p.world, 0.0025);
  potential.Refresh(p.x);
  const Eigen::SparseMatrix<double> H = Hessian(potential, p.x);
  ASSERT_GT(H.norm(), 0.0);
  const Eigen::SparseMatrix<double> asymmetry = H - Eigen::SparseMatrix<double>(H.transpose());
  EXPECT_LE(asymmetry.norm(), 1e-12 * H.norm());

  // A step of a tenth of the shallowest |delta| (0.15 mm here): no contact opens or closes,
  // the penalty stays one quadratic, and g(x + s) - g(x) = H s holds up to the gradients'
  // round-off (~1e-16 |g| per entry, |g| ~ 100 N, against |H s| ~ 2 N): 1e-10 relative
  // leaves a margin of 1000 over it, and is far below what a wrong block would give.
  double shallowest = 1e300;
  for (const Contact& c : potential.contacts()) {
    shallowest = std::min(shallowest, std::abs(p.world.Penetration(c, p.x)));
  }
  ASSERT_GT(shallowest, 0.0);
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> unit(-1.0, 1.0);
  Vertices step(p.x.rows(), 3);
  for (int i = 0; i < step.size(); ++i) step.data()[i] = unit(rng);
  step *= 0.1 * shallowest / step.rowwise().norm().maxCoeff();
  Eigen::VectorXd g0 = Eigen::VectorXd::Zero(3 * p.x.rows()), g1 = g0;
  potential.Evaluate(p.x, &g0);
  potential.Evaluate(p.x + step, &g1);
  const Eigen::Map<const Eigen::VectorXd> s(step.data(), step.size());
  const Eigen::VectorXd Hs = H * s;
  ASSERT_GT(Hs.norm(), 0.0);
  EXPECT_LE((g1 - g0 - Hs).norm(), 1e-10 * Hs.norm());
  // k J^T J: s^T H s >= 0 for any s (round-off aside).
  for (int trial = 0; trial < 5; ++trial) {
    Eigen::VectorXd r(3 * p.x.rows());
    for (int i = 0; i < r.size(); ++i) r(i) = unit(rng);
    EXPECT_GE(r.dot(H * r), -1e-12 * H.norm() * r.squaredNorm());
  }
}

}  // namespace
}  // namespace femreg
