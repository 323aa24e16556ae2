// The consistent corotational tangent against finite differences: one element's
// (fem.h's CorotationalTangent) and the assembled system's (EvaluateForwardSystem)
// (forward_test.cc has the solves).
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
#include "forward_setup.h"

namespace femreg {
namespace {

using namespace forward_testing;  // NOLINT(build/namespaces)

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

// The closed form (the twist through M = tr(S) I - S) is the eigendecomposition's tangent on
// every state the tests above use, inverted ones included, and declines the degenerate ones.
TEST(CorotationalTangent, BlocksInClosedFormAreTheEigendecompositions) {
  std::mt19937 rng(18);
  for (double nu : {0.3, 0.49}) {
    const ElementRest rest = TangentTestRest(nu);
    int taken = 0;
    for (const auto& [name, F] : TangentStates(&rng)) {
      const Vector12 x = PositionsWithGradient(rest, F, Eigen::Vector3d(0.3, -0.1, 0.2));
      Eigen::Matrix3d R;
      const Matrix12 tangent = CorotationalTangent(rest, x, TangentProjection::kNone, nullptr, &R);
      Eigen::Matrix3d blocks[16];
      if (!CorotationalTangentBlocks(rest, F, PolarRotation(F), blocks)) continue;
      ++taken;
      Matrix12 closed;
      for (int a = 0; a < 4; ++a)
        for (int b = 0; b < 4; ++b) closed.block<3, 3>(3 * a, 3 * b) = blocks[4 * a + b];
      EXPECT_LT((closed - tangent).cwiseAbs().maxCoeff(), 1e-9 * tangent.cwiseAbs().maxCoeff())
          << name << ", nu " << nu << "\nF =\n" << F;
      EXPECT_EQ(closed, closed.transpose()) << name;
    }
    EXPECT_EQ(taken, 41);
  }
  // Near a collapse in an oblique frame M's pivots stay large while sigma_i + sigma_j is tiny:
  // declined, or the eigendecomposition's tangent (which drops such a mode).
  for (const Eigen::Vector3d& sigma : {Eigen::Vector3d(1.2, 1e-7, 7e-8), Eigen::Vector3d(1.0, 0.5, -0.5 + 1e-8),
                                       Eigen::Vector3d(1.0, 0.5, -0.5 + 1e-5)}) {
    const ElementRest rest = TangentTestRest(0.45);
    int near_taken = 0;
    for (int frame = 0; frame < 200; ++frame) {
      const Eigen::Matrix3d F = RandomRotation(&rng) * sigma.asDiagonal() * RandomRotation(&rng).transpose();
      Eigen::Matrix3d blocks[16];
      if (!CorotationalTangentBlocks(rest, F, PolarRotation(F), blocks)) continue;
      ++near_taken;
      const Matrix12 tangent = CorotationalTangent(rest, PositionsWithGradient(rest, F, Eigen::Vector3d::Zero()),
                                                   TangentProjection::kNone);
      Matrix12 closed;
      for (int a = 0; a < 4; ++a)
        for (int b = 0; b < 4; ++b) closed.block<3, 3>(3 * a, 3 * b) = blocks[4 * a + b];
      EXPECT_LT((closed - tangent).cwiseAbs().maxCoeff(), 1e-6 * tangent.cwiseAbs().maxCoeff())
          << "sigma " << sigma.transpose() << "\nF =\n" << F;
    }
    // Above the cut-off (sigma_2 + sigma_3 = 1e-5) the closed form is taken in some frames.
    if (sigma(1) + sigma(2) > 1e-6) {
      EXPECT_GT(near_taken, 0) << sigma.transpose();
    }
  }
  Eigen::Matrix3d line = Eigen::Matrix3d::Zero();
  line(0, 0) = 1.2;
  const ElementRest rest = TangentTestRest(0.3);
  Eigen::Matrix3d blocks[16];
  for (const Eigen::Matrix3d& F : {Eigen::Matrix3d(Eigen::Matrix3d::Zero()), line,
                                   Eigen::Matrix3d(Eigen::Vector3d(1.0, 0.5, -0.5).asDiagonal())}) {
    EXPECT_FALSE(CorotationalTangentBlocks(rest, F, PolarRotation(F), blocks)) << F;
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
  const double scale = ElementStiffness(rest).cwiseAbs().maxCoeff();
  const Matrix12 at_rest = CorotationalTangent(rest, rest.X, TangentProjection::kNone);
  EXPECT_LT((at_rest - ElementStiffness(rest)).cwiseAbs().maxCoeff(), 1e-12 * scale);
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

// With a start rotation (the element's held one) the tangent comes from Newton's polar
// rotation and a closed-form symmetric eigensolver instead of the SVD: the same matrix to
// 1e-9, also at rest (three equal singular values), at nearly equal or equal ones (where the
// closed form's roots split by sqrt(eps), amplified by 1 / (sigma_i + sigma_j) for an
// inverted element near the tie), and for inverted and degenerate elements; from starts 0.01
// and 0.3 rad from R(x) (Newton's steps; from 1 rad its first step is too long and the SVD
// decides).
TEST(CorotationalTangent, AStartRotationGivesTheSameTangent) {
  std::mt19937 rng(20);
  const ElementRest rest = TangentTestRest(0.4);
  std::vector<std::pair<std::string, Eigen::Matrix3d>> states = TangentStates(&rng);
  states.push_back({"rest", Eigen::Matrix3d::Identity()});
  states.push_back({"rotated", RandomRotation(&rng)});
  states.push_back({"nearly equal", RandomRotation(&rng) * Eigen::Vector3d(1.0 + 1e-9, 1.0, 1.0 - 1e-9).asDiagonal()});
  states.push_back({"two equal", RandomRotation(&rng) * Eigen::Vector3d(1.2, 0.9, 0.9).asDiagonal() *
                                     RandomRotation(&rng).transpose()});
  states.push_back({"inverted, sigma2 = -sigma3", Eigen::Vector3d(1.0, 0.5, -0.5).asDiagonal()});
  for (const double c : {0.2, 0.9, 0.99}) {
    for (int frame = 0; frame < 20; ++frame) {
      states.push_back({"inverted, two equal, sigma3 = -" + std::to_string(c),
                        RandomRotation(&rng) * Eigen::Vector3d(1.0, 1.0, -c).asDiagonal() *
                            RandomRotation(&rng).transpose()});
    }
  }
  states.push_back({"flat, two equal", RandomRotation(&rng) * Eigen::Vector3d(1.0, 1.0, 1e-3).asDiagonal() *
                                           RandomRotation(&rng).transpose()});
  states.push_back({"collapsed to a point", Eigen::Matrix3d::Zero()});
  for (const auto& [name, F] : states) {
    const Vector12 x = PositionsWithGradient(rest, F, Eigen::Vector3d(0.1, -0.2, 0.3));
    ElementTangentInfo info, info_start;
    Eigen::Matrix3d R, R_start;
    const Matrix12 t = CorotationalTangent(rest, x, TangentProjection::kNone, &info, &R);
    const double scale = std::max(t.cwiseAbs().maxCoeff(), ElementStiffness(rest).cwiseAbs().maxCoeff());
    for (const double angle : {0.01, 0.3}) {
      const Eigen::Matrix3d start = R * Eigen::AngleAxisd(angle, Eigen::Vector3d(1, 2, 2).normalized()).toRotationMatrix();
      const Matrix12 t_start =
          CorotationalTangent(rest, x, TangentProjection::kNone, &info_start, &R_start, &start);
      EXPECT_LT((t_start - t).cwiseAbs().maxCoeff(), 1e-9 * scale) << name << ", start " << angle;
      EXPECT_LT((R_start - R).cwiseAbs().maxCoeff(), 1e-9) << name << ", start " << angle;
      EXPECT_EQ(info_start.degenerate_modes, info.degenerate_modes) << name;
      // Under a rigid motion every g_ij is 0 up to round-off, and so is its sign.
      if (std::abs(info.min_eigenvalue) > 1e-9 * rest.mu) {
        EXPECT_EQ(info_start.negative_modes, info.negative_modes) << name;
      }
    }
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

}  // namespace
}  // namespace femreg
