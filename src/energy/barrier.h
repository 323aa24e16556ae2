// The inversion barrier: an element compressed below a fraction j of its rest volume stores
//   e = V mu (j - J)^2 log(j / J),   J = det F = v / V,
// which is zero with its first two derivatives at J = j and grows without bound as J -> 0
// (IPC's barrier, on the volume ratio instead of a distance). An element's volume then never
// reaches zero: a step that would flatten or invert one has infinite energy, and the line
// search (both back ends) refuses it. Added to any material's elements (the corotational one
// has inverted states that cost little), in the elastic group: its force is part of the
// body's internal force (docs/theory/inversion.md).
#ifndef FEMREG_ENERGY_BARRIER_H_
#define FEMREG_ENERGY_BARRIER_H_

#include <Eigen/Core>
#include <array>
#include <vector>

#include "energy/term.h"
#include "femreg/fem.h"
#include "femreg/mesh.h"

namespace femreg {
namespace energy {

// As least squares: r = sqrt(2 V mu) (j - J) sqrt(log(j / J)) for 0 < J < j, 0 for J >= j,
// +inf for J <= 0 (the energy of an inverted element). J_i = dr/dJ cof(F) b_i.
struct InversionBarrier {
  static constexpr int kResiduals = 1;
  static constexpr int kVertices = 4;
  static constexpr bool kConstantJacobian = false;
  // Gauss-Newton's J^T J falls short of the curvature near the wall by a factor 2 log(j / J):
  // its steps run into the wall and the line search cuts them. Newton's (projected) instead.
  static constexpr bool kNewtonCurvature = true;
  std::array<int, 4> vertices = {{0, 0, 0, 0}};
  double weight = 1.0;
  const ElementRest* rest = nullptr;
  double threshold = 0.2;  // j: the volume ratio below which the barrier acts, in (0, 1]
  double wall = 0.0;       // j det D_m: the triple product det D_s below which it acts

  InversionBarrier() = default;
  InversionBarrier(const std::array<int, 4>& vertices, const ElementRest& rest, double weight, double threshold);

  // Most elements are far from the wall: their residual and Jacobian are zero, which one
  // triple product of the positions tells, without F or the rest state (energy/term.h).
  bool Inactive(const double* const* x) const {
    const double* a = x[0];
    const double e[3][3] = {{x[1][0] - a[0], x[1][1] - a[1], x[1][2] - a[2]},
                            {x[2][0] - a[0], x[2][1] - a[1], x[2][2] - a[2]},
                            {x[3][0] - a[0], x[3][1] - a[1], x[3][2] - a[2]}};
    const double triple = e[0][0] * (e[1][1] * e[2][2] - e[1][2] * e[2][1]) -
                          e[0][1] * (e[1][0] * e[2][2] - e[1][2] * e[2][0]) +
                          e[0][2] * (e[1][0] * e[2][1] - e[1][1] * e[2][0]);
    return triple >= wall;
  }
  bool Evaluate(const double* const* x, double* r, double** J) const;
  // e = V mu phi(J), phi = (j - J)^2 log(j / J); its Hessian V mu B^T (phi'' g g^T + phi' H_J) B
  // (g = vec cof F, H_J the Hessian of det F, B = dvec F / dx); the projection clamps the
  // negative eigenvalues of phi' H_J's 9 by 9 sum with the first term.
  bool SecondOrder(const double* const* x, double* energy, Eigen::Vector3d* gradient,
                   Eigen::Matrix3d* hessian, TangentProjection projection) const;
};

// The volume ratio det F of an element at positions x[0..3].
double VolumeRatio(const ElementRest& rest, const double* const* x);

// A fraction t <= alpha of the step dx (3 per vertex) from x at which every barrier element
// keeps at least half of its volume at x and at least half of the barrier's threshold volume:
// a step cut to t lands inside the barrier's zone, not at its wall, so that the next step has
// its curvature. alpha when no element is below that at alpha dx; else, for each such
// element, a crossing bisection finds between 0 and the t so far. Elements are tested at the
// ends only: one whose volume dips below and comes back within the step is not seen (the
// line search's energy test is what stands against it).
double UprightFraction(const std::vector<TermSet<InversionBarrier>>& sets, const Vertices& x,
                       const Eigen::VectorXd& dx, double alpha);

}  // namespace energy
}  // namespace femreg

#endif  // FEMREG_ENERGY_BARRIER_H_
