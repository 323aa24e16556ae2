// Tests of the mesh readers, writers, generators and ComputeQuality (femreg/io.h).
#include <gtest/gtest.h>

#include <Eigen/Geometry>

#include <cctype>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <iterator>
#include <map>
#include <sstream>
#include <string>
#include <sys/stat.h>

#include "femreg/io.h"
#include "femreg/mesh.h"
#include "io/ply_reader.h"
#include "femreg_test_config.h"
#include "test_util.h"

namespace femreg {
namespace {

const std::string kFixtures = std::string(FEMREG_FIXTURES_DIR) + "/io/";

using testing_util::TempDir;

bool Exists(const std::string& path) {
  struct stat st;
  return stat(path.c_str(), &st) == 0;
}

std::map<int, int> RegionCounts(const TetMesh& mesh) {
  std::map<int, int> counts;
  for (int t = 0; t < mesh.num_tets(); ++t) ++counts[mesh.region(t)];
  return counts;
}

// Checks a finalized mesh: positive elements, every vertex used, a closed two-manifold
// outward surface (each edge in exactly two triangles, in opposite directions) whose
// divergence-theorem volume equals RestVolume.
void ExpectWellFormed(const TetMesh& mesh) {
  ASSERT_GT(mesh.num_tets(), 0);
  std::vector<int> uses(mesh.num_vertices(), 0);
  for (int t = 0; t < mesh.num_tets(); ++t) {
    for (int k = 0; k < 4; ++k) ++uses[mesh.tets(t, k)];
    EXPECT_GT(SignedTetVolume(mesh.rest.row(mesh.tets(t, 0)), mesh.rest.row(mesh.tets(t, 1)),
                              mesh.rest.row(mesh.tets(t, 2)), mesh.rest.row(mesh.tets(t, 3))),
              0.0)
        << "element " << t;
  }
  for (int v = 0; v < mesh.num_vertices(); ++v) EXPECT_GT(uses[v], 0) << "orphan vertex " << v;
  std::map<std::pair<int, int>, int> directed;
  double surface_volume = 0.0;
  for (int f = 0; f < mesh.num_surface_triangles(); ++f) {
    for (int k = 0; k < 3; ++k) ++directed[{mesh.surface(f, k), mesh.surface(f, (k + 1) % 3)}];
    const Eigen::Vector3d a = mesh.rest.row(mesh.surface(f, 0)), b = mesh.rest.row(mesh.surface(f, 1)),
                          c = mesh.rest.row(mesh.surface(f, 2));
    surface_volume += a.dot(b.cross(c)) / 6.0;
  }
  for (const auto& e : directed) {
    EXPECT_EQ(e.second, 1) << "edge " << e.first.first << "-" << e.first.second;
    const auto reverse = directed.find({e.first.second, e.first.first});
    EXPECT_TRUE(reverse != directed.end() && reverse->second == 1)
        << "edge " << e.first.first << "-" << e.first.second << " is not shared by two triangles";
  }
  EXPECT_NEAR(surface_volume, RestVolume(mesh), 1e-9 * std::max(1.0, std::abs(RestVolume(mesh))));
}

// The fixtures all hold the same two tetrahedra (volume 1/6 + 1/3) on five used vertices,
// plus cells of other kinds and an unused vertex that the reader must drop.
struct FixtureCase {
  const char* file;
  MeshFormat format;
  std::map<int, int> regions;
};

void PrintTo(const FixtureCase& c, std::ostream* os) { *os << c.file; }

class FixtureTest : public ::testing::TestWithParam<FixtureCase> {};

TEST_P(FixtureTest, ReadsTwoTetsWithRegions) {
  const FixtureCase& c = GetParam();
  const std::string path = kFixtures + c.file;
  EXPECT_EQ(DetectMeshFormat(path), c.format);
  TetMesh mesh;
  const Status status = ReadTetMesh(path, &mesh);
  ASSERT_TRUE(status.ok()) << status.message();
  EXPECT_EQ(mesh.num_vertices(), 5);
  EXPECT_EQ(mesh.num_tets(), 2);
  EXPECT_EQ(mesh.num_surface_triangles(), 6);
  EXPECT_NEAR(RestVolume(mesh), 0.5, 1e-12);
  EXPECT_EQ(RegionCounts(mesh), c.regions);
  EXPECT_TRUE(mesh.x == mesh.rest);
  ExpectWellFormed(mesh);
}

const std::map<int, int> kRegions78 = {{7, 1}, {8, 1}};
INSTANTIATE_TEST_SUITE_P(
    AllFormats, FixtureTest,
    ::testing::Values(FixtureCase{"two_tets_v1.msh", MeshFormat::kGmsh, kRegions78},
                      FixtureCase{"two_tets_v22.msh", MeshFormat::kGmsh, kRegions78},
                      // 4.1: the second volume entity has no physical tag.
                      FixtureCase{"two_tets_v41.msh", MeshFormat::kGmsh, {{0, 1}, {7, 1}}},
                      FixtureCase{"two_tets_1based.ele", MeshFormat::kTetGen, kRegions78},
                      FixtureCase{"two_tets_1based.node", MeshFormat::kTetGen, kRegions78},
                      FixtureCase{"two_tets_1based", MeshFormat::kTetGen, kRegions78},
                      FixtureCase{"two_tets_0based.node", MeshFormat::kTetGen, {{0, 2}}},
                      FixtureCase{"two_tets.mesh", MeshFormat::kMedit, kRegions78},
                      FixtureCase{"two_tets_legacy.vtk", MeshFormat::kVtkLegacy, kRegions78},
                      FixtureCase{"two_tets_ascii.vtu", MeshFormat::kVtu, kRegions78}),
    [](const ::testing::TestParamInfo<FixtureCase>& info) {
      std::string name = info.param.file;
      for (char& ch : name) {
        if (!std::isalnum(static_cast<unsigned char>(ch))) ch = '_';
      }
      return name;
    });

TEST(ReadTetMesh, SurfaceOnlyFileSaysNoTetrahedra) {
  TetMesh mesh;
  const Status status = ReadTetMesh(kFixtures + "surface_only.obj", &mesh);
  ASSERT_FALSE(status.ok());
  EXPECT_NE(status.message().find("surface_only.obj"), std::string::npos);
  EXPECT_NE(status.message().find("no tetrahedra"), std::string::npos) << status.message();
}

TEST(ReadTetMesh, MissingFileNamesIt) {
  TetMesh mesh;
  const Status status = ReadTetMesh("/nonexistent/mesh.msh", &mesh);
  ASSERT_FALSE(status.ok());
  EXPECT_NE(status.message().find("/nonexistent/mesh.msh"), std::string::npos);
}

TEST(ReadTetMesh, BrokenVtuGivesStatusNamingTheFile) {
  TetMesh mesh;
  const Status status = ReadTetMesh(kFixtures + "broken.vtu", &mesh);
  ASSERT_FALSE(status.ok());
  EXPECT_NE(status.message().find("broken.vtu"), std::string::npos) << status.message();
}

// Bad inputs: the message names the file and the line of the problem.
struct BadInput {
  const char* name;
  const char* file;
  const char* contents;
  int line;
  const char* expected;  // a phrase the message must contain
};

void PrintTo(const BadInput& b, std::ostream* os) { *os << b.name; }

class BadInputTest : public ::testing::TestWithParam<BadInput> {};

TEST_P(BadInputTest, MessageNamesFileAndLine) {
  const BadInput& b = GetParam();
  TempDir dir;
  const std::string path = dir.Write(b.file, b.contents);
  TetMesh mesh;
  const Status status = ReadTetMesh(path, &mesh);
  ASSERT_FALSE(status.ok());
  const std::string& message = status.message();
  const std::string where = b.line > 0 ? path + ":" + std::to_string(b.line) + ":" : path + ": ";
  EXPECT_EQ(message.rfind(where, 0), 0u) << message;
  EXPECT_NE(message.find(b.expected), std::string::npos) << message;
  EXPECT_EQ(mesh.num_tets(), 0);  // untouched on failure
}

constexpr char kMsh22Header[] = "$MeshFormat\n2.2 0 8\n$EndMeshFormat\n";
const std::string kNodes5 =
    "$Nodes\n5\n1 0 0 0\n2 1 0 0\n3 0 1 0\n4 0 0 1\n5 1 1 1\n$EndNodes\n";

const std::string kTruncated = std::string(kMsh22Header) + kNodes5 +
                               "$Elements\n3\n1 4 2 7 1 1 2 3 4\n2 4 2 8 1 2 3 4 5\n";
const std::string kOutOfRange =
    std::string(kMsh22Header) + kNodes5 + "$Elements\n2\n1 4 2 7 1 1 2 3 4\n2 4 2 8 1 2 3 4 9\n$EndElements\n";
const std::string kNoTets =
    std::string(kMsh22Header) + kNodes5 + "$Elements\n1\n1 2 2 7 1 1 2 3\n$EndElements\n";
const std::string kNan = std::string(kMsh22Header) +
                         "$Nodes\n4\n1 0 0 0\n2 1 0 0\n3 0 nan 0\n4 0 0 1\n$EndNodes\n"
                         "$Elements\n1\n1 4 2 7 1 1 2 3 4\n$EndElements\n";
const std::string kDegenerate =
    std::string(kMsh22Header) + "$Nodes\n5\n1 0 0 0\n2 1 0 0\n3 0 1 0\n4 0 0 1\n5 1 1 0\n$EndNodes\n" +
    "$Elements\n2\n1 4 2 7 1 1 2 3 4\n2 4 2 7 1 1 2 3 5\n$EndElements\n";

INSTANTIATE_TEST_SUITE_P(
    Readers, BadInputTest,
    ::testing::Values(
        BadInput{"GmshTruncated", "t.msh", kTruncated.c_str(), 15, "end of file"},
        BadInput{"GmshIndexOutOfRange", "t.msh", kOutOfRange.c_str(), 15, "out of range"},
        BadInput{"GmshNoTetrahedra", "t.msh", kNoTets.c_str(), 0, "no tetrahedra"},
        BadInput{"GmshNanCoordinate", "t.msh", kNan.c_str(), 8, "non-finite"},
        BadInput{"GmshDegenerate", "t.msh", kDegenerate.c_str(), 15, "degenerate"},
        BadInput{"Msh1Truncated", "t.msh", "$NOD\n4\n1 0 0 0\n2 1 0 0\n3 0 1", 5, "end of file"},
        BadInput{"Msh41IndexOutOfRange", "t.msh",
                 "$MeshFormat\n4.1 0 8\n$EndMeshFormat\n$Nodes\n1 4 1 4\n3 1 0 4\n1\n2\n3\n4\n"
                 "0 0 0\n1 0 0\n0 1 0\n0 0 1\n$EndNodes\n$Elements\n1 1 1 1\n3 1 4 1\n"
                 "1 1 2 3 7\n$EndElements\n",
                 19, "out of range"},
        BadInput{"MeditIndexOutOfRange", "t.mesh",
                 "MeshVersionFormatted 1\nDimension 3\nVertices\n4\n0 0 0 0\n1 0 0 0\n0 1 0 0\n"
                 "0 0 1 0\nTetrahedra\n1\n1 2 3 5 0\nEnd\n",
                 11, "out of range"},
        BadInput{"MeditNanCoordinate", "t.mesh",
                 "MeshVersionFormatted 1\nDimension 3\nVertices\n4\n0 0 0 0\n1 0 0 0\n0 NaN 0 0\n"
                 "0 0 1 0\nTetrahedra\n1\n1 2 3 4 0\nEnd\n",
                 7, "non-finite"},
        BadInput{"MeditTruncated", "t.mesh",
                 "MeshVersionFormatted 1\nDimension 3\nVertices\n4\n0 0 0 0\n1 0 0 0\n", 6,
                 "end of file"},
        BadInput{"VtkLegacyDegenerate", "t.vtk",
                 "# vtk DataFile Version 2.0\nflat\nASCII\nDATASET UNSTRUCTURED_GRID\n"
                 "POINTS 4 float\n0 0 0\n1 0 0\n0 1 0\n1 1 0\nCELLS 1 5\n4 0 1 2 3\n"
                 "CELL_TYPES 1\n10\n",
                 11, "degenerate"},
        BadInput{"VtkLegacyIndexOutOfRange", "t.vtk",
                 "# vtk DataFile Version 2.0\nbad\nASCII\nDATASET UNSTRUCTURED_GRID\n"
                 "POINTS 4 float\n0 0 0\n1 0 0\n0 1 0\n0 0 1\nCELLS 1 5\n4 0 1 2 4\n"
                 "CELL_TYPES 1\n10\n",
                 11, "out of range"},
        // Counts are checked against the file before anything is sized from them.
        BadInput{"VtkLegacyPointsBeyondTheFile", "t.vtk",
                 "# vtk DataFile Version 3.0\nx\nASCII\nDATASET UNSTRUCTURED_GRID\n"
                 "POINTS 4000000000 double\n0 0 0 1 0 0\n",
                 5, "POINTS: 4000000000 tuples of 3 values cannot fit"},
        BadInput{"VtkLegacyNegativeCellCount", "t.vtk",
                 "# vtk DataFile Version 3.0\nx\nASCII\nDATASET UNSTRUCTURED_GRID\n"
                 "POINTS 1 float\n0 0 0\nCELLS -2147483649 5\n",
                 7, "CELLS counts are negative"},
        BadInput{"VtkLegacySecondCells", "t.vtk",
                 "# vtk DataFile Version 3.0\nx\nASCII\nDATASET UNSTRUCTURED_GRID\n"
                 "POINTS 4 float\n0 0 0 1 0 0 0 1 0 0 0 1\nCELLS 1 5\n4 0 1 2 3\nCELL_TYPES 1\n10\n"
                 "CELLS 1 5\n4 0 1 2 3\n",
                 11, "a second CELLS section"},
        BadInput{"VtkLegacyRegionOutOfRange", "t.vtk",
                 "# vtk DataFile Version 3.0\nx\nASCII\nDATASET UNSTRUCTURED_GRID\n"
                 "POINTS 4 float\n0 0 0 1 0 0 0 1 0 0 0 1\nCELLS 1 5\n4 0 1 2 3\nCELL_TYPES 1\n10\n"
                 "CELL_DATA 1\nSCALARS region int 1\nLOOKUP_TABLE default\n1e300\n",
                 14, "is not a region id"},
        BadInput{"Msh41NodeBlockBeyondTheFile", "t.msh",
                 "$MeshFormat\n4.1 0 8\n$EndMeshFormat\n$Nodes\n1 4 1 4\n3 1 0 4611686018427387904\n"
                 "1\n2\n3\n4\n0 0 0\n1 0 0\n0 1 0\n0 0 1\n$EndNodes\n",
                 6, "the number of nodes in the block is 4611686018427387904, more than the rest"},
        BadInput{"MeditSkippedBlockOverflow", "t.mesh",
                 "MeshVersionFormatted 2\nDimension 3\nTriangles 4611686018427387904\n1 2 3 1\n", 3,
                 "the number of Triangles is 4611686018427387904"},
        BadInput{"VtuComponentsOutOfRange", "t.vtu",
                 "<VTKFile type=\"UnstructuredGrid\" version=\"0.1\" byte_order=\"LittleEndian\">\n"
                 "<UnstructuredGrid><Piece NumberOfPoints=\"4\" NumberOfCells=\"1\"><Points>\n"
                 "<DataArray type=\"Float32\" NumberOfComponents=\"4294967299\" format=\"ascii\">"
                 "0 0 0 1 0 0 0 1 0 0 0 1</DataArray></Points></Piece></UnstructuredGrid></VTKFile>\n",
                 0, "byte 145: DataArray NumberOfComponents='4294967299' is out of range (1 to 1024)"},
        // VTK 9.1 crashed (SIGSEGV) on a token it could not parse in an ascii array.
        BadInput{"VtuAsciiValueNotANumber", "t.vtu",
                 "<VTKFile type=\"UnstructuredGrid\" version=\"0.1\" byte_order=\"LittleEndian\">\n"
                 "<UnstructuredGrid><Piece NumberOfPoints=\"4\" NumberOfCells=\"1\"><Points>\n"
                 "<DataArray type=\"Float32\" NumberOfComponents=\"3\" format=\"ascii\">"
                 "0 0 0 1 0 0 0 =1 0 0 0 1</DataArray></Points></Piece></UnstructuredGrid></VTKFile>\n",
                 0, "ascii DataArray '' value 7 is not a number: '=1'"},
        BadInput{"VtuPointsBeyondTheFile", "t.vtu",
                 "<VTKFile type=\"UnstructuredGrid\" version=\"0.1\" byte_order=\"LittleEndian\">\n"
                 "<UnstructuredGrid><Piece NumberOfPoints=\"2000000000\" NumberOfCells=\"1\"><Points>\n"
                 "<DataArray type=\"Float32\" NumberOfComponents=\"3\" format=\"ascii\">"
                 "0 0 0 1 0 0 0 1 0 0 0 1</DataArray></Points></Piece></UnstructuredGrid></VTKFile>\n",
                 0, "NumberOfPoints='2000000000' is out of range"},
        BadInput{"VtkLegacyNoTetrahedra", "t.vtk",
                 "# vtk DataFile Version 2.0\ntriangle\nASCII\nDATASET UNSTRUCTURED_GRID\n"
                 "POINTS 3 float\n0 0 0\n1 0 0\n0 1 0\nCELLS 1 4\n3 0 1 2\nCELL_TYPES 1\n5\n",
                 0, "no tetrahedra"}),
    [](const ::testing::TestParamInfo<BadInput>& info) { return std::string(info.param.name); });

// BINARY legacy files (written by VTK 9.1, file versions 4.2 and 5.1) are read by femreg
// itself, not by VTK's reader: 12 vertices, 12 tetrahedra with regions 0 1 2 ..., and a
// triangle that is skipped.
TEST(ReadTetMesh, BinaryLegacyVtkOfBothVersions) {
  const TetMesh box = MakeBox(Eigen::Vector3d(1, 0.5, 0.25), 2, 1, 1);
  for (const char* file : {"box_binary_v42.vtk", "box_binary_v51.vtk"}) {
    SCOPED_TRACE(file);
    TetMesh mesh;
    const Status status = ReadTetMesh(kFixtures + file, &mesh);
    ASSERT_TRUE(status.ok()) << status.message();
    ASSERT_EQ(mesh.num_vertices(), box.num_vertices());
    ASSERT_EQ(mesh.num_tets(), box.num_tets());
    EXPECT_TRUE(mesh.tets == box.tets);
    EXPECT_EQ((mesh.rest - box.rest).cwiseAbs().maxCoeff(), 0.0);  // doubles stored exactly
    for (int t = 0; t < mesh.num_tets(); ++t) EXPECT_EQ(mesh.region(t), t % 3);
  }
}

// A BINARY legacy file cut short, or with a count beyond its length, is refused at the
// byte offset where its data would start.
TEST(ReadTetMesh, BinaryLegacyVtkCountsAreCheckedAgainstTheFile) {
  std::ifstream in(kFixtures + "box_binary_v42.vtk", std::ios::binary);
  const std::string whole((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  TempDir dir;
  TetMesh mesh;
  const std::string cut = dir.Write("cut.vtk", whole.substr(0, whole.size() / 2));
  Status status = ReadTetMesh(cut, &mesh);
  ASSERT_FALSE(status.ok());
  EXPECT_EQ(status.message().rfind(cut + ": byte ", 0), 0u) << status.message();
  std::string huge = whole;
  const size_t at = huge.find("POINTS 12");
  ASSERT_NE(at, std::string::npos);
  huge.replace(at, 9, "POINTS -2147483649");
  const std::string path = dir.Write("huge.vtk", huge);
  status = ReadTetMesh(path, &mesh);
  ASSERT_FALSE(status.ok());
  EXPECT_EQ(status.message().rfind(path + ":5: POINTS: negative size", 0), 0u) << status.message();
  EXPECT_EQ(mesh.num_tets(), 0);
}

// TetGen: an index out of range in the .ele names the .ele file and its line.
TEST(ReadTetMesh, TetGenErrorsNameTheEleFile) {
  TempDir dir;
  dir.Write("t.node", "4 3 0 0\n1 0 0 0\n2 1 0 0\n3 0 1 0\n4 0 0 1\n");
  dir.Write("t.ele", "2 4 0\n1 1 2 3 4\n2 1 2 3 9\n");
  TetMesh mesh;
  const Status status = ReadTetMesh(dir.File("t.node"), &mesh);
  ASSERT_FALSE(status.ok());
  EXPECT_NE(status.message().find(dir.File("t.ele") + ":3:"), std::string::npos)
      << status.message();
}

TEST(ReadTetMesh, TetGenTruncatedNode) {
  TempDir dir;
  dir.Write("t.node", "4 3 0 0\n1 0 0 0\n2 1 0 0\n3 0 1\n");
  dir.Write("t.ele", "1 4 0\n1 1 2 3 4\n");
  TetMesh mesh;
  const Status status = ReadTetMesh(dir.File("t"), &mesh);
  ASSERT_FALSE(status.ok());
  EXPECT_NE(status.message().find(dir.File("t.node") + ":4:"), std::string::npos)
      << status.message();
}

TEST(WriteVtu, RoundTripKeepsPositionsTetsAndRegions) {
  TetMesh mesh = MakeBox(Eigen::Vector3d(1.0, 2.0, 0.5), 3, 2, 2);
  for (int t = 0; t < mesh.num_tets(); ++t) mesh.region(t) = t % 3 + 1;
  Vertices moved = mesh.rest;
  moved.col(0) *= 1.5;
  TempDir dir;
  const std::string path = dir.File("box.vtu");
  MeshField displacement{"displacement", moved - mesh.rest, false};
  MeshField stress{"stress", Eigen::MatrixXd::Constant(mesh.num_tets(), 1, 2.5), true};
  const Status status = WriteVtu(path, mesh, moved, {displacement, stress});
  ASSERT_TRUE(status.ok()) << status.message();
  EXPECT_EQ(DetectMeshFormat(path), MeshFormat::kVtu);
  TetMesh back;
  const Status read = ReadTetMesh(path, &back);
  ASSERT_TRUE(read.ok()) << read.message();
  ASSERT_EQ(back.num_vertices(), mesh.num_vertices());
  ASSERT_EQ(back.num_tets(), mesh.num_tets());
  EXPECT_EQ((back.rest - moved).cwiseAbs().maxCoeff(), 0.0);
  EXPECT_TRUE(back.tets == mesh.tets);
  EXPECT_TRUE(back.region == mesh.region);
  // Nothing else is left in the folder (the temporary file was renamed).
  EXPECT_FALSE(Exists(path + ".tmp"));
}

TEST(WriteVtu, TruncatedBinaryVtuGivesStatusNamingTheFile) {
  const TetMesh mesh = MakeBox(Eigen::Vector3d::Ones(), 4, 4, 4);
  TempDir dir;
  ASSERT_TRUE(WriteVtu(dir.File("box.vtu"), mesh, mesh.rest).ok());
  const std::string full = [&] {
    std::ifstream in(dir.File("box.vtu"), std::ios::binary);
    return std::string((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  }();
  const std::string cut = dir.File("cut.vtu");
  std::ofstream(cut, std::ios::binary) << full.substr(0, full.size() * 3 / 4);
  TetMesh back;
  const Status status = ReadTetMesh(cut, &back);
  ASSERT_FALSE(status.ok());
  EXPECT_EQ(status.message().rfind(cut + ": ", 0), 0u) << status.message();
}

TEST(WriteVtu, BadFieldAndUnwritableFolderGiveStatus) {
  const TetMesh mesh = MakeBox(Eigen::Vector3d::Ones(), 1, 1, 1);
  TempDir dir;
  MeshField wrong{"wrong", Eigen::MatrixXd::Zero(3, 2), false};
  Status status = WriteVtu(dir.File("a.vtu"), mesh, mesh.rest, {wrong});
  EXPECT_FALSE(status.ok());
  EXPECT_NE(status.message().find("wrong"), std::string::npos);
  status = WriteVtu("/nonexistent/folder/a.vtu", mesh, mesh.rest);
  ASSERT_FALSE(status.ok());
  EXPECT_NE(status.message().find("/nonexistent/folder/a.vtu"), std::string::npos);
}

// The binary PolyData and PLY writers (a cloud; an embedded surface's frame): the PLY reads
// back through the one PLY reader to the same vertices and triangles; the VTPs say their
// counts and fields; normals that are not one per point are refused, naming the file.
TEST(WriteBinary, TrianglesPlyAndVtpAndCloudVtp) {
  const TetMesh mesh = MakeBox(Eigen::Vector3d(0.3, 0.2, 0.1), 2, 2, 1);
  const Triangles& triangles = mesh.surface;
  TempDir dir;
  ASSERT_TRUE(WriteTrianglesPly(dir.File("s.ply"), mesh.rest, triangles).ok());
  Vertices V;
  Triangles F;
  ASSERT_TRUE(internal::ReadPlySurface(dir.File("s.ply"), &V, &F).ok());
  EXPECT_EQ(V, mesh.rest);
  EXPECT_EQ(F, triangles);

  Eigen::VectorXd height = mesh.rest.col(2);
  ASSERT_TRUE(WriteTrianglesVtp(dir.File("s.vtp"), mesh.rest, triangles, {{"height", height}}).ok());
  std::ifstream vtp(dir.File("s.vtp"), std::ios::binary);
  const std::string text((std::istreambuf_iterator<char>(vtp)), std::istreambuf_iterator<char>());
  EXPECT_NE(text.find("NumberOfPoints=\"" + std::to_string(mesh.rest.rows()) + "\""), std::string::npos);
  EXPECT_NE(text.find("NumberOfPolys=\"" + std::to_string(triangles.rows()) + "\""), std::string::npos);
  EXPECT_NE(text.find("Name=\"height\""), std::string::npos);

  Vertices normals = Vertices::Zero(mesh.rest.rows(), 3);
  normals.col(2).setOnes();
  ASSERT_TRUE(WriteCloudVtp(dir.File("c.vtp"), mesh.rest, &normals).ok());
  std::ifstream cloud(dir.File("c.vtp"), std::ios::binary);
  const std::string cloud_text((std::istreambuf_iterator<char>(cloud)), std::istreambuf_iterator<char>());
  EXPECT_NE(cloud_text.find("NumberOfVerts=\"" + std::to_string(mesh.rest.rows()) + "\""), std::string::npos);
  EXPECT_NE(cloud_text.find("Normals=\"normals\""), std::string::npos);
  ASSERT_TRUE(WriteCloudVtp(dir.File("bare.vtp"), mesh.rest).ok());
  const Vertices too_few = normals.topRows(3);
  const Status refused = WriteCloudVtp(dir.File("bad.vtp"), mesh.rest, &too_few);
  EXPECT_FALSE(refused.ok());
  EXPECT_NE(refused.message().find("bad.vtp"), std::string::npos) << refused.message();
}

TEST(WriteText, PvdPlyObjAndAtomicWrites) {
  const TetMesh mesh = MakeBox(Eigen::Vector3d::Ones(), 2, 2, 2);
  TempDir dir;
  ASSERT_TRUE(WritePvd(dir.File("run.pvd"), {{0.0, "f0.vtu"}, {0.5, "a&b.vtu"}}).ok());
  std::ifstream pvd(dir.File("run.pvd"));
  const std::string text((std::istreambuf_iterator<char>(pvd)), std::istreambuf_iterator<char>());
  EXPECT_NE(text.find("type=\"Collection\""), std::string::npos);
  EXPECT_NE(text.find("timestep=\"0.5\""), std::string::npos);
  EXPECT_NE(text.find("a&amp;b.vtu"), std::string::npos);

  ASSERT_TRUE(WritePlySurface(dir.File("s.ply"), mesh, mesh.rest).ok());
  std::ifstream ply(dir.File("s.ply"));
  std::string line;
  std::getline(ply, line);
  EXPECT_EQ(line, "ply");
  ASSERT_TRUE(WriteObjSurface(dir.File("s.obj"), mesh, mesh.rest).ok());
  std::ifstream obj(dir.File("s.obj"));
  int v = 0, f = 0;
  while (std::getline(obj, line)) {
    v += line.rfind("v ", 0) == 0;
    f += line.rfind("f ", 0) == 0;
  }
  EXPECT_EQ(v, static_cast<int>(mesh.surface_vertices.size()));
  EXPECT_EQ(f, mesh.num_surface_triangles());
  // A surface file is not a tet mesh.
  TetMesh back;
  EXPECT_FALSE(ReadTetMesh(dir.File("s.obj"), &back).ok());

  EXPECT_FALSE(WriteFileAtomically("/nonexistent/folder/x.txt", "x").ok());
  ASSERT_TRUE(WriteFileAtomically(dir.File("x.txt"), "first").ok());
  ASSERT_TRUE(WriteFileAtomically(dir.File("x.txt"), "second").ok());
  std::ifstream x(dir.File("x.txt"));
  std::getline(x, line);
  EXPECT_EQ(line, "second");
}

TEST(Generators, BoxIsConformingAndExact) {
  const TetMesh box = MakeBox(Eigen::Vector3d(2.0, 1.0, 3.0), 4, 3, 5, Eigen::Vector3d(1, -1, 0));
  EXPECT_EQ(box.num_vertices(), 5 * 4 * 6);
  EXPECT_EQ(box.num_tets(), 6 * 4 * 3 * 5);
  EXPECT_NEAR(RestVolume(box), 6.0, 1e-12);
  EXPECT_EQ(box.num_surface_triangles(), 4 * (4 * 3 + 3 * 5 + 4 * 5));
  EXPECT_DOUBLE_EQ(box.rest.col(0).minCoeff(), 1.0);
  EXPECT_DOUBLE_EQ(box.rest.col(1).maxCoeff(), 0.0);
  ExpectWellFormed(box);
}

TEST(Generators, CylinderVolumeAndQuality) {
  const double radius = 0.5, length = 2.0;
  const TetMesh cylinder = MakeCylinder(radius, length, 6, 24);  // cells about as long as wide
  ExpectWellFormed(cylinder);
  const double analytic = M_PI * radius * radius * length;
  EXPECT_NEAR(RestVolume(cylinder), analytic, 0.02 * analytic);
  const MeshQuality q = ComputeQuality(cylinder, cylinder.rest);
  EXPECT_EQ(q.num_inverted, 0);
  EXPECT_EQ(q.num_degenerate, 0);
  EXPECT_GT(q.min_dihedral_deg, 20.0);
  EXPECT_LT(q.max_aspect_ratio, 3.0);
}

TEST(Generators, SphereVolumeAndQuality) {
  const double radius = 2.0;
  const TetMesh sphere = MakeSphere(radius, 6);
  ExpectWellFormed(sphere);
  const double analytic = 4.0 / 3.0 * M_PI * radius * radius * radius;
  EXPECT_NEAR(RestVolume(sphere), analytic, 0.03 * analytic);
  EXPECT_NEAR(sphere.rest.rowwise().norm().maxCoeff(), radius, 1e-12);
  const MeshQuality q = ComputeQuality(sphere, sphere.rest);
  EXPECT_EQ(q.num_inverted, 0);
  EXPECT_EQ(q.num_degenerate, 0);
  EXPECT_GT(q.min_dihedral_deg, 25.0);
  EXPECT_LT(q.max_aspect_ratio, 2.5);
}

TEST(ComputeQuality, RegularTetrahedron) {
  TetMesh mesh;
  mesh.rest.resize(4, 3);
  mesh.rest << 1, 1, 1, 1, -1, -1, -1, 1, -1, -1, -1, 1;
  mesh.tets.resize(1, 4);
  mesh.tets << 0, 1, 2, 3;
  ASSERT_TRUE(FinalizeMesh(&mesh).ok());
  const MeshQuality q = ComputeQuality(mesh, mesh.rest);
  const double dihedral = std::acos(1.0 / 3.0) * 180.0 / M_PI;  // 70.5288 degrees
  EXPECT_NEAR(q.min_dihedral_deg, dihedral, 1e-9);
  EXPECT_NEAR(q.max_dihedral_deg, dihedral, 1e-9);
  EXPECT_NEAR(q.max_aspect_ratio, 1.0, 1e-12);
  EXPECT_NEAR(q.mean_aspect_ratio, 1.0, 1e-12);
  EXPECT_EQ(q.num_inverted, 0);
  // Mirrored positions invert the element.
  Vertices mirrored = mesh.rest;
  mirrored.col(0) *= -1.0;
  EXPECT_EQ(ComputeQuality(mesh, mirrored).num_inverted, 1);
}

// Every tetrahedral mesh in FEMREG_SHARED_MESHES_DIR loads with the counts below
// (docs/dev/licences.md). Unused vertices are dropped, so raptorTetra_8418.vtu (3 points no cell
// uses) has 2993.
TEST(SharedMeshes, LoadWithReadmeCounts) {
  const std::string dir = FEMREG_SHARED_MESHES_DIR;
  if (!Exists(dir)) GTEST_SKIP() << dir << " does not exist";
  struct Expected {
    const char* file;
    int vertices;
    int tets;
  };
  const Expected expected[] = {
      {"liver.msh", 181, 596},
      {"liver2.msh", 507, 1493},
      {"torus_low_res.msh", 264, 862},
      {"cylinder.msh", 510, 2430},
      {"truss_tetra.msh", 40, 54},
      {"Armadillo_Tetra_4406.vtu", 1446, 4406},
      {"raptorTetra_8418.vtu", 2993, 8418},
      {"Bunny.vtk", 1911, 5897},
      {"SOFA_volume.vtk", 959, 2564},
      {"octopus-low.mesh", 452, 1140},
      {"simple_bar_bar-186.msh", 86, 186},
      {"simple_bar_bar-651.msh", 292, 651},
      {"simple_bar_bar-2523.msh", 886, 2523},
      {"creatures_bunny.msh", 4670, 19379},
  };
  for (const Expected& e : expected) {
    SCOPED_TRACE(e.file);
    TetMesh mesh;
    const Status status = ReadTetMesh(dir + "/" + e.file, &mesh);
    ASSERT_TRUE(status.ok()) << status.message();
    EXPECT_EQ(mesh.num_vertices(), e.vertices);
    EXPECT_EQ(mesh.num_tets(), e.tets);
    EXPECT_GT(RestVolume(mesh), 0.0);
    EXPECT_EQ(ComputeQuality(mesh, mesh.rest).num_inverted, 0);
  }
  EXPECT_EQ(DetectMeshFormat(dir + "/Bunny.vtk"), MeshFormat::kVtu);
  EXPECT_EQ(DetectMeshFormat(dir + "/SOFA_volume.vtk"), MeshFormat::kVtkLegacy);
  for (const char* surface : {"liver-smooth.obj", "dragon.obj", "Bunny.stl"}) {
    TetMesh mesh;
    const Status status = ReadTetMesh(dir + "/" + surface, &mesh);
    ASSERT_FALSE(status.ok()) << surface;
    EXPECT_NE(status.message().find("no tetrahedra"), std::string::npos) << status.message();
  }
}

#ifdef FEMREG_CLI_PATH
std::string ReadAll(const std::string& path) {
  std::ifstream in(path);
  return std::string((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
}

TEST(InfoCommand, PrintsCountsAndFailsWithExitCodeOne) {
  TempDir dir;
  const std::string out = dir.File("out.txt"), err = dir.File("err.txt");
  const std::string cli = FEMREG_CLI_PATH;
  int code = std::system((cli + " info --json '" + kFixtures + "two_tets_v22.msh' >" + out +
                          " 2>" + err).c_str());
  ASSERT_TRUE(WIFEXITED(code));
  EXPECT_EQ(WEXITSTATUS(code), 0) << ReadAll(err);
  const std::string json = ReadAll(out);
  EXPECT_NE(json.find("\"format\": \"gmsh\""), std::string::npos) << json;
  EXPECT_NE(json.find("\"vertices\": 5"), std::string::npos) << json;
  EXPECT_NE(json.find("\"elements\": 2"), std::string::npos) << json;
  EXPECT_NE(json.find("\"regions\": {\"7\": 1, \"8\": 1}"), std::string::npos) << json;

  code = std::system((cli + " info '" + kFixtures + "surface_only.obj' >" + out + " 2>" + err).c_str());
  ASSERT_TRUE(WIFEXITED(code));
  EXPECT_EQ(WEXITSTATUS(code), 1);
  EXPECT_NE(ReadAll(err).find("surface_only.obj: no tetrahedra"), std::string::npos) << ReadAll(err);
}
#endif  // FEMREG_CLI_PATH

}  // namespace
}  // namespace femreg
