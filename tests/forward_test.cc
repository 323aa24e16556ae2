// Tests of the forward quasi-static solve against beam theory, rotation equivariance,
// large-deformation behaviour of corotational vs linear FEM, and failure modes; Newton's
// quadratic convergence with the full tangent; femreg simulate's report. The tangent
// (element and assembled) is tested in forward_tangent_test.cc, the forces on the body in
// forward_forces_test.cc; the shared cantilever in forward_setup.h.
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
#include <nlohmann/json.hpp>
#include <string>
#include <utility>
#include <vector>

#include "femreg/fem.h"
#include "femreg/forward.h"
#include "femreg/io.h"
#include "femreg/mesh.h"
#include "femreg_test_config.h"
#include "forward_setup.h"

namespace femreg {
namespace {

using namespace forward_testing;  // NOLINT(build/namespaces)

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
  options.relative_tolerance = std::nan("");  // named by its scene key, forward.tolerance
  EXPECT_FALSE(options.IsValid(&error));
  EXPECT_NE(error.find("forward.tolerance"), std::string::npos);
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
  const nlohmann::json json = nlohmann::json::parse(ReadFile(dir_ / "out" / "summary.json"));
  EXPECT_EQ(json["tangent"], "full");
  EXPECT_EQ(json["forward"]["load_steps"], 2);
  const nlohmann::json& beam = json["objects"][0];
  EXPECT_EQ(beam["ok"], true) << beam;
  ASSERT_EQ(beam["load_steps"].size(), 2u) << beam;
  for (int step = 0; step < 2; ++step) {
    const nlohmann::json& s = beam["load_steps"][step];
    EXPECT_EQ(s["load_step"], step + 1);
    EXPECT_DOUBLE_EQ(s["load_factor"].get<double>(), 0.5 * (step + 1));
    EXPECT_EQ(s["termination"], "CONVERGED");
    EXPECT_GT(s["newton_iterations"].get<int>(), 0);
  }
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
  const nlohmann::json json = nlohmann::json::parse(ReadFile(dir_ / "out" / "summary.json"));
  const nlohmann::json& beam = json["objects"][0];
  EXPECT_EQ(beam["ok"], false) << beam;
  EXPECT_TRUE(beam["vtu"].is_null()) << beam;
  EXPECT_EQ(json["max_iterations"], 15);
  ASSERT_FALSE(beam["load_steps"].empty()) << beam;
  EXPECT_EQ(beam["load_steps"].back()["termination"], "MAX_ITERATIONS");  // the step that stopped
  EXPECT_EQ(beam["load_steps"].back()["newton_iterations"], 15);
  EXPECT_FALSE(std::filesystem::exists(dir_ / "out" / "beam.vtu"));
}
#endif  // FEMREG_CLI_PATH

}  // namespace
}  // namespace femreg
