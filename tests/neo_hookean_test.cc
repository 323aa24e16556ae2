// Tests of the stable neo-Hookean element (fem.h): its stress and Hessian against central
// differences, linear elasticity at small strain, rest and rigid motion, inversion; the
// forward solve with it (assembled tangent against differences of the residual, Newton's
// quadratic tail), and the nodal volume against locking.
#include <gtest/gtest.h>

#include <Eigen/Eigenvalues>
#include <Eigen/Geometry>
#include <cmath>
#include <cstdio>
#include <random>
#include <vector>

#include "femreg/fem.h"
#include "femreg/forward.h"
#include "femreg/io.h"
#include "femreg/tracker.h"

namespace femreg {
namespace {

constexpr double kMu = 2.0e5, kLambda = 1.5e6;

Eigen::Matrix3d RandomF(std::mt19937* rng, double spread) {
  std::uniform_real_distribution<double> u(-spread, spread);
  Eigen::Matrix3d F = Eigen::Matrix3d::Identity();
  for (int i = 0; i < 9; ++i) F.data()[i] += u(*rng);
  return F;
}

// Deformation gradients with stretch, compression, a flat and an inverted one.
std::vector<Eigen::Matrix3d> SampleF() {
  std::mt19937 rng(7);
  std::vector<Eigen::Matrix3d> out;
  for (int i = 0; i < 20; ++i) out.push_back(RandomF(&rng, 0.4));
  Eigen::Matrix3d flat = RandomF(&rng, 0.2);
  flat.col(2) = 0.5 * flat.col(0) - 0.3 * flat.col(1);
  out.push_back(flat);
  Eigen::Matrix3d inverted = RandomF(&rng, 0.2);
  inverted.col(1) *= -1.0;
  out.push_back(inverted);
  return out;
}

TEST(NeoHookean, StressAndHessianMatchCentralDifferences) {
  const double kappa = kLambda + kMu, pressure = 3.0e4;
  for (const Eigen::Matrix3d& F : SampleF()) {
    Eigen::Matrix3d P;
    NeoHookeanDensity(F, kMu, kappa, &P);
    const Matrix9 H = NeoHookeanDensityHessian(F, kMu, kappa, pressure, TangentProjection::kNone);
    const double h = 1e-6;
    Matrix9 numeric;
    for (int k = 0; k < 9; ++k) {
      Eigen::Matrix3d Fp = F, Fm = F;
      Fp.data()[k] += h;
      Fm.data()[k] -= h;
      Eigen::Matrix3d Pp, Pm;
      const double psi_p = NeoHookeanDensity(Fp, kMu, kappa, &Pp);
      const double psi_m = NeoHookeanDensity(Fm, kMu, kappa, &Pm);
      EXPECT_NEAR(P.data()[k], (psi_p - psi_m) / (2 * h), 1e-6 * kappa) << "entry " << k;
      // The pressure adds p cof F to the stress: its derivative is p H_J.
      Pp += pressure * Fp.determinant() * Fp.inverse().transpose();
      Pm += pressure * Fm.determinant() * Fm.inverse().transpose();
      if (std::abs(F.determinant()) < 1e-9) continue;  // cof through the inverse: not here
      const Eigen::Matrix3d dP = (Pp - Pm) / (2 * h);
      numeric.col(k) = Eigen::Map<const Eigen::Matrix<double, 9, 1>>(dP.data());
    }
    if (std::abs(F.determinant()) < 1e-9) continue;
    EXPECT_LT((H - numeric).cwiseAbs().maxCoeff(), 1e-6 * kappa) << F;
    EXPECT_LT((H - H.transpose()).cwiseAbs().maxCoeff(), 1e-12 * kappa);
    // The projection: positive semi-definite, and H itself where H already is.
    ElementTangentInfo info;
    const Matrix9 projected =
        NeoHookeanDensityHessian(F, kMu, kappa, pressure, TangentProjection::kPositiveSemiDefinite, &info);
    Eigen::SelfAdjointEigenSolver<Matrix9> eig(projected);
    EXPECT_GT(eig.eigenvalues().minCoeff(), -1e-9 * kappa);
    if (info.negative_modes == 0) {
      EXPECT_LT((projected - H).cwiseAbs().maxCoeff(), 1e-9 * kappa);
    }
  }
}

TEST(NeoHookean, IsLinearElasticityAtSmallStrain) {
  std::mt19937 rng(3);
  const double kappa = kLambda + kMu;
  for (int trial = 0; trial < 10; ++trial) {
    const Eigen::Matrix3d G = RandomF(&rng, 1e-6) - Eigen::Matrix3d::Identity();
    Eigen::Matrix3d P;
    NeoHookeanDensity(Eigen::Matrix3d::Identity() + G, kMu, kappa, &P);
    const Eigen::Matrix3d eps = 0.5 * (G + G.transpose());
    const Eigen::Matrix3d hooke = 2 * kMu * eps + kLambda * eps.trace() * Eigen::Matrix3d::Identity();
    EXPECT_LT((P - hooke).norm(), 1e-4 * hooke.norm());  // second order in |G| ~ 1e-6
  }
  // The nodal split: the deviatoric element part plus the bulk term is the element form.
  const Eigen::Matrix3d F = RandomF(&rng, 0.3);
  const double J = F.determinant(), K = kLambda + 2 * kMu / 3;
  EXPECT_NEAR(NeoHookeanDensity(F, kMu, kMu / 3, nullptr) + 0.5 * K * (J - 1) * (J - 1),
              NeoHookeanDensity(F, kMu, kappa, nullptr), 1e-9 * kappa);
}

// The tangent tests' element: a 2 cm corner tetrahedron of a nearly incompressible material.
Eigen::Matrix<double, 3, 4> CornerTetrahedron() {
  Eigen::Matrix<double, 3, 4> X;
  X << 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1;
  return 0.02 * X;
}

Material TangentTestMaterial() {
  Material material;
  material.youngs_modulus = 5e5;
  material.poisson_ratio = 0.45;
  return material;
}

// The blocks in closed form (the determinant's second derivative as a cross product) are
// B^T H B on every sample F, the flat and the inverted one included, with and without the
// nodal volume's pressure.
TEST(NeoHookean, TangentBlocksInClosedFormAreTheNineByNineProducts) {
  const Eigen::Matrix<double, 3, 4> X = CornerTetrahedron();
  const ElementRest rest = BuildElementRest(X, TangentTestMaterial());
  for (const Eigen::Matrix3d& F : SampleF()) {
    Vector12 x;
    for (int k = 0; k < 4; ++k) x.segment<3>(3 * k) = F * X.col(k);
    for (bool nodal : {false, true}) {
      const double kappa = NeoHookeanKappa(rest, nodal), pressure = nodal ? -2e4 : 0.0;
      const Matrix12 K = NeoHookeanTangent(rest, kappa, pressure, x, TangentProjection::kNone);
      Eigen::Matrix3d blocks[16];
      NeoHookeanTangentBlocks(rest, kappa, pressure, F, blocks);
      Matrix12 closed;
      for (int a = 0; a < 4; ++a)
        for (int b = 0; b < 4; ++b) closed.block<3, 3>(3 * a, 3 * b) = blocks[4 * a + b];
      EXPECT_LT((closed - K).cwiseAbs().maxCoeff(), 1e-12 * K.cwiseAbs().maxCoeff()) << "F =\n" << F;
      EXPECT_EQ(closed, closed.transpose());
    }
  }
}

TEST(NeoHookean, ZeroAtRestAndUnderRotationAndPushesBackWhenInverted) {
  const double kappa = kLambda + kMu;
  const Eigen::Matrix3d R = Eigen::AngleAxisd(1.1, Eigen::Vector3d(1, 2, -1).normalized()).toRotationMatrix();
  for (const Eigen::Matrix3d& F : {Eigen::Matrix3d(Eigen::Matrix3d::Identity()), R}) {
    Eigen::Matrix3d P;
    EXPECT_NEAR(NeoHookeanDensity(F, kMu, kappa, &P), 0.0, 1e-9 * kappa);
    EXPECT_LT(P.norm(), 1e-9 * kappa);
  }
  // Through a flat state into an inverted one, along F = diag(1, 1, t): finite, and the
  // energy keeps falling as t grows back towards 1 (the force points out of the inversion).
  double previous = std::numeric_limits<double>::infinity();
  for (double t = -0.5; t <= 1.0; t += 0.1) {
    const double psi = NeoHookeanDensity(Eigen::Vector3d(1, 1, t).asDiagonal(), kMu, kappa, nullptr);
    EXPECT_TRUE(std::isfinite(psi));
    EXPECT_LT(psi, previous) << "t = " << t;
    previous = psi;
  }
}

TEST(NeoHookean, ElementTangentMatchesCentralDifferencesOfTheForce) {
  const Eigen::Matrix<double, 3, 4> X = CornerTetrahedron();
  const ElementRest rest = BuildElementRest(X, TangentTestMaterial());
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> u(-0.006, 0.006);
  for (int trial = 0; trial < 10; ++trial) {
    Vector12 x = rest.X;
    for (int i = 0; i < 12; ++i) x(i) += u(rng);
    for (bool nodal : {false, true}) {
      const double kappa = NeoHookeanKappa(rest, nodal), pressure = nodal ? -2e4 : 0.0;
      const Matrix12 K = NeoHookeanTangent(rest, kappa, pressure, x, TangentProjection::kNone);
      Matrix12 numeric;
      const double h = 1e-8;
      for (int j = 0; j < 12; ++j) {
        Vector12 xp = x, xm = x, fp, fm;
        xp(j) += h;
        xm(j) -= h;
        NeoHookeanEnergyAndForce(rest, kappa, pressure, xp, &fp);
        NeoHookeanEnergyAndForce(rest, kappa, pressure, xm, &fm);
        numeric.col(j) = -(fp - fm) / (2 * h);
      }
      EXPECT_LT((K - numeric).cwiseAbs().maxCoeff(), 1e-6 * K.cwiseAbs().maxCoeff());
      // The force is minus the energy's gradient (pressure 0: the energy is all here).
      if (!nodal) {
        Vector12 f;
        NeoHookeanEnergyAndForce(rest, kappa, 0.0, x, &f);
        for (int j = 0; j < 12; ++j) {
          Vector12 xp = x, xm = x, unused;
          xp(j) += h;
          xm(j) -= h;
          const double d = (NeoHookeanEnergyAndForce(rest, kappa, 0.0, xp, &unused) -
                            NeoHookeanEnergyAndForce(rest, kappa, 0.0, xm, &unused)) / (2 * h);
          EXPECT_NEAR(-f(j), d, 1e-6 * f.cwiseAbs().maxCoeff());
        }
      }
    }
  }
}

// A cantilever of nx * n * n cubes (6 tets each), clamped at x = 0, tip load along -z.
struct Beam {
  TetMesh mesh;
  ForwardProblem problem;
  std::vector<int> tip;
};

Beam MakeBeam(double length, double height, int n, double load) {
  Beam b;
  b.mesh = MakeBox(Eigen::Vector3d(length, height, height), static_cast<int>(std::lround(n * length / height)), n, n);
  for (int v = 0; v < b.mesh.num_vertices(); ++v) {
    if (b.mesh.rest(v, 0) < 1e-9) b.problem.clamped.push_back(v);
    if (b.mesh.rest(v, 0) > length - 1e-9) b.tip.push_back(v);
  }
  for (int v : b.tip) b.problem.nodal_loads.push_back({v, Eigen::Vector3d(0, 0, -load / b.tip.size())});
  return b;
}

double TipDeflection(const Beam& b) {
  double sum = 0.0;
  for (int v : b.tip) sum -= b.mesh.x(v, 2) - b.mesh.rest(v, 2);
  return sum / b.tip.size();
}

ForwardSummary SolveBeam(Beam* b, double nu, MaterialModel law, bool nodal_volume,
                         ForwardTangent tangent = ForwardTangent::kFull, int load_steps = 1) {
  ObjectMaterial material;
  material.material.youngs_modulus = 1e6;
  material.material.poisson_ratio = nu;
  material.model = law;
  material.nodal_volume = nodal_volume;
  ElasticModel model;
  model.Build(b->mesh, ElasticModelType::kCorotational, material);
  ForwardOptions options;
  options.tangent = tangent;
  options.load_steps = load_steps;
  options.relative_tolerance = 1e-10;
  options.max_iterations = 200;
  ForwardSummary summary;
  EXPECT_TRUE(SolveQuasiStatic(b->problem, options, &model, &b->mesh, &summary).ok());
  return summary;
}

TEST(NeoHookeanForward, AssembledTangentMatchesCentralDifferencesOfTheResidual) {
  for (bool nodal : {false, true}) {
    Beam b = MakeBeam(0.3, 0.1, 1, 0.0);
    ObjectMaterial material;
    material.material.youngs_modulus = 1e6;
    material.material.poisson_ratio = 0.45;
    material.model = MaterialModel::kNeoHookean;
    material.nodal_volume = nodal;
    ElasticModel model;
    model.Build(b.mesh, ElasticModelType::kCorotational, material);
    ASSERT_EQ(model.type(), ElasticModelType::kNeoHookean);
    ASSERT_EQ(model.nodal_volume(), nodal);
    std::mt19937 rng(5);
    std::uniform_real_distribution<double> u(-0.01, 0.01);
    Vertices x = b.mesh.x;
    for (int v = 0; v < x.rows(); ++v)
      if (b.mesh.rest(v, 0) > 1e-9) x.row(v) += Eigen::RowVector3d(u(rng), u(rng), u(rng));
    ForwardOptions options;
    Eigen::VectorXd residual;
    Eigen::SparseMatrix<double> tangent;
    std::vector<int> free_dofs;
    ASSERT_TRUE(EvaluateForwardSystem(b.problem, options, model, b.mesh, x, &residual, &tangent,
                                      &free_dofs).ok());
    const Eigen::MatrixXd full(tangent);
    const int n = static_cast<int>(free_dofs.size());
    Eigen::MatrixXd numeric(n, n);
    const double h = 1e-7;
    for (int j = 0; j < n; ++j) {
      Vertices plus = x, minus = x;
      plus(free_dofs[j] / 3, free_dofs[j] % 3) += h;
      minus(free_dofs[j] / 3, free_dofs[j] % 3) -= h;
      Eigen::VectorXd rp, rm;
      Eigen::SparseMatrix<double> unused;
      std::vector<int> dofs;
      ASSERT_TRUE(EvaluateForwardSystem(b.problem, options, model, b.mesh, plus, &rp, &unused, &dofs).ok());
      ASSERT_TRUE(EvaluateForwardSystem(b.problem, options, model, b.mesh, minus, &rm, &unused, &dofs).ok());
      for (int i = 0; i < n; ++i) numeric(i, j) = (rp(free_dofs[i]) - rm(free_dofs[i])) / (2 * h);
    }
    const double scale = full.cwiseAbs().maxCoeff();
    EXPECT_LT((full - numeric).cwiseAbs().maxCoeff(), 1e-6 * scale) << "nodal volume " << nodal;
    EXPECT_LT((full - full.transpose()).cwiseAbs().maxCoeff(), 1e-12 * scale);
  }
}

TEST(NeoHookeanForward, NewtonConvergesQuadraticallyOnALargeBend) {
  for (bool nodal : {false, true}) {
    Beam b = MakeBeam(1.0, 0.1, 2, 6.0);  // about a quarter of the length down
    const ForwardSummary summary = SolveBeam(&b, 0.45, MaterialModel::kNeoHookean, nodal,
                                             ForwardTangent::kFull, 2);
    ASSERT_EQ(summary.termination, ForwardTermination::kConverged) << summary.FullReport();
    std::printf("neo-Hookean bend (nodal volume %d): tip %.4f m, Newton iterations %d [%d, %d]\n",
                nodal, TipDeflection(b), summary.NumNewtonIterations(),
                summary.load_steps[0].iterations, summary.load_steps[1].iterations);
    EXPECT_GT(TipDeflection(b), 0.05);
    for (const ForwardLoadStep& step : summary.load_steps) EXPECT_LE(step.iterations, 12);
    const std::vector<ForwardIteration>& rows = summary.iterations;
    const double r0 = rows.front().residual_norm;
    int checked = 0;
    for (size_t k = 0; k + 1 < rows.size(); ++k) {
      if (rows[k + 1].load_step != rows[k].load_step) continue;
      const double a = rows[k].residual_norm / r0, c = rows[k + 1].residual_norm / r0;
      if (a > 5e-2 || c < 1e-9) continue;  // not yet asymptotic, or near round-off
      EXPECT_LE(c, 100.0 * a * a) << "iteration " << rows[k + 1].iteration;
      ++checked;
    }
    EXPECT_GE(checked, 1);
  }
}

// Small load: the neo-Hookean and corotational elements agree (the same linearization).
// As nu -> 0.5 the element form locks in bending (the tip deflection falls 5x at nu 0.49,
// 24x at 0.499 on this mesh) while beam theory says it does not change; with the nodal volume
// it stays near the nu = 0.3 answer of the same mesh. (That answer is itself below beam
// theory: linear tetrahedra are stiff in bending at 2 cells across.)
TEST(NeoHookeanForward, NodalVolumeRemovesVolumetricLocking) {
  const double load = 0.02;  // N: about 1e-3 of the length
  Beam hooke = MakeBeam(1.0, 0.1, 2, load), nh = hooke;
  SolveBeam(&hooke, 0.3, MaterialModel::kHooke, false);
  SolveBeam(&nh, 0.3, MaterialModel::kNeoHookean, false);
  EXPECT_NEAR(TipDeflection(nh), TipDeflection(hooke), 1e-3 * TipDeflection(hooke));

  const double reference = TipDeflection(hooke);
  for (double nu : {0.49, 0.499}) {
    Beam element = MakeBeam(1.0, 0.1, 2, load), nodal = element;
    SolveBeam(&element, nu, MaterialModel::kNeoHookean, false);
    SolveBeam(&nodal, nu, MaterialModel::kNeoHookean, true);
    std::printf("tip at nu %.3f: element volume %.3e m, nodal volume %.3e m; nu 0.3: %.3e m\n",
                nu, TipDeflection(element), TipDeflection(nodal), reference);
    EXPECT_LT(TipDeflection(element), 0.25 * reference);  // locked
    EXPECT_GT(TipDeflection(nodal), 0.9 * reference);     // not locked
    EXPECT_LT(TipDeflection(nodal), 1.5 * reference);
  }
}

// Registration takes the element form under the FEM regularizer, and says what to change
// otherwise.
TEST(NeoHookeanRegistration, TrackerTakesTheElementAndRefusesWhatItCannotDo) {
  const TetMesh mesh = MakeBox(Eigen::Vector3d(0.1, 0.04, 0.04), 4, 2, 2);
  ObjectMaterial material;
  material.model = MaterialModel::kNeoHookean;
  RegistrationOptions options;
  std::unique_ptr<Tracker> tracker;
  EXPECT_TRUE(Tracker::Create({mesh}, {material}, options, &tracker).ok());

  material.nodal_volume = true;
  options.solver.backend = SolverBackend::kCeres;  // either back end (nodal_volume_registration_test)
  EXPECT_TRUE(Tracker::Create({mesh}, {material}, options, &tracker).ok());
  options.solver.backend = SolverBackend::kFast;

  material.nodal_volume = false;
  options.regularizer = Regularizer::kMassSpring;
  Status status = Tracker::Create({mesh}, {material}, options, &tracker);
  EXPECT_FALSE(status.ok());
  EXPECT_NE(status.message().find("needs registration.regularizer corotational"), std::string::npos)
      << status.message();
}

}  // namespace
}  // namespace femreg
