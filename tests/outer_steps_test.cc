// Steps over the outer iterations (solver.outer_steps, docs/notes/2026-11-30-outer-steps.md):
// Anderson's point from the last outer iterations of a fixed-point map, and the energy test
// that keeps it only where it is lower.
#include "registration/outer_steps.h"

#include <gtest/gtest.h>

#include <Eigen/Core>
#include <Eigen/QR>
#include <cmath>
#include <limits>
#include <vector>

namespace femreg {
namespace {

// A linear map on 5 x 3 vertex arrays, G(x) = x* + sum_i a_i u_i u_i^T (x - x*) with orthonormal
// directions u_i (flattened): its outer iterations shrink the distance to x* along u_i by a_i
// each time and drop what is off the u_i.
struct LinearMap {
  Vertices fixed;
  std::vector<Eigen::VectorXd> directions;
  std::vector<double> factors;
  Vertices operator()(const Vertices& x) const {
    const Vertices e = x - fixed;
    const Eigen::Map<const Eigen::VectorXd> ev(e.data(), e.size());
    Eigen::VectorXd out = Eigen::VectorXd::Zero(e.size());
    for (size_t i = 0; i < directions.size(); ++i)
      out += factors[i] * directions[i].dot(ev) * directions[i];
    return fixed + Eigen::Map<const Vertices>(out.data(), e.rows(), 3);
  }
};

LinearMap MakeMap(const std::vector<double>& factors) {
  LinearMap g;
  g.fixed = Vertices::Random(5, 3);
  Eigen::MatrixXd basis = Eigen::MatrixXd::Random(15, static_cast<Eigen::Index>(factors.size()));
  const Eigen::MatrixXd q = Eigen::HouseholderQR<Eigen::MatrixXd>(basis).householderQ() *
                            Eigen::MatrixXd::Identity(15, basis.cols());
  for (Eigen::Index i = 0; i < q.cols(); ++i) g.directions.push_back(q.col(i));
  g.factors = factors;
  return g;
}

// Outer iterations 0 .. n-1 of g from x0, recorded; returns the last result.
Vertices Iterate(const LinearMap& g, Vertices x, int n, OuterStepHistory* history) {
  for (int k = 0; k < n; ++k) {
    const Vertices next = g(x);
    history->Record(k, x, next);
    x = next;
  }
  return x;
}

double Distance(const Vertices& a, const Vertices& b) { return (a - b).norm(); }

// A creep along one direction that shrinks by a tenth each time (the moves all point the same
// way): after two outer iterations, one step goes to its end, 8 more moves' worth away.
TEST(OuterSteps, OneStepEndsACreepAlongOneDirection) {
  const LinearMap g = MakeMap({0.9});
  const Vertices x0 =
      g.fixed + Eigen::Map<const Vertices>(Eigen::VectorXd(0.01 * g.directions[0]).data(), 5, 3);
  OuterStepHistory history;
  const Vertices reached = Iterate(g, x0, 2, &history);
  ASSERT_EQ(history.size(), 2);
  Vertices further;
  ASSERT_TRUE(history.Propose(&further));
  EXPECT_GT(Distance(reached, g.fixed), 0.8 * Distance(x0, g.fixed));
  EXPECT_LT(Distance(further, g.fixed), 1e-9 * Distance(x0, g.fixed));
}

// A creep that zigzags (one direction shrinks by 0.95, another flips sign and shrinks by 0.8,
// so that consecutive moves point apart): the default depth combines three outer iterations
// and lands on the fixed point; the plain iterations are still far.
TEST(OuterSteps, ThreeIterationsEndACreepThatZigzags) {
  const LinearMap g = MakeMap({0.95, -0.8});
  const Eigen::VectorXd e0 = 0.01 * g.directions[0] + 0.02 * g.directions[1];
  const Vertices x0 = g.fixed + Eigen::Map<const Vertices>(e0.data(), 5, 3);
  OuterStepHistory history;
  const Vertices reached = Iterate(g, x0, 3, &history);
  ASSERT_EQ(history.size(), 3);
  Vertices further;
  ASSERT_TRUE(history.Propose(&further));
  EXPECT_GT(Distance(reached, g.fixed), 0.5 * Distance(x0, g.fixed));
  EXPECT_LT(Distance(further, g.fixed), 1e-9 * Distance(x0, g.fixed));
  // With one difference only (depth 1) it cannot: the two directions need two.
  OuterStepHistory shallow(1);
  Iterate(g, x0, 3, &shallow);
  EXPECT_EQ(shallow.size(), 2);
  Vertices near;
  ASSERT_TRUE(shallow.Propose(&near));
  EXPECT_GT(Distance(near, g.fixed), 1e-3 * Distance(x0, g.fixed));
}

// The history is one schedule's consecutive outer iterations: a gap (a restart) or another
// vertex count (a split) starts it again, and one iteration proposes nothing.
TEST(OuterSteps, HistoryStartsAgainAfterAGapOrAnotherMesh) {
  const LinearMap g = MakeMap({0.9});
  OuterStepHistory history;
  Vertices x = Iterate(g, g.fixed + Vertices::Constant(5, 3, 0.01), 3, &history);
  EXPECT_EQ(history.size(), 3);
  Vertices further;
  history.Record(5, x, g(x));  // k 3 and 4 did not run in this schedule
  EXPECT_EQ(history.size(), 1);
  EXPECT_FALSE(history.Propose(&further));
  history.Record(6, g(x), g(g(x)));
  EXPECT_EQ(history.size(), 2);
  history.Record(7, Vertices::Zero(4, 3), Vertices::Ones(4, 3));
  EXPECT_EQ(history.size(), 1);
  history.Clear();
  EXPECT_EQ(history.size(), 0);
}

// A move that repeats without shrinking has no end to go to: no difference of the moves says
// where, and nothing is proposed (no division by zero). One that shrinks a little does.
TEST(OuterSteps, AMoveThatRepeatsHasNoEnd) {
  OuterStepHistory repeat, shrinking;
  for (int k = 0; k < 3; ++k) {
    repeat.Record(k, Vertices::Constant(5, 3, k), Vertices::Constant(5, 3, k + 1.0));
    const double at = 1.0 - std::pow(0.99, k), next = 1.0 - std::pow(0.99, k + 1);
    shrinking.Record(k, Vertices::Constant(5, 3, at), Vertices::Constant(5, 3, next));
  }
  Vertices further = Vertices::Zero(5, 3);
  EXPECT_FALSE(repeat.Propose(&further));
  EXPECT_TRUE(further.isZero()) << "left as it was";
  ASSERT_TRUE(shrinking.Propose(&further));
  EXPECT_TRUE(further.isApprox(Vertices::Ones(5, 3), 1e-9)) << further.row(0);
}

// The energy decides: a step that lowers it is kept, one that raises it is not (the caller
// goes on from the solve's end), and where the energy at the solve's end cannot be had (no
// pairs found there) the step is not evaluated at all.
TEST(OuterSteps, AStepIsKeptOnlyWhereItLowersTheEnergy) {
  const Vertices reached = Vertices::Constant(4, 3, 1.0);
  const Vertices target = Vertices::Constant(4, 3, 2.0);
  std::vector<Vertices> asked;
  auto distance_to_target = [&](const Vertices& y) {
    asked.push_back(y);
    return (y - target).squaredNorm();
  };
  const Vertices closer = Vertices::Constant(4, 3, 1.5), beyond = Vertices::Constant(4, 3, 3.5);
  OuterStepTrial t = TryOuterStep(reached, closer, distance_to_target);
  EXPECT_TRUE(t.kept);
  EXPECT_LT(t.further, t.at);
  ASSERT_EQ(asked.size(), 2u);
  EXPECT_TRUE(asked[0].isApprox(reached) && asked[1].isApprox(closer))
      << "the solve's end first, then the step's";

  asked.clear();
  t = TryOuterStep(reached, beyond, distance_to_target);
  EXPECT_FALSE(t.kept) << "the step raises the energy from " << t.at << " to " << t.further;
  EXPECT_GT(t.further, t.at);
  EXPECT_EQ(asked.size(), 2u);

  // Equal energies: nothing gained, not kept.
  t = TryOuterStep(reached, Vertices::Constant(4, 3, 3.0), distance_to_target);
  EXPECT_FALSE(t.kept);

  asked.clear();
  auto nothing_found = [&](const Vertices& y) {
    asked.push_back(y);
    return std::numeric_limits<double>::quiet_NaN();
  };
  t = TryOuterStep(reached, closer, nothing_found);
  EXPECT_FALSE(t.kept);
  EXPECT_EQ(asked.size(), 1u);
  EXPECT_TRUE(std::isinf(t.further));
}

}  // namespace
}  // namespace femreg
