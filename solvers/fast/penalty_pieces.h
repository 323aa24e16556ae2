// The pushing-only penalty's pieces within a Gauss-Newton step of the equilibrium solve
// (solvers/fast/equilibrium_step.h). The penalty 1/2 beta dist(f, C)^2 on a surface force f
// is smooth inside the cone C and on each piece beyond it (the half-space's face, the cone's
// side, its apex), with kinks between them; frictionless, a force near zero changes piece with
// the sign of f . n. The step's model, the penalty's expansion at x's forces f, is wrong
// wherever the step carries a force to another piece. Given the step's predicted forces
// f + K dx, the penalty of each vertex whose piece changes is modelled around its prediction,
// and the step is solved again on the same factor
// (docs/theory/equilibrium.md, docs/notes/2026-12-02-penalty-kinks.md).
#ifndef FEMREG_SOLVERS_FAST_PENALTY_PIECES_H_
#define FEMREG_SOLVERS_FAST_PENALTY_PIECES_H_

#include <Eigen/Core>
#include <vector>

#include "energy/equilibrium.h"

namespace femreg {
namespace fast_backend {

// Phi~_v^-1, the preconditioner's block of vertex v for its penalty curvature c: a support's
// reaction is free (Phi = 0), and the preconditioner takes its vertex as a free one's.
Eigen::Matrix3d PenaltyBlockInverse(const energy::Equilibrium& eq, int v, const Eigen::Matrix3d& c);

class PenaltyPieces {
 public:
  // The pieces of x's forces f (3 #V).
  void Start(const energy::Equilibrium& eq, const Eigen::VectorXd& f);
  // For the predicted forces f + kdx: each vertex whose piece changes (from the last Start or
  // Remodel) gets the penalty's curvature c at its prediction in *phi, the model's gradient at
  // f, phi'(f + kdx) - c kdx, in *phi_gradient (on a quadratic piece, the piece itself) and
  // PenaltyBlockInverse in *phi_inverse. Returns how many changed.
  int Remodel(const energy::Equilibrium& eq, const Eigen::VectorXd& f, const Eigen::VectorXd& kdx,
              std::vector<Eigen::Matrix3d>* phi, Eigen::VectorXd* phi_gradient,
              std::vector<Eigen::Matrix3d>* phi_inverse);

 private:
  std::vector<int> piece_;
};

}  // namespace fast_backend
}  // namespace femreg

#endif  // FEMREG_SOLVERS_FAST_PENALTY_PIECES_H_
