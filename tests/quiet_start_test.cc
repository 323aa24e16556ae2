// A pushing-only frame's quiet start (docs/theory/equilibrium.md#where-a-pushing-only-frame-starts):
// which of organ_patch's frames solve pushing only from their first outer iteration, and which
// may not (the first, with the adaptive weight, after the cloud jumped, without the clamp).
#include <gtest/gtest.h>

#include <Eigen/Core>
#include <algorithm>
#include <cstdio>
#include <memory>
#include <string>
#include <vector>

#include "femreg/io.h"
#include "femreg/point_cloud.h"
#include "femreg/scene.h"
#include "femreg/tracker.h"
#include "femreg_test_config.h"
#include "test_util.h"

namespace femreg {
namespace {

const std::string kOrgan = std::string(FEMREG_DATASETS_DIR) + "/organ_patch";

// organ_patch's clouds, in frame order.
std::vector<PointCloud> OrganClouds() { return testing_util::ReadDatasetClouds(kOrgan); }

// organ_patch's scene with its forces estimated, pushing only and frictionless.
Scene PushingOnlyOrgan() {
  Scene scene;
  EXPECT_TRUE(LoadScene(kOrgan + "/scene.yaml", &scene).ok());
  scene.registration.forces.estimate = true;
  scene.registration.forces.pushing_only = true;
  scene.registration.forces.friction = 0.0;
  return scene;
}

// organ_patch's frame summaries (PushingOnlyOrgan), with the scene's settings changed by `edit`;
// `shift` moves frame `shifted`'s cloud.
std::vector<FrameSummary> OrganFrames(void (*edit)(Scene*), int shifted = -1,
                                      const Eigen::Vector3d& shift = Eigen::Vector3d::Zero()) {
  Scene scene = PushingOnlyOrgan();
  if (edit) edit(&scene);
  std::unique_ptr<Tracker> tracker;
  EXPECT_TRUE(Tracker::Create(scene, &tracker).ok());
  std::vector<FrameSummary> frames;
  if (!tracker) return frames;
  std::vector<PointCloud> clouds = OrganClouds();
  for (size_t f = 0; f < clouds.size(); ++f) {
    if (static_cast<int>(f) == shifted) clouds[f].points.rowwise() += shift.transpose();
    FrameSummary s;
    EXPECT_TRUE(tracker->Track(clouds[f], &s).ok());
    frames.push_back(s);
  }
  return frames;
}

// Per frame, whether it solved the pushing-only problem from its first outer iteration
// (FrameSummary::quiet_start).
std::vector<bool> QuietStarts(const std::vector<FrameSummary>& frames) {
  std::vector<bool> quiet;
  for (const FrameSummary& s : frames) quiet.push_back(s.quiet_start);
  return quiet;
}

std::vector<bool> OrganQuietStarts(void (*edit)(Scene*), int shifted = -1,
                                   const Eigen::Vector3d& shift = Eigen::Vector3d::Zero()) {
  return QuietStarts(OrganFrames(edit, shifted, shift));
}

// A clamped organ pressed a little further each frame: after the first frame, its frames solve
// pushing only from the start (docs/theory/equilibrium.md#where-a-pushing-only-frame-starts);
// never the first, never with the adaptive weight (whose reference is the warm start's fit),
// and not a frame whose cloud jumped.
TEST(QuietStart, ClampedOrganFramesSolvePushingOnlyFromTheStart) {
  const std::vector<FrameSummary> frames = OrganFrames(nullptr);
  const std::vector<bool> quiet = QuietStarts(frames);
  ASSERT_EQ(quiet.size(), 12u);
  EXPECT_FALSE(quiet[0]);
  EXPECT_GE(std::count(quiet.begin(), quiet.end(), true), 6);  // 8 of 12 when written

  const std::vector<bool> adaptive = OrganQuietStarts([](Scene* s) { s->registration.forces.adaptive_weight = true; });
  EXPECT_EQ(std::count(adaptive.begin(), adaptive.end(), true), 0);

  // Frame 6's cloud 2 cm off (an eighth of the organ): its first pairs misfit the start.
  const std::vector<bool> jumped = OrganQuietStarts(nullptr, 6, Eigen::Vector3d(0.0, 0.0, 0.02));
  ASSERT_EQ(jumped.size(), 12u);
  EXPECT_TRUE(quiet[6]);
  EXPECT_FALSE(jumped[6]);

  // Without the clamp the organ is a free body, which the warm start's classic fit places.
  const std::vector<bool> free_body = OrganQuietStarts([](Scene* s) { s->anchors.clear(); });
  EXPECT_EQ(std::count(free_body.begin(), free_body.end(), true), 0);
}

// The caller's shape (Tracker::SetVertices) starts afresh: the frame after it takes the warm start.
// Here the shape set is the one the last frame ended on, and the cloud that frame's again: its
// first pairs fit as well as the last frame's, so only the reset tells (with quiet_next kept,
// the frame started quietly when written).
TEST(QuietStart, NotAfterSetVertices) {
  const Scene scene = PushingOnlyOrgan();
  const std::vector<PointCloud> clouds = OrganClouds();
  ASSERT_EQ(clouds.size(), 12u);
  std::unique_ptr<Tracker> tracker;
  ASSERT_TRUE(Tracker::Create(scene, &tracker).ok());
  FrameSummary s;
  size_t quiet = 0;  // the first quiet frame after frame 1
  for (size_t f = 0; f < clouds.size() && quiet == 0; ++f) {
    ASSERT_TRUE(tracker->Track(clouds[f], &s).ok());
    if (f >= 2 && s.quiet_start) quiet = f;
  }
  ASSERT_GT(quiet, 0u);
  ASSERT_TRUE(tracker->SetVertices(0, Vertices(tracker->vertices(0))).ok());
  ASSERT_TRUE(tracker->Track(clouds[quiet], &s).ok());
  EXPECT_FALSE(s.quiet_start);
}

// A quiet start that cost more than the last warm start (its factorizations and its PCG iterations
// at 8 a factorization, counts that do not depend on the machine) leaves the next three frames to
// the warm start; then quiet starts come back.
TEST(QuietStart, CostlyQuietStartBacksOffForThreeFrames) {
  const std::vector<FrameSummary> frames = OrganFrames(nullptr);
  ASSERT_EQ(frames.size(), 12u);
  constexpr int kBackoff = 3;
  double last_warm = -1.0;
  int backoffs = 0, quiet_after_backoff = 0;
  int backoff_end = -1;  // the last frame a back-off keeps from a quiet start
  for (int f = 0; f < static_cast<int>(frames.size()); ++f) {
    const FrameSummary& s = frames[static_cast<size_t>(f)];
    if (f <= backoff_end) {
      EXPECT_FALSE(s.quiet_start) << "frame " << f << " is within a back-off ending at frame " << backoff_end;
    } else if (backoffs > 0 && s.quiet_start) {
      ++quiet_after_backoff;
    }
    const double cost = s.factorizations + s.pcg_iterations / 8.0;
    if (!s.quiet_start) {
      last_warm = cost;
    } else if (last_warm >= 0.0 && cost > last_warm) {
      ++backoffs;
      backoff_end = f + kBackoff;
    }
  }
  EXPECT_GE(backoffs, 1);  // frame 1 when written
  EXPECT_GE(quiet_after_backoff, 1);
}

}  // namespace
}  // namespace femreg
