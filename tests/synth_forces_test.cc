// femreg synth's forces.csv: the true external force per frame, every force on the ground
// truth but gravity and what the tracking scene's anchors hold, for each kind of anchor.
#include <gtest/gtest.h>

#include <cmath>
#include <string>
#include <vector>

#include "femreg/datasets.h"
#include "femreg/ground_truth.h"
#include "femreg/mesh.h"
#include "femreg/scene.h"
#include "femreg/synth.h"
#include "synth_samples.h"
#include "test_util.h"

namespace femreg {
namespace {

using testing_util::TempDir;

// The synth sequence of a scene's text, made in a temporary folder: its forces.csv in *forces
// (with its force columns) and the report in *report.
::testing::AssertionResult SynthForces(const std::string& text, std::vector<ForceFrame>* forces,
                                       SynthReport* report = nullptr) {
  Scene scene;
  Status status = ParseScene(text, "synth.yaml", "", &scene);
  if (!status.ok()) return ::testing::AssertionFailure() << status.message();
  TempDir dir;
  SynthReport local;
  status = GenerateSynthSequence(scene, dir.path(), 0, report != nullptr ? report : &local);
  if (!status.ok()) return ::testing::AssertionFailure() << status.message();
  bool has_columns = false;
  status = ReadForces(dir.path() + "/forces.csv", forces, &has_columns);
  if (!status.ok()) return ::testing::AssertionFailure() << status.message();
  if (!has_columns) return ::testing::AssertionFailure() << "forces.csv has no force columns";
  return ::testing::AssertionSuccess();
}

// A force far below the forward solve's tolerance times the forces that act, but far above
// what the solve left unbalanced, is a force: 1 mN sideways on the top of a block that weighs
// 0.3 N, solved to a loose tolerance, is written as it acts.
TEST(SynthSequenceTest, ASmallForceAboveTheSolvesLeftoverIsKept) {
  // The block of the press scenes with its tool kept above it.
  std::vector<ForceFrame> forces;
  ASSERT_TRUE(SynthForces(testing_util::BlockPressSynthScene(
                              "  frames: 1\n  ground_truth: {refinement: 2}\n", "{frame: 1}",
                              "anchors:\n"
                              "  - {name: table, select: {box: {min: [-1, -1, -1], max: [1, 1, 0.0001]}}, hard: true}\n"
                              "gravity: [0, 0, -9.81]\n"
                              "forward: {tolerance: 1e-4}\n"
                              "loads:\n"
                              "  - {select: {box: {min: [-1, -1, 0.0199], max: [1, 1, 1]}}, force: [0.001, 0, 0]}\n"),
                          &forces));
  ASSERT_EQ(forces.size(), 1u);
  EXPECT_NEAR(forces[0].force.x(), 0.001, 1e-5);
  EXPECT_NEAR(forces[0].force.tail<2>().norm(), 0.0, 1e-5);  // the weight and the clamp's reaction
}

// forces.csv holds every external force but gravity and what the tracking scene's anchors
// hold. A block clamped at its bottom and pressed by a tool: with the clamp anchored (by a
// box, a plane, or the tracked vertices' indices on a refined truth) the truth is the tool's
// push, down, and the same under gravity with a load on the clamped face (the anchor's
// reaction takes both, as the tracker's does); with nothing anchored it is the tool and the
// clamp together, which balance to zero; with every vertex anchored it is zero under gravity
// too (not anchored, the clamp's reaction to the weight would remain).
TEST(SynthSequenceTest, ForcesAreWhatTheAnchorsDoNotHold) {
  const std::string synth = "  frames: 2\n  ground_truth: {refinement: 2}\n";
  std::string bottom_indices;
  const TetMesh tracked = MakeBox(Eigen::Vector3d(0.04, 0.04, 0.02), 4, 4, 2);
  for (int v = 0; v < tracked.num_vertices(); ++v) {
    if (tracked.rest(v, 2) < 1e-4) bottom_indices += (bottom_indices.empty() ? "" : ", ") + std::to_string(v);
  }
  struct Case {
    const char* name;
    std::string anchors;
    bool pressed;
  };
  const std::string box_anchor =
      "anchors:\n  - {name: table, select: {box: {min: [-1, -1, -1], max: [1, 1, 0.0001]}}, hard: true}\n";
  const Case cases[] = {
      {"box anchor", box_anchor, true},
      {"index anchor", "anchors:\n  - {name: table, select: {indices: [" + bottom_indices + "]}, hard: true}\n", true},
      {"box anchor, gravity, a load on the clamped face",
       box_anchor + "gravity: [0, 0, -9.81]\n"
                    "loads:\n  - {select: {box: {min: [-1, -1, -1], max: [1, 1, 0.0001]}}, force: [0, 0, -5]}\n",
       true},
      {"plane anchor",
       "anchors:\n  - {name: table, select: {plane: {point: [0, 0, 0.0001], normal: [0, 0, -1]}}, hard: true}\n",
       true},
      {"no anchor", "", false},
      {"every vertex anchored, gravity",
       "gravity: [0, 0, -9.81]\nanchors:\n  - {name: all, select: {all: true}, hard: true}\n", false},
  };
  std::vector<double> pushes;
  for (const Case& c : cases) {
    SCOPED_TRACE(c.name);
    SynthReport report;
    std::vector<ForceFrame> forces;
    ASSERT_TRUE(SynthForces(testing_util::BlockPressSynthScene(synth, "{frame: 1, translation: [0, 0, -0.014]}", c.anchors),
                            &forces, &report));
    EXPECT_GT(report.truth_vertices, report.tracked_vertices);
    ASSERT_EQ(forces.size(), 2u);
    EXPECT_LT(forces[0].force.norm(), 1e-9);  // the tool above the block
    if (c.pressed) {
      // 4 mm into 2 cm of a 1e4 Pa block under a 2 x 2 cm tool: E A d / h = 0.8 N for a free
      // column, about 2 N with the block around it.
      EXPECT_LT(forces[1].force.z(), -0.5);
      EXPECT_LT(forces[1].force.head<2>().norm(), 0.05 * std::abs(forces[1].force.z()));
      pushes.push_back(forces[1].force.z());
    } else {
      EXPECT_LT(forces[1].force.norm(), 1e-6);
      EXPECT_LT(forces[1].torque.norm(), 1e-6);
    }
  }
  ASSERT_EQ(pushes.size(), 4u);
  EXPECT_NEAR(pushes[0], pushes[1], 1e-9 * std::abs(pushes[0]));  // the same vertices held
  EXPECT_NEAR(pushes[0], pushes[3], 1e-9 * std::abs(pushes[0]));
  // Gravity (0.3 N here) and the 5 N load sag the block a little under the tool: the push
  // changes by a few percent, not by either.
  EXPECT_NEAR(pushes[2], pushes[0], 0.05 * std::abs(pushes[0]));
}

// An anchor box around a tracked vertex that no vertex of a truth mesh of its own lies in holds
// the truth vertices nearest that tracked vertex: a load on them is the anchor's reaction,
// not an external force.
TEST(SynthSequenceTest, AnAnchorBoxWithNoTruthVertexHoldsTheNearestOnes) {
  // The truth's 5 x 5 x 3 cells put no vertex at the tracked mesh's mid-height z = 0.01; its
  // edge x = y = 0 has vertices at z = 0.0067 and 0.0133, both nearest the tracked (0, 0, 0.01).
  const std::string synth =
      "  frames: 2\n  ground_truth: {generate: {shape: box, size: [0.04, 0.04, 0.02], cells: [5, 5, 3]}}\n";
  const std::string clamp = "  - {name: table, select: {box: {min: [-1, -1, -1], max: [1, 1, 0.0001]}}, hard: true}\n";
  const std::string load =
      "loads:\n  - {select: {box: {min: [-1, -1, 0.005], max: [0.0001, 0.0001, 0.015]}}, force: [0.5, 0, 0]}\n";
  std::vector<double> sideways;
  for (const bool edge_anchored : {false, true}) {
    SCOPED_TRACE(edge_anchored ? "the edge's tracked vertex anchored" : "only the clamp anchored");
    const std::string anchors =
        "anchors:\n" + clamp +
        (edge_anchored ? "  - {name: edge, select: {box: {min: [-1, -1, 0.0099], max: [0.0001, 0.0001, 0.0101]}}}\n"
                       : "");
    std::vector<ForceFrame> forces;
    ASSERT_TRUE(SynthForces(
        testing_util::BlockPressSynthScene(synth, "{frame: 1, translation: [0, 0, -0.014]}", load + anchors), &forces));
    ASSERT_EQ(forces.size(), 2u);
    EXPECT_LT(forces[1].force.z(), -0.5);  // the tool's push either way
    sideways.push_back(forces[1].force.x());
  }
  // The same truth either way (anchors are the tracking scene's): the difference is the load.
  EXPECT_NEAR(sideways[0] - sideways[1], 0.5, 1e-6);
}

}  // namespace
}  // namespace femreg
