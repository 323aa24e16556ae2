#include "energy/loss.h"

#include <cmath>

namespace femreg {
namespace energy {

void Loss::Evaluate(double s, double rho[3]) const {
  const double b = scale * scale;
  switch (kind) {
    case RobustLoss::kNone:
      rho[0] = s;
      rho[1] = 1.0;
      rho[2] = 0.0;
      return;
    case RobustLoss::kHuber:
      if (s > b) {
        const double r = std::sqrt(s);
        rho[0] = 2.0 * scale * r - b;
        rho[1] = scale / r;
        rho[2] = -rho[1] / (2.0 * s);
      } else {
        rho[0] = s;
        rho[1] = 1.0;
        rho[2] = 0.0;
      }
      return;
    case RobustLoss::kCauchy: {
      const double c = 1.0 / b;
      const double sum = 1.0 + s * c;
      const double inv = 1.0 / sum;
      rho[0] = b * std::log1p(s * c);
      rho[1] = inv;
      rho[2] = -c * (inv * inv);
      return;
    }
    case RobustLoss::kTukey:
      if (s <= b) {
        const double t = 1.0 - s / b;
        rho[0] = b * (1.0 - t * t * t) / 3.0;
        rho[1] = t * t;
        rho[2] = -2.0 * t / b;
      } else {
        rho[0] = b / 3.0;
        rho[1] = 0.0;
        rho[2] = 0.0;
      }
      return;
  }
}

}  // namespace energy
}  // namespace femreg
