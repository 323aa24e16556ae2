// The equilibrium step's special directions (solvers/fast/equilibrium_step.h). The rigid
// motions of the pieces no vertex of which is fixed (K's null space, up to the contacts' and
// loads' share): the preconditioner solves them exactly on a coarse matrix and K~'s factor on
// the rest, since a free body's rigid motion is what the data alone decide and K~ has only a
// tiny shift for it. And the held turns (energy::Equilibrium::held_turns): turns of a free
// body that its surface does not show, which the step does not make at all.
#ifndef FEMREG_SOLVERS_FAST_STEP_MODES_H_
#define FEMREG_SOLVERS_FAST_STEP_MODES_H_

#include <Eigen/Core>
#include <functional>
#include <utility>
#include <vector>

#include "energy/problem.h"

namespace femreg {
namespace fast_backend {

class StepModes {
 public:
  // y = A p for the step's matrix A, with the held turns projected out of y (ProjectHeld).
  using Product = std::function<void(const Eigen::VectorXd& p, Eigen::VectorXd* y)>;

  // The held turns at x (orthonormal; each a turn about its axis through its vertices'
  // centroid, none for a set with a fixed vertex), the rigid modes at x (orthonormal, and orthogonal to
  // the held turns) and the coarse matrix's inverse (R^T A R)^-1 over them.
  void Build(const energy::Problem& problem, const Vertices& x, const Product& product);
  // v - W W^T v over the held turns W.
  void ProjectHeld(Eigen::VectorXd* v) const;
  // v - R R^T v - W W^T v.
  void Project(Eigen::VectorXd* v) const;
  // z += R (R^T A R)^-1 R^T r.
  void AddCoarse(const Eigen::VectorXd& r, Eigen::VectorXd* z) const;

 private:
  void HeldTurns(const energy::Problem& problem, const Vertices& x);
  void FindFreePieces(const energy::Problem& problem);
  void RigidModes(const energy::Problem& problem, const Vertices& x, const Product& product);

  std::vector<Eigen::VectorXd> held_;
  std::vector<std::pair<int, int>> held_range_;  // each held turn's vertices [first, end)
  std::vector<Eigen::VectorXd> modes_;
  Eigen::MatrixXd coarse_inverse_;
  std::vector<std::vector<int>> free_pieces_;  // per piece without fixed vertices, its vertices
};

}  // namespace fast_backend
}  // namespace femreg

#endif  // FEMREG_SOLVERS_FAST_STEP_MODES_H_
