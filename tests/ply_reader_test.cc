// The one PLY reader (io/ply_reader.h) serves point clouds (ReadPointCloud) and surfaces
// (ReadSurface). These cases pin what sharing it changed: the cloud reader and the surface
// reader now accept and refuse the same headers and values.
#include <gtest/gtest.h>

#include <cstdint>
#include <string>
#include <vector>

#include "femreg/meshing.h"
#include "femreg/point_cloud.h"
#include "io/ply_reader.h"
#include "test_util.h"

namespace femreg {
namespace {

using testing_util::TempDir;

const char kTriangleBody[] = "0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n";

std::string SurfaceHeader(const std::string& format_line, const std::string& extra = "") {
  return "ply\n" + format_line + "\nelement vertex 3\nproperty float x\nproperty float y\n"
         "property float z\n" + extra + "element face 1\nproperty list uchar int vertex_indices\n"
         "end_header\n";
}

// Accepted by both readers now: a format line without its version (the cloud reader
// wanted three words), and an ASCII body whose last value has no newline after it.
TEST(PlyReader, FormatWithoutVersionAndNoFinalNewline) {
  TempDir dir;
  const std::string body(kTriangleBody, sizeof(kTriangleBody) - 2);  // no final newline
  const std::string path = dir.Write("s.ply", SurfaceHeader("format ascii") + body);
  Vertices V;
  Triangles F;
  const Status s = ReadSurface(path, &V, &F);
  ASSERT_TRUE(s.ok()) << s.message();
  EXPECT_EQ(V.rows(), 3);
  EXPECT_EQ(F.rows(), 1);
  PointCloud cloud;
  Status c = ReadPointCloud(path, &cloud);
  ASSERT_TRUE(c.ok()) << c.message();
  EXPECT_EQ(cloud.size(), 3);
  const std::string tight = dir.Write(
      "c.ply", "ply\nformat ascii\nelement vertex 1\nproperty float x\nproperty float y\n"
               "property float z\nend_header\n1 2 3");
  c = ReadPointCloud(tight, &cloud);
  ASSERT_TRUE(c.ok()) << c.message();
  ASSERT_EQ(cloud.size(), 1);
  EXPECT_EQ(cloud.points(0, 2), 3.0);
}

// Refused by both readers now, with the same message naming the file and the line: an
// ASCII value that is not an integer in an integer property (the cloud reader took any
// number), an element given twice (the surface reader used the first), and a property line
// with extra words (the surface reader ignored them).
TEST(PlyReader, BothReadersRefuseTheSameFiles) {
  TempDir dir;
  struct Case {
    std::string name, contents, expect;
  };
  const Case cases[] = {
      {"int.ply",
       SurfaceHeader("format ascii 1.0", "property uchar red\n") + "0 0 0 1\n1 0 0 2.5\n0 1 0 3\n3 0 1 2\n",
       ":12: expected an integer for vertex 1's red, got '2.5'"},
      {"twice.ply",
       "ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nproperty float y\n"
       "property float z\nelement vertex 1\nproperty float x\nend_header\n0 0 0\n1\n",
       ":7: element 'vertex' given twice"},
      {"words.ply", SurfaceHeader("format ascii 1.0", "property float w extra\n") + kTriangleBody,
       ":7: expected 'property TYPE NAME'"},
  };
  for (const Case& c : cases) {
    const std::string path = dir.Write(c.name, c.contents);
    Vertices V;
    Triangles F;
    const Status s = ReadSurface(path, &V, &F);
    ASSERT_FALSE(s.ok()) << c.name;
    EXPECT_NE(s.message().find(path + c.expect), std::string::npos) << c.name << ": " << s.message();
    PointCloud cloud;
    const Status r = ReadPointCloud(path, &cloud);
    ASSERT_FALSE(r.ok()) << c.name;
    EXPECT_EQ(r.message(), s.message()) << c.name;
  }
}

// The reader itself: elements, properties and rows as the file has them, in either byte
// order, with a list's items.
TEST(PlyReader, ReadsElementsAndListsInBothByteOrders) {
  TempDir dir;
  for (const bool big : {false, true}) {
    std::string bytes = std::string("ply\nformat ") + (big ? "binary_big_endian" : "binary_little_endian") +
                        " 1.0\nelement vertex 1\nproperty short x\nproperty double y\n"
                        "element face 1\nproperty list uchar uint vertex_indices\nend_header\n";
    auto put = [&](const void* p, int n) {
      const char* c = static_cast<const char*>(p);
      for (int i = 0; i < n; ++i) bytes += c[big ? n - 1 - i : i];  // the test machine is little-endian
    };
    const int16_t x = -7;
    const double y = 2.5;
    const unsigned char n = 2;
    const uint32_t items[2] = {4, 70000};
    put(&x, 2);
    put(&y, 8);
    put(&n, 1);
    put(&items[0], 4);
    put(&items[1], 4);
    const std::string path = dir.Write(big ? "big.ply" : "little.ply", bytes);
    internal::PlyFile ply;
    ASSERT_TRUE(ply.Open(path).ok());
    ASSERT_EQ(ply.elements().size(), 2u);
    EXPECT_EQ(ply.FindElement("face"), 1);
    EXPECT_EQ(ply.FindProperty(0, "y", false), 1);
    EXPECT_EQ(ply.FindProperty(1, "vertex_indices", true), 0);
    EXPECT_EQ(ply.FindProperty(1, "vertex_indices", false), -1);
    int rows = 0;
    const Status s = ply.ReadBody([&](int element, long long index, const internal::PlyRow& row) {
      ++rows;
      EXPECT_EQ(index, 0);
      if (element == 0) {
        EXPECT_EQ(row.values[0], -7.0);
        EXPECT_EQ(row.values[1], 2.5);
      } else {
        EXPECT_EQ(row.values[0], 2.0);
        EXPECT_EQ(row.lists[0], (std::vector<double>{4.0, 70000.0}));
      }
      return Status::Ok();
    });
    ASSERT_TRUE(s.ok()) << s.message();
    EXPECT_EQ(rows, 2);
  }
}

}  // namespace
}  // namespace femreg
