// A hand in the cloud (issues 38 and 39), on the bundled hand_press sequence: the hand's points
// are occluders and do not pull the ball into the hand, the fingers beside it are implausible
// points, the inversion barrier keeps every element upright, and backtracking between outer
// iterations lets the pressed frames stop on a criterion rather than cycle to the cap. Each
// switched off shows the failure it prevents.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <functional>
#include <memory>
#include <string>

#include "femreg/fem.h"
#include "femreg/ground_truth.h"
#include "femreg/io.h"
#include "femreg/point_cloud.h"
#include "femreg/scene.h"
#include "femreg/tracker.h"
#include "femreg_test_config.h"
#include "geometry/nearest.h"
#include "registration/occluders.h"
#include "registration/tracker_state.h"

namespace fs = std::filesystem;

namespace femreg {
namespace {

const std::string kHandPress = std::string(FEMREG_DATASETS_DIR) + "/hand_press";
// Frames 0-2 the ball rests, 3-8 the palm presses it 15 mm down.
constexpr int kFrames = 8;

struct PressRun {
  double worst_top = 0.0;   // m: the tracked top above the truth's, largest over the frames
  double mean_error = 0.0;  // m: mean over the frames of the mean vertex error
  int most_inverted = 0;    // elements with a negative volume, most in a frame
  int occluded_from_press = 1 << 30;  // occluder points, fewest in a pressed frame
  int capped = 0;                     // frames at solver.max_outer_iterations
  int backtracks = 0;                 // outer-iteration moves halved, over the frames
  double worst_width = 0.0;  // m: the tracked extent along x (the fingers' axis) beyond the truth's
  int implausible = 0;       // cloud points found implausible (data.max_strain_step), over the frames
  int carried = 0;           // of those, the ones near the last frame's, left out from the start
  int implausible_frames = 0;  // frames with implausible points
  int restarted_frames = 0;    // frames that started again without them
};

int InvertedElements(const TetMesh& mesh, const Vertices& x) {
  int inverted = 0;
  for (int e = 0; e < mesh.num_tets(); ++e) {
    const Eigen::Vector3d a = x.row(mesh.tets(e, 0)), b = x.row(mesh.tets(e, 1)),
                          c = x.row(mesh.tets(e, 2)), d = x.row(mesh.tets(e, 3));
    const Eigen::Vector3d A = mesh.rest.row(mesh.tets(e, 0)), B = mesh.rest.row(mesh.tets(e, 1)),
                          C = mesh.rest.row(mesh.tets(e, 2)), D = mesh.rest.row(mesh.tets(e, 3));
    const double now = (b - a).cross(c - a).dot(d - a), rest = (B - A).cross(C - A).dot(D - A);
    inverted += now * rest <= 0.0;
  }
  return inverted;
}

// hand_press's frame f: its cloud (the hand's points in it) and its ground truth.
void ReadHandPressFrame(int f, PointCloud* cloud, GroundTruthFrame* truth) {
  char name[64];
  std::snprintf(name, sizeof(name), "frame_%04d", f);
  EXPECT_TRUE(ReadPointCloud(kHandPress + "/clouds/" + name + ".pcd", cloud).ok());
  EXPECT_TRUE(ReadGroundTruthFrame(kHandPress + "/ground_truth/" + name + ".csv", truth).ok());
}

// A tracker on hand_press's scene, one thread, edited by `edit` (may be null); null on failure.
std::unique_ptr<Tracker> HandPressTracker(const std::function<void(Scene*)>& edit) {
  Scene scene;
  Status status = LoadScene(kHandPress + "/scene.yaml", &scene);
  EXPECT_TRUE(status.ok()) << status.message();
  scene.registration.solver.num_threads = 1;
  if (edit) edit(&scene);
  std::unique_ptr<Tracker> tracker;
  status = Tracker::Create(scene, &tracker);
  EXPECT_TRUE(status.ok()) << status.message();
  return tracker;
}

PressRun RunHandPress(void (*edit)(Scene*)) {
  PressRun run;
  const std::unique_ptr<Tracker> tracker = HandPressTracker(edit);
  if (!tracker) return run;
  for (int f = 0; f < kFrames; ++f) {
    PointCloud cloud;
    GroundTruthFrame truth;
    ReadHandPressFrame(f, &cloud, &truth);
    FrameSummary s;
    EXPECT_TRUE(tracker->Track(cloud, &s).ok());
    const Vertices& x = tracker->vertices(0);
    const double top = x.col(2).maxCoeff() - truth.positions.col(2).maxCoeff();
    const double error = ComputeVertexErrors(x, truth).all.mean;
    const int inverted = InvertedElements(tracker->mesh(0), x);
    std::printf("frame %d: error %.2f mm, top above the truth's %.2f mm, %d inverted, %d occluder points, "
                "stopped by %s after %d outer iterations (%d halvings)\n",
                f, error * 1e3, top * 1e3, inverted, s.occluded_points, s.stopped_by.c_str(), s.outer_iterations,
                s.backtracks);
    run.capped += s.termination == TerminationType::kMaxIterations;
    run.backtracks += s.backtracks;
    run.worst_top = std::max(run.worst_top, top);
    const double width = (x.col(0).maxCoeff() - x.col(0).minCoeff()) -
                         (truth.positions.col(0).maxCoeff() - truth.positions.col(0).minCoeff());
    run.worst_width = std::max(run.worst_width, width);
    run.implausible += s.implausible_points;
    run.carried += s.implausible_carried;
    run.implausible_frames += s.implausible_points > 0;
    run.restarted_frames += s.implausible_restarts > 0;
    run.mean_error += error / kFrames;
    run.most_inverted = std::max(run.most_inverted, inverted);
    if (f >= 3) run.occluded_from_press = std::min(run.occluded_from_press, s.occluded_points);
  }
  return run;
}

TEST(HandPress, TheHandIsAnOccluderAndNoElementInverts) {
  const PressRun run = RunHandPress(nullptr);
  EXPECT_GT(run.occluded_from_press, 100);  // the palm's points, in every pressed frame
  EXPECT_EQ(run.most_inverted, 0);
  // The palm hides the top, pressed 15 mm down: the tracked top stays under the palm's
  // points instead of climbing into them.
  EXPECT_LT(run.worst_top, 0.015);
  EXPECT_LT(run.mean_error, 0.008);
  EXPECT_LE(run.capped, 1);
}

// The finger pads hang beside the ball, 25-45 mm from its sides and off every ray that meets
// it: no occluder. Their pull would stretch the sides out to them, a strain no foam takes in a
// frame; they are implausible points and pull nothing.
TEST(HandPress, TheFingersBesideTheBallAreImplausiblePoints) {
  const PressRun run = RunHandPress(nullptr);
  EXPECT_GT(run.implausible, 100);
  EXPECT_LT(run.worst_width, 0.005);
  // The fingers stay from frame to frame: the last frame's implausible points are left out
  // from the start, and many frames need not start again.
  EXPECT_GT(run.carried, 100);
  EXPECT_LT(run.restarted_frames, run.implausible_frames);
  const PressRun off = RunHandPress([](Scene* s) { s->registration.data.max_strain_step = 0.0; });
  EXPECT_EQ(off.implausible, 0);
  EXPECT_EQ(off.carried, 0);
  EXPECT_GT(off.worst_width, 0.02);
}

// The next three switch off the implausible points too: the fingers' pull they remove is what
// made the press cycle, and it also stood behind the climb and the inversions.
TEST(HandPress, WithoutBacktrackingOrReversalCutsThePressedFramesCycleToTheCap) {
  const PressRun run = RunHandPress([](Scene* s) {
    s->registration.solver.backtrack = false;
    s->registration.solver.cut_reversals = false;
    s->registration.data.max_strain_step = 0.0;
  });
  EXPECT_EQ(run.backtracks, 0);
  EXPECT_GE(run.capped, 3);
}

TEST(HandPress, WithoutOccludersTheBallClimbsIntoTheHand) {
  const PressRun run = RunHandPress([](Scene* s) {
    s->registration.data.occluders = false;
    s->registration.data.max_strain_step = 0.0;
  });
  EXPECT_EQ(run.occluded_from_press, 0);
  // Where it ends is chaotic (the pull of a hand the body cannot follow)
  // (docs/notes/2026-11-29-occluders-and-inversion.md).
  EXPECT_GT(run.worst_top, 0.020);
}

TEST(HandPress, WithoutTheBarrierElementsInvert) {
  const PressRun run = RunHandPress([](Scene* s) {
    s->registration.weights.barrier = 0.0;
    s->registration.data.max_strain_step = 0.0;
  });
  EXPECT_GT(run.most_inverted, 0);
}

// forces.when_occluded's test: an occluder whose points reach the body's (within the three
// spacings its growth looks) touches it; one that passes a few centimetres in front does not.
TEST(Occluders, OnlyAnOccluderBesideTheBodysPointsTouchesIt) {
  const double h = 0.002;  // the spacing
  std::vector<Eigen::Vector3d> points;
  std::vector<char> marks;
  for (int i = 0; i < 20; ++i) {
    for (int j = 0; j < 20; ++j) {  // the body: a patch at z = 0
      points.emplace_back(i * h, j * h, 0.0);
      marks.push_back(0);
    }
  }
  auto blob = [&](double x, double z, int columns = 5) {  // an occluder: columns x 5 at height z
    for (int i = 0; i < columns; ++i) {
      for (int j = 0; j < 5; ++j) {
        points.emplace_back(x + i * h, 0.01 + j * h, z);
        marks.push_back(1);
      }
    }
  };
  blob(0.012, 0.03);  // 3 cm in front
  auto count = [&](int enough) {
    Vertices cloud(static_cast<int>(points.size()), 3);
    for (size_t k = 0; k < points.size(); ++k) cloud.row(static_cast<int>(k)) = points[k].transpose();
    const PointIndex index(cloud);
    return TouchingOccluderPoints(cloud, index, h, marks, enough);
  };
  EXPECT_EQ(count(1000), 0);
  blob(-0.010, 0.0, 2);  // 4 and 5 h beside the patch's other edge: among the nearest, beyond the reach
  EXPECT_EQ(count(1000), 0);
  blob(0.041, 0.0);  // 1.5 h beside the patch's edge at x = 0.038, in its plane: a hand holding it
  const int touching = count(1000);
  EXPECT_GE(touching, 5);  // its first column, and its second (2.5 h off) where among its nearest
  EXPECT_LE(touching, 10);
  EXPECT_EQ(count(3), 3);     // stops at enough
}

// The hand holds the ball from frame 13 (its pads close on the sides): those frames are
// registered with the forces estimated (forces.when_occluded, on by default), and the pads no
// longer pull the sides out and roll the ball. Before, while the palm presses (frames 3-8) its
// points stand clear of the ball's, and the frames stay classic.
TEST(HandPress, FramesWhereTheHandHoldsTheBallAreRegisteredWithTheForcesEstimated) {
  auto run = [](bool when_occluded, std::vector<int>* estimated) {
    const auto tracker =
        HandPressTracker([&](Scene* scene) { scene->registration.forces.when_occluded = when_occluded; });
    double grasp_error = 0.0;
    for (int f = 0; f <= 15; ++f) {
      PointCloud cloud;
      GroundTruthFrame truth;
      ReadHandPressFrame(f, &cloud, &truth);
      FrameSummary s;
      EXPECT_TRUE(tracker->Track(cloud, &s).ok());
      if (s.forces_estimated) estimated->push_back(f);
      if (f >= 13) grasp_error += ComputeVertexErrors(tracker->vertices(0), truth).all.mean / 3.0;
    }
    return grasp_error;
  };
  std::vector<int> estimated, none;
  const double with = run(true, &estimated);
  const double without = run(false, &none);
  EXPECT_TRUE(none.empty());
  ASSERT_FALSE(estimated.empty());
  EXPECT_GE(estimated.front(), 12);  // not while the palm presses
  EXPECT_GE(estimated.size(), 2u);
  std::printf("grasp frames 13-15: mean vertex error %.2f mm with the forces estimated there, %.2f mm without\n",
              with * 1e3, without * 1e3);
  EXPECT_LT(with, 0.7 * without);
}

// Frame 18: the hand holds the ball up by its sides, and the frame starts with none of the
// hand's points in front of it, only the last frame's implausible points (the fingers'),
// carried from frame 17, which was switched: they switch it to the forces estimated. There
// the forces push only (forces.when_occluded_pushing_only): a hand cannot pull the surface out
// to its fingers.
TEST(HandPress, WhereTheHandHoldsTheBallUpItsForcesPush) {
  auto run = [](bool pushing_only, double* pull_share) {
    const auto tracker =
        HandPressTracker([&](Scene* scene) { scene->registration.forces.when_occluded_pushing_only = pushing_only; });
    FrameSummary s;
    for (int f = 0; f <= 18; ++f) {
      PointCloud cloud;
      GroundTruthFrame truth;
      ReadHandPressFrame(f, &cloud, &truth);
      EXPECT_TRUE(tracker->Track(cloud, &s).ok());
    }
    // The share of the forces' size that pulls outwards, along the ball's radius.
    const Vertices& x = tracker->vertices(0);
    const Vertices& forces = tracker->external_forces(0);
    const Eigen::RowVector3d centre = x.colwise().mean();
    double pull = 0.0, size = 0.0;
    for (int v = 0; v < x.rows(); ++v) {
      const Eigen::RowVector3d out = (x.row(v) - centre).normalized();
      pull += std::max(0.0, forces.row(v).dot(out));
      size += forces.row(v).norm();
    }
    *pull_share = size > 0 ? pull / size : 0.0;
    return s.forces_estimated;
  };
  double pushing = 0.0, pulling = 0.0;
  EXPECT_TRUE(run(true, &pushing));
  EXPECT_TRUE(run(false, &pulling));
  std::printf("frame 18: share of the forces pulling outwards %.3f pushing only, %.3f free\n", pushing, pulling);
  EXPECT_LT(pushing, 0.1);
  EXPECT_GT(pulling, 0.2);
}

// A part of the body that lagged behind a motion looks like an occluder beside it at the
// frame's start; the switch is decided once an outer iteration has brought the model there and
// released it, also after a restart (whose first iteration starts from the frame's start
// again) and when the pair set is held from the first iteration (no release on its schedule).
// beam_bend has no occluder, and its frame 21 starts with such a part.
TEST(Occluders, ABodysOwnLaggingPartDoesNotSwitchTheFrame) {
  const std::string beam = std::string(FEMREG_DATASETS_DIR) + "/beam_bend";
  for (int variant = 0; variant < 3; ++variant) {
    Scene scene;
    ASSERT_TRUE(LoadScene(beam + "/scene.yaml", &scene).ok());
    scene.registration.solver.num_threads = 1;
    if (variant == 1) scene.registration.data.hold_pairs_after = 1;
    if (variant == 2) scene.registration.solver.stiff_restart_volume = 0.999;  // every frame restarts
    std::unique_ptr<Tracker> tracker;
    ASSERT_TRUE(Tracker::Create(scene, &tracker).ok());
    int solved = 0;
    for (int f = 0; f < 24; ++f) {
      char name[64];
      std::snprintf(name, sizeof(name), "/clouds/frame_%04d.pcd", f);
      PointCloud cloud;
      ASSERT_TRUE(ReadPointCloud(beam + name, &cloud).ok());
      FrameSummary s;
      ASSERT_TRUE(tracker->Track(cloud, &s).ok());
      EXPECT_FALSE(s.forces_estimated) << "variant " << variant << ", frame " << f;
      solved += s.IsSolutionUsable();
    }
    EXPECT_EQ(solved, 24);
  }
}

// The frame back after the object was away starts from the shape held when it left, several
// frames' motion from the cloud: the body's own points in front of that shape look like
// occluders there. The restart's stiff stages bring the model to them, and there they are
// released. beam_bend with frames 8-12 empty: its end, already 10 cm down, sinks 2 cm more and
// twists about 40 degrees meanwhile, and nothing in the cloud is an occluder.
TEST(Occluders, TheFrameBackFromAnAbsenceReleasesItsOwnPointsAsTheModelReachesThem) {
  const std::string beam = std::string(FEMREG_DATASETS_DIR) + "/beam_bend";
  Scene scene;
  ASSERT_TRUE(LoadScene(beam + "/scene.yaml", &scene).ok());
  scene.registration.solver.num_threads = 1;
  std::unique_ptr<Tracker> tracker;
  ASSERT_TRUE(Tracker::Create(scene, &tracker).ok());
  FrameSummary s;
  for (int f = 0; f <= 13; ++f) {
    PointCloud cloud;
    if (f < 8 || f > 12) {
      char name[64];
      std::snprintf(name, sizeof(name), "/clouds/frame_%04d.pcd", f);
      ASSERT_TRUE(ReadPointCloud(beam + name, &cloud).ok());
    }
    ASSERT_TRUE(tracker->Track(cloud, &s).ok());
  }
  EXPECT_EQ(s.large_motion_restarts, 1) << s.message;
  EXPECT_LE(s.occluded_points, 5) << "the beam's own points stayed occluders";
  GroundTruthFrame truth;
  ASSERT_TRUE(ReadGroundTruthFrame(beam + "/ground_truth/frame_0013.csv", &truth).ok());
  const VertexErrors errors = ComputeVertexErrors(tracker->vertices(0), truth);
  // About as close as the run that never lost the beam.
  EXPECT_LT(errors.seen.mean, 0.85e-3) << errors.all.mean;
}

// A tracker state of one bar along x, 10 cm long, `side` square, 10 x 2 x 2 cells, centred on
// the x axis, at rest.
TrackerState BarState(double side) {
  TrackerState state;
  state.objects.resize(1);
  state.objects[0].mesh =
      MakeBox(Eigen::Vector3d(0.1, side, side), 10, 2, 2, Eigen::Vector3d(0, -0.5 * side, -0.5 * side));
  state.objects[0].model.Build(state.objects[0].mesh, ElasticModelType::kCorotational, Material());
  state.RebuildGlobalArrays();
  return state;
}

// Points found implausible (data.max_strain_step) are a hand's beside the body, not the body's
// own part that moved faster than the frame's first solve followed. A 10 x 2 x 2 cm bar seen
// from -y, its tip (x >= 9 cm) pulled 3 cm towards the sensor so that the cell before it is
// sheared far past the limit. Where nothing of the cloud is left at the tip's place at the
// frame's start while the rest of the bar's points are where it was, the points that pulled
// the tip are the tip itself, and nothing is marked. They are marked where the body's own
// points are still around the tip's place (a hand pulled it), where the whole bar or most of
// it left its place (a hand carried it: an empty place tells nothing), seen from behind (the
// empty places face away), and without a view.
TEST(Occluders, ABodysOwnPartCarriedOffIsNotImplausible) {
  TrackerState state = BarState(0.02);
  const Vertices start = state.objects[0].mesh.rest;
  const double h = 0.002;
  std::vector<Eigen::Vector3d> points;
  // Points on the face y, x in [x0, x1], kept 1 mm inside its edges: on an edge, a point's
  // closest triangle would be a tie between faces.
  auto face = [&](double x0, double x1, double y) {
    for (double x = x0 + 0.001; x <= x1 - 0.001 + 1e-9; x += h) {
      for (double z = -0.009; z <= 0.009 + 1e-9; z += h) points.emplace_back(x, y, z);
    }
  };
  // The bar moved by `carried` towards the sensor, its tip 3 cm further; the cloud: the bar's
  // visible face up to x = `seen` (1 cm short of the sheared cell), and the tip, where they are
  // now. Of the 33 vertices facing the sensor, 3 per 1 cm of x, those up to `seen` have points.
  auto pose = [&](double carried, double seen = 0.07) {
    state.x = start;
    for (int v = 0; v < state.x.rows(); ++v) state.x(v, 1) -= carried + (state.x(v, 0) > 0.0899 ? 0.03 : 0.0);
    points.clear();
    face(0.0, seen, -0.01 - carried);
    face(0.09, 0.1, -0.04 - carried);
  };
  const auto mark = [&](int view) {  // 0: none; -1, +1: the sensor on that side of y
    Vertices cloud(static_cast<int>(points.size()), 3);
    for (size_t k = 0; k < points.size(); ++k) cloud.row(static_cast<int>(k)) = points[k].transpose();
    const PointIndex index(cloud);
    std::vector<char> marks;
    std::function<bool(const Eigen::Vector3d&, const Eigen::Vector3d&)> faces;
    if (view != 0) faces = [view](const Eigen::Vector3d&, const Eigen::Vector3d& n) { return view * n.y() > 0.0; };
    return MarkImplausible(state, start, cloud, index, h, faces, &marks);
  };
  pose(0.0);
  EXPECT_EQ(mark(-1), 0) << "nothing of the cloud is where the tip was: the tip's own points";
  EXPECT_GT(mark(0), 0) << "without a view, as before";
  face(0.0, 0.07, 0.01);  // the back face, at its place: the empty places there are of the back
  EXPECT_GT(mark(+1), 0) << "seen from behind, the tip's front faces away and says nothing";
  face(0.07, 0.1, -0.01);
  EXPECT_GT(mark(-1), 0) << "the body's own points still at the tip's place: a hand pulled it";
  pose(0.02);
  EXPECT_GT(mark(-1), 0) << "the whole bar left its place: a hand carried it";
  pose(0.0, 0.05);
  EXPECT_EQ(mark(-1), 0) << "18 of 33 facing vertices still have points: the rest stayed";
  pose(0.0, 0.03);
  EXPECT_GT(mark(-1), 0) << "12 of 33: most of the bar left its place";
}

// A seed of the implausible marks lies outside the body at the frame's start: a hand's points
// cannot be inside the body's material, and the body's own points are there where the start
// overshot a motion that stopped (docs/notes/2026-12-08-marks-from-the-side.md). A 10 x 4 x 4
// cm bar whose tip's -y face is moved 2.5 cm, its first layer of cells stretched 2.25 times or
// turned inside out, to points on the moved face 2 cm off the bar's surface at the start:
// pulled out in front of the bar, they are marked; pushed in, inside the bar, they are not,
// unless the side test is off (a cage around an embedded surface).
TEST(Occluders, PointsInsideTheBodyAtTheStartAreNotImplausible) {
  TrackerState state = BarState(0.04);
  const Vertices start = state.objects[0].mesh.rest;
  const double h = 0.002;
  const auto mark = [&](double move, bool outside_only) {
    state.x = start;
    for (int v = 0; v < state.x.rows(); ++v) {
      if (start(v, 0) > 0.0899 && start(v, 1) < -0.0199) state.x(v, 1) += move;
    }
    // On the moved face, 7-9 mm from the bar's end and 10 mm or more from its sides.
    std::vector<Eigen::Vector3d> points;
    for (double x : {0.091, 0.093}) {
      for (double z = -0.01; z <= 0.01 + 1e-9; z += h) points.emplace_back(x, -0.02 + move, z);
    }
    Vertices cloud(static_cast<int>(points.size()), 3);
    for (size_t k = 0; k < points.size(); ++k) cloud.row(static_cast<int>(k)) = points[k].transpose();
    const PointIndex index(cloud);
    std::vector<char> marks;
    return MarkImplausible(state, start, cloud, index, h, {}, &marks, outside_only);
  };
  EXPECT_GT(mark(-0.025, true), 0) << "pulled out to points in front of the bar: a hand's";
  EXPECT_EQ(mark(0.025, true), 0) << "pushed in to points inside the bar at the start: its own";
  EXPECT_GT(mark(0.025, false), 0) << "the same without the side test";
}

// A sliver's strain is not evidence (data.max_strain_step): a good tetrahedron with a sliver
// 0.1 mm thin under it, a few points 1 cm below, 2 mm apart. Moves of the sliver's apex that
// turn it inside out or stretch it many times past the limit, while no edge changes by more
// than the cloud's spacing, mark nothing; once an edge changes by more, the points are marked.
TEST(Occluders, ASliversStrainBelowTheSpacingMarksNothing) {
  TrackerState state;
  state.objects.resize(1);
  TetMesh& mesh = state.objects[0].mesh;
  mesh.rest.resize(5, 3);
  mesh.rest << 0, 0, 0, 0.01, 0, 0, 0, 0.01, 0, 0.003, 0.003, 0.01, 0.003, 0.003, -0.0001;
  mesh.tets.resize(2, 4);
  mesh.tets << 0, 1, 2, 3, 0, 2, 1, 4;
  ASSERT_TRUE(FinalizeMesh(&mesh, "two tetrahedra").ok());
  state.objects[0].model.Build(mesh, ElasticModelType::kCorotational, Material());
  state.RebuildGlobalArrays();
  const Vertices start = mesh.rest;
  const double h = 0.002;
  Vertices cloud(9, 3);
  for (int k = 0; k < 9; ++k) cloud.row(k) << 0.001 + h * (k % 3), 0.001 + h * (k / 3), -0.01;
  const PointIndex index(cloud);
  const auto mark = [&](double apex_z) {
    state.x = start;
    state.x(4, 2) = apex_z;
    std::vector<char> marks;
    return MarkImplausible(state, start, cloud, index, h, {}, &marks);
  };
  EXPECT_EQ(mark(0.00015), 0) << "the sliver inverted by a move far below the spacing";
  EXPECT_EQ(mark(-0.0011), 0) << "upright, eleven times as thick: its edges change by 0.14 mm";
  // The apex's edges are sqrt(18 + z^2) mm long (z in mm), 4.24 mm at rest.
  EXPECT_EQ(mark(-0.0044), 0) << "its edges 1.87 mm longer, below the 2 mm spacing";
  EXPECT_GT(mark(-0.0047), 0) << "its edges 2.09 mm longer, above it";
  EXPECT_GT(mark(-0.0101), 0) << "the apex pulled to the points";
}

}  // namespace
}  // namespace femreg
