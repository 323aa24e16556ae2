// The layouts users record in, through `femreg register`: the bundled demo's depth frames
// rewritten as a TUM RGB-D sequence (5000 units per metre, an associations file whose order
// is not the names' order), as float32 .npy frames in metres with the camera from an
// Open3D intrinsics JSON (--intrinsics), each tracked as the PNG frames are; and the errors
// of a bad list or intrinsics file, which name the file and the line or field.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "femreg/camera_io.h"
#include "femreg/point_cloud.h"
#include "femreg/scene.h"
#include "femreg_test_config.h"
#include "npy_bytes.h"
#include "test_util.h"

namespace femreg {
namespace {

namespace fs = std::filesystem;
using testing_util::CliRun;
using testing_util::Femreg;
using testing_util::NpyBytes;
using testing_util::Slurp;
using testing_util::StatsColumn;
using testing_util::TempDir;

constexpr int kFrames = 3;

std::string Demo() { return std::string(FEMREG_DATASETS_DIR) + "/demo"; }

std::string DemoDepth(int f) {
  char name[64];
  std::snprintf(name, sizeof(name), "/depth/frame_%04d.png", f);
  return Demo() + name;
}

std::string RegisterArgs(const std::string& frames, const std::string& out) {
  return "register --scene " + Demo() + "/scene.yaml --frames " + frames + " --ground-truth " + Demo() +
         "/ground_truth --no-progress --report none --threads 1 --force --out " + out;
}

// The demo's first frames as bundled (millimetre PNGs), tracked: the reference.
std::vector<std::string> PlainErrors(const TempDir& tmp) {
  fs::create_directories(tmp.File("plain"));
  for (int f = 0; f < kFrames; ++f) fs::copy_file(DemoDepth(f), tmp.File("plain") + "/" + fs::path(DemoDepth(f)).filename().string());
  const CliRun run = Femreg(RegisterArgs(tmp.File("plain"), tmp.File("out_plain")));
  EXPECT_EQ(run.code, 0) << run.out;
  return StatsColumn(tmp.File("out_plain"), "err_mean_mm");
}

void ExpectSameErrors(const std::vector<std::string>& a, const std::vector<std::string>& b, double tol_mm) {
  ASSERT_EQ(a.size(), b.size());
  for (size_t f = 0; f < a.size(); ++f) {
    std::printf("frame %zu: mean vertex error %s mm, reference %s mm\n", f, a[f].c_str(), b[f].c_str());
    EXPECT_NEAR(std::stod(a[f]), std::stod(b[f]), tol_mm) << "frame " << f;
  }
}

// The demo as a TUM sequence: depth at 5000 units per metre, files named so that their
// natural order is the reverse of time (frame f is depth/<9 - f>.png), listed in time order
// by an associations file (rgb first, as associate.py rgb.txt depth.txt writes it). Tracked
// in the list's order with TUM's scale, it is the bundled sequence: the same errors.
TEST(FrameLayouts, RegisterReadsATumSequenceInItsListsOrder) {
  TempDir tmp;
  const std::vector<std::string> plain = PlainErrors(tmp);
  const std::string seq = tmp.File("rgbd_dataset_demo");
  fs::create_directories(seq + "/depth");
  std::string list = "# timestamp rgb timestamp depth\n";
  for (int f = 0; f < kFrames; ++f) {
    RawDepthImage image;
    ASSERT_TRUE(ReadDepthPng(DemoDepth(f), &image).ok());
    for (uint16_t& v : image.values) v = static_cast<uint16_t>(v * 5);  // mm -> 1/5000 m
    const std::string name = "depth/" + std::to_string(9 - f) + ".png";
    ASSERT_TRUE(WriteDepthPng(seq + "/" + name, image).ok());
    const std::string t = std::to_string(1305031102 + f) + ".5";
    list += t + " rgb/" + std::to_string(9 - f) + ".png " + t + " " + name + "\n";
  }
  tmp.Write("rgbd_dataset_demo/associations.txt", list);

  CliRun run = Femreg(RegisterArgs(seq, tmp.File("out_tum")));
  ASSERT_EQ(run.code, 0) << run.out;
  EXPECT_NE(run.out.find("TUM RGB-D sequence: 3 depth frames in the order of " + seq +
                         "/associations.txt; depth scale 0.0002 m per unit"), std::string::npos) << run.out;
  ExpectSameErrors(StatsColumn(tmp.File("out_tum"), "err_mean_mm"), plain, 2e-3);
  const std::string summary = Slurp(tmp.File("out_tum") + "/summary.json");
  EXPECT_NE(summary.find("\"tum_list\": \"" + seq + "/associations.txt\""), std::string::npos) << summary;
  EXPECT_NE(summary.find("\"depth_scale\": 0.0002"), std::string::npos) << summary;
  EXPECT_NE(summary.find(seq + "/depth/9.png"), std::string::npos) << summary;

  // --depth-scale wins over TUM's (and is recorded).
  run = Femreg(RegisterArgs(seq, tmp.File("out_scale")) + " --max-frames 1 --depth-scale 0.0004");
  EXPECT_NE(run.out.find("depth scale 0.0004 m per unit (--depth-scale)"), std::string::npos) << run.out;
  EXPECT_NE(Slurp(tmp.File("out_scale") + "/summary.json").find("\"depth_scale\": 0.0004"), std::string::npos);

  // A list's bad line and a missing image stop the run before anything is tracked.
  tmp.Write("rgbd_dataset_demo/associations.txt", list + "1305031199.5 rgb/0.png 1305031199.5 depth/0.png\n");
  run = Femreg(RegisterArgs(seq, tmp.File("out_bad")));
  EXPECT_EQ(run.code, 1) << run.out;
  EXPECT_NE(run.out.find(seq + "/associations.txt:5: " + seq + "/depth/0.png: no such file"), std::string::npos)
      << run.out;
  tmp.Write("rgbd_dataset_demo/associations.txt", list + "1305031199.5 depth/9.png extra\n");
  run = Femreg(RegisterArgs(seq, tmp.File("out_bad")));
  EXPECT_EQ(run.code, 1) << run.out;
  EXPECT_NE(run.out.find(seq + "/associations.txt:5: expected \"timestamp depth_path\""), std::string::npos)
      << run.out;
}

// The demo as float32 .npy frames in metres, with the camera's intrinsics from an Open3D
// JSON (--intrinsics replaces a wrong fx that --set put in the scene): the PNG frames'
// errors, to the rounding of metres to float32.
TEST(FrameLayouts, RegisterReadsNpyFramesThroughOpen3dIntrinsics) {
  TempDir tmp;
  const std::vector<std::string> plain = PlainErrors(tmp);
  Scene scene;
  ASSERT_TRUE(LoadScene(Demo() + "/scene.yaml", &scene).ok());
  ASSERT_TRUE(WriteCameraIntrinsics(tmp.File("camera.json"), scene.registration.camera).ok());
  fs::create_directories(tmp.File("npy"));
  fs::create_directories(tmp.File("masks"));
  for (int f = 0; f < kFrames; ++f) {
    RawDepthImage image;
    ASSERT_TRUE(ReadDepthPng(DemoDepth(f), &image).ok());
    std::string data(image.values.size() * 4, '\0');
    for (size_t i = 0; i < image.values.size(); ++i) {
      const float z = static_cast<float>(image.values[i] * 0.001);
      std::memcpy(&data[4 * i], &z, 4);  // little-endian host, as '<f4' says
    }
    const std::string stem = fs::path(DemoDepth(f)).stem().string();
    tmp.Write("npy/" + stem + ".npy",
              NpyBytes("{'descr': '<f4', 'fortran_order': False, 'shape': (" + std::to_string(image.height) + ", " +
                           std::to_string(image.width) + "), }",
                       data));
    ASSERT_TRUE(WriteMaskPng(tmp.File("masks/" + stem + ".png"), image.width, image.height,
                             std::vector<uint8_t>(image.values.size(), 1)).ok());
  }
  CliRun run = Femreg(RegisterArgs(tmp.File("npy"), tmp.File("out_npy")) + " --set registration.camera.fx=100" +
                      " --intrinsics " + tmp.File("camera.json"));
  ASSERT_EQ(run.code, 0) << run.out;
  ExpectSameErrors(StatsColumn(tmp.File("out_npy"), "err_mean_mm"), plain, 2e-3);
  EXPECT_NE(Slurp(tmp.File("out_npy") + "/summary.json").find("\"intrinsics\": \"" + tmp.File("camera.json") + "\""),
            std::string::npos);
  // Masks apply to .npy frames (masks/<stem>.png); all-ones masks keep every point.
  run = Femreg(RegisterArgs(tmp.File("npy"), tmp.File("out_masked")) + " --max-frames 1 --mask-dir " + tmp.File("masks"));
  ASSERT_EQ(run.code, 0) << run.out;
  EXPECT_EQ(StatsColumn(tmp.File("out_masked"), "points_used")[0], StatsColumn(tmp.File("out_npy"), "points_used")[0]);

  tmp.Write("bad.json", "{\"width\": 320, \"height\": 240, \"intrinsic_matrix\": [0, 0, 0, 0, 300, 0, 160, 120, 1]}");
  run = Femreg(RegisterArgs(tmp.File("npy"), tmp.File("out_bad")) + " --intrinsics " + tmp.File("bad.json"));
  EXPECT_EQ(run.code, 1) << run.out;
  EXPECT_NE(run.out.find("--intrinsics: " + tmp.File("bad.json") + ": intrinsic_matrix[0] (fx): must be > 0 (got 0)"),
            std::string::npos) << run.out;
  run = Femreg(RegisterArgs(Demo() + "/clouds", tmp.File("out_bad")) + " --intrinsics " + tmp.File("camera.json"));
  EXPECT_EQ(run.code, 1) << run.out;
  EXPECT_NE(run.out.find("--intrinsics: the frames are point clouds"), std::string::npos) << run.out;
}

// The camera matrix as text (DeepDeform's intrinsics.txt is its 4x4 form): --intrinsics
// replaces a wrong fx and a wrong image size that --set put in the scene; the size is the
// first frame's. The bundled PNG frames' errors.
TEST(FrameLayouts, RegisterTakesAMatrixAndTheFramesImageSize) {
  TempDir tmp;
  const std::vector<std::string> plain = PlainErrors(tmp);
  Scene scene;
  ASSERT_TRUE(LoadScene(Demo() + "/scene.yaml", &scene).ok());
  const CameraOptions& c = scene.registration.camera;
  char matrix[512];
  std::snprintf(matrix, sizeof(matrix), "%.17g 0 %.17g 0\n0 %.17g %.17g 0\n0 0 1 0\n0 0 0 1\n", c.fx, c.cx, c.fy,
                c.cy);
  tmp.Write("intrinsics.txt", matrix);
  CliRun run = Femreg(RegisterArgs(tmp.File("plain"), tmp.File("out_matrix")) +
                      " --set registration.camera.fx=100 --set registration.camera.width=100 --intrinsics " +
                      tmp.File("intrinsics.txt"));
  ASSERT_EQ(run.code, 0) << run.out;
  ExpectSameErrors(StatsColumn(tmp.File("out_matrix"), "err_mean_mm"), plain, 2e-3);

  tmp.Write("bad.txt", "262.5 0 159.5\n0 0 119.5\n0 0 1\n");
  run = Femreg(RegisterArgs(tmp.File("plain"), tmp.File("out_bad")) + " --intrinsics " + tmp.File("bad.txt"));
  EXPECT_EQ(run.code, 1) << run.out;
  EXPECT_NE(run.out.find("--intrinsics: " + tmp.File("bad.txt") + ":2: [1][1] (fy): must be > 0 (got 0)"),
            std::string::npos) << run.out;
}

}  // namespace
}  // namespace femreg
