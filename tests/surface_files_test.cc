// Surface files in (ReadSurface): PLY in ASCII and either binary byte order, and bad files
// refused naming the file and the place.

#include "meshing_surfaces.h"

namespace femreg {
namespace {

using namespace meshing_testing;  // NOLINT: the shared surfaces and checks

TEST(MeshingTest, PlyAsciiAndBinaryReadTheSameSurface) {
  TempDir dir;
  const Surface sphere = Icosphere(1.0, 2);
  Surface ascii, binary;
  WritePly(dir.path() + "/a.ply", sphere, false);
  WritePly(dir.path() + "/b.ply", sphere, true);
  Status s = ReadSurface(dir.path() + "/a.ply", &ascii.V, &ascii.F);
  ASSERT_TRUE(s.ok()) << s.message();
  s = ReadSurface(dir.path() + "/b.ply", &binary.V, &binary.F);
  ASSERT_TRUE(s.ok()) << s.message();
  // %.17g and raw doubles both carry every bit: the same numbers come back.
  EXPECT_EQ(ascii.V, sphere.V);
  EXPECT_EQ(binary.V, sphere.V);
  EXPECT_EQ(ascii.F, sphere.F);
  EXPECT_EQ(binary.F, sphere.F);

  // Big-endian binary: the same tetrahedron as in little-endian, bytes reversed.
  {
    std::ofstream out(dir.path() + "/big.ply", std::ios::binary);
    out << "ply\nformat binary_big_endian 1.0\nelement vertex 4\nproperty float x\n"
           "property float y\nproperty float z\nelement face 4\n"
           "property list uchar int vertex_indices\nend_header\n";
    auto put = [&out](auto value) {
      char bytes[sizeof(value)];
      std::memcpy(bytes, &value, sizeof(value));
      std::reverse(bytes, bytes + sizeof(value));
      out.write(bytes, sizeof(value));
    };
    const float corners[4][3] = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
    for (const auto& c : corners) {
      for (float x : c) put(x);
    }
    const int faces[4][3] = {{0, 2, 1}, {0, 1, 3}, {0, 3, 2}, {1, 2, 3}};
    for (const auto& f : faces) {
      out.put(3);
      for (int i : f) put(static_cast<int32_t>(i));
    }
  }
  Surface big;
  s = ReadSurface(dir.path() + "/big.ply", &big.V, &big.F);
  ASSERT_TRUE(s.ok()) << s.message();
  ASSERT_EQ(big.V.rows(), 4);
  EXPECT_EQ(big.V.row(3), Eigen::RowVector3d(0, 0, 1));
  EXPECT_EQ(big.F.row(3), Eigen::RowVector3i(1, 2, 3));
  EXPECT_NEAR(EnclosedVolume(big), 1.0 / 6.0, 1e-15);

  // Quads and polygons are fanned into triangles.
  const std::string quads =
      "ply\nformat ascii 1.0\nelement vertex 4\nproperty float x\nproperty float y\n"
      "property float z\nelement face 1\nproperty list uchar uint vertex_index\nend_header\n"
      "0 0 0\n1 0 0\n1 1 0\n0 1 0\n4 0 1 2 3\n";
  std::ofstream(dir.path() + "/quad.ply") << quads;
  Surface q;
  ASSERT_TRUE(ReadSurface(dir.path() + "/quad.ply", &q.V, &q.F).ok());
  ASSERT_EQ(q.F.rows(), 2);
  EXPECT_EQ(q.F.row(1), Eigen::RowVector3i(0, 2, 3));

  TetMesh mesh;
  ASSERT_TRUE(TetrahedralizeSurface(binary.V, binary.F, MeshingOptions(), &mesh, nullptr).ok());
  ExpectValidMesh(mesh);
}

TEST(MeshingTest, BadPlyFilesAreRefusedWithFileAndPlace) {
  TempDir dir;
  const std::string header =
      "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n"
      "property float z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n";
  struct Case {
    std::string name, contents, expect;
  };
  const Case cases[] = {
      {"index.ply", header + "0 0 0\n1 0 0\n0 1 0\n3 0 1 7\n",
       "bad.ply:13: face 0's vertex_indices refers to vertex 7"},
      {"short.ply", header + "0 0 0\n1 0 0\n0 1 0\n3 0 1\n",
       "the file ends before face 0's vertex_indices"},
      {"counts.ply", header + "0 0 0\n", ":3: the header announces 3 vertex records, more than"},
      {"word.ply", header + "0 0 0\n1 zero 0\n0 1 0\n3 0 1 2\n", ":11: expected a number"},
      {"nan.ply", header + "0 0 0\nnan 0 0\n0 1 0\n3 0 1 2\n", "is not finite"},
      {"format.ply", "ply\nformat binary_middle_endian 1.0\nend_header\n", ":2: unknown format"},
      {"noend.ply", "ply\nformat ascii 1.0\nelement vertex 3\n", "no end_header"},
      {"cloud.ply",
       "ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nproperty float y\n"
       "property float z\nend_header\n0 0 0\n",
       "a point cloud, not a surface"},
      {"huge.ply",
       "ply\nformat binary_little_endian 1.0\nelement vertex 2000000000\nproperty "
       "float x\nproperty float y\nproperty float z\nelement face 1\nproperty list "
       "uchar int vertex_indices\nend_header\n\x01\x02",
       ":3: the header announces 2000000000 vertex"},
      {"two.ply", header + "0 0 0\n1 0 0\n0 1 0\n2 0 1\n", "at least 3 corners"},
      {"notply.ply", "solid x\n", "not a PLY file"},
  };
  for (const Case& c : cases) {
    const std::string path = dir.path() + "/" + c.name;
    std::ofstream(path, std::ios::binary) << c.contents;
    Vertices V;
    Triangles F;
    const Status s = ReadSurface(path, &V, &F);
    ASSERT_FALSE(s.ok()) << c.name;
    EXPECT_NE(s.message().find(path), std::string::npos) << s.message();
    std::string expect = c.expect;
    if (expect.rfind("bad.ply", 0) == 0) expect = path + expect.substr(7);
    EXPECT_NE(s.message().find(expect), std::string::npos) << c.name << ": " << s.message();
  }
  // A truncated binary file names the byte where it ran out.
  Surface cube = Cube();
  WritePly(dir.path() + "/whole.ply", cube, true);
  const std::string bytes = ReadAll(dir.path() + "/whole.ply");
  std::ofstream(dir.path() + "/cut.ply", std::ios::binary) << bytes.substr(0, bytes.size() - 5);
  Vertices V;
  Triangles F;
  const Status s = ReadSurface(dir.path() + "/cut.ply", &V, &F);
  ASSERT_FALSE(s.ok());
  EXPECT_NE(s.message().find(": byte "), std::string::npos) << s.message();
  // Unknown extensions are refused.
  EXPECT_FALSE(ReadSurface(dir.path() + "/whole.off", &V, &F).ok());
}

}  // namespace
}  // namespace femreg
