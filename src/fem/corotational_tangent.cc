// The consistent corotational tangent: the exact Hessian of the corotational element's energy
// (femreg/fem.h for the derivation, docs/theory/hessians.md for both of its forms).
#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>

#include "femreg/fem.h"
#include "fem/twist_matrix.h"

namespace femreg {

namespace {
// The signed SVD from the polar rotation R of F (Newton's, from a close start): S = R^T F is
// symmetric, its eigenvectors are V and U = R V. A 3x3 eigensolver in closed form costs about
// a fifth of the SVD. Its eigenvalues come from a cubic's roots, which split a double root by
// about sqrt(eps); the Rayleigh quotients v^T S v of its eigenvectors are accurate to
// round-off (any vector of a double root's plane has that root's quotient). False where the
// eigenvectors are not orthonormal to 1e-10, for the SVD to decide.
bool SignedSvdFromPolar(const Eigen::Matrix3d& F, const Eigen::Matrix3d& R, SignedSvd* out) {
  Eigen::Matrix3d S = R.transpose() * F;
  S = (0.5 * (S + S.transpose())).eval();
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eigen;
  eigen.computeDirect(S);
  const Eigen::Vector3d& values = eigen.eigenvalues();
  const Eigen::Matrix3d& vectors = eigen.eigenvectors();
  if (!values.allFinite() || !vectors.allFinite() ||
      !((vectors.transpose() * vectors - Eigen::Matrix3d::Identity()).cwiseAbs().maxCoeff() <= 1e-10)) {
    return false;
  }
  Eigen::Vector3d quotients;
  for (int k = 0; k < 3; ++k) quotients(k) = vectors.col(k).dot(S * vectors.col(k));
  // |sigma| decreasing. R maximizes tr(R^T F), so a negative eigenvalue is the smallest in
  // size, and lands in sigma(2) unless it ties with another (the tangent sums over unordered
  // pairs: the order does not change it).
  int order[3] = {0, 1, 2};
  std::sort(order, order + 3, [&](int a, int b) { return std::abs(quotients(a)) > std::abs(quotients(b)); });
  for (int k = 0; k < 3; ++k) {
    out->sigma(k) = quotients(order[k]);
    out->V.col(k) = vectors.col(order[k]);
  }
  if (out->V.determinant() < 0) out->V.col(2) *= -1.0;
  out->U = R * out->V;
  return true;
}

}  // namespace

Matrix12 CorotationalTangent(const ElementRest& rest, const Vector12& x,
                             TangentProjection projection, ElementTangentInfo* info,
                             Eigen::Matrix3d* rotation, const Eigen::Matrix3d* start) {
  Eigen::Matrix<double, 3, 4> xm;
  for (int k = 0; k < 4; ++k) xm.col(k) = x.segment<3>(3 * k);
  const Eigen::Matrix3d F = DeformationGradient(xm, rest.dm_inv);
  SignedSvd svd;
  if (start == nullptr || !F.allFinite() || !SignedSvdFromPolar(F, PolarRotation(F, *start), &svd)) {
    svd = SignedSingularValueDecomposition(F);
  }
  const Eigen::Matrix3d R = svd.U * svd.V.transpose();
  if (rotation != nullptr) *rotation = R;
  Matrix12 tangent = WarpedStiffness(rest, R);

  // Lame parameters of the (isotropic) Hooke matrix, and tr(S - I).
  const double mu = rest.mu;
  const double lambda = rest.lambda;
  const double trace = svd.sigma.sum() - 3.0;
  // Shape-function gradients (columns): F = sum_k x_k grad N_k^T.
  Eigen::Matrix<double, 3, 4> grad;
  grad.rightCols<3>() = rest.dm_inv.transpose();
  grad.col(0) = -grad.rightCols<3>().rowwise().sum();

  ElementTangentInfo stats;
  bool have_min = false;
  static const int kPairs[3][2] = {{0, 1}, {0, 2}, {1, 2}};
  for (const auto& pair : kPairs) {
    const int i = pair[0], j = pair[1];
    const double sum = svd.sigma(i) + svd.sigma(j);
    if (!(sum >= kMinTwistSingularSum)) {
      ++stats.degenerate_modes;
      continue;
    }
    double g = 2.0 * mu + 2.0 * (lambda * trace - 2.0 * mu) / sum;
    stats.min_eigenvalue = have_min ? std::fmin(stats.min_eigenvalue, g) : g;
    have_min = true;
    if (g < 0.0) {
      ++stats.negative_modes;
      if (projection == TangentProjection::kPositiveSemiDefinite) continue;
    }
    const Eigen::Matrix3d T = (svd.U.col(i) * svd.V.col(j).transpose() -
                               svd.U.col(j) * svd.V.col(i).transpose()) /
                              std::sqrt(2.0);
    Vector12 b;
    for (int k = 0; k < 4; ++k) b.segment<3>(3 * k) = T * grad.col(k);
    tangent.noalias() += (rest.volume * g) * b * b.transpose();
  }
  if (info != nullptr) *info = stats;
  return tangent;
}

bool CorotationalTangentBlocks(const ElementRest& rest, const Eigen::Matrix3d& F, const Eigen::Matrix3d& R,
                               Eigen::Matrix3d* blocks) {
  // M = tr(S) I - S, S = sym(R^T F), through its adjugate, as PolarRotation's Newton step.
  const Eigen::Matrix3d A = R.transpose() * F;
  const double trace = A.trace();
  const TwistMatrix m(A);
  const double min_pivot = 1e-4 * F.cwiseAbs().maxCoeff();
  if (!(min_pivot > 0.0) || !m.PivotsAtLeast(min_pivot)) return false;
  // Pivots bound M's smallest eigenvalue only from above (an oblique axis of a nearly flat
  // element passes them); det / tr(adj M) bounds it from below: taken only where every
  // sigma_i + sigma_j is at least kMinTwistSingularSum, where the eigendecomposition keeps all
  // three twist modes.
  if (!(m.det >= kMinTwistSingularSum * (m.c00 + m.c11 + m.c22))) return false;
  const double mu = rest.mu, lambda = rest.lambda, V = rest.volume;
  Eigen::Matrix3d adjugate;
  adjugate << m.c00, m.c10, m.c20, m.c10, m.c11, m.c21, m.c20, m.c21, m.c22;
  // With Z = mu I + k R M^-1 R^T (k = lambda tr(S - I) - 2 mu) the twist adds
  // -V [c_a]x Z [c_b]x; its mu I part, mu ((c_a . c_b) I - c_b c_a^T), turns the warped
  // stiffness' mu c_b c_a^T into a second mu (c_a . c_b) I, which leaves
  //   V (lambda c_a c_b^T + 2 mu (c_a . c_b) I) - [c_a]x W [c_b]x,  W = V k R M^-1 R^T.
  const Eigen::Matrix3d W = (V * (lambda * (trace - 3.0) - 2.0 * mu) / m.det) * (R * adjugate * R.transpose());
  Eigen::Matrix<double, 4, 3> b;
  b.bottomRows<3>() = rest.dm_inv;
  b.row(0) = -(rest.dm_inv.row(0) + rest.dm_inv.row(1) + rest.dm_inv.row(2));
  const Eigen::Matrix<double, 4, 3> c = b * R.transpose();  // row a: (R b_a)^T
  // E_d = W [c_d]x, column by column: [c]x e_j = c x e_j.
  Eigen::Matrix3d E[4];
  for (int d = 0; d < 4; ++d) {
    const double x0 = c(d, 0), x1 = c(d, 1), x2 = c(d, 2);
    E[d].col(0) = x2 * W.col(1) - x1 * W.col(2);
    E[d].col(1) = x0 * W.col(2) - x2 * W.col(0);
    E[d].col(2) = x1 * W.col(0) - x0 * W.col(1);
  }
  const double Vlambda = V * lambda, V2mu = 2.0 * V * mu;
  for (int a = 0; a < 4; ++a) {
    const Eigen::Vector3d ca = c.row(a).transpose();
    for (int d = a; d < 4; ++d) {
      Eigen::Matrix3d& block = blocks[4 * a + d];
      block.noalias() = (Vlambda * ca) * c.row(d);
      for (int j = 0; j < 3; ++j) block.col(j) += E[d].col(j).cross(ca);  // -[c_a]x E_d
      block.diagonal().array() += V2mu * ca.dot(c.row(d).transpose());
      if (d != a) {
        blocks[4 * d + a] = block.transpose();
      } else {
        block = (0.5 * (block + block.transpose())).eval();  // symmetric to the bit, as the sum of b b^T
      }
    }
  }
  return true;
}

}  // namespace femreg
