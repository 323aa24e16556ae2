// Contacts between objects (pairs of surface triangles found by two AABB trees) and with
// rigid obstacles (planes by vertex, boxes and meshes by triangle pairs). See collision.h
// for the sign conventions.
#include <algorithm>
#include <cmath>
#include <limits>
#include <map>

#include "femreg/collision.h"
#include "femreg/io.h"  // ReadTriangleSurface

namespace femreg {

namespace {

Eigen::Vector3d Row(const Vertices& x, int v) { return x.row(v).transpose(); }

Eigen::Vector3d UnitNormal(const Vertices& x, const Triangles& t, int f) {
  const Eigen::Vector3d a = Row(x, t(f, 0)), b = Row(x, t(f, 1)), c = Row(x, t(f, 2));
  const Eigen::Vector3d n = (b - a).cross(c - a);
  const double len = n.norm();
  return len > 0 ? Eigen::Vector3d(n / len) : Eigen::Vector3d::Zero();
}

}  // namespace

Status CollisionWorld::Init(const CollisionSpec& spec, const std::vector<std::string>& names,
                            const std::vector<Triangles>& surfaces, const Vertices& x,
                            const std::vector<Triangles>& obstacle_surfaces) {
  spec_ = spec;
  std::string error;
  if (!spec.IsValid(&error)) return Status::Error(error);  // "collision.stiffness must be > 0 (got 0)"
  const int n = static_cast<int>(surfaces.size());
  surfaces_ = surfaces;
  auto find = [&](const std::string& name, int* index) {
    for (int i = 0; i < n; ++i)
      if (i < static_cast<int>(names.size()) && names[i] == name) {
        *index = i;
        return true;
      }
    return false;
  };
  pairs_.clear();
  std::vector<std::pair<std::string, std::string>> named;
  for (const CollisionPair& p : spec.pairs) named.emplace_back(p.first, p.second);
  if (named.empty()) {  // every pair
    for (size_t i = 0; i < names.size(); ++i)
      for (size_t j = i + 1; j < names.size(); ++j) named.emplace_back(names[i], names[j]);
  }
  for (const auto& p : named) {
    int a = -1, b = -1;
    if (!find(p.first, &a)) return Status::Error("collision.pairs: no object named '" + p.first + "'");
    if (!find(p.second, &b)) return Status::Error("collision.pairs: no object named '" + p.second + "'");
    if (a == b) return Status::Error("collision.pairs: '" + p.first + "' paired with itself");
    pairs_.emplace_back(std::min(a, b), std::max(a, b));
  }
  std::sort(pairs_.begin(), pairs_.end());
  pairs_.erase(std::unique(pairs_.begin(), pairs_.end()), pairs_.end());
  // Friction per pair where the spec gives one (an unset one falls back to the default).
  pair_friction_.clear();
  has_friction_ = spec.friction > 0;
  for (const CollisionPair& p : spec.pairs) {
    int a = -1, b = -1;
    if (!p.friction || !find(p.first, &a) || !find(p.second, &b)) continue;
    pair_friction_.push_back({{std::min(a, b), std::max(a, b)}, *p.friction});
    has_friction_ = has_friction_ || *p.friction > 0;
  }
  for (const ObstacleSpec& os : spec.obstacles) has_friction_ = has_friction_ || os.friction.value_or(0.0) > 0;

  obstacles_.clear();
  for (const ObstacleSpec& os : spec.obstacles) {
    Obstacle o;
    o.spec = os;
    o.hits.assign(n, os.objects.empty() ? 1 : 0);
    for (const std::string& name : os.objects) {
      int i = -1;
      if (!find(name, &i)) {
        return Status::Error("collision.obstacles '" + os.name + "': no object named '" + name + "'");
      }
      o.hits[i] = 1;
    }
    if (os.kind == ObstacleSpec::Kind::kBox) {
      const Eigen::Vector3d h = 0.5 * os.box_size;
      o.local.resize(8, 3);
      for (int c = 0; c < 8; ++c) {
        o.local.row(c) << ((c & 1) ? h.x() : -h.x()), ((c & 2) ? h.y() : -h.y()), ((c & 4) ? h.z() : -h.z());
      }
      o.triangles.resize(12, 3);
      o.triangles << 0, 2, 3, 0, 3, 1,  // -z
          4, 5, 7, 4, 7, 6,             // +z
          0, 1, 5, 0, 5, 4,             // -y
          2, 6, 7, 2, 7, 3,             // +y
          0, 4, 6, 0, 6, 2,             // -x
          1, 3, 7, 1, 7, 5;             // +x
    } else if (os.kind == ObstacleSpec::Kind::kMesh) {
      const std::string what = "collision.obstacles '" + os.name + "': ";
      if (os.surface) {  // checked as the reader checks a file's
        o.local = os.surface->vertices;
        o.triangles = os.surface->triangles;
        if (o.triangles.rows() == 0) return Status::Error(what + "its surface in memory has no triangle");
        if (!o.local.allFinite()) return Status::Error(what + "its surface in memory has a vertex that is not finite");
        if (o.triangles.minCoeff() < 0 || o.triangles.maxCoeff() >= o.local.rows()) {
          return Status::Error(what + "its surface in memory has a triangle index outside its " +
                               std::to_string(o.local.rows()) + " vertices");
        }
      } else {
        Status status = ReadTriangleSurface(os.mesh_path, &o.local, &o.triangles);
        if (!status.ok()) return Status::Error(what + status.message());
      }
      o.local *= os.scale;
    } else if (!(os.plane_normal.norm() > 0)) {
      return Status::Error("collision.obstacles '" + os.name + "': the plane normal is zero");
    }
    obstacles_.push_back(std::move(o));
  }
  // An object with a surface of its own for the obstacles (an embedded one) meets them there:
  // one more slot of the world, whose contacts are reported as the object's.
  owner_.resize(static_cast<size_t>(n));
  for (int i = 0; i < n; ++i) owner_[static_cast<size_t>(i)] = i;
  for (int i = 0; i < n && i < static_cast<int>(obstacle_surfaces.size()); ++i) {
    if (obstacle_surfaces[static_cast<size_t>(i)].rows() == 0) continue;
    surfaces_.push_back(obstacle_surfaces[static_cast<size_t>(i)]);
    owner_.push_back(i);
    for (Obstacle& o : obstacles_) {
      o.hits.push_back(o.hits[static_cast<size_t>(i)]);
      o.hits[static_cast<size_t>(i)] = 0;
    }
  }
  const int slots = static_cast<int>(surfaces_.size());
  needs_tree_.assign(static_cast<size_t>(slots), 0);
  for (const auto& p : pairs_) needs_tree_[p.first] = needs_tree_[p.second] = 1;
  for (const Obstacle& o : obstacles_)
    for (int i = 0; i < slots; ++i)
      if (o.hits[static_cast<size_t>(i)] && o.spec.kind != ObstacleSpec::Kind::kPlane) needs_tree_[i] = 1;
  enabled_ = !pairs_.empty() || !obstacles_.empty();
  trees_.assign(static_cast<size_t>(slots), AabbTree());
  surface_vertices_.assign(static_cast<size_t>(slots), {});
  vertex_triangle_.assign(static_cast<size_t>(slots), {});
  trees_built_ = 0;
  const std::vector<Triangles> all = surfaces_;
  for (int i = 0; i < slots; ++i) Rebuild(i, all[static_cast<size_t>(i)], x);
  SetFrame(0);
  return Status::Ok();
}

void CollisionWorld::Rebuild(int object, const Triangles& surface, const Vertices& x) {
  surfaces_.at(object) = surface;
  std::map<int, std::array<int, 2>> first;
  for (int f = 0; f < surface.rows(); ++f)
    for (int k = 0; k < 3; ++k) first.emplace(surface(f, k), std::array<int, 2>{f, k});
  surface_vertices_[object].clear();
  vertex_triangle_[object].clear();
  for (const auto& kv : first) {
    surface_vertices_[object].push_back(kv.first);
    vertex_triangle_[object].push_back(kv.second);
  }
  trees_[object] = AabbTree();
  if (needs_tree_[object]) {
    trees_[object].Build(x, surface);
    ++trees_built_;
  }
}

void CollisionWorld::SetFrame(double frame) {
  frame_ = frame;
  for (Obstacle& o : obstacles_) {
    o.pose = ObstaclePose(o.spec.keyframes, frame);
    if (o.triangles.rows() == 0) continue;
    o.world = (o.local * o.pose.linear().transpose()).rowwise() + o.pose.translation().transpose();
    o.world_normals.resize(o.triangles.rows(), 3);
    for (int f = 0; f < o.triangles.rows(); ++f) o.world_normals.row(f) = UnitNormal(o.world, o.triangles, f).transpose();
    if (o.tree.empty()) {
      o.tree.Build(o.world, o.triangles);
    } else {
      o.tree.Refit(o.world);
    }
  }
}

void CollisionWorld::Detect(const Vertices& x, double margin, std::vector<Contact>* contacts) {
  contacts->clear();
  if (!enabled_) return;
  for (size_t i = 0; i < trees_.size(); ++i)
    if (!trees_[i].empty()) trees_[i].Refit(x);
  const double limit = spec_.distance + std::max(0.0, margin);
  for (const auto& p : pairs_) {
    // Broad phase: the roots' boxes.
    const AabbTree& a = trees_[p.first];
    const AabbTree& b = trees_[p.second];
    if (a.empty() || b.empty()) continue;
    const Eigen::AlignedBox3d& ba = a.bounds();
    const Eigen::AlignedBox3d& bb = b.bounds();
    if (((ba.min().array() > bb.max().array() + limit).any()) ||
        ((bb.min().array() > ba.max().array() + limit).any())) {
      continue;
    }
    DetectPair(p.first, p.second, x, limit, contacts);
  }
  for (size_t o = 0; o < obstacles_.size(); ++o)
    for (size_t i = 0; i < trees_.size(); ++i)
      if (obstacles_[o].hits[i]) DetectObstacle(static_cast<int>(o), static_cast<int>(i), x, limit, contacts);
}

namespace {

// The closest point to p over candidate triangles (rows of `tris` over positions xs), with
// the pseudo-normal there: the sum of the outward normals of every candidate triangle that
// attains the minimum (one face inside a face, the faces around an edge or a corner), which
// tells inside from outside also at edges and corners.
struct ClosestOnSurface {
  double distance = std::numeric_limits<double>::infinity();
  int triangle = -1;
  Eigen::Vector3d point = Eigen::Vector3d::Zero(), bary = Eigen::Vector3d(1, 0, 0);
  Eigen::Vector3d pseudo_normal = Eigen::Vector3d::Zero();
};

ClosestOnSurface ClosestPoint(const Eigen::Vector3d& p, const Vertices& xs, const Triangles& tris,
                              const int* candidates, int count) {
  ClosestOnSurface best;
  for (int i = 0; i < count; ++i) {
    const int f = candidates[i];
    Eigen::Vector3d w;
    const Eigen::Vector3d q =
        TriangleClosestPoint(p, Row(xs, tris(f, 0)), Row(xs, tris(f, 1)), Row(xs, tris(f, 2)), &w);
    const double d = (p - q).norm();
    if (d < best.distance) {
      best.distance = d;
      best.triangle = f;
      best.point = q;
      best.bary = w;
    }
  }
  // The faces that reach the same point (a second pass: which they are is known only once
  // the nearest point is; a vertex has a handful of candidates).
  const double tie = 1e-9 + 1e-6 * best.distance;
  for (int i = 0; i < count; ++i) {
    const int f = candidates[i];
    const Eigen::Vector3d q =
        TriangleClosestPoint(p, Row(xs, tris(f, 0)), Row(xs, tris(f, 1)), Row(xs, tris(f, 2)));
    if ((q - best.point).norm() <= tie) best.pseudo_normal += UnitNormal(xs, tris, f);
  }
  return best;
}

// Normal (pointing from the triangle's surface towards the vertex's side) and signed gap of
// a vertex p against its closest surface point: positive outside the surface, negative
// inside. False when no direction is defined.
bool OrientVertex(const Eigen::Vector3d& p, const ClosestOnSurface& c, double scale,
                  Eigen::Vector3d* normal, double* gap) {
  const Eigen::Vector3d d = p - c.point;
  const double pn = c.pseudo_normal.norm();
  if (c.distance > 1e-9 * scale) {
    const double side = pn > 0 && d.dot(c.pseudo_normal) < 0 ? -1.0 : 1.0;
    *normal = side * d / c.distance;
    *gap = side * c.distance;
    return true;
  }
  if (!(pn > 0)) return false;
  *normal = c.pseudo_normal / pn;
  *gap = 0.0;
  return true;
}

// Longest edge of triangle f.
double Diameter(const Vertices& xs, const Triangles& tris, int f) {
  const Eigen::Vector3d a = Row(xs, tris(f, 0)), b = Row(xs, tris(f, 1)), c = Row(xs, tris(f, 2));
  return std::max({(b - a).norm(), (c - b).norm(), (a - c).norm()});
}

// Candidate vertices with the radius to search the other surface in, the largest kept per
// vertex: the limit for a vertex of a near triangle pair, the triangle's size for a vertex
// of a triangle that cuts the other surface (it may be deeper inside than the limit).
void MergeCandidates(std::vector<std::pair<int, double>>* list) {
  std::sort(list->begin(), list->end());
  size_t out = 0;
  for (size_t i = 0; i < list->size();) {
    const int v = (*list)[i].first;
    double radius = 0.0;
    for (; i < list->size() && (*list)[i].first == v; ++i) radius = std::max(radius, (*list)[i].second);
    (*list)[out++] = {v, radius};
  }
  list->resize(out);
}

}  // namespace

// Candidates from the coarse-to-fine phases: the two trees are descended together to the
// triangle pairs whose boxes come within the limit, and the exact triangle-triangle distance
// keeps the pairs that are nearer than the limit or cut each other. Each vertex of a kept
// pair is then one contact against the other surface: its closest point there, searched in
// the other tree within the limit, or within its triangle's size when the pair cuts (a
// vertex that went deeper than D is still pushed out, towards its nearest way out). One
// contact per surface vertex and surface (not one per triangle pair, which repeats a vertex
// up to a dozen times and adds oblique normals where a pair's closest point falls on an
// edge of a triangle that is not the nearest), with the normal of the true closest point:
// the face normal inside a face, the direction to it at an edge or corner.
void CollisionWorld::VertexContacts(const Vertices& xv, const std::vector<std::pair<int, double>>& candidates,
                                    const Vertices& xs, const Triangles& tris, const AabbTree& tree,
                                    double limit,
                                    std::vector<std::pair<int, ClosestPointContact>>* out) const {
  const double scale = std::max({1.0, xv.cwiseAbs().maxCoeff(), xs.cwiseAbs().maxCoeff()});
  std::vector<int> near;
  for (const auto& cand : candidates) {
    const Eigen::Vector3d p = Row(xv, cand.first);
    tree.Overlapping(Eigen::AlignedBox3d(p, p), cand.second, &near);
    if (near.empty()) continue;
    const ClosestOnSurface cs = ClosestPoint(p, xs, tris, near.data(), static_cast<int>(near.size()));
    ClosestPointContact c;
    if (!OrientVertex(p, cs, scale, &c.normal, &c.gap)) continue;
    if (!(c.gap < limit)) continue;
    c.triangle = cs.triangle;
    c.bary = cs.bary;
    c.point = cs.point;
    out->emplace_back(cand.first, c);
  }
}

void CollisionWorld::DetectPair(int a, int b, const Vertices& x, double limit,
                                std::vector<Contact>* out) const {
  std::vector<std::pair<int, int>> candidates;
  trees_[a].Overlapping(trees_[b], limit, &candidates);
  const Triangles& ta = surfaces_[a];
  const Triangles& tb = surfaces_[b];
  std::vector<std::pair<int, double>> a_side, b_side;  // (vertex, search radius)
  for (const auto& c : candidates) {
    Eigen::Vector3d t1[3], t2[3];
    for (int k = 0; k < 3; ++k) {
      t1[k] = Row(x, ta(c.first, k));
      t2[k] = Row(x, tb(c.second, k));
    }
    const TrianglePairDistance d = TriangleTriangleDistance(t1, t2);
    if (d.distance >= limit) continue;
    const double ra = d.intersecting ? std::max(limit, Diameter(x, ta, c.first)) : limit;
    const double rb = d.intersecting ? std::max(limit, Diameter(x, tb, c.second)) : limit;
    for (int k = 0; k < 3; ++k) {
      a_side.emplace_back(ta(c.first, k), ra);
      b_side.emplace_back(tb(c.second, k), rb);
    }
  }
  MergeCandidates(&a_side);
  MergeCandidates(&b_side);
  // Vertices of a against b, then vertices of b against a.
  for (int side = 0; side < 2; ++side) {
    const int own = side == 0 ? a : b, other = side == 0 ? b : a;
    std::vector<std::pair<int, ClosestPointContact>> found;
    VertexContacts(x, side == 0 ? a_side : b_side, x, surfaces_[other], trees_[other], limit, &found);
    for (const auto& f : found) {
      std::array<int, 2> corner;
      if (!Corner(own, f.first, &corner)) continue;
      Contact contact;
      contact.object_a = own;
      contact.object_b = other;
      for (int k = 0; k < 3; ++k) {
        contact.vertices_a[k] = surfaces_[own](corner[0], k);
        contact.vertices_b[k] = surfaces_[other](f.second.triangle, k);
      }
      contact.bary_a = Eigen::Vector3d::Unit(corner[1]);
      contact.bary_b = f.second.bary;
      contact.normal = f.second.normal;
      contact.gap = f.second.gap;
      contact.source = f.first;
      out->push_back(contact);
    }
  }
}

// Contacts of an object with a rigid obstacle: a plane against every surface vertex; a box or
// a mesh like two objects (every vertex against its closest point on the other side), the
// obstacle's vertices against the object's triangles too, so a tool's corner pressing into
// a face is held.
void CollisionWorld::DetectObstacle(int oi, int i, const Vertices& x, double limit,
                                    std::vector<Contact>* out) const {
  const Obstacle& o = obstacles_[oi];
  const Triangles& ta = surfaces_[i];
  if (o.spec.kind == ObstacleSpec::Kind::kPlane) {
    const Eigen::Vector3d n = (o.pose.linear() * o.spec.plane_normal).normalized();
    const Eigen::Vector3d p0 = o.pose * o.spec.plane_point;
    for (size_t s = 0; s < surface_vertices_[i].size(); ++s) {
      const int v = surface_vertices_[i][s];
      const double gap = n.dot(Row(x, v) - p0);
      if (gap >= limit) continue;
      Contact c;
      c.object_a = owner_[static_cast<size_t>(i)];
      c.object_b = -1 - oi;
      const auto& ft = vertex_triangle_[i][s];
      for (int k = 0; k < 3; ++k) c.vertices_a[k] = ta(ft[0], k);
      c.bary_a = Eigen::Vector3d::Unit(ft[1]);
      c.point_b = Row(x, v) - gap * n;
      c.normal = n;
      c.gap = gap;
      c.source = v;
      out->push_back(c);
    }
    return;
  }
  if (trees_[i].empty() || o.tree.empty()) return;
  std::vector<std::pair<int, int>> candidates;
  trees_[i].Overlapping(o.tree, limit, &candidates);
  std::vector<std::pair<int, double>> object_side, obstacle_side;
  for (const auto& c : candidates) {
    Eigen::Vector3d t1[3], t2[3];
    for (int k = 0; k < 3; ++k) {
      t1[k] = Row(x, ta(c.first, k));
      t2[k] = Row(o.world, o.triangles(c.second, k));
    }
    const TrianglePairDistance d = TriangleTriangleDistance(t1, t2);
    if (d.distance >= limit) continue;
    const double ra = d.intersecting ? std::max(limit, Diameter(x, ta, c.first)) : limit;
    const double rb = d.intersecting ? std::max(limit, Diameter(o.world, o.triangles, c.second)) : limit;
    for (int k = 0; k < 3; ++k) {
      object_side.emplace_back(ta(c.first, k), ra);
      obstacle_side.emplace_back(o.triangles(c.second, k), rb);
    }
  }
  MergeCandidates(&object_side);
  MergeCandidates(&obstacle_side);
  std::vector<std::pair<int, ClosestPointContact>> found;
  VertexContacts(x, object_side, o.world, o.triangles, o.tree, limit, &found);
  for (const auto& f : found) {  // object vertices against the obstacle
    std::array<int, 2> corner;
    if (!Corner(i, f.first, &corner)) continue;
    Contact contact;
    contact.object_a = owner_[static_cast<size_t>(i)];
    contact.object_b = -1 - oi;
    for (int k = 0; k < 3; ++k) contact.vertices_a[k] = ta(corner[0], k);
    contact.bary_a = Eigen::Vector3d::Unit(corner[1]);
    contact.point_b = f.second.point;
    contact.normal = f.second.normal;
    contact.gap = f.second.gap;
    contact.source = f.first;
    out->push_back(contact);
  }
  found.clear();
  VertexContacts(o.world, obstacle_side, x, ta, trees_[i], limit, &found);
  for (const auto& f : found) {  // obstacle vertices against the object
    Contact contact;
    contact.object_a = owner_[static_cast<size_t>(i)];
    contact.object_b = -1 - oi;
    for (int k = 0; k < 3; ++k) contact.vertices_a[k] = ta(f.second.triangle, k);
    contact.bary_a = f.second.bary;
    contact.point_b = Row(o.world, f.first);
    contact.normal = -f.second.normal;  // from the obstacle towards the object
    contact.gap = f.second.gap;
    contact.source = -1 - f.first;
    out->push_back(contact);
  }
}

bool CollisionWorld::Corner(int object, int v, std::array<int, 2>* corner) const {
  const std::vector<int>& list = surface_vertices_[object];
  const auto it = std::lower_bound(list.begin(), list.end(), v);
  if (it == list.end() || *it != v) return false;
  *corner = vertex_triangle_[object][it - list.begin()];
  return true;
}

double CollisionWorld::Gap(const Contact& c, const Vertices& x) const {
  Eigen::Vector3d pa = Eigen::Vector3d::Zero(), pb = c.point_b;
  for (int k = 0; k < 3; ++k) pa += c.bary_a[k] * Row(x, c.vertices_a[k]);
  if (!c.obstacle()) {
    pb.setZero();
    for (int k = 0; k < 3; ++k) pb += c.bary_b[k] * Row(x, c.vertices_b[k]);
  }
  return c.normal.dot(pa - pb);
}

ContactStats CollisionWorld::Evaluate(const std::vector<Contact>& contacts, const Vertices& x) const {
  ContactStats s;
  s.min_gap = spec_.distance;
  for (const Contact& c : contacts) {
    const double gap = Gap(c, x);
    s.min_gap = std::min(s.min_gap, gap);
    if (!(gap < spec_.tolerance)) continue;
    ++s.contacts;
    ++(c.obstacle() ? s.obstacle_contacts : s.object_contacts);
    if (gap < 0) s.energy += 0.5 * spec_.stiffness * gap * gap;
  }
  s.max_penetration = std::max(0.0, -s.min_gap);
  return s;
}

}  // namespace femreg
