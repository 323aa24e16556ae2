// Lagged Coulomb friction of one contact (docs/theory/contact.md#friction). With the contact's
// normal n and barycentrics held, its point's tangential slip since a reference state (the
// frame's start in registration, the solve's start in the forward solve) is affine in x:
//   u = T (sum_i c_i x_i) - offset,
// T the 2 by 3 tangent basis (rows orthonormal, perpendicular to n), c_i the barycentrics of
// side a minus those of side b, offset = T (sum_i c_i x0_i) plus the obstacle's own motion
// since then. The block is that residual, 2 components, with a constant Jacobian c_i T; its
// set carries the Huber loss of scale eps (the slip below which a contact sticks), and its
// weight is mu lambda / eps with the normal force lambda held: the energy
//   1/2 w rho(|u|^2) = mu lambda |u|^2 / (2 eps)   for |u| <= eps  (sticking: a stiff spring)
//                    = mu lambda (|u| - eps / 2)   above           (sliding: the force mu lambda)
// is C1, and both back ends take it as least squares with a robust loss. N = 3 against an
// obstacle, 6 between two objects.
#ifndef FEMREG_ENERGY_FRICTION_H_
#define FEMREG_ENERGY_FRICTION_H_

#include <Eigen/Core>
#include <array>
#include <cmath>

namespace femreg {
namespace energy {

template <int N>
struct Friction {
  static constexpr int kResiduals = 2;
  static constexpr int kVertices = N;
  static constexpr bool kConstantJacobian = true;  // the loss, not the residual, bends
  std::array<int, N> vertices{};
  double weight = 1.0;                  // mu lambda / eps (N/m)
  std::array<double, N> coefficients{};  // c_i
  Eigen::Matrix<double, 2, 3, Eigen::RowMajor> tangent =
      (Eigen::Matrix<double, 2, 3, Eigen::RowMajor>() << 1, 0, 0, 0, 1, 0).finished();
  Eigen::Vector2d offset = Eigen::Vector2d::Zero();  // m

  bool Evaluate(const double* const* x, double* r, double** J) const {
    Eigen::Vector3d p = Eigen::Vector3d::Zero();
    for (int i = 0; i < N; ++i) p += coefficients[i] * Eigen::Map<const Eigen::Vector3d>(x[i]);
    Eigen::Map<Eigen::Vector2d> residual(r);
    residual = tangent * p - offset;
    if (J == nullptr) return true;
    for (int i = 0; i < N; ++i) {
      if (J[i] == nullptr) continue;
      Eigen::Map<Eigen::Matrix<double, 2, 3, Eigen::RowMajor>> Ji(J[i]);
      Ji = coefficients[i] * tangent;
    }
    return true;
  }
};

// An orthonormal tangent basis (as rows) of the plane perpendicular to the unit normal n.
inline Eigen::Matrix<double, 2, 3, Eigen::RowMajor> TangentBasis(const Eigen::Vector3d& n) {
  const Eigen::Vector3d helper =
      std::abs(n.x()) < 0.9 ? Eigen::Vector3d::UnitX() : Eigen::Vector3d::UnitY();
  const Eigen::Vector3d t1 = n.cross(helper).normalized();
  const Eigen::Vector3d t2 = n.cross(t1);
  Eigen::Matrix<double, 2, 3, Eigen::RowMajor> T;
  T.row(0) = t1.transpose();
  T.row(1) = t2.transpose();
  return T;
}

}  // namespace energy
}  // namespace femreg

#endif  // FEMREG_ENERGY_FRICTION_H_
