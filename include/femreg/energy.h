// femreg/energy.h - the public face of the energy layer: the robust losses a data term can
// use and the energy of a frame split by term. The terms themselves (src/energy/) are
// internal: both solver back ends consume them.
#ifndef FEMREG_ENERGY_H_
#define FEMREG_ENERGY_H_

namespace femreg {

// Robust loss rho(s) on a residual's squared norm s, with a scale a (m) where it bends:
// Huber rho = s (s <= a^2), 2 a sqrt(s) - a^2 beyond; Cauchy rho = a^2 log(1 + s / a^2);
// Tukey rho = a^2 / 3 (1 - (1 - s / a^2)^3) (s <= a^2), a^2 / 3 beyond. Ceres' conventions.
enum class RobustLoss { kNone, kHuber, kCauchy, kTukey };

// The energy of one frame by term (J), robust losses applied. `load`: the external loads'
// (gravity, nodal loads) potential about the outer iteration's start, plus a constant
// (src/energy/load.h); 0 without loads. `equilibrium`: with the external forces estimated
// (registration.forces), the penalty on the forces that the shape needs to be in equilibrium
// (docs/theory/equilibrium.md); the elastic, load and collision energies are then not
// minimized but balanced, and stay 0 here.
struct EnergyTerms {
  double data = 0.0, elastic = 0.0, temporal = 0.0, anchor = 0.0, collision = 0.0, load = 0.0;
  double equilibrium = 0.0;
  double total() const { return data + elastic + temporal + anchor + collision + load + equilibrium; }
};

}  // namespace femreg

#endif  // FEMREG_ENERGY_H_
