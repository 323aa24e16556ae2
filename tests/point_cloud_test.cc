// Point clouds: PCD (ASCII, binary, binary-compressed), PLY and text; NaN handling and the
// preprocessing filters.
#include <gtest/gtest.h>
#include <pcl/io/pcd_io.h>
#include <pcl/point_types.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <limits>
#include <random>

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
