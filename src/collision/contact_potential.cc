// The contact penalty for the forward solver, and merging meshes for multi-object solves.
// The penalty itself (value, gradient, Gauss-Newton Hessian) is energy::ContactPenalty's,
// evaluated through the generic block functions of energy/term.h; this file only turns
// contacts into blocks and scatters the blocks' shares into the solver's global arrays.
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

namespace {

// Calls f(block) with the penalty block of every contact (3 or 6 vertices), zero at contact:
// D only detects.
template <class F>
void ForEachPenaltyBlock(const std::vector<Contact>& contacts, const CollisionWorld& world, F&& f) {
  for (const Contact& c : contacts) {
    if (c.obstacle()) {
      f(ObstaclePenaltyBlock(c, 0.0, world.stiffness()));
    } else {
      f(PairPenaltyBlock(c, 0.0, world.stiffness()));
    }
  }
}

// Whether the block's contact is active (delta > 0) at x: an open contact adds nothing.
template <class Block>
bool Active(const Block& block, const Vertices& x) {
  return block.Penetration(energy::StencilPositions(block, x).data()) > 0;
}

}  // namespace

void ContactPotential::Refresh(const Vertices& x) {
  const bool stale = detections_ == 0 || detected_at_.rows() != x.rows() ||
                     world_->frame() != detected_frame_ ||
                     (x - detected_at_).rowwise().norm().maxCoeff() > 0.5 * margin_;
  if (!stale) return;
  world_->Detect(x, margin_, &contacts_);
  detected_at_ = x;
  detected_frame_ = world_->frame();
  ++detections_;
}

double ContactPotential::Evaluate(const Vertices& x, Eigen::VectorXd* gradient) const {
  const energy::Loss none;  // 1/2 k delta^2 as it is
  double value = 0.0;
  ForEachPenaltyBlock(contacts_, *world_, [&](const auto& block) {
    using Block = std::decay_t<decltype(block)>;
    if (!Active(block, x)) return;
    if (gradient == nullptr) {
      value += energy::BlockValue(block, none, x);
      return;
    }
    energy::Linearization<Block> share;
    energy::Linearize(block, none, x, &share, /*with_hessian=*/false);
    value += share.value;
    for (int i = 0; i < Block::kVertices; ++i) {
      gradient->segment<3>(3 * block.vertices[i]) += share.gradient[i];
    }
  });
  return value;
}

void ContactPotential::AddHessian(const Vertices& x,
                                  std::vector<Eigen::Triplet<double>>* triplets) const {
  const energy::Loss none;
  ForEachPenaltyBlock(contacts_, *world_, [&](const auto& block) {
    using Block = std::decay_t<decltype(block)>;
    constexpr int n = Block::kVertices;
    if (!Active(block, x)) return;
    // k J^T J: exact for the penalty while the normal is held (the residual is linear in x).
    energy::Linearization<Block> share;
    if (!energy::Linearize(block, none, x, &share) || share.scale == 0.0) return;
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
