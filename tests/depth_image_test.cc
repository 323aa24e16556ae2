// Depth images as frames: 16-bit PNG round trip, refused formats, masks, back-projection
// against the virtual camera, the depth-PNG twin of the bundled demo tracked to the same
// accuracy as its PCD clouds, and masks on the command line (femreg register --mask-dir,
// registration.preprocess.mask_dir) with the units hint on the cloud as used.
#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "femreg/eval.h"
#include "femreg/ground_truth.h"
#include "femreg/io.h"
#include "femreg/point_cloud.h"
#include "femreg/scene.h"
#include "femreg/synth.h"
#include "femreg/tracker.h"
#include "femreg_test_config.h"
#include "test_util.h"

namespace femreg {
namespace {

namespace fs = std::filesystem;

std::string TempPath(const std::string& name) {
  return (fs::temp_directory_path() / ("femreg_depth_" + std::to_string(::getpid()) + "_" + name))
      .string();
}

CameraOptions SmallCamera() {
  CameraOptions c;
  c.enabled = true;
  c.position = Eigen::Vector3d(0.1, -0.3, 0.25);
  c.target = Eigen::Vector3d(0.1, 0.0, 0.0);
  c.up = Eigen::Vector3d::UnitZ();
  c.width = 64;
  c.height = 48;
  c.fx = c.fy = 60.0;
  c.cx = 31.5;
  c.cy = 23.5;
  return c;
}

TEST(DepthPng, RoundTripKeepsEveryValue) {
  RawDepthImage image;
  image.width = 7;
  image.height = 5;
  for (int i = 0; i < 35; ++i) image.values.push_back(static_cast<uint16_t>(i * 1871 % 65536));
  image.values[3] = 65535;
  const std::string path = TempPath("rt.png");
  ASSERT_TRUE(WriteDepthPng(path, image).ok());
  RawDepthImage back;
  Status s = ReadDepthPng(path, &back);
  ASSERT_TRUE(s.ok()) << s.message();
  EXPECT_EQ(back.width, 7);
  EXPECT_EQ(back.height, 5);
  EXPECT_EQ(back.values, image.values);  // integers: exact
  std::remove(path.c_str());
}

TEST(DepthPng, RefusesWhatIsNotA16BitGreyscalePng) {
  const std::string grey8 = TempPath("grey8.png");  // an 8-bit image (a mask)
  ASSERT_TRUE(WriteMaskPng(grey8, 4, 3, std::vector<uint8_t>(12, 1)).ok());
  RawDepthImage image;
  Status s = ReadDepthPng(grey8, &image);
  ASSERT_FALSE(s.ok());
  EXPECT_NE(s.message().find(grey8), std::string::npos) << s.message();
  EXPECT_NE(s.message().find("must be a 16-bit greyscale PNG; this one is 8-bit greyscale"),
            std::string::npos) << s.message();

  const std::string text = TempPath("not.png");
  std::ofstream(text) << "P5 not a png";
  s = ReadDepthPng(text, &image);
  ASSERT_FALSE(s.ok());
  EXPECT_NE(s.message().find("not a PNG file"), std::string::npos) << s.message();

  // A truncated file: the error names it instead of crashing.
  RawDepthImage big;
  big.width = 40;
  big.height = 30;
  for (int i = 0; i < 1200; ++i) big.values.push_back(static_cast<uint16_t>(i * 7919));
  const std::string cut = TempPath("cut.png");
  ASSERT_TRUE(WriteDepthPng(cut, big).ok());
  fs::resize_file(cut, fs::file_size(cut) / 2);
  s = ReadDepthPng(cut, &image);
  ASSERT_FALSE(s.ok());
  EXPECT_NE(s.message().find(cut), std::string::npos) << s.message();
  EXPECT_FALSE(ReadDepthPng(TempPath("missing.png"), &image).ok());
  for (const auto& p : {grey8, text, cut}) std::remove(p.c_str());
}

// The virtual camera renders a box; back-projecting its (noise-free) depth image must give
// the sensor's own cloud: the same rays, the same depths.
TEST(BackProjectDepth, AgreesWithTheVirtualCamera) {
  DepthSensorOptions sensor;
  sensor.camera = SmallCamera();
  sensor.noise_coefficient = 0.0;
  sensor.grazing_angle_deg = 90.0;  // keep every pixel
  TetMesh box = MakeBox(Eigen::Vector3d(0.2, 0.05, 0.05), 4, 1, 1);
  DepthSensor camera(sensor);
  const DepthImage rendered = camera.Render({{&box.x, &box.surface, true}});
  const PointCloud expected = camera.Sample(rendered, {{&box.x, &box.surface, true}}, 1);
  ASSERT_GT(expected.size(), 100);
  EXPECT_TRUE(CameraRotation(sensor.camera).isApprox(camera.rotation(), 1e-15));

  // In units of 1e-6 m so that the rounding to integers is far below the tolerance.
  RawDepthImage image;
  image.width = rendered.width;
  image.height = rendered.height;
  for (float d : rendered.depth) image.values.push_back(static_cast<uint16_t>(std::lround(d / 1e-5)));
  DepthImageOptions options;
  options.depth_scale = 1e-5;
  PointCloud cloud;
  SensorPose pose;
  ASSERT_TRUE(BackProjectDepth(image, sensor.camera, options, nullptr, &cloud, &pose).ok());
  ASSERT_EQ(cloud.size(), expected.size());
  // Both walk the pixels in the same order; the depths differ by the rounding to 1e-5 m
  // (half a unit along a ray that is at most 1.3 times longer than its depth here).
  EXPECT_LT((cloud.points - expected.points).cwiseAbs().maxCoeff(), 1e-5);
  EXPECT_TRUE(pose.known);
  EXPECT_EQ(pose.origin, sensor.camera.position);

  // And back: projecting the cloud gives the image again.
  int dropped = -1;
  const RawDepthImage again = CloudToDepthImage(cloud, sensor.camera, 1e-5, &dropped);
  EXPECT_EQ(dropped, 0);
  EXPECT_EQ(again.values, image.values);
}

TEST(BackProjectDepth, MaskStrideRangeAndSizeChecks) {
  const CameraOptions camera = SmallCamera();
  RawDepthImage image;
  image.width = camera.width;
  image.height = camera.height;
  image.values.assign(static_cast<size_t>(camera.width * camera.height), 400);  // 0.4 m
  image.values[0] = 0;     // no return
  image.values[1] = 2000;  // 2 m: beyond max_depth below
  DepthImageOptions options;
  PointCloud cloud;
  ASSERT_TRUE(BackProjectDepth(image, camera, options, nullptr, &cloud).ok());
  EXPECT_EQ(cloud.size(), camera.width * camera.height - 1);
  // Every point lies at depth 0.4 m along the axis.
  const Eigen::Matrix3d r = CameraRotation(camera);
  const Eigen::Vector3d q = r * (cloud.points.row(5).transpose() - camera.position);
  EXPECT_NEAR(q.z(), 0.4, 1e-12);

  options.max_depth = 1.0;
  ASSERT_TRUE(BackProjectDepth(image, camera, options, nullptr, &cloud).ok());
  EXPECT_EQ(cloud.size(), camera.width * camera.height - 2);

  // A mask keeping the left half, written as an 8-bit PNG and read back.
  std::vector<uint8_t> mask(static_cast<size_t>(camera.width * camera.height), 0);
  for (int v = 0; v < camera.height; ++v) {
    for (int u = 0; u < camera.width / 2; ++u) mask[static_cast<size_t>(v * camera.width + u)] = 255;
  }
  const std::string dir = TempPath("frames");
  fs::create_directories(dir + "/depth");
  fs::create_directories(dir + "/masks");
  ASSERT_TRUE(WriteMaskPng(dir + "/masks/f.png", camera.width, camera.height, mask).ok());
  ASSERT_TRUE(WriteDepthPng(dir + "/depth/f.png", image).ok());
  options.mask_dir = dir + "/masks";
  PointCloud masked;
  SensorPose pose;
  Status s = ReadFrame(dir + "/depth/f.png", camera, options, &masked, nullptr, &pose);
  ASSERT_TRUE(s.ok()) << s.message();
  EXPECT_EQ(masked.size(), camera.width / 2 * camera.height - 2);
  EXPECT_TRUE(pose.known);

  options.pixel_stride = 2;
  options.mask_dir.clear();
  options.max_depth = 0.0;
  ASSERT_TRUE(ReadFrame(dir + "/depth/f.png", camera, options, &masked).ok());
  EXPECT_EQ(masked.size(), (camera.width / 2) * (camera.height / 2) - 1);

  // A mask of the wrong size, a missing mask, a bad option, a camera of another size.
  ASSERT_TRUE(WriteMaskPng(dir + "/masks/f.png", 3, 3, std::vector<uint8_t>(9, 1)).ok());
  options.mask_dir = dir + "/masks";
  s = ReadFrame(dir + "/depth/f.png", camera, options, &masked);
  ASSERT_FALSE(s.ok());
  EXPECT_NE(s.message().find("the mask is 3x3 pixels"), std::string::npos) << s.message();
  options.mask_dir = dir + "/nowhere";
  EXPECT_FALSE(ReadFrame(dir + "/depth/f.png", camera, options, &masked).ok());
  options.mask_dir.clear();
  options.depth_scale = 0.0;
  s = ReadFrame(dir + "/depth/f.png", camera, options, &masked);
  ASSERT_FALSE(s.ok());
  EXPECT_NE(s.message().find("depth_scale"), std::string::npos) << s.message();
  options.depth_scale = 0.001;
  CameraOptions other = camera;
  other.width = 640;
  s = ReadFrame(dir + "/depth/f.png", other, options, &masked);
  ASSERT_FALSE(s.ok());
  EXPECT_NE(s.message().find("64x48 pixels, the camera 640x48"), std::string::npos) << s.message();
  fs::remove_all(dir);
}

// Mean vertex error (m) over the frames of one version of the demo.
double TrackDemo(const Scene& scene, const std::vector<std::string>& frames, bool depth) {
  std::unique_ptr<Tracker> tracker;
  Status s = Tracker::Create(scene, &tracker);
  EXPECT_TRUE(s.ok()) << s.message();
  double sum = 0.0;
  for (size_t f = 0; f < frames.size(); ++f) {
    const std::string stem = frames[f];
    PointCloud cloud;
    s = depth ? ReadFrame(std::string(FEMREG_DATASETS_DIR) + "/demo/depth/" + stem + ".png",
                          scene.registration.camera, DepthImageOptions(), &cloud)
              : ReadFrame(std::string(FEMREG_DATASETS_DIR) + "/demo/clouds/" + stem + ".pcd",
                          scene.registration.camera, DepthImageOptions(), &cloud);
    EXPECT_TRUE(s.ok()) << s.message();
    FrameSummary summary;
    EXPECT_TRUE(tracker->Track(cloud, &summary).ok());
    EXPECT_TRUE(summary.IsSolutionUsable()) << summary.message;
    GroundTruthFrame truth;
    s = ReadGroundTruthFrame(std::string(FEMREG_DATASETS_DIR) + "/demo/ground_truth/" + stem + ".csv",
                             &truth);
    EXPECT_TRUE(s.ok()) << s.message();
    sum += ComputeVertexErrors(tracker->vertices(0), truth).all.mean;
  }
  return sum / static_cast<double>(frames.size());
}

// The bundled demo as 16-bit millimetre PNGs (femreg synth --depth-png) is tracked as well
// as from its PCD clouds: the 1 mm depth rounding is small against the clouds' sensor noise and
// changes the mean vertex error by little (docs/notes/2026-11-28-figures-from-code-comments.md).
TEST(DepthFrames, DemoTwinTracksLikeItsClouds) {
  Scene scene;
  Status s = LoadScene(std::string(FEMREG_DATASETS_DIR) + "/demo/scene.yaml", &scene);
  ASSERT_TRUE(s.ok()) << s.message();
  std::vector<std::string> frames;
  for (int f = 0; f < 30; ++f) {
    char name[32];
    std::snprintf(name, sizeof(name), "frame_%04d", f);
    frames.push_back(name);
  }
  const double pcd = TrackDemo(scene, frames, false);
  const double png = TrackDemo(scene, frames, true);
  std::printf("mean vertex error: PCD %.4f mm, depth PNG %.4f mm\n", pcd * 1e3, png * 1e3);
  EXPECT_GT(pcd, 0.0);
  EXPECT_LT(std::abs(png - pcd), 0.05 * pcd);
}

// ---- Masks on the command line.

// A 16-bit mask whose object pixels hold the label 1 (as segmentation tools write them):
// nonzero, so kept (reducing 16-bit samples to 8 bits would make it 0).
TEST(DepthMasks, SixteenBitLabelMaskKeepsItsPixels) {
  testing_util::TempDir tmp;
  RawDepthImage labels;
  labels.width = 5;
  labels.height = 2;
  labels.values = {0, 1, 0, 2, 0, 300, 0, 0, 0, 65535};
  ASSERT_TRUE(WriteDepthPng(tmp.File("labels.png"), labels).ok());  // 16-bit greyscale
  std::vector<uint8_t> keep;
  Status s = ReadMaskPng(tmp.File("labels.png"), 5, 2, &keep);
  ASSERT_TRUE(s.ok()) << s.message();
  EXPECT_EQ(keep, (std::vector<uint8_t>{0, 1, 0, 1, 0, 1, 0, 0, 0, 1}));
  s = ReadMaskPng(tmp.File("labels.png"), 4, 2, &keep);
  ASSERT_FALSE(s.ok());
  EXPECT_NE(s.message().find(tmp.File("labels.png")), std::string::npos) << s.message();
  EXPECT_NE(s.message().find("the mask is 5x2 pixels, the depth image 4x2"), std::string::npos) << s.message();
}

// The scene key: relative to the scene file's folder, written back relative to it.
TEST(DepthMasks, SceneKeyIsRelativeToTheSceneFile) {
  testing_util::TempDir tmp;
  const std::string text =
      "objects: [{generate: {shape: box, size: [0.1, 0.02, 0.02], cells: [4, 1, 1]}}]\n"
      "registration:\n  preprocess: {mask_dir: masks, crop: {min: [-1, -1, -1], max: [1, 1, 1]}}\n";
  const std::string path = tmp.Write("scene.yaml", text);
  Scene scene;
  Status s = LoadScene(path, &scene);
  ASSERT_TRUE(s.ok()) << s.message();
  EXPECT_EQ(scene.registration.preprocess.mask_dir, tmp.path() + "/masks");
  EXPECT_NE(SceneToYaml(scene, tmp.path()).find("mask_dir: masks"), std::string::npos)
      << SceneToYaml(scene, tmp.path());
  tmp.Write("empty.yaml", "objects: [{generate: {shape: box, size: [0.1, 0.02, 0.02], cells: [4, 1, 1]}}]\n"
                          "registration: {preprocess: {mask_dir: ''}}\n");
  s = LoadScene(tmp.File("empty.yaml"), &scene);
  ASSERT_FALSE(s.ok());
  EXPECT_NE(s.message().find("registration.preprocess.mask_dir: must name a folder"), std::string::npos)
      << s.message();
}

using testing_util::CliRun;
using testing_util::Femreg;
using testing_util::Slurp;
using testing_util::StatsColumn;

constexpr int kMaskFrames = 3;

// The first frames of the demo's depth twin in a room: every pixel where the sensor saw
// nothing gets a wall 2.5 m away (ROOT/room/), so the raw images span about 4 m around a
// 0.3 m beam; ROOT/masks/ holds 16-bit masks, label 1 on the beam's pixels; ROOT/plain/ the
// frames as bundled. Returns the beam's pixel count per frame.
std::vector<int> MakeRoomFrames(const std::string& root) {
  const std::string demo = std::string(FEMREG_DATASETS_DIR) + "/demo";
  for (const char* d : {"/room", "/masks", "/plain"}) fs::create_directories(root + d);
  std::vector<int> beam_pixels;
  for (int f = 0; f < kMaskFrames; ++f) {
    char name[32];
    std::snprintf(name, sizeof(name), "frame_%04d.png", f);
    RawDepthImage image, mask;
    EXPECT_TRUE(ReadDepthPng(demo + "/depth/" + name, &image).ok());
    fs::copy_file(demo + "/depth/" + name, root + "/plain/" + name);
    mask = image;
    int count = 0;
    for (size_t i = 0; i < image.values.size(); ++i) {
      mask.values[i] = image.values[i] != 0 ? 1 : 0;
      count += image.values[i] != 0;
      if (image.values[i] == 0) image.values[i] = 2500;  // mm
    }
    beam_pixels.push_back(count);
    EXPECT_TRUE(WriteDepthPng(root + "/room/" + name, image).ok());
    EXPECT_TRUE(WriteDepthPng(root + "/masks/" + name, mask).ok());  // a 16-bit mask
  }
  return beam_pixels;
}

std::string RegisterArgs(const std::string& frames, const std::string& out) {
  const std::string demo = std::string(FEMREG_DATASETS_DIR) + "/demo";
  return "register --scene " + demo + "/scene.yaml --frames " + frames + " --ground-truth " + demo +
         "/ground_truth --no-progress --report none --threads 1 --force --out " + out;
}

// Masked, the room's frames are the bundled frames: the same points read, the same points
// used, the same vertex errors; the wall is not used. Unmasked, the wall is read and the
// units hint (which looks at the cloud as used) sees a cloud 20 times the beam whose points
// are as close as the beam's edges: a note to mask or crop, not "Different units?" (the
// units are right); masked, or cropped to the beam, nothing.
TEST(DepthMasks, RegisterAppliesMasksFromTheCommandLine) {
  testing_util::TempDir tmp;
  const std::vector<int> beam_pixels = MakeRoomFrames(tmp.path());
  const CliRun plain = Femreg(RegisterArgs(tmp.File("plain"), tmp.File("out_plain")));
  ASSERT_EQ(plain.code, 0) << plain.out;
  const CliRun masked = Femreg(RegisterArgs(tmp.File("room"), tmp.File("out_masked")) + " --mask-dir " +
                               tmp.File("masks"));
  ASSERT_EQ(masked.code, 0) << masked.out;
  EXPECT_EQ(masked.out.find("Different units?"), std::string::npos) << masked.out;
  EXPECT_EQ(masked.out.find("the first cloud"), std::string::npos) << masked.out;
  const CliRun room = Femreg(RegisterArgs(tmp.File("room"), tmp.File("out_room")));
  ASSERT_EQ(room.code, 0) << room.out;
  const size_t hint = room.out.find("femreg register: note");
  if (hint != std::string::npos) {
    std::printf("%s\n", room.out.substr(hint, room.out.find('\n', hint) - hint).c_str());
  }
  EXPECT_EQ(room.out.find("Different units?"), std::string::npos) << room.out;
  EXPECT_NE(room.out.find("note: the first cloud"), std::string::npos) << room.out;
  EXPECT_NE(room.out.find("points used, after masks and preprocessing"), std::string::npos)
      << room.out;
  EXPECT_NE(room.out.find("median nearest neighbour"), std::string::npos) << room.out;
  EXPECT_NE(room.out.find("The units look right"), std::string::npos) << room.out;
  EXPECT_NE(room.out.find("Mask it (--mask-dir"), std::string::npos) << room.out;

  const auto read_masked = StatsColumn(tmp.File("out_masked"), "cloud_points");
  const auto read_room = StatsColumn(tmp.File("out_room"), "cloud_points");
  const auto used_plain = StatsColumn(tmp.File("out_plain"), "points_used");
  const auto used_masked = StatsColumn(tmp.File("out_masked"), "points_used");
  const auto used_room = StatsColumn(tmp.File("out_room"), "points_used");
  ASSERT_EQ(read_masked.size(), static_cast<size_t>(kMaskFrames));
  for (int f = 0; f < kMaskFrames; ++f) {
    std::printf("frame %d: %d beam pixels; read %s of %d pixels unmasked, %s masked; used %s "
                "unmasked, %s masked, %s bundled\n",
                f, beam_pixels[f], read_room[f].c_str(), 320 * 240, read_masked[f].c_str(),
                used_room[f].c_str(), used_masked[f].c_str(), used_plain[f].c_str());
    EXPECT_EQ(std::stoi(read_masked[f]), beam_pixels[f]);
    EXPECT_EQ(std::stoi(read_room[f]), 320 * 240);
    EXPECT_EQ(used_masked[f], used_plain[f]);
    EXPECT_GT(std::stoi(used_room[f]), 2 * std::stoi(used_masked[f]));
  }
  const auto err_plain = StatsColumn(tmp.File("out_plain"), "err_mean_mm");
  const auto err_masked = StatsColumn(tmp.File("out_masked"), "err_mean_mm");
  const auto err_room = StatsColumn(tmp.File("out_room"), "err_mean_mm");
  for (int f = 0; f < kMaskFrames; ++f) {
    std::printf("frame %d: mean vertex error %s mm bundled, %s masked, %s unmasked\n", f,
                err_plain[f].c_str(), err_masked[f].c_str(), err_room[f].c_str());
  }
  EXPECT_EQ(err_masked, err_plain);

  // summary.json records the masks.
  const std::string summary = Slurp(tmp.File("out_masked") + "/summary.json");
  EXPECT_NE(summary.find("\"mask_dir\": \"" + tmp.File("masks") + "\""), std::string::npos) << summary;
  EXPECT_NE(summary.find(tmp.File("masks") + "/frame_0002.png"), std::string::npos) << summary;
  EXPECT_NE(Slurp(tmp.File("out_room") + "/summary.json").find("\"mask_dir\": null"), std::string::npos);

  // The scene key does the same (here through --set; relative paths: the test above).
  const CliRun key = Femreg(RegisterArgs(tmp.File("room"), tmp.File("out_key")) + " --max-frames 1" +
                            " --set registration.preprocess.mask_dir=" + tmp.File("masks"));
  ASSERT_EQ(key.code, 0) << key.out;
  EXPECT_EQ(StatsColumn(tmp.File("out_key"), "points_used")[0], used_plain[0]);
  EXPECT_EQ(key.out.find("Different units?"), std::string::npos) << key.out;

  // A crop to the beam's surroundings instead of a mask: no units hint either.
  const CliRun cropped = Femreg(RegisterArgs(tmp.File("room"), tmp.File("out_crop")) + " --max-frames 1" +
                                " --set 'registration.preprocess.crop={min: [-0.2, -0.2, -0.2], max: [0.5, 0.3, 0.3]}'");
  ASSERT_EQ(cropped.code, 0) << cropped.out;
  EXPECT_EQ(cropped.out.find("Different units?"), std::string::npos) << cropped.out;
  EXPECT_EQ(cropped.out.find("the first cloud"), std::string::npos) << cropped.out;
}

// A real units mistake is still caught: the demo's first cloud in millimetres against the
// beam in metres.
TEST(DepthMasks, UnitsHintStillCatchesACloudInMillimetres) {
  testing_util::TempDir tmp;
  const std::string demo = std::string(FEMREG_DATASETS_DIR) + "/demo";
  PointCloud cloud;
  ASSERT_TRUE(ReadPointCloud(demo + "/clouds/frame_0000.pcd", &cloud).ok());
  cloud.points *= 1000.0;
  fs::create_directories(tmp.File("mm"));
  ASSERT_TRUE(WritePointCloud(tmp.File("mm/frame_0000.pcd"), cloud).ok());
  const CliRun run = Femreg("register --scene " + demo + "/scene.yaml --frames " + tmp.File("mm") +
                            " --no-progress --report none --threads 1 --out " + tmp.File("out"));
  EXPECT_NE(run.out.find("Different units?"), std::string::npos) << run.out;
  const size_t hint = run.out.find("femreg register: warning: the first cloud");
  ASSERT_NE(hint, std::string::npos) << run.out;
  std::printf("%s\n", run.out.substr(hint, run.out.find('\n', hint) - hint).c_str());
  EXPECT_NE(run.out.find("times larger; its points are"), std::string::npos) << run.out;
  EXPECT_EQ(run.out.find("The units look right"), std::string::npos) << run.out;
}

// A missing mask, or one of another size, stops the run naming the file; with
// --skip-bad-frames the frame is counted as unusable, as an unreadable frame is.
TEST(DepthMasks, MissingOrWrongSizedMaskNamesTheFile) {
  testing_util::TempDir tmp;
  MakeRoomFrames(tmp.path());
  fs::remove(tmp.File("masks/frame_0001.png"));
  CliRun run = Femreg(RegisterArgs(tmp.File("room"), tmp.File("out")) + " --mask-dir " + tmp.File("masks"));
  EXPECT_EQ(run.code, 1) << run.out;
  EXPECT_NE(run.out.find("cannot read frame 1"), std::string::npos) << run.out;
  EXPECT_NE(run.out.find(tmp.File("masks/frame_0001.png") + ": cannot open"), std::string::npos) << run.out;

  run = Femreg(RegisterArgs(tmp.File("room"), tmp.File("out")) + " --mask-dir " + tmp.File("masks") +
               " --skip-bad-frames");
  EXPECT_EQ(run.code, 0) << run.out;
  EXPECT_NE(run.out.find("1 frame(s) could not be read"), std::string::npos) << run.out;
  const std::string summary = Slurp(tmp.File("out/summary.json"));
  EXPECT_NE(summary.find("\"frames_unreadable\": 1"), std::string::npos) << summary;
  EXPECT_NE(summary.find("\"frames_usable\": 2"), std::string::npos) << summary;
  EXPECT_NE(Slurp(tmp.File("out/stats.csv")).find(tmp.File("masks/frame_0001.png")), std::string::npos);

  ASSERT_TRUE(WriteMaskPng(tmp.File("masks/frame_0001.png"), 10, 10, std::vector<uint8_t>(100, 1)).ok());
  run = Femreg(RegisterArgs(tmp.File("room"), tmp.File("out")) + " --mask-dir " + tmp.File("masks"));
  EXPECT_EQ(run.code, 1) << run.out;
  EXPECT_NE(run.out.find(tmp.File("masks/frame_0001.png") + ": the mask is 10x10 pixels, the depth image 320x240"),
            std::string::npos) << run.out;

  // Masks are for depth images; a folder that is not there is named.
  run = Femreg(RegisterArgs(tmp.File("room"), tmp.File("out")) + " --mask-dir " + tmp.File("nowhere"));
  EXPECT_EQ(run.code, 1) << run.out;
  EXPECT_NE(run.out.find("--mask-dir: " + tmp.File("nowhere") + ": no such folder"), std::string::npos) << run.out;
  const std::string demo = std::string(FEMREG_DATASETS_DIR) + "/demo";
  run = Femreg(RegisterArgs(demo + "/clouds", tmp.File("out")) + " --mask-dir " + tmp.File("masks"));
  EXPECT_EQ(run.code, 1) << run.out;
  EXPECT_NE(run.out.find("masks apply to depth-image (.png, .npy) frames"), std::string::npos) << run.out;
}

}  // namespace
}  // namespace femreg
