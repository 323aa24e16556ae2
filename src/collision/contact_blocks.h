// A detected contact (femreg/collision.h) as the penalty block of the energy layer
// (energy/contact.h): the one place the contact's stencil, barycentric coefficients and
// offset are laid out. The forward solve's ContactPotential evaluates these blocks; the
// frame problem of registration can build its collision set from them as well.
#ifndef FEMREG_COLLISION_CONTACT_BLOCKS_H_
#define FEMREG_COLLISION_CONTACT_BLOCKS_H_

#include <array>
#include <map>
#include <utility>
#include <vector>

#include "energy/contact.h"
#include "energy/friction.h"
#include "energy/term.h"
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

// A contact against an obstacle whose side a is a point of an embedded surface
// (docs/theory/embedded-surfaces.md#contacts), carried by 4 cage vertices with `weights`.
energy::ContactPenalty<4> EmbeddedPenaltyBlock(const Contact& c, const std::array<int, 4>& vertices,
                                               const std::array<double, 4>& weights, double standoff,
                                               double stiffness);

// Friction (energy/friction.h): the block's weight mu lambda / eps, 0 unless all are > 0.
double FrictionWeight(double mu, double normal_force, double slip);
// A contact against an obstacle: the slip of side a's point since `reference` (#V by 3),
// relative to the obstacle's surface, which moved by obstacle_motion (m) since then.
energy::Friction<3> ObstacleFrictionBlock(const Contact& c, const Vertices& reference,
                                          const Eigen::Vector3d& obstacle_motion, double weight);
// Against an obstacle, side a an embedded surface's point (the cage's reference positions).
energy::Friction<4> EmbeddedFrictionBlock(const Contact& c, const std::array<int, 4>& vertices,
                                          const std::array<double, 4>& weights, const Vertices& reference,
                                          const Eigen::Vector3d& obstacle_motion, double weight);
// Between two objects: side a's point relative to side b's.
energy::Friction<6> PairFrictionBlock(const Contact& c, const Vertices& reference, double weight);

// The contact blocks' forces summed per object pair and obstacle (femreg/collision_spec.h's
// ContactForce; a pair on its lower-numbered object).
class ContactForceSum {
 public:
  // Adds the force a contact's penalty or friction block exerts at x on side a (the first 3
  // vertices of a pair's block, all of an obstacle's); a block that adds nothing (an open
  // contact) is not counted.
  template <class Block>
  void Add(const Contact& c, const Block& block, const energy::Loss& loss, const Vertices& x, bool friction) {
    energy::Linearization<Block> share;
    if (!energy::Linearize(block, loss, x, &share, false) || share.scale == 0.0) return;
    Eigen::Vector3d f = Eigen::Vector3d::Zero();
    const int side_a = c.obstacle() ? Block::kVertices : 3;
    for (int i = 0; i < side_a; ++i) f -= share.gradient[i];
    AddSideA(c, f, friction);
  }
  void AddSideA(const Contact& c, const Eigen::Vector3d& force_on_a, bool friction);
  std::vector<ContactForce> Result() const;

 private:
  std::map<std::pair<int, int>, ContactForce> sums_;
};

}  // namespace femreg

#endif  // FEMREG_COLLISION_CONTACT_BLOCKS_H_
