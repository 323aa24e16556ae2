// Tests of the corotational and linear tetrahedral elements: derivatives against finite
// differences and ceres::GradientChecker, rigid-motion invariance, stiffness spectra,
// degenerate elements, the polar rotation, and the material.
#include <ceres/ceres.h>
#include <ceres/gradient_checker.h>
#include <gtest/gtest.h>

#include <Eigen/Eigenvalues>
#include <Eigen/Geometry>
#include <Eigen/SVD>
#include <random>
#include <string>
#include <vector>

#include "femreg/fem.h"

namespace femreg {
namespace {

using Matrix34 = Eigen::Matrix<double, 3, 4>;

Material TestMaterial() {
  Material m;
  m.youngs_modulus = 2.0e5;
  m.poisson_ratio = 0.35;
  return m;
}

Matrix34 RestTet() {
  Matrix34 X;
  X << 0.0, 0.11, -0.01, 0.02,  //
      0.0, 0.01, 0.09, 0.015,   //
      0.0, -0.02, 0.01, 0.1;
  return X;
}

Vector12 Stack(const Matrix34& x) {
  Vector12 v;
  for (int i = 0; i < 4; ++i) v.segment<3>(3 * i) = x.col(i);
  return v;
}

Eigen::Matrix3d RandomRotation(std::mt19937* rng) {
  std::normal_distribution<double> n(0.0, 1.0);
  Eigen::Quaterniond q(n(*rng), n(*rng), n(*rng), n(*rng));
  return q.normalized().toRotationMatrix();
}

// A random deformed state: random rotation, stretch up to 30%, translation, noise.
Vector12 RandomDeformed(const ElementRest& rest, std::mt19937* rng) {
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  Eigen::Matrix3d A = Eigen::Matrix3d::Identity();
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) A(i, j) += 0.3 * u(*rng);
  const Eigen::Matrix3d Q = RandomRotation(rng);
  const Eigen::Vector3d t(u(*rng), u(*rng), u(*rng));
  Vector12 x;
  for (int i = 0; i < 4; ++i) {
    x.segment<3>(3 * i) = Q * A * rest.X.segment<3>(3 * i) + t;
    for (int k = 0; k < 3; ++k) x(3 * i + k) += 0.005 * u(*rng);
  }
  return x;
}

Eigen::Matrix3d RotationAt(const ElementRest& rest, const Vector12& x) {
  Matrix34 xm;
  for (int i = 0; i < 4; ++i) xm.col(i) = x.segment<3>(3 * i);
  return PolarRotation(DeformationGradient(xm, rest.dm_inv));
}

// The element residual r = S (R^T x - X) with R held fixed, as a Ceres cost function:
// 6 residuals, the four vertices as 3-vector parameter blocks.
class ElementResidualCost : public ceres::SizedCostFunction<6, 3, 3, 3, 3> {
 public:
  ElementResidualCost(const ElementRest& rest, const Eigen::Matrix3d& R) : rest_(rest), R_(R) {}
  bool Evaluate(double const* const* parameters, double* residuals,
                double** jacobians) const override {
    Vector12 x;
    for (int i = 0; i < 4; ++i) x.segment<3>(3 * i) = Eigen::Map<const Eigen::Vector3d>(parameters[i]);
    Eigen::Map<Vector6> r(residuals);
    r = ElementResidual(rest_, R_, x);
    if (jacobians) {
      const Matrix6x12 J = ElementResidualJacobian(rest_, R_);
      for (int i = 0; i < 4; ++i) {
        if (jacobians[i]) {
          Eigen::Map<Eigen::Matrix<double, 6, 3, Eigen::RowMajor>> block(jacobians[i]);
          block = J.block<6, 3>(0, 3 * i);
        }
      }
    }
    return true;
  }

 private:
  const ElementRest& rest_;
  Eigen::Matrix3d R_;
};

TEST(Element, ResidualJacobianMatchesCentralDifferences) {
  std::mt19937 rng(1);
  const ElementRest rest = BuildElementRest(RestTet(), TestMaterial());
  for (int trial = 0; trial < 20; ++trial) {
    const Vector12 x = RandomDeformed(rest, &rng);
    const Eigen::Matrix3d R = RotationAt(rest, x);
    const Matrix6x12 J = ElementResidualJacobian(rest, R);
    ASSERT_GT(J.squaredNorm(), 0.0);
    const double h = 1e-6;
    Matrix6x12 numeric;
    for (int k = 0; k < 12; ++k) {
      Vector12 xp = x, xm = x;
      xp(k) += h;
      xm(k) -= h;
      numeric.col(k) = (ElementResidual(rest, R, xp) - ElementResidual(rest, R, xm)) / (2 * h);
    }
    EXPECT_LT((J - numeric).norm(), 1e-7 * J.norm()) << "trial " << trial;
  }
}

TEST(Element, ResidualJacobianPassesCeresGradientChecker) {
  std::mt19937 rng(2);
  const ElementRest rest = BuildElementRest(RestTet(), TestMaterial());
  for (int trial = 0; trial < 20; ++trial) {
    const Vector12 x = RandomDeformed(rest, &rng);
    const ElementResidualCost cost(rest, RotationAt(rest, x));
    const double* parameters[4] = {x.data(), x.data() + 3, x.data() + 6, x.data() + 9};
    ceres::NumericDiffOptions options;
    const std::vector<const ceres::Manifold*>* no_manifolds = nullptr;
    ceres::GradientChecker checker(&cost, no_manifolds, options);
    ceres::GradientChecker::ProbeResults results;
    ASSERT_TRUE(checker.Probe(parameters, 1e-7, &results)) << results.error_log;
    double norm = 0.0;
    for (const auto& j : results.jacobians) norm += j.squaredNorm();
    EXPECT_GT(norm, 0.0);
  }
}

// The exact gradient of E(x) = 0.5 |S (R(x)^T x - X)|^2 with R = polar(F(x)) recomputed is
// R K (R^T x - X): the rotation's derivative drops out.
TEST(Element, ForceIsTheExactGradientWithRotationRecomputed) {
  std::mt19937 rng(3);
  const ElementRest rest = BuildElementRest(RestTet(), TestMaterial());
  auto energy = [&](const Vector12& x) { return ElementEnergy(rest, RotationAt(rest, x), x); };
  for (int trial = 0; trial < 50; ++trial) {
    const Vector12 x = RandomDeformed(rest, &rng);
    const Vector12 gradient = -ElementForce(rest, RotationAt(rest, x), x);
    ASSERT_GT(gradient.squaredNorm(), 0.0);
    const double h = 1e-7;
    Vector12 numeric;
    for (int k = 0; k < 12; ++k) {
      Vector12 xp = x, xm = x;
      xp(k) += h;
      xm(k) -= h;
      numeric(k) = (energy(xp) - energy(xm)) / (2 * h);
    }
    EXPECT_LT((gradient - numeric).norm(), 1e-5 * gradient.norm()) << "trial " << trial;
  }
}

TEST(Element, CorotationalZeroAtRestAndUnderRigidMotion) {
  std::mt19937 rng(4);
  std::uniform_real_distribution<double> u(-10.0, 10.0);
  const ElementRest rest = BuildElementRest(RestTet(), TestMaterial());
  const Eigen::Matrix3d I = Eigen::Matrix3d::Identity();
  EXPECT_NEAR(ElementEnergy(rest, RotationAt(rest, rest.X), rest.X), 0.0, 1e-20);
  EXPECT_LT(ElementForce(rest, RotationAt(rest, rest.X), rest.X).norm(), 1e-9);
  // A reference: the force of a 1% stretch.
  Vector12 stretched = rest.X;
  for (int i = 0; i < 4; ++i) stretched(3 * i) *= 1.01;
  const double force_scale = ElementForce(rest, I, stretched).norm();
  const double energy_scale = ElementEnergy(rest, I, stretched);
  int linear_nonzero = 0;
  for (int trial = 0; trial < 100; ++trial) {
    const Eigen::Matrix3d Q = RandomRotation(&rng);
    const Eigen::Vector3d t(u(rng), u(rng), u(rng));
    Vector12 x;
    for (int i = 0; i < 4; ++i) x.segment<3>(3 * i) = Q * rest.X.segment<3>(3 * i) + t;
    const Eigen::Matrix3d R = RotationAt(rest, x);
    EXPECT_LT((R - Q).norm(), 1e-9);
    EXPECT_LT(ElementEnergy(rest, R, x), 1e-12 * energy_scale) << "trial " << trial;
    EXPECT_LT(ElementForce(rest, R, x).norm(), 1e-7 * force_scale) << "trial " << trial;
    // The linear model (R = I) sees strain in a rotation.
    if (ElementEnergy(rest, I, x) > energy_scale) ++linear_nonzero;
  }
  EXPECT_GT(linear_nonzero, 90);
}

// The rest data keep what every step reads; the matrices are formed from it: C is
// IsotropicElasticity's, and the force through the stress is -R K u with K = V L^T C L.
TEST(Element, MatricesFromTheRestDataAreTheElementsOwn) {
  const Material material = TestMaterial();
  const ElementRest rest = BuildElementRest(RestTet(), material);
  const Matrix6 C = IsotropicElasticity(material.youngs_modulus, material.poisson_ratio);
  EXPECT_LT((HookeMatrix(rest) - C).cwiseAbs().maxCoeff(), 1e-12 * C.cwiseAbs().maxCoeff());
  const Matrix6x12 L = StrainDisplacement(rest);
  const Matrix12 K = ElementStiffness(rest);
  EXPECT_LT((K - rest.volume * L.transpose() * C * L).norm(), 1e-12 * K.norm());
  // The warped stiffness at R = I is K, built from the shape gradients without L.
  EXPECT_LT((K - WarpedStiffness(rest, Eigen::Matrix3d::Identity())).norm(), 1e-12 * K.norm());
  // L u is the small strain of the displacement (engineering shears): u = G X for any G.
  Eigen::Matrix3d G;
  G << 1e-3, 2e-3, -3e-3, 4e-3, -5e-3, 6e-3, 7e-3, 8e-3, 9e-3;
  Vector12 u;
  for (int i = 0; i < 4; ++i) u.segment<3>(3 * i) = G * rest.X.segment<3>(3 * i);
  Vector6 expected_strain;
  expected_strain << G(0, 0), G(1, 1), G(2, 2), G(1, 2) + G(2, 1), G(0, 2) + G(2, 0), G(0, 1) + G(1, 0);
  EXPECT_LT((L * u - expected_strain).cwiseAbs().maxCoeff(), 1e-12 * G.cwiseAbs().maxCoeff());
  // What every step reads, and no more (the matrices are formed where needed).
  EXPECT_LE(sizeof(ElementRest), 192u);
  std::mt19937 rng(11);
  for (int trial = 0; trial < 20; ++trial) {
    const Vector12 x = RandomDeformed(rest, &rng);
    const Eigen::Matrix3d R = RotationAt(rest, x);
    Vector12 ur;
    for (int i = 0; i < 4; ++i) ur.segment<3>(3 * i) = R.transpose() * x.segment<3>(3 * i) - rest.X.segment<3>(3 * i);
    const Vector12 ku = K * ur;
    Vector12 expected;
    for (int i = 0; i < 4; ++i) expected.segment<3>(3 * i) = -R * ku.segment<3>(3 * i);
    EXPECT_LT((ElementForce(rest, R, x) - expected).norm(), 1e-10 * expected.norm()) << "trial " << trial;
    EXPECT_NEAR(ElementEnergy(rest, R, x), 0.5 * ur.dot(ku), 1e-10 * ur.dot(ku)) << "trial " << trial;
  }
}

TEST(Element, StiffnessAtRestIsSymmetricPsdWithSixRigidModes) {
  const ElementRest rest = BuildElementRest(RestTet(), TestMaterial());
  const Matrix12 K = ElementStiffness(rest);
  const Matrix6x12 S = ElementResidualMatrix(rest);
  EXPECT_LT((K - K.transpose()).norm(), 1e-12 * K.norm());
  EXPECT_LT((S.transpose() * S - K).norm(), 1e-10 * K.norm());
  Eigen::SelfAdjointEigenSolver<Matrix12> eig(K);
  const Vector12 values = eig.eigenvalues();
  const double tol = 1e-10 * values.maxCoeff();
  int zeros = 0;
  for (int i = 0; i < 12; ++i) {
    EXPECT_GT(values(i), -tol);
    if (std::abs(values(i)) <= tol) ++zeros;
  }
  EXPECT_EQ(zeros, 6);

  std::mt19937 rng(5);
  for (int trial = 0; trial < 20; ++trial) {
    const Vector12 x = RandomDeformed(rest, &rng);
    const Matrix12 W = WarpedStiffness(rest, RotationAt(rest, x));
    EXPECT_LT((W - W.transpose()).norm(), 1e-12 * W.norm());
    Eigen::SelfAdjointEigenSolver<Matrix12> we(W);
    EXPECT_GT(we.eigenvalues().minCoeff(), -1e-10 * we.eigenvalues().maxCoeff());
    // Warped stiffness = J^T J of the residual with R fixed.
    const Matrix6x12 J = ElementResidualJacobian(rest, RotationAt(rest, x));
    EXPECT_LT((J.transpose() * J - W).norm(), 1e-10 * W.norm());
  }
}

void ExpectProperRotation(const Eigen::Matrix3d& R) {
  ASSERT_TRUE(R.allFinite());
  EXPECT_NEAR(R.determinant(), 1.0, 1e-10);
  EXPECT_LT((R.transpose() * R - Eigen::Matrix3d::Identity()).norm(), 1e-10);
}

TEST(Element, InvertedAndFlatElementsStayFinite) {
  const ElementRest rest = BuildElementRest(RestTet(), TestMaterial());
  const Matrix34 X = RestTet();
  std::vector<Matrix34> states;
  Matrix34 inverted = X;  // vertex 3 pushed through the opposite face
  inverted.col(3) = X.col(0) - 0.5 * (X.col(3) - X.col(0));
  states.push_back(inverted);
  Matrix34 flat = X;  // all four points in the plane z = 0
  flat.row(2).setZero();
  states.push_back(flat);
  Matrix34 collinear;  // all on a line
  for (int i = 0; i < 4; ++i) collinear.col(i) = Eigen::Vector3d(1, 2, 3) * (0.1 * i);
  states.push_back(collinear);
  Matrix34 coincident;
  for (int i = 0; i < 4; ++i) coincident.col(i) = Eigen::Vector3d(0.3, -0.2, 0.1);
  states.push_back(coincident);
  for (const Matrix34& xm : states) {
    const Eigen::Matrix3d R = PolarRotation(DeformationGradient(xm, rest.dm_inv));
    ExpectProperRotation(R);
    const Vector12 x = Stack(xm);
    EXPECT_TRUE(std::isfinite(ElementEnergy(rest, R, x)));
    EXPECT_TRUE(ElementForce(rest, R, x).allFinite());
    EXPECT_GT(ElementEnergy(rest, R, x), 0.0);  // squashed, not rigid
  }
}

TEST(PolarRotation, RecoversTheRotationOfRotationTimesStretch) {
  std::mt19937 rng(6);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  for (int trial = 0; trial < 100; ++trial) {
    const Eigen::Matrix3d Q = RandomRotation(&rng);
    Eigen::Matrix3d B;
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j < 3; ++j) B(i, j) = u(rng);
    const Eigen::Matrix3d S = B * B.transpose() + 0.1 * Eigen::Matrix3d::Identity();  // SPD
    const Eigen::Matrix3d R = PolarRotation(Q * S);
    ExpectProperRotation(R);
    EXPECT_LT((R - Q).norm(), 1e-8) << "trial " << trial;
  }
}

// The warm-started Newton rotation is PolarRotation's (the SVD's) to round-off: on random F
// of either sign of det, flat F (rank 2 and rank 1), inverted elements, from close starts,
// the identity and a random one.
TEST(PolarRotation, WarmStartedNewtonMatchesTheSvd) {
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  auto small_rotation = [&](double angle) {
    const Eigen::Vector3d axis = Eigen::Vector3d(u(rng), u(rng), u(rng)).normalized();
    return Eigen::AngleAxisd(angle, axis).toRotationMatrix();
  };
  std::vector<std::pair<std::string, Eigen::Matrix3d>> cases;
  for (int trial = 0; trial < 300; ++trial) {
    Eigen::Matrix3d F;
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j < 3; ++j) F(i, j) = u(rng);
    cases.emplace_back("random " + std::to_string(trial), F);
    // Flat: one singular value zero (a tetrahedron squashed onto a plane).
    Eigen::JacobiSVD<Eigen::Matrix3d> svd(F, Eigen::ComputeFullU | Eigen::ComputeFullV);
    Eigen::Vector3d sigma = svd.singularValues();
    sigma(2) = 0.0;
    cases.emplace_back("flat " + std::to_string(trial),
                       svd.matrixU() * sigma.asDiagonal() * svd.matrixV().transpose());
    // Inverted: a rotation times a stretch with one negative entry, away from the tie.
    const Eigen::Matrix3d Q = RandomRotation(&rng);
    const Eigen::Vector3d s(1.0 + 0.5 * std::abs(u(rng)), 0.6 + 0.3 * std::abs(u(rng)),
                            -0.4 * std::abs(u(rng)));
    cases.emplace_back("inverted " + std::to_string(trial), Q * s.asDiagonal() * RandomRotation(&rng));
  }
  cases.emplace_back("rank 1", Eigen::Vector3d(1, 2, 3) * Eigen::RowVector3d(0.5, -1, 2));
  cases.emplace_back("zero", Eigen::Matrix3d::Zero());
  cases.emplace_back("minus identity (the tie)", -Eigen::Matrix3d::Identity());
  for (const auto& [name, F] : cases) {
    const Eigen::Matrix3d exact = PolarRotation(F);
    const double scale = std::max(1.0, F.norm());
    // Close starts too: there the iteration stops after one or two steps, on its estimate of
    // the angle left.
    for (const Eigen::Matrix3d& start :
         {Eigen::Matrix3d(exact * small_rotation(0.05)), Eigen::Matrix3d(exact * small_rotation(1e-3)),
          Eigen::Matrix3d(exact * small_rotation(1e-6)), Eigen::Matrix3d(Eigen::Matrix3d::Identity()),
          RandomRotation(&rng)}) {
      const Eigen::Matrix3d R = PolarRotation(F, start);
      ExpectProperRotation(R);
      // The objective is what is unique (at the tie several rotations share its maximum).
      EXPECT_NEAR((R.transpose() * F).trace(), (exact.transpose() * F).trace(), 1e-13 * scale) << name;
      const bool unique = name.rfind("minus", 0) != 0 && name != "rank 1" && name != "zero";
      if (unique) {
        EXPECT_LT((R - exact).cwiseAbs().maxCoeff(), 1e-10) << name;
      }
    }
  }
}

// Warm starts chained over many steps (an element turning slowly, frame after frame) keep
// the rotation orthonormal to round-off.
TEST(PolarRotation, ChainedWarmStartsStayOrthonormal) {
  const Eigen::Matrix3d S = Eigen::Vector3d(1.2, 0.9, 0.7).asDiagonal();
  Eigen::Matrix3d R = Eigen::Matrix3d::Identity();
  for (int step = 1; step <= 20000; ++step) {
    const Eigen::Matrix3d Q =
        Eigen::AngleAxisd(1e-3 * step, Eigen::Vector3d(1, 2, 3).normalized()).toRotationMatrix();
    R = PolarRotation(Q * S, R);
    if (step % 5000 == 0) {
      EXPECT_LT((R.transpose() * R - Eigen::Matrix3d::Identity()).cwiseAbs().maxCoeff(), 1e-14);
      EXPECT_LT((R - Q).cwiseAbs().maxCoeff(), 1e-12) << step;
    }
  }
}

TEST(Material, IsotropicElasticityMatchesLame) {
  const double E = 3.0e5, nu = 0.25;
  const double lambda = E * nu / ((1 + nu) * (1 - 2 * nu));  // 1.2e5
  const double mu = E / (2 * (1 + nu));                      // 1.2e5
  const Matrix6 C = IsotropicElasticity(E, nu);
  EXPECT_NEAR(lambda, 1.2e5, 1e-6);
  for (int i = 0; i < 3; ++i) {
    EXPECT_NEAR(C(i, i), lambda + 2 * mu, 1e-6);
    EXPECT_NEAR(C(i + 3, i + 3), mu, 1e-6);
    for (int j = 0; j < 3; ++j) {
      if (i != j) {
        EXPECT_NEAR(C(i, j), lambda, 1e-6);
      }
    }
  }
  EXPECT_NEAR((C.block<3, 3>(0, 3).norm() + C.block<3, 3>(3, 0).norm()), 0.0, 1e-12);
  // Uniaxial stress: the compliance gives E and nu back.
  const Matrix6 compliance = C.inverse();
  EXPECT_NEAR(1.0 / compliance(0, 0), E, 1e-6 * E);
  EXPECT_NEAR(-compliance(0, 1) / compliance(0, 0), nu, 1e-12);
}

TEST(Material, IsValidNamesTheField) {
  std::string error;
  Material m;
  EXPECT_TRUE(m.IsValid(&error));
  for (double nu : {0.5, 0.7, -1.0, -1.5}) {
    m = Material();
    m.poisson_ratio = nu;
    EXPECT_FALSE(m.IsValid(&error)) << nu;
    EXPECT_NE(error.find("poisson_ratio"), std::string::npos) << error;
  }
  for (double E : {0.0, -1.0}) {
    m = Material();
    m.youngs_modulus = E;
    EXPECT_FALSE(m.IsValid(&error));
    EXPECT_NE(error.find("youngs_modulus"), std::string::npos) << error;
  }
  m = Material();
  m.density = 0.0;
  EXPECT_FALSE(m.IsValid(&error));
  EXPECT_NE(error.find("density"), std::string::npos) << error;
}

}  // namespace
}  // namespace femreg
