// The friction block of a contact (energy/friction.h) and the contacts' resultant forces per
// object pair and obstacle: shared by registration's frame problem and the forward solve's
// contact potential (docs/theory/contact.md#friction).
#include <algorithm>
#include <utility>

#include "collision/contact_blocks.h"

namespace femreg {

double CollisionWorld::Friction(const Contact& c) const {
  if (c.obstacle()) {
    const size_t i = static_cast<size_t>(-1 - c.object_b);
    if (i < obstacles_.size()) return obstacles_[i].spec.friction.value_or(spec_.friction);
    return spec_.friction;
  }
  const std::pair<int, int> key(std::min(c.object_a, c.object_b), std::max(c.object_a, c.object_b));
  for (const auto& [pair, mu] : pair_friction_) {
    if (pair == key) return mu;
  }
  return spec_.friction;
}

Eigen::Vector3d CollisionWorld::ObstacleMotion(int i, const Eigen::Vector3d& p, double since_frame) const {
  const Obstacle& o = obstacles_.at(static_cast<size_t>(i));
  const Eigen::Isometry3d then = ObstaclePose(o.spec.keyframes, since_frame);
  return p - then * (o.pose.inverse() * p);
}

double FrictionWeight(double mu, double normal_force, double slip) {
  if (!(mu > 0) || !(normal_force > 0) || !(slip > 0)) return 0.0;
  return mu * normal_force / slip;
}

energy::Friction<3> ObstacleFrictionBlock(const Contact& c, const Vertices& reference,
                                          const Eigen::Vector3d& obstacle_motion, double weight) {
  energy::Friction<3> block;
  block.tangent = energy::TangentBasis(c.normal);
  Eigen::Vector3d p0 = Eigen::Vector3d::Zero();
  for (int k = 0; k < 3; ++k) {
    block.vertices[k] = c.vertices_a[k];
    block.coefficients[k] = c.bary_a[k];
    p0 += c.bary_a[k] * reference.row(c.vertices_a[k]).transpose();
  }
  // The slip is relative to the obstacle's surface, which moved by obstacle_motion.
  block.offset = block.tangent * (p0 + obstacle_motion);
  block.weight = weight;
  return block;
}

energy::Friction<4> EmbeddedFrictionBlock(const Contact& c, const std::array<int, 4>& vertices,
                                          const std::array<double, 4>& weights, const Vertices& reference,
                                          const Eigen::Vector3d& obstacle_motion, double weight) {
  energy::Friction<4> block;
  block.tangent = energy::TangentBasis(c.normal);
  Eigen::Vector3d p0 = Eigen::Vector3d::Zero();
  for (int k = 0; k < 4; ++k) p0 += weights[static_cast<size_t>(k)] * reference.row(vertices[static_cast<size_t>(k)]).transpose();
  block.vertices = vertices;
  block.coefficients = weights;
  block.offset = block.tangent * (p0 + obstacle_motion);
  block.weight = weight;
  return block;
}

energy::Friction<6> PairFrictionBlock(const Contact& c, const Vertices& reference, double weight) {
  energy::Friction<6> block;
  block.tangent = energy::TangentBasis(c.normal);
  Eigen::Vector3d p0 = Eigen::Vector3d::Zero();
  for (int k = 0; k < 3; ++k) {
    block.vertices[k] = c.vertices_a[k];
    block.coefficients[k] = c.bary_a[k];
    block.vertices[3 + k] = c.vertices_b[k];
    block.coefficients[3 + k] = -c.bary_b[k];
    p0 += c.bary_a[k] * reference.row(c.vertices_a[k]).transpose() -
          c.bary_b[k] * reference.row(c.vertices_b[k]).transpose();
  }
  block.offset = block.tangent * p0;
  block.weight = weight;
  return block;
}

void ContactForceSum::AddSideA(const Contact& c, const Eigen::Vector3d& force_on_a, bool friction) {
  int object = c.object_a, other = c.object_b;
  Eigen::Vector3d f = force_on_a;
  if (!c.obstacle() && other < object) {  // a pair is reported on its lower-numbered object
    std::swap(object, other);
    f = -f;
  }
  ContactForce& s = sums_[{object, other}];
  s.object = object;
  s.other = other;
  s.force += f;
  if (friction) {
    s.friction += f;
  } else {
    ++s.contacts;
  }
}

std::vector<ContactForce> ContactForceSum::Result() const {
  std::vector<ContactForce> out;
  out.reserve(sums_.size());
  for (const auto& kv : sums_) out.push_back(kv.second);
  return out;
}

}  // namespace femreg
