// The inversion barrier's invariants (docs/theory/inversion.md): zero above its threshold,
// decided by the cheap test exactly where the full evaluation is zero; infinite at and past
// a flat element; growing without bound towards it; a force that balances and has no torque.
#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <cmath>
#include <limits>
#include <random>
#include <vector>

#include "energy/barrier.h"
#include "energy/term.h"
#include "energy_samples.h"

namespace femreg {
namespace {

// The element of `rest` deformed by A (rest vertex 0 held), as #V by 3 positions.
Vertices Deformed(const ElementRest& rest, const Eigen::Matrix3d& A) {
  Vertices x(4, 3);
  const Eigen::Vector3d X0 = rest.X.segment<3>(0);
  for (int c = 0; c < 4; ++c) x.row(c) = (A * (rest.X.segment<3>(3 * c) - X0) + X0).transpose();
  return x;
}

// A deformation with det = ratio: a random rotation times an anisotropic stretch.
Eigen::Matrix3d WithVolumeRatio(std::mt19937* rng, double ratio) {
  std::uniform_real_distribution<double> side(0.7, 1.4);
  const double a = side(*rng), b = side(*rng);
  return testing_util::RandomRotation(rng) * Eigen::Vector3d(a, b, ratio / (a * b)).asDiagonal() *
         testing_util::RandomRotation(rng).transpose();
}

TEST(InversionBarrier, TheCheapTestIsExactlyWhereTheBarrierIsZero) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> ratio_of(0.02, 1.5);
  const energy::Loss loss;
  int active = 0, inactive = 0;
  for (int trial = 0; trial < 400; ++trial) {
    const ElementRest rest = testing_util::RandomRest(&rng, 0.3);
    const double threshold = trial % 2 == 0 ? 0.2 : 0.5;
    const energy::InversionBarrier block({{0, 1, 2, 3}}, rest, 1.5, threshold);
    const Vertices x = Deformed(rest, WithVolumeRatio(&rng, ratio_of(rng)));
    const auto p = energy::StencilPositions(block, x);
    const double ratio = energy::VolumeRatio(rest, p.data());
    if (std::abs(ratio - threshold) < 1e-9) continue;
    const bool skip = block.Inactive(p.data());
    EXPECT_EQ(skip, ratio >= threshold) << "ratio " << ratio << " threshold " << threshold;
    double r = -1.0;
    Eigen::Matrix<double, 1, 3> J[4];
    double* Jp[4] = {J[0].data(), J[1].data(), J[2].data(), J[3].data()};
    ASSERT_TRUE(block.Evaluate(p.data(), &r, Jp));
    energy::Linearization<energy::InversionBarrier> lin;
    ASSERT_TRUE(energy::Linearize(block, loss, x, &lin));
    if (skip) {
      ++inactive;
      EXPECT_EQ(r, 0.0);
      for (const auto& row : J) EXPECT_TRUE(row.isZero(0.0));
      EXPECT_EQ(lin.scale, 0.0);
      EXPECT_EQ(lin.value, 0.0);
      for (const auto& g : lin.gradient) EXPECT_TRUE(g.isZero(0.0));
    } else {
      ++active;
      EXPECT_GT(r, 0.0);
      EXPECT_GT(lin.value, 0.0);
      EXPECT_GT(lin.scale, 0.0);
    }
  }
  EXPECT_GT(active, 50);
  EXPECT_GT(inactive, 50);
}

TEST(InversionBarrier, InfiniteWhenFlatOrInverted) {
  std::mt19937 rng(11);
  const ElementRest rest = testing_util::RandomRest(&rng, 0.3);
  const energy::InversionBarrier block({{0, 1, 2, 3}}, rest, 1.0, 0.2);
  for (double ratio : {0.0, -1e-6, -0.3, -1.0}) {
    const Vertices x = Deformed(rest, WithVolumeRatio(&rng, ratio));
    EXPECT_EQ(energy::BlockValue(block, energy::Loss(), x), std::numeric_limits<double>::infinity())
        << "ratio " << ratio;
  }
}

TEST(InversionBarrier, GrowsWithoutBoundTowardsFlatAndItsForceBalances) {
  std::mt19937 rng(13);
  const ElementRest rest = testing_util::RandomRest(&rng, 0.3);
  const energy::InversionBarrier block({{0, 1, 2, 3}}, rest, 1.0, 0.2);
  const Eigen::Matrix3d Q = testing_util::RandomRotation(&rng);
  const Eigen::Matrix3d R = testing_util::RandomRotation(&rng);
  double previous = 0.0, at_tenth = 0.0;
  for (double ratio : {0.19, 0.1, 0.03, 1e-3, 1e-6, 1e-9}) {
    const Vertices x = Deformed(rest, Q * Eigen::Vector3d(1.0, 1.0, ratio).asDiagonal() * R);
    energy::Linearization<energy::InversionBarrier> lin;
    ASSERT_TRUE(energy::LinearizeSecondOrder(block, energy::Loss(), x, energy::Curvature::kExact, &lin));
    EXPECT_GT(lin.value, previous) << "ratio " << ratio;
    previous = lin.value;
    if (ratio == 0.1) at_tenth = lin.value;
    // It depends on the volume alone: no net force and no torque on the element.
    Eigen::Vector3d force = Eigen::Vector3d::Zero(), torque = Eigen::Vector3d::Zero();
    double size = 0.0;
    for (int i = 0; i < 4; ++i) {
      force += lin.gradient[i];
      torque += x.row(i).transpose().cross(lin.gradient[i]);
      size += lin.gradient[i].norm();
    }
    EXPECT_LT(force.norm(), 1e-9 * size) << "ratio " << ratio;
    EXPECT_LT(torque.norm(), 1e-9 * size * (1.0 + x.norm())) << "ratio " << ratio;
  }
  // (j - J)^2 log(j / J): from J = j/2 to J = 1e-9 it grows by 4 log(2e8) / log 2 ~ 110.
  EXPECT_GT(previous, 100.0 * at_tenth);
}

TEST(InversionBarrier, AStepIsCutInsideTheZoneNotAtTheWall) {
  // A step that turns the element inside out (to -1 times its volume) and one that squeezes
  // it to 0.6: the first is cut where the volume ratio is half the threshold (0.1), the second
  // is not cut; from inside the zone (0.15), the cut keeps half of the volume (0.075).
  std::mt19937 rng(17);
  const ElementRest rest = testing_util::RandomRest(&rng, 0.3);
  const Eigen::Matrix3d Q = testing_util::RandomRotation(&rng);
  auto at = [&](double ratio) { return Deformed(rest, Q * Eigen::Vector3d(1.0, 1.0, ratio).asDiagonal()); };
  std::vector<energy::TermSet<energy::InversionBarrier>> sets;
  sets.emplace_back(energy::TermGroup::kElastic, energy::Loss());
  sets.back().Add(energy::InversionBarrier({{0, 1, 2, 3}}, rest, 1.0, 0.2));
  auto ratio_after = [&](double from, double to, double* t) {
    const Vertices x = at(from);
    const Vertices y = at(to);
    Eigen::VectorXd dx(12);
    for (int v = 0; v < 4; ++v) dx.segment<3>(3 * v) = (y.row(v) - x.row(v)).transpose();
    *t = energy::UprightFraction(sets, x, dx, 1.0);
    Vertices z = x;
    for (int v = 0; v < 4; ++v) z.row(v) += *t * dx.segment<3>(3 * v).transpose();
    const auto p = energy::StencilPositions(sets.back().blocks()[0], z);
    return energy::VolumeRatio(rest, p.data());
  };
  double t = 0.0;
  EXPECT_NEAR(ratio_after(1.0, -1.0, &t), 0.1, 1e-9);
  EXPECT_NEAR(t, 0.45, 1e-9);  // the ratio is linear in t along this step: 1 - 2 t = 0.1
  EXPECT_NEAR(ratio_after(1.0, 0.6, &t), 0.6, 1e-12);
  EXPECT_EQ(t, 1.0);
  EXPECT_NEAR(ratio_after(0.15, -0.5, &t), 0.075, 1e-9);
}

}  // namespace
}  // namespace femreg
