#include "energy/elastic.h"

#include <Eigen/LU>
#include <algorithm>
#include <cmath>

namespace femreg {
namespace energy {

namespace {
// F = D_s D_m^-1 at the stencil's positions, from edge vectors (no cancellation of a large
// translation).
Eigen::Matrix3d StencilF(const double* const* x, const Eigen::Matrix3d& dm_inv) {
  const Eigen::Vector3d x0 = Eigen::Map<const Eigen::Vector3d>(x[0]);
  Eigen::Matrix3d Ds;
  for (int j = 0; j < 3; ++j) Ds.col(j) = Eigen::Map<const Eigen::Vector3d>(x[j + 1]) - x0;
  return Ds * dm_inv;
}

Vector12 StencilVector(const double* const* x) {
  Vector12 xe;
  for (int i = 0; i < 4; ++i) xe.segment<3>(3 * i) = Eigen::Map<const Eigen::Vector3d>(x[i]);
  return xe;
}

// An element's force f (12) and stiffness K (12 by 12) as a block's gradient -f and Hessian.
void ElementDerivatives(const Vector12& force, const Matrix12* stiffness, Eigen::Vector3d* gradient,
                        Eigen::Matrix3d* hessian) {
  for (int i = 0; i < 4; ++i) gradient[i] = -force.segment<3>(3 * i);
  if (hessian == nullptr) return;
  for (int i = 0; i < 4; ++i)
    for (int j = 0; j < 4; ++j) hessian[i * 4 + j] = stiffness->block<3, 3>(3 * i, 3 * j);
}
}  // namespace

bool ElasticElement::SecondOrder(const double* const* x, double* energy, Eigen::Vector3d* gradient,
                                 Eigen::Matrix3d* hessian, TangentProjection projection) const {
  const Vector12 xe = StencilVector(x);
  Eigen::Matrix3d R = Eigen::Matrix3d::Identity();
  if (hessian != nullptr && corotational && projection == TangentProjection::kNone) {
    // The exact tangent in closed form from Newton's polar rotation: no eigendecomposition, the
    // blocks written where they go.
    const Eigen::Matrix3d F = StencilF(x, rest->dm_inv);
    R = rotation != nullptr ? PolarRotation(F, *rotation) : PolarRotation(F);
    if (CorotationalTangentBlocks(*rest, F, R, hessian)) {
      Vector12 force;
      *energy = ElementEnergyAndForce(*rest, R, xe, &force);
      ElementDerivatives(force, nullptr, gradient, nullptr);
      return true;
    }
  }
  Matrix12 K;
  if (hessian != nullptr) {  // one decomposition for R and the tangent
    K = corotational ? CorotationalTangent(*rest, xe, projection, nullptr, &R, rotation)
                     : WarpedStiffness(*rest, Eigen::Matrix3d::Identity());  // K, in closed form
  } else if (corotational) {
    // Newton from the held rotation (near R(x) between outer iterations) costs a fraction
    // of the SVD: the force residual of equilibrium registration evaluates every element.
    const Eigen::Matrix3d F = StencilF(x, rest->dm_inv);
    R = rotation != nullptr ? PolarRotation(F, *rotation) : PolarRotation(F);
  }
  Vector12 force;
  *energy = ElementEnergyAndForce(*rest, R, xe, &force);
  ElementDerivatives(force, hessian != nullptr ? &K : nullptr, gradient, hessian);
  return true;
}

bool NeoHookeanElement::SecondOrder(const double* const* x, double* energy, Eigen::Vector3d* gradient,
                                    Eigen::Matrix3d* hessian, TangentProjection projection) const {
  const Vector12 xe = StencilVector(x);
  const double kappa = NeoHookeanKappa(*rest, deviatoric);
  Vector12 force;
  *energy = NeoHookeanEnergyAndForce(*rest, kappa, 0.0, xe, &force) + 0.5 * Offset();
  if (hessian != nullptr && projection == TangentProjection::kNone) {
    NeoHookeanTangentBlocks(*rest, kappa, 0.0, StencilF(x, rest->dm_inv), hessian);
    ElementDerivatives(force, nullptr, gradient, nullptr);
    return true;
  }
  Matrix12 K;
  if (hessian != nullptr) K = NeoHookeanTangent(*rest, kappa, 0.0, xe, projection);
  ElementDerivatives(force, hessian != nullptr ? &K : nullptr, gradient, hessian);
  return true;
}

bool EdgeSpring::SecondOrder(const double* const* x, double* energy, Eigen::Vector3d* gradient,
                             Eigen::Matrix3d* hessian, TangentProjection projection) const {
  const Eigen::Vector3d d =
      Eigen::Map<const Eigen::Vector3d>(x[0]) - Eigen::Map<const Eigen::Vector3d>(x[1]);
  const double norm = d.norm(), stretch = norm - length;
  *energy = 0.5 * stretch * stretch;
  const Eigen::Vector3d u = norm > 0 ? Eigen::Vector3d(d / norm) : Eigen::Vector3d::Zero();
  gradient[0] = stretch * u;
  gradient[1] = -gradient[0];
  if (hessian == nullptr) return true;
  const Eigen::Matrix3d uu = u * u.transpose();
  // At zero length the lateral directions have no defined curvature: the axial part only.
  double lateral = norm > 0 ? stretch / norm : 0.0;
  if (projection == TangentProjection::kPositiveSemiDefinite) lateral = std::max(lateral, 0.0);
  const Eigen::Matrix3d H = uu + lateral * (Eigen::Matrix3d::Identity() - uu);
  hessian[0] = H;
  hessian[3] = H;
  hessian[1] = -H;
  hessian[2] = -H;
  return true;
}

bool ElasticElement::Evaluate(const double* const* x, double* r, double** J) const {
  Vector12 xe;
  for (int i = 0; i < 4; ++i) xe.segment<3>(3 * i) = Eigen::Map<const Eigen::Vector3d>(x[i]);
  // S formed once for the residual and the four blocks (the rest data do not store it).
  const Matrix6x12 S = ElementResidualMatrix(*rest);
  const Eigen::Matrix3d& R = *rotation;
  Vector12 u;
  for (int i = 0; i < 4; ++i) u.segment<3>(3 * i) = R.transpose() * xe.segment<3>(3 * i) - rest->X.segment<3>(3 * i);
  Eigen::Map<Vector6>{r} = S * u;
  if (J == nullptr) return true;
  for (int i = 0; i < 4; ++i) {
    if (J[i] == nullptr) continue;
    Eigen::Map<Eigen::Matrix<double, 6, 3, Eigen::RowMajor>> Ji(J[i]);
    Ji = S.block<6, 3>(0, 3 * i) * R.transpose();
  }
  return true;
}

bool ElasticElement::Normal(const double* const* x, double* squared_norm, Eigen::Vector3d* jtr,
                            Eigen::Matrix3d* jtj) const {
  const Eigen::Matrix3d& R = *rotation;
  const Eigen::Matrix3d& dm_inv = rest->dm_inv;
  const double V = rest->volume, lambda = rest->lambda, mu = rest->mu;
  // Shape gradients as rows: b_1..b_3 the rows of D_m^-1, b_0 = -(b_1 + b_2 + b_3).
  Eigen::Matrix<double, 4, 3> b;
  b.bottomRows<3>() = dm_inv;
  b.row(0) = -(dm_inv.row(0) + dm_inv.row(1) + dm_inv.row(2));
  // sum_j u_j b_j^T = R^T F - I (sum_j X_j b_j^T = I): the displacement gradient in the
  // element's frame.
  Eigen::Matrix3d e = R.transpose() * StencilF(x, dm_inv);
  e.diagonal().array() -= 1.0;
  e = (0.5 * (e + e.transpose())).eval();
  const double trace = e.trace();
  *squared_norm = V * (2.0 * mu * e.squaredNorm() + lambda * trace * trace);
  if (jtr == nullptr) return true;
  Eigen::Matrix3d P = 2.0 * mu * e;
  P.diagonal().array() += lambda * trace;
  // Row i: (V R P b_i)^T = b_i^T (V P R^T) (P symmetric).
  const Eigen::Matrix<double, 4, 3> forces = b * (V * P * R.transpose());
  for (int i = 0; i < 4; ++i) jtr[i] = forces.row(i).transpose();
  if (jtj == nullptr) return true;
  const Eigen::Matrix<double, 4, 3> c = b * R.transpose();  // row i: (R b_i)^T
  const Eigen::Matrix4d dots = b * b.transpose();
  const double Vmu = V * mu, Vlambda = V * lambda;
  for (int i = 0; i < 4; ++i) {
    for (int j = i; j < 4; ++j) {
      Eigen::Matrix3d& block = jtj[i * 4 + j];
      block.noalias() = Vmu * c.row(j).transpose() * c.row(i);
      block.noalias() += Vlambda * c.row(i).transpose() * c.row(j);
      block.diagonal().array() += Vmu * dots(i, j);
      if (j != i) jtj[j * 4 + i] = block.transpose();
    }
  }
  return true;
}

bool NeoHookeanElement::Evaluate(const double* const* x, double* r, double** J) const {
  const double V = rest->volume, mu = rest->mu, kappa = NeoHookeanKappa(*rest, deviatoric);
  const Eigen::Matrix3d F = StencilF(x, rest->dm_inv);
  const double a = std::sqrt(V * mu), c = std::sqrt(V * kappa);
  Eigen::Map<Eigen::Matrix<double, 9, 1>>{r} = a * Eigen::Map<const Eigen::Matrix<double, 9, 1>>(F.data());
  r[9] = c * (F.determinant() - (1.0 + mu / kappa));
  if (J == nullptr) return true;
  const Eigen::Matrix<double, 3, 4> b = ShapeGradients(*rest);
  const Eigen::Matrix3d cof = Cofactor(F);
  for (int i = 0; i < 4; ++i) {
    if (J[i] == nullptr) continue;
    Eigen::Map<Eigen::Matrix<double, 10, 3, Eigen::RowMajor>> Ji(J[i]);
    Ji.setZero();
    for (int col = 0; col < 3; ++col) Ji.block<3, 3>(3 * col, 0).diagonal().setConstant(a * b(col, i));
    Ji.row(9) = c * (cof * b.col(i)).transpose();
  }
  return true;
}

bool NeoHookeanElement::Normal(const double* const* x, double* squared_norm, Eigen::Vector3d* jtr,
                               Eigen::Matrix3d* jtj) const {
  const double V = rest->volume, mu = rest->mu, kappa = NeoHookeanKappa(*rest, deviatoric);
  const Eigen::Matrix3d F = StencilF(x, rest->dm_inv);
  const double d = F.determinant() - (1.0 + mu / kappa);
  *squared_norm = V * (mu * F.squaredNorm() + kappa * d * d);
  if (jtr == nullptr) return true;
  const Eigen::Matrix<double, 3, 4> b = ShapeGradients(*rest);
  const Eigen::Matrix3d cof = Cofactor(F);
  const Eigen::Matrix<double, 3, 4> forces = V * (mu * F + kappa * d * cof) * b;
  for (int i = 0; i < 4; ++i) jtr[i] = forces.col(i);
  if (jtj == nullptr) return true;
  const Eigen::Matrix<double, 3, 4> c = cof * b;
  const Eigen::Matrix4d dots = b.transpose() * b;
  for (int i = 0; i < 4; ++i) {
    for (int j = i; j < 4; ++j) {
      Eigen::Matrix3d& block = jtj[i * 4 + j];
      block.noalias() = (V * kappa) * c.col(i) * c.col(j).transpose();
      block.diagonal().array() += V * mu * dots(i, j);
      if (j != i) jtj[j * 4 + i] = block.transpose();
    }
  }
  return true;
}

double NeoHookeanElement::Offset() const {
  const double mu = rest->mu, kappa = NeoHookeanKappa(*rest, deviatoric);
  return rest->volume * (3.0 * mu + mu * mu / kappa);
}

bool EdgeSpring::Evaluate(const double* const* x, double* r, double** J) const {
  const Eigen::Vector3d d =
      Eigen::Map<const Eigen::Vector3d>(x[0]) - Eigen::Map<const Eigen::Vector3d>(x[1]);
  const double norm = d.norm();
  r[0] = norm - length;
  if (J == nullptr) return true;
  const Eigen::Vector3d u = norm > 0 ? Eigen::Vector3d(d / norm) : Eigen::Vector3d::Zero();
  if (J[0] != nullptr) Eigen::Map<Eigen::Vector3d>{J[0]} = u;
  if (J[1] != nullptr) Eigen::Map<Eigen::Vector3d>{J[1]} = -u;
  return true;
}

}  // namespace energy
}  // namespace femreg
