// The equilibrium penalties (energy/equilibrium.h): their gradients and curvatures against
// central differences, the pushing-only cone (nothing more inside it, its side's curvature just
// outside), the pieces a step's model is re-solved across, and the penalty as least squares.
#include <gtest/gtest.h>

#include <Eigen/Eigenvalues>
#include <Eigen/Geometry>
#include <cmath>
#include <cstdio>
#include <random>
#include <string>

#include "energy/equilibrium.h"
#include "test_util.h"

namespace femreg {
namespace {

using testing_util::Format;

// One vertex of each kind, the free one with every option.
energy::Equilibrium Sites(bool pushing_only, double friction, double sparsity) {
  energy::Equilibrium eq;
  eq.site = {energy::ForceSite::kBalanced, energy::ForceSite::kFree, energy::ForceSite::kSupport};
  eq.force_weight = {1.0, 0.7, 1.0};
  eq.strong_weight = {50.0, 80.0, 50.0};
  eq.sparsity = {0.0, sparsity, 0.0};
  eq.sparsity_floor = 0.05;
  eq.pushing_only = pushing_only;
  eq.friction = friction;
  eq.normal.assign(3, Eigen::Vector3d(1, 2, 2) / 3.0);
  return eq;
}

// check(eq, v, f, sparsity, label) for 200 random forces f on each vertex v of every option
// set: L2 alone, pushing only (a half-space, frictionless, friction 0.6), each with and
// without the sparse term.
template <class Check>
void ForEachOptionsAndForce(unsigned seed, Check check) {
  std::mt19937 rng(seed);
  std::normal_distribution<double> normal(0.0, 1.0);
  for (bool pushing : {false, true}) {
    for (double friction : {-1.0, 0.0, 0.6}) {
      if (friction >= 0 && !pushing) continue;
      for (double sparsity : {0.0, 0.3}) {
        const energy::Equilibrium eq = Sites(pushing, friction, sparsity);
        ASSERT_TRUE(eq.IsValid(3));
        for (int trial = 0; trial < 200; ++trial) {
          for (int v = 0; v < 3; ++v) {
            const Eigen::Vector3d f(normal(rng), normal(rng), normal(rng));
            const std::string label = "vertex " + std::to_string(v) + " pushing " + std::to_string(pushing) +
                                      " friction " + std::to_string(friction) + " sparsity " + std::to_string(sparsity) +
                                      " f " + Format(f);
            check(eq, v, f, sparsity, label);
          }
        }
      }
    }
  }
}

TEST(EquilibriumPenalty, GradientAndCurvatureMatchCentralDifferencesAndCurvatureIsPositive) {
  ForEachOptionsAndForce(5, [](const energy::Equilibrium& eq, int v, const Eigen::Vector3d& f, double sparsity,
                               const std::string& label) {
    Eigen::Vector3d g;
    Eigen::Matrix3d c;
    const double value = eq.Penalty(v, f, &g, &c);
    EXPECT_GE(value, 0.0);
    const double h = 1e-6;
    for (int k = 0; k < 3; ++k) {
      Eigen::Vector3d fp = f, fm = f;
      fp[k] += h;
      fm[k] -= h;
      const double slope = (eq.Penalty(v, fp, nullptr, nullptr) - eq.Penalty(v, fm, nullptr, nullptr)) / (2 * h);
      EXPECT_NEAR(g[k], slope, 1e-5 * (1.0 + g.norm())) << label;
    }
    // The cone's curvature is exact (the sparse term's is a majorizer): the gradient's
    // central differences, away from the cone's edges (random f are, almost surely).
    if (sparsity == 0.0) {
      for (int k = 0; k < 3; ++k) {
        Eigen::Vector3d fp = f, fm = f, gp, gm;
        fp[k] += h;
        fm[k] -= h;
        eq.Penalty(v, fp, &gp, nullptr);
        eq.Penalty(v, fm, &gm, nullptr);
        EXPECT_LT((c.col(k) - (gp - gm) / (2 * h)).norm(), 1e-5 * (1.0 + c.norm())) << label;
      }
    }
    EXPECT_LT((c - c.transpose()).norm(), 1e-12 * (1.0 + c.norm()));
    EXPECT_GT(Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d>(c).eigenvalues().minCoeff(), -1e-12);
  });
}

// The least-squares form (for the Ceres back end): 1/2 |r|^2 plus the sparse term is the
// penalty, and dr/df matches the residuals' central differences.
TEST(EquilibriumPenalty, ResidualsAreThePenaltyAsLeastSquares) {
  ForEachOptionsAndForce(7, [](const energy::Equilibrium& eq, int v, const Eigen::Vector3d& f, double /*sparsity*/,
                               const std::string& label) {
    Eigen::Matrix<double, 6, 1> r, rp, rm;
    Eigen::Matrix<double, 6, 3> j, unused;
    eq.Residuals(v, f, &r, &j);
    const double s = eq.sparsity[static_cast<size_t>(v)];
    const double floor = eq.sparsity_floor;
    const double sparse = s * (std::sqrt(f.squaredNorm() + floor * floor) - floor);
    EXPECT_NEAR(0.5 * r.squaredNorm() + sparse, eq.Penalty(v, f, nullptr, nullptr), 1e-12 * (1.0 + r.squaredNorm()))
        << label;
    const double h = 1e-6;
    for (int k = 0; k < 3; ++k) {
      Eigen::Vector3d fp = f, fm = f;
      fp[k] += h;
      fm[k] -= h;
      eq.Residuals(v, fp, &rp, &unused);
      eq.Residuals(v, fm, &rm, &unused);
      EXPECT_LT((j.col(k) - (rp - rm) / (2 * h)).norm(), 1e-5 * (1.0 + j.norm())) << label;
    }
  });
}

TEST(EquilibriumPenalty, PushingOnlyCostsNothingMoreInsideTheConeAndTheSupportNothing) {
  const energy::Equilibrium free = Sites(false, -1.0, 0.0);
  const energy::Equilibrium cone = Sites(true, 0.5, 0.0);
  const Eigen::Vector3d n = cone.normal[1];
  const Eigen::Vector3d t = n.unitOrthogonal();
  const Eigen::Vector3d push = -2.0 * n + 0.9 * t;  // |f_t| = 0.9 <= 0.5 * 2
  const double inside = free.Penalty(1, push, nullptr, nullptr);
  EXPECT_NEAR(cone.Penalty(1, push, nullptr, nullptr), inside, 1e-14 * inside);
  const Eigen::Vector3d slide = -2.0 * n + 1.5 * t;  // beyond the cone
  EXPECT_GT(cone.Penalty(1, slide, nullptr, nullptr), free.Penalty(1, slide, nullptr, nullptr));
  const Eigen::Vector3d pull = 2.0 * n;  // the whole pull is outside: 1/2 beta |f|^2 more
  EXPECT_NEAR(cone.Penalty(1, pull, nullptr, nullptr) - free.Penalty(1, pull, nullptr, nullptr),
              0.5 * cone.strong_weight[1] * pull.squaredNorm(), 1e-12);
  EXPECT_EQ(cone.Penalty(2, pull, nullptr, nullptr), 0.0);
  const double balanced = 0.5 * cone.strong_weight[0] * pull.squaredNorm();
  EXPECT_NEAR(cone.Penalty(0, pull, nullptr, nullptr), balanced, 1e-14 * balanced);
  // Frictionless, a pull straight along the normal is all outside (the ray), a push not.
  const energy::Equilibrium ray = Sites(true, 0.0, 0.0);
  EXPECT_NEAR(ray.Penalty(1, pull, nullptr, nullptr) - free.Penalty(1, pull, nullptr, nullptr),
              0.5 * ray.strong_weight[1] * pull.squaredNorm(), 1e-12);
  EXPECT_NEAR(ray.Penalty(1, -pull, nullptr, nullptr), free.Penalty(1, -pull, nullptr, nullptr), 1e-12);
}

// PenaltyPiece names the piece of the pushing-only penalty that holds at f (the steps' model
// is re-solved where a step changes it): inside the cone, beyond the half-space's face, the
// cone's side or its apex; 0 off the free surface and without pushing_only.
TEST(EquilibriumPenalty, PiecesAreTheConesRegions) {
  const energy::Equilibrium free = Sites(false, -1.0, 0.0);
  const energy::Equilibrium cone = Sites(true, 0.5, 0.0);
  const energy::Equilibrium half_space = Sites(true, -1.0, 0.0);
  const energy::Equilibrium ray = Sites(true, 0.0, 0.0);
  const Eigen::Vector3d n = cone.normal[1];
  const Eigen::Vector3d t = n.unitOrthogonal();
  const Eigen::Vector3d push = -2.0 * n + 0.9 * t, slide = -2.0 * n + 1.5 * t, pull = 2.0 * n + 0.1 * t;
  EXPECT_EQ(cone.PenaltyPiece(1, push), 0);
  EXPECT_EQ(cone.PenaltyPiece(1, slide), 2);
  EXPECT_EQ(cone.PenaltyPiece(1, pull), 3);
  EXPECT_EQ(half_space.PenaltyPiece(1, slide), 0);
  EXPECT_EQ(half_space.PenaltyPiece(1, pull), 1);
  EXPECT_EQ(ray.PenaltyPiece(1, push), 2);      // frictionless: any sideways part is beyond the side
  EXPECT_EQ(ray.PenaltyPiece(1, pull), 3);
  for (const Eigen::Vector3d& f : {push, slide, pull}) {
    EXPECT_EQ(free.PenaltyPiece(1, f), 0);
    EXPECT_EQ(cone.PenaltyPiece(0, f), 0);  // balanced
    EXPECT_EQ(cone.PenaltyPiece(2, f), 0);  // a support
  }
}

// Just outside the cone's side the curvature is its side's (u u^T plus a vanishing b b^T),
// continuous with the inside's nothing, not the apex's beta I.
TEST(EquilibriumPenalty, CurvatureJustOutsideTheConesSideIsTheSides) {
  const energy::Equilibrium cone = Sites(true, 0.5, 0.0);
  const energy::Equilibrium free = Sites(false, -1.0, 0.0);
  const Eigen::Vector3d n = cone.normal[1];
  const Eigen::Vector3d t = n.unitOrthogonal();
  for (double excess : {1e-15, 1e-12, 1e-9}) {
    const Eigen::Vector3d f = -2.0 * n + (1.0 + excess) * t;  // |f_t| just above 0.5 * 2
    Eigen::Matrix3d c, c_free;
    cone.Penalty(1, f, nullptr, &c);
    free.Penalty(1, f, nullptr, &c_free);
    const double beta = cone.strong_weight[1];
    EXPECT_LE((c - c_free).trace(), beta * (1.0 + 1e-6)) << "excess " << excess;
    EXPECT_GE((c - c_free).trace(), 0.0);
    // (At 1e-15 the force may round back inside; beyond, it is on the side: u u^T.)
    if (excess >= 1e-12) {
      EXPECT_GE((c - c_free).trace(), beta * (1.0 - 1e-6)) << "excess " << excess;
    }
  }
}

}  // namespace
}  // namespace femreg
