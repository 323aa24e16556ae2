// The contact penalty for the forward solver, and merging meshes for multi-object solves.
// The penalty itself (value, gradient, Gauss-Newton Hessian) is energy::ContactPenalty's,
// evaluated through the generic block functions of energy/term.h; this file only turns
// contacts into blocks and scatters the blocks' shares into the solver's global arrays.
#include <algorithm>
#include <type_traits>

#include "collision/contact_blocks.h"
#include "energy/term.h"
#include "femreg/collision.h"

namespace femreg {

energy::ContactPenalty<3> ObstaclePenaltyBlock(const Contact& c, double standoff, double stiffness) {
  energy::ContactPenalty<3> block;
  for (int k = 0; k < 3; ++k) {
    block.vertices[k] = c.vertices_a[k];
    block.coefficients[k] = c.bary_a[k];
  }
  block.normal = c.normal;
  block.offset = standoff + c.normal.dot(c.point_b);
  block.weight = stiffness;
  return block;
}

energy::ContactPenalty<4> EmbeddedPenaltyBlock(const Contact& c, const std::array<int, 4>& vertices,
                                               const std::array<double, 4>& weights, double standoff,
                                               double stiffness) {
  energy::ContactPenalty<4> block;
  block.vertices = vertices;
  block.coefficients = weights;
  block.normal = c.normal;
  block.offset = standoff + c.normal.dot(c.point_b);
  block.weight = stiffness;
  return block;
}

energy::ContactPenalty<6> PairPenaltyBlock(const Contact& c, double standoff, double stiffness) {
  energy::ContactPenalty<6> block;
  for (int k = 0; k < 3; ++k) {
    block.vertices[k] = c.vertices_a[k];
    block.coefficients[k] = c.bary_a[k];
    block.vertices[3 + k] = c.vertices_b[k];
    block.coefficients[3 + k] = -c.bary_b[k];
  }
  block.normal = c.normal;
  block.offset = standoff;
  block.weight = stiffness;
  return block;
}

// Calls f(block, contact, loss, friction) with each contact's penalty block (3 or 6 vertices),
// zero at contact (D only detects), and its friction block where it has one.
template <class F>
void ContactPotential::ForEachBlock(F&& f) const {
  const energy::Loss none;  // 1/2 k delta^2 as it is
  const energy::Loss huber{RobustLoss::kHuber, world_->friction_slip()};
  const bool friction = friction_weight_.size() == contacts_.size();
  for (size_t i = 0; i < contacts_.size(); ++i) {
    const Contact& c = contacts_[i];
    if (c.obstacle()) {
      f(ObstaclePenaltyBlock(c, 0.0, world_->stiffness()), c, none, false);
    } else {
      f(PairPenaltyBlock(c, 0.0, world_->stiffness()), c, none, false);
    }
    if (!friction || !(friction_weight_[i] > 0)) continue;
    if (c.obstacle()) {
      f(ObstacleFrictionBlock(c, reference_, friction_motion_[i], friction_weight_[i]), c, huber, true);
    } else {
      f(PairFrictionBlock(c, reference_, friction_weight_[i]), c, huber, true);
    }
  }
}

namespace {

// Whether the block adds to the energy at x: an open contact's penalty does not.
template <class Block>
bool Active(const Block& block, const Vertices& x) {
  if constexpr (std::is_same_v<Block, energy::ContactPenalty<3>> || std::is_same_v<Block, energy::ContactPenalty<6>>) {
    return block.Penetration(energy::StencilPositions(block, x).data()) > 0;
  } else {
    return true;
  }
}

// The friction reference of a frame: the positions its solve starts from, taken at the first
// call after the obstacles were posed for another frame (`frame`); the obstacles' motion is
// from the frame before.
void StartSlip(const Vertices& x, double frame, Vertices* reference, double* reference_frame,
               double* motion_from) {
  if (reference->rows() != x.rows()) {
    *reference = x;
    *reference_frame = *motion_from = frame;
  } else if (frame != *reference_frame) {
    *motion_from = *reference_frame;
    *reference = x;
    *reference_frame = frame;
  }
}

}  // namespace

void ContactPotential::Refresh(const Vertices& x) {
  StartSlip(x, world_->frame(), &reference_, &reference_frame_, &motion_from_);
  const bool stale = detections_ == 0 || detected_at_.rows() != x.rows() ||
                     world_->frame() != detected_frame_ ||
                     (x - detected_at_).rowwise().norm().maxCoeff() > 0.5 * margin_;
  if (stale) {
    world_->Detect(x, margin_, &contacts_);
    detected_at_ = x;
    detected_frame_ = world_->frame();
    ++detections_;
  }
  const std::vector<double> previous = friction_weight_;
  friction_weight_.clear();
  friction_motion_.clear();
  if (!world_->has_friction()) return;
  const bool relax = !stale && previous.size() == contacts_.size();
  // The normal forces of this iteration's x, held for its step (lagged friction); between
  // detections half way from the last ones, which settles the fixed point where the gaps answer
  // to the friction (two bodies pressed and dragged, a block slid on a plane), and cycles without.
  friction_weight_.assign(contacts_.size(), 0.0);
  friction_motion_.assign(contacts_.size(), Eigen::Vector3d::Zero());
  for (size_t i = 0; i < contacts_.size(); ++i) {
    const Contact& c = contacts_[i];
    const double normal = world_->stiffness() * std::max(0.0, -world_->Gap(c, x));
    friction_weight_[i] = FrictionWeight(world_->Friction(c), normal, world_->friction_slip());
    if (relax) friction_weight_[i] = 0.5 * (previous[i] + friction_weight_[i]);
    if (c.obstacle() && friction_weight_[i] > 0) {
      friction_motion_[i] = world_->ObstacleMotion(-1 - c.object_b, c.point_b, motion_from_);
    }
  }
}

double ContactPotential::Evaluate(const Vertices& x, Eigen::VectorXd* gradient) const {
  double value = 0.0;
  ForEachBlock([&](const auto& block, const Contact&, const energy::Loss& loss, bool) {
    using Block = std::decay_t<decltype(block)>;
    if (!Active(block, x)) return;
    if (gradient == nullptr) {
      value += energy::BlockValue(block, loss, x);
      return;
    }
    energy::Linearization<Block> share;
    energy::Linearize(block, loss, x, &share, /*with_hessian=*/false);
    value += share.value;
    for (int i = 0; i < Block::kVertices; ++i) {
      gradient->segment<3>(3 * block.vertices[i]) += share.gradient[i];
    }
  });
  return value;
}

void ContactPotential::AddHessian(const Vertices& x,
                                  std::vector<Eigen::Triplet<double>>* triplets) const {
  // The solver's predictor for moved prescribed vertices asks for the Hessian before the
  // frame's first Refresh: the frame's slip starts before that move.
  if (world_->has_friction()) StartSlip(x, world_->frame(), &reference_, &reference_frame_, &motion_from_);
  ForEachBlock([&](const auto& block, const Contact&, const energy::Loss& loss, bool friction) {
    using Block = std::decay_t<decltype(block)>;
    constexpr int n = Block::kVertices;
    if (!Active(block, x)) return;
    // The exact Hessian: k J^T J for the penalty while the normal is held (the residual is
    // linear in x); for friction the Huber loss' own, positive semi-definite (no stiffness
    // along a sliding contact's slip), which Newton converges on where the reweighted one crawls.
    energy::Linearization<Block> share;
    const bool linearized = friction
                                ? energy::LinearizeSecondOrder(block, loss, x, energy::Curvature::kExact, &share)
                                : energy::Linearize(block, loss, x, &share);
    if (!linearized || share.scale == 0.0) return;
    for (int i = 0; i < n; ++i) {
      for (int j = 0; j < n; ++j) {
        const Eigen::Matrix3d& h = share.hessian[i * n + j];
        for (int r = 0; r < 3; ++r) {
          for (int s = 0; s < 3; ++s) {
            triplets->emplace_back(3 * block.vertices[i] + r, 3 * block.vertices[j] + s, h(r, s));
          }
        }
      }
    }
  });
}

std::vector<ContactForce> ContactPotential::Forces(const Vertices& x) const {
  ContactForceSum sum;
  ForEachBlock([&](const auto& block, const Contact& c, const energy::Loss& loss, bool friction) {
    sum.Add(c, block, loss, x, friction);
  });
  return sum.Result();
}

TetMesh MergeMeshes(const std::vector<TetMesh>& meshes, std::vector<int>* offsets) {
  TetMesh merged;
  int nv = 0, nt = 0;
  offsets->clear();
  for (const TetMesh& m : meshes) {
    offsets->push_back(nv);
    nv += m.num_vertices();
    nt += m.num_tets();
  }
  merged.rest.resize(nv, 3);
  merged.x.resize(nv, 3);
  merged.mass = Eigen::VectorXd::Zero(nv);
  merged.tets.resize(nt, 4);
  merged.region.resize(nt);
  int t = 0;
  for (size_t i = 0; i < meshes.size(); ++i) {
    const TetMesh& m = meshes[i];
    const int o = (*offsets)[i];
    merged.rest.middleRows(o, m.num_vertices()) = m.rest;
    merged.x.middleRows(o, m.num_vertices()) = m.x.rows() == m.rest.rows() ? m.x : m.rest;
    if (m.mass.size() == m.num_vertices()) merged.mass.segment(o, m.num_vertices()) = m.mass;
    merged.tets.middleRows(t, m.num_tets()) = m.tets.array() + o;
    merged.region.segment(t, m.num_tets()).setConstant(static_cast<int>(i));
    t += m.num_tets();
  }
  BuildTopology(&merged);
  return merged;
}

}  // namespace femreg
