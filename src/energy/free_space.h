// Free space (docs/theory/data-terms.md#free-space): the camera saw along each ray as far as
// the observed surface, so the model may not be in front of it. With the ray's unit direction
// n from the sensor (its position e, or any point on the ray's line for an orthographic view)
// held between outer iterations, and the depth along it that the observation allows, s (the
// observed depth minus a tolerance), the residual
//   r = max(0, s - n . (x - e))
// is one-sided: zero wherever the vertex is behind s, and 1/2 k r^2 pushes it back along the
// ray when it is in front. Affine wherever it is differentiable, like the contact penalty.
#ifndef FEMREG_ENERGY_FREE_SPACE_H_
#define FEMREG_ENERGY_FREE_SPACE_H_

#include <Eigen/Core>
#include <array>

namespace femreg {
namespace energy {

struct FreeSpacePenalty {
  static constexpr int kResiduals = 1;
  static constexpr int kVertices = 1;
  static constexpr bool kConstantJacobian = false;  // zero behind the observed depth
  static constexpr bool kPiecewiseAffine = true;
  std::array<int, 1> vertices{};
  double weight = 1.0;                                // k (N/m)
  Eigen::Vector3d ray = Eigen::Vector3d::UnitZ();     // n, unit, away from the sensor
  Eigen::Vector3d origin = Eigen::Vector3d::Zero();   // e (m)
  double depth = 0.0;                                 // s (m): the nearest allowed depth along n

  // How far the vertex is in front of the allowed depth (> 0: in the seen-through space).
  double Violation(const double* x) const {
    return depth - ray.dot(Eigen::Map<const Eigen::Vector3d>(x) - origin);
  }
  bool Inactive(const double* const* x) const { return !(Violation(x[0]) > 0); }
  bool Evaluate(const double* const* x, double* r, double** J) const {
    const double v = Violation(x[0]);
    const bool active = v > 0;
    r[0] = active ? v : 0.0;
    if (J != nullptr && J[0] != nullptr) {
      Eigen::Map<Eigen::Vector3d> J0(J[0]);
      if (active) {
        J0 = -ray;
      } else {
        J0.setZero();
      }
    }
    return true;
  }
};

}  // namespace energy
}  // namespace femreg

#endif  // FEMREG_ENERGY_FREE_SPACE_H_
