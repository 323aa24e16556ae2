// The elastic terms: the corotational (or, with R = I, small-strain) FEM element, and a
// spring on a mesh edge (the mass-spring regularizer, for comparison).
#ifndef FEMREG_ENERGY_ELASTIC_H_
#define FEMREG_ENERGY_ELASTIC_H_

#include <Eigen/Core>
#include <array>

#include "femreg/fem.h"

namespace femreg {
namespace energy {

// One tetrahedron: r = S (R^T x_e - X_e) (6 residuals; 1/2 w |r|^2 = w E_e, seed eqs. 1-6),
// with the element's rest data and rotation (femreg/fem.h) read through pointers, so that
// refreshing the rotations between outer iterations needs no new block. J_i = S_i R^T.
struct ElasticElement {
  static constexpr int kResiduals = 6;
  static constexpr int kVertices = 4;
  static constexpr bool kConstantJacobian = true;  // while R is held
  std::array<int, 4> vertices = {{0, 0, 0, 0}};
  double weight = 1.0;
  const ElementRest* rest = nullptr;
  const Eigen::Matrix3d* rotation = nullptr;

  bool Evaluate(const double* const* x, double* r, double** J) const;
};

// A spring on an edge: r = |x_a - x_b| - L, 1/2 k r^2 with k the weight. At zero length the
// direction is undefined and the Jacobian is zero.
struct EdgeSpring {
  static constexpr int kResiduals = 1;
  static constexpr int kVertices = 2;
  static constexpr bool kConstantJacobian = false;
  std::array<int, 2> vertices = {{0, 0}};
  double weight = 1.0;  // k (N/m)
  double length = 0.0;  // L (m)

  bool Evaluate(const double* const* x, double* r, double** J) const;
};

}  // namespace energy
}  // namespace femreg

#endif  // FEMREG_ENERGY_ELASTIC_H_
