// Every block type of the energy layer, checked by one generic test over the registry
// (energy::Problem::Sets): its Jacobian against central differences and, through the Ceres
// back end's cost adapter, ceres::GradientChecker; the generic linearization (gradient
// and Gauss-Newton blocks, with each robust loss) against central differences of the value;
// symmetric positive semi-definite Gauss-Newton blocks. A block type added to the registry
// without a Sample<> (tests/energy_samples.h) does not compile. Then the robust losses, and the elastic
// invariants (zero energy and force at rest and under rigid motion).
#include "energy_samples.h"

namespace femreg {
namespace testing_util {
namespace {

TYPED_TEST_SUITE(EnergyBlockTest, typename BlockTypesOf<energy::Problem::Sets>::type);

TYPED_TEST(EnergyBlockTest, JacobianMatchesCentralDifferences) {
  using T = TypeParam;
  std::mt19937 rng(7);
  for (int trial = 0; trial < kTrials; ++trial) {
    Sample<T> s(&rng);
    constexpr int m = T::kResiduals, n = T::kVertices;
    std::array<Eigen::Matrix<double, m, 3, Eigen::RowMajor>, n> J;
    std::array<double*, n> Jp;
    for (int i = 0; i < n; ++i) Jp[i] = J[i].data();
    Eigen::VectorXd r(m);
    const auto p = energy::StencilPositions(s.block, s.x);
    ASSERT_TRUE(s.block.Evaluate(p.data(), r.data(), Jp.data()));
    double norm = 0.0;
    const double h = 1e-7;
    for (int i = 0; i < n; ++i) {
      for (int c = 0; c < 3; ++c) {
        Vertices xp = s.x, xm = s.x;
        xp(i, c) += h;
        xm(i, c) -= h;
        const Eigen::VectorXd numeric = (Residual(s.block, xp) - Residual(s.block, xm)) / (2 * h);
        for (int k = 0; k < m; ++k) {
          norm += J[i](k, c) * J[i](k, c);
          EXPECT_NEAR(J[i](k, c), numeric[k], 1e-6 * (1.0 + std::abs(numeric[k])))
              << Sample<T>::kName << " vertex " << i << " coordinate " << c << " residual " << k;
        }
      }
    }
    EXPECT_GT(norm, 1e-12) << Sample<T>::kName << ": the Jacobian is trivially zero";
  }
}

TYPED_TEST(EnergyBlockTest, CeresCostPassesGradientChecker) {
  using T = TypeParam;
  std::mt19937 rng(11);
  for (int trial = 0; trial < kTrials; ++trial) {
    Sample<T> s(&rng);
    ceres_backend::TermCost<T> cost(&s.block, std::sqrt(s.block.weight));
    // The checker's relative step is too small near coordinates at 0: shift the state off
    // the origin (every block is translation-covariant in its inputs).
    std::vector<std::vector<double>> params;
    for (int i = 0; i < T::kVertices; ++i) params.push_back({s.x(i, 0), s.x(i, 1), s.x(i, 2)});
    std::vector<double*> ptrs;
    for (auto& q : params) ptrs.push_back(q.data());
    // Ridders' first step (1e-2 |x|) would cross the contact penalty's hinge: start smaller.
    ceres::NumericDiffOptions numeric;
    numeric.ridders_relative_initial_step_size = 1e-5;
    const std::vector<const ceres::Manifold*>* no_manifolds = nullptr;
    ceres::GradientChecker checker(&cost, no_manifolds, numeric);
    ceres::GradientChecker::ProbeResults results;
    EXPECT_TRUE(checker.Probe(ptrs.data(), 1e-6, &results)) << Sample<T>::kName << "\n" << results.error_log;
  }
}

// The value 1/2 w rho(|r|^2) and its generic gradient, for every loss.
TYPED_TEST(EnergyBlockTest, LinearizationIsTheValuesGradientAndItsBlocksArePsd) {
  using T = TypeParam;
  constexpr int n = T::kVertices;
  std::mt19937 rng(13);
  for (RobustLoss kind : {RobustLoss::kNone, RobustLoss::kHuber, RobustLoss::kCauchy, RobustLoss::kTukey}) {
    for (int trial = 0; trial < kTrials; ++trial) {
      Sample<T> s(&rng);
      // The loss bends near the residual's size, so both branches are exercised; never at
      // the bend itself, where central differences of a C1 loss err by h times the jump of
      // its second derivative (visible on the stiff inversion barrier).
      const double size = Residual(s.block, s.x).norm();
      const Loss loss{kind, kind == RobustLoss::kNone ? 1.0 : (0.45 + 0.1 * (trial % 12)) * std::max(size, 1e-9)};
      energy::Linearization<T> lin;
      ASSERT_TRUE(energy::Linearize(s.block, loss, s.x, &lin));
      // Round-off of |r|^2 (summed two ways), which includes the offset where there is one.
      EXPECT_NEAR(lin.value, energy::BlockValue(s.block, loss, s.x),
                  1e-15 * (1 + lin.value + 8 * energy::OffsetValue(s.block, loss)));
      const double h = 1e-7;
      double norm = 0.0;
      for (int i = 0; i < n; ++i) {
        for (int c = 0; c < 3; ++c) {
          Vertices xp = s.x, xm = s.x;
          xp(i, c) += h;
          xm(i, c) -= h;
          const double numeric =
              (energy::BlockValue(s.block, loss, xp) - energy::BlockValue(s.block, loss, xm)) / (2 * h);
          norm += numeric * numeric;
          EXPECT_NEAR(lin.gradient[i][c], numeric, 1e-6 * (1.0 + std::abs(numeric)) * std::max(1.0, lin.scale))
              << Sample<T>::kName << " loss " << static_cast<int>(kind) << " vertex " << i << " coordinate " << c;
        }
      }
      // (Not at Tukey's bend, where rho' is a round-off-sized positive number: with the
      // neo-Hookean element's large |r| the differences of the value are then 0.)
      if (lin.scale > 1e-6 * s.block.weight) {
        EXPECT_GT(norm, 0.0) << Sample<T>::kName << ": trivially zero gradient";
      }
      Eigen::MatrixXd H(3 * n, 3 * n);
      for (int i = 0; i < n; ++i)
        for (int j = 0; j < n; ++j) H.block<3, 3>(3 * i, 3 * j) = lin.hessian[i * n + j];
      EXPECT_LT((H - H.transpose()).norm(), 1e-12 * (1 + H.norm()));
      const double smallest = Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd>(H).eigenvalues().minCoeff();
      EXPECT_GT(smallest, -1e-10 * (1 + H.norm())) << Sample<T>::kName;
    }
  }
}

// Linearize's value, gradient and Gauss-Newton blocks are w rho' (J^T r, J^T J) from
// Evaluate's r and J, with every loss: for a block type with a closed form (Normal), that
// form against the residual and Jacobian the Ceres back end uses.
TYPED_TEST(EnergyBlockTest, LinearizationIsTheNormalEquationsOfEvaluate) {
  using T = TypeParam;
  constexpr int m = T::kResiduals, n = T::kVertices;
  std::mt19937 rng(17);
  for (RobustLoss kind : {RobustLoss::kNone, RobustLoss::kHuber, RobustLoss::kCauchy, RobustLoss::kTukey}) {
    for (int trial = 0; trial < kTrials; ++trial) {
      Sample<T> s(&rng);
      std::array<Eigen::Matrix<double, m, 3, Eigen::RowMajor>, n> J;
      std::array<double*, n> Jp;
      for (int i = 0; i < n; ++i) Jp[i] = J[i].data();
      Eigen::Matrix<double, m, 1> r;
      const auto p = energy::StencilPositions(s.block, s.x);
      ASSERT_TRUE(s.block.Evaluate(p.data(), r.data(), Jp.data()));
      const Loss loss{kind, kind == RobustLoss::kNone ? 1.0 : (0.45 + 0.1 * (trial % 10)) * std::max(r.norm(), 1e-9)};  // not at the bend: rho' there is 0 up to round-off
      double rho[3];
      loss.Evaluate(r.squaredNorm(), rho);
      const double scale = s.block.weight * rho[1];
      energy::Linearization<T> lin;
      ASSERT_TRUE(energy::Linearize(s.block, loss, s.x, &lin));
      const double value = 0.5 * s.block.weight * rho[0] - energy::OffsetValue(s.block, loss);
      EXPECT_NEAR(lin.value, value, 1e-12 * 0.5 * s.block.weight * rho[0] + 1e-300) << Sample<T>::kName;
      EXPECT_NEAR(lin.scale, scale, 1e-10 * std::abs(scale) + 1e-300) << Sample<T>::kName;
      for (int i = 0; i < n; ++i) {
        const Eigen::Vector3d g = scale * J[i].transpose() * r;
        EXPECT_LT((lin.gradient[i] - g).norm(), 1e-10 * (g.norm() + 1e-300) + 1e-300)
            << Sample<T>::kName << " loss " << static_cast<int>(kind) << " vertex " << i;
        for (int j = 0; j < n; ++j) {
          const Eigen::Matrix3d h = scale * J[i].transpose() * J[j];
          EXPECT_LT((lin.hessian[i * n + j] - h).norm(), 1e-10 * (h.norm() + 1e-300) + 1e-300)
              << Sample<T>::kName << " loss " << static_cast<int>(kind) << " block " << i << "," << j;
        }
      }
    }
  }
}

// The value and gradient of a whole problem: the sum of its blocks'.
TEST(EnergyProblem, EvaluateSumsTheSetsByGroup) {
  std::mt19937 rng(3);
  Sample<energy::ElasticElement> e(&rng);
  energy::Problem problem;
  problem.Reset(4);
  problem.AddSet<energy::ElasticElement>(energy::TermGroup::kElastic).Add(e.block);
  auto& springs = problem.AddSet<energy::VertexSpring>(energy::TermGroup::kTemporal);
  springs.Add(energy::MakeVertexSpring(2, Eigen::Vector3d(0.1, 0.2, 0.3), 4.0));
  const EnergyTerms t = problem.Evaluate(e.x);
  EXPECT_NEAR(t.elastic, 2.5 * ElementEnergy(e.rest, e.rotation, Eigen::Map<const Vector12>(
                                                                         Vertices(e.x).data())),
              1e-12 * t.elastic);
  EXPECT_NEAR(t.temporal, 0.5 * 4.0 * (e.x.row(2) - Eigen::RowVector3d(0.1, 0.2, 0.3)).squaredNorm(), 1e-15);
  EXPECT_EQ(t.data, 0.0);
  EXPECT_EQ(problem.num_blocks(), 2);
  problem.Clear(energy::TermGroup::kTemporal);
  EXPECT_EQ(problem.Evaluate(e.x).temporal, 0.0);
}

// On several threads the energy is the one-thread sum (sets summed in fixed chunks, added in
// chunk order), and the chunked sum is the blocks' sum. A set of 3000 elements (12 chunks)
// with weights over 7 decades, and one of 100 springs (one chunk). Compared to 1e-13: the
// additions are the same on every thread count, but another compiler may contract the
// serial and the parallel copy of a chunk's loop into fused multiply-adds differently.
TEST(EnergyProblem, EvaluateOnSeveralThreadsIsTheOneThreadSum) {
  std::mt19937 rng(5);
  std::vector<std::unique_ptr<Sample<energy::ElasticElement>>> elements;
  for (int i = 0; i < 3000; ++i) elements.push_back(std::make_unique<Sample<energy::ElasticElement>>(&rng));
  const int num_vertices = 4 * 3000;
  Vertices x(num_vertices, 3);
  energy::Problem problem;
  problem.Reset(num_vertices);
  auto& set = problem.AddSet<energy::ElasticElement>(energy::TermGroup::kElastic);
  double elastic = 0.0;
  for (int i = 0; i < 3000; ++i) {
    const Sample<energy::ElasticElement>& e = *elements[static_cast<size_t>(i)];
    energy::ElasticElement b = e.block;
    b.weight = std::pow(10.0, i % 7 - 3);
    for (int k = 0; k < 4; ++k) {
      b.vertices[k] = 4 * i + k;
      x.row(4 * i + k) = e.x.row(e.block.vertices[k]);
    }
    set.Add(b);
    elastic += energy::BlockValue(b, set.loss(), x);
  }
  auto& springs = problem.AddSet<energy::VertexSpring>(energy::TermGroup::kTemporal);
  double temporal = 0.0;
  for (int v = 0; v < 100; ++v) {
    springs.Add(energy::MakeVertexSpring(v, Eigen::Vector3d(0.1, 0.2, 0.3), 4.0));
    temporal += energy::BlockValue(springs.blocks().back(), springs.loss(), x);
  }
  const EnergyTerms one = problem.Evaluate(x, 1);
  EXPECT_NEAR(one.elastic, elastic, 1e-12 * elastic);
  EXPECT_NEAR(one.temporal, temporal, 1e-13 * temporal);
  for (int threads : {0, 2, 3, 8}) {  // 0: the machine's count, as ParallelFor's
    const EnergyTerms several = problem.Evaluate(x, threads);
    EXPECT_NEAR(several.elastic, one.elastic, 1e-13 * one.elastic) << threads;
    EXPECT_NEAR(several.temporal, one.temporal, 1e-13 * one.temporal) << threads;
  }
}

// rho', rho'' against central differences, on both sides of the bend; the same numbers as
// Ceres' own losses.
// The load's force is exactly f where the block is made (the outer iteration's start), and
// its energy is the potential -f . dx there to first order.
TEST(ExternalLoad, ForceIsExactAtTheOriginAndTheEnergyIsThePotential) {
  const Eigen::Vector3d f(0.3, -0.1, -2.0), origin(0.1, 0.2, 0.3);
  energy::ExternalLoad block;
  ASSERT_TRUE(energy::MakeExternalLoad(0, f, origin, 0.01, &block));
  EXPECT_FALSE(energy::MakeExternalLoad(0, Eigen::Vector3d::Zero(), origin, 0.01, &block));
  Vertices x(1, 3);
  x.row(0) = origin.transpose();
  energy::Linearization<energy::ExternalLoad> lin;
  ASSERT_TRUE(energy::Linearize(block, energy::Loss(), x, &lin));
  EXPECT_LT((lin.gradient[0] + f).norm(), 1e-14 * f.norm());
  const double at_origin = lin.value;
  const Eigen::Vector3d dx(1e-5, -2e-5, 3e-5);
  x.row(0) += dx.transpose();
  const double moved = energy::BlockValue(block, energy::Loss(), x);
  EXPECT_NEAR(moved - at_origin, -f.dot(dx), 1e-3 * std::abs(f.dot(dx)));
}

TEST(RobustLoss, DerivativesMatchCentralDifferencesAndCeres) {
  const double a = 0.005;
  for (RobustLoss kind : {RobustLoss::kNone, RobustLoss::kHuber, RobustLoss::kCauchy, RobustLoss::kTukey}) {
    const Loss loss{kind, a};
    // rho(0) = 0: an inactive block's value is its offset alone (energy/term.h InactiveValue).
    double at_zero[3];
    loss.Evaluate(0.0, at_zero);
    EXPECT_EQ(at_zero[0], 0.0) << static_cast<int>(kind);
    std::unique_ptr<ceres::LossFunction> reference;
    if (kind == RobustLoss::kHuber) reference = std::make_unique<ceres::HuberLoss>(a);
    if (kind == RobustLoss::kCauchy) reference = std::make_unique<ceres::CauchyLoss>(a);
    if (kind == RobustLoss::kTukey) reference = std::make_unique<ceres::TukeyLoss>(a);
    for (double s : {1e-7, 4e-6, 2.4e-5, 2.6e-5, 1e-4, 3e-3}) {
      double rho[3], rp[3], rm[3];
      loss.Evaluate(s, rho);
      const double h = 1e-4 * s;
      loss.Evaluate(s + h, rp);
      loss.Evaluate(s - h, rm);
      EXPECT_NEAR(rho[1], (rp[0] - rm[0]) / (2 * h), 1e-6 * (1 + std::abs(rho[1]))) << static_cast<int>(kind) << " s " << s;
      EXPECT_NEAR(rho[2], (rp[1] - rm[1]) / (2 * h), 1e-5 * (1 + std::abs(rho[2]) * s) / s)
          << static_cast<int>(kind) << " s " << s;
      if (reference) {
        double c[3];
        reference->Evaluate(s, c);
        for (int i = 0; i < 3; ++i) EXPECT_NEAR(rho[i], c[i], 1e-12 * std::abs(c[i]) + 1e-300);
      }
    }
  }
}

// The neo-Hookean element: zero energy (its offset left out) and force at rest and under
// any rigid motion, with no rotation to hold; the value is the fem layer's energy.
TEST(NeoHookeanElement, ZeroAtRestAndUnderRigidMotionAndIsTheElementEnergy) {
  std::mt19937 rng(6);
  for (int trial = 0; trial < 100; ++trial) {
    Sample<energy::NeoHookeanElement> s(&rng);
    const Vector12 strained = [&] {
      Vector12 v;
      for (int c = 0; c < 4; ++c) v.segment<3>(3 * c) = s.x.row(c).transpose();
      return v;
    }();
    Vector12 force;
    const double expected = s.block.weight * NeoHookeanEnergyAndForce(s.rest, NeoHookeanKappa(s.rest, false), 0.0, strained, &force);
    EXPECT_NEAR(energy::BlockValue(s.block, Loss(), s.x), expected, 1e-9 * s.block.Offset() * s.block.weight);
    const Eigen::Matrix3d Q =
        Eigen::AngleAxisd(0.7 * trial, RandomPoint(&rng, 1).normalized()).toRotationMatrix();
    const Eigen::Vector3d t = RandomPoint(&rng, 1);
    Vertices x(4, 3);
    for (int c = 0; c < 4; ++c) x.row(c) = (Q * s.rest.X.segment<3>(3 * c) + t).transpose();
    energy::Linearization<energy::NeoHookeanElement> lin;
    ASSERT_TRUE(energy::Linearize(s.block, Loss(), x, &lin));
    EXPECT_NEAR(lin.value, 0.0, 1e-12 * s.block.Offset());
    for (int i = 0; i < 4; ++i) EXPECT_LT(lin.gradient[i].norm(), 1e-9);
  }
}

// Zero energy and force at rest and under any rigid motion, with R recomputed.
TEST(ElasticElement, ZeroAtRestAndUnderRigidMotion) {
  std::mt19937 rng(5);
  for (int trial = 0; trial < 100; ++trial) {
    Sample<energy::ElasticElement> s(&rng);
    const Eigen::Matrix3d Q =
        Eigen::AngleAxisd(0.7 * trial, RandomPoint(&rng, 1).normalized()).toRotationMatrix();
    const Eigen::Vector3d t = RandomPoint(&rng, 1);
    Eigen::Matrix<double, 3, 4> xm;
    Vertices x(4, 3);
    for (int c = 0; c < 4; ++c) {
      xm.col(c) = Q * s.rest.X.segment<3>(3 * c) + t;
      x.row(c) = xm.col(c).transpose();
    }
    s.rotation = PolarRotation(DeformationGradient(xm, s.rest.dm_inv));
    energy::Linearization<energy::ElasticElement> lin;
    ASSERT_TRUE(energy::Linearize(s.block, Loss(), x, &lin));
    EXPECT_NEAR(lin.value, 0.0, 1e-20);
    for (int i = 0; i < 4; ++i) EXPECT_LT(lin.gradient[i].norm(), 1e-9);
  }
}

}  // namespace
}  // namespace testing_util
}  // namespace femreg
