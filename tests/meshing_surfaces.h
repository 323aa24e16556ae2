// What the meshing tests share (meshing_test.cc, meshing_checks_test.cc,
// surface_files_test.cc, mesh_cli_test.cc): surfaces made in code (a cube, an icosphere),
// their writers (OBJ, binary STL, PLY) and the checks every mesh must pass.
#ifndef FEMREG_TESTS_MESHING_SURFACES_H_
#define FEMREG_TESTS_MESHING_SURFACES_H_

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
namespace meshing_testing {

namespace fs = std::filesystem;
using testing_util::TempDir;

constexpr double kPi = 3.14159265358979323846;

struct Surface {
  Vertices V;
  Triangles F;
};

// The unit cube [origin, origin + size]^3, 12 triangles facing outwards.
inline Surface Cube(const Eigen::Vector3d& origin = Eigen::Vector3d::Zero(), double size = 1.0) {
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
inline Surface Icosphere(double radius, int levels) {
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
inline Surface Join(const Surface& a, const Surface& b, bool flip_b = false) {
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
inline double EnclosedVolume(const Surface& s) {
  double v = 0.0;
  for (int t = 0; t < s.F.rows(); ++t) {
    const Eigen::Vector3d a = s.V.row(s.F(t, 0)), b = s.V.row(s.F(t, 1)), c = s.V.row(s.F(t, 2));
    v += a.dot(b.cross(c)) / 6.0;
  }
  return v;
}

inline void WriteObj(const std::string& path, const Surface& s) {
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
inline void WriteBinaryStl(const std::string& path, const Surface& s) {
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

inline void WritePly(const std::string& path, const Surface& s, bool binary) {
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

inline std::string ReadAll(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  return std::string((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
}

// What every mesh TetrahedralizeSurface returns must satisfy.
inline void ExpectValidMesh(const TetMesh& mesh) {
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
inline double MeanEdge(const TetMesh& mesh) {
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

// The message of a surface that must be refused.
inline std::string Refusal(const Surface& s, const MeshingOptions& options = MeshingOptions()) {
  TetMesh mesh;
  MeshingReport report;
  const Status status = TetrahedralizeSurface(s.V, s.F, options, &mesh, &report, "bad_surface.stl");
  EXPECT_FALSE(status.ok());
  EXPECT_EQ(mesh.num_tets(), 0);
  EXPECT_EQ(status.message().rfind("bad_surface.stl: ", 0), 0u) << status.message();
  return status.message();
}

}  // namespace meshing_testing
}  // namespace femreg

#endif  // FEMREG_TESTS_MESHING_SURFACES_H_
