// What the forward tests share (forward_test.cc, forward_tangent_test.cc,
// forward_forces_test.cc): a box of Kuhn tetrahedra (MakeTestBox), the clamped cantilever with
// a tip load and its material, the quasi-static solve with one model, and Timoshenko's tip
// deflection.
#ifndef FEMREG_TESTS_FORWARD_SETUP_H_
#define FEMREG_TESTS_FORWARD_SETUP_H_

#include <gtest/gtest.h>

#include <cmath>
#include <string>
#include <vector>

#include "femreg/fem.h"
#include "femreg/forward.h"
#include "femreg/mesh.h"

namespace femreg {
namespace forward_testing {

// A box [0, size] of nx * ny * nz cubes, each split into the 6 Kuhn tetrahedra around its
// main diagonal (conforming across cubes), finalized.
inline TetMesh MakeTestBox(const Eigen::Vector3d& size, int nx, int ny, int nz) {
  TetMesh mesh;
  auto id = [&](int i, int j, int k) { return (k * (ny + 1) + j) * (nx + 1) + i; };
  mesh.rest.resize((nx + 1) * (ny + 1) * (nz + 1), 3);
  for (int k = 0; k <= nz; ++k)
    for (int j = 0; j <= ny; ++j)
      for (int i = 0; i <= nx; ++i)
        mesh.rest.row(id(i, j, k)) << size.x() * i / nx, size.y() * j / ny, size.z() * k / nz;
  static const int kPerm[6][3] = {{0, 1, 2}, {0, 2, 1}, {1, 0, 2}, {1, 2, 0}, {2, 0, 1}, {2, 1, 0}};
  mesh.tets.resize(6 * nx * ny * nz, 4);
  int t = 0;
  for (int k = 0; k < nz; ++k)
    for (int j = 0; j < ny; ++j)
      for (int i = 0; i < nx; ++i)
        for (const auto& p : kPerm) {
          int c[3] = {i, j, k};
          mesh.tets(t, 0) = id(c[0], c[1], c[2]);
          for (int s = 0; s < 3; ++s) {
            ++c[p[s]];
            mesh.tets(t, s + 1) = id(c[0], c[1], c[2]);
          }
          ++t;
        }
  const Status status = FinalizeMesh(&mesh, "test box");
  EXPECT_TRUE(status.ok()) << status.message();
  return mesh;
}

constexpr double kLength = 1.0;
constexpr double kHeight = 0.1;
constexpr double kYoungs = 1e6;
constexpr double kPoisson = 0.3;

inline Material BeamMaterial(double youngs_modulus = kYoungs) {
  Material m;
  m.youngs_modulus = youngs_modulus;
  m.poisson_ratio = kPoisson;
  m.density = 1000.0;
  return m;
}

// A cantilever along x with n cells across the h by h section and 10 n along, clamped at
// x = 0, with a total tip load spread evenly over the x = L face vertices.
struct Cantilever {
  TetMesh mesh;
  ForwardProblem problem;
  std::vector<int> tip;
};

inline Cantilever MakeCantilever(int n, const Eigen::Vector3d& tip_load) {
  Cantilever c;
  c.mesh = MakeTestBox(Eigen::Vector3d(kLength, kHeight, kHeight), 10 * n, n, n);
  for (int v = 0; v < c.mesh.num_vertices(); ++v) {
    if (c.mesh.rest(v, 0) < 1e-9) c.problem.clamped.push_back(v);
    if (c.mesh.rest(v, 0) > kLength - 1e-9) c.tip.push_back(v);
  }
  for (int v : c.tip) c.problem.nodal_loads.push_back({v, tip_load / double(c.tip.size())});
  return c;
}

inline Eigen::Vector3d MeanDisplacement(const TetMesh& mesh, const std::vector<int>& vertices) {
  Eigen::Vector3d sum = Eigen::Vector3d::Zero();
  for (int v : vertices) sum += (mesh.x.row(v) - mesh.rest.row(v)).transpose();
  return sum / double(vertices.size());
}

inline double Volume(const TetMesh& mesh, const Vertices& x) {
  double volume = 0.0;
  for (int t = 0; t < mesh.num_tets(); ++t)
    volume += SignedTetVolume(x.row(mesh.tets(t, 0)), x.row(mesh.tets(t, 1)),
                              x.row(mesh.tets(t, 2)), x.row(mesh.tets(t, 3)));
  return volume;
}

inline ForwardSummary Solve(const ForwardProblem& problem, ElasticModelType type, TetMesh* mesh,
                            int load_steps = 1, double youngs_modulus = kYoungs) {
  ElasticModel model;
  model.Build(*mesh, type, BeamMaterial(youngs_modulus));
  ForwardOptions options;
  options.load_steps = load_steps;
  ForwardSummary summary;
  SolveQuasiStatic(problem, options, &model, mesh, &summary);
  return summary;
}

// "4, 3, 3": Newton iterations per load step.
inline std::string IterationCounts(const ForwardSummary& summary) {
  std::string out;
  for (const ForwardLoadStep& step : summary.load_steps)
    out += (out.empty() ? "" : ", ") + std::to_string(step.iterations);
  return out;
}

// Timoshenko deflection of a cantilever of square section under a tip load P.
inline double TimoshenkoTip(double P) {
  const double I = std::pow(kHeight, 4) / 12.0, A = kHeight * kHeight;
  const double G = kYoungs / (2.0 * (1.0 + kPoisson));
  const double kappa = 10.0 * (1.0 + kPoisson) / (12.0 + 11.0 * kPoisson);
  return P * std::pow(kLength, 3) / (3.0 * kYoungs * I) + P * kLength / (kappa * G * A);
}

}  // namespace forward_testing
}  // namespace femreg

#endif  // FEMREG_TESTS_FORWARD_SETUP_H_
