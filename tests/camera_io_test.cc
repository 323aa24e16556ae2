// The files of depth cameras (femreg/camera_io.h), each written by hand into a temporary
// folder: NumPy .npy depth images (versions 1 and 2, C and Fortran order, both byte
// orders, the dtypes of a depth image and the refusals), Open3D's PinholeCameraIntrinsic
// JSON (as Open3D writes it, and each bad field named), and TUM RGB-D lists (file order,
// which column is the depth image, comments, every bad line named by its line).
#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <cstring>
#include <filesystem>
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
using testing_util::NpyBytes;
using testing_util::TempDir;

// The message of a failed status, and that it failed.
std::string ErrorOf(const Status& s) {
  EXPECT_FALSE(s.ok()) << "accepted";
  return s.message();
}

#define EXPECT_HAS(text, part) EXPECT_NE((text).find(part), std::string::npos) << (text)

// ---- NumPy

template <typename T>
std::string Bytes(const std::vector<T>& v, bool big_endian = false) {
  std::string out(v.size() * sizeof(T), '\0');
  for (size_t i = 0; i < v.size(); ++i) {
    unsigned char b[sizeof(T)];
    std::memcpy(b, &v[i], sizeof(T));  // the host (x86) is little-endian
    for (size_t k = 0; k < sizeof(T); ++k) out[i * sizeof(T) + k] = static_cast<char>(b[big_endian ? sizeof(T) - 1 - k : k]);
  }
  return out;
}

TEST(NpyDepth, ReadsFloat32MetresInRowOrder) {
  TempDir tmp;
  const std::vector<float> m = {0.5f, 0.0f, 1.25f, NAN, 2.0f, 0.75f};
  const std::string path = tmp.Write(
      "d.npy", NpyBytes("{'descr': '<f4', 'fortran_order': False, 'shape': (2, 3), }", Bytes(m)));
  RawDepthImage image;
  Status s = ReadDepthNpy(path, &image);
  ASSERT_TRUE(s.ok()) << s.message();
  EXPECT_EQ(image.width, 3);
  EXPECT_EQ(image.height, 2);
  ASSERT_TRUE(image.in_metres());
  EXPECT_TRUE(image.values.empty());
  EXPECT_EQ(image.metres[0], 0.5f);
  EXPECT_EQ(image.metres[2], 1.25f);
  EXPECT_TRUE(std::isnan(image.metres[3]));
  EXPECT_EQ(image.metres[5], 0.75f);
}

// Version 2 (a 4-byte header length), Fortran order transposed into rows, uint16 units.
TEST(NpyDepth, ReadsUint16UnitsInFortranOrderAndVersion2) {
  TempDir tmp;
  // The 2 x 3 image [[1, 2, 3], [4, 5, 6]] stored column by column.
  const std::vector<uint16_t> columns = {1, 4, 2, 5, 3, 65535};
  const std::string path = tmp.Write(
      "f.npy", NpyBytes("{'descr': '<u2', 'fortran_order': True, 'shape': (2, 3), }", Bytes(columns), 2));
  RawDepthImage image;
  Status s = ReadDepthNpy(path, &image);
  ASSERT_TRUE(s.ok()) << s.message();
  EXPECT_FALSE(image.in_metres());
  EXPECT_EQ(image.values, (std::vector<uint16_t>{1, 2, 3, 4, 5, 65535}));
}

// The header is read as a dict: either quote, keys in any order, no trailing comma; the
// big-endian and float64 dtypes.
TEST(NpyDepth, ReadsTheHeaderAsADictAndBothByteOrders) {
  TempDir tmp;
  const std::vector<float> m = {1.5f, 0.25f};
  std::string path = tmp.Write(
      "be.npy", NpyBytes("{\"shape\": (1, 2), \"fortran_order\": False, \"descr\": \">f4\"}", Bytes(m, true)));
  RawDepthImage image;
  Status s = ReadDepthNpy(path, &image);
  ASSERT_TRUE(s.ok()) << s.message();
  EXPECT_EQ(image.metres, m);
  const std::vector<double> d = {0.125, 3.0};
  path = tmp.Write("f8.npy", NpyBytes("{'descr': '<f8', 'fortran_order': False, 'shape': (2L, 1L), }", Bytes(d)));
  s = ReadDepthNpy(path, &image);
  ASSERT_TRUE(s.ok()) << s.message();
  EXPECT_EQ(image.width, 1);
  EXPECT_EQ(image.metres, (std::vector<float>{0.125f, 3.0f}));
  const std::vector<uint16_t> u = {7, 8};
  path = tmp.Write("beu.npy", NpyBytes("{'descr': '>u2', 'fortran_order': False, 'shape': (1, 2), }", Bytes(u, true)));
  s = ReadDepthNpy(path, &image);
  ASSERT_TRUE(s.ok()) << s.message();
  EXPECT_EQ(image.values, u);
}

TEST(NpyDepth, RefusalsNameTheFileAndTheField) {
  TempDir tmp;
  RawDepthImage image;
  const std::string six_floats = Bytes(std::vector<float>(6, 1.0f));
  auto refuse = [&](const std::string& name, const std::string& bytes) {
    const std::string path = tmp.Write(name, bytes);
    const std::string message = ErrorOf(ReadDepthNpy(path, &image));
    EXPECT_EQ(message.rfind(path + ": ", 0), 0u) << message;  // starts with the file
    return message;
  };
  EXPECT_HAS(refuse("magic.npy", "PK\x03\x04 a zip, not an npy"), "not a NumPy .npy file");
  EXPECT_HAS(refuse("v9.npy", NpyBytes("{'descr': '<f4', 'fortran_order': False, 'shape': (2, 3), }", six_floats, 9)),
             "npy format version 9.0: only versions 1, 2 and 3 are read");
  EXPECT_HAS(refuse("i4.npy", NpyBytes("{'descr': '<i4', 'fortran_order': False, 'shape': (2, 3), }", six_floats)),
             "npy header: descr '<i4': a depth image is float32 or float64 metres");
  EXPECT_HAS(refuse("rank3.npy", NpyBytes("{'descr': '<f4', 'fortran_order': False, 'shape': (1, 2, 3), }", six_floats)),
             "npy header: shape (1, 2, 3): a depth image is (height, width)");
  EXPECT_HAS(refuse("rank1.npy", NpyBytes("{'descr': '<f4', 'fortran_order': False, 'shape': (6,), }", six_floats)),
             "npy header: shape (6,): a depth image is (height, width)");
  EXPECT_HAS(refuse("empty.npy", NpyBytes("{'descr': '<f4', 'fortran_order': False, 'shape': (0, 3), }", "")),
             "shape (0, 3): an empty image");
  EXPECT_HAS(refuse("short.npy", NpyBytes("{'descr': '<f4', 'fortran_order': False, 'shape': (3, 3), }", six_floats)),
             "has 24 bytes; shape (3, 3) of '<f4' needs 36 (truncated)");
  EXPECT_HAS(refuse("long.npy", NpyBytes("{'descr': '<f4', 'fortran_order': False, 'shape': (1, 3), }", six_floats)),
             "has 24 bytes; shape (1, 3) of '<f4' needs 12");
  EXPECT_HAS(refuse("huge.npy", NpyBytes("{'descr': '<f4', 'fortran_order': False, 'shape': (100000, 100000), }", six_floats)),
             "too large (at most 2^28 pixels)");
  EXPECT_HAS(refuse("nokey.npy", NpyBytes("{'descr': '<f4', 'shape': (2, 3), }", six_floats)),
             "npy header: no 'fortran_order' key");
  EXPECT_HAS(refuse("extra.npy", NpyBytes("{'descr': '<f4', 'fortran_order': False, 'shape': (2, 3), 'units': 'mm'}", six_floats)),
             "npy header: unknown key 'units'");
  EXPECT_HAS(refuse("fortran.npy", NpyBytes("{'descr': '<f4', 'fortran_order': 0, 'shape': (2, 3), }", six_floats)),
             "npy header, byte 44: expected a string, True, False or a tuple");
  EXPECT_HAS(refuse("colon.npy", NpyBytes("{'descr' '<f4', 'fortran_order': False, 'shape': (2, 3), }", six_floats)),
             "npy header, byte 19: expected ':' after the key 'descr'");
  EXPECT_HAS(refuse("struct.npy", NpyBytes("{'descr': [('x', '<f4')], 'fortran_order': False, 'shape': (2, 3), }", six_floats)),
             "a structured dtype");
  EXPECT_HAS(refuse("twice.npy", NpyBytes("{'descr': '<f4', 'descr': '<f4', 'fortran_order': False, 'shape': (2, 3)}", six_floats)),
             "the key 'descr' twice");
  // A header length beyond the file, before anything is allocated from it.
  std::string lying = NpyBytes("{'descr': '<f4', 'fortran_order': False, 'shape': (2, 3), }", six_floats);
  lying[8] = '\xff';
  lying[9] = '\xff';
  EXPECT_HAS(refuse("lying.npy", lying), "npy header length 65535 at byte 8: beyond the file's");
  EXPECT_HAS(ErrorOf(ReadDepthNpy(tmp.File("missing.npy"), &image)), tmp.File("missing.npy") + ": cannot open");
}

// A .npy frame back-projects as its PNG twin: uint16 units exactly, float metres to float
// precision; masks of .npy frames are <stem>.png.
TEST(NpyDepth, FramesBackProjectAsTheirPngTwins) {
  TempDir tmp;
  Scene scene;
  Status s = LoadScene(std::string(FEMREG_DATASETS_DIR) + "/demo/scene.yaml", &scene);
  ASSERT_TRUE(s.ok()) << s.message();
  const CameraOptions& camera = scene.registration.camera;
  const std::string png = std::string(FEMREG_DATASETS_DIR) + "/demo/depth/frame_0000.png";
  RawDepthImage image;
  ASSERT_TRUE(ReadDepthPng(png, &image).ok());
  const std::string shape = "(" + std::to_string(image.height) + ", " + std::to_string(image.width) + ")";
  tmp.Write("frame_0000.npy", NpyBytes("{'descr': '<u2', 'fortran_order': False, 'shape': " + shape + ", }",
                                       Bytes(image.values)));
  std::vector<float> metres(image.values.size());
  for (size_t i = 0; i < metres.size(); ++i) metres[i] = static_cast<float>(image.values[i] * 0.001);
  tmp.Write("metres.npy", NpyBytes("{'descr': '<f4', 'fortran_order': False, 'shape': " + shape + ", }", Bytes(metres)));

  DepthImageOptions options;
  PointCloud from_png, from_units, from_metres;
  ASSERT_TRUE(ReadFrame(png, camera, options, &from_png).ok());
  s = ReadFrame(tmp.File("frame_0000.npy"), camera, options, &from_units);
  ASSERT_TRUE(s.ok()) << s.message();
  options.depth_scale = 0.5;  // not used by an image in metres
  s = ReadFrame(tmp.File("metres.npy"), camera, options, &from_metres);
  ASSERT_TRUE(s.ok()) << s.message();
  ASSERT_GT(from_png.size(), 1000);
  EXPECT_EQ(from_units.points, from_png.points);
  ASSERT_EQ(from_metres.size(), from_png.size());
  EXPECT_LT((from_metres.points - from_png.points).cwiseAbs().maxCoeff(), 1e-6);

  // The mask of frame_0000.npy is masks/frame_0000.png.
  EXPECT_EQ(MaskPathFor(tmp.File("masks"), tmp.File("frame_0000.npy")), tmp.File("masks/frame_0000.png"));
  EXPECT_EQ(MaskPathFor("m", "depth/A.PNG"), "m/A.PNG");
  fs::create_directories(tmp.File("masks"));
  std::vector<uint8_t> keep(image.values.size(), 0);
  for (size_t i = 0; i < keep.size() / 2; ++i) keep[i] = 1;
  ASSERT_TRUE(WriteMaskPng(tmp.File("masks/frame_0000.png"), image.width, image.height, keep).ok());
  options.depth_scale = 0.001;
  options.mask_dir = tmp.File("masks");
  PointCloud masked;
  s = ReadFrame(tmp.File("frame_0000.npy"), camera, options, &masked);
  ASSERT_TRUE(s.ok()) << s.message();
  EXPECT_GT(masked.size(), 0);
  EXPECT_LT(masked.size(), from_png.size());
}

// ReadDepthImageFile picks the reader by the extension, in any case: a .npy and a .png of
// the same units read as the same image; another extension is refused naming the file.
TEST(DepthImageFile, ReadsPngAndNpyByExtensionAndRefusesOthers) {
  TempDir tmp;
  RawDepthImage image;
  image.width = 3, image.height = 2, image.values = {0, 1000, 1200, 65535, 7, 900};
  ASSERT_TRUE(WriteDepthPng(tmp.File("d.PNG"), image).ok());
  tmp.Write("d.npy", NpyBytes("{'descr': '<u2', 'fortran_order': False, 'shape': (2, 3), }", Bytes(image.values)));
  RawDepthImage png, npy;
  Status s = ReadDepthImageFile(tmp.File("d.PNG"), &png);
  ASSERT_TRUE(s.ok()) << s.message();
  s = ReadDepthImageFile(tmp.File("d.npy"), &npy);
  ASSERT_TRUE(s.ok()) << s.message();
  for (const RawDepthImage* read : {&png, &npy}) {
    EXPECT_EQ(read->width, 3);
    EXPECT_EQ(read->height, 2);
    EXPECT_EQ(read->values, image.values);
  }
  fs::copy_file(tmp.File("d.npy"), tmp.File("d.tif"));
  const std::string error = ErrorOf(ReadDepthImageFile(tmp.File("d.tif"), &png));
  EXPECT_HAS(error, tmp.File("d.tif"));
  EXPECT_HAS(error, ".png or a .npy");
}

// ---- Open3D intrinsics

// What open3d.io.write_pinhole_camera_intrinsic writes (Open3D 0.16: tabs, spaces before
// the colons).
const char kOpen3dJson[] =
    "{\n\t\"height\" : 480,\n\t\"intrinsic_matrix\" : [ 525.0, 0.0, 0.0, 0.0, 520.5, 0.0, 319.5, "
    "239.25, 1.0 ],\n\t\"width\" : 640\n}";

TEST(Open3dIntrinsics, ReadsWhatOpen3dWritesAndWritesItBack) {
  TempDir tmp;
  PinholeIntrinsics k;
  Status s = ReadOpen3dIntrinsics(tmp.Write("camera.json", kOpen3dJson), &k);
  ASSERT_TRUE(s.ok()) << s.message();
  EXPECT_EQ(k.width, 640);
  EXPECT_EQ(k.height, 480);
  EXPECT_EQ(k.fx, 525.0);
  EXPECT_EQ(k.fy, 520.5);
  EXPECT_EQ(k.cx, 319.5);
  EXPECT_EQ(k.cy, 239.25);
  ASSERT_TRUE(WriteOpen3dIntrinsics(tmp.File("back.json"), k).ok());
  PinholeIntrinsics back;
  ASSERT_TRUE(ReadOpen3dIntrinsics(tmp.File("back.json"), &back).ok());
  EXPECT_EQ(back.fx, k.fx);
  EXPECT_EQ(back.cy, k.cy);
  EXPECT_EQ(back.width, k.width);

  // Into a camera: the intrinsics change, the pose does not.
  CameraOptions camera;
  camera.position = Eigen::Vector3d(1, 2, 3);
  s = ReadCameraIntrinsics(tmp.File("camera.json"), &camera);
  ASSERT_TRUE(s.ok()) << s.message();
  EXPECT_EQ(camera.fy, 520.5);
  EXPECT_EQ(camera.width, 640);
  EXPECT_EQ(camera.position, Eigen::Vector3d(1, 2, 3));
}

TEST(Open3dIntrinsics, ErrorsNameTheFileAndTheField) {
  TempDir tmp;
  PinholeIntrinsics k;
  const std::string matrix = "\"intrinsic_matrix\": [525, 0, 0, 0, 525, 0, 319.5, 239.5, 1]";
  auto refuse = [&](const std::string& text) {
    const std::string path = tmp.Write("camera.json", text);
    const std::string message = ErrorOf(ReadOpen3dIntrinsics(path, &k));
    EXPECT_EQ(message.rfind(path + ":", 0), 0u) << message;
    return message;
  };
  EXPECT_HAS(refuse("{\"height\": 480, " + matrix + "}"), "camera.json: width: missing");
  EXPECT_HAS(refuse("{\"width\": 0, \"height\": 480, " + matrix + "}"), "width: must be a positive integer (got 0)");
  EXPECT_HAS(refuse("{\"width\": 640.5, \"height\": 480, " + matrix + "}"), "width: must be a positive integer (got 640.5)");
  EXPECT_HAS(refuse("{\"width\": 640, \"height\": \"480\", " + matrix + "}"),
             "height: must be a positive integer (got the string '480')");
  EXPECT_HAS(refuse("{\"width\": 640, \"height\": 480}"), "intrinsic_matrix: missing");
  EXPECT_HAS(refuse("{\"width\": 640, \"height\": 480, \"intrinsic_matrix\": [525, 0, 0, 0, 525, 0, 319.5, 239.5]}"),
             "intrinsic_matrix: must be a list of 9 numbers");
  EXPECT_HAS(refuse("{\"width\": 640, \"height\": 480, \"intrinsic_matrix\": [525, 0, 0, 0, 525, 0, \"cx\", 239.5, 1]}"),
             "intrinsic_matrix[6]: must be a finite number (got the string 'cx')");
  EXPECT_HAS(refuse("{\"width\": 640, \"height\": 480, \"intrinsic_matrix\": [525, 0, 0, 0, 0, 0, 319.5, 239.5, 1]}"),
             "intrinsic_matrix[4] (fy): must be > 0 (got 0)");
  EXPECT_HAS(refuse("{\"width\": 640, \"height\": 480, \"intrinsic_matrix\": [525, 0, 0, 0.5, 525, 0, 319.5, 239.5, 1]}"),
             "intrinsic_matrix[3] (the skew): must be 0");
  EXPECT_HAS(refuse("{\"width\": 640, \"height\": 480, \"intrinsic_matrix\": [525, 0, 319.5, 0, 525, 239.5, 0, 0, 1]}"),
             "where a row-major matrix has them; Open3D writes the matrix column by column");
  EXPECT_HAS(refuse("{\"width\": 640, \"height\": 480, \"intrinsic_matrix\": [525, 0, 0, 0, 525, 0, 319.5, 239.5, 2]}"),
             "intrinsic_matrix[8]: must be 1 (got 2)");
  EXPECT_HAS(refuse("[640, 480]"), "must be a JSON object with width, height and intrinsic_matrix");
  // A syntax error names its line.
  const std::string syntax = refuse("{\n\t\"width\" : 640,\n\t\"height\" 480\n}");
  EXPECT_HAS(syntax, "camera.json:3: not JSON: 'parse error at line 3, column");
  // A number JSON cannot hold (nlohmann throws out_of_range, not parse_error: found by the
  // intrinsics fuzz target, fuzz/regressions/intrinsics/).
  EXPECT_HAS(refuse("{\"width\": 1e999, \"height\": 480}"), "camera.json: not JSON: 'number overflow parsing '1e999''");
  EXPECT_HAS(ErrorOf(ReadOpen3dIntrinsics(tmp.File("none.json"), &k)), tmp.File("none.json") + ": cannot open");
}

// The scene key registration.camera.intrinsics: the file relative to the scene, never
// beside the keys it sets, its errors named through the scene's line.
TEST(Open3dIntrinsics, SceneCameraReadsTheFile) {
  TempDir tmp;
  tmp.Write("camera.json", kOpen3dJson);
  const std::string objects = "objects: [{generate: {shape: box, size: [0.1, 0.02, 0.02], cells: [4, 1, 1]}}]\n";
  tmp.Write("scene.yaml", objects +
                              "registration:\n  camera: {position: [0, 0, 1], target: [0, 0, 0], up: [0, 1, 0],\n"
                              "           intrinsics: camera.json}\n");
  Scene scene;
  Status s = LoadScene(tmp.File("scene.yaml"), &scene);
  ASSERT_TRUE(s.ok()) << s.message();
  EXPECT_TRUE(scene.registration.camera.enabled);
  EXPECT_EQ(scene.registration.camera.fy, 520.5);
  EXPECT_EQ(scene.registration.camera.height, 480);
  EXPECT_EQ(scene.registration.camera.position, Eigen::Vector3d(0, 0, 1));
  // Written back resolved: the numbers, so the scene stands without the file.
  EXPECT_HAS(SceneToYaml(scene, tmp.path()), "fy: 520.5");

  tmp.Write("missing.yaml", objects + "registration:\n  camera: {intrinsics: absent.json}\n");
  EXPECT_HAS(ErrorOf(LoadScene(tmp.File("missing.yaml"), &scene)), "absent.json: cannot open: no such file");
  tmp.Write("both.yaml", objects + "registration:\n  camera: {intrinsics: camera.json, fx: 500}\n");
  EXPECT_HAS(ErrorOf(LoadScene(tmp.File("both.yaml"), &scene)),
             "registration.camera.fx: given beside camera.intrinsics, which sets it");
  tmp.Write("bad.json", "{\"width\": 640, \"height\": 480, \"intrinsic_matrix\": [1, 2, 3]}");
  tmp.Write("bad.yaml", objects + "registration:\n  camera:\n    intrinsics: bad.json\n");
  const std::string message = ErrorOf(LoadScene(tmp.File("bad.yaml"), &scene));
  EXPECT_HAS(message, tmp.File("bad.yaml") + ":4: registration.camera.intrinsics: ");
  EXPECT_HAS(message, tmp.File("bad.json") + ": intrinsic_matrix: must be a list of 9 numbers, the 3x3 "
                      "matrix column by column (got a list of 3 values)");
}

// ---- A camera matrix as text

// DeepDeform's intrinsics.txt as its sequences hold it: numpy.savetxt of the 4x4 matrix.
const char kDeepDeformMatrix[] =
    "5.755480000000000018e+02 0.000000000000000000e+00 3.231720000000000255e+02 0.000000000000000000e+00\n"
    "0.000000000000000000e+00 5.774600000000000364e+02 2.364170000000000016e+02 0.000000000000000000e+00\n"
    "0.000000000000000000e+00 0.000000000000000000e+00 1.000000000000000000e+00 0.000000000000000000e+00\n"
    "0.000000000000000000e+00 0.000000000000000000e+00 0.000000000000000000e+00 1.000000000000000000e+00\n";

TEST(MatrixIntrinsics, ReadsDeepDeformsFourByFourAndAThreeByThree) {
  TempDir tmp;
  PinholeIntrinsics k;
  Status s = ReadMatrixIntrinsics(tmp.Write("intrinsics.txt", kDeepDeformMatrix), &k);
  ASSERT_TRUE(s.ok()) << s.message();
  EXPECT_EQ(k.fx, 575.548);
  EXPECT_EQ(k.fy, 577.46);
  EXPECT_EQ(k.cx, 323.172);
  EXPECT_EQ(k.cy, 236.417);
  EXPECT_EQ(k.width, 0);  // a matrix has no image size
  EXPECT_EQ(k.height, 0);
  EXPECT_FALSE(LooksLikeJsonFile(tmp.File("intrinsics.txt")));
  // A byte order mark before Open3D's JSON: still JSON, and read as such.
  EXPECT_TRUE(LooksLikeJsonFile(tmp.Write("bom.json", std::string("\xEF\xBB\xBF") + kOpen3dJson)));
  PinholeIntrinsics with_bom;
  ASSERT_TRUE(ReadOpen3dIntrinsics(tmp.File("bom.json"), &with_bom).ok());
  EXPECT_EQ(with_bom.fx, 525.0);

  // A 3x3 K with a comment, blank lines and Windows line ends.
  s = ReadMatrixIntrinsics(tmp.Write("k.txt", "# K\r\n525 0 319.5\r\n\r\n0 520.5 239.25  # fy, cy\r\n0 0 1\r\n"), &k);
  ASSERT_TRUE(s.ok()) << s.message();
  EXPECT_EQ(k.fx, 525.0);
  EXPECT_EQ(k.fy, 520.5);
  EXPECT_EQ(k.cx, 319.5);
  EXPECT_EQ(k.cy, 239.25);

  // Into a camera: fx..cy change; the image size and the pose are the camera's.
  CameraOptions camera;
  camera.width = 320;
  camera.height = 240;
  camera.position = Eigen::Vector3d(1, 2, 3);
  s = ReadCameraIntrinsics(tmp.File("intrinsics.txt"), &camera);
  ASSERT_TRUE(s.ok()) << s.message();
  EXPECT_EQ(camera.fx, 575.548);
  EXPECT_EQ(camera.cy, 236.417);
  EXPECT_EQ(camera.width, 320);
  EXPECT_EQ(camera.height, 240);
  EXPECT_EQ(camera.position, Eigen::Vector3d(1, 2, 3));
  // A JSON file (even with white space before its brace) is still read as Open3D's.
  s = ReadCameraIntrinsics(tmp.Write("camera.json", std::string("\n  ") + kOpen3dJson), &camera);
  ASSERT_TRUE(s.ok()) << s.message();
  EXPECT_EQ(camera.width, 640);
  EXPECT_EQ(camera.fy, 520.5);
}

TEST(MatrixIntrinsics, ErrorsNameTheFileTheLineAndTheEntry) {
  TempDir tmp;
  PinholeIntrinsics k;
  auto refuse = [&](const std::string& text) {
    return ErrorOf(ReadMatrixIntrinsics(tmp.Write("m.txt", text), &k));
  };
  const std::string m = tmp.File("m.txt");
  EXPECT_HAS(refuse("525 0 319.5\n0 0 239.5\n0 0 1\n"), m + ":2: [1][1] (fy): must be > 0 (got 0)");
  EXPECT_HAS(refuse("525 0.5 319.5\n0 525 239.5\n0 0 1\n"), m + ":1: [0][1] (the skew): must be 0 in a pinhole matrix (got 0.5)");
  // Transposed (cx, cy in the last row): said so.
  EXPECT_HAS(refuse("525 0 0\n0 525 0\n319.5 239.5 1\n"),
             m + ":3: [2][0]: must be 0 in a pinhole matrix (got 319.5); cx and cy are in the last row");
  EXPECT_HAS(refuse("525 0 319.5 0\n0 525 239.5 0\n0 0 1 0\n0 0 0 2\n"), m + ":4: [3][3]: must be 1 in a pinhole matrix (got 2)");
  EXPECT_HAS(refuse("525 0 319.5\n0 525 239.5\n"), m + ": has 2 rows of numbers; a camera matrix as text has 3 (K) or 4");
  EXPECT_HAS(refuse("525 0 319.5\n0 525\n0 0 1\n"), m + ":2: row 1 has 2 numbers; a 3x3 matrix has 3 in every row");
  EXPECT_HAS(refuse("525 0 319.5\n0 fy 239.5\n0 0 1\n"), m + ":2: 'fy' is not a finite number");
  EXPECT_HAS(refuse("525 0 319.5\n0 nan 239.5\n0 0 1\n"), m + ":2: 'nan' is not a finite number");
  EXPECT_HAS(ErrorOf(ReadMatrixIntrinsics(tmp.File("none.txt"), &k)), tmp.File("none.txt") + ": cannot open");
  CameraOptions camera;
  EXPECT_HAS(ErrorOf(ReadCameraIntrinsics(tmp.File("none.txt"), &camera)), tmp.File("none.txt") + ": cannot open");
}

// The scene key with a matrix: fx..cy from the file, width and height beside it (required:
// the file has none), the keys the file sets refused beside it.
TEST(MatrixIntrinsics, SceneCameraTakesTheMatrixAndTheImageSizeBesideIt) {
  TempDir tmp;
  tmp.Write("intrinsics.txt", kDeepDeformMatrix);
  const std::string objects = "objects: [{generate: {shape: box, size: [0.1, 0.02, 0.02], cells: [4, 1, 1]}}]\n";
  tmp.Write("scene.yaml", objects + "registration:\n  camera: {intrinsics: intrinsics.txt, width: 640, height: 480}\n");
  Scene scene;
  Status s = LoadScene(tmp.File("scene.yaml"), &scene);
  ASSERT_TRUE(s.ok()) << s.message();
  EXPECT_TRUE(scene.registration.camera.enabled);
  EXPECT_EQ(scene.registration.camera.fx, 575.548);
  EXPECT_EQ(scene.registration.camera.cx, 323.172);
  EXPECT_EQ(scene.registration.camera.width, 640);
  EXPECT_EQ(scene.registration.camera.height, 480);

  tmp.Write("nosize.yaml", objects + "registration:\n  camera: {intrinsics: intrinsics.txt, width: 640}\n");
  EXPECT_HAS(ErrorOf(LoadScene(tmp.File("nosize.yaml"), &scene)),
             "is a camera matrix (not Open3D's JSON), which holds no image size: give camera.width and "
             "camera.height beside it");
  tmp.Write("both.yaml", objects + "registration:\n  camera: {intrinsics: intrinsics.txt, width: 640, height: 480, cy: 240}\n");
  EXPECT_HAS(ErrorOf(LoadScene(tmp.File("both.yaml"), &scene)),
             "registration.camera.cy: given beside camera.intrinsics, which sets it: give the intrinsics either in "
             "the file or as fx, fy, cx, cy");
  tmp.Write("bad.txt", "525 0 319.5\n0 0 239.5\n0 0 1\n");
  tmp.Write("bad.yaml", objects + "registration:\n  camera: {intrinsics: bad.txt, width: 640, height: 480}\n");
  EXPECT_HAS(ErrorOf(LoadScene(tmp.File("bad.yaml"), &scene)), tmp.File("bad.txt") + ":2: [1][1] (fy): must be > 0");
}

// ---- TUM RGB-D lists

// A sequence folder with depth/ and rgb/ images (empty files: the list reader checks that
// they exist, not what they hold).
void MakeImages(const TempDir& tmp, const std::vector<std::string>& names) {
  fs::create_directories(tmp.File("depth"));
  fs::create_directories(tmp.File("rgb"));
  for (const std::string& n : names) tmp.Write(n, "");
}

TEST(TumSequence, ReadsAnAssociationsFileInItsOrder) {
  TempDir tmp;
  MakeImages(tmp, {"depth/3.0.png", "depth/1.0.png", "depth/2.0.png", "rgb/3.0.png", "rgb/1.0.png", "rgb/2.0.png"});
  // associate.py rgb.txt depth.txt order, one line depth-first, CRLF, comments, a blank line;
  // the order of the file is kept (not sorted by time or name).
  tmp.Write("associations.txt",
            "# associated by hand\r\n"
            "3.01 rgb/3.0.png 3.0 depth/3.0.png\r\n"
            "\n"
            "1.0 depth/1.0.png 1.02 rgb/1.0.png  # depth first\n"
            "2.0 rgb/2.0.png 2.0 depth/2.0.png\n");
  tmp.Write("depth.txt", "1.0 depth/1.0.png\n");  // the associations file wins
  EXPECT_EQ(FindTumList(tmp.path()), tmp.File("associations.txt"));
  TumSequence seq;
  Status s = ReadTumSequence(tmp.path(), &seq);
  ASSERT_TRUE(s.ok()) << s.message();
  EXPECT_EQ(seq.list, tmp.File("associations.txt"));
  ASSERT_EQ(seq.frames.size(), 3u);
  EXPECT_EQ(seq.frames[0].depth, tmp.File("depth/3.0.png"));
  EXPECT_EQ(seq.frames[0].time, 3.0);
  EXPECT_EQ(seq.frames[0].rgb, tmp.File("rgb/3.0.png"));
  EXPECT_EQ(seq.frames[0].rgb_time, 3.01);
  EXPECT_EQ(seq.frames[0].line, 2);
  EXPECT_EQ(seq.frames[1].depth, tmp.File("depth/1.0.png"));
  EXPECT_EQ(seq.frames[1].rgb_time, 1.02);
  EXPECT_EQ(seq.frames[1].line, 4);
  EXPECT_EQ(seq.frames[2].depth, tmp.File("depth/2.0.png"));

  // What femreg register reads: the list's order and TUM's depth scale.
  FrameFiles frames;
  s = ListFrameFiles(tmp.path(), &frames);
  ASSERT_TRUE(s.ok()) << s.message();
  EXPECT_EQ(frames.tum_list, tmp.File("associations.txt"));
  EXPECT_EQ(frames.depth_scale, 1.0 / 5000.0);
  EXPECT_EQ(frames.files, (std::vector<std::string>{tmp.File("depth/3.0.png"), tmp.File("depth/1.0.png"),
                                                    tmp.File("depth/2.0.png")}));
  EXPECT_EQ(frames.times, (std::vector<double>{3.0, 1.0, 2.0}));
  // The list itself, given as the frames.
  s = ListFrameFiles(tmp.File("depth.txt"), &frames);
  ASSERT_TRUE(s.ok()) << s.message();
  EXPECT_EQ(frames.files, std::vector<std::string>{tmp.File("depth/1.0.png")});
}

TEST(TumSequence, ReadsDepthTxtAsTumWritesIt) {
  TempDir tmp;
  MakeImages(tmp, {"depth/1305031102.160407.png", "depth/1305031102.194330.png"});
  tmp.Write("depth.txt",
            "# depth maps\n# file: 'rgbd_dataset_freiburg1_xyz.bag'\n# timestamp filename\n"
            "1305031102.160407 depth/1305031102.160407.png\n"
            "1305031102.194330 depth/1305031102.194330.png\n");
  TumSequence seq;
  Status s = ReadTumSequence(tmp.File("depth.txt"), &seq);
  ASSERT_TRUE(s.ok()) << s.message();
  ASSERT_EQ(seq.frames.size(), 2u);
  EXPECT_DOUBLE_EQ(seq.frames[1].time, 1305031102.194330);
  EXPECT_EQ(seq.frames[1].rgb, "");
  EXPECT_EQ(seq.frames[1].line, 5);
}

TEST(TumSequence, BadLinesAndMissingImagesNameTheListAndTheLine) {
  TempDir tmp;
  MakeImages(tmp, {"depth/1.png", "depth/2.png"});
  auto refuse = [&](const std::string& text) {
    tmp.Write("associations.txt", text);
    TumSequence seq;
    return ErrorOf(ReadTumSequence(tmp.path(), &seq));
  };
  const std::string list = tmp.File("associations.txt");
  EXPECT_HAS(refuse("1 depth/1.png\n2 depth/2.png extra\n"),
             list + ":2: expected \"timestamp depth_path\" or \"timestamp rgb_path timestamp depth_path\" (got 3 fields)");
  EXPECT_HAS(refuse("# header\n1 depth/1.png\n1.5s depth/2.png\n"), list + ":3: '1.5s' is not a timestamp");
  EXPECT_HAS(refuse("1 depth/1.png\nnan depth/2.png\n"), list + ":2: 'nan' is not a timestamp");
  EXPECT_HAS(refuse("1 depth/1.png\n\n2 rgb/2.png 2 depth/3.png\n"), list + ":3: " + tmp.File("depth/3.png") + ": no such file");
  EXPECT_HAS(refuse("1 depth/1.png\n2 depth/2.jpg\n"), list + ":2: " + tmp.File("depth/2.jpg") + ": not a depth image");
  // Only comments: not a list at all.
  EXPECT_HAS(refuse("# nothing\n"), tmp.path() + ": not a TUM RGB-D sequence");
  TumSequence seq;
  const std::string empty = tmp.Write("empty.txt", "# nothing yet\n\n");
  EXPECT_HAS(ErrorOf(ReadTumSequence(empty, &seq)), empty + ": no frames");
}

// A folder of text clouds is not a TUM sequence, even with a depth.txt (of numbers); a
// folder of .npy frames is listed in natural order.
TEST(TumSequence, OtherFoldersAreListedByName) {
  TempDir tmp;
  tmp.Write("depth.txt", "0.1 0.2 0.3\n0.2 0.2 0.3\n");
  tmp.Write("cloud_2.xyz", "0 0 0\n");
  tmp.Write("cloud_10.xyz", "0 0 0\n");
  EXPECT_FALSE(LooksLikeTumList(tmp.File("depth.txt")));
  EXPECT_EQ(FindTumList(tmp.path()), "");
  FrameFiles frames;
  Status s = ListFrameFiles(tmp.path(), &frames);
  ASSERT_TRUE(s.ok()) << s.message();
  EXPECT_EQ(frames.tum_list, "");
  EXPECT_EQ(frames.depth_scale, 0.0);
  EXPECT_EQ(frames.files, (std::vector<std::string>{tmp.File("cloud_2.xyz"), tmp.File("cloud_10.xyz"),
                                                    tmp.File("depth.txt")}));
  TempDir npy;
  npy.Write("f_10.npy", "");
  npy.Write("f_9.npy", "");
  npy.Write("notes.md", "");
  s = ListFrameFiles(npy.path(), &frames);
  ASSERT_TRUE(s.ok()) << s.message();
  EXPECT_EQ(frames.files, (std::vector<std::string>{npy.File("f_9.npy"), npy.File("f_10.npy")}));
  EXPECT_HAS(ErrorOf(ListFrameFiles(npy.File("*.pcd"), &frames)), "no file matches it as a pattern");
}

// Files written by the tools themselves (tests/fixtures/camera/, made with numpy.save,
// open3d.io.write_pinhole_camera_intrinsic and open3d.io.write_image): a TUM-like sequence
// whose depth is 5000 units per metre of [[0.5, 0, 1.25, 2], ...] m plus the frame number.
TEST(CameraFixtures, ReadsWhatNumpyAndOpen3dWrite) {
  const std::string dir = std::string(FEMREG_FIXTURES_DIR) + "/camera";
  RawDepthImage image;
  Status s = ReadDepthNpy(dir + "/depth_3x4_f4.npy", &image);
  ASSERT_TRUE(s.ok()) << s.message();
  ASSERT_EQ(image.metres.size(), 12u);
  EXPECT_EQ(image.metres[2], 1.25f);
  EXPECT_TRUE(std::isnan(image.metres[6]));
  s = ReadDepthNpy(dir + "/depth_3x4_u2_fortran.npy", &image);
  ASSERT_TRUE(s.ok()) << s.message();
  const std::vector<uint16_t> units = {500, 0, 1250, 2000, 750, 1000, 0, 250, 3000, 500, 500, 125};
  EXPECT_EQ(image.values, units);
  PinholeIntrinsics k;
  s = ReadOpen3dIntrinsics(dir + "/open3d_intrinsics.json", &k);
  ASSERT_TRUE(s.ok()) << s.message();
  EXPECT_EQ(k.width, 640);
  EXPECT_EQ(k.cx, 319.5);
  FrameFiles frames;
  s = ListFrameFiles(dir + "/tum", &frames);
  ASSERT_TRUE(s.ok()) << s.message();
  EXPECT_EQ(frames.tum_list, dir + "/tum/associations.txt");
  ASSERT_EQ(frames.files.size(), 3u);
  for (int f = 0; f < 3; ++f) {
    s = ReadDepthPng(frames.files[static_cast<size_t>(f)], &image);
    ASSERT_TRUE(s.ok()) << s.message();
    for (size_t i = 0; i < units.size(); ++i) EXPECT_EQ(image.values[i], units[i] * 5 + f);
  }
  EXPECT_NEAR(image.values[2] * frames.depth_scale, 1.25 + 2 * frames.depth_scale, 1e-12);  // metres
}

}  // namespace
}  // namespace femreg
