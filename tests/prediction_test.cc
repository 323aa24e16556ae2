// The prediction leaves out the turns a body's surface does not show (registration/prediction.h).
#include "registration/prediction.h"

#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <cmath>

#include "femreg/io.h"
#include "femreg/mesh.h"

namespace femreg {
namespace {

Eigen::Vector3d Centre(const TetMesh& m) { return m.rest.colwise().mean().transpose(); }

TEST(TurnVisibility, SphereShowsNoTurnCubeShowsAFifth) {
  const TetMesh sphere = MakeSphere(0.05, 6);
  Eigen::Matrix3d axes;
  const Eigen::Vector3d s = TurnVisibility(sphere.rest, sphere.surface, Centre(sphere), &axes);
  EXPECT_LT(s.maxCoeff(), 0.2 * kVisibleTurn) << s.transpose();

  const TetMesh cube = MakeBox(Eigen::Vector3d(0.1, 0.1, 0.1), 4, 4, 4);
  const Eigen::Vector3d b = TurnVisibility(cube.rest, cube.surface, Centre(cube), &axes);
  for (int k = 0; k < 3; ++k) EXPECT_NEAR(b(k), 0.2, 0.02) << b.transpose();
}

TEST(TurnVisibility, CylinderHidesOnlyItsAxis) {
  const TetMesh cyl = MakeCylinder(0.02, 0.2, 16, 10);
  Eigen::Matrix3d axes;
  const Eigen::Vector3d c = Centre(cyl);
  const Eigen::Vector3d s = TurnVisibility(cyl.rest, cyl.surface, c, &axes);
  EXPECT_LT(s(0), 0.2 * kVisibleTurn) << s.transpose();
  EXPECT_GT(s(1), kVisibleTurn) << s.transpose();
  // The hidden axis is the cylinder's: the direction of its largest extent.
  const Eigen::Vector3d extent = cyl.rest.colwise().maxCoeff() - cyl.rest.colwise().minCoeff();
  Eigen::Index along;
  extent.maxCoeff(&along);
  EXPECT_GT(std::abs(axes.col(0).normalized()(along)), 0.999) << axes;
}

// A turn is invariant under a rigid motion of the surface: the visibilities do not change.
TEST(TurnVisibility, IndependentOfPose) {
  const TetMesh box = MakeBox(Eigen::Vector3d(0.2, 0.05, 0.03), 8, 3, 2);
  const Eigen::Matrix3d R = Eigen::AngleAxisd(0.7, Eigen::Vector3d(1, 2, 3).normalized()).toRotationMatrix();
  const Eigen::RowVector3d t(0.3, -0.1, 0.5);
  Vertices moved = (box.rest * R.transpose()).rowwise() + t;
  const Eigen::Vector3d a = TurnVisibility(box.rest, box.surface, Centre(box), nullptr);
  const Eigen::Vector3d b = TurnVisibility(moved, box.surface, R * Centre(box) + t.transpose(), nullptr);
  EXPECT_LT((a - b).norm(), 1e-9) << a.transpose() << " / " << b.transpose();
}

// One object's state after two frames: x_before, then x turned by `angle` about `axis` through
// its centre and shifted by `shift`.
TrackerState Turned(const TetMesh& mesh, const Eigen::Vector3d& axis, double angle,
                    const Eigen::Vector3d& shift) {
  TrackerState state;
  ObjectState object;
  object.mesh = mesh;
  state.objects.push_back(object);
  state.num_vertices = mesh.num_vertices();
  state.mass = Eigen::VectorXd::Ones(state.num_vertices);
  state.x_before = mesh.rest;
  const Eigen::Vector3d c = state.x_before.colwise().mean().transpose();
  const Eigen::Matrix3d R = Eigen::AngleAxisd(angle, axis.normalized()).toRotationMatrix();
  state.x = ((state.x_before.rowwise() - c.transpose()) * R.transpose()).rowwise() +
            (c + shift).transpose();
  return state;
}

TEST(PredictMotion, CarriesASpheresShiftButNotItsTurn) {
  const Eigen::Vector3d shift(0.004, -0.002, 0.001);
  const TrackerState state = Turned(MakeSphere(0.05, 5), Eigen::Vector3d(1, 1, 0), 0.05, shift);
  const Vertices predicted = PredictMotion(state);
  // Where it is now, moved on by the shift: every vertex within a faceted sphere's share.
  const Vertices expected = state.x.rowwise() + shift.transpose();
  const double full_turn = (2.0 * state.x - state.x_before - expected).rowwise().norm().maxCoeff();
  EXPECT_LT((predicted - expected).rowwise().norm().maxCoeff(), 0.15 * full_turn);
}

TEST(PredictMotion, CarriesABoxsTurn) {
  const TrackerState state = Turned(MakeBox(Eigen::Vector3d(0.1, 0.1, 0.1), 3, 3, 3),
                                    Eigen::Vector3d(0, 0, 1), 0.05, Eigen::Vector3d(0.001, 0, 0));
  const Vertices predicted = PredictMotion(state);
  EXPECT_LT((predicted - (2.0 * state.x - state.x_before)).norm(), 1e-12);
}

TEST(PredictMotion, AnchoredBodiesKeepTheirTurn) {
  TrackerState state = Turned(MakeSphere(0.05, 5), Eigen::Vector3d(0, 0, 1), 0.05, Eigen::Vector3d::Zero());
  Anchor anchor;
  anchor.object = 0;
  anchor.vertices = {0};
  state.anchors["clamp"] = anchor;
  EXPECT_LT((PredictMotion(state) - (2.0 * state.x - state.x_before)).norm(), 1e-12);
}

// An outer iteration's move (x_before -> x here) keeps a sphere's shift and loses its turn,
// keeps a box's turn, and leaves an anchored sphere alone.
TEST(HoldHiddenTurns, TakesASpheresTurnOutOfAMove) {
  const Eigen::Vector3d shift(0.003, 0.001, -0.002);
  const TrackerState state = Turned(MakeSphere(0.05, 5), Eigen::Vector3d(1, -1, 2), 0.04, shift);
  Vertices x = state.x;
  EXPECT_TRUE(HoldHiddenTurns(state, state.x_before, &x));
  const Vertices expected = state.x_before.rowwise() + shift.transpose();
  const double turn = (state.x - expected).rowwise().norm().maxCoeff();
  EXPECT_LT((x - expected).rowwise().norm().maxCoeff(), 0.15 * turn);
  // The move's shift is kept: the mass centre does not move.
  EXPECT_LT((x.colwise().mean() - state.x.colwise().mean()).norm(), 1e-12);
}

TEST(HoldHiddenTurns, KeepsVisibleAndAnchoredTurns) {
  const TrackerState box = Turned(MakeBox(Eigen::Vector3d(0.1, 0.1, 0.1), 3, 3, 3),
                                  Eigen::Vector3d(0, 1, 1), 0.05, Eigen::Vector3d(0, 0.001, 0));
  Vertices x = box.x;
  HoldHiddenTurns(box, box.x_before, &x);
  EXPECT_LT((x - box.x).norm(), 1e-12);

  TrackerState held = Turned(MakeSphere(0.05, 5), Eigen::Vector3d(0, 0, 1), 0.05, Eigen::Vector3d::Zero());
  Anchor anchor;
  anchor.object = 0;
  anchor.vertices = {0};
  held.anchors["clamp"] = anchor;
  x = held.x;
  EXPECT_FALSE(HoldHiddenTurns(held, held.x_before, &x));
  EXPECT_LT((x - held.x).norm(), 1e-12);
}

// With an embedded surface, its visibility decides: a box scanned inside a round cage keeps
// its turn, which the cage alone would hide.
TEST(HoldHiddenTurns, TheEmbeddedSurfaceDecides) {
  const TetMesh sphere = MakeSphere(0.05, 5);
  const TrackerState state = Turned(sphere, Eigen::Vector3d(0, 0, 1), 0.05, Eigen::Vector3d::Zero());
  const TetMesh box = MakeBox(Eigen::Vector3d(0.05, 0.03, 0.02), 3, 2, 2);
  const Vertices rest = (box.rest.rowwise() - box.rest.colwise().mean()).rowwise() + sphere.rest.colwise().mean();
  EmbeddedSurface surface;
  ASSERT_TRUE(MakeEmbeddedSurface(sphere, rest, box.surface, &surface).ok());
  DataSurface data;
  data.Build(state, {&surface});
  Vertices x = state.x;
  EXPECT_FALSE(HoldHiddenTurns(state, state.x_before, &x, &data));
  EXPECT_LT((x - state.x).norm(), 1e-12);
  EXPECT_TRUE(HoldHiddenTurns(state, state.x_before, &x));
}

// The turns the physical mode's step holds are those the hold takes back: a sphere's three, a
// box's none, and, on a tilted cylinder with uneven masses, a rigid move with no component
// along the returned turn (sum_v (c x r_v) . d_v = 0) has no hidden turn for FindHiddenTurn.
TEST(HiddenTurnAxes, AreTheTurnsTheHoldTakesBack) {
  const TrackerState sphere = Turned(MakeSphere(0.05, 5), Eigen::Vector3d(0, 0, 1), 0.0, Eigen::Vector3d::Zero());
  EXPECT_EQ(HiddenTurnAxes(sphere, 0, sphere.x).size(), 3u);
  const TrackerState box = Turned(MakeBox(Eigen::Vector3d(0.1, 0.1, 0.1), 3, 3, 3), Eigen::Vector3d(0, 0, 1), 0.0,
                                  Eigen::Vector3d::Zero());
  EXPECT_TRUE(HiddenTurnAxes(box, 0, box.x).empty());

  TrackerState cyl = Turned(MakeCylinder(0.02, 0.2, 16, 10), Eigen::Vector3d(1, 2, 0.5), 0.6, Eigen::Vector3d::Zero());
  const int n = cyl.num_vertices;
  for (int v = 0; v < n; ++v) cyl.mass(v) = 1.0 + 0.8 * std::sin(3.0 * v);
  const std::vector<Eigen::Vector3d> held = HiddenTurnAxes(cyl, 0, cyl.x);
  ASSERT_EQ(held.size(), 1u);
  const Eigen::Vector3d centroid = cyl.x.colwise().mean().transpose();
  // A small rigid move about a point off the body: a turn about every axis and a shift.
  const Eigen::Vector3d w = 1e-6 * Eigen::Vector3d(0.3, -1.1, 0.7), pivot(0.05, -0.02, 0.1);
  Eigen::VectorXd u(3 * n), d(3 * n);
  for (int v = 0; v < n; ++v) {
    u.segment<3>(3 * v) = held[0].cross(cyl.x.row(v).transpose() - centroid);
    d.segment<3>(3 * v) = w.cross(cyl.x.row(v).transpose() - pivot);
  }
  const Eigen::VectorXd kept = d - (u.dot(d) / u.squaredNorm()) * u;  // still rigid: u is a turn
  auto hidden_turn = [&](const Eigen::VectorXd& move) {
    Vertices to = cyl.x;
    for (int v = 0; v < n; ++v) to.row(v) += move.segment<3>(3 * v).transpose();
    return FindHiddenTurn(cyl, 0, cyl.x, to).turn.norm();
  };
  const double before = hidden_turn(d), after = hidden_turn(kept);
  EXPECT_GT(before, 0.1 * w.norm());
  EXPECT_LT(after, 1e-4 * before) << before << " -> " << after;
}

}  // namespace
}  // namespace femreg
