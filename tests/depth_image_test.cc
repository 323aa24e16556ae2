// Depth images as frames: 16-bit PNG round trip, refused formats, masks, back-projection
// against the virtual camera, and the depth-PNG twin of the bundled demo tracked to the
// same accuracy as its PCD clouds.
#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
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

}  // namespace
}  // namespace femreg
