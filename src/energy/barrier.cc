#include "energy/barrier.h"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <limits>

namespace femreg {
namespace energy {

namespace {

Eigen::Matrix3d Deformation(const Eigen::Matrix<double, 3, 4>& B, const double* const* x) {
  Eigen::Matrix3d F = Eigen::Matrix3d::Zero();
  for (int i = 0; i < 4; ++i) F.noalias() += Eigen::Map<const Eigen::Vector3d>(x[i]) * B.col(i).transpose();
  return F;
}

// phi(J) = (j - J)^2 log(j / J) and its first two derivatives, for 0 < J < j.
void Phi(double J, double j, double* phi, double* d1, double* d2) {
  const double gap = j - J, log_ratio = std::log(j / J);
  *phi = gap * gap * log_ratio;
  *d1 = -2.0 * gap * log_ratio - gap * gap / J;
  *d2 = 2.0 * log_ratio + 4.0 * gap / J + gap * gap / (J * J);
}

}  // namespace

double VolumeRatio(const ElementRest& rest, const double* const* x) {
  // det F = det D_s det D_m^-1, D_s's columns the edges from vertex 0: a triple product.
  const Eigen::Map<const Eigen::Vector3d> x0(x[0]), x1(x[1]), x2(x[2]), x3(x[3]);
  return (x1 - x0).dot((x2 - x0).cross(x3 - x0)) * rest.dm_inv.determinant();
}

InversionBarrier::InversionBarrier(const std::array<int, 4>& vertices_in, const ElementRest& rest_in,
                                   double weight_in, double threshold_in)
    : vertices(vertices_in), weight(weight_in), rest(&rest_in), threshold(threshold_in),
      wall(threshold_in / rest_in.dm_inv.determinant()) {}

bool InversionBarrier::Evaluate(const double* const* x, double* r, double** J) const {
  if (Inactive(x)) {
    r[0] = 0.0;
    for (int i = 0; i < 4; ++i) {
      if (J != nullptr && J[i] != nullptr) std::fill(J[i], J[i] + 3, 0.0);
    }
    return true;
  }
  const Eigen::Matrix<double, 3, 4> B = ShapeGradients(*rest);
  const Eigen::Matrix3d F = Deformation(B, x);
  const double ratio = F.determinant();
  auto zero_jacobian = [&]() {
    for (int i = 0; i < 4; ++i) {
      if (J != nullptr && J[i] != nullptr) std::fill(J[i], J[i] + 3, 0.0);
    }
  };
  if (!(ratio > 0.0)) {
    r[0] = std::numeric_limits<double>::infinity();
    zero_jacobian();
    return true;
  }
  if (ratio >= threshold) {
    r[0] = 0.0;
    zero_jacobian();
    return true;
  }
  const double scale = std::sqrt(2.0 * rest->volume * rest->mu);
  const double gap = threshold - ratio, root = std::sqrt(std::log(threshold / ratio));
  r[0] = scale * gap * root;
  if (J == nullptr) return true;
  // d/dJ [(j - J) sqrt(log(j / J))] = -sqrt(L) - (j - J) / (2 J sqrt(L)).
  const double slope = scale * (-root - gap / (2.0 * ratio * root));
  const Eigen::Matrix3d cof = Cofactor(F);
  for (int i = 0; i < 4; ++i) {
    if (J[i] == nullptr) continue;
    const Eigen::Vector3d row = slope * (cof * B.col(i));
    std::copy(row.data(), row.data() + 3, J[i]);
  }
  return true;
}

bool InversionBarrier::SecondOrder(const double* const* x, double* energy, Eigen::Vector3d* gradient,
                                   Eigen::Matrix3d* hessian, TangentProjection projection) const {
  for (int i = 0; i < 4; ++i) gradient[i].setZero();
  if (hessian != nullptr) {
    for (int k = 0; k < 16; ++k) hessian[k].setZero();
  }
  *energy = 0.0;
  if (Inactive(x)) return true;
  const Eigen::Matrix<double, 3, 4> B = ShapeGradients(*rest);
  const Eigen::Matrix3d F = Deformation(B, x);
  const double ratio = F.determinant();
  if (!(ratio > 0.0)) {
    *energy = std::numeric_limits<double>::infinity();
    return true;
  }
  if (ratio >= threshold) return true;
  const double c = rest->volume * rest->mu;
  double phi = 0, d1 = 0, d2 = 0;
  Phi(ratio, threshold, &phi, &d1, &d2);
  *energy = c * phi;
  const Eigen::Matrix3d cof = Cofactor(F);
  for (int i = 0; i < 4; ++i) gradient[i] = c * d1 * (cof * B.col(i));
  if (hessian == nullptr) return true;
  Eigen::Map<const Eigen::Matrix<double, 9, 1>> g(cof.data());
  Matrix9 H = d2 * g * g.transpose() + d1 * DeterminantHessian(F);
  if (projection == TangentProjection::kPositiveSemiDefinite) {
    Eigen::SelfAdjointEigenSolver<Matrix9> eig(H);
    H = eig.eigenvectors() * eig.eigenvalues().cwiseMax(0.0).asDiagonal() * eig.eigenvectors().transpose();
  }
  // (i, j)[a][c] = sum_pq H(a + 3p, c + 3q) b_i[p] b_j[q] (vec F column-major).
  for (int i = 0; i < 4; ++i) {
    for (int j = 0; j < 4; ++j) {
      Eigen::Matrix3d& h = hessian[i * 4 + j];
      for (int p = 0; p < 3; ++p) {
        for (int q = 0; q < 3; ++q) h += (B(p, i) * B(q, j)) * H.block<3, 3>(3 * p, 3 * q);
      }
      h *= c;
    }
  }
  return true;
}

double UprightFraction(const std::vector<TermSet<InversionBarrier>>& sets, const Vertices& x,
                       const Eigen::VectorXd& dx, double alpha) {
  double t = alpha;
  for (const TermSet<InversionBarrier>& set : sets) {
    for (const InversionBarrier& b : set.blocks()) {
      // The triple product det D_s (six times the volume) along the step, at a fraction s of it.
      auto triple = [&](double s) {
        auto at = [&](int i) -> Eigen::Vector3d {
          return x.row(b.vertices[i]).transpose() + s * dx.segment<3>(3 * b.vertices[i]);
        };
        return 6.0 * SignedTetVolume(at(0), at(1), at(2), at(3));
      };
      const double target = 0.5 * std::min(b.wall, triple(0.0));
      if (!(target > 0.0) || triple(t) > target) continue;
      double lo = 0.0, hi = t;  // triple(lo) > target >= triple(hi)
      for (int k = 0; k < 40; ++k) {
        const double mid = 0.5 * (lo + hi);
        (triple(mid) > target ? lo : hi) = mid;
      }
      t = lo;
    }
  }
  return t;
}

}  // namespace energy
}  // namespace femreg
