// Every Ceres cost function of the registration energy: analytic Jacobians against central
// differences and ceres::GradientChecker, at random states, with a guard that the
// derivative is not trivially zero.
#include <ceres/ceres.h>
#include <ceres/gradient_checker.h>
#include <gtest/gtest.h>

#include <memory>
#include <random>
#include <vector>

#include "femreg/fem.h"
#include "solvers/ceres/cost_functions.h"

namespace femreg {
namespace {

using ceres_backend::EdgeSpringCost;
using ceres_backend::ElasticCost;
using ceres_backend::PointToPlaneCost1;
using ceres_backend::PointToPlaneCost3;
using ceres_backend::PointToPointCost1;
using ceres_backend::PointToPointCost3;

// Central-difference Jacobian of `cost` at `params` against its analytic Jacobian.
void ExpectJacobianMatchesCentralDifferences(const ceres::CostFunction& cost,
                                             std::vector<std::vector<double>> params) {
  const int nr = cost.num_residuals();
  const auto& sizes = cost.parameter_block_sizes();
  std::vector<double*> ptrs;
  for (auto& p : params) ptrs.push_back(p.data());
  std::vector<std::vector<double>> jac(sizes.size());
  std::vector<double*> jptrs;
  for (size_t b = 0; b < sizes.size(); ++b) {
    jac[b].assign(static_cast<size_t>(nr * sizes[b]), 0.0);
    jptrs.push_back(jac[b].data());
  }
  std::vector<double> r(nr);
  ASSERT_TRUE(cost.Evaluate(ptrs.data(), r.data(), jptrs.data()));
  double jac_norm = 0.0;
  const double h = 1e-6;
  for (size_t b = 0; b < sizes.size(); ++b) {
    for (int j = 0; j < sizes[b]; ++j) {
      const double saved = params[b][j];
      std::vector<double> rp(nr), rm(nr);
      params[b][j] = saved + h;
      ASSERT_TRUE(cost.Evaluate(ptrs.data(), rp.data(), nullptr));
      params[b][j] = saved - h;
      ASSERT_TRUE(cost.Evaluate(ptrs.data(), rm.data(), nullptr));
      params[b][j] = saved;
      for (int i = 0; i < nr; ++i) {
        const double numeric = (rp[i] - rm[i]) / (2 * h);
        const double analytic = jac[b][static_cast<size_t>(i * sizes[b] + j)];
        jac_norm += analytic * analytic;
        EXPECT_NEAR(analytic, numeric, 1e-6 * (1.0 + std::abs(numeric)))
            << "block " << b << " param " << j << " residual " << i;
      }
    }
  }
  EXPECT_GT(jac_norm, 1e-12) << "the Jacobian is trivially zero";
}

void ExpectGradientCheckerPasses(const ceres::CostFunction& cost,
                                 std::vector<std::vector<double>> params) {
  std::vector<double*> ptrs;
  for (auto& p : params) ptrs.push_back(p.data());
  ceres::NumericDiffOptions numeric_options;
  const std::vector<const ceres::Manifold*>* no_manifolds = nullptr;
  ceres::GradientChecker checker(&cost, no_manifolds, numeric_options);
  ceres::GradientChecker::ProbeResults results;
  EXPECT_TRUE(checker.Probe(ptrs.data(), 1e-7, &results)) << results.error_log;
  EXPECT_GT(results.maximum_relative_error, -1.0);
}

std::vector<double> RandomVec3(std::mt19937* rng, double scale = 1.0) {
  std::uniform_real_distribution<double> u(-scale, scale);
  return {u(*rng), u(*rng), u(*rng)};
}

Eigen::Matrix<double, 3, 4> RegularishTet(std::mt19937* rng) {
  std::uniform_real_distribution<double> u(-0.02, 0.02);
  Eigen::Matrix<double, 3, 4> X;
  X << 0, 0.1, 0, 0, 0, 0, 0.1, 0, 0, 0, 0, 0.1;
  for (int c = 0; c < 4; ++c)
    for (int r = 0; r < 3; ++r) X(r, c) += u(*rng);
  return X;
}

TEST(ElasticCost, JacobianMatchesCentralDifferencesAndGradientChecker) {
  std::mt19937 rng(7);
  Material material;
  material.youngs_modulus = 1e5;
  material.poisson_ratio = 0.35;
  for (int trial = 0; trial < 20; ++trial) {
    const Eigen::Matrix<double, 3, 4> X = RegularishTet(&rng);
    const ElementRest rest = BuildElementRest(X, material);
    // A random deformed state and the rotation of that state, held fixed as in one inner
    // solve.
    std::vector<std::vector<double>> params;
    Eigen::Matrix<double, 3, 4> x;
    const Eigen::Matrix3d Q = Eigen::AngleAxisd(1.3 * trial, Eigen::Vector3d(1, 2, 3).normalized())
                                  .toRotationMatrix();
    for (int c = 0; c < 4; ++c) {
      std::vector<double> p = RandomVec3(&rng, 0.02);
      Eigen::Vector3d xc = Q * X.col(c) + Eigen::Map<Eigen::Vector3d>(p.data());
      x.col(c) = xc;
      params.push_back({xc.x(), xc.y(), xc.z()});
    }
    const Eigen::Matrix3d R = PolarRotation(DeformationGradient(x, rest.dm_inv));
    ElasticCost cost(&rest, &R, 2.5);
    ExpectJacobianMatchesCentralDifferences(cost, params);
    ExpectGradientCheckerPasses(cost, params);
  }
}

TEST(ElasticCost, ResidualEnergyEqualsElementEnergy) {
  std::mt19937 rng(3);
  Material material;
  const ElementRest rest = BuildElementRest(RegularishTet(&rng), material);
  Vector12 x = rest.X;
  for (int i = 0; i < 12; ++i) x[i] += 0.01 * std::sin(3.0 * i);
  Eigen::Matrix<double, 3, 4> xm = Eigen::Map<Eigen::Matrix<double, 3, 4>>(x.data());
  const Eigen::Matrix3d R = PolarRotation(DeformationGradient(xm, rest.dm_inv));
  ElasticCost cost(&rest, &R, 1.0);
  std::vector<double*> p = {x.data(), x.data() + 3, x.data() + 6, x.data() + 9};
  Vector6 r;
  ASSERT_TRUE(cost.Evaluate(p.data(), r.data(), nullptr));
  EXPECT_NEAR(0.5 * r.squaredNorm(), ElementEnergy(rest, R, x), 1e-12);
  EXPECT_GT(r.squaredNorm(), 0.0);
}

TEST(DataCosts, JacobiansMatchCentralDifferencesAndGradientChecker) {
  std::mt19937 rng(11);
  for (int trial = 0; trial < 20; ++trial) {
    const std::vector<double> t = RandomVec3(&rng), n = RandomVec3(&rng);
    const Eigen::Vector3d target(t[0], t[1], t[2]);
    const Eigen::Vector3d normal = Eigen::Vector3d(n[0], n[1], n[2]).normalized();
    std::uniform_real_distribution<double> u(0.0, 1.0);
    Eigen::Vector3d bary(u(rng), u(rng), u(rng));
    bary /= bary.sum();
    const double w = 0.5 + u(rng);

    PointToPointCost1 p2p1(target, w);
    PointToPlaneCost1 p2l1(target, normal, w);
    PointToPointCost3 p2p3(bary, target, w);
    PointToPlaneCost3 p2l3(bary, target, normal, w);
    const std::vector<std::vector<double>> one = {RandomVec3(&rng)};
    const std::vector<std::vector<double>> three = {RandomVec3(&rng), RandomVec3(&rng),
                                                    RandomVec3(&rng)};
    for (const ceres::CostFunction* c : {static_cast<const ceres::CostFunction*>(&p2p1),
                                         static_cast<const ceres::CostFunction*>(&p2l1)}) {
      ExpectJacobianMatchesCentralDifferences(*c, one);
      ExpectGradientCheckerPasses(*c, one);
    }
    for (const ceres::CostFunction* c : {static_cast<const ceres::CostFunction*>(&p2p3),
                                         static_cast<const ceres::CostFunction*>(&p2l3)}) {
      ExpectJacobianMatchesCentralDifferences(*c, three);
      ExpectGradientCheckerPasses(*c, three);
    }
  }
}

TEST(EdgeSpringCost, JacobianMatchesCentralDifferencesAndGradientChecker) {
  std::mt19937 rng(13);
  for (int trial = 0; trial < 20; ++trial) {
    const std::vector<std::vector<double>> two = {RandomVec3(&rng), RandomVec3(&rng)};
    EdgeSpringCost cost(0.7, 3.0);
    ExpectJacobianMatchesCentralDifferences(cost, two);
    ExpectGradientCheckerPasses(cost, two);
  }
  // Zero at the rest length, under any rigid motion of the edge.
  EdgeSpringCost cost(0.5, 2.0);
  std::vector<double> a = {0.1, 0.2, 0.3}, b = {0.1, 0.2, 0.8};
  double* p[] = {a.data(), b.data()};
  double r = 1.0;
  ASSERT_TRUE(cost.Evaluate(p, &r, nullptr));
  EXPECT_NEAR(r, 0.0, 1e-15);
}

TEST(DataCosts, ZeroAtTarget) {
  const Eigen::Vector3d target(0.1, 0.2, 0.3);
  PointToPointCost1 cost(target, 4.0);
  std::vector<double> x = {0.1, 0.2, 0.3};
  double* p[] = {x.data()};
  double r[3];
  ASSERT_TRUE(cost.Evaluate(p, r, nullptr));
  EXPECT_EQ(r[0], 0.0);
  EXPECT_EQ(r[1], 0.0);
  EXPECT_EQ(r[2], 0.0);
}

}  // namespace
}  // namespace femreg
