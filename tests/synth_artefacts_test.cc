// The synth artefacts by name (the scene's synth.artefacts, femreg synth --artefact) and the
// sequence's own: an occluder whose points are in the clouds, the object leaving the view.
#include <gtest/gtest.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

#include "femreg/datasets.h"
#include "femreg/ground_truth.h"
#include "femreg/io.h"
#include "femreg/point_cloud.h"
#include "femreg/scene.h"
#include "synth_samples.h"
#include "test_util.h"

namespace fs = std::filesystem;

namespace femreg {
namespace {

class TempDir : public testing_util::TempDir {
 public:
  TempDir() : testing_util::TempDir("femreg_synth_artefacts_test") {}
};

// A clamped bar whose free end moves down, seen from in front and above.
std::string BarScene(const std::string& synth_extra) {
  return testing_util::BarSynthScene(
      "  frames: 6\n"
      "  sanity_check: true\n"
      "  sensor: {noise_coefficient: 0}\n"
      "  motion:\n"
      "    - {name: end, select: {box: {min: [0.0999, -1, -1], max: [1, 1, 1]}},\n"
      "       keyframes: [{frame: 0}, {frame: 5, translation: [0, 0, -0.01]}]}\n" +
      synth_extra);
}

std::string ReadFile(const std::string& path) {
  std::ifstream in(path);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

std::string ParseError(const std::string& text) {
  Scene scene;
  const Status status = ParseScene(text, "synth.yaml", "", &scene);
  return status.ok() ? std::string("(no error)") : status.message();
}

TEST(SynthArtefactsTest, NamesSetStrengthsAndKeys) {
  SynthSpec s;
  EXPECT_EQ(SynthArtefactSummary(s), "");
  ASSERT_TRUE(SetSynthArtefact("flying_pixels=0.3", &s).ok());
  EXPECT_EQ(s.sensor.artefacts.flying_fraction, 0.3);
  ASSERT_TRUE(SetSynthArtefact("flying_pixels.jump=0.01", &s).ok());
  EXPECT_EQ(s.sensor.artefacts.flying_jump, 0.01);
  ASSERT_TRUE(SetSynthArtefact("quantisation", &s).ok());
  EXPECT_EQ(s.sensor.artefacts.disparity_step, 0.125);
  ASSERT_TRUE(SetSynthArtefact("leave_view=4", &s).ok());
  EXPECT_EQ(s.leave_frames, 4);
  EXPECT_EQ(SynthArtefactSummary(s),
            "flying_pixels fraction 0.3 jump 0.01; quantisation step 0.125 baseline 0.075; "
            "leave_view frames 4 start -1");
  SynthSpec all;
  ASSERT_TRUE(SetSynthArtefact("all", &all).ok());
  for (const SynthArtefactKey& k : SynthArtefactKeys()) {
    EXPECT_EQ(k.get(all), k.realistic) << k.artefact << "." << k.key;
  }
  std::string why;
  EXPECT_TRUE(all.sensor.IsValid(&why)) << why;
  EXPECT_NE(SetSynthArtefact("sparkles", &s).message().find("unknown artefact 'sparkles'"),
            std::string::npos);
  EXPECT_NE(SetSynthArtefact("flying_pixels=2", &s).message().find("in [0, 1] (got 2)"),
            std::string::npos);
  EXPECT_NE(SetSynthArtefact("flying_pixels=lots", &s).message().find("not a number"),
            std::string::npos);
  EXPECT_NE(SetSynthArtefact("multipath.depth=1", &s).message().find("one of: bias, radius"),
            std::string::npos);
  EXPECT_NE(SetSynthArtefact("leave_view=2.5", &s).message().find("an integer"),
            std::string::npos);
}

TEST(SynthArtefactsTest, SceneSectionParsesAndErrorsNameTheKey) {
  Scene scene;
  const Status status = ParseScene(
      BarScene("  artefacts: {flicker: 0.002, multipath: {bias: 0.004, radius: 0.02},\n"
               "              occluder: {radius: 0.01}}\n"),
      "synth.yaml", "", &scene);
  ASSERT_TRUE(status.ok()) << status.message();
  EXPECT_EQ(scene.synth.sensor.artefacts.flicker_offset, 0.002);
  EXPECT_EQ(scene.synth.sensor.artefacts.multipath_bias, 0.004);
  EXPECT_EQ(scene.synth.sensor.artefacts.multipath_radius, 0.02);
  EXPECT_EQ(scene.synth.occluder_radius, 0.01);
  EXPECT_EQ(scene.synth.sensor.artefacts.flying_fraction, 0.0);  // the others stay off
  const std::string bad_key = ParseError(BarScene("  artefacts: {multipath: {depth: 1}}\n"));
  EXPECT_NE(bad_key.find("synth.yaml:17"), std::string::npos) << bad_key;
  EXPECT_NE(bad_key.find("depth"), std::string::npos) << bad_key;
  const std::string bad_value = ParseError(BarScene("  artefacts: {dark_holes: 3}\n"));
  EXPECT_NE(bad_value.find("in [0, 1] (got 3)"), std::string::npos) << bad_value;
  const std::string bad_name = ParseError(BarScene("  artefacts: {rain: 1}\n"));
  EXPECT_NE(bad_name.find("rain"), std::string::npos) << bad_name;
}

TEST(SynthArtefactsTest, TheObjectLeavesTheViewAndComesBack) {
  Scene scene;
  ASSERT_TRUE(ParseScene(BarScene("  artefacts: {leave_view: {frames: 2, start: 2}}\n"),
                         "leave.yaml", "", &scene).ok());
  TempDir dir;
  SynthReport report;
  const Status status = GenerateSynthSequence(scene, dir.path(), 0, &report);
  ASSERT_TRUE(status.ok()) << status.message();
  for (int f = 0; f < 6; ++f) {
    SCOPED_TRACE("frame " + std::to_string(f));
    char name[32];
    std::snprintf(name, sizeof(name), "frame_%04d", f);
    PointCloud cloud;
    ASSERT_TRUE(ReadPointCloud(dir.path() + "/clouds/" + name + ".pcd", &cloud).ok());
    GroundTruthFrame truth;
    ASSERT_TRUE(ReadGroundTruthFrame(dir.path() + "/ground_truth/" + name + ".csv", &truth).ok());
    int seen = 0;
    for (char v : truth.visible) seen += v ? 1 : 0;
    const bool away = f == 2 || f == 3;
    EXPECT_EQ(cloud.size() == 0, away);
    EXPECT_EQ(seen == 0, away);
  }
  EXPECT_EQ(report.min_points, 0);
  EXPECT_NE(ReadFile(dir.path() + "/README.md").find("leave_view frames 2 start 2"),
            std::string::npos);
}

TEST(SynthArtefactsTest, AnOccluderCrossesInFrontAndItsPointsAreKept) {
  Scene clean_scene, scene;
  ASSERT_TRUE(ParseScene(BarScene(""), "clean.yaml", "", &clean_scene).ok());
  ASSERT_TRUE(ParseScene(BarScene("  artefacts: {occluder: {radius: 0.012, standoff: 0.02}}\n"),
                         "hand.yaml", "", &scene).ok());
  TempDir clean_dir, dir;
  SynthReport clean_report, report;
  ASSERT_TRUE(GenerateSynthSequence(clean_scene, clean_dir.path(), 0, &clean_report).ok());
  const Status status = GenerateSynthSequence(scene, dir.path(), 0, &report);
  ASSERT_TRUE(status.ok()) << status.message();
  EXPECT_LT(report.mean_seen_fraction, clean_report.mean_seen_fraction);
  // In the middle of its pass, the sphere is in front of the bar: points nearer the camera
  // than any of the bar's.
  const Eigen::Vector3d camera = scene.registration.camera.position;
  int nearer_frames = 0;
  for (int f = 0; f < 6; ++f) {
    char name[32];
    std::snprintf(name, sizeof(name), "frame_%04d", f);
    PointCloud cloud, clean;
    ASSERT_TRUE(ReadPointCloud(dir.path() + "/clouds/" + name + ".pcd", &cloud).ok());
    ASSERT_TRUE(ReadPointCloud(clean_dir.path() + "/clouds/" + name + ".pcd", &clean).ok());
    double clean_nearest = 1e9, nearest = 1e9;
    for (int i = 0; i < clean.size(); ++i) {
      clean_nearest = std::min(clean_nearest, (clean.points.row(i).transpose() - camera).norm());
    }
    for (int i = 0; i < cloud.size(); ++i) {
      nearest = std::min(nearest, (cloud.points.row(i).transpose() - camera).norm());
    }
    nearer_frames += nearest < clean_nearest - 0.015;
  }
  EXPECT_GE(nearer_frames, 2);
  // Too big to fit between the camera and the bar: refused.
  ASSERT_TRUE(SetSynthArtefact("occluder=0.1", &scene.synth).ok());
  TempDir refused;
  const std::string message = GenerateSynthSequence(scene, refused.path(), 0, &report).message();
  EXPECT_NE(message.find("does not fit"), std::string::npos) << message;
}

#ifdef FEMREG_CLI_PATH
TEST(SynthArtefactsTest, TheCommandLineSwitchesThemOn) {
  TempDir dir;
  const std::string scene = dir.path() + "/bar.yaml";
  std::ofstream(scene) << BarScene("");
  using testing_util::Femreg;
  const testing_util::CliRun bad =
      Femreg("synth " + scene + " --out " + dir.path() + "/bad --artefact sparkles=1");
  EXPECT_NE(bad.code, 0);
  EXPECT_NE(bad.out.find("--artefact: unknown artefact 'sparkles'"), std::string::npos) << bad.out;
  // Repeated, and before the scene: each --artefact takes one value.
  const std::string out = dir.path() + "/away";
  const testing_util::CliRun run = Femreg("synth --artefact leave_view=2 --artefact "
                                          "leave_view.start=0 " + scene + " --out " + out +
                                          " --frames 3 --no-progress");
  ASSERT_EQ(run.code, 0) << run.out;
  EXPECT_NE(run.out.find("artefacts: leave_view frames 2 start 0"), std::string::npos) << run.out;
  for (int f = 0; f < 3; ++f) {
    PointCloud cloud;
    const std::string path = out + "/clouds/frame_000" + std::to_string(f) + ".pcd";
    ASSERT_TRUE(ReadPointCloud(path, &cloud).ok());
    EXPECT_EQ(cloud.size() == 0, f < 2) << path;
  }
}
#endif

}  // namespace
}  // namespace femreg
