// The contacts a Gauss-Newton step of the equilibrium solve closes (solvers/fast/
// equilibrium_step.h). A contact's force k max(0, delta) n is piecewise linear in the
// positions, and the step's model has only the contacts closed at x: a step that closes another
// meets a force its model did not have, and the line search cuts it short. The penetration
// delta is linear in the positions, so the contacts that x + dx closes are known exactly; the
// step is solved again with them taken as closed (their stiffness added to K's products, their
// force on the closed branch to f): one update of the active set of the step's piecewise-linear
// model, by the contacts it closes (docs/notes/2026-12-01-equilibrium-inexact-solves.md#contacts-closed-within-a-step).
#ifndef FEMREG_SOLVERS_FAST_CLOSING_CONTACTS_H_
#define FEMREG_SOLVERS_FAST_CLOSING_CONTACTS_H_

#include <Eigen/Core>
#include <array>
#include <utility>
#include <vector>

#include "energy/problem.h"

namespace femreg {
namespace fast_backend {

class ClosingContacts {
 public:
  // The problem's contact penalties that are open at x (delta <= 0) and closed at x + dx.
  // Returns how many.
  // With `add`, those found before stay and only new ones are added (and counted).
  int Find(const energy::Problem& problem, const Vertices& x, const Eigen::VectorXd& dx, bool add = false);
  void Clear() {
    closing_.clear();
    keys_.clear();
  }
  bool empty() const { return closing_.empty(); }
  // f += their potential's gradient on the closed branch at x: k delta(x) d(delta)/dx.
  void AddForce(Eigen::VectorXd* f) const;
  // y += sum of k d(delta)/dx d(delta)/dx^T p: their share of K p.
  void AddProduct(const Eigen::VectorXd& p, Eigen::VectorXd* y) const;

 private:
  struct Closing {
    std::array<int, 6> vertices{};       // the free ones of the stencil
    std::array<double, 6> coefficients{};  // c_i: d(delta)/dx_i = -c_i n
    int count = 0;
    Eigen::Vector3d normal = Eigen::Vector3d::UnitZ();
    double stiffness = 0.0, delta = 0.0;  // k, and delta at x
  };
  std::vector<Closing> closing_;
  std::vector<std::pair<int, int>> keys_;  // each one's penalty set (in ForEachSet's order) and block
};

}  // namespace fast_backend
}  // namespace femreg

#endif  // FEMREG_SOLVERS_FAST_CLOSING_CONTACTS_H_
