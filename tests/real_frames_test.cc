// Real RGB-D frames of a deforming object through femreg's readers: DeepDeform's samples
// (the example_data folder of DeformableFriends/NeuralTracking: a shirt held up and moved,
// 16-bit depth PNGs in millimetres, intrinsics.txt, a 16-bit mask, ground-truth scene flow).
// Their licence keeps them out of the repository: the tests run when FEMREG_DEEPDEFORM_DIR
// names a copy of example_data, and are skipped otherwise
// (docs/guide/depth-images.md#deepdeform-and-other-real-recordings).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "femreg/camera_io.h"
#include "femreg/point_cloud.h"
#include "test_util.h"

namespace femreg {
namespace {

namespace fs = std::filesystem;
using testing_util::TempDir;

std::string DataDir() {
  const char* dir = std::getenv("FEMREG_DEEPDEFORM_DIR");
  return dir != nullptr ? dir : "";
}

#define SKIP_WITHOUT_DEEPDEFORM()                                                                        \
  if (DataDir().empty())                                                                                 \
  GTEST_SKIP() << "FEMREG_DEEPDEFORM_DIR is not set: point it at a copy of DeepDeform's example_data "   \
                  "(DeformableFriends/NeuralTracking) to read real frames; the data is not in the "      \
                  "repository"

std::string Seq258() { return DataDir() + "/train/seq258"; }
std::string Seq017() { return DataDir() + "/test/seq017"; }

CameraOptions CameraOf(const std::string& sequence) {
  CameraOptions camera;
  camera.enabled = true;
  camera.width = 640;  // DeepDeform's depth images (the matrix holds no size)
  camera.height = 480;
  const Status s = ReadCameraIntrinsics(sequence + "/intrinsics.txt", &camera);
  EXPECT_TRUE(s.ok()) << s.message();
  return camera;
}

// A DeepDeform flow file: uint32 width, height, channels, then float32 [channel][row][col].
struct Flow {
  int width = 0, height = 0, channels = 0;
  std::vector<float> values;
  float at(int c, int v, int u) const { return values[(static_cast<size_t>(c) * height + v) * width + u]; }
};

Flow ReadFlow(const std::string& path) {
  Flow flow;
  std::ifstream in(path, std::ios::binary);
  uint32_t header[3] = {0, 0, 0};
  in.read(reinterpret_cast<char*>(header), sizeof(header));  // little-endian, as the host
  flow.width = static_cast<int>(header[0]);
  flow.height = static_cast<int>(header[1]);
  flow.channels = static_cast<int>(header[2]);
  flow.values.resize(static_cast<size_t>(flow.width) * flow.height * flow.channels);
  in.read(reinterpret_cast<char*>(flow.values.data()), static_cast<std::streamsize>(flow.values.size() * 4));
  EXPECT_TRUE(in.good()) << path << ": shorter than its header says";
  return flow;
}

double Median(std::vector<double> v) {
  std::nth_element(v.begin(), v.begin() + v.size() / 2, v.end());
  return v[v.size() / 2];
}

TEST(DeepDeform, IntrinsicsTxtIsTheFourByFourMatrix) {
  SKIP_WITHOUT_DEEPDEFORM();
  for (const std::string& seq : {Seq258(), Seq017()}) {
    PinholeIntrinsics k;
    const Status s = ReadMatrixIntrinsics(seq + "/intrinsics.txt", &k);
    ASSERT_TRUE(s.ok()) << s.message();
    // The sample's Structure Sensor: the values NeuralTracking's example hard-codes.
    EXPECT_NEAR(k.fx, 575.548, 1e-9) << seq;
    EXPECT_NEAR(k.fy, 577.46, 1e-9) << seq;
    EXPECT_NEAR(k.cx, 323.172, 1e-9) << seq;
    EXPECT_NEAR(k.cy, 236.417, 1e-9) << seq;
  }
}

TEST(DeepDeform, DepthPngsAreMillimetresOfTheCamerasSize) {
  SKIP_WITHOUT_DEEPDEFORM();
  const std::string files[] = {Seq258() + "/depth/000000.png", Seq258() + "/depth/000110.png",
                               Seq017() + "/depth/000300.png", Seq017() + "/depth/000600.png"};
  for (const std::string& f : files) {
    RawDepthImage image;
    const Status s = ReadDepthPng(f, &image);
    ASSERT_TRUE(s.ok()) << s.message();
    EXPECT_EQ(image.width, 640) << f;
    EXPECT_EQ(image.height, 480) << f;
    ASSERT_FALSE(image.in_metres());
    std::vector<double> metres;
    for (uint16_t v : image.values) {
      if (v > 0) metres.push_back(v * 0.001);
    }
    // Indoors, a person at arm's length in front of a wall: most pixels have a return, at
    // room distances in millimetres (1 to 4 m).
    EXPECT_GT(metres.size(), image.values.size() * 8 / 10) << f;
    EXPECT_GT(Median(metres), 1.0) << f;
    EXPECT_LT(Median(metres), 4.0) << f;
  }
}

// The 16-bit mask (0 and 65535) as a frame's mask, named like the frame: the cloud is the
// shirt's pixels with a depth, back-projected through intrinsics.txt.
TEST(DeepDeform, MaskKeepsTheShirtOfTheFirstFrame) {
  SKIP_WITHOUT_DEEPDEFORM();
  TempDir tmp;
  fs::create_directories(tmp.File("masks"));
  fs::copy_file(Seq258() + "/mask/000000_shirt.png", tmp.File("masks/000000.png"));
  const CameraOptions camera = CameraOf(Seq258());
  RawDepthImage depth;
  ASSERT_TRUE(ReadDepthPng(Seq258() + "/depth/000000.png", &depth).ok());
  std::vector<uint8_t> keep;
  Status s = ReadMaskPng(tmp.File("masks/000000.png"), 640, 480, &keep);
  ASSERT_TRUE(s.ok()) << s.message();
  size_t kept = 0, with_depth = 0;
  double sum_x = 0, sum_z = 0;
  for (int v = 0; v < 480; ++v) {
    for (int u = 0; u < 640; ++u) {
      const size_t i = static_cast<size_t>(v) * 640 + u;
      if (!keep[i]) continue;
      ++kept;
      if (depth.values[i] == 0) continue;
      ++with_depth;
      const double z = depth.values[i] * 0.001;
      sum_x += (u - camera.cx) / camera.fx * z;
      sum_z += z;
    }
  }
  // A shirt held up at arm's length fills a sixth of the image or so.
  EXPECT_GT(kept, 640u * 480u / 10) << "mask pixels";
  EXPECT_LT(kept, 640u * 480u / 3) << "mask pixels";

  DepthImageOptions options;  // millimetres
  options.mask_dir = tmp.File("masks");
  PointCloud cloud;
  s = ReadDepthFrame(Seq258() + "/depth/000000.png", camera, options, &cloud);
  ASSERT_TRUE(s.ok()) << s.message();
  ASSERT_EQ(static_cast<size_t>(cloud.points.rows()), with_depth);
  // Camera coordinates (the camera at the origin looking along z): the points' centre is
  // the one the pinhole formula gives.
  EXPECT_NEAR(cloud.points.col(0).mean(), sum_x / with_depth, 1e-9);
  EXPECT_NEAR(cloud.points.col(2).mean(), sum_z / with_depth, 1e-9);
  EXPECT_GT(cloud.points.col(2).mean(), 1.0);
  EXPECT_LT(cloud.points.col(2).mean(), 1.6);
}

// DeepDeform's ground truth ties both frames together: each shirt pixel of frame 0 moved by
// its scene flow (metres) lands on frame 110's depth surface. With femreg's depth scale and
// intrinsics it does, to the sensor's millimetres: a wrong scale or matrix would leave the
// moved points metres or pixels off.
TEST(DeepDeform, SceneFlowCarriesTheFirstFrameOntoTheSecond) {
  SKIP_WITHOUT_DEEPDEFORM();
  const CameraOptions camera = CameraOf(Seq258());
  RawDepthImage d0, d1;
  ASSERT_TRUE(ReadDepthPng(Seq258() + "/depth/000000.png", &d0).ok());
  ASSERT_TRUE(ReadDepthPng(Seq258() + "/depth/000110.png", &d1).ok());
  std::vector<uint8_t> keep;
  ASSERT_TRUE(ReadMaskPng(Seq258() + "/mask/000000_shirt.png", 640, 480, &keep).ok());
  const Flow flow = ReadFlow(Seq258() + "/scene_flow/shirt_000000_000110.sflow");
  ASSERT_EQ(flow.width, 640);
  ASSERT_EQ(flow.height, 480);
  ASSERT_EQ(flow.channels, 3);

  const double scale = 0.001;
  std::vector<double> gaps;
  size_t with_flow = 0;
  for (int v = 0; v < 480; ++v) {
    for (int u = 0; u < 640; ++u) {
      const size_t i = static_cast<size_t>(v) * 640 + u;
      if (!keep[i] || d0.values[i] == 0) continue;
      const double f[3] = {flow.at(0, v, u), flow.at(1, v, u), flow.at(2, v, u)};
      if (!std::isfinite(f[0]) || !std::isfinite(f[1]) || !std::isfinite(f[2])) continue;
      ++with_flow;
      const double z = d0.values[i] * scale;
      const double q[3] = {(u - camera.cx) / camera.fx * z + f[0], (v - camera.cy) / camera.fy * z + f[1], z + f[2]};
      const long u1 = std::lround(camera.fx * q[0] / q[2] + camera.cx);
      const long v1 = std::lround(camera.fy * q[1] / q[2] + camera.cy);
      if (u1 < 0 || v1 < 0 || u1 >= 640 || v1 >= 480) continue;
      const uint16_t seen = d1.values[static_cast<size_t>(v1) * 640 + u1];
      if (seen > 0) gaps.push_back(std::abs(seen * scale - q[2]));
    }
  }
  ASSERT_GT(with_flow, 10000u);
  ASSERT_GT(gaps.size(), with_flow * 9 / 10);
  const double within_2cm =
      static_cast<double>(std::count_if(gaps.begin(), gaps.end(), [](double g) { return g < 0.02; })) / gaps.size();
  std::printf("%zu shirt pixels with a scene flow; moved onto frame 110: median depth gap %.2f mm, %.1f %% within 2 cm\n",
              with_flow, Median(gaps) * 1000, 100 * within_2cm);
  EXPECT_LT(Median(gaps), 0.01);
  EXPECT_GT(within_2cm, 0.8);
}

}  // namespace
}  // namespace femreg
