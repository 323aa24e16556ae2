// Point clouds: PCD (ASCII, binary, binary-compressed), PLY and text; NaN handling and the
// preprocessing filters.
#include <gtest/gtest.h>
#include <pcl/io/pcd_io.h>
#include <pcl/point_types.h>

#include <cmath>
#include <cstdio>
#include <fstream>
#include <filesystem>
#include <limits>
#include <random>
#include <string>

#include "femreg/point_cloud.h"
#include "femreg_test_config.h"

namespace femreg {
namespace {

std::string Fixture(const std::string& name) {
  return std::string(FEMREG_FIXTURES_DIR) + "/clouds/" + name;
}

std::string TempPath(const std::string& name) {
  return (std::filesystem::temp_directory_path() /
          ("femreg_pc_" + std::to_string(::getpid()) + "_" + name)).string();
}

TEST(ReadPointCloud, AsciiPcdDropsAndCountsNaN) {
  PointCloud cloud;
  int dropped = -1;
  ASSERT_TRUE(ReadPointCloud(Fixture("ascii.pcd"), &cloud, &dropped).ok());
  EXPECT_EQ(cloud.size(), 3);
  EXPECT_EQ(dropped, 1);
  EXPECT_FALSE(cloud.has_normals());
  EXPECT_DOUBLE_EQ(cloud.points(2, 2), 0.5);
}

TEST(ReadPointCloud, KeepsNormals) {
  PointCloud cloud;
  ASSERT_TRUE(ReadPointCloud(Fixture("normals.pcd"), &cloud).ok());
  ASSERT_TRUE(cloud.has_normals());
  EXPECT_DOUBLE_EQ(cloud.normals(0, 2), 1.0);
  EXPECT_DOUBLE_EQ(cloud.points(1, 2), 3.0);
}

TEST(ReadPointCloud, BinaryAndCompressedPcdWrittenByPcl) {
  pcl::PointCloud<pcl::PointXYZ> in;
  std::mt19937 rng(1);
  std::uniform_real_distribution<float> u(-1, 1);
  for (int i = 0; i < 100; ++i) in.push_back(pcl::PointXYZ(u(rng), u(rng), u(rng)));
  in[7].x = std::numeric_limits<float>::quiet_NaN();
  in.width = static_cast<uint32_t>(in.size());
  in.height = 1;
  in.is_dense = false;
  for (bool compressed : {false, true}) {
    const std::string path = TempPath(compressed ? "c.pcd" : "b.pcd");
    if (compressed) {
      ASSERT_EQ(pcl::io::savePCDFileBinaryCompressed(path, in), 0);
    } else {
      ASSERT_EQ(pcl::io::savePCDFileBinary(path, in), 0);
    }
    PointCloud cloud;
    int dropped = 0;
    ASSERT_TRUE(ReadPointCloud(path, &cloud, &dropped).ok());
    EXPECT_EQ(cloud.size(), 99);
    EXPECT_EQ(dropped, 1);
    EXPECT_FLOAT_EQ(static_cast<float>(cloud.points(0, 0)), in[0].x);
    std::remove(path.c_str());
  }
}

TEST(ReadPointCloud, PlyAndText) {
  PointCloud ply, xyz;
  ASSERT_TRUE(ReadPointCloud(Fixture("cloud.ply"), &ply).ok());
  EXPECT_EQ(ply.size(), 3);
  ASSERT_TRUE(ReadPointCloud(Fixture("cloud.xyz"), &xyz).ok());
  EXPECT_EQ(xyz.size(), 3);
  EXPECT_DOUBLE_EQ(xyz.points(2, 1), 5.0);
}

TEST(ReadPointCloud, TextCloudsTakeSeparatorsNormalsAndComments) {
  const std::string dir = testing::TempDir();
  auto write = [&](const std::string& name, const std::string& text) {
    std::ofstream(dir + "/" + name) << text;
    return dir + "/" + name;
  };
  PointCloud cloud;
  ASSERT_TRUE(ReadPointCloud(write("n.xyz", "# x y z nx ny nz\n\n1,2,3,0,0,1\n4;5;6;0;1;0\r\n"), &cloud).ok());
  ASSERT_EQ(cloud.size(), 2);
  ASSERT_TRUE(cloud.has_normals());
  EXPECT_DOUBLE_EQ(cloud.points(1, 2), 6.0);
  EXPECT_DOUBLE_EQ(cloud.normals(1, 1), 1.0);
  EXPECT_FALSE(cloud.has_labels());
  ASSERT_TRUE(ReadPointCloud(write("p.txt", "1 2 3\n"), &cloud).ok());
  EXPECT_FALSE(cloud.has_normals());
  const std::string mixed = write("mixed.xyz", "1 2 3\n1 2 3 0 0 1\n");
  EXPECT_EQ(ReadPointCloud(mixed, &cloud).message(), mixed + ":2: 6 values where earlier lines had 3");
  const std::string four = write("four.xyz", "1 2 3 4\n");
  EXPECT_EQ(ReadPointCloud(four, &cloud).message(),
            four + ":1: expected 'x y z' or 'x y z nx ny nz', got 4 values");
  const std::string word = write("word.xyz", "1 2 abc\n");
  EXPECT_EQ(ReadPointCloud(word, &cloud).message(), word + ":1: not a number: 'abc'");
  EXPECT_EQ(cloud.size(), 1);  // left as it was
}

TEST(ReadPointCloud, ErrorsNameTheFileAndLine) {
  PointCloud cloud;
  Status s = ReadPointCloud(Fixture("bad.xyz"), &cloud);
  ASSERT_FALSE(s.ok());
  EXPECT_NE(s.message().find("bad.xyz:2"), std::string::npos) << s.message();
  s = ReadPointCloud(Fixture("truncated.pcd"), &cloud);
  ASSERT_FALSE(s.ok());
  EXPECT_NE(s.message().find("truncated.pcd"), std::string::npos) << s.message();
  s = ReadPointCloud(Fixture("missing.pcd"), &cloud);
  ASSERT_FALSE(s.ok());
  EXPECT_NE(s.message().find("missing.pcd"), std::string::npos);
}

// Written by PCL (savePCDFileBinaryCompressed of PointXYZLNormal with a sensor pose): five
// points, labels 7..11, normals +z, VIEWPOINT 0.5 -1 2 / (w 0, x 1, y 0, z 0).
TEST(ReadPointCloud, CompressedPcdKeepsLabelsNormalsAndTheViewpoint) {
  PointCloud cloud;
  SensorPose sensor;
  const Status status = ReadPointCloud(Fixture("labels_normals_compressed.pcd"), &cloud, nullptr, &sensor);
  ASSERT_TRUE(status.ok()) << status.message();
  ASSERT_EQ(cloud.size(), 5);
  ASSERT_TRUE(cloud.has_normals());
  ASSERT_TRUE(cloud.has_labels());
  for (int i = 0; i < 5; ++i) {
    // Stored as float: 0.1f * i is within 1e-7 of 0.1 * i.
    EXPECT_NEAR(cloud.points(i, 0), 0.1 * i, 1e-6);
    EXPECT_EQ(cloud.points(i, 2), 1.0 + i);
    EXPECT_EQ(cloud.normals(i, 2), 1.0);
    EXPECT_EQ(cloud.labels(i), 7 + i);
  }
  ASSERT_TRUE(sensor.known);
  EXPECT_EQ(sensor.origin, Eigen::Vector3d(0.5, -1.0, 2.0));
  EXPECT_EQ(sensor.orientation.coeffs(), Eigen::Vector4d(1, 0, 0, 0));  // x y z w
  // PLY and text clouds have no viewpoint.
  ASSERT_TRUE(ReadPointCloud(Fixture("cloud.xyz"), &cloud, nullptr, &sensor).ok());
  EXPECT_FALSE(sensor.known);
}

// Written by PCL's PLYWriter (binary, PointNormal): normals named normal_x ... are kept.
TEST(ReadPointCloud, BinaryPlyWithNormals) {
  PointCloud cloud;
  const Status status = ReadPointCloud(Fixture("binary_normals.ply"), &cloud);
  ASSERT_TRUE(status.ok()) << status.message();
  ASSERT_EQ(cloud.size(), 4);
  ASSERT_TRUE(cloud.has_normals());
  EXPECT_EQ(cloud.points(3, 2), 9.0);
  EXPECT_EQ(cloud.normals(2, 0), 1.0);
}

// PCD headers that PCL's reader crashed on, or read as nothing, are refused naming the line
// (or the byte offset in binary data), and the cloud is left as it was.
TEST(ReadPointCloud, InconsistentPcdHeadersAreRefused) {
  const std::string head = "# .PCD v0.7\nVERSION 0.7\n";
  const std::string xyz = "FIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nCOUNT 1 1 1\n";
  const struct {
    std::string text;
    std::string expected;
  } cases[] = {
      {head + "FIELDS label x y z\nSIZE 4 4 4\nTYPE F F F\nCOUNT 1 1 1\nWIDTH 1\nHEIGHT 1\nPOINTS 1\nDATA ascii\n1 2 3\n",
       ":4: SIZE has 3 entries, FIELDS (line 3) has 4"},
      {head + "SIZE 4 4 4\nTYPE F F F\nWIDTH 1\nPOINTS 1\nDATA ascii\n1 2 3\n", ":7: no FIELDS line before DATA"},
      {head + xyz + "WIDTH 3\nHEIGHT 2\nPOINTS 5\nDATA ascii\n", ":10: POINTS 5 is not WIDTH x HEIGHT = 3 x 2"},
      {head + "FIELDS x y w\nSIZE 4 4 4\nTYPE F F F\nWIDTH 1\nDATA ascii\n1 2 3\n", ":3: no field z"},
      {head + "FIELDS x y z\nSIZE 4 4 4\nTYPE F F I\nWIDTH 1\nDATA ascii\n1 2 3\n", ":3: field z must be one float"},
      {head + xyz + "WIDTH 2\nDATA ascii\n1 2 3\n4 5\n" + std::string(20, ' '), ":10: point 1: 2 values, the fields need 3"},
      {head + xyz + "WIDTH 3\nDATA ascii\n1 2 3\n", ":8: 3 points of 3 values cannot fit in the 6 bytes after the header"},
      {head + xyz + "WIDTH 3\nDATA ascii\n1 2 3\n" + std::string(20, '\n'), ":9: the file ends after 1 of 3 points"},
      {head + xyz + "WIDTH 1000\nDATA binary\n" + std::string(24, '\0'),
       ": byte 94: binary data of 1000 points of 12 bytes needs 12000 bytes, the file has 24"},
      {head + xyz + "WIDTH 1\nDATA binary_compressed\n" + std::string("\xff\xff\xff\x0f\x0c\0\0\0", 8),
       ": byte 102: compressed size 268435455 is more than the 0 bytes after the header"},
      {head + xyz + "WIDTH 1\nVIEWPOINT 0 0 0 0 0 0 0\nDATA ascii\n1 2 3\n", ":8: VIEWPOINT orientation is a zero quaternion"},
  };
  for (const auto& c : cases) {
    const std::string path = TempPath("bad.pcd");
    std::ofstream(path, std::ios::binary) << c.text;
    PointCloud cloud;
    cloud.points = Vertices::Ones(2, 3);
    const Status s = ReadPointCloud(path, &cloud);
    std::remove(path.c_str());
    ASSERT_FALSE(s.ok()) << c.expected;
    EXPECT_EQ(s.message().rfind(path + c.expected, 0), 0u) << s.message() << "\nexpected " << c.expected;
    EXPECT_EQ(cloud.size(), 2);  // untouched
  }
}

TEST(WritePointCloud, RoundTripsWithAndWithoutNormals) {
  PointCloud cloud;
  cloud.points = Vertices::Random(50, 3);
  for (bool normals : {false, true}) {
    cloud.normals = normals ? Vertices(Vertices::Random(50, 3)) : Vertices(0, 3);
    const std::string path = TempPath("rt.pcd");
    ASSERT_TRUE(WritePointCloud(path, cloud).ok());
    PointCloud back;
    ASSERT_TRUE(ReadPointCloud(path, &back).ok());
    ASSERT_EQ(back.size(), 50);
    EXPECT_EQ(back.has_normals(), normals);
    EXPECT_LT((back.points - cloud.points).cwiseAbs().maxCoeff(), 1e-6);
    std::remove(path.c_str());
  }
  EXPECT_FALSE(WritePointCloud("/nonexistent/dir/x.pcd", cloud).ok());
  // Only PCD is written: a .ply name would hold a PCD.
  const std::string ply = TempPath("rt.ply");
  const Status refused = WritePointCloud(ply, cloud);
  EXPECT_FALSE(refused.ok());
  EXPECT_NE(refused.message().find("name the file .pcd"), std::string::npos) << refused.message();
  std::ifstream written(ply);
  EXPECT_FALSE(written.good());
}

TEST(ReadPointCloud, AnEmptyPcdOrPlyFileIsAnErrorAnEmptyTextCloudIsNot) {
  for (const char* name : {"empty.pcd", "empty.PLY"}) {
    const std::string path = TempPath(name);
    std::ofstream(path).close();
    PointCloud cloud;
    const Status s = ReadPointCloud(path, &cloud);
    std::remove(path.c_str());
    ASSERT_FALSE(s.ok()) << name;
    EXPECT_NE(s.message().find("the file is empty (0 bytes)"), std::string::npos) << s.message();
  }
  const std::string text = TempPath("empty.xyz");
  std::ofstream(text).close();
  PointCloud cloud;
  EXPECT_TRUE(ReadPointCloud(text, &cloud).ok());
  std::remove(text.c_str());
  EXPECT_EQ(cloud.size(), 0);
}

PointCloud NoisyPlane(int n, double z, uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> u(0, 1);
  PointCloud c;
  c.points.resize(n, 3);
  for (int i = 0; i < n; ++i) c.points.row(i) << u(rng), u(rng), z;
  return c;
}

TEST(PreprocessPointCloud, CropVoxelOutliersNormals) {
  PointCloud c = NoisyPlane(2000, 0.5, 1);
  c.points.row(0) << std::numeric_limits<double>::quiet_NaN(), 0, 0;
  c.points.row(1) << 0.5, 0.5, 3.0;  // a far outlier
  PreprocessOptions o;
  int dropped = 0;
  PointCloud a = c;
  PreprocessPointCloud(o, &a, &dropped);  // nothing asked: only NaN removal
  EXPECT_EQ(dropped, 1);
  EXPECT_EQ(a.size(), 1999);

  PointCloud cropped = c;
  o.crop = true;
  o.crop_min = Eigen::Vector3d(0, 0, 0);
  o.crop_max = Eigen::Vector3d(0.5, 1, 1);
  PreprocessPointCloud(o, &cropped);
  EXPECT_GT(cropped.size(), 800);
  EXPECT_LT(cropped.size(), 1200);
  EXPECT_LE(cropped.points.col(0).maxCoeff(), 0.5 + 1e-6);

  o = PreprocessOptions();
  o.voxel_size = 0.1;
  PointCloud voxel = c;
  PreprocessPointCloud(o, &voxel);
  EXPECT_LE(voxel.size(), 121);
  EXPECT_GE(voxel.size(), 90);

  o = PreprocessOptions();
  o.outlier_neighbors = 10;
  o.outlier_stddev = 1.0;
  PointCloud sor = c;
  PreprocessPointCloud(o, &sor);
  EXPECT_LT(sor.points.col(2).maxCoeff(), 1.0) << "the far outlier must go";

  o = PreprocessOptions();
  o.normal_neighbors = 10;
  PointCloud with_normals = NoisyPlane(500, 0.5, 2);
  PreprocessPointCloud(o, &with_normals, nullptr, Eigen::Vector3d(0.5, 0.5, 2.0));
  ASSERT_TRUE(with_normals.has_normals());
  // Oriented towards the viewpoint above the plane.
  EXPECT_GT(with_normals.normals.col(2).minCoeff(), 0.99);
}

}  // namespace
}  // namespace femreg
