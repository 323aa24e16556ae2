#include "registration/frame_problem.h"

#include <algorithm>
#include <atomic>
#include <map>
#include <type_traits>
#include <utility>

#include "collision/contact_blocks.h"
#include "energy/nodal_volume.h"
#include "femreg/geometry.h"
#include "parallel/pool.h"

namespace femreg {

using energy::TermGroup;

namespace {
// A surface triangle's key: its three global vertex indices, sorted, 21 bits each.
uint64_t TriangleKey(int a, int b, int c) {
  if (a > b) std::swap(a, b);
  if (b > c) std::swap(b, c);
  if (a > b) std::swap(a, b);
  return (static_cast<uint64_t>(a) << 42) | (static_cast<uint64_t>(b) << 21) | static_cast<uint64_t>(c);
}

// Whether a data block has a normal (point-to-plane) or not (point-to-point).
template <typename Block, typename = void>
struct HasNormal : std::false_type {};
template <typename Block>
struct HasNormal<Block, std::void_t<decltype(std::declval<Block>().normal)>> : std::true_type {};
}  // namespace

// Rest areas of the surface for the data weights per unit area.
void FrameProblem::BuildAreas(const TrackerState& state) {
  vertex_area_.assign(state.num_vertices, 0.0);
  vertex_object_.assign(state.vertex_object.begin(), state.vertex_object.end());
  num_objects_ = static_cast<int>(state.objects.size());
  triangle_area_.clear();
  for (const ObjectState& o : state.objects) {
    const TetMesh& m = o.mesh;
    for (int f = 0; f < m.num_surface_triangles(); ++f) {
      const int a = m.surface(f, 0), b = m.surface(f, 1), c = m.surface(f, 2);
      const Eigen::Vector3d ab = m.rest.row(b) - m.rest.row(a), ac = m.rest.row(c) - m.rest.row(a);
      const double area = 0.5 * ab.cross(ac).norm();
      triangle_area_[TriangleKey(a + o.offset, b + o.offset, c + o.offset)] = area;
      for (int v : {a, b, c}) vertex_area_[v + o.offset] += area / 3.0;
    }
  }
}

void FrameProblem::BuildNodalVolume(const TrackerState& state, double weight) {
  int nt = 0;
  for (const ObjectState& o : state.objects) nt += o.model.nodal_volume() ? o.model.num_elements() : 0;
  if (nt == 0) return;
  Tets tets(nt, 4);
  std::vector<const ElementRest*> rests;
  rests.reserve(static_cast<size_t>(nt));
  for (const ObjectState& o : state.objects) {
    if (!o.model.nodal_volume()) continue;
    for (int e = 0; e < o.model.num_elements(); ++e) {
      for (int k = 0; k < 4; ++k) tets(static_cast<int>(rests.size()), k) = o.model.tets()(e, k) + o.offset;
      rests.push_back(&o.model.rest(e));
    }
  }
  auto nodal = std::make_shared<energy::NodalVolume>();
  nodal->Build(tets, rests, state.num_vertices, /*threads=*/1, weight);
  problem_.SetNodalVolume(std::move(nodal));
}

void FrameProblem::SetElasticScale(const TrackerState& state, double scale) {
  const double w = state.options.weights.elastic * scale;
  for (auto& set : problem_.SetsOf<energy::ElasticElement>()) {
    for (energy::ElasticElement& b : *set.mutable_blocks()) b.weight = w;
  }
  for (auto& set : problem_.SetsOf<energy::NeoHookeanElement>()) {
    for (energy::NeoHookeanElement& b : *set.mutable_blocks()) b.weight = w;
  }
  bool nodal = false;
  for (const ObjectState& o : state.objects) nodal = nodal || o.model.nodal_volume();
  if (nodal) BuildNodalVolume(state, w);
}

void FrameProblem::BuildElastic(const TrackerState& state) {
  BuildAreas(state);
  force_contacts_.clear();  // their vertex numbering may be gone
  force_penalty_.clear();
  force_friction_obstacle_.clear();
  force_friction_pair_.clear();
  problem_.Clear(TermGroup::kElastic);
  problem_.Reset(state.num_vertices);
  free_space_.clear();  // numbered by the old vertices
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
  barrier_ = nullptr;
  barrier_blocks_.clear();
  if (options.regularizer != Regularizer::kNone && options.weights.barrier > 0 && w > 0) {
    barrier_ = &problem_.AddSet<energy::InversionBarrier>(TermGroup::kBarrier);
    auto* barrier = &barrier_blocks_;
    for (const ObjectState& o : state.objects) {
      for (int e = 0; e < o.model.num_elements(); ++e) {
        std::array<int, 4> v;
        for (int k = 0; k < 4; ++k) v[k] = o.model.tets()(e, k) + o.offset;
        barrier->emplace_back(v, o.model.rest(e), w * options.weights.barrier, options.weights.barrier_volume);
      }
    }
    *barrier_->mutable_blocks() = barrier_blocks_;
  }
  switch (options.regularizer) {
    case Regularizer::kNone:
      return;
    case Regularizer::kCorotational:
    case Regularizer::kLinear: {
      // Neo-Hookean objects (material.model) have their own element.
      std::vector<energy::NeoHookeanElement>* neo_hookean = nullptr;
      for (const ObjectState& o : state.objects) {
        if (o.model.type() != ElasticModelType::kNeoHookean) continue;
        if (neo_hookean == nullptr) {
          neo_hookean = problem_.AddSet<energy::NeoHookeanElement>(TermGroup::kElastic).mutable_blocks();
        }
        for (int e = 0; e < o.model.num_elements(); ++e) {
          energy::NeoHookeanElement b;
          for (int k = 0; k < 4; ++k) b.vertices[k] = o.model.tets()(e, k) + o.offset;
          b.weight = w;
          b.rest = &o.model.rest(e);
          b.deviatoric = o.model.nodal_volume();
          neo_hookean->push_back(b);
        }
      }
      BuildNodalVolume(state, w);
      auto& set = problem_.AddSet<energy::ElasticElement>(TermGroup::kElastic);
      auto* blocks = set.mutable_blocks();
      for (const ObjectState& o : state.objects) {
        if (o.model.type() == ElasticModelType::kNeoHookean) continue;
        for (int e = 0; e < o.model.num_elements(); ++e) {
          energy::ElasticElement b;
          for (int k = 0; k < 4; ++k) b.vertices[k] = o.model.tets()(e, k) + o.offset;
          b.weight = w;
          b.rest = &o.model.rest(e);
          b.rotation = &o.model.rotation(e);
          b.corotational = o.model.type() == ElasticModelType::kCorotational;
          blocks->push_back(b);
        }
      }
      return;
    }
    case Regularizer::kMassSpring: {
      // One spring per tet edge, k = sum_e E_e V_e / L^2 over the elements around it, with
      // each region's E (Van Gelder's stiffness): a uniform dilation then costs what it costs
      // an element of Poisson's ratio 1/4, the one isotropic material central springs can match.
      auto& set = problem_.AddSet<energy::EdgeSpring>(TermGroup::kElastic);
      auto* blocks = set.mutable_blocks();
      for (const ObjectState& o : state.objects) {
        std::map<std::pair<int, int>, double> edges;  // E V_edge
        for (int e = 0; e < o.model.num_elements(); ++e) {
          const int region = e < o.mesh.region.size() ? o.mesh.region(e) : 0;
          const double share = o.material.ForRegion(region).youngs_modulus * o.model.rest(e).volume;
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

bool NoFlatElement(const TrackerState& state, const Vertices& x) {
  for (const ObjectState& o : state.objects) {
    std::atomic<bool> flat(false);
    ParallelFor(state.options.solver.num_threads, o.model.num_elements(), 4096, [&](int64_t e) {
      if (flat) return;
      const double* p[4];
      for (int k = 0; k < 4; ++k) p[k] = x.data() + 3 * (o.model.tets()(e, k) + o.offset);
      if (!(energy::VolumeRatio(o.model.rest(static_cast<int>(e)), p) > 0.0)) flat = true;
    });
    if (flat) return false;
  }
  return true;
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
      // Turned about the centre (no rotations: the identity), then moved.
      const Eigen::Matrix3d R = a.rotations.empty() ? Eigen::Matrix3d::Identity() : RotationFromVector(a.rotations[i]);
      const Eigen::RowVector3d c = a.centre.transpose();
      a.targets = ((a.origin.rowwise() - c) * R.transpose()).rowwise() + (c + a.translations[i].transpose());
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
  if (barrier_ != nullptr) {
    // All or none: an element folded at the start unfolds only if its neighbours may pass
    // through flat on the way, which the barrier forbids.
    const bool unfolded = NoFlatElement(*state, state->x);
    const size_t want = unfolded ? barrier_blocks_.size() : 0;
    if (barrier_->blocks().size() != want) {
      *barrier_->mutable_blocks() = unfolded ? barrier_blocks_ : std::vector<energy::InversionBarrier>();
    }
  }
}

void FrameProblem::SetDataSurface(const DataSurface* surface) {
  data_surface_ = surface;
  surface_vertex_area_.clear();
  surface_triangle_area_.clear();
  if (surface == nullptr) return;
  const TrackerState& view = surface->view();
  const Vertices& rest = surface->rest();
  surface_vertex_area_ = surface->pair_area();
  for (Eigen::Index f = 0; f < view.surface.rows(); ++f) {
    const int a = view.surface(f, 0), b = view.surface(f, 1), c = view.surface(f, 2);
    const Eigen::Vector3d ab = rest.row(b) - rest.row(a), ac = rest.row(c) - rest.row(a);
    surface_triangle_area_[TriangleKey(a, b, c)] = 0.5 * ab.cross(ac).norm();
  }
}

void FrameProblem::SetData(const std::vector<DataPair>& pairs, const RegistrationOptions& options) {
  problem_.Clear(TermGroup::kData);
  const energy::Loss loss{options.data.loss, options.data.loss_scale};
  auto& point1 = *problem_.AddSet<energy::PointToPoint<1>>(TermGroup::kData, loss).mutable_blocks();
  auto& point3 = *problem_.AddSet<energy::PointToPoint<3>>(TermGroup::kData, loss).mutable_blocks();
  auto& plane1 = *problem_.AddSet<energy::PointToPlane<1>>(TermGroup::kData, loss).mutable_blocks();
  auto& plane3 = *problem_.AddSet<energy::PointToPlane<3>>(TermGroup::kData, loss).mutable_blocks();
  // Points of an embedded surface (four coarse vertices); only with a data surface, so that
  // a problem without one has the same sets as before.
  std::vector<energy::PointToPoint<4>>* point4 = nullptr;
  std::vector<energy::PointToPlane<4>>* plane4 = nullptr;
  if (data_surface_ != nullptr) {
    point4 = problem_.AddSet<energy::PointToPoint<4>>(TermGroup::kData, loss).mutable_blocks();
    plane4 = problem_.AddSet<energy::PointToPlane<4>>(TermGroup::kData, loss).mutable_blocks();
  }
  // The areas and objects of the surface the pairs are on.
  const std::vector<double>& vertex_area = data_surface_ != nullptr ? surface_vertex_area_ : vertex_area_;
  const std::unordered_map<uint64_t, double>& triangle_area =
      data_surface_ != nullptr ? surface_triangle_area_ : triangle_area_;
  const std::vector<int>& vertex_object =
      data_surface_ != nullptr ? data_surface_->view().vertex_object : vertex_object_;
  // Per pair: the legacy weight, or data_per_area times the area the pair stands for. The
  // area of a cloud point is the median over the touched surface triangles of (triangle's
  // rest area / its cloud->model pairs): the cloud's spacing, measured where it covers the
  // surface. One value for all points: a triangle reached by a single stray point (an
  // outlier, a hand next to the object) must not hand it the triangle's whole area.
  const bool per_pair = options.weights.data >= 0;
  double point_area = 0.0;
  if (!per_pair) {
    std::unordered_map<uint64_t, int> triangle_pairs;  // cloud->model pairs per triangle
    for (const DataPair& p : pairs) {
      if (p.num_vertices == 3) ++triangle_pairs[TriangleKey(p.vertices[0], p.vertices[1], p.vertices[2])];
    }
    std::vector<double> shares;
    shares.reserve(triangle_pairs.size());
    for (const auto& [key, count] : triangle_pairs) {
      const auto it = triangle_area.find(key);
      if (it != triangle_area.end()) shares.push_back(it->second / count);
    }
    if (!shares.empty()) {
      std::nth_element(shares.begin(), shares.begin() + shares.size() / 2, shares.end());
      point_area = shares[shares.size() / 2];
    }
  }
  auto weight_of = [&](const DataPair& p) {
    if (per_pair) return options.weights.data;
    const double k = options.weights.data_per_area;
    if (p.num_vertices == 1) {
      if (p.vertices[0] >= static_cast<int>(vertex_area.size())) return 0.0;
      double area = vertex_area[p.vertices[0]];
      const double cap = options.weights.model_to_cloud_area_cap;
      if (cap > 0 && point_area > 0) area = std::min(area, cap * point_area);
      return k * options.weights.model_to_cloud_share * area;
    }
    return k * point_area;
  };
  // The balance (weights.model_to_cloud_balance): per object, the share of its model->cloud
  // pairs' weight when they outnumber the cloud points its cloud->model pairs stand for (a
  // voxel's weight, p.weight, and every cloud_stride-th point's stride: a dense cloud
  // subsampled is still the denser); 1 otherwise, and 1 for an object without cloud->model
  // pairs (data.cloud_to_model off, or its points all another object's). A cloud->model pair
  // is its triangle's object's.
  std::vector<double> balance;
  if (per_pair && options.weights.model_to_cloud_balance && num_objects_ > 0) {
    const auto objects = static_cast<size_t>(num_objects_);
    std::vector<double> m2c(objects, 0.0), c2m(objects, 0.0);
    for (const DataPair& p : pairs) {
      if (p.vertices[0] >= static_cast<int>(vertex_object.size())) continue;
      const auto o = static_cast<size_t>(vertex_object[static_cast<size_t>(p.vertices[0])]);
      if (p.num_vertices == 1) {
        m2c[o] += 1.0;
      } else {
        c2m[o] += p.weight * options.data.cloud_stride;
      }
    }
    balance.assign(objects, 1.0);
    for (size_t o = 0; o < balance.size(); ++o) {
      if (m2c[o] > c2m[o] && c2m[o] > 0) balance[o] = c2m[o] / m2c[o];
    }
  }
  auto fill = [&](const DataPair& p, auto* b) {
    if (data_surface_ != nullptr) {
      const DataSurface::Stencil st = data_surface_->Map(p);
      for (size_t k = 0; k < b->vertices.size(); ++k) {
        b->vertices[k] = st.vertices[k];
        b->barycentric[k] = st.weights[k];
      }
    } else if constexpr (std::remove_pointer_t<decltype(b)>::kVertices <= 3) {  // 4: embedded only
      for (size_t k = 0; k < b->vertices.size(); ++k) {
        b->vertices[k] = p.vertices[k];
        b->barycentric[k] = p.barycentric[static_cast<Eigen::Index>(k)];
      }
    }
    b->target = p.target;
    if constexpr (HasNormal<std::remove_pointer_t<decltype(b)>>::value) b->normal = p.normal;
    // A legacy per-pair weight counts the points a voxel stands for (p.weight); a weight per
    // unit area already divides the area among the points that are there.
    b->weight = per_pair ? weight_of(p) * p.weight : weight_of(p);
    if (p.num_vertices == 1 && !balance.empty() && p.vertices[0] < static_cast<int>(vertex_object.size())) {
      b->weight *= balance[static_cast<size_t>(vertex_object[static_cast<size_t>(p.vertices[0])])];
    }
  };
  // Which set a pair goes to; each set sized once (they are made anew every outer iteration).
  enum Kind { kPoint1, kPoint3, kPlane1, kPlane3, kPoint4, kPlane4 };
  auto kind_of = [&](const DataPair& p) {
    const bool plane = p.normal.squaredNorm() > 0;
    // On an embedded surface (a data-surface vertex carried by four coarse ones).
    if (data_surface_ != nullptr && data_surface_->embedded(data_surface_->view().vertex_object[static_cast<size_t>(p.vertices[0])])) {
      return plane ? kPlane4 : kPoint4;
    }
    if (p.num_vertices == 1) return plane ? kPlane1 : kPoint1;
    return plane ? kPlane3 : kPoint3;
  };
  size_t counts[6] = {0, 0, 0, 0, 0, 0};
  for (const DataPair& p : pairs) ++counts[kind_of(p)];
  point1.reserve(counts[kPoint1]);
  point3.reserve(counts[kPoint3]);
  plane1.reserve(counts[kPlane1]);
  plane3.reserve(counts[kPlane3]);
  if (point4 != nullptr) {
    point4->reserve(counts[kPoint4]);
    plane4->reserve(counts[kPlane4]);
  }
  auto add = [&](const DataPair& p, auto* set) {
    typename std::remove_pointer_t<decltype(set)>::value_type b;
    fill(p, &b);
    set->push_back(b);
  };
  for (const DataPair& p : pairs) {
    switch (kind_of(p)) {
      case kPoint1: add(p, &point1); break;
      case kPoint3: add(p, &point3); break;
      case kPlane1: add(p, &plane1); break;
      case kPlane3: add(p, &plane3); break;
      case kPoint4: add(p, point4); break;
      case kPlane4: add(p, plane4); break;
    }
  }
}

void FrameProblem::SetFreeSpace(const TrackerState& state, const ObservedDepth& observed) {
  free_space_.clear();
  const FreeSpaceOptions& options = state.options.free_space;
  if (!options.enabled || observed.empty()) return;
  for (int v : state.surface_vertices) {
    if (problem_.is_fixed(v)) continue;
    energy::FreeSpacePenalty b;
    double depth = 0.0;
    if (!observed.Observed(state.x.row(v).transpose(), &b.ray, &b.origin, &depth)) continue;
    b.vertices = {{v}};
    b.weight = options.weight;
    b.depth = depth - options.tolerance;
    // Only the vertices in the seen-through space at the outer iteration's start, like the
    // pairs: where there are none, the problem is the one without free space, to the last bit
    // (the surface the data hold lies within the tolerance of the observed depth).
    const double violation = b.Violation(state.x.data() + 3 * v);
    if (!(violation > 0)) continue;
    // A vertex whose way out across the rays is shorter than back along its ray (within a
    // tolerance: the image resolves sideways distances only to a pixel) is a surface off
    // sideways, lagging behind a motion across the rays: the pairs move it, not free space.
    const double reach = violation + options.tolerance;
    if (observed.SidewaysExit(state.x.row(v).transpose(), options.tolerance, reach) < reach) continue;
    free_space_.push_back(b);
  }
  if (free_space_.empty()) return;
  *problem_.AddSet<energy::FreeSpacePenalty>(TermGroup::kData).mutable_blocks() = free_space_;
}

int FrameProblem::FreeSpaceHeld(const Vertices& x) const {
  int held = 0;
  for (const energy::FreeSpacePenalty& b : free_space_) {
    if (b.vertices[0] < x.rows() && b.Violation(x.data() + 3 * b.vertices[0]) > 0) ++held;
  }
  return held;
}

void FrameProblem::SetLoads(const TrackerState& state) {
  problem_.Clear(TermGroup::kLoad);
  const bool any = std::any_of(state.objects.begin(), state.objects.end(), [](const ObjectState& o) {
    return o.gravity.squaredNorm() > 0 || o.loads.rows() > 0;
  });
  if (!any) return;  // a scene without loads gets no load set
  auto* blocks = problem_.AddSet<energy::ExternalLoad>(TermGroup::kLoad).mutable_blocks();
  for (const ObjectState& o : state.objects) {
    const bool gravity = o.gravity.squaredNorm() > 0;
    const bool nodal = o.loads.rows() == o.mesh.num_vertices();
    if (!gravity && !nodal) continue;
    for (int v = 0; v < o.mesh.num_vertices(); ++v) {
      const int g = v + o.offset;
      if (problem_.is_fixed(g)) continue;
      Eigen::Vector3d f = Eigen::Vector3d::Zero();
      if (gravity) f += state.mass(g) * o.gravity;
      if (nodal) f += o.loads.row(v).transpose();
      energy::ExternalLoad b;
      if (energy::MakeExternalLoad(g, f, state.x.row(g).transpose(), state.mean_edge_length, &b)) {
        blocks->push_back(b);
      }
    }
  }
}

void FrameProblem::SetContacts(
    const std::vector<Contact>& contacts, const CollisionWorld& world,
    const std::map<std::pair<int, int>, TrackerState::ContactMultiplier>& multipliers) {
  problem_.Clear(TermGroup::kCollision);
  force_contacts_ = contacts;
  force_penalty_.clear();
  force_friction_obstacle_.clear();
  force_friction_pair_.clear();
  force_friction_embedded_.clear();
  auto& obstacle = *problem_.AddSet<energy::ContactPenalty<3>>(TermGroup::kCollision).mutable_blocks();
  auto& pair = *problem_.AddSet<energy::ContactPenalty<6>>(TermGroup::kCollision).mutable_blocks();
  std::vector<energy::ContactPenalty<4>> embedded;
  for (const Contact& c : contacts) {
    // 1/2 k max(0, lambda / k - g)^2: its force at g = 0 is the multiplier's lambda.
    double k = world.stiffness(), standoff = 0.0;
    const auto it = multipliers.find({c.source, c.object_b});
    if (it != multipliers.end()) {
      k = it->second.stiffness;
      standoff = it->second.lambda / k;
    }
    force_penalty_.emplace_back(standoff, k);
    const DataSurface::Stencil st = ContactStencil(c);
    if (st.n == 4) {
      embedded.push_back(EmbeddedPenaltyBlock(c, st.vertices, st.weights, standoff, k));
    } else if (c.obstacle()) {
      obstacle.push_back(ObstaclePenaltyBlock(c, standoff, k));
    } else {
      pair.push_back(PairPenaltyBlock(c, standoff, k));
    }
  }
  // Only with a data surface, so that a scene without one keeps its sets as they were.
  if (!embedded.empty()) {
    *problem_.AddSet<energy::ContactPenalty<4>>(TermGroup::kCollision).mutable_blocks() = std::move(embedded);
  }
}

DataSurface::Stencil FrameProblem::ContactStencil(const Contact& c) const {
  DataSurface::Stencil none;
  none.n = 0;
  const int meshes = problem_.num_vertices();
  if (data_surface_ == nullptr || c.vertices_a[0] < meshes) return none;
  // A vertex of the surface (the contact's corner, a unit barycentric) is carried by its own
  // embedding, exactly; a point inside a triangle as the data terms' cloud->model pairs are.
  DataPair p;
  int corner = -1;
  for (int k = 0; k < 3; ++k) {
    if (c.bary_a[k] == 1.0) corner = k;
  }
  if (corner >= 0) {
    p.num_vertices = 1;
    p.vertices[0] = c.vertices_a[corner] - meshes;
  } else {
    p.num_vertices = 3;
    for (int k = 0; k < 3; ++k) p.vertices[k] = c.vertices_a[k] - meshes;
    p.barycentric = c.bary_a;
  }
  return data_surface_->Map(p);
}

}  // namespace femreg
