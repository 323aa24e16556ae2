// The fast back end's solve of an equilibrium registration problem (energy/equilibrium.h):
// Gauss-Newton on
//
//   J(x) = E_obj(x) + sum_v phi_v(f_v(x)),   f = dPi/dx,
//
// E_obj the data, temporal and anchor terms. A step solves (H + K Phi K) dx = -(g + K phi'),
// H and g E_obj's Gauss-Newton matrix and gradient, K = d2Pi/dx2 the potential's exact
// Hessian, Phi and phi' the penalties' curvatures and gradients. K Phi K couples a vertex's
// two-ring and fills in far more than K; it is never formed: conjugate gradients multiply
// by it (two products with K), preconditioned by M = K~ Phi~ K~, whose inverse is two
// solves with a Cholesky factor of K~ = K + a small shift (rigid motions of a free body)
// and a 3x3 block per vertex. M^-1 (K Phi K) is the identity, so PCG's iterations go to the
// few smooth modes the data H stiffens: the same spectrum as the reduced, force-space
// problem's (docs/theory/equilibrium.md). Every step factorizes K~ anew; after a step whose
// PCG took many iterations (soft modes of K that the data hold), K~ + s H instead. The step
// stays orthogonal to the problem's held turns (Equilibrium::held_turns: a free body's turns
// that its surface does not show). A step that closes contacts open at x is solved again with
// them closed in its model (solvers/fast/closing_contacts.h).
#ifndef FEMREG_SOLVERS_FAST_EQUILIBRIUM_STEP_H_
#define FEMREG_SOLVERS_FAST_EQUILIBRIUM_STEP_H_

#include <memory>

#include "energy/problem.h"
#include "solvers/backend.h"

namespace femreg {
namespace fast_backend {

class EquilibriumSolver {
 public:
  EquilibriumSolver(const BackendOptions& options, int threads);
  ~EquilibriumSolver();
  // As Backend::Solve, for a problem with an equilibrium (problem.equilibrium() not null).
  SolveReport Solve(const energy::Problem& problem, double time_limit_s, Vertices* x);
  // As Solve, leaving the step mode it learns from solve to solve as it was (Backend::SolveAside).
  SolveReport SolveAside(const energy::Problem& problem, double time_limit_s, Vertices* x);
  // The threads of the next solves (the results do not depend on them).
  void set_threads(int threads);

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace fast_backend
}  // namespace femreg

#endif  // FEMREG_SOLVERS_FAST_EQUILIBRIUM_STEP_H_
