// External loads: the work of a constant force f (N) on a vertex — gravity on its lumped
// mass, a nodal load — whose potential is -f . x. A sum of squares has no linear term, so
// the block writes it about a point x0 (the vertex at the start of the outer iteration,
// FrameProblem::SetLoads) with a scale a > 0 (sqrt(J)):
//
//   r = sqrt(2) (a - f . (x - x0) / (2 a)),   1/2 r^2 = a^2 - f . (x - x0) + (f . (x - x0))^2 / (4 a^2).
//
// The constant a^2 moves nothing; the gradient is -f at x0, and the last term is a spring of
// stiffness f f^T / (2 a^2) along f that only acts while x moves away from x0 within one outer
// iteration: at the outer loop's fixed point (x0 = x) the force is exactly f. With a^2 = |f| l
// (l the mesh's mean edge length) that stiffness is |f| / (2 l), far below the elastic
// stiffness around a vertex (~ E l): rho g l / E ~ 1e-3 for a gel.
#ifndef FEMREG_ENERGY_LOAD_H_
#define FEMREG_ENERGY_LOAD_H_

#include <Eigen/Core>
#include <array>
#include <cmath>

namespace femreg {
namespace energy {

struct ExternalLoad {
  static constexpr int kResiduals = 1;
  static constexpr int kVertices = 1;
  static constexpr bool kConstantJacobian = true;
  std::array<int, 1> vertices{};
  double weight = 1.0;
  Eigen::Vector3d force = Eigen::Vector3d::Zero();   // f (N)
  Eigen::Vector3d origin = Eigen::Vector3d::Zero();  // x0 (m)
  double scale = 1.0;                                // a (sqrt(J)), > 0

  bool Evaluate(const double* const* x, double* r, double** J) const {
    const Eigen::Vector3d dx = Eigen::Map<const Eigen::Vector3d>(x[0]) - origin;
    r[0] = std::sqrt(2.0) * (scale - force.dot(dx) / (2.0 * scale));
    if (J != nullptr && J[0] != nullptr) {
      Eigen::Map<Eigen::Vector3d> J0(J[0]);
      J0 = -force / (std::sqrt(2.0) * scale);
    }
    return true;
  }
};

// The block for vertex v with force f about x0, a^2 = |f| l; false (no block) for f = 0.
inline bool MakeExternalLoad(int vertex, const Eigen::Vector3d& force, const Eigen::Vector3d& origin,
                             double length, ExternalLoad* block) {
  const double f = force.norm();
  if (!(f > 0) || !(length > 0)) return false;
  block->vertices = {{vertex}};
  block->force = force;
  block->origin = origin;
  block->scale = std::sqrt(f * length);
  return true;
}

}  // namespace energy
}  // namespace femreg

#endif  // FEMREG_ENERGY_LOAD_H_
