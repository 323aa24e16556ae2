// The stable neo-Hookean element (see femreg/fem.h for the energy and its split).
#include <Eigen/Eigenvalues>
#include <Eigen/Geometry>
#include <Eigen/LU>
#include <algorithm>

#include "femreg/fem.h"

namespace femreg {

namespace {

// The cross-product matrix [v]x (v x w = [v]x w).
Eigen::Matrix3d Cross(const Eigen::Vector3d& v) {
  Eigen::Matrix3d m;
  m << 0, -v(2), v(1), v(2), 0, -v(0), -v(1), v(0), 0;
  return m;
}

// F of the element at x (its 4 positions stacked: a 3 by 4 matrix column by column).
Eigen::Matrix3d ElementF(const ElementRest& rest, const Vector12& x) {
  return DeformationGradient(Eigen::Map<const Eigen::Matrix<double, 3, 4>>(x.data()), rest.dm_inv);
}

}  // namespace

Eigen::Matrix<double, 3, 4> ShapeGradients(const ElementRest& rest) {
  Eigen::Matrix<double, 3, 4> b;
  b.rightCols<3>() = rest.dm_inv.transpose();
  b.col(0) = -b.rightCols<3>().rowwise().sum();
  return b;
}

Eigen::Matrix3d Cofactor(const Eigen::Matrix3d& F) {
  Eigen::Matrix3d c;
  c.col(0) = F.col(1).cross(F.col(2));
  c.col(1) = F.col(2).cross(F.col(0));
  c.col(2) = F.col(0).cross(F.col(1));
  return c;
}

double NeoHookeanKappa(const ElementRest& rest, bool nodal_volume) {
  return nodal_volume ? rest.mu / 3.0 : rest.lambda + rest.mu;
}

double BulkModulus(const ElementRest& rest) { return rest.lambda + 2.0 * rest.mu / 3.0; }

double DeterminantMinusOne(const Eigen::Matrix3d& F) {
  const Eigen::Matrix3d H = F - Eigen::Matrix3d::Identity();
  const double trace = H.trace();
  return trace + 0.5 * (trace * trace - (H * H).trace()) + H.determinant();
}

double NeoHookeanDensity(const Eigen::Matrix3d& F, double mu, double kappa, Eigen::Matrix3d* P) {
  // In H = F - I, so that no term of size mu cancels another near rest (|F|^2 - 3 and J - 1
  // formed directly would leave round-off of eps mu in psi, which swamps the last Newton
  // steps' decrease of a stiff body's potential):
  //   J - 1 = tr H + i2(H) + det H,  i2 = ((tr H)^2 - tr(H^2)) / 2,
  //   mu/2 (|F|^2 - 3) - mu (J - 1) = mu/2 |H|^2 - mu (i2(H) + det H),
  //   F - cof F = H + H^T - tr(H) I - cof H.
  const Eigen::Matrix3d H = F - Eigen::Matrix3d::Identity();
  const double trace = H.trace();
  const double i2 = 0.5 * (trace * trace - (H * H).trace());
  const double det = H.determinant();
  const double j1 = trace + i2 + det;  // J - 1
  if (P != nullptr) {
    Eigen::Matrix3d f_minus_cof = H + H.transpose() - Cofactor(H);
    f_minus_cof.diagonal().array() -= trace;
    *P = mu * f_minus_cof + (kappa * j1) * Cofactor(F);
  }
  return 0.5 * mu * H.squaredNorm() - mu * (i2 + det) + 0.5 * kappa * j1 * j1;
}

Matrix9 DeterminantHessian(const Eigen::Matrix3d& F) {
  // Block (c, d) is d2 J / df_c df_d over the columns f of F: J = f0 . (f1 x f2).
  Matrix9 H = Matrix9::Zero();
  H.block<3, 3>(0, 3) = -Cross(F.col(2));
  H.block<3, 3>(0, 6) = Cross(F.col(1));
  H.block<3, 3>(3, 6) = -Cross(F.col(0));
  H.block<3, 3>(3, 0) = H.block<3, 3>(0, 3).transpose();
  H.block<3, 3>(6, 0) = H.block<3, 3>(0, 6).transpose();
  H.block<3, 3>(6, 3) = H.block<3, 3>(3, 6).transpose();
  return H;
}

Matrix9 NeoHookeanDensityHessian(const Eigen::Matrix3d& F, double mu, double kappa,
                                 double pressure, TangentProjection projection,
                                 ElementTangentInfo* info) {
  const double J = F.determinant();
  const Eigen::Matrix3d cof = Cofactor(F);
  const Eigen::Map<const Eigen::Matrix<double, 9, 1>> g(cof.data());
  Matrix9 H = (kappa * (J - 1.0) - mu + pressure) * DeterminantHessian(F);
  H.noalias() += kappa * g * g.transpose();
  H.diagonal().array() += mu;
  if (projection == TangentProjection::kNone && info == nullptr) return H;
  Eigen::SelfAdjointEigenSolver<Matrix9> eig(H);
  const Eigen::Matrix<double, 9, 1> values = eig.eigenvalues();
  if (info != nullptr) {
    *info = ElementTangentInfo();
    info->min_eigenvalue = values.minCoeff();
    info->negative_modes = static_cast<int>((values.array() < 0.0).count());
  }
  if (projection == TangentProjection::kNone || values.minCoeff() >= 0.0) return H;
  return eig.eigenvectors() * values.cwiseMax(0.0).asDiagonal() * eig.eigenvectors().transpose();
}

double NeoHookeanEnergyAndForce(const ElementRest& rest, double kappa, double pressure,
                                const Vector12& x, Vector12* force) {
  const Eigen::Matrix3d F = ElementF(rest, x);
  Eigen::Matrix3d P;
  const double psi = NeoHookeanDensity(F, rest.mu, kappa, &P);
  if (pressure != 0.0) P += pressure * Cofactor(F);
  // f_k = -V P b_k.
  const Eigen::Matrix<double, 3, 4> f = -rest.volume * P * ShapeGradients(rest);
  for (int k = 0; k < 4; ++k) force->segment<3>(3 * k) = f.col(k);
  return rest.volume * psi;
}

Matrix12 NeoHookeanTangent(const ElementRest& rest, double kappa, double pressure,
                           const Vector12& x, TangentProjection projection,
                           ElementTangentInfo* info) {
  const Eigen::Matrix<double, 3, 4> b = ShapeGradients(rest);
  const Matrix9 H =
      NeoHookeanDensityHessian(ElementF(rest, x), rest.mu, kappa, pressure, projection, info);
  // K = V B^T H B, where B (9 by 12) has vec F (3 c + a) depend on x_k (3 k + a) with weight
  // b_k(c): three terms per entry of H B and of B^T (H B), where a dense product's packing
  // costs more than its flops at this size.
  Eigen::Matrix<double, 9, 12> HB;
  for (int k = 0; k < 4; ++k) {
    for (int a = 0; a < 3; ++a) {
      HB.col(3 * k + a) = b(0, k) * H.col(a) + b(1, k) * H.col(3 + a) + b(2, k) * H.col(6 + a);
    }
  }
  Matrix12 K;
  for (int k = 0; k < 4; ++k) {
    for (int a = 0; a < 3; ++a) {
      K.row(3 * k + a) = rest.volume * (b(0, k) * HB.row(a) + b(1, k) * HB.row(3 + a) + b(2, k) * HB.row(6 + a));
    }
  }
  return 0.5 * (K + K.transpose());
}

void NeoHookeanTangentBlocks(const ElementRest& rest, double kappa, double pressure, const Eigen::Matrix3d& F,
                             Eigen::Matrix3d* blocks) {
  const Eigen::Matrix<double, 3, 4> b = ShapeGradients(rest);
  const double V = rest.volume, mu = rest.mu;
  const double J = F.determinant();
  // d2J[u b_a^T, w b_b^T] = (u x w) . F (b_a x b_b) = -u^T [F (b_a x b_b)]x w.
  const double c = V * (kappa * (J - 1.0) - mu + pressure);
  const Eigen::Matrix<double, 3, 4> q = Cofactor(F) * b;
  for (int a = 0; a < 4; ++a) {
    for (int d = a; d < 4; ++d) {
      Eigen::Matrix3d& block = blocks[4 * a + d];
      block.noalias() = (V * kappa) * q.col(a) * q.col(d).transpose();
      block.diagonal().array() += V * mu * b.col(a).dot(b.col(d));
      if (d == a) {  // b_a x b_a = 0; symmetric to the bit, as 0.5 (K + K^T) was
        block = (0.5 * (block + block.transpose())).eval();
        continue;
      }
      block -= c * Cross(F * b.col(a).cross(b.col(d)));
      blocks[4 * d + a] = block.transpose();
    }
  }
}

Vector12 VolumeGradient(const ElementRest& rest, const Vector12& x) {
  const Eigen::Matrix<double, 3, 4> g = rest.volume * Cofactor(ElementF(rest, x)) * ShapeGradients(rest);
  Vector12 out;
  for (int k = 0; k < 4; ++k) out.segment<3>(3 * k) = g.col(k);
  return out;
}

}  // namespace femreg
