// The volumetric energy of the neo-Hookean element on the vertices instead of on each element
// (femreg/fem.h: the average nodal pressure tetrahedron, against the locking of linear
// tetrahedra as nu -> 0.5):
//   N(x) = sum_a K_a V_a / 2 (J_a - 1)^2,   J_a = v_a(x) / V_a,
// V_a a quarter of the rest volumes of the elements around vertex a, v_a the same of their
// current volumes, K_a their volume-weighted bulk modulus. Its elements then carry the
// deviatoric energy only (NeoHookeanElement::deviatoric). A vertex's volume couples every
// vertex of the elements around it, a stencil of no fixed size, so this term is not a block
// type: it adds its value, gradient and Hessian next to the assembler's (energy/assembler.h).
//   dN/dx = sum_e p_e dv_e/dx,  p_e = sum of its vertices' K_a (J_a - 1) / 4 (a pressure, Pa),
//   d2N/dx2 = sum_a K_a / V_a (dv_a/dx)(dv_a/dx)^T + sum_e p_e d2v_e/dx2.
// The first sum is positive semi-definite; the second, V_e B^T (p_e H_J) B per element (H_J
// the Hessian of det F), is indefinite, and its projection clamps the negative eigenvalues
// of p_e H_J; Gauss-Newton's matrix (registration's, where N is a sum of squares of the
// residuals sqrt(K_a / V_a) (v_a - V_a)) is the first sum alone.
#ifndef FEMREG_ENERGY_NODAL_VOLUME_H_
#define FEMREG_ENERGY_NODAL_VOLUME_H_

#include <Eigen/Core>
#include <array>
#include <utility>
#include <vector>

#include "energy/assembler.h"
#include "energy/term.h"
#include "femreg/fem.h"
#include "femreg/mesh.h"

namespace femreg {
namespace energy {

class NodalVolume {
 public:
  // Vertex a's share of N as one residual, r_a = sqrt(K_a V_a) (J_a - 1), so that N = 1/2
  // sum_a r_a^2 (the Ceres back end's form): the vertices of the elements around a, and per
  // element its rest data and its four vertices' places among them.
  struct Star {
    std::vector<int> vertices;
    std::vector<std::array<int, 4>> elements;
    std::vector<const ElementRest*> rests;
    double rest_volume = 0.0;  // V_a
    double stiffness = 0.0;    // K_a V_a, the scale included
  };
  int num_vertices() const { return num_vertices_; }
  Star StarOf(int a) const;
  // r_a at the star's positions x[i] (3 each) and, if not null, dr_a/dx[i] (3 each; an entry
  // null: not wanted).
  static double StarResidual(const Star& star, const double* const* x, double** jacobians);

  // The elements (vertex indices into the positions) and their rest data, which must
  // outlive this term; `scale` multiplies the energy (registration's elastic weight).
  void Build(const Tets& tets, const std::vector<const ElementRest*>& rests, int num_vertices,
             int threads, double scale = 1.0);
  // The vertex pairs the Hessian couples (for Assembler::Prepare), a < b, sorted.
  const std::vector<std::pair<int, int>>& Pairs() const { return pairs_; }
  // N(x); adds dN/dx to *gradient (3 #V) when not null.
  double Evaluate(const Vertices& x, Eigen::VectorXd* gradient) const;
  // Adds d2N/dx2 at x (or its projection) into the assembler's H.
  void AddHessian(const Vertices& x, Curvature curvature, Assembler* assembler) const;

 private:
  // Per element v_e - V_e and, if not null, dv_e/dx; per element its pressure p_e. Returns N.
  double Pressures(const Vertices& x, std::vector<double>* pressure,
                   std::vector<Vector12>* volume_gradient) const;
  Tets tets_;
  std::vector<const ElementRest*> rests_;
  int num_vertices_ = 0;
  int threads_ = 1;
  std::vector<double> rest_volume_, stiffness_;  // per vertex: V_a, K_a V_a
  std::vector<int> element_offsets_, element_slots_;  // vertex -> 4 e + k of its elements
  std::vector<std::pair<int, int>> pairs_;
};

}  // namespace energy
}  // namespace femreg

#endif  // FEMREG_ENERGY_NODAL_VOLUME_H_
