// The contact penalty (docs/theory/contact.md#response; femreg/collision.h gives the sign
// conventions): with the normal n held between detections, delta = s - n . (p_a - p_b), s the
// standoff where the penalty starts (0, or an augmented-Lagrangian lambda / k), is linear in
// the stencil's positions, delta = offset - sum_i c_i n . x_i (c_i: the barycentrics of side
// a, minus those of side b; offset: s, plus n . p_b for a fixed obstacle point), and the
// residual r = max(0, delta) is one-sided: 1/2 k r^2 with k the weight. N = 3 against an
// obstacle, 6 between two objects, 4 for an embedded surface's point (carried by 4 cage
// vertices) against an obstacle.
#ifndef FEMREG_ENERGY_CONTACT_H_
#define FEMREG_ENERGY_CONTACT_H_

#include <Eigen/Core>
#include <array>

namespace femreg {
namespace energy {

template <int N>
struct ContactPenalty {
  static constexpr int kResiduals = 1;
  static constexpr int kVertices = N;
  static constexpr bool kConstantJacobian = false;  // zero once the contact opens
  // ... but r is affine wherever it is differentiable: J^T J is the exact Hessian of 1/2 r^2
  // (energy/term.h, Curvature).
  static constexpr bool kPiecewiseAffine = true;
  std::array<int, N> vertices{};
  double weight = 1.0;                                  // k (N/m)
  std::array<double, N> coefficients{};                 // c_i
  Eigen::Vector3d normal = Eigen::Vector3d::UnitZ();    // n, from b towards a
  double offset = 0.0;                                  // m

  double Penetration(const double* const* x) const {
    double delta = offset;
    for (int i = 0; i < N; ++i) delta -= coefficients[i] * normal.dot(Eigen::Map<const Eigen::Vector3d>(x[i]));
    return delta;
  }
  bool Evaluate(const double* const* x, double* r, double** J) const {
    const double delta = Penetration(x);
    const bool active = delta > 0;
    r[0] = active ? delta : 0.0;
    if (J == nullptr) return true;
    for (int i = 0; i < N; ++i) {
      if (J[i] == nullptr) continue;
      Eigen::Map<Eigen::Vector3d> Ji(J[i]);
      if (active) {
        Ji = -coefficients[i] * normal;
      } else {
        Ji.setZero();
      }
    }
    return true;
  }
};

}  // namespace energy
}  // namespace femreg

#endif  // FEMREG_ENERGY_CONTACT_H_
