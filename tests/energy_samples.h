// The energy tests' samples: a block of every registered type at a random state, shared by
// tests/energy_test.cc (first order) and tests/energy_second_order_test.cc.
#ifndef FEMREG_TESTS_ENERGY_SAMPLES_H_
#define FEMREG_TESTS_ENERGY_SAMPLES_H_

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
namespace testing_util {

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

// Compressed below the threshold (J in 0.05-0.19 against 0.2), where the barrier acts.
template <>
struct Sample<energy::InversionBarrier> {
  static constexpr const char* kName = "InversionBarrier";
  ElementRest rest;
  energy::InversionBarrier block;
  Vertices x;
  explicit Sample(std::mt19937* rng) {
    rest = RandomRest(rng, 0.3);
    const Eigen::Matrix3d Q = RandomRotation(rng);
    std::uniform_real_distribution<double> flat(0.08, 0.16), side(0.8, 1.1);
    const Eigen::Matrix3d A = Q * Eigen::Vector3d(flat(*rng), side(*rng), side(*rng)).asDiagonal() *
                              RandomRotation(rng).transpose();
    x.resize(4, 3);
    const Eigen::Vector3d X0 = rest.X.segment<3>(0), shift = RandomPoint(rng, 0.1);
    for (int c = 0; c < 4; ++c) x.row(c) = (A * (rest.X.segment<3>(3 * c) - X0) + X0 + shift).transpose();
    block = energy::InversionBarrier({{0, 1, 2, 3}}, rest, 1.5, 0.2);
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
  static constexpr const char* kName = N == 1 ? "PointToPoint<1>" : N == 3 ? "PointToPoint<3>" : "PointToPoint<4>";
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
  static constexpr const char* kName = N == 1 ? "PointToPlane<1>" : N == 3 ? "PointToPlane<3>" : "PointToPlane<4>";
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
  static constexpr const char* kName = N == 3 ? "ContactPenalty<3>" : N == 4 ? "ContactPenalty<4>" : "ContactPenalty<6>";
  static constexpr int kSideA = N == 6 ? 3 : N;  // 4: an embedded surface's point, its weights may be < 0
  energy::ContactPenalty<N> block;
  Vertices x;
  // Active: side a a little above side b along n, closer than D; away from the hinge at
  // delta = 0, where numeric differences would straddle it.
  explicit Sample(std::mt19937* rng) {
    const double D = 0.004;
    block.normal = Eigen::Vector3d(RandomPoint(rng, 0.01).x(), RandomPoint(rng, 0.01).y(), 1).normalized();
    const auto a = RandomBarycentric<kSideA>(rng);
    x.resize(N, 3);
    Eigen::Vector3d pa = Eigen::Vector3d::Zero();
    for (int i = 0; i < kSideA; ++i) {
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

// Friction: a slip of a few eps (m) at a random normal, either side of the Huber loss' bend
// when the test gives it a scale near the residual's size.
template <int N>
struct Sample<energy::Friction<N>> {
  static constexpr const char* kName = N == 3 ? "Friction<3>" : N == 4 ? "Friction<4>" : "Friction<6>";
  static constexpr int kSideA = N == 6 ? 3 : N;
  energy::Friction<N> block;
  Vertices x;
  explicit Sample(std::mt19937* rng) {
    block.tangent = energy::TangentBasis(Eigen::Vector3d(RandomPoint(rng, 0.3).x(), RandomPoint(rng, 0.3).y(), 1).normalized());
    const auto a = RandomBarycentric<kSideA>(rng);
    x.resize(N, 3);
    Eigen::Vector3d p = Eigen::Vector3d::Zero();
    for (int i = 0; i < N; ++i) {
      x.row(i) = (Eigen::Vector3d(0.3, 0.2, 0.5) + RandomPoint(rng, 0.01)).transpose();
      block.vertices[i] = i;
      block.coefficients[i] = i < kSideA ? a[i] : -RandomBarycentric<3>(rng)[i - 3];
      p += block.coefficients[i] * x.row(i).transpose();
    }
    block.offset = block.tangent * p + RandomPoint(rng, 4e-4).head<2>();
    block.weight = 2e3;
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

// Free space: the vertex a little in front of the allowed depth along a random ray (away from
// the hinge at zero, where numeric differences would straddle it).
template <>
struct Sample<energy::FreeSpacePenalty> {
  static constexpr const char* kName = "FreeSpacePenalty";
  energy::FreeSpacePenalty block;
  Vertices x;
  explicit Sample(std::mt19937* rng) {
    block.origin = RandomPoint(rng, 0.5);
    block.ray = RandomPoint(rng, 1).normalized();
    x.resize(1, 3);
    x.row(0) = (block.origin + 0.4 * block.ray + RandomPoint(rng, 0.01)).transpose();
    block.depth = block.ray.dot(x.row(0).transpose() - block.origin) + 0.003;
    block.weight = 1e4;
  }
};

// The registry's block types, as a gtest type list.
template <class Tuple>
struct BlockTypesOf;
template <class... Sets>
struct BlockTypesOf<std::tuple<Sets...>> {
  using type = ::testing::Types<typename Sets::value_type::Block...>;
};

constexpr int kTrials = 20;

template <class T>
Eigen::VectorXd Residual(const T& block, const Vertices& x) {
  Eigen::VectorXd r(T::kResiduals);
  const auto p = energy::StencilPositions(block, x);
  EXPECT_TRUE(block.Evaluate(p.data(), r.data(), nullptr));
  return r;
}

// The registry's block types, as the typed tests' fixture.
template <class T>
class EnergyBlockTest : public ::testing::Test {};

}  // namespace testing_util
}  // namespace femreg

#endif  // FEMREG_TESTS_ENERGY_SAMPLES_H_
