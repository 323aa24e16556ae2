// The elastic terms: the corotational (or, with R = I, small-strain) FEM element, and a
// spring on a mesh edge (the mass-spring regularizer, for comparison).
#ifndef FEMREG_ENERGY_ELASTIC_H_
#define FEMREG_ENERGY_ELASTIC_H_

#include <Eigen/Core>
#include <array>

#include "femreg/fem.h"

namespace femreg {
namespace energy {

// One tetrahedron: r = S (R^T x_e - X_e) (6 residuals; 1/2 w |r|^2 = w E_e, the corotational
// element of docs/theory), with the element's rest data and rotation (femreg/fem.h) read
// through pointers, so that refreshing the rotations between outer iterations needs no new
// block. J_i = S_i R^T.
struct ElasticElement {
  static constexpr int kResiduals = 6;
  static constexpr int kVertices = 4;
  static constexpr bool kConstantJacobian = true;  // while R is held
  std::array<int, 4> vertices = {{0, 0, 0, 0}};
  double weight = 1.0;
  const ElementRest* rest = nullptr;
  const Eigen::Matrix3d* rotation = nullptr;
  // false: the small-strain element, whose R stays I.
  bool corotational = true;

  bool Evaluate(const double* const* x, double* r, double** J) const;
  // The same in closed form (see energy/term.h): |r|^2 = V (2 mu e:e + lambda tr(e)^2) with
  // the small strain e = sym(R^T F - I); J_i^T r = V R P b_i with P = 2 mu e + lambda tr(e) I
  // and b_i the shape gradients; J_i^T J_j = V (mu (b_i.b_j) I + mu c_j c_i^T + lambda c_i c_j^T)
  // with c = R b. A third of the flops of forming J = S R^T and J^T J, and S is not read.
  // jtr null: |r|^2 only.
  bool Normal(const double* const* x, double* squared_norm, Eigen::Vector3d* jtr,
              Eigen::Matrix3d* jtj) const;
  // The exact element (energy/term.h's SecondOrder): R = R(x), the polar rotation of F(x)
  // (the held rotation is only Newton's start), and the Hessian the consistent corotational
  // tangent (femreg/fem.h's CorotationalTangent); the small-strain element's is K.
  bool SecondOrder(const double* const* x, double* energy, Eigen::Vector3d* gradient,
                   Eigen::Matrix3d* hessian, TangentProjection projection) const;
};

// The stable neo-Hookean element (femreg/fem.h) as least squares. With kappa = lambda + mu
// and alpha = 1 + mu / kappa,
//   r = sqrt(V) [sqrt(mu) vec F; sqrt(kappa) (J - alpha)]   (10 residuals),
// 1/2 |r|^2 = V (psi(F) + c), c = 3 mu / 2 + mu^2 / (2 kappa): the element's energy plus a
// constant, which Offset() gives (|r|^2 at rest) and the energy layer leaves out of the
// value (energy/term.h). Its Gauss-Newton matrix V (mu I + kappa g g^T) (g = vec cof F) is
// the Hessian without the (kappa (J - alpha)) H_J term: positive semi-definite for every F,
// also inverted ones, with no rotation to hold. J_i = sqrt(V) [sqrt(mu) (b_i^T (x) I);
// sqrt(kappa) (cof F b_i)^T], b_i the shape gradients.
struct NeoHookeanElement {
  static constexpr int kResiduals = 10;
  static constexpr int kVertices = 4;
  static constexpr bool kConstantJacobian = false;
  std::array<int, 4> vertices = {{0, 0, 0, 0}};
  double weight = 1.0;
  const ElementRest* rest = nullptr;
  // The deviatoric part of the nodal-volume split (kappa = mu / 3, femreg/fem.h), whose
  // volumetric energy is energy::NodalVolume's; else the whole element (kappa = lambda + mu).
  bool deviatoric = false;

  bool Evaluate(const double* const* x, double* r, double** J) const;
  // In closed form: |r|^2 = V (mu |F|^2 + kappa (J - alpha)^2), J_i^T r = V (mu F +
  // kappa (J - alpha) cof F) b_i, J_i^T J_j = V (mu (b_i . b_j) I + kappa c_i c_j^T) with
  // c = cof(F) b.
  bool Normal(const double* const* x, double* squared_norm, Eigen::Vector3d* jtr,
              Eigen::Matrix3d* jtj) const;
  double Offset() const;
  // e = 1/2 |r|^2 = V psi(F) + Offset() / 2, and the Hessian V B^T (d2psi/dF2) B
  // (femreg/fem.h's NeoHookeanTangent), projected if asked.
  bool SecondOrder(const double* const* x, double* energy, Eigen::Vector3d* gradient,
                   Eigen::Matrix3d* hessian, TangentProjection projection) const;
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
  // H_00 = u u^T + (1 - L / |d|) (I - u u^T) (d = x_a - x_b, u = d / |d|), H_01 = -H_00;
  // the projection clamps the compressed spring's negative lateral term to 0.
  bool SecondOrder(const double* const* x, double* energy, Eigen::Vector3d* gradient,
                   Eigen::Matrix3d* hessian, TangentProjection projection) const;
};

}  // namespace energy
}  // namespace femreg

#endif  // FEMREG_ENERGY_ELASTIC_H_
