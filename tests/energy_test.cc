// Every block type of the energy layer, checked by one generic test over the registry
// (energy::Problem::Sets): its Jacobian against central differences and, through the Ceres
// back end's cost adapter, ceres::GradientChecker; the generic linearization (gradient
// and Gauss-Newton blocks, with each robust loss) against central differences of the value;
// symmetric positive semi-definite Gauss-Newton blocks. A block type added to the registry
// without a Sample<> below does not compile. Then the robust losses, and the elastic
// invariants (zero energy and force at rest and under rigid motion).
#include <ceres/ceres.h>
#include <ceres/gradient_checker.h>
#include <gtest/gtest.h>

#include <Eigen/Eigenvalues>
#include <Eigen/Geometry>
#include <memory>
#include <random>
#include <tuple>
#include <vector>

#include "energy/assembler.h"
#include "energy/problem.h"
#include "femreg/fem.h"
#include "solvers/ceres/ceres_backend.h"

namespace femreg {
namespace {

using energy::Loss;

// A block at a random state: the block, what it points to, and its stencil's positions.
template <class T>
struct Sample;

Eigen::Vector3d RandomPoint(std::mt19937* rng, double scale) {
  std::uniform_real_distribution<double> u(-scale, scale);
  return Eigen::Vector3d(u(*rng), u(*rng), u(*rng));
}

template <int N>
std::array<double, N> RandomBarycentric(std::mt19937* rng) {
  std::uniform_real_distribution<double> u(0.05, 1.0);
  std::array<double, N> b;
  double sum = 0.0;
  for (double& v : b) sum += (v = u(*rng));
  for (double& v : b) v /= sum;
  return b;
}

// A tetrahedron of 10 cm legs, its vertices moved by up to 2 cm, and its rest data.
ElementRest RandomRest(std::mt19937* rng, double poisson_ratio) {
  Eigen::Matrix<double, 3, 4> X;
  X << 0, 0.1, 0, 0, 0, 0, 0.1, 0, 0, 0, 0, 0.1;
  for (int c = 0; c < 4; ++c) X.col(c) += RandomPoint(rng, 0.02);
  Material material;
  material.youngs_modulus = 1e5;
  material.poisson_ratio = poisson_ratio;
  return BuildElementRest(X, material);
}

Eigen::Matrix3d RandomRotation(std::mt19937* rng) {
  return Eigen::AngleAxisd(std::uniform_real_distribution<double>(0, 6)(*rng), RandomPoint(rng, 1).normalized())
      .toRotationMatrix();
}

template <>
struct Sample<energy::ElasticElement> {
  static constexpr const char* kName = "ElasticElement";
  ElementRest rest;
  Eigen::Matrix3d rotation;
  energy::ElasticElement block;
  Vertices x;
  explicit Sample(std::mt19937* rng) {
    rest = RandomRest(rng, 0.35);
    // A rotated and strained state; its rotation held as in one inner solve.
    const Eigen::Matrix3d Q = RandomRotation(rng);
    x.resize(4, 3);
    Eigen::Matrix<double, 3, 4> xm;
    for (int c = 0; c < 4; ++c) {
      xm.col(c) = Q * rest.X.segment<3>(3 * c) + RandomPoint(rng, 0.02);
      x.row(c) = xm.col(c).transpose();
    }
    rotation = PolarRotation(DeformationGradient(xm, rest.dm_inv));
    block.vertices = {{0, 1, 2, 3}};
    block.weight = 2.5;
    block.rest = &rest;
    block.rotation = &rotation;
  }
  Sample(const Sample&) = delete;
};

template <>
struct Sample<energy::NeoHookeanElement> {
  static constexpr const char* kName = "NeoHookeanElement";
  ElementRest rest;
  energy::NeoHookeanElement block;
  Vertices x;
  explicit Sample(std::mt19937* rng) {
    rest = RandomRest(rng, 0.45);
    // Rotated, stretched or compressed; one sample in five inverted (a vertex through the
    // opposite face).
    const Eigen::Matrix3d Q = RandomRotation(rng);
    const bool invert = std::uniform_int_distribution<int>(0, 4)(*rng) == 0;
    x.resize(4, 3);
    for (int c = 0; c < 4; ++c) {
      const Eigen::Vector3d X0 = rest.X.segment<3>(0);
      Eigen::Vector3d p = rest.X.segment<3>(3 * c);
      if (invert && c == 3) p = X0 + (X0 - p) * 0.5;
      x.row(c) = (Q * p + RandomPoint(rng, 0.02)).transpose();
    }
    block.vertices = {{0, 1, 2, 3}};
    block.weight = 2.5;
    block.rest = &rest;
  }
  Sample(const Sample&) = delete;
};

template <>
struct Sample<energy::EdgeSpring> {
  static constexpr const char* kName = "EdgeSpring";
  energy::EdgeSpring block;
  Vertices x;
  explicit Sample(std::mt19937* rng) {
    x.resize(2, 3);
    x.row(0) = RandomPoint(rng, 1).transpose();
    x.row(1) = x.row(0) + RandomPoint(rng, 1).transpose();
    block.vertices = {{0, 1}};
    block.weight = 3.0;
    block.length = 0.7;
  }
};

template <int N>
struct Sample<energy::PointToPoint<N>> {
  static constexpr const char* kName = N == 1 ? "PointToPoint<1>" : "PointToPoint<3>";
  energy::PointToPoint<N> block;
  Vertices x;
  explicit Sample(std::mt19937* rng) {
    x.resize(N, 3);
    for (int i = 0; i < N; ++i) {
      x.row(i) = RandomPoint(rng, 0.01).transpose();
      block.vertices[i] = i;
    }
    block.barycentric = N == 1 ? std::array<double, N>{} : RandomBarycentric<N>(rng);
    if (N == 1) block.barycentric[0] = 1.0;
    block.target = RandomPoint(rng, 0.01);
    block.weight = 1.5;
  }
};

template <int N>
struct Sample<energy::PointToPlane<N>> {
  static constexpr const char* kName = N == 1 ? "PointToPlane<1>" : "PointToPlane<3>";
  energy::PointToPlane<N> block;
  Vertices x;
  explicit Sample(std::mt19937* rng) {
    x.resize(N, 3);
    for (int i = 0; i < N; ++i) {
      x.row(i) = RandomPoint(rng, 0.01).transpose();
      block.vertices[i] = i;
    }
    block.barycentric = N == 1 ? std::array<double, N>{} : RandomBarycentric<N>(rng);
    if (N == 1) block.barycentric[0] = 1.0;
    block.target = RandomPoint(rng, 0.01);
    block.normal = RandomPoint(rng, 1).normalized();
    block.weight = 1.5;
  }
};

template <int N>
struct Sample<energy::ContactPenalty<N>> {
  static constexpr const char* kName = N == 3 ? "ContactPenalty<3>" : "ContactPenalty<6>";
  energy::ContactPenalty<N> block;
  Vertices x;
  // Active: side a a little above side b along n, closer than D; away from the hinge at
  // delta = 0, where numeric differences would straddle it.
  explicit Sample(std::mt19937* rng) {
    const double D = 0.004;
    block.normal = Eigen::Vector3d(RandomPoint(rng, 0.01).x(), RandomPoint(rng, 0.01).y(), 1).normalized();
    const auto a = RandomBarycentric<3>(rng);
    x.resize(N, 3);
    Eigen::Vector3d pa = Eigen::Vector3d::Zero();
    for (int i = 0; i < 3; ++i) {
      x.row(i) = (Eigen::Vector3d(0.3, 0.2, 0.5) + RandomPoint(rng, 0.01)).transpose();
      block.vertices[i] = i;
      block.coefficients[i] = a[i];
      pa += a[i] * x.row(i).transpose();
    }
    Eigen::Vector3d pb = pa - 0.5 * D * block.normal;  // gap D/2: delta = D/2 > 0
    block.offset = D;
    if (N == 6) {
      const auto b = RandomBarycentric<3>(rng);
      Eigen::Vector3d sum = Eigen::Vector3d::Zero();
      for (int i = 0; i < 3; ++i) {
        x.row(3 + i) = (pb + RandomPoint(rng, 0.01)).transpose();
        sum += b[i] * x.row(3 + i).transpose();
      }
      for (int i = 0; i < 3; ++i) {  // move side b so that its point is pb
        x.row(3 + i) += (pb - sum).transpose();
        block.vertices[3 + i] = 3 + i;
        block.coefficients[3 + i] = -b[i];
      }
    } else {
      block.offset = D + block.normal.dot(pb);
    }
    block.weight = 5e3;
  }
};

template <>
struct Sample<energy::ExternalLoad> {
  static constexpr const char* kName = "ExternalLoad";
  energy::ExternalLoad block;
  Vertices x;
  explicit Sample(std::mt19937* rng) {
    const Eigen::Vector3d origin = RandomPoint(rng, 0.1);
    x.resize(1, 3);
    x.row(0) = (origin + RandomPoint(rng, 0.01)).transpose();
    EXPECT_TRUE(energy::MakeExternalLoad(0, RandomPoint(rng, 2.0), origin, 0.01, &block));
  }
};

// The registry's block types, as a gtest type list.
template <class Tuple>
struct BlockTypesOf;
template <class... Sets>
struct BlockTypesOf<std::tuple<Sets...>> {
  using type = ::testing::Types<typename Sets::value_type::Block...>;
};

template <class T>
class EnergyBlockTest : public ::testing::Test {};
TYPED_TEST_SUITE(EnergyBlockTest, typename BlockTypesOf<energy::Problem::Sets>::type);

constexpr int kTrials = 20;

template <class T>
Eigen::VectorXd Residual(const T& block, const Vertices& x) {
  Eigen::VectorXd r(T::kResiduals);
  const auto p = energy::StencilPositions(block, x);
  EXPECT_TRUE(block.Evaluate(p.data(), r.data(), nullptr));
  return r;
}

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
      // The loss bends near the residual's size, so both branches are exercised.
      const double size = Residual(s.block, s.x).norm();
      const Loss loss{kind, kind == RobustLoss::kNone ? 1.0 : (0.4 + 0.1 * (trial % 12)) * std::max(size, 1e-9)};
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
      EXPECT_EQ(plus.value, lin.value);
      for (int i = 0; i < n; ++i) EXPECT_EQ(plus.gradient[i], lin.gradient[i]);
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
    const double stiffness = s.block.weight * s.rest.K.norm();
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
      const Matrix12 K = s.block.weight * s.rest.K;
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
      EXPECT_LT((exact.hessian[i * 4 + j] - s.block.weight * s.rest.K.block<3, 3>(3 * i, 3 * j)).norm(),
                1e-9 * s.block.weight * s.rest.K.norm());
    }
  }
}

// The assembler's exact Hessian and gradient of a problem are the sum of its blocks' (placed
// densely), the same on one and two threads; a pair outside the pattern is refused.
TEST(Assembler, SecondOrderSystemIsTheSumOfTheBlocks) {
  std::mt19937 rng(41);
  std::vector<std::unique_ptr<Sample<energy::ElasticElement>>> elements;
  const int count = 3000;  // past the parallel threshold
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
    for (int i = 0; i < 4; ++i) {
      gradient.segment<3>(3 * b.vertices[i]) += lin.gradient[i];
      for (int j = 0; j < 4; ++j)
        for (int c = 0; c < 3; ++c)
          for (int r = 0; r < 3; ++r)
            entries.emplace_back(3 * b.vertices[i] + r, 3 * b.vertices[j] + c, lin.hessian[i * 4 + j](r, c));
    }
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
    EXPECT_EQ((H - first).norm(), 0.0) << "the same on any thread count";
    EXPECT_FALSE(assembler.AddBlock(0, 4, Eigen::Matrix3d::Identity()));  // two elements apart
    EXPECT_TRUE(assembler.AddBlock(0, 1, Eigen::Matrix3d::Identity()));
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
  for (int threads : {2, 3, 8}) {
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
}  // namespace femreg
