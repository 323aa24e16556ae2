#include "registration/frame_problem.h"

#include <algorithm>
#include <map>
#include <utility>

namespace femreg {

using energy::TermGroup;

void FrameProblem::BuildElastic(const TrackerState& state) {
  problem_.Clear(TermGroup::kElastic);
  problem_.Reset(state.num_vertices);
  std::vector<std::array<int, 4>> cells;
  for (const ObjectState& o : state.objects) {
    for (int e = 0; e < o.mesh.num_tets(); ++e) {
      std::array<int, 4> t;
      for (int k = 0; k < 4; ++k) t[k] = o.mesh.tets(e, k) + o.offset;
      cells.push_back(t);
    }
  }
  problem_.SetCoupling(std::move(cells));
  const RegistrationOptions& options = state.options;
  const double w = options.weights.elastic;
  switch (options.regularizer) {
    case Regularizer::kNone:
      return;
    case Regularizer::kCorotational:
    case Regularizer::kLinear: {
      auto& set = problem_.AddSet<energy::ElasticElement>(TermGroup::kElastic);
      auto* blocks = set.mutable_blocks();
      for (const ObjectState& o : state.objects) {
        for (int e = 0; e < o.model.num_elements(); ++e) {
          energy::ElasticElement b;
          for (int k = 0; k < 4; ++k) b.vertices[k] = o.model.tets()(e, k) + o.offset;
          b.weight = w;
          b.rest = &o.model.rest(e);
          b.rotation = &o.model.rotation(e);
          blocks->push_back(b);
        }
      }
      return;
    }
    case Regularizer::kMassSpring: {
      // One spring per tet edge, k = sum_e E_e V_e / 6 / L^2 over the elements around it (a
      // sixth of each element's volume, with its region's E), so that a uniform stretch of
      // the mesh costs about as much as in the FEM model.
      auto& set = problem_.AddSet<energy::EdgeSpring>(TermGroup::kElastic);
      auto* blocks = set.mutable_blocks();
      for (const ObjectState& o : state.objects) {
        std::map<std::pair<int, int>, double> edges;  // E V_edge
        for (int e = 0; e < o.model.num_elements(); ++e) {
          const int region = e < o.mesh.region.size() ? o.mesh.region(e) : 0;
          const double share = o.material.ForRegion(region).youngs_modulus * o.model.rest(e).volume / 6.0;
          for (int i = 0; i < 4; ++i) {
            for (int j = i + 1; j < 4; ++j) {
              int a = o.model.tets()(e, i), b = o.model.tets()(e, j);
              if (a > b) std::swap(a, b);
              edges[{a, b}] += share;
            }
          }
        }
        for (const auto& edge : edges) {
          const int a = edge.first.first, b = edge.first.second;
          energy::EdgeSpring s;
          s.vertices = {{a + o.offset, b + o.offset}};
          s.length = (o.mesh.rest.row(a) - o.mesh.rest.row(b)).norm();
          s.weight = w * edge.second / (s.length * s.length);
          blocks->push_back(s);
        }
      }
      return;
    }
  }
}

void FrameProblem::BuildFrameTerms(TrackerState* state) {
  problem_.Clear(TermGroup::kTemporal);
  problem_.Clear(TermGroup::kAnchor);
  const RegistrationOptions& options = state->options;
  const double wt = options.weights.temporal;
  if (wt > 0) {
    auto* blocks = problem_.AddSet<energy::VertexSpring>(TermGroup::kTemporal).mutable_blocks();
    for (int v = 0; v < state->num_vertices; ++v) {
      const double w = wt * state->mass(v);
      if (!(w > 0)) continue;
      blocks->push_back(energy::MakeVertexSpring(v, state->frame_start.row(v).transpose(), w));
    }
  }
  std::vector<char>& fixed = problem_.fixed();
  fixed.assign(state->num_vertices, 0);
  auto* anchors = problem_.AddSet<energy::VertexSpring>(TermGroup::kAnchor).mutable_blocks();
  for (auto& kv : state->anchors) {
    Anchor& a = kv.second;
    if (!a.translations.empty()) {
      const size_t i = std::min(static_cast<size_t>(state->frame), a.translations.size() - 1);
      a.targets = a.origin.rowwise() + a.translations[i].transpose();
    }
    for (size_t i = 0; i < a.vertices.size(); ++i) {
      const int g = a.vertices[i];
      const Eigen::Vector3d target = a.targets.row(static_cast<Eigen::Index>(i)).transpose();
      if (a.hard) {
        state->x.row(g) = target.transpose();
        fixed[g] = 1;
      } else {
        anchors->push_back(energy::MakeVertexSpring(g, target, a.weight > 0 ? a.weight : options.weights.anchor));
      }
    }
  }
}

void FrameProblem::SetData(const std::vector<DataPair>& pairs, const RegistrationOptions& options) {
  problem_.Clear(TermGroup::kData);
  const energy::Loss loss{options.data.loss, options.data.loss_scale};
  auto& point1 = *problem_.AddSet<energy::PointToPoint<1>>(TermGroup::kData, loss).mutable_blocks();
  auto& point3 = *problem_.AddSet<energy::PointToPoint<3>>(TermGroup::kData, loss).mutable_blocks();
  auto& plane1 = *problem_.AddSet<energy::PointToPlane<1>>(TermGroup::kData, loss).mutable_blocks();
  auto& plane3 = *problem_.AddSet<energy::PointToPlane<3>>(TermGroup::kData, loss).mutable_blocks();
  const double w = options.weights.data;
  auto fill = [&](const DataPair& p, auto* b) {
    for (size_t k = 0; k < b->vertices.size(); ++k) {
      b->vertices[k] = p.vertices[k];
      b->barycentric[k] = p.barycentric[static_cast<Eigen::Index>(k)];
    }
    b->target = p.target;
    b->weight = w * p.weight;
  };
  for (const DataPair& p : pairs) {
    const bool plane = p.normal.squaredNorm() > 0;
    if (p.num_vertices == 1 && plane) {
      energy::PointToPlane<1> b;
      fill(p, &b);
      b.normal = p.normal;
      plane1.push_back(b);
    } else if (p.num_vertices == 1) {
      energy::PointToPoint<1> b;
      fill(p, &b);
      point1.push_back(b);
    } else if (plane) {
      energy::PointToPlane<3> b;
      fill(p, &b);
      b.normal = p.normal;
      plane3.push_back(b);
    } else {
      energy::PointToPoint<3> b;
      fill(p, &b);
      point3.push_back(b);
    }
  }
}

void FrameProblem::SetContacts(const std::vector<Contact>& contacts, const CollisionWorld& world) {
  problem_.Clear(TermGroup::kCollision);
  auto& obstacle = *problem_.AddSet<energy::ContactPenalty<3>>(TermGroup::kCollision).mutable_blocks();
  auto& pair = *problem_.AddSet<energy::ContactPenalty<6>>(TermGroup::kCollision).mutable_blocks();
  for (const Contact& c : contacts) {
    if (c.obstacle()) {
      energy::ContactPenalty<3> b;
      for (int j = 0; j < 3; ++j) {
        b.vertices[j] = c.vertices_a[j];
        b.coefficients[j] = c.bary_a[j];
      }
      b.normal = c.normal;
      b.offset = world.distance() + c.normal.dot(c.point_b);
      b.weight = world.stiffness();
      obstacle.push_back(b);
    } else {
      energy::ContactPenalty<6> b;
      for (int j = 0; j < 3; ++j) {
        b.vertices[j] = c.vertices_a[j];
        b.coefficients[j] = c.bary_a[j];
        b.vertices[3 + j] = c.vertices_b[j];
        b.coefficients[3 + j] = -c.bary_b[j];
      }
      b.normal = c.normal;
      b.offset = world.distance();
      b.weight = world.stiffness();
      pair.push_back(b);
    }
  }
}

}  // namespace femreg
