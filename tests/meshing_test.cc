// Tests of femreg/meshing.h: surface files in, the checks, TetGen's tetrahedralization, mesh
// files out, and the femreg mesh command.
#include "femreg/meshing.h"

#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <map>
#include <random>
#include <set>
#include <sstream>
#include <string>
#include <vector>

#include "femreg/io.h"
#include "femreg/mesh.h"
#include "femreg_test_config.h"
#include "test_util.h"

namespace femreg {
namespace {

namespace fs = std::filesystem;
using testing_util::TempDir;

constexpr double kPi = 3.14159265358979323846;

struct Surface {
  Vertices V;
  Triangles F;
};

// The unit cube [origin, origin + size]^3, 12 triangles facing outwards.
Surface Cube(const Eigen::Vector3d& origin = Eigen::Vector3d::Zero(), double size = 1.0) {
  Surface s;
  s.V.resize(8, 3);
  for (int i = 0; i < 8; ++i) {
    s.V.row(i) = (origin + size * Eigen::Vector3d(i & 1, (i >> 1) & 1, (i >> 2) & 1)).transpose();
  }
  // Each face as a quad (counter-clockwise seen from outside), split in two.
  const int quads[6][4] = {{0, 2, 3, 1}, {4, 5, 7, 6}, {0, 1, 5, 4},
                           {2, 6, 7, 3}, {0, 4, 6, 2}, {1, 3, 7, 5}};
  s.F.resize(12, 3);
  for (int q = 0; q < 6; ++q) {
    s.F.row(2 * q) << quads[q][0], quads[q][1], quads[q][2];
    s.F.row(2 * q + 1) << quads[q][0], quads[q][2], quads[q][3];
  }
  return s;
}

// An icosphere: the icosahedron's triangles split `levels` times, vertices on the sphere.
Surface Icosphere(double radius, int levels) {
  const double t = (1.0 + std::sqrt(5.0)) / 2.0;
  std::vector<Eigen::Vector3d> v = {{-1, t, 0}, {1, t, 0}, {-1, -t, 0}, {1, -t, 0},
                                    {0, -1, t}, {0, 1, t}, {0, -1, -t}, {0, 1, -t},
                                    {t, 0, -1}, {t, 0, 1}, {-t, 0, -1}, {-t, 0, 1}};
  for (auto& p : v) p.normalize();
  std::vector<Eigen::Vector3i> f = {{0, 11, 5}, {0, 5, 1},  {0, 1, 7},   {0, 7, 10}, {0, 10, 11},
                                    {1, 5, 9},  {5, 11, 4}, {11, 10, 2}, {10, 7, 6}, {7, 1, 8},
                                    {3, 9, 4},  {3, 4, 2},  {3, 2, 6},   {3, 6, 8},  {3, 8, 9},
                                    {4, 9, 5},  {2, 4, 11}, {6, 2, 10},  {8, 6, 7},  {9, 8, 1}};
  for (int level = 0; level < levels; ++level) {
    std::map<std::pair<int, int>, int> midpoint;
    auto mid = [&](int a, int b) {
      const auto key = std::minmax(a, b);
      auto it = midpoint.find(key);
      if (it != midpoint.end()) return it->second;
      v.push_back((v[static_cast<size_t>(a)] + v[static_cast<size_t>(b)]).normalized());
      return midpoint[key] = static_cast<int>(v.size()) - 1;
    };
    std::vector<Eigen::Vector3i> next;
    for (const auto& tri : f) {
      const int a = mid(tri[0], tri[1]), b = mid(tri[1], tri[2]), c = mid(tri[2], tri[0]);
      next.insert(next.end(), {{tri[0], a, c}, {tri[1], b, a}, {tri[2], c, b}, {a, b, c}});
    }
    f.swap(next);
  }
  Surface s;
  s.V.resize(static_cast<int>(v.size()), 3);
  for (size_t i = 0; i < v.size(); ++i) s.V.row(static_cast<int>(i)) = radius * v[i].transpose();
  s.F.resize(static_cast<int>(f.size()), 3);
  for (size_t i = 0; i < f.size(); ++i) s.F.row(static_cast<int>(i)) = f[i].transpose();
  return s;
}

// Two surfaces as one (the second's indices shifted).
Surface Join(const Surface& a, const Surface& b, bool flip_b = false) {
  Surface s;
  s.V.resize(a.V.rows() + b.V.rows(), 3);
  s.V << a.V, b.V;
  s.F.resize(a.F.rows() + b.F.rows(), 3);
  Triangles fb = b.F.array() + static_cast<int>(a.V.rows());
  if (flip_b) fb.col(1).swap(fb.col(2));
  s.F << a.F, fb;
  return s;
}

// Volume enclosed by a closed, outward-oriented triangle surface (divergence theorem).
double EnclosedVolume(const Surface& s) {
  double v = 0.0;
  for (int t = 0; t < s.F.rows(); ++t) {
    const Eigen::Vector3d a = s.V.row(s.F(t, 0)), b = s.V.row(s.F(t, 1)), c = s.V.row(s.F(t, 2));
    v += a.dot(b.cross(c)) / 6.0;
  }
  return v;
}

void WriteObj(const std::string& path, const Surface& s) {
  std::ofstream out(path);
  char buf[128];
  for (int i = 0; i < s.V.rows(); ++i) {
    std::snprintf(buf, sizeof(buf), "v %.17g %.17g %.17g\n", s.V(i, 0), s.V(i, 1), s.V(i, 2));
    out << buf;
  }
  for (int t = 0; t < s.F.rows(); ++t) {
    out << "f " << s.F(t, 0) + 1 << " " << s.F(t, 1) + 1 << " " << s.F(t, 2) + 1 << "\n";
  }
}

// Binary STL: every triangle stores its own 3 corners (as 32-bit floats).
void WriteBinaryStl(const std::string& path, const Surface& s) {
  std::ofstream out(path, std::ios::binary);
  char header[80] = "femreg meshing_test";
  out.write(header, 80);
  const uint32_t n = static_cast<uint32_t>(s.F.rows());
  out.write(reinterpret_cast<const char*>(&n), 4);
  for (int t = 0; t < s.F.rows(); ++t) {
    float record[12] = {0, 0, 0};
    for (int k = 0; k < 3; ++k) {
      for (int d = 0; d < 3; ++d) record[3 + 3 * k + d] = static_cast<float>(s.V(s.F(t, k), d));
    }
    out.write(reinterpret_cast<const char*>(record), 48);
    const uint16_t attribute = 0;
    out.write(reinterpret_cast<const char*>(&attribute), 2);
  }
}

void WritePly(const std::string& path, const Surface& s, bool binary) {
  std::ofstream out(path, std::ios::binary);
  out << "ply\nformat " << (binary ? "binary_little_endian" : "ascii") << " 1.0\n"
      << "comment written by meshing_test\n"
      << "element vertex " << s.V.rows() << "\nproperty double x\nproperty double y\n"
      << "property double z\nproperty uchar red\n"
      << "element face " << s.F.rows() << "\nproperty list uchar int vertex_indices\n"
      << "end_header\n";
  for (int i = 0; i < s.V.rows(); ++i) {
    if (binary) {
      out.write(reinterpret_cast<const char*>(&s.V(i, 0)), 8);
      out.write(reinterpret_cast<const char*>(&s.V(i, 1)), 8);
      out.write(reinterpret_cast<const char*>(&s.V(i, 2)), 8);
      const unsigned char red = 200;
      out.write(reinterpret_cast<const char*>(&red), 1);
    } else {
      char buf[128];
      std::snprintf(buf, sizeof(buf), "%.17g %.17g %.17g 200\n", s.V(i, 0), s.V(i, 1), s.V(i, 2));
      out << buf;
    }
  }
  for (int t = 0; t < s.F.rows(); ++t) {
    if (binary) {
      const unsigned char three = 3;
      out.write(reinterpret_cast<const char*>(&three), 1);
      for (int k = 0; k < 3; ++k) out.write(reinterpret_cast<const char*>(&s.F(t, k)), 4);
    } else {
      out << "3 " << s.F(t, 0) << " " << s.F(t, 1) << " " << s.F(t, 2) << "\n";
    }
  }
}

std::string ReadAll(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  return std::string((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
}

// What every mesh TetrahedralizeSurface returns must satisfy.
void ExpectValidMesh(const TetMesh& mesh) {
  ASSERT_GT(mesh.num_tets(), 0);
  int not_positive = 0;
  for (int t = 0; t < mesh.num_tets(); ++t) {
    const double v =
        SignedTetVolume(mesh.rest.row(mesh.tets(t, 0)), mesh.rest.row(mesh.tets(t, 1)),
                        mesh.rest.row(mesh.tets(t, 2)), mesh.rest.row(mesh.tets(t, 3)));
    if (!(v > 0.0)) ++not_positive;
  }
  EXPECT_EQ(not_positive, 0);
  const MeshQuality q = ComputeQuality(mesh, mesh.rest);
  EXPECT_EQ(q.num_inverted, 0);
  EXPECT_EQ(q.num_degenerate, 0);
  EXPECT_GT(mesh.num_surface_triangles(), 0);
  EXPECT_EQ(static_cast<int>(mesh.vertex_tet_offsets.size()), mesh.num_vertices() + 1);
  EXPECT_EQ(mesh.x, mesh.rest);
}

// Mean edge length over the unique edges of the tetrahedra.
double MeanEdge(const TetMesh& mesh) {
  std::set<std::pair<int, int>> edges;
  for (int t = 0; t < mesh.num_tets(); ++t) {
    for (int i = 0; i < 4; ++i) {
      for (int j = i + 1; j < 4; ++j) edges.insert(std::minmax(mesh.tets(t, i), mesh.tets(t, j)));
    }
  }
  double sum = 0.0;
  for (const auto& e : edges) sum += (mesh.rest.row(e.first) - mesh.rest.row(e.second)).norm();
  return sum / static_cast<double>(edges.size());
}

// ---------------------------------------------------------------------------------------

TEST(MeshingOptionsTest, IsValidNamesTheField) {
  std::string error;
  EXPECT_TRUE(MeshingOptions().IsValid(&error)) << error;
  MeshingOptions o;
  o.edge_length = -1.0;
  EXPECT_FALSE(o.IsValid(&error));
  EXPECT_NE(error.find("edge_length"), std::string::npos) << error;
  o = MeshingOptions();
  o.radius_edge_ratio = 1.0;
  EXPECT_FALSE(o.IsValid(&error));
  EXPECT_NE(error.find("radius_edge_ratio"), std::string::npos) << error;
  o = MeshingOptions();
  o.max_volume = std::nan("");
  EXPECT_FALSE(o.IsValid(&error));
  EXPECT_NE(error.find("max_volume"), std::string::npos) << error;
  o = MeshingOptions();
  o.min_dihedral_deg = 30.0;
  EXPECT_FALSE(o.IsValid(&error));
  EXPECT_NE(error.find("min_dihedral_deg"), std::string::npos) << error;
  o = MeshingOptions();
  o.max_tets = 0;
  EXPECT_FALSE(o.IsValid(&error));
  EXPECT_NE(error.find("max_tets"), std::string::npos) << error;

  // Through TetrahedralizeSurface: the message names the source and the field.
  Surface cube = Cube();
  TetMesh mesh;
  o = MeshingOptions();
  o.edge_length = -1.0;
  const Status s = TetrahedralizeSurface(cube.V, cube.F, o, &mesh, nullptr, "cube.obj");
  ASSERT_FALSE(s.ok());
  EXPECT_NE(s.message().find("cube.obj"), std::string::npos) << s.message();
  EXPECT_NE(s.message().find("edge_length"), std::string::npos) << s.message();
}

TEST(MeshingTest, CubeFromObjIsFilledWithPositiveTetsOfTheTargetSize) {
  TempDir dir;
  const std::string path = dir.path() + "/cube.obj";
  WriteObj(path, Cube());
  Surface s;
  ASSERT_TRUE(ReadSurface(path, &s.V, &s.F).ok());
  ASSERT_EQ(s.F.rows(), 12);

  MeshingOptions options;
  options.edge_length = 0.1;
  TetMesh mesh;
  MeshingReport report;
  const Status status = TetrahedralizeSurface(s.V, s.F, options, &mesh, &report, path);
  ASSERT_TRUE(status.ok()) << status.message();
  ExpectValidMesh(mesh);

  // The tets fill the cube exactly: TetGen splits the flat faces but moves no point off them.
  // Summing a few thousand tet volumes, each exact to ~1e-16 relative, leaves < 1e-12.
  EXPECT_NEAR(RestVolume(mesh), 1.0, 1e-12);
  EXPECT_NEAR(report.mesh_volume, 1.0, 1e-12);
  EXPECT_NEAR(report.surface_volume, 1.0, 1e-12);
  double area = 0.0;
  for (int f = 0; f < mesh.num_surface_triangles(); ++f) {
    const Eigen::Vector3d a = mesh.rest.row(mesh.surface(f, 0)),
                          b = mesh.rest.row(mesh.surface(f, 1)),
                          c = mesh.rest.row(mesh.surface(f, 2));
    area += 0.5 * (b - a).cross(c - a).norm();
    // Outward: the normal points away from the centre.
    EXPECT_GT((b - a).cross(c - a).dot((a + b + c) / 3.0 - Eigen::Vector3d(0.5, 0.5, 0.5)), 0.0);
  }
  EXPECT_NEAR(area, 6.0, 1e-12);
  for (int v : mesh.surface_vertices) {
    const Eigen::Vector3d p = mesh.rest.row(v);
    const double to_face = std::min(p.minCoeff(), 1.0 - p.maxCoeff());
    EXPECT_NEAR(to_face, 0.0, 1e-15);
  }

  // The size is honoured roughly: no tet is larger than the bound, so there are at least
  // volume / max_volume of them; Delaunay refinement makes tets below the bound, so allow up to 5
  // times as many (docs/notes/2026-11-28-figures-from-code-comments.md); TetGen is deterministic,
  // the margin
  // of 0.75 .. 1.1 L leaves room for another TetGen build, not for a wrong volume bound
  // (the regular tetrahedron's volume gives 0.82 L, half of it 0.65 L).
  const double max_volume = std::pow(0.1, 3) / (4.0 * std::sqrt(2.0));
  EXPECT_NEAR(report.max_volume, max_volume, 1e-15);
  EXPECT_GE(mesh.num_tets(), 1.0 / max_volume);
  EXPECT_LE(mesh.num_tets(), 5.0 / max_volume);
  const double mean_edge = MeanEdge(mesh);
  EXPECT_NEAR(report.mean_edge_length, mean_edge, 1e-12);
  EXPECT_GT(mean_edge, 0.75 * 0.1);
  EXPECT_LT(mean_edge, 1.1 * 0.1);
  // The quality bound: the radius-edge ratio <= 1.5 keeps the aspect ratio moderate; TetGen
  // does not bound dihedral angles this way (slivers), so only sanity bounds here.
  EXPECT_GT(report.quality.min_dihedral_deg, 0.0);
  EXPECT_LT(report.quality.max_dihedral_deg, 180.0);
  EXPECT_EQ(report.input_vertices, 8);
  EXPECT_EQ(report.input_triangles, 12);
  EXPECT_EQ(report.merged_vertices, 0);
  EXPECT_EQ(report.shells, 1);
  EXPECT_EQ(report.regions, 1);
  EXPECT_EQ(report.vertices, mesh.num_vertices());
  EXPECT_EQ(report.tets, mesh.num_tets());

  // A finer target makes more tets.
  options.edge_length = 0.05;
  TetMesh finer;
  ASSERT_TRUE(TetrahedralizeSurface(s.V, s.F, options, &finer, nullptr, path).ok());
  EXPECT_GT(finer.num_tets(), 4 * mesh.num_tets());  // 8 times in the bulk
}

TEST(MeshingTest, SphereFromBinaryStlHasTheInscribedPolyhedronsVolume) {
  TempDir dir;
  const double r = 0.05;
  const Surface sphere = Icosphere(r, 3);  // 642 vertices, 1280 triangles
  const std::string path = dir.path() + "/sphere.stl";
  WriteBinaryStl(path, sphere);
  Surface s;
  ASSERT_TRUE(ReadSurface(path, &s.V, &s.F).ok());
  ASSERT_EQ(s.F.rows(), 1280);
  ASSERT_EQ(s.V.rows(), 642);  // the STL reader welds the 3840 corners by exact position

  TetMesh mesh;
  MeshingReport report;
  const Status status = TetrahedralizeSurface(s.V, s.F, MeshingOptions(), &mesh, &report, path);
  ASSERT_TRUE(status.ok()) << status.message();
  ExpectValidMesh(mesh);
  // The tets fill the polyhedron the triangles bound, not the ball: compare with the
  // polyhedron's own volume (as read, in float precision) to summation rounding (1e-12
  // relative). Vertices on the sphere make an inscribed, convex polyhedron: it lies inside the
  // ball of radius r and contains the ball of radius d_min, the distance from the centre to
  // the nearest triangle plane; its volume is between theirs (0.9914 of the ball measured).
  const double polyhedron = EnclosedVolume(s);
  double d_min = r;
  for (int t = 0; t < s.F.rows(); ++t) {
    const Eigen::Vector3d a = s.V.row(s.F(t, 0)), b = s.V.row(s.F(t, 1)), c = s.V.row(s.F(t, 2));
    d_min = std::min(d_min, std::abs((b - a).cross(c - a).normalized().dot(a)));
  }
  EXPECT_NEAR(RestVolume(mesh), polyhedron, 1e-12 * polyhedron);
  EXPECT_LT(polyhedron, 4.0 / 3.0 * kPi * r * r * r);
  EXPECT_GT(polyhedron, 4.0 / 3.0 * kPi * d_min * d_min * d_min);
  EXPECT_GT(d_min, 0.98 * r);  // level 3: the triangles are small
  // The default target is the surface's mean edge length. The ball is only 13 of them
  // across, so the surface's triangles (whose edges TetGen keeps or splits, never joins) and
  // the refinement around them set the size as much as the volume bound does: the mean edge
  // comes out shorter than the target (0.85 L measured); only a loose check here.
  EXPECT_NEAR(report.edge_length, report.surface_mean_edge_length, 1e-15);
  EXPECT_GT(report.mean_edge_length, 0.6 * report.edge_length);
  EXPECT_LT(report.mean_edge_length, 1.1 * report.edge_length);
  // Every mesh vertex lies in the ball (TetGen adds points on the flat triangles and inside).
  for (int v = 0; v < mesh.num_vertices(); ++v) EXPECT_LE(mesh.rest.row(v).norm(), r * (1 + 1e-6));
}

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

TEST(MeshingTest, KeepSurfaceKeepsEveryInputTriangle) {
  const Surface sphere = Icosphere(1.0, 2);  // 320 triangles
  MeshingOptions options;
  options.keep_surface = true;
  options.edge_length = 0.2;
  TetMesh mesh;
  MeshingReport report;
  const Status status = TetrahedralizeSurface(sphere.V, sphere.F, options, &mesh, &report);
  ASSERT_TRUE(status.ok()) << status.message();
  ExpectValidMesh(mesh);
  ASSERT_EQ(mesh.num_surface_triangles(), sphere.F.rows());
  // The same triangles, as sets of corner positions (TetGen copies the input points).
  auto key = [](const Vertices& V, int a, int b, int c) {
    std::vector<std::vector<double>> corners;
    for (int i : {a, b, c}) corners.push_back({V(i, 0), V(i, 1), V(i, 2)});
    std::sort(corners.begin(), corners.end());
    return corners;
  };
  std::set<std::vector<std::vector<double>>> input;
  for (int t = 0; t < sphere.F.rows(); ++t)
    input.insert(key(sphere.V, sphere.F(t, 0), sphere.F(t, 1), sphere.F(t, 2)));
  for (int t = 0; t < mesh.num_surface_triangles(); ++t) {
    EXPECT_TRUE(
        input.count(key(mesh.rest, mesh.surface(t, 0), mesh.surface(t, 1), mesh.surface(t, 2))))
        << "boundary triangle " << t << " is not an input triangle";
  }
  EXPECT_NE(report.tetgen_switches.find('Y'), std::string::npos);
  // Interior points were added for the size.
  EXPECT_GT(mesh.num_vertices(), sphere.V.rows());
}

TEST(MeshingTest, DisjointShellsAreRegionsAndNestedShellsCavities) {
  // Two disjoint cubes: two regions of volume 1 each.
  const Surface two = Join(Cube(), Cube(Eigen::Vector3d(2, 0, 0)));
  MeshingOptions options;
  options.edge_length = 0.25;
  TetMesh mesh;
  MeshingReport report;
  Status status = TetrahedralizeSurface(two.V, two.F, options, &mesh, &report);
  ASSERT_TRUE(status.ok()) << status.message();
  ExpectValidMesh(mesh);
  EXPECT_EQ(report.shells, 2);
  EXPECT_EQ(report.cavities, 0);
  EXPECT_EQ(report.regions, 2);
  double volume[2] = {0, 0};
  for (int t = 0; t < mesh.num_tets(); ++t) {
    const Eigen::Vector3d c = (mesh.rest.row(mesh.tets(t, 0)) + mesh.rest.row(mesh.tets(t, 1)) +
                               mesh.rest.row(mesh.tets(t, 2)) + mesh.rest.row(mesh.tets(t, 3))) /
                              4.0;
    // Region 0 is the shell of the first triangle: the cube at the origin.
    EXPECT_EQ(mesh.region(t), c.x() < 1.5 ? 0 : 1);
    volume[mesh.region(t)] +=
        SignedTetVolume(mesh.rest.row(mesh.tets(t, 0)), mesh.rest.row(mesh.tets(t, 1)),
                        mesh.rest.row(mesh.tets(t, 2)), mesh.rest.row(mesh.tets(t, 3)));
  }
  EXPECT_NEAR(volume[0], 1.0, 1e-12);
  EXPECT_NEAR(volume[1], 1.0, 1e-12);
  options.region_per_shell = false;
  ASSERT_TRUE(TetrahedralizeSurface(two.V, two.F, options, &mesh, &report).ok());
  EXPECT_EQ(mesh.region.maxCoeff(), 0);

  // A cube of side 1 inside one of side 3: a hollow box of volume 26, the cavity unmeshed,
  // whichever way the inner shell faces.
  options.region_per_shell = true;
  for (bool flip : {true, false}) {
    const Surface hollow = Join(Cube(Eigen::Vector3d(-1, -1, -1), 3.0), Cube(), flip);
    status = TetrahedralizeSurface(hollow.V, hollow.F, options, &mesh, &report);
    ASSERT_TRUE(status.ok()) << status.message();
    ExpectValidMesh(mesh);
    EXPECT_EQ(report.shells, 2);
    EXPECT_EQ(report.cavities, 1);
    EXPECT_EQ(report.regions, 1);
    EXPECT_NEAR(RestVolume(mesh), 26.0, 1e-10);
    for (int t = 0; t < mesh.num_tets(); ++t) {
      const Eigen::Vector3d c = (mesh.rest.row(mesh.tets(t, 0)) + mesh.rest.row(mesh.tets(t, 1)) +
                                 mesh.rest.row(mesh.tets(t, 2)) + mesh.rest.row(mesh.tets(t, 3))) /
                                4.0;
      EXPECT_FALSE(c.minCoeff() > 0.0 && c.maxCoeff() < 1.0) << "tet " << t << " in the cavity";
    }
  }
}

TEST(MeshingTest, NearDuplicateVerticesAreMerged) {
  // Every triangle with its own corners, each a hair off (as a float export might leave them).
  const Surface cube = Cube();
  Surface soup;
  soup.V.resize(3 * cube.F.rows(), 3);
  soup.F.resize(cube.F.rows(), 3);
  for (int t = 0; t < cube.F.rows(); ++t) {
    for (int k = 0; k < 3; ++k) {
      soup.V.row(3 * t + k) = cube.V.row(cube.F(t, k)).array() + 1e-13 * ((t + k) % 3);
      soup.F(t, k) = 3 * t + k;
    }
  }
  TetMesh mesh;
  MeshingReport report;
  Status status = TetrahedralizeSurface(soup.V, soup.F, MeshingOptions(), &mesh, &report);
  ASSERT_TRUE(status.ok()) << status.message();
  EXPECT_EQ(report.merged_vertices, 36 - 8);
  EXPECT_EQ(report.surface_vertices, 8);
  EXPECT_NEAR(RestVolume(mesh), 1.0, 1e-9);  // the corners moved by <= 2e-13

  // With merging limited to exact copies the soup is open everywhere.
  MeshingOptions exact;
  exact.merge_distance = 0.0;
  status = TetrahedralizeSurface(soup.V, soup.F, exact, &mesh, &report, "soup.stl");
  ASSERT_FALSE(status.ok());
  EXPECT_NE(status.message().find("boundary edges"), std::string::npos) << status.message();

  // An unused vertex is dropped and counted.
  Surface extra = cube;
  extra.V.conservativeResize(9, 3);
  extra.V.row(8) << 5, 5, 5;
  ASSERT_TRUE(TetrahedralizeSurface(extra.V, extra.F, MeshingOptions(), &mesh, &report).ok());
  EXPECT_EQ(report.unused_vertices, 1);
  EXPECT_LE(mesh.rest.maxCoeff(), 1.0);
}

// The message of a surface that must be refused.
std::string Refusal(const Surface& s, const MeshingOptions& options = MeshingOptions()) {
  TetMesh mesh;
  MeshingReport report;
  const Status status = TetrahedralizeSurface(s.V, s.F, options, &mesh, &report, "bad_surface.stl");
  EXPECT_FALSE(status.ok());
  EXPECT_EQ(mesh.num_tets(), 0);
  EXPECT_EQ(status.message().rfind("bad_surface.stl: ", 0), 0u) << status.message();
  return status.message();
}

TEST(MeshingTest, OpenSurfaceIsRefusedWithItsBoundaryEdges) {
  Surface open = Cube();
  open.F.conservativeResize(11, 3);  // one triangle of the top missing: 3 boundary edges
  const std::string message = Refusal(open);
  EXPECT_NE(message.find("3 boundary edges: the surface is open"), std::string::npos) << message;
  // The example edge is given by its corners' positions.
  EXPECT_NE(message.find("the edge ("), std::string::npos) << message;
}

TEST(MeshingTest, SelfIntersectingSurfaceIsRefusedNamingTriangles) {
  // Two cubes overlapping by half: their faces cross.
  const Surface overlapping = Join(Cube(), Cube(Eigen::Vector3d(0.5, 0.5, 0.5)));
  std::string message = Refusal(overlapping);
  EXPECT_NE(message.find("self-intersections"), std::string::npos) << message;
  EXPECT_NE(message.find("cross"), std::string::npos) << message;
  EXPECT_NE(message.find("triangles "), std::string::npos) << message;

  // The top corner (1,1,1) pulled down through the bottom face: its triangles cross the
  // bottom's (topologically still a closed, consistently oriented surface).
  Surface folded = Cube();
  folded.V.row(7) << 0.5, 0.5, -1.0;
  message = Refusal(folded);
  EXPECT_NE(message.find("self-intersections"), std::string::npos) << message;

  // Two cubes touching along a face (not sharing vertices): they touch, which TetGen cannot
  // mesh as two solids.
  const Surface touching = Join(Cube(), Cube(Eigen::Vector3d(1, 0.25, 0.25), 0.5));
  message = Refusal(touching);
  EXPECT_NE(message.find("touch"), std::string::npos) << message;

  // With the check off, TetGen itself stops on the crossing.
  MeshingOptions unchecked;
  unchecked.check_self_intersections = false;
  message = Refusal(overlapping, unchecked);
  EXPECT_NE(message.find("TetGen"), std::string::npos) << message;
}

TEST(MeshingTest, NonManifoldAndInconsistentSurfacesAreRefused) {
  // Two cubes sharing an edge: after merging, that edge is in 4 triangles.
  std::string message = Refusal(Join(Cube(), Cube(Eigen::Vector3d(1, 1, 0))));
  EXPECT_NE(message.find("edges shared by more than two triangles (non-manifold)"),
            std::string::npos)
      << message;
  // Two cubes sharing a corner: one vertex, two fans.
  message = Refusal(Join(Cube(), Cube(Eigen::Vector3d(1, 1, 1))));
  EXPECT_NE(message.find("1 vertices where separate sheets"), std::string::npos) << message;
  // One triangle flipped: its three edges run the same way as their neighbours'.
  Surface flipped = Cube();
  flipped.F.row(3) = Eigen::RowVector3i(Cube().F(3, 0), Cube().F(3, 2), Cube().F(3, 1));
  message = Refusal(flipped);
  EXPECT_NE(message.find("3 edges whose two triangles are oriented inconsistently"),
            std::string::npos)
      << message;
  // A zero-area triangle (a corner repeated).
  Surface sliver = Cube();
  sliver.F.conservativeResize(13, 3);
  sliver.F.row(12) << 0, 1, 1;
  message = Refusal(sliver);
  EXPECT_NE(message.find("1 zero-area triangles"), std::string::npos) << message;
  // A closed sheet with no volume: a triangle and its reverse. The self-intersection check
  // calls them coincident; without it, the volume check refuses them.
  Surface pillow;
  pillow.V = Cube().V.topRows(3);
  pillow.F.resize(2, 3);
  pillow.F << 0, 1, 2, 0, 2, 1;
  message = Refusal(pillow);
  EXPECT_NE(message.find("coincide"), std::string::npos) << message;
  MeshingOptions unchecked;
  unchecked.check_self_intersections = false;
  message = Refusal(pillow, unchecked);
  EXPECT_NE(message.find("encloses no volume"), std::string::npos) << message;
  // Out-of-range indices and non-finite coordinates.
  Surface bad = Cube();
  bad.F(5, 1) = 8;
  message = Refusal(bad);
  EXPECT_NE(message.find("triangle 5 refers to vertex 8"), std::string::npos) << message;
  bad = Cube();
  bad.V(2, 1) = std::nan("");
  message = Refusal(bad);
  EXPECT_NE(message.find("vertex 2 is not finite"), std::string::npos) << message;
}

TEST(MeshingTest, SelfIntersectionCheckAgreesWithTetGen) {
  // Spheres with a few vertices pushed at random, some far enough to fold the surface
  // through itself. Whatever the check refuses, TetGen (without the check) must fail on too,
  // and whatever it accepts TetGen must mesh: no false alarm, no miss, by TetGen's own
  // judgement (docs/notes/2026-11-28-figures-from-code-comments.md).
  std::mt19937 rng(7);
  std::normal_distribution<double> push(0.0, 0.5);
  int refused = 0, accepted = 0;
  for (int i = 0; i < 30; ++i) {
    Surface s = Icosphere(1.0, 2);
    std::uniform_int_distribution<int> pick(0, static_cast<int>(s.V.rows()) - 1);
    for (int k = 0; k <= i % 3; ++k)
      s.V.row(pick(rng)) += Eigen::RowVector3d(push(rng), push(rng), push(rng));
    MeshingOptions checked, unchecked;
    checked.edge_length = unchecked.edge_length = 0.5;
    unchecked.check_self_intersections = false;
    TetMesh mesh;
    const Status with_check = TetrahedralizeSurface(s.V, s.F, checked, &mesh, nullptr, "sphere");
    const Status tetgen_alone =
        TetrahedralizeSurface(s.V, s.F, unchecked, &mesh, nullptr, "sphere");
    EXPECT_EQ(with_check.ok(), tetgen_alone.ok())
        << "case " << i << ": with the check: " << with_check.message()
        << "\nTetGen alone: " << tetgen_alone.message();
    (with_check.ok() ? accepted : refused) += 1;
  }
  // Both kinds occurred, so the comparison meant something.
  EXPECT_GT(refused, 0);
  EXPECT_GT(accepted, 0);
}

TEST(MeshingTest, RealSurfaces) {
  // Public surfaces beside the repository when present (not part of it): the Bunny is
  // clean; the dragon has duplicated triangles; the smoothed liver folds through itself in
  // 7 places (TetGen's -d finds the same 7 pairs).
  const std::string dir = FEMREG_SHARED_MESHES_DIR;
  if (!fs::exists(dir + "/Bunny.stl")) GTEST_SKIP() << dir << " does not exist";
  Surface s;
  ASSERT_TRUE(ReadSurface(dir + "/Bunny.stl", &s.V, &s.F).ok());
  MeshingOptions options;
  options.edge_length = 1.0;  // the Bunny is about 5 x 5 x 4 (units of the file)
  TetMesh mesh;
  MeshingReport report;
  Status status = TetrahedralizeSurface(s.V, s.F, options, &mesh, &report, "Bunny.stl");
  ASSERT_TRUE(status.ok()) << status.message();
  ExpectValidMesh(mesh);
  EXPECT_NEAR(report.mesh_volume, report.surface_volume, 1e-12 * report.surface_volume);

  ASSERT_TRUE(ReadSurface(dir + "/dragon.obj", &s.V, &s.F).ok());
  status = TetrahedralizeSurface(s.V, s.F, options, &mesh, &report, "dragon.obj");
  ASSERT_FALSE(status.ok());
  EXPECT_NE(status.message().find("non-manifold"), std::string::npos) << status.message();
  EXPECT_NE(status.message().find("coincide"), std::string::npos) << status.message();

  ASSERT_TRUE(ReadSurface(dir + "/liver-smooth.obj", &s.V, &s.F).ok());
  status = TetrahedralizeSurface(s.V, s.F, options, &mesh, &report, "liver-smooth.obj");
  ASSERT_FALSE(status.ok());
  EXPECT_NE(status.message().find("7 pairs of triangles that cross"), std::string::npos)
      << status.message();
}

TEST(MeshingTest, TooFineATargetIsRefusedBeforeTetGenRuns) {
  const Surface cube = Cube();
  MeshingOptions options;
  options.edge_length = 1e-4;  // at least 7e12 tets
  const std::string message = Refusal(cube, options);
  EXPECT_NE(message.find("max_tets"), std::string::npos) << message;
}

TEST(MeshingTest, WrittenMeshesReadBackInEveryFormat) {
  TempDir dir;
  const Surface two = Join(Cube(), Cube(Eigen::Vector3d(2, 0, 0)));
  MeshingOptions options;
  options.edge_length = 0.3;
  TetMesh mesh;
  ASSERT_TRUE(TetrahedralizeSurface(two.V, two.F, options, &mesh, nullptr).ok());
  for (const char* ext : {".vtu", ".msh", ".mesh", ".vtk"}) {
    const std::string path = dir.path() + "/out" + ext;
    Status s = WriteTetMesh(path, mesh);
    ASSERT_TRUE(s.ok()) << s.message();
    TetMesh back;
    s = ReadTetMesh(path, &back);
    ASSERT_TRUE(s.ok()) << ext << ": " << s.message();
    EXPECT_EQ(back.num_vertices(), mesh.num_vertices()) << ext;
    EXPECT_EQ(back.num_tets(), mesh.num_tets()) << ext;
    EXPECT_EQ(back.tets, mesh.tets) << ext;
    EXPECT_EQ(back.region, mesh.region) << ext;
    // Text formats print 17 significant digits and VTU stores doubles: positions come back
    // to the last bit or so; 1e-14 leaves room for a reader's decimal conversion.
    EXPECT_LT((back.rest - mesh.rest).cwiseAbs().maxCoeff(), 1e-14) << ext;
  }
  // Unknown extensions and folders that do not exist are refused, and nothing is left.
  EXPECT_FALSE(WriteTetMesh(dir.path() + "/out.stl", mesh).ok());
  const Status s = WriteTetMesh(dir.path() + "/no/such/folder/out.vtk", mesh);
  EXPECT_FALSE(s.ok());
  EXPECT_FALSE(fs::exists(dir.path() + "/out.stl"));
}

#ifdef FEMREG_CLI_PATH
// Runs the command line; returns its exit code and what it printed.
int RunCli(const std::string& args, std::string* out, std::string* err) {
  TempDir dir("femreg_meshing_cli");
  const std::string o = dir.path() + "/stdout", e = dir.path() + "/stderr";
  const int rc =
      std::system((std::string(FEMREG_CLI_PATH) + " " + args + " > " + o + " 2> " + e).c_str());
  if (out != nullptr) *out = ReadAll(o);
  if (err != nullptr) *err = ReadAll(e);
  return WIFEXITED(rc) ? WEXITSTATUS(rc) : -1;
}

TEST(MeshCliTest, MeshesRefusesToOverwriteAndReportsErrors) {
  TempDir dir;
  const std::string cube = dir.path() + "/cube.obj";
  WriteObj(cube, Cube());
  const std::string out_path = dir.path() + "/cube.msh";
  std::string out, err;
  ASSERT_EQ(RunCli("mesh " + cube + " --out " + out_path + " --edge-length 0.25", &out, &err), 0)
      << err;
  EXPECT_NE(out.find("8 vertices, 12 triangles"), std::string::npos) << out;
  EXPECT_NE(out.find("tetrahedra"), std::string::npos) << out;
  EXPECT_NE(out.find("dihedral angles"), std::string::npos) << out;
  TetMesh mesh;
  ASSERT_TRUE(ReadTetMesh(out_path, &mesh).ok());
  EXPECT_NEAR(RestVolume(mesh), 1.0, 1e-12);

  // A second run refuses to overwrite, and the file stays as it was.
  const std::string before = ReadAll(out_path);
  EXPECT_EQ(RunCli("mesh " + cube + " --out " + out_path + " --edge-length 0.5", &out, &err), 1);
  EXPECT_NE(err.find("exists; pass --force"), std::string::npos) << err;
  EXPECT_EQ(ReadAll(out_path), before);
  // --force overwrites (a coarser mesh now).
  EXPECT_EQ(
      RunCli("mesh " + cube + " --out " + out_path + " --edge-length 0.5 --force", &out, &err), 0)
      << err;
  TetMesh coarser;
  ASSERT_TRUE(ReadTetMesh(out_path, &coarser).ok());
  EXPECT_LT(coarser.num_tets(), mesh.num_tets());

  // --json: one object with the counts; --scale multiplies the coordinates.
  const std::string json_path = dir.path() + "/cube.vtu";
  ASSERT_EQ(RunCli("mesh " + cube + " --out " + json_path + " --scale 0.001 --json", &out, &err), 0)
      << err;
  EXPECT_EQ(out.rfind("{", 0), 0u) << out;
  EXPECT_NE(out.find("\"ok\": true"), std::string::npos) << out;
  EXPECT_NE(out.find("\"tetrahedra\": "), std::string::npos) << out;
  ASSERT_TRUE(ReadTetMesh(json_path, &mesh).ok());
  EXPECT_NEAR(RestVolume(mesh), 1e-9, 1e-21);

  // An open surface: exit 1, the reason on stderr, nothing written.
  Surface open = Cube();
  open.F.conservativeResize(11, 3);
  const std::string open_path = dir.path() + "/open.obj";
  WriteObj(open_path, open);
  const std::string not_written = dir.path() + "/open.vtk";
  EXPECT_EQ(RunCli("mesh " + open_path + " --out " + not_written, &out, &err), 1);
  EXPECT_NE(err.find(open_path), std::string::npos) << err;
  EXPECT_NE(err.find("boundary edges"), std::string::npos) << err;
  EXPECT_FALSE(fs::exists(not_written));
  EXPECT_EQ(RunCli("mesh " + open_path + " --out " + not_written + " --json", &out, &err), 1);
  EXPECT_NE(out.find("\"ok\": false"), std::string::npos) << out;

  // An unknown output format is refused before any work; bad option values by CLI11.
  EXPECT_EQ(RunCli("mesh " + cube + " --out " + dir.path() + "/cube.stl", &out, &err), 1);
  EXPECT_NE(err.find("unknown mesh format"), std::string::npos) << err;
  EXPECT_NE(RunCli("mesh " + cube + " --out " + dir.path() + "/x.vtu --quality 0.5", &out, &err),
            0);
  EXPECT_NE(RunCli("mesh " + cube + " --out " + dir.path() + "/x.vtu --edge-length -1", &out, &err),
            0);
  EXPECT_FALSE(fs::exists(dir.path() + "/x.vtu"));
  // --help explains the options and their units.
  ASSERT_EQ(RunCli("mesh --help", &out, &err), 0);
  for (const char* option : {"--edge-length", "--quality", "--max-volume", "--scale", "--force",
                             "--json", "--keep-surface", "millimetres"}) {
    EXPECT_NE(out.find(option), std::string::npos) << option;
  }
}
#endif  // FEMREG_CLI_PATH

}  // namespace
}  // namespace femreg
