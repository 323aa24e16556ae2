// Tests of the forward quasi-static solve against beam theory, rotation equivariance,
// large-deformation behaviour of corotational vs linear FEM, and failure modes; the
// consistent corotational tangent (element and assembled) against finite differences, and
// Newton's quadratic convergence with it; femreg simulate's report.
#include <dlfcn.h>
#include <gtest/gtest.h>
#include <sys/wait.h>

#include <Eigen/Eigenvalues>
#include <Eigen/Geometry>
#include <Eigen/SparseCholesky>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <random>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

#include "femreg/fem.h"
#include "femreg/forward.h"
#include "femreg/io.h"
#include "femreg/mesh.h"
#include "femreg_test_config.h"

namespace femreg {
namespace {

// A box [0, size] of nx * ny * nz cubes, each split into the 6 Kuhn tetrahedra around its
// main diagonal (conforming across cubes), finalized.
TetMesh MakeTestBox(const Eigen::Vector3d& size, int nx, int ny, int nz) {
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

Material BeamMaterial(double youngs_modulus = kYoungs) {
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

Cantilever MakeCantilever(int n, const Eigen::Vector3d& tip_load) {
  Cantilever c;
  c.mesh = MakeTestBox(Eigen::Vector3d(kLength, kHeight, kHeight), 10 * n, n, n);
  for (int v = 0; v < c.mesh.num_vertices(); ++v) {
    if (c.mesh.rest(v, 0) < 1e-9) c.problem.clamped.push_back(v);
    if (c.mesh.rest(v, 0) > kLength - 1e-9) c.tip.push_back(v);
  }
  for (int v : c.tip) c.problem.nodal_loads.push_back({v, tip_load / double(c.tip.size())});
  return c;
}

Eigen::Vector3d MeanDisplacement(const TetMesh& mesh, const std::vector<int>& vertices) {
  Eigen::Vector3d sum = Eigen::Vector3d::Zero();
  for (int v : vertices) sum += (mesh.x.row(v) - mesh.rest.row(v)).transpose();
  return sum / double(vertices.size());
}

double Volume(const TetMesh& mesh, const Vertices& x) {
  double volume = 0.0;
  for (int t = 0; t < mesh.num_tets(); ++t)
    volume += SignedTetVolume(x.row(mesh.tets(t, 0)), x.row(mesh.tets(t, 1)),
                              x.row(mesh.tets(t, 2)), x.row(mesh.tets(t, 3)));
  return volume;
}

ForwardSummary Solve(const ForwardProblem& problem, ElasticModelType type, TetMesh* mesh,
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
std::string IterationCounts(const ForwardSummary& summary) {
  std::string out;
  for (const ForwardLoadStep& step : summary.load_steps)
    out += (out.empty() ? "" : ", ") + std::to_string(step.iterations);
  return out;
}

// Timoshenko deflection of a cantilever of square section under a tip load P.
double TimoshenkoTip(double P) {
  const double I = std::pow(kHeight, 4) / 12.0, A = kHeight * kHeight;
  const double G = kYoungs / (2.0 * (1.0 + kPoisson));
  const double kappa = 10.0 * (1.0 + kPoisson) / (12.0 + 11.0 * kPoisson);
  return P * std::pow(kLength, 3) / (3.0 * kYoungs * I) + P * kLength / (kappa * G * A);
}

TEST(ForwardOptions, IsValidNamesTheField) {
  ForwardOptions options;
  std::string error;
  EXPECT_TRUE(options.IsValid(&error));
  options.load_steps = 0;
  EXPECT_FALSE(options.IsValid(&error));
  EXPECT_NE(error.find("load_steps"), std::string::npos);
  options = ForwardOptions();
  options.min_step = 0.0;
  EXPECT_FALSE(options.IsValid(&error));
  EXPECT_NE(error.find("min_step"), std::string::npos);
  options = ForwardOptions();
  options.relative_tolerance = std::nan("");
  EXPECT_FALSE(options.IsValid(&error));
  EXPECT_NE(error.find("relative_tolerance"), std::string::npos);
}

TEST(ForwardSummary, StartsNotRun) {
  ForwardSummary summary;
  EXPECT_EQ(summary.termination, ForwardTermination::kNotRun);
  EXPECT_FALSE(summary.IsSolutionUsable());
  EXPECT_STREQ(ToString(ForwardTermination::kFactorizationFailed), "FACTORIZATION_FAILED");
}

// Small load: the tip deflection converges toward Timoshenko beam theory on refinement.
TEST(SolveQuasiStatic, CantileverConvergesToTimoshenko) {
  const double P = 0.025;  // N: about 1 mm of deflection, 1e-3 L
  const double expected = TimoshenkoTip(P);
  double previous_error = 1e9;
  for (int n : {2, 4, 6, 8}) {
    Cantilever c = MakeCantilever(n, Eigen::Vector3d(0, 0, -P));
    const ForwardSummary summary = Solve(c.problem, ElasticModelType::kCorotational, &c.mesh);
    ASSERT_EQ(summary.termination, ForwardTermination::kConverged) << summary.FullReport();
    const double tip = -MeanDisplacement(c.mesh, c.tip).z();
    const double error = std::abs(tip - expected) / expected;
    std::printf("cantilever %2d x %d x %d cells, %5d vertices: tip %.6e m, Timoshenko %.6e m, "
                "relative error %.2f%% (%d Newton iterations)\n",
                10 * n, n, n, c.mesh.num_vertices(), tip, expected, 100.0 * error,
                summary.NumNewtonIterations());
    EXPECT_LT(error, previous_error) << "n = " << n;
    previous_error = error;
    EXPECT_LT(tip, expected * 1.01);  // linear tets are too stiff, never too soft
  }
  // Linear tets lock in bending; the errors per refinement:
  // docs/notes/2026-11-28-figures-from-code-comments.md.
  EXPECT_LT(previous_error, 0.08);
}

// Large load: corotational stays bounded; small-strain linear FEM over-predicts and grows
// the volume.
TEST(SolveQuasiStatic, LargeTipLoadCorotationalVsLinear) {
  const double P = 16.0;  // Timoshenko: about 0.64 L, this coarse mesh (linear): about 0.45 L
  Cantilever corot = MakeCantilever(3, Eigen::Vector3d(0, 0, -P));
  Cantilever linear = corot;
  const ForwardSummary sc = Solve(corot.problem, ElasticModelType::kCorotational, &corot.mesh, 5);
  const ForwardSummary sl = Solve(linear.problem, ElasticModelType::kLinear, &linear.mesh);
  ASSERT_EQ(sc.termination, ForwardTermination::kConverged) << sc.FullReport();
  ASSERT_EQ(sl.termination, ForwardTermination::kConverged) << sl.FullReport();
  const Eigen::Vector3d uc = MeanDisplacement(corot.mesh, corot.tip);
  const Eigen::Vector3d ul = MeanDisplacement(linear.mesh, linear.tip);
  const double v0 = RestVolume(corot.mesh);
  const double vc = Volume(corot.mesh, corot.mesh.x) / v0 - 1.0;
  const double vl = Volume(linear.mesh, linear.mesh.x) / v0 - 1.0;
  std::printf("large load %.1f N: corotational tip (%.4f, %.4f) m, volume change %.3f%%, "
              "Newton iterations per load step [%s]; linear tip (%.4f, %.4f) m, volume change "
              "%.3f%%\n",
              P, uc.x(), uc.z(), 100 * vc, IterationCounts(sc).c_str(), ul.x(), ul.z(), 100 * vl);
  EXPECT_GT(-uc.z(), 0.2 * kLength);
  EXPECT_LT(-uc.z(), -ul.z());   // the linear model over-predicts the deflection
  EXPECT_LT(uc.x(), -0.02);      // the bent beam shortens along x
  EXPECT_NEAR(ul.x(), 0.0, 1e-3);  // ... the linear one does not
  // The tip stays on the circle of radius L around the clamp.
  const Eigen::Vector3d tip_position = Eigen::Vector3d(kLength, 0.5 * kHeight, 0.5 * kHeight) + uc;
  EXPECT_LT((tip_position - Eigen::Vector3d(0, 0.5 * kHeight, 0.5 * kHeight)).norm(), 1.01 * kLength);
  EXPECT_LT(std::abs(vc), 0.005);
  EXPECT_GT(vl, 2.0 * std::abs(vc) + 0.005);
}

Eigen::Matrix3d AxisRotation(int axis, double angle) {
  return Eigen::AngleAxisd(angle, Eigen::Vector3d::Unit(axis)).toRotationMatrix();
}

// The whole problem rotated by 90 degrees about x, y or z gives the rotated answer.
TEST(SolveQuasiStatic, RotatedBeamGivesRotatedAnswer) {
  const Eigen::Vector3d load(0, 0.3, -2.0);
  Cantilever base = MakeCantilever(1, load);
  const ForwardSummary s0 = Solve(base.problem, ElasticModelType::kCorotational, &base.mesh, 2);
  ASSERT_EQ(s0.termination, ForwardTermination::kConverged) << s0.FullReport();
  const double scale = (base.mesh.x - base.mesh.rest).cwiseAbs().maxCoeff();
  for (int axis = 0; axis < 3; ++axis) {
    const Eigen::Matrix3d Q = AxisRotation(axis, M_PI / 2);
    TetMesh mesh;
    mesh.rest = base.mesh.rest * Q.transpose();
    mesh.tets = MakeTestBox(Eigen::Vector3d(kLength, kHeight, kHeight), 10, 1, 1).tets;
    ASSERT_TRUE(FinalizeMesh(&mesh, "rotated").ok());
    ForwardProblem problem = base.problem;
    for (auto& l : problem.nodal_loads) l.second = Q * l.second;
    const ForwardSummary s = Solve(problem, ElasticModelType::kCorotational, &mesh, 2);
    ASSERT_EQ(s.termination, ForwardTermination::kConverged) << s.FullReport();
    const Vertices expected = base.mesh.x * Q.transpose();
    const double error = (mesh.x - expected).cwiseAbs().maxCoeff() / scale;
    EXPECT_LT(error, 1e-6) << "axis " << axis;
  }
}

// Gravity sag vs the distributed-load formula w L^4 / (8 E I) (+ the shear term).
TEST(SolveQuasiStatic, GravitySag) {
  Cantilever c = MakeCantilever(6, Eigen::Vector3d::Zero());
  c.problem.nodal_loads.clear();
  c.problem.gravity = Eigen::Vector3d(0, 0, -9.81);
  ComputeLumpedMasses(&c.mesh, 1000.0);
  const double E = 1e9;  // a stiff beam: the sag stays small (about 1.5 mm)
  const ForwardSummary s = Solve(c.problem, ElasticModelType::kCorotational, &c.mesh, 1, E);
  ASSERT_EQ(s.termination, ForwardTermination::kConverged) << s.FullReport();
  const double I = std::pow(kHeight, 4) / 12.0, A = kHeight * kHeight;
  const double w = 1000.0 * 9.81 * A;
  const double G = E / (2.0 * (1.0 + kPoisson));
  const double kappa = 10.0 * (1.0 + kPoisson) / (12.0 + 11.0 * kPoisson);
  const double expected = w * std::pow(kLength, 4) / (8 * E * I) +
                          w * kLength * kLength / (2 * kappa * G * A);
  const double tip = -MeanDisplacement(c.mesh, c.tip).z();
  std::printf("gravity sag: tip %.6e m, beam theory %.6e m, relative error %.2f%%\n", tip,
              expected, 100 * std::abs(tip - expected) / expected);
  EXPECT_NEAR(tip, expected, 0.15 * expected);  // locking, as above
}

// The linear model is one linear solve: it matches a direct solve of the reduced system
// assembled from ElasticModel::AddStiffnessTriplets.
TEST(SolveQuasiStatic, LinearModelIsOneLinearSolve) {
  Cantilever c = MakeCantilever(1, Eigen::Vector3d(0.1, 0.2, -0.5));
  TetMesh mesh = c.mesh;
  const ForwardSummary s = Solve(c.problem, ElasticModelType::kLinear, &mesh);
  ASSERT_EQ(s.termination, ForwardTermination::kConverged) << s.FullReport();
  EXPECT_EQ(s.NumNewtonIterations(), 1);  // K is the exact tangent: one step

  ElasticModel model;
  model.Build(c.mesh, ElasticModelType::kLinear, BeamMaterial());
  std::vector<Eigen::Triplet<double>> triplets;
  model.AddStiffnessTriplets(&triplets);
  const int n = 3 * c.mesh.num_vertices();
  Eigen::SparseMatrix<double> K(n, n);
  K.setFromTriplets(triplets.begin(), triplets.end());
  std::vector<int> free_index(n, 0);
  for (int v : c.problem.clamped)
    for (int i = 0; i < 3; ++i) free_index[3 * v + i] = -1;
  int nf = 0;
  for (int d = 0; d < n; ++d)
    free_index[d] = free_index[d] == 0 ? nf++ : -1;
  std::vector<Eigen::Triplet<double>> reduced;
  for (int col = 0; col < n; ++col)
    for (Eigen::SparseMatrix<double>::InnerIterator it(K, col); it; ++it)
      if (free_index[it.row()] >= 0 && free_index[col] >= 0)
        reduced.emplace_back(free_index[it.row()], free_index[col], it.value());
  Eigen::SparseMatrix<double> Kf(nf, nf);
  Kf.setFromTriplets(reduced.begin(), reduced.end());
  Eigen::VectorXd f = Eigen::VectorXd::Zero(nf);
  for (const auto& l : c.problem.nodal_loads)
    for (int i = 0; i < 3; ++i) f(free_index[3 * l.first + i]) += l.second(i);
  Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>> ldlt(Kf);
  const Eigen::VectorXd u = ldlt.solve(f);
  double max_error = 0.0;
  for (int d = 0; d < n; ++d) {
    if (free_index[d] < 0) continue;
    const double ud = mesh.x(d / 3, d % 3) - mesh.rest(d / 3, d % 3);
    max_error = std::max(max_error, std::abs(ud - u(free_index[d])));
  }
  EXPECT_LT(max_error, 1e-9 * u.cwiseAbs().maxCoeff());
}

// Prescribing a 120 degree rigid rotation on the surface moves the interior rigidly and
// costs no energy (corotational); the linear model sees a large strain.
TEST(SolveQuasiStatic, PrescribedRigidRotationOfTheSurface) {
  TetMesh cube = MakeTestBox(Eigen::Vector3d(1, 1, 1), 3, 3, 3);
  const Eigen::Matrix3d Q = Eigen::AngleAxisd(2.0 * M_PI / 3.0, Eigen::Vector3d(1, 2, 3).normalized())
                                .toRotationMatrix();
  const Eigen::Vector3d t(0.3, -0.2, 0.5);
  ForwardProblem problem;
  for (int v : cube.surface_vertices) {
    const Eigen::Vector3d X = cube.rest.row(v).transpose();
    problem.prescribed.push_back({v, Q * X + t - X});
  }
  ASSERT_LT(static_cast<int>(cube.surface_vertices.size()), cube.num_vertices());
  TetMesh linear = cube;
  const ForwardSummary s = Solve(problem, ElasticModelType::kCorotational, &cube, 1);
  ASSERT_EQ(s.termination, ForwardTermination::kConverged) << s.FullReport();
  const Vertices expected = (cube.rest * Q.transpose()).rowwise() + t.transpose();
  EXPECT_LT((cube.x - expected).cwiseAbs().maxCoeff(), 1e-8);
  EXPECT_LT(std::abs(s.final_energy), 1e-9);
  // The linear model also reproduces the affine field, but charges it strain energy.
  const ForwardSummary sl = Solve(problem, ElasticModelType::kLinear, &linear, 1);
  ASSERT_EQ(sl.termination, ForwardTermination::kConverged) << sl.FullReport();
  EXPECT_GT(sl.final_energy, 1e4);
}

TEST(SolveQuasiStatic, FreeFloatingMeshFailsCleanly) {
  TetMesh mesh = MakeTestBox(Eigen::Vector3d(1, 0.2, 0.2), 5, 1, 1);
  ComputeLumpedMasses(&mesh, 1000.0);
  ForwardProblem problem;
  problem.gravity = Eigen::Vector3d(0, 0, -9.81);
  const Vertices before = mesh.x;
  ForwardSummary summary;
  ElasticModel model;
  model.Build(mesh, ElasticModelType::kCorotational, BeamMaterial());
  const Status status = SolveQuasiStatic(problem, ForwardOptions(), &model, &mesh, &summary);
  EXPECT_FALSE(status.ok());
  EXPECT_EQ(summary.termination, ForwardTermination::kFactorizationFailed);
  EXPECT_NE(summary.message.find("float"), std::string::npos) << summary.message;
  EXPECT_FALSE(summary.IsSolutionUsable());
  EXPECT_TRUE(mesh.x.allFinite());
  EXPECT_EQ(mesh.x, before);

  // Two clamped vertices leave a rotation about their axis.
  problem.clamped = {0, 1};
  SolveQuasiStatic(problem, ForwardOptions(), &model, &mesh, &summary);
  EXPECT_EQ(summary.termination, ForwardTermination::kFactorizationFailed) << summary.message;
  EXPECT_NE(summary.message.find("collinear"), std::string::npos) << summary.message;
}

// Two tetrahedra joined at one vertex: each piece is held structurally, but the second
// can swing about the shared vertex. The numeric check must catch it.
TEST(SolveQuasiStatic, MechanismFailsCleanly) {
  TetMesh mesh;
  mesh.rest.resize(7, 3);  // the second tet shares vertex 3 with the first
  mesh.rest << 0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1, 1, 0, 2, 0, 1, 2, 0, 0, 3;
  mesh.tets.resize(2, 4);
  mesh.tets << 0, 1, 2, 3, 3, 4, 5, 6;
  ASSERT_TRUE(FinalizeMesh(&mesh, "hinge").ok());
  ForwardProblem problem;
  problem.clamped = {0, 1, 2};
  problem.nodal_loads = {{6, Eigen::Vector3d(1, 0, 0)}};
  ElasticModel model;
  model.Build(mesh, ElasticModelType::kCorotational, BeamMaterial());
  ForwardSummary summary;
  const Status status = SolveQuasiStatic(problem, ForwardOptions(), &model, &mesh, &summary);
  EXPECT_FALSE(status.ok());
  EXPECT_EQ(summary.termination, ForwardTermination::kFactorizationFailed) << summary.FullReport();
  EXPECT_TRUE(mesh.x.allFinite());
}

TEST(SolveQuasiStatic, InvalidInputs) {
  Cantilever c = MakeCantilever(1, Eigen::Vector3d(0, 0, -1));
  ElasticModel model;
  model.Build(c.mesh, ElasticModelType::kCorotational, BeamMaterial());
  ForwardSummary summary;

  ForwardProblem nan_load = c.problem;
  nan_load.nodal_loads[0].second.x() = std::nan("");
  EXPECT_FALSE(SolveQuasiStatic(nan_load, ForwardOptions(), &model, &c.mesh, &summary).ok());
  EXPECT_EQ(summary.termination, ForwardTermination::kInvalidInput);
  EXPECT_NE(summary.message.find("nodal_loads"), std::string::npos) << summary.message;

  ForwardProblem both = c.problem;
  both.prescribed.push_back({both.clamped[0], Eigen::Vector3d::Zero()});
  SolveQuasiStatic(both, ForwardOptions(), &model, &c.mesh, &summary);
  EXPECT_EQ(summary.termination, ForwardTermination::kInvalidInput);
  EXPECT_NE(summary.message.find("also clamped"), std::string::npos) << summary.message;

  ForwardProblem gravity = c.problem;
  gravity.gravity = Eigen::Vector3d(0, 0, -9.81);
  c.mesh.mass.resize(0);
  SolveQuasiStatic(gravity, ForwardOptions(), &model, &c.mesh, &summary);
  EXPECT_EQ(summary.termination, ForwardTermination::kInvalidInput);
  EXPECT_NE(summary.message.find("mass"), std::string::npos) << summary.message;

  TetMesh nan_mesh = c.mesh;
  nan_mesh.x(3, 1) = std::nan("");
  SolveQuasiStatic(c.problem, ForwardOptions(), &model, &nan_mesh, &summary);
  EXPECT_EQ(summary.termination, ForwardTermination::kInvalidInput);

  ForwardOptions bad;
  bad.max_iterations = 0;
  SolveQuasiStatic(c.problem, bad, &model, &c.mesh, &summary);
  EXPECT_EQ(summary.termination, ForwardTermination::kInvalidInput);
  EXPECT_NE(summary.message.find("max_iterations"), std::string::npos);
}

TEST(SolveQuasiStatic, ReportsIterations) {
  Cantilever c = MakeCantilever(1, Eigen::Vector3d(0, 0, -2));
  // Without the watchdog the line search is monotone: the potential never rises in a step.
  ElasticModel model;
  model.Build(c.mesh, ElasticModelType::kCorotational, BeamMaterial());
  ForwardOptions options;
  options.load_steps = 2;
  options.watchdog_steps = 0;
  ForwardSummary s;
  ASSERT_TRUE(SolveQuasiStatic(c.problem, options, &model, &c.mesh, &s).ok());
  ASSERT_EQ(s.termination, ForwardTermination::kConverged) << s.FullReport();
  ASSERT_GE(s.iterations.size(), 3u);
  EXPECT_EQ(s.iterations.back().load_step, 2);
  for (size_t i = 1; i < s.iterations.size(); ++i) {
    if (s.iterations[i].load_step == s.iterations[i - 1].load_step) {
      EXPECT_LE(s.iterations[i].energy, s.iterations[i - 1].energy + 1e-12);
    }
  }
  // One record per load step; the rows are each step's start plus its Newton iterations.
  ASSERT_EQ(s.load_steps.size(), 2u);
  for (const ForwardLoadStep& step : s.load_steps) {
    EXPECT_EQ(step.termination, ForwardTermination::kConverged);
    EXPECT_GT(step.iterations, 0);
    EXPECT_LE(step.final_residual_norm, 1e-6 * step.initial_residual_norm + 1e-9);
  }
  EXPECT_DOUBLE_EQ(s.load_steps[0].load_factor, 0.5);
  EXPECT_EQ(s.NumNewtonIterations() + 2, static_cast<int>(s.iterations.size()));
  EXPECT_NE(s.BriefReport().find("Newton iterations in 2 load steps ["), std::string::npos)
      << s.BriefReport();
  EXPECT_NE(s.FullReport().find("CONVERGED"), std::string::npos);
  EXPECT_NE(s.BriefReport().find("CONVERGED"), std::string::npos);
  EXPECT_GT(s.max_displacement, 0.0);
  EXPECT_EQ(s.num_free_dofs, 3 * (c.mesh.num_vertices() - static_cast<int>(c.problem.clamped.size())));
}

// ---------------------------------------------------------------------------------------
// The consistent corotational tangent of one element (fem.h's CorotationalTangent).

using Matrix34 = Eigen::Matrix<double, 3, 4>;

// An irregular tetrahedron of about 10 cm.
ElementRest TangentTestRest(double poisson_ratio) {
  Matrix34 X;
  X << 0.0, 0.11, -0.01, 0.02,  //
      0.0, 0.01, 0.09, 0.015,   //
      0.0, -0.02, 0.01, 0.1;
  Material m;
  m.youngs_modulus = 2.0e5;
  m.poisson_ratio = poisson_ratio;
  return BuildElementRest(X, m);
}

// Positions whose deformation gradient is F (plus a translation).
Vector12 PositionsWithGradient(const ElementRest& rest, const Eigen::Matrix3d& F,
                               const Eigen::Vector3d& t) {
  Vector12 x;
  for (int k = 0; k < 4; ++k) x.segment<3>(3 * k) = F * rest.X.segment<3>(3 * k) + t;
  return x;
}

Eigen::Matrix3d RandomRotation(std::mt19937* rng) {
  std::normal_distribution<double> n(0.0, 1.0);
  Eigen::Quaterniond q(n(*rng), n(*rng), n(*rng), n(*rng));
  return q.normalized().toRotationMatrix();
}

// f = -R K (R^T x - X) with R recomputed from x.
Vector12 CorotationalForce(const ElementRest& rest, const Vector12& x) {
  Matrix34 xm;
  for (int k = 0; k < 4; ++k) xm.col(k) = x.segment<3>(3 * k);
  return ElementForce(rest, PolarRotation(DeformationGradient(xm, rest.dm_inv)), x);
}

// -df/dx by central differences.
Matrix12 CentralDifferenceTangent(const ElementRest& rest, const Vector12& x, double h) {
  Matrix12 out;
  for (int j = 0; j < 12; ++j) {
    Vector12 plus = x, minus = x;
    plus(j) += h;
    minus(j) -= h;
    out.col(j) = -(CorotationalForce(rest, plus) - CorotationalForce(rest, minus)) / (2 * h);
  }
  return out;
}

struct TangentCase {
  const char* name;
  Eigen::Vector3d sigma;  // signed singular values of F
};

// Stretched, compressed, mixed, nearly flat and inverted elements, each in random frames
// U, V; plus random gradients Q (I + 0.5 noise) (strains up to about 50%).
std::vector<std::pair<std::string, Eigen::Matrix3d>> TangentStates(std::mt19937* rng) {
  const TangentCase cases[] = {
      {"mild", {1.05, 0.97, 1.01}},
      {"stretched", {1.6, 1.3, 1.1}},
      {"compressed", {0.7, 0.6, 0.5}},
      {"mixed", {1.5, 0.9, 0.6}},
      {"nearly flat", {1.2, 0.8, 1e-3}},
      {"inverted", {1.1, 0.8, -0.3}},
      {"inverted, sigma2 + sigma3 = 0.05", {1.0, 0.3, -0.25}},
  };
  std::vector<std::pair<std::string, Eigen::Matrix3d>> states;
  for (const TangentCase& c : cases) {
    for (int frame = 0; frame < 3; ++frame) {
      states.push_back({c.name, RandomRotation(rng) * c.sigma.asDiagonal() *
                                    RandomRotation(rng).transpose()});
    }
  }
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  while (states.size() < 41) {
    Eigen::Matrix3d A = Eigen::Matrix3d::Identity();
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j < 3; ++j) A(i, j) += 0.5 * u(*rng);
    if (A.determinant() < 0.2) continue;
    states.push_back({"random", RandomRotation(rng) * A});
  }
  return states;
}

TEST(CorotationalTangent, MatchesCentralDifferencesOfTheForce) {
  std::mt19937 rng(14);
  for (double nu : {0.3, 0.49}) {
    const ElementRest rest = TangentTestRest(nu);
    for (const auto& [name, F] : TangentStates(&rng)) {
      const Vector12 x = PositionsWithGradient(rest, F, Eigen::Vector3d(0.3, -0.1, 0.2));
      const Matrix12 tangent = CorotationalTangent(rest, x, TangentProjection::kNone);
      // h = 1e-7 m on 0.1 m coordinates: the truncation error (h^2 / 6 times the third
      // derivative) is about 1e-12 |K| / (sigma_i + sigma_j)^2 and the round-off
      // eps |f| / h about 1e-10 |K|, so 1e-6 of the largest entry leaves a margin of 100
      // even at sigma_i + sigma_j = 0.05; a missing or wrong rotation term is off by 1e-3
      // of it or more (checked below; 6e-3 in the "mixed" state at nu = 0.49, where lambda
      // dominates the largest entry).
      const Matrix12 numeric = CentralDifferenceTangent(rest, x, 1e-7);
      const double scale = tangent.cwiseAbs().maxCoeff();
      EXPECT_LT((tangent - numeric).cwiseAbs().maxCoeff(), 1e-6 * scale)
          << name << ", nu " << nu << "\nF =\n" << F;
      // Not trivially the warped stiffness (else the test could not see the rotation term).
      if (name != "mild") {
        EXPECT_GT((numeric - WarpedStiffness(rest, PolarRotation(F))).cwiseAbs().maxCoeff(),
                  1e-3 * scale)
            << name;
      }
    }
  }
}

TEST(CorotationalTangent, IsSymmetric) {
  std::mt19937 rng(15);
  const ElementRest rest = TangentTestRest(0.45);
  for (const auto& [name, F] : TangentStates(&rng)) {
    const Matrix12 t = CorotationalTangent(
        rest, PositionsWithGradient(rest, F, Eigen::Vector3d::Zero()), TangentProjection::kNone);
    // A sum of symmetric terms (R K R^T and g b b^T): equal up to round-off.
    EXPECT_LT((t - t.transpose()).cwiseAbs().maxCoeff(), 1e-12 * t.cwiseAbs().maxCoeff()) << name;
  }
}

// At rest and under any rigid motion the rotation term vanishes (g_ij = 0 at S = I): the
// tangent is K, rotated.
TEST(CorotationalTangent, IsTheWarpedStiffnessUnderRigidMotion) {
  std::mt19937 rng(16);
  const ElementRest rest = TangentTestRest(0.3);
  const double scale = rest.K.cwiseAbs().maxCoeff();
  const Matrix12 at_rest = CorotationalTangent(rest, rest.X, TangentProjection::kNone);
  EXPECT_LT((at_rest - rest.K).cwiseAbs().maxCoeff(), 1e-12 * scale);
  for (int i = 0; i < 5; ++i) {
    const Eigen::Matrix3d Q = RandomRotation(&rng);
    const Vector12 x = PositionsWithGradient(rest, Q, Eigen::Vector3d(1, 2, 3));
    const Matrix12 t = CorotationalTangent(rest, x, TangentProjection::kNone);
    EXPECT_LT((t - WarpedStiffness(rest, Q)).cwiseAbs().maxCoeff(), 1e-10 * scale);
  }
}

// Compression makes the exact tangent indefinite; the projection clamps exactly those
// twist eigenvalues, so it is PSD, differs from the exact one by a PSD matrix, and equals it
// where nothing is compressed.
TEST(CorotationalTangent, ProjectionIsPsdAndExactWithoutCompression) {
  std::mt19937 rng(17);
  const ElementRest rest = TangentTestRest(0.3);
  const Eigen::Matrix3d U = RandomRotation(&rng), V = RandomRotation(&rng);
  const Vector12 compressed = PositionsWithGradient(
      rest, U * Eigen::Vector3d(0.7, 0.6, 0.5).asDiagonal() * V.transpose(),
      Eigen::Vector3d::Zero());
  ElementTangentInfo info;
  const Matrix12 exact = CorotationalTangent(rest, compressed, TangentProjection::kNone, &info);
  EXPECT_EQ(info.negative_modes, 3);
  EXPECT_EQ(info.degenerate_modes, 0);
  EXPECT_LT(info.min_eigenvalue, 0.0);
  const Matrix12 projected =
      CorotationalTangent(rest, compressed, TangentProjection::kPositiveSemiDefinite);
  const double scale = exact.cwiseAbs().maxCoeff();
  // Eigenvalues to 1e-10 of the largest entry: the round-off of a 12 by 12 eigensolver.
  Eigen::SelfAdjointEigenSolver<Matrix12> e_exact(exact), e_projected(projected),
      e_difference(projected - exact);
  EXPECT_LT(e_exact.eigenvalues().minCoeff(), -1e-3 * scale);
  EXPECT_GT(e_projected.eigenvalues().minCoeff(), -1e-10 * scale);
  EXPECT_GT(e_difference.eigenvalues().minCoeff(), -1e-10 * scale);

  const Vector12 stretched = PositionsWithGradient(
      rest, U * Eigen::Vector3d(1.6, 1.3, 1.1).asDiagonal() * V.transpose(),
      Eigen::Vector3d::Zero());
  const Matrix12 s_exact = CorotationalTangent(rest, stretched, TangentProjection::kNone, &info);
  EXPECT_EQ(info.negative_modes, 0);
  EXPECT_GT(info.min_eigenvalue, 0.0);
  EXPECT_EQ(s_exact,
            CorotationalTangent(rest, stretched, TangentProjection::kPositiveSemiDefinite));
}

// Where sigma_i + sigma_j = 0 the rotation has no derivative: those twist modes keep the
// warped stiffness, and everything stays finite.
TEST(CorotationalTangent, DegenerateElementsStayFinite) {
  const ElementRest rest = TangentTestRest(0.3);
  struct Degenerate {
    const char* name;
    Eigen::Matrix3d F;
    int degenerate_modes;
  };
  Eigen::Matrix3d line = Eigen::Matrix3d::Zero();
  line(0, 0) = 1.2;
  const Degenerate cases[] = {
      {"collapsed to a point", Eigen::Matrix3d::Zero(), 3},
      {"collapsed to a line", line, 1},
      {"inverted, sigma2 = -sigma3", Eigen::Vector3d(1.0, 0.5, -0.5).asDiagonal(), 1},
  };
  for (const Degenerate& c : cases) {
    ElementTangentInfo info;
    const Matrix12 t =
        CorotationalTangent(rest, PositionsWithGradient(rest, c.F, Eigen::Vector3d::Zero()),
                            TangentProjection::kNone, &info);
    EXPECT_TRUE(t.allFinite()) << c.name;
    EXPECT_EQ(info.degenerate_modes, c.degenerate_modes) << c.name;
    EXPECT_LT((t - t.transpose()).cwiseAbs().maxCoeff(), 1e-12 * t.cwiseAbs().maxCoeff()) << c.name;
  }
  Eigen::Matrix3d nan = Eigen::Matrix3d::Identity();
  nan(1, 2) = std::nan("");
  const SignedSvd svd = SignedSingularValueDecomposition(nan);
  EXPECT_TRUE(svd.U.allFinite() && svd.V.allFinite() && svd.sigma.allFinite());
}

TEST(CorotationalTangent, SignedSvdMatchesPolarRotation) {
  std::mt19937 rng(18);
  for (const auto& [name, F] : TangentStates(&rng)) {
    const SignedSvd svd = SignedSingularValueDecomposition(F);
    EXPECT_LT((svd.U * svd.sigma.asDiagonal() * svd.V.transpose() - F).norm(), 1e-12 * F.norm())
        << name;
    EXPECT_LT((svd.U * svd.V.transpose() - PolarRotation(F)).norm(), 1e-12) << name;
    EXPECT_NEAR(svd.U.determinant(), 1.0, 1e-12);
    EXPECT_NEAR(svd.V.determinant(), 1.0, 1e-12);
    EXPECT_EQ(svd.sigma(2) < 0, F.determinant() < 0) << name;
  }
}

TEST(CorotationalTangent, EnergyAndForceInOnePass) {
  std::mt19937 rng(19);
  const ElementRest rest = TangentTestRest(0.3);
  for (const auto& [name, F] : TangentStates(&rng)) {
    const Vector12 x = PositionsWithGradient(rest, F, Eigen::Vector3d(0.1, 0.2, 0.3));
    const Eigen::Matrix3d R = PolarRotation(F);
    Vector12 f;
    const double energy = ElementEnergyAndForce(rest, R, x, &f);
    // The same arithmetic in another order: equal to round-off. u = R^T x - X carries the
    // translation (0.37 m against strains of a few mm) that K u cancels, so the energies
    // agree to about eps |K| |u|^2, 2e-12 of the energy in the mildest state.
    EXPECT_NEAR(energy, ElementEnergy(rest, R, x), 1e-10 * std::abs(energy)) << name;
    EXPECT_LT((f - ElementForce(rest, R, x)).cwiseAbs().maxCoeff(),
              1e-12 * f.cwiseAbs().maxCoeff())
        << name;
  }
}

// ---------------------------------------------------------------------------------------
// The assembled system (EvaluateForwardSystem) and Newton's convergence.

// A bent cantilever (the converged large-load state) with every free vertex moved by up to
// 2 mm: a generic state with large rotations, stretch and compression.
struct BentState {
  Cantilever c;
  ElasticModel model;
  Vertices x;
};

BentState MakeBentState() {
  BentState s;
  s.c = MakeCantilever(1, Eigen::Vector3d(0, 0.5, -6.0));
  s.model.Build(s.c.mesh, ElasticModelType::kCorotational, BeamMaterial());
  TetMesh mesh = s.c.mesh;
  ForwardOptions options;
  options.load_steps = 2;
  ForwardSummary summary;
  EXPECT_TRUE(SolveQuasiStatic(s.c.problem, options, &s.model, &mesh, &summary).ok());
  EXPECT_EQ(summary.termination, ForwardTermination::kConverged) << summary.FullReport();
  std::mt19937 rng(20);
  std::uniform_real_distribution<double> u(-2e-3, 2e-3);
  s.x = mesh.x;
  std::vector<char> clamped(mesh.num_vertices(), 0);
  for (int v : s.c.problem.clamped) clamped[v] = 1;
  for (int v = 0; v < mesh.num_vertices(); ++v)
    if (!clamped[v]) s.x.row(v) += Eigen::RowVector3d(u(rng), u(rng), u(rng));
  return s;
}

Eigen::MatrixXd DenseSystem(const BentState& s, ForwardTangent tangent,
                            Eigen::VectorXd* residual, std::vector<int>* free_dofs) {
  ForwardOptions options;
  options.tangent = tangent;
  Eigen::SparseMatrix<double> matrix;
  const Status status = EvaluateForwardSystem(s.c.problem, options, s.model, s.c.mesh, s.x,
                                              residual, &matrix, free_dofs);
  EXPECT_TRUE(status.ok()) << status.message();
  return Eigen::MatrixXd(matrix);
}

TEST(ForwardSystem, TangentMatchesCentralDifferencesOfTheResidual) {
  const BentState s = MakeBentState();
  Eigen::VectorXd residual;
  std::vector<int> free_dofs;
  const Eigen::MatrixXd full = DenseSystem(s, ForwardTangent::kFull, &residual, &free_dofs);
  const int n = static_cast<int>(free_dofs.size());
  ASSERT_EQ(n, 3 * (s.c.mesh.num_vertices() - static_cast<int>(s.c.problem.clamped.size())));
  ASSERT_EQ(full.rows(), n);
  ForwardOptions options;
  Eigen::MatrixXd numeric(n, n);
  const double h = 1e-7;  // m, on 1 m coordinates
  for (int j = 0; j < n; ++j) {
    Vertices plus = s.x, minus = s.x;
    plus(free_dofs[j] / 3, free_dofs[j] % 3) += h;
    minus(free_dofs[j] / 3, free_dofs[j] % 3) -= h;
    Eigen::VectorXd r_plus, r_minus;
    Eigen::SparseMatrix<double> unused;
    std::vector<int> dofs;
    ASSERT_TRUE(EvaluateForwardSystem(s.c.problem, options, s.model, s.c.mesh, plus, &r_plus,
                                      &unused, &dofs).ok());
    ASSERT_TRUE(EvaluateForwardSystem(s.c.problem, options, s.model, s.c.mesh, minus, &r_minus,
                                      &unused, &dofs).ok());
    for (int i = 0; i < n; ++i)
      numeric(i, j) = (r_plus(free_dofs[i]) - r_minus(free_dofs[i])) / (2 * h);
  }
  const double scale = full.cwiseAbs().maxCoeff();
  // As for one element (the same error terms, summed over a few elements per entry): 1e-6
  // of the largest entry; the rotation term the warped matrix leaves out is 1e-2 of it or
  // more.
  EXPECT_LT((full - numeric).cwiseAbs().maxCoeff(), 1e-6 * scale);
  EXPECT_LT((full - full.transpose()).cwiseAbs().maxCoeff(), 1e-12 * scale);
  Eigen::VectorXd unused_residual;
  const Eigen::MatrixXd warped =
      DenseSystem(s, ForwardTangent::kWarped, &unused_residual, &free_dofs);
  EXPECT_GT((warped - numeric).cwiseAbs().maxCoeff(), 1e-2 * scale);
  // The projected matrix is positive definite (the clamps remove the rigid modes).
  const Eigen::MatrixXd projected =
      DenseSystem(s, ForwardTangent::kProjected, &unused_residual, &free_dofs);
  Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eig(projected);
  EXPECT_GT(eig.eigenvalues().minCoeff(), 0.0);
}

TEST(ForwardSystem, InvalidInputIsAnError) {
  Cantilever c = MakeCantilever(1, Eigen::Vector3d(0, 0, -1));
  ElasticModel model;
  model.Build(c.mesh, ElasticModelType::kCorotational, BeamMaterial());
  Eigen::VectorXd residual;
  Eigen::SparseMatrix<double> matrix;
  std::vector<int> free_dofs;
  Vertices bad = c.mesh.x;
  bad(2, 1) = std::nan("");
  EXPECT_FALSE(EvaluateForwardSystem(c.problem, ForwardOptions(), model, c.mesh, bad, &residual,
                                     &matrix, &free_dofs)
                   .ok());
  ForwardProblem floating;
  const Status status = EvaluateForwardSystem(floating, ForwardOptions(), model, c.mesh,
                                              c.mesh.x, &residual, &matrix, &free_dofs);
  EXPECT_FALSE(status.ok());
  EXPECT_NE(status.message().find("float"), std::string::npos) << status.message();
}

// ---------------------------------------------------------------------------------------
// The forces on the body at a result (EvaluateForwardForces).

// A bar of nu = 0 stretched by u along its axis (clamped at x = 0, its x = L face moved) is
// uniformly strained, which linear tetrahedra represent exactly: the face is pulled with
// E A u / L, the clamp holds with the opposite, and no free vertex needs a support.
TEST(ForwardForces, StretchedBarIsPulledWithEAOverL) {
  const double L = 0.2, h = 0.02, u = 1e-3, E = 1e6;
  for (ElasticModelType type : {ElasticModelType::kLinear, ElasticModelType::kCorotational}) {
    SCOPED_TRACE(type == ElasticModelType::kLinear ? "linear" : "corotational");
    TetMesh mesh = MakeTestBox(Eigen::Vector3d(L, h, h), 10, 2, 2);
    ForwardProblem problem;
    std::vector<char> end(mesh.num_vertices(), 0), clamp(mesh.num_vertices(), 0);
    for (int v = 0; v < mesh.num_vertices(); ++v) {
      if (mesh.rest(v, 0) < 1e-9) {
        problem.clamped.push_back(v);
        clamp[v] = 1;
      } else if (mesh.rest(v, 0) > L - 1e-9) {
        problem.prescribed.push_back({v, Eigen::Vector3d(u, 0, 0)});
        end[v] = 1;
      }
    }
    Material material;
    material.youngs_modulus = E;
    material.poisson_ratio = 0.0;
    ElasticModel model;
    model.Build(mesh, type, material);
    ForwardSummary summary;
    ASSERT_TRUE(SolveQuasiStatic(problem, ForwardOptions(), &model, &mesh, &summary).ok());
    ASSERT_EQ(summary.termination, ForwardTermination::kConverged) << summary.FullReport();
    ForwardForces forces;
    const Status status =
        EvaluateForwardForces(problem, ForwardOptions(), model, mesh, mesh.x, &forces);
    ASSERT_TRUE(status.ok()) << status.message();
    ASSERT_EQ(forces.reactions.rows(), mesh.num_vertices());
    const double pull = E * h * h * u / L;  // N
    Eigen::Vector3d at_end = Eigen::Vector3d::Zero(), at_clamp = Eigen::Vector3d::Zero();
    for (int v = 0; v < mesh.num_vertices(); ++v) {
      const Eigen::Vector3d r = forces.reactions.row(v).transpose();
      if (end[v]) at_end += r;
      if (clamp[v]) at_clamp += r;
      if (!end[v] && !clamp[v]) {
        EXPECT_EQ(r.norm(), 0.0) << "free vertex " << v;
      }
    }
    EXPECT_LT((at_end - Eigen::Vector3d(pull, 0, 0)).norm(), 1e-9 * pull) << at_end.transpose();
    EXPECT_LT((at_clamp + Eigen::Vector3d(pull, 0, 0)).norm(), 1e-9 * pull) << at_clamp.transpose();
    EXPECT_EQ(forces.potential.cwiseAbs().maxCoeff(), 0.0);
    EXPECT_EQ(forces.loads.cwiseAbs().maxCoeff(), 0.0);
  }
}

// Springs from some vertices to fixed points, E = k/2 |x_v - p_v|^2: a potential whose force
// is known in closed form.
class SpringPotential : public ForwardPotential {
 public:
  SpringPotential(std::vector<std::pair<int, Eigen::Vector3d>> anchors, double k)
      : anchors_(std::move(anchors)), k_(k) {}
  void Refresh(const Vertices&) override {}
  double Evaluate(const Vertices& x, Eigen::VectorXd* gradient) const override {
    double energy = 0.0;
    for (const auto& a : anchors_) {
      const Eigen::Vector3d d = x.row(a.first).transpose() - a.second;
      energy += 0.5 * k_ * d.squaredNorm();
      if (gradient != nullptr) gradient->segment<3>(3 * a.first) += k_ * d;
    }
    return energy;
  }
  void AddHessian(const Vertices&, std::vector<Eigen::Triplet<double>>* triplets) const override {
    for (const auto& a : anchors_)
      for (int i = 0; i < 3; ++i) triplets->emplace_back(3 * a.first + i, 3 * a.first + i, k_);
  }
  const std::vector<std::pair<int, Eigen::Vector3d>>& anchors() const { return anchors_; }
  double k() const { return k_; }

 private:
  std::vector<std::pair<int, Eigen::Vector3d>> anchors_;
  double k_;
};

// A cantilever under a tip load, gravity and springs: at the converged result the clamp's
// reactions, the springs' forces and the loads sum to zero, and so do their moments (the
// corotational forces are those of a rotation-invariant energy, so they carry no moment).
TEST(ForwardForces, ReactionsBalanceLoadsGravityAndThePotential) {
  Cantilever c = MakeCantilever(2, Eigen::Vector3d(0, 0.3, -1.0));
  ComputeLumpedMasses(&c.mesh, 100.0);
  c.problem.gravity = Eigen::Vector3d(0, 0, -9.81);
  std::vector<std::pair<int, Eigen::Vector3d>> anchors;
  for (int v = 0; v < c.mesh.num_vertices(); ++v) {
    const Eigen::Vector3d X = c.mesh.rest.row(v).transpose();
    if (std::abs(X.x() - 0.5 * kLength) < 1e-9 && X.z() > kHeight - 1e-9) {
      anchors.push_back({v, X + Eigen::Vector3d(0, 0, -0.002)});  // pulled down
    }
  }
  ASSERT_FALSE(anchors.empty());
  SpringPotential springs(anchors, 200.0);
  c.problem.potential = &springs;
  ElasticModel model;
  model.Build(c.mesh, ElasticModelType::kCorotational, BeamMaterial(1e7));
  ForwardSummary summary;
  ASSERT_TRUE(SolveQuasiStatic(c.problem, ForwardOptions(), &model, &c.mesh, &summary).ok());
  ASSERT_EQ(summary.termination, ForwardTermination::kConverged) << summary.FullReport();

  ForwardForces forces;
  ASSERT_TRUE(
      EvaluateForwardForces(c.problem, ForwardOptions(), model, c.mesh, c.mesh.x, &forces).ok());
  const int nv = c.mesh.num_vertices();
  std::vector<char> clamped(nv, 0);
  for (int v : c.problem.clamped) clamped[v] = 1;
  Vertices loads = Vertices::Zero(nv, 3), pull = Vertices::Zero(nv, 3);
  for (int v = 0; v < nv; ++v) loads.row(v) = c.mesh.mass(v) * c.problem.gravity.transpose();
  for (const auto& l : c.problem.nodal_loads) loads.row(l.first) += l.second.transpose();
  for (const auto& a : anchors) {
    pull.row(a.first) = -springs.k() * (c.mesh.x.row(a.first) - a.second.transpose());
  }
  EXPECT_LT((forces.loads - loads).cwiseAbs().maxCoeff(), 1e-15);
  EXPECT_LT((forces.potential - pull).cwiseAbs().maxCoeff(), 1e-12);
  for (int v = 0; v < nv; ++v) {
    if (!clamped[v]) {
      EXPECT_EQ(forces.reactions.row(v).norm(), 0.0) << "free vertex " << v;
    }
  }

  const Vertices total = forces.reactions + forces.potential + forces.loads;
  const double scale = loads.colwise().sum().norm() + pull.colwise().sum().norm();
  Eigen::Vector3d moment = Eigen::Vector3d::Zero();
  for (int v = 0; v < nv; ++v) {
    moment += c.mesh.x.row(v).transpose().cross(total.row(v).transpose());
  }
  EXPECT_LT(total.colwise().sum().norm(), 1e-7 * scale);
  EXPECT_LT(moment.norm(), 1e-7 * scale * kLength);
  // The clamp holds the rest: its resultant and torque are minus those of the other forces.
  const ForceResultant support = ResultantAboutCentroid(forces.reactions, c.mesh.x, c.mesh.mass);
  const ForceResultant applied =
      ResultantAboutCentroid(forces.potential + forces.loads, c.mesh.x, c.mesh.mass);
  EXPECT_LT((support.force + applied.force).norm(), 1e-7 * scale);
  EXPECT_LT((support.torque + applied.torque).norm(), 1e-7 * scale * kLength);
  // The springs' share is far above the tolerances: a balance without it would fail.
  EXPECT_GT(pull.colwise().sum().norm(), 0.01 * scale);

  Vertices bad = c.mesh.x;
  bad(0, 0) = std::nan("");
  EXPECT_FALSE(
      EvaluateForwardForces(c.problem, ForwardOptions(), model, c.mesh, bad, &forces).ok());
}

// The torque is about the mass-weighted centroid of the positions.
TEST(ForwardForces, ResultantIsAboutTheMassWeightedCentroid) {
  Vertices x(2, 3), f(2, 3);
  x << 0, 0, 0, 4, 0, 0;
  f << 0, 1, 0, 0, 1, 0;
  Eigen::VectorXd mass(2);
  mass << 1, 3;  // centroid (3, 0, 0)
  const ForceResultant r = ResultantAboutCentroid(f, x, mass);
  EXPECT_LT((r.force - Eigen::Vector3d(0, 2, 0)).norm(), 1e-15);
  EXPECT_LT((r.torque - Eigen::Vector3d(0, 0, -2)).norm(), 1e-15);  // -3 e_x x e_y + e_x x e_y
}

// A soft, nearly incompressible cylinder sagging under its own weight (the forward bench's
// sag, coarser: 525 vertices, 1,920 tets): Newton on the full tangent converges in a few
// iterations with a quadratic tail; on the warped stiffness it takes many more.
struct SagRun {
  ForwardSummary summary;
  double deflection = 0.0;
};

SagRun SolveSag(ForwardTangent tangent) {
  const double length = 0.4;
  TetMesh mesh = MakeCylinder(0.03, length, 2, 20);
  ComputeLumpedMasses(&mesh, 1000.0);
  ForwardProblem problem;
  std::vector<int> tip;
  for (int v = 0; v < mesh.num_vertices(); ++v) {
    if (mesh.rest(v, 2) < 1e-9) problem.clamped.push_back(v);
    if (mesh.rest(v, 2) > length - 1e-9) tip.push_back(v);
  }
  problem.gravity = Eigen::Vector3d(-9.81, 0, 0);
  Material material;
  material.youngs_modulus = 3e5;
  material.poisson_ratio = 0.49;
  material.density = 1000.0;
  ElasticModel model;
  model.Build(mesh, ElasticModelType::kCorotational, material);
  ForwardOptions options;
  options.tangent = tangent;
  options.max_iterations = 300;
  options.relative_tolerance = 1e-10;
  SagRun run;
  EXPECT_TRUE(SolveQuasiStatic(problem, options, &model, &mesh, &run.summary).ok());
  for (int v : tip) run.deflection -= (mesh.x(v, 0) - mesh.rest(v, 0)) / tip.size();
  return run;
}

TEST(SolveQuasiStatic, FullTangentConvergesQuadratically) {
  const SagRun full = SolveSag(ForwardTangent::kFull);
  const SagRun warped = SolveSag(ForwardTangent::kWarped);
  ASSERT_EQ(full.summary.termination, ForwardTermination::kConverged) << full.summary.FullReport();
  ASSERT_EQ(warped.summary.termination, ForwardTermination::kConverged)
      << warped.summary.FullReport();
  std::printf("sag: tip %.4f m; full tangent %d Newton iterations, warped %d\n%s",
              full.deflection, full.summary.NumNewtonIterations(),
              warped.summary.NumNewtonIterations(), full.summary.FullReport().c_str());
  EXPECT_GT(full.deflection, 0.05);  // a large deformation: more than 12% of the length
  // The same equilibrium: both stop at |r| <= 1e-10 |load|, far below this.
  EXPECT_NEAR(full.deflection, warped.deflection, 1e-6);
  EXPECT_LE(full.summary.NumNewtonIterations(), 8);
  EXPECT_GE(warped.summary.NumNewtonIterations(), 2 * full.summary.NumNewtonIterations());

  // The quadratic tail: once the residual is below 1e-2 of the first one, each iteration
  // squares it, r_{k+1} / r_0 <= C (r_k / r_0)^2. C = 100 leaves a margin over the measured
  // constant (see the printed report) and fails for linear convergence, where r_{k+1} / r_k
  // stays near a fixed ratio (at r_k / r_0 = 1e-4 it would have to be below 1e-2).
  const std::vector<ForwardIteration>& rows = full.summary.iterations;
  const double r0 = rows.front().residual_norm;
  int checked = 0;
  for (size_t k = 0; k + 1 < rows.size(); ++k) {
    const double a = rows[k].residual_norm / r0, b = rows[k + 1].residual_norm / r0;
    if (a > 1e-2 || b < 1e-11) continue;  // not yet asymptotic, or at round-off
    EXPECT_LE(b, 100.0 * a * a) << "iteration " << rows[k + 1].iteration;
    ++checked;
  }
  EXPECT_GE(checked, 1);
}

// A potential that adds nothing but looks at the BLAS thread count while the solve runs.
class BlasThreadProbe : public ForwardPotential {
 public:
  using Get = int (*)();
  explicit BlasThreadProbe(Get get) : get_(get) {}
  void Refresh(const Vertices&) override {}
  double Evaluate(const Vertices&, Eigen::VectorXd*) const override {
    seen_max_ = std::max(seen_max_, get_());
    return 0.0;
  }
  void AddHessian(const Vertices&, std::vector<Eigen::Triplet<double>>*) const override {}
  int seen_max() const { return seen_max_; }

 private:
  Get get_;
  mutable int seen_max_ = 0;
};

// OpenBLAS (under CHOLMOD) runs on num_threads during the solve and gets its own setting
// back after.
TEST(SolveQuasiStatic, HoldsOpenBlasToNumThreads) {
  using Set = void (*)(int);
  const auto get = reinterpret_cast<BlasThreadProbe::Get>(dlsym(RTLD_DEFAULT, "openblas_get_num_threads"));
  const auto set = reinterpret_cast<Set>(dlsym(RTLD_DEFAULT, "openblas_set_num_threads"));
  if (get == nullptr || set == nullptr) GTEST_SKIP() << "the BLAS is not OpenBLAS";
  const int original = get();
  set(2);
  if (get() != 2) {
    set(original);
    GTEST_SKIP() << "OpenBLAS does not take 2 threads here";
  }
  Cantilever c = MakeCantilever(1, Eigen::Vector3d(0, 0, -2));
  BlasThreadProbe probe(get);
  c.problem.potential = &probe;
  ElasticModel model;
  model.Build(c.mesh, ElasticModelType::kCorotational, BeamMaterial());
  ForwardOptions options;
  options.num_threads = 1;
  ForwardSummary summary;
  EXPECT_TRUE(SolveQuasiStatic(c.problem, options, &model, &c.mesh, &summary).ok());
  EXPECT_EQ(summary.termination, ForwardTermination::kConverged) << summary.FullReport();
  EXPECT_EQ(summary.num_threads, 1);
  EXPECT_EQ(probe.seen_max(), 1);
  EXPECT_EQ(get(), 2);
  set(original);
}

// ---------------------------------------------------------------------------------------
// femreg simulate: iterations per load step in the report, exit code 1 when not converged.

#ifdef FEMREG_CLI_PATH
int RunCommand(const std::string& command) {
  const int status = std::system(command.c_str());
  return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
}

std::string ReadFile(const std::filesystem::path& path) {
  std::stringstream text;
  text << std::ifstream(path.string()).rdbuf();
  return text.str();
}

class SimulateTest : public ::testing::Test {
 protected:
  void SetUp() override {
    const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
    dir_ = std::filesystem::temp_directory_path() /
           (std::string("femreg_forward_test_") + info->name() + "_" + std::to_string(::getpid()));
    std::filesystem::remove_all(dir_);
    std::filesystem::create_directories(dir_);
  }
  void TearDown() override { std::filesystem::remove_all(dir_); }
  std::filesystem::path dir_;
};

TEST_F(SimulateTest, ReportsNewtonIterationsPerLoadStep) {
  const std::string scene = std::string(FEMREG_DATASETS_DIR) + "/beam/beam.yaml";
  const std::string command = std::string(FEMREG_CLI_PATH) + " simulate " + scene + " --out " +
                              (dir_ / "out").string() + " > " + (dir_ / "log.txt").string() +
                              " 2>&1";
  ASSERT_EQ(RunCommand(command), 0) << ReadFile(dir_ / "log.txt");
  const std::string log = ReadFile(dir_ / "log.txt");
  EXPECT_NE(log.find("Newton iterations in 2 load steps ["), std::string::npos) << log;
  const std::string json = ReadFile(dir_ / "out" / "summary.json");
  EXPECT_NE(json.find("\"ok\": true"), std::string::npos) << json;
  EXPECT_NE(json.find("\"tangent\": \"full\""), std::string::npos) << json;
  EXPECT_NE(json.find("{\"load_step\": 1, \"load_factor\": 0.5, \"termination\": \"CONVERGED\", "
                      "\"newton_iterations\": "),
            std::string::npos)
      << json;
  EXPECT_NE(json.find("{\"load_step\": 2, \"load_factor\": 1, \"termination\": \"CONVERGED\""),
            std::string::npos)
      << json;
}

// E = 100 Pa on the bundled 1 m beam: the load would stretch it several times over and
// invert its cross-section; the solve does not converge, so simulate says so and exits 1.
TEST_F(SimulateTest, NotConvergedIsAnError) {
  std::string scene = ReadFile(std::string(FEMREG_DATASETS_DIR) + "/beam/beam.yaml");
  const std::string stiff = "youngs_modulus: 1.0e6";
  ASSERT_NE(scene.find(stiff), std::string::npos);
  scene.replace(scene.find(stiff), stiff.size(), "youngs_modulus: 100");
  std::ofstream((dir_ / "soft.yaml").string()) << scene;
  const std::string command = std::string(FEMREG_CLI_PATH) + " simulate " +
                              (dir_ / "soft.yaml").string() + " --max-iterations 15 --out " +
                              (dir_ / "out").string() + " > " + (dir_ / "log.txt").string() +
                              " 2> " + (dir_ / "err.txt").string();
  EXPECT_EQ(RunCommand(command), 1) << ReadFile(dir_ / "log.txt");
  const std::string err = ReadFile(dir_ / "err.txt");
  EXPECT_NE(err.find("MAX_ITERATIONS"), std::string::npos) << err;
  EXPECT_NE(err.find("Try more load steps"), std::string::npos) << err;
  const std::string json = ReadFile(dir_ / "out" / "summary.json");
  EXPECT_NE(json.find("\"ok\": false"), std::string::npos) << json;
  EXPECT_NE(json.find("\"vtu\": null"), std::string::npos) << json;
  EXPECT_NE(json.find("\"termination\": \"MAX_ITERATIONS\", \"newton_iterations\": 15"),
            std::string::npos)
      << json;
  EXPECT_FALSE(std::filesystem::exists(dir_ / "out" / "beam.vtu"));
}
#endif  // FEMREG_CLI_PATH

}  // namespace
}  // namespace femreg
