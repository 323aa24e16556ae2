// The robust losses of the data term, written once: the fast back end reweights with them and
// the Ceres back end wraps them in a ceres::LossFunction (solvers/ceres/).
#ifndef FEMREG_ENERGY_LOSS_H_
#define FEMREG_ENERGY_LOSS_H_

#include "femreg/energy.h"

namespace femreg {
namespace energy {

// rho(s) of a residual's squared norm s (femreg/energy.h gives the formulas), with scale a.
struct Loss {
  RobustLoss kind = RobustLoss::kNone;
  double scale = 1.0;  // a (m), > 0 unless kind is kNone

  bool robust() const { return kind != RobustLoss::kNone; }
  // rho[0] = rho(s), rho[1] = rho'(s), rho[2] = rho''(s), as ceres::LossFunction::Evaluate.
  void Evaluate(double s, double rho[3]) const;
};

}  // namespace energy
}  // namespace femreg

#endif  // FEMREG_ENERGY_LOSS_H_
