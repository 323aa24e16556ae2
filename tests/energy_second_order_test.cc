// The energy layer's second order: every registered block type's exact Hessian (and its
// projection) against central differences of its gradient, the least-squares energy where its
// held parameters are current, the elastic Hessians' rigid null space, and the assembler's
// second-order system against the sum of its blocks.
#include <algorithm>

#include "energy_samples.h"

namespace femreg {
namespace testing_util {
namespace {

TYPED_TEST_SUITE(EnergyBlockTest, typename BlockTypesOf<energy::Problem::Sets>::type);

// Second order (energy/term.h): the exact Hessian against central differences of the exact
// gradient, and that gradient against central differences of the value, with and without a
// loss that bends; symmetric; the projection positive semi-definite.
TYPED_TEST(EnergyBlockTest, SecondOrderMatchesCentralDifferences) {
  using T = TypeParam;
  constexpr int n = T::kVertices;
  std::mt19937 rng(19);
  for (RobustLoss kind : {RobustLoss::kNone, RobustLoss::kCauchy}) {
    for (int trial = 0; trial < kTrials; ++trial) {
      Sample<T> s(&rng);
      const double size = Residual(s.block, s.x).norm();
      const Loss loss{kind, kind == RobustLoss::kNone ? 1.0 : (0.5 + 0.1 * (trial % 10)) * std::max(size, 1e-9)};
      energy::Linearization<T> lin, plus, minus;
      ASSERT_TRUE(energy::LinearizeSecondOrder(s.block, loss, s.x, energy::Curvature::kExact, &lin));
      Eigen::MatrixXd H(3 * n, 3 * n), numeric(3 * n, 3 * n);
      for (int i = 0; i < n; ++i)
        for (int j = 0; j < n; ++j) H.block<3, 3>(3 * i, 3 * j) = lin.hessian[i * n + j];
      double gradient_norm = 0.0;
      for (int i = 0; i < n; ++i) gradient_norm += lin.gradient[i].squaredNorm();
      // A step small against the state (element legs 0.1 m, data offsets 0.01 m).
      const double h = 1e-6;
      for (int j = 0; j < n; ++j) {
        for (int c = 0; c < 3; ++c) {
          Vertices xp = s.x, xm = s.x;
          xp(j, c) += h;
          xm(j, c) -= h;
          ASSERT_TRUE(energy::LinearizeSecondOrder(s.block, loss, xp, energy::Curvature::kExact, &plus));
          ASSERT_TRUE(energy::LinearizeSecondOrder(s.block, loss, xm, energy::Curvature::kExact, &minus));
          const double slope = (plus.value - minus.value) / (2 * h);
          EXPECT_NEAR(lin.gradient[j][c], slope, 1e-5 * (std::abs(slope) + std::sqrt(gradient_norm)) + 1e-12)
              << Sample<T>::kName << " vertex " << j << " coordinate " << c;
          for (int i = 0; i < n; ++i) {
            numeric.block<3, 1>(3 * i, 3 * j + c) = (plus.gradient[i] - minus.gradient[i]) / (2 * h);
          }
        }
      }
      // Against the Gauss-Newton blocks' size too: the loss' bend can cancel them.
      energy::Linearization<T> gauss_newton;
      ASSERT_TRUE(energy::Linearize(s.block, loss, s.x, &gauss_newton));
      double gauss_newton_norm = 0.0;
      for (const auto& b : gauss_newton.hessian) gauss_newton_norm += b.squaredNorm();
      EXPECT_LT((H - numeric).norm(), 1e-5 * (1.0 + H.norm() + std::sqrt(gauss_newton_norm)))
          << Sample<T>::kName << " loss " << static_cast<int>(kind) << "\nexact\n" << H << "\nnumeric\n" << numeric;
      EXPECT_LT((H - H.transpose()).norm(), 1e-12 * (1 + H.norm())) << Sample<T>::kName;
      ASSERT_TRUE(energy::LinearizeSecondOrder(s.block, loss, s.x, energy::Curvature::kProjected, &plus));
      Eigen::MatrixXd P(3 * n, 3 * n);
      for (int i = 0; i < n; ++i)
        for (int j = 0; j < n; ++j) P.block<3, 3>(3 * i, 3 * j) = plus.hessian[i * n + j];
      EXPECT_LT((P - P.transpose()).norm(), 1e-12 * (1 + P.norm())) << Sample<T>::kName;
      const double smallest = Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd>(P).eigenvalues().minCoeff();
      EXPECT_GT(smallest, -1e-10 * (1 + P.norm())) << Sample<T>::kName;
      // The projection changes the Hessian only.
      EXPECT_NEAR(plus.value, lin.value, 1e-14 * (std::abs(lin.value) + 1.0));
      for (int i = 0; i < n; ++i) {
        EXPECT_LT((plus.gradient[i] - lin.gradient[i]).norm(), 1e-14 * (lin.gradient[i].norm() + 1.0));
      }
    }
  }
}

// Where the parameters a block holds are current (the samples' rotations are R(x)), the
// second-order value and gradient are the least-squares ones; for an affine residual without
// a loss the Hessian is the Gauss-Newton one.
TYPED_TEST(EnergyBlockTest, SecondOrderIsTheLeastSquaresEnergyWhereItsParametersAreCurrent) {
  using T = TypeParam;
  constexpr int n = T::kVertices;
  std::mt19937 rng(23);
  for (int trial = 0; trial < kTrials; ++trial) {
    Sample<T> s(&rng);
    energy::Linearization<T> exact, gauss_newton;
    ASSERT_TRUE(energy::LinearizeSecondOrder(s.block, Loss(), s.x, energy::Curvature::kExact, &exact));
    ASSERT_TRUE(energy::Linearize(s.block, Loss(), s.x, &gauss_newton));
    const double offset = energy::OffsetValue(s.block, Loss());
    EXPECT_NEAR(exact.value, gauss_newton.value, 1e-12 * (std::abs(gauss_newton.value) + offset) + 1e-300)
        << Sample<T>::kName;
    for (int i = 0; i < n; ++i) {
      EXPECT_LT((exact.gradient[i] - gauss_newton.gradient[i]).norm(),
                1e-9 * (1.0 + gauss_newton.gradient[i].norm()))
          << Sample<T>::kName << " vertex " << i;
    }
    if constexpr (!energy::HasSecondOrder<T>::value) {
      for (int ij = 0; ij < n * n; ++ij) {
        EXPECT_LT((exact.hessian[ij] - gauss_newton.hessian[ij]).norm(), 1e-14 * (1 + gauss_newton.hessian[ij].norm()))
            << Sample<T>::kName;
      }
    }
  }
}

// The elastic elements' exact Hessian at a rigidly moved rest state: zero energy and force,
// and the rigid motions (translations, infinitesimal rotations about the centroid) in its
// null space; at rest itself it is the small-strain stiffness K.
template <class T>
void ExpectRigidMotionsInTheNullSpace(int seed) {
  std::mt19937 rng(seed);
  for (int trial = 0; trial < 20; ++trial) {
    Sample<T> s(&rng);
    const Eigen::Matrix3d Q = trial == 0 ? Eigen::Matrix3d::Identity() : RandomRotation(&rng);
    const Eigen::Vector3d t = trial == 0 ? Eigen::Vector3d::Zero() : RandomPoint(&rng, 1);
    Vertices x(4, 3);
    for (int c = 0; c < 4; ++c) x.row(c) = (Q * s.rest.X.template segment<3>(3 * c) + t).transpose();
    energy::Linearization<T> lin;
    ASSERT_TRUE(energy::LinearizeSecondOrder(s.block, Loss(), x, energy::Curvature::kExact, &lin));
    const double stiffness = s.block.weight * ElementStiffness(s.rest).norm();
    EXPECT_NEAR(lin.value, 0.0, 1e-12 * stiffness * 0.01) << Sample<T>::kName;
    Eigen::Matrix<double, 12, 12> H;
    for (int i = 0; i < 4; ++i) {
      EXPECT_LT(lin.gradient[i].norm(), 1e-10 * stiffness) << Sample<T>::kName;
      for (int j = 0; j < 4; ++j) H.block<3, 3>(3 * i, 3 * j) = lin.hessian[i * 4 + j];
    }
    const Eigen::Vector3d centroid = x.colwise().mean().transpose();
    for (int mode = 0; mode < 6; ++mode) {
      Vector12 v;
      for (int c = 0; c < 4; ++c) {
        const Eigen::Vector3d arm = x.row(c).transpose() - centroid;
        v.segment<3>(3 * c) = mode < 3 ? Eigen::Vector3d::Unit(mode) : Eigen::Vector3d::Unit(mode - 3).cross(arm);
      }
      EXPECT_LT((H * v).norm(), 1e-9 * stiffness * v.norm()) << Sample<T>::kName << " mode " << mode;
    }
    if (trial == 0) {
      const Matrix12 K = s.block.weight * ElementStiffness(s.rest);
      EXPECT_LT((H - K).norm(), 1e-9 * K.norm()) << Sample<T>::kName;
    }
  }
}

TEST(ElasticElement, ExactHessianHasTheRigidMotionsInItsNullSpace) {
  ExpectRigidMotionsInTheNullSpace<energy::ElasticElement>(29);
}
TEST(NeoHookeanElement, ExactHessianHasTheRigidMotionsInItsNullSpace) {
  ExpectRigidMotionsInTheNullSpace<energy::NeoHookeanElement>(31);
}

// The small-strain element's exact Hessian is K wherever it is, and its energy ignores the
// held rotation.
TEST(ElasticElement, SmallStrainSecondOrderIsK) {
  std::mt19937 rng(37);
  Sample<energy::ElasticElement> s(&rng);
  s.block.corotational = false;
  const Eigen::Matrix3d identity = Eigen::Matrix3d::Identity();
  s.block.rotation = &identity;
  energy::Linearization<energy::ElasticElement> exact, gauss_newton;
  ASSERT_TRUE(energy::LinearizeSecondOrder(s.block, Loss(), s.x, energy::Curvature::kExact, &exact));
  ASSERT_TRUE(energy::Linearize(s.block, Loss(), s.x, &gauss_newton));
  EXPECT_NEAR(exact.value, gauss_newton.value, 1e-12 * gauss_newton.value);
  for (int i = 0; i < 4; ++i) {
    EXPECT_LT((exact.gradient[i] - gauss_newton.gradient[i]).norm(), 1e-9 * (1 + gauss_newton.gradient[i].norm()));
    for (int j = 0; j < 4; ++j) {
      EXPECT_LT((exact.hessian[i * 4 + j] - s.block.weight * ElementStiffness(s.rest).block<3, 3>(3 * i, 3 * j)).norm(),
                1e-9 * s.block.weight * ElementStiffness(s.rest).norm());
    }
  }
}

// The assembler's exact Hessian and gradient of a problem are the sum of its blocks' (placed
// densely), the same on one and two threads; a pair outside the pattern is refused.
// A 4-vertex block's linearization added into a dense sum: its gradient into `gradient`, its
// Hessian blocks as triplets.
template <class Lin>
void AddToDenseSum(const std::array<int, 4>& vertices, const Lin& lin, Eigen::VectorXd* gradient,
                   std::vector<Eigen::Triplet<double>>* entries) {
  for (int i = 0; i < 4; ++i) {
    gradient->segment<3>(3 * vertices[i]) += lin.gradient[i];
    for (int j = 0; j < 4; ++j)
      for (int c = 0; c < 3; ++c)
        for (int r = 0; r < 3; ++r)
          entries->emplace_back(3 * vertices[i] + r, 3 * vertices[j] + c, lin.hessian[i * 4 + j](r, c));
  }
}

// The assembler's row vertex per 3x3 block, column block by column block, against H's pattern.
void ExpectBlockRowsOf(const energy::Assembler& assembler) {
  const Eigen::SparseMatrix<double>& H = assembler.H();
  const std::vector<int>& block_rows = assembler.block_rows();
  ASSERT_EQ(static_cast<Eigen::Index>(9 * block_rows.size()), H.nonZeros());
  for (Eigen::Index b = 0; 3 * b < H.cols(); ++b) {
    const int begin = H.outerIndexPtr()[3 * b];
    for (int k = begin; k < H.outerIndexPtr()[3 * b + 1]; k += 3) {
      ASSERT_EQ(block_rows[static_cast<size_t>(begin / 9 + (k - begin) / 3)],
                H.innerIndexPtr()[k] / 3);
    }
  }
}

TEST(Assembler, SecondOrderSystemIsTheSumOfTheBlocks) {
  std::mt19937 rng(41);
  std::vector<std::unique_ptr<Sample<energy::ElasticElement>>> elements;
  const int count = 9000;  // past the parallel threshold (144k 3x3 blocks)
  Vertices x(4 * count, 3);
  energy::Problem problem;
  problem.Reset(4 * count);
  std::vector<std::array<int, 4>> cells;
  auto& set = problem.AddSet<energy::ElasticElement>(energy::TermGroup::kElastic);
  for (int i = 0; i < count; ++i) {
    elements.push_back(std::make_unique<Sample<energy::ElasticElement>>(&rng));
    energy::ElasticElement b = elements.back()->block;
    for (int k = 0; k < 4; ++k) {
      b.vertices[k] = 4 * i + k;
      x.row(4 * i + k) = elements.back()->x.row(k);
    }
    cells.push_back(b.vertices);
    set.Add(b);
  }
  problem.SetCoupling(cells);
  std::vector<Eigen::Triplet<double>> entries;
  Eigen::VectorXd gradient = Eigen::VectorXd::Zero(12 * count);
  for (const auto& b : set.blocks()) {
    energy::Linearization<energy::ElasticElement> lin;
    ASSERT_TRUE(energy::LinearizeSecondOrder(b, set.loss(), x, energy::Curvature::kExact, &lin));
    AddToDenseSum(b.vertices, lin, &gradient, &entries);
  }
  Eigen::SparseMatrix<double> sum(12 * count, 12 * count);
  sum.setFromTriplets(entries.begin(), entries.end());
  Eigen::SparseMatrix<double> first;
  for (int threads : {1, 2}) {
    energy::Assembler assembler(threads);
    assembler.Prepare(problem, x);
    Eigen::VectorXd g;
    assembler.AssembleSecondOrder(problem, x, energy::Curvature::kExact, true, &g);
    const Eigen::SparseMatrix<double> H = assembler.H();
    EXPECT_LT((H - sum).norm(), 1e-12 * sum.norm()) << threads;
    EXPECT_LT((g - gradient).norm(), 1e-12 * gradient.norm()) << threads;
    if (threads == 1) first = H;
    EXPECT_LT((H - first).norm(), 1e-14 * first.norm()) << "the same on any thread count";
    ExpectBlockRowsOf(assembler);
    EXPECT_FALSE(assembler.AddBlock(0, 4, Eigen::Matrix3d::Identity()));  // two elements apart
    EXPECT_TRUE(assembler.AddBlock(0, 1, Eigen::Matrix3d::Identity()));
    // Widened by a pair outside the pattern: built anew, and its block rows with it.
    EXPECT_EQ(assembler.Prepare(problem, x, {{0, 4}}), 1);
    ExpectBlockRowsOf(assembler);
    EXPECT_TRUE(assembler.AddBlock(0, 4, Eigen::Matrix3d::Identity()));
  }
}

// 4-vertex stencils are found again by key (an embedded surface's data pairs, a new set every
// outer iteration, on the cage's elements): in any vertex order, and in a set made anew, each
// block lands where its vertices are. The system is the blocks' sum on one and two threads.
TEST(Assembler, FourVertexStencilsMetAgainScatterWhereTheirVerticesAre) {
  std::mt19937 rng(43);
  const int count = 2400;  // elements; 4 data blocks each: past the parallel threshold (154k)
  energy::Problem problem;
  problem.Reset(4 * count);
  Vertices x(4 * count, 3);
  std::vector<std::array<int, 4>> cells;
  for (int i = 0; i < count; ++i) {
    cells.push_back({4 * i, 4 * i + 1, 4 * i + 2, 4 * i + 3});
    for (int k = 0; k < 4; ++k) x.row(4 * i + k) = RandomPoint(&rng, 0.01).transpose();
  }
  problem.SetCoupling(cells);
  auto& data = problem.AddSet<energy::PointToPlane<4>>(energy::TermGroup::kData);
  // Every block of the set on a permutation of its element's vertices (drawn by `draw`).
  auto fill = [&](int draw) {
    std::mt19937 order(static_cast<unsigned>(draw)), values(static_cast<unsigned>(1000 + draw));
    std::vector<energy::PointToPlane<4>>& blocks = *data.mutable_blocks();
    blocks.clear();
    for (int i = 0; i < count; ++i) {
      for (int k = 0; k < 4; ++k) {
        Sample<energy::PointToPlane<4>> sample(&values);
        std::array<int, 4> v = cells[static_cast<size_t>(i)];
        std::shuffle(v.begin(), v.end(), order);
        sample.block.vertices = v;
        blocks.push_back(sample.block);
      }
    }
  };
  auto dense_sum = [&](Eigen::VectorXd* gradient) {
    std::vector<Eigen::Triplet<double>> entries;
    gradient->setZero(12 * count);
    for (const auto& b : data.blocks()) {
      energy::Linearization<energy::PointToPlane<4>> lin;
      EXPECT_TRUE(energy::Linearize(b, data.loss(), x, &lin));
      AddToDenseSum(b.vertices, lin, gradient, &entries);
    }
    Eigen::SparseMatrix<double> sum(12 * count, 12 * count);
    sum.setFromTriplets(entries.begin(), entries.end());
    return sum;
  };
  std::vector<Eigen::SparseMatrix<double>> one_thread_H;
  std::vector<Eigen::VectorXd> one_thread_g;
  for (int threads : {1, 2}) {
    energy::Assembler assembler(threads);
    for (int round = 0; round < 3; ++round) {  // the second and third sets: their stencils known
      fill(round);
      const int builds = assembler.Prepare(problem, x);
      EXPECT_EQ(builds, round == 0 ? 1 : 0) << "the elements' pattern holds";
      Eigen::VectorXd g, gradient;
      assembler.AssembleGaussNewton(problem, x, /*first=*/true, &g);
      const Eigen::SparseMatrix<double> sum = dense_sum(&gradient);
      const Eigen::SparseMatrix<double> H = assembler.H();
      EXPECT_LT((H - sum).norm(), 1e-10 * sum.norm()) << threads << " threads, set " << round;
      EXPECT_LT((g - gradient).norm(), 1e-12 * gradient.norm()) << threads << " threads, set " << round;
      if (threads == 1) {
        one_thread_H.push_back(H);
        one_thread_g.push_back(g);
        continue;
      }
      // The same on two threads as on one (each entry's terms added in block order): to
      // round-off far below the dense sum's.
      const Eigen::SparseMatrix<double>& H1 = one_thread_H[static_cast<size_t>(round)];
      const Eigen::VectorXd& g1 = one_thread_g[static_cast<size_t>(round)];
      EXPECT_LE((H - H1).norm(), 1e-14 * H1.norm()) << "set " << round;
      EXPECT_LE((g - g1).norm(), 1e-14 * g1.norm()) << "set " << round;
    }
  }
}

}  // namespace
}  // namespace testing_util
}  // namespace femreg
