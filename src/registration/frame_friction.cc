// The frame problem's friction blocks and the contact forces it reports
// (docs/theory/contact.md#friction).
#include <algorithm>

#include "collision/contact_blocks.h"
#include "registration/frame_problem.h"

namespace femreg {

using energy::TermGroup;

void FrameProblem::SetFriction(
    const std::vector<Contact>& contacts, const CollisionWorld& world,
    const std::map<std::pair<int, int>, TrackerState::ContactMultiplier>& multipliers, const Vertices& y,
    const Vertices& reference, double reference_frame) {
  force_friction_obstacle_.clear();
  force_friction_pair_.clear();
  force_friction_embedded_.clear();
  force_friction_obstacle_contact_.clear();
  force_friction_pair_contact_.clear();
  force_friction_embedded_contact_.clear();
  friction_slip_ = world.friction_slip();
  if (!world.has_friction() || reference.rows() != problem_.num_vertices()) return;
  for (size_t i = 0; i < contacts.size(); ++i) {
    const Contact& c = contacts[i];
    const double mu = world.Friction(c);
    if (!(mu > 0)) continue;
    // The normal force the penalty exerts at the outer iteration's start, held for the solve.
    double k = world.stiffness(), lambda = 0.0;
    const auto it = multipliers.find({c.source, c.object_b});
    if (it != multipliers.end()) {
      k = it->second.stiffness;
      lambda = it->second.lambda;
    }
    const double normal = std::max(0.0, lambda - k * world.Gap(c, y));
    const double weight = FrictionWeight(mu, normal, friction_slip_);
    if (!(weight > 0)) continue;
    const DataSurface::Stencil st = ContactStencil(c);
    if (st.n == 4) {
      const Eigen::Vector3d motion = world.ObstacleMotion(-1 - c.object_b, c.point_b, reference_frame);
      force_friction_embedded_.push_back(EmbeddedFrictionBlock(c, st.vertices, st.weights, reference, motion, weight));
      force_friction_embedded_contact_.push_back(static_cast<int>(i));
    } else if (c.obstacle()) {
      const Eigen::Vector3d motion = world.ObstacleMotion(-1 - c.object_b, c.point_b, reference_frame);
      force_friction_obstacle_.push_back(ObstacleFrictionBlock(c, reference, motion, weight));
      force_friction_obstacle_contact_.push_back(static_cast<int>(i));
    } else {
      force_friction_pair_.push_back(PairFrictionBlock(c, reference, weight));
      force_friction_pair_contact_.push_back(static_cast<int>(i));
    }
  }
  const energy::Loss huber{RobustLoss::kHuber, friction_slip_};
  if (!force_friction_obstacle_.empty()) {
    *problem_.AddSet<energy::Friction<3>>(TermGroup::kCollision, huber).mutable_blocks() = force_friction_obstacle_;
  }
  if (!force_friction_pair_.empty()) {
    *problem_.AddSet<energy::Friction<6>>(TermGroup::kCollision, huber).mutable_blocks() = force_friction_pair_;
  }
  if (!force_friction_embedded_.empty()) {
    *problem_.AddSet<energy::Friction<4>>(TermGroup::kCollision, huber).mutable_blocks() = force_friction_embedded_;
  }
}

std::vector<ContactForce> FrameProblem::ContactForces(const Vertices& x) const {
  ContactForceSum sum;
  if (x.rows() != problem_.num_vertices()) return {};  // a new topology since
  const energy::Loss none;
  for (size_t i = 0; i < force_contacts_.size(); ++i) {
    const Contact& c = force_contacts_[i];
    const double standoff = force_penalty_[i].first, k = force_penalty_[i].second;
    const DataSurface::Stencil st = ContactStencil(c);
    if (st.n == 4) {
      sum.Add(c, EmbeddedPenaltyBlock(c, st.vertices, st.weights, standoff, k), none, x, false);
    } else if (c.obstacle()) {
      sum.Add(c, ObstaclePenaltyBlock(c, standoff, k), none, x, false);
    } else {
      sum.Add(c, PairPenaltyBlock(c, standoff, k), none, x, false);
    }
  }
  const energy::Loss huber{RobustLoss::kHuber, friction_slip_};
  for (size_t j = 0; j < force_friction_obstacle_.size(); ++j) {
    sum.Add(force_contacts_[force_friction_obstacle_contact_[j]], force_friction_obstacle_[j], huber, x, true);
  }
  for (size_t j = 0; j < force_friction_pair_.size(); ++j) {
    sum.Add(force_contacts_[force_friction_pair_contact_[j]], force_friction_pair_[j], huber, x, true);
  }
  for (size_t j = 0; j < force_friction_embedded_.size(); ++j) {
    sum.Add(force_contacts_[force_friction_embedded_contact_[j]], force_friction_embedded_[j], huber, x, true);
  }
  return sum.Result();
}

}  // namespace femreg
