// A detected contact (femreg/collision.h) as the penalty block of the energy layer
// (energy/contact.h): the one place the contact's stencil, barycentric coefficients and
// offset are laid out. The forward solve's ContactPotential evaluates these blocks; the
// frame problem of registration can build its collision set from them as well.
#ifndef FEMREG_COLLISION_CONTACT_BLOCKS_H_
#define FEMREG_COLLISION_CONTACT_BLOCKS_H_

#include "energy/contact.h"
#include "femreg/collision.h"

namespace femreg {

// A contact against an obstacle (c.obstacle()): side a's 3 vertices with coefficients
// bary_a; offset s + n . p_b (the obstacle point is fixed). standoff: s (m), the gap where
// the penalty starts (registration: lambda / k; the forward solve: 0); stiffness: k (N/m),
// the block's weight.
energy::ContactPenalty<3> ObstaclePenaltyBlock(const Contact& c, double standoff, double stiffness);
// A contact between two objects: side a's 3 vertices (coefficients bary_a), then side b's
// (coefficients -bary_b); offset s.
energy::ContactPenalty<6> PairPenaltyBlock(const Contact& c, double standoff, double stiffness);

}  // namespace femreg

#endif  // FEMREG_COLLISION_CONTACT_BLOCKS_H_
