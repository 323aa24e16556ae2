// The Tracker's set-up calls: labels, contacts, fracture, force regions, anchors and loads
// (the frame loop: tracker.cc).
#include <string>
#include <utility>
#include <vector>

#include "femreg/tracker.h"
#include "fracture/measure_bound.h"
#include "registration/tracker_impl.h"

namespace femreg {

Status Tracker::SetObjectLabel(int object, int label) {
  if (object < 0 || object >= num_objects()) return Status::Error("no object " + std::to_string(object));
  if (label >= 0 && impl_->data_surface) {
    return Status::Error("object " + std::to_string(object) +
                         ": labels do not combine with embedded surfaces (objects[i].surface) yet");
  }
  impl_->state.objects[object].label = label;
  return Status::Ok();
}

Status Tracker::SetEmbeddedSurface(int object, const Vertices& rest, const Triangles& triangles) {
  TrackerState& state = impl_->state;
  const std::string name = "object " + std::to_string(object);
  if (object < 0 || object >= num_objects()) return Status::Error("embedded surface: no " + name);
  if (state.fracture) return Status::Error(name + ": an embedded surface does not combine with fracture");
  for (const ObjectState& o : state.objects) {
    if (o.label >= 0) return Status::Error(name + ": an embedded surface does not combine with labels yet");
  }
  EmbeddedSurface surface;
  const Status status = MakeEmbeddedSurface(state.objects[object].mesh, rest, triangles, &surface);
  if (!status.ok()) return Status::Error(name + ": embedded surface: " + status.message());
  impl_->embedded.resize(state.objects.size());
  impl_->embedded[static_cast<size_t>(object)] = std::move(surface);
  std::vector<const EmbeddedSurface*> surfaces;
  for (const EmbeddedSurface& e : impl_->embedded) surfaces.push_back(e.rest.rows() > 0 ? &e : nullptr);
  impl_->data_surface = std::make_unique<DataSurface>();
  impl_->data_surface->Build(state, surfaces);
  impl_->data_index.Reset();
  impl_->frame_problem.SetDataSurface(impl_->data_surface.get());
  // Contacts enabled before: the world takes the embedded surface for the obstacles.
  if (!impl_->collision_names.empty()) return impl_->BuildCollision();
  return Status::Ok();
}

bool Tracker::has_embedded_surface(int object) const {
  const auto i = static_cast<size_t>(object);
  return object >= 0 && i < impl_->embedded.size() && impl_->embedded[i].rest.rows() > 0;
}

Vertices Tracker::surface_vertices(int object) const {
  if (!has_embedded_surface(object)) return Vertices(0, 3);
  const EmbeddedSurface& e = impl_->embedded[static_cast<size_t>(object)];
  const ObjectState& o = impl_->state.objects[static_cast<size_t>(object)];
  return InterpolateEmbedded(o.mesh, impl_->state.x.middleRows(o.offset, o.mesh.num_vertices()), e.embedding);
}

const Triangles& Tracker::surface_triangles(int object) const {
  static const Triangles kNone(0, 3);
  if (!has_embedded_surface(object)) return kNone;
  return impl_->embedded[static_cast<size_t>(object)].triangles;
}

double Tracker::surface_outside(int object) const {
  return has_embedded_surface(object) ? impl_->embedded[static_cast<size_t>(object)].outside : 0.0;
}

Status Tracker::EnableCollision(const CollisionSpec& spec, const std::vector<std::string>& names) {
  TrackerState& state = impl_->state;
  if (names.size() != state.objects.size()) return Status::Error("one name per object is needed");
  impl_->collision_spec = spec;
  impl_->collision_names = names;
  const Status status = impl_->BuildCollision();
  if (!status.ok()) impl_->collision_names.clear();
  return status;
}

Status Tracker::Impl::BuildCollision() {
  std::vector<Triangles> surfaces, obstacle_surfaces;
  for (int i = 0; i < static_cast<int>(state.objects.size()); ++i) surfaces.push_back(state.ObjectSurface(i));
  // Body-body contacts stay on the meshes' surfaces; an embedded surface meets the obstacles,
  // its vertices numbered after the meshes' in CollisionPositions.
  if (data_surface) {
    obstacle_surfaces.resize(state.objects.size());
    for (int i = 0; i < static_cast<int>(state.objects.size()); ++i) {
      if (!data_surface->embedded(i)) continue;
      obstacle_surfaces[static_cast<size_t>(i)] =
          data_surface->ObjectSurface(i).array() + static_cast<int>(state.x.rows()) + data_surface->offset(i);
    }
  }
  auto world = std::make_unique<CollisionWorld>();
  Status status = world->Init(collision_spec, collision_names, surfaces, CollisionPositions(),  // no pairs: every pair
                              obstacle_surfaces);
  if (!status.ok()) return status;
  state.collision = world->enabled() ? std::move(world) : nullptr;
  state.contacts.clear();
  return Status::Ok();
}

const Vertices& Tracker::Impl::CollisionPositions() {
  if (!data_surface) return state.x;
  const Vertices& y = data_surface->Update(state.x).x;
  collision_x.resize(state.x.rows() + y.rows(), 3);
  collision_x.topRows(state.x.rows()) = state.x;
  collision_x.bottomRows(y.rows()) = y;
  return collision_x;
}

Status Tracker::EnableFracture(const std::vector<FractureOptions>& options) {
  TrackerState& state = impl_->state;
  if (options.size() != state.objects.size()) {
    return Status::Error("one FractureOptions per object is needed");
  }
  std::string error;
  for (size_t i = 0; i < options.size(); ++i) {
    if (!options[i].IsValid(&error)) return Status::Error("object " + std::to_string(i) + ": " + error);
  }
  if (impl_->data_surface) {
    return Status::Error("fracture does not combine with embedded surfaces (objects[i].surface): a split "
                         "would leave the surface's vertices in elements that no longer exist");
  }
  auto f = std::make_unique<FractureState>();
  f->options = options;
  for (const ObjectState& o : state.objects) {
    std::vector<int> ids(o.mesh.num_vertices());
    for (int v = 0; v < o.mesh.num_vertices(); ++v) ids[v] = v;
    f->original.push_back(std::move(ids));
    std::vector<char> on_surface(static_cast<size_t>(o.mesh.num_vertices()), 0);
    for (int v : o.mesh.surface_vertices) on_surface[static_cast<size_t>(v)] = 1;
    f->initial_surface.push_back(std::move(on_surface));
    NodeSeparation sep;
    sep.measure = Eigen::VectorXd::Zero(o.mesh.num_vertices());
    f->separation.push_back(std::move(sep));
  }
  const size_t n = state.objects.size();
  f->detected_at.resize(n);
  f->partial.assign(n, 0);
  f->full_measure.resize(n);
  f->bound.resize(n);
  state.fracture = std::move(f);
  return Status::Ok();
}

Status Tracker::SetForceRegion(int object, const std::vector<int>& vertices) {
  TrackerState& state = impl_->state;
  if (object < 0 || object >= num_objects()) return Status::Error("force region: no object " + std::to_string(object));
  const int nv = state.objects[object].mesh.num_vertices();
  std::vector<char> region;
  if (!vertices.empty()) {
    region.assign(static_cast<size_t>(nv), 0);
    for (int v : vertices) {
      if (v < 0 || v >= nv) {
        return Status::Error("force region: vertex " + std::to_string(v) + " is not one of object " +
                             std::to_string(object) + "'s " + std::to_string(nv));
      }
      region[static_cast<size_t>(v)] = 1;
    }
  }
  if (state.force_region.size() < state.objects.size()) state.force_region.resize(state.objects.size());
  state.force_region[static_cast<size_t>(object)] = std::move(region);
  return Status::Ok();
}

const Vertices& Tracker::external_forces(int object) const { return impl_->state.external_forces.at(object); }

const Eigen::VectorXd& Tracker::fracture_measure(int object) const {
  static const Eigen::VectorXd kEmpty;
  if (!impl_->state.fracture) return kEmpty;
  FractureState& f = *impl_->state.fracture;
  const NodeSeparation& sep = f.separation.at(object);
  const Vertices& x = f.detected_at.at(object);
  if (!f.partial.at(object) || x.rows() != sep.measure.size()) return sep.measure;
  // The last detection evaluated it only where it could matter: the full measure at its
  // positions, once (a cache: not to be asked from two threads at once), with the rotations
  // found there (the model's are left as they are).
  Eigen::VectorXd& full = f.full_measure[static_cast<size_t>(object)];
  if (full.size() != sep.measure.size()) {
    const ObjectState& o = impl_->state.objects[static_cast<size_t>(object)];
    NodeSeparation all;
    fracture_internal::DetectFractureWith(o.mesh, o.model, fracture_internal::RotationsAt(o.model, x), x,
                                          f.options[static_cast<size_t>(object)], &all);
    full = std::move(all.measure);
  }
  return full;
}

const std::vector<int>& Tracker::original_vertices(int object) const {
  static const std::vector<int> kEmpty;
  return impl_->state.fracture ? impl_->state.fracture->original.at(object) : kEmpty;
}

Status Tracker::AddAnchor(const std::string& name, int object, const std::vector<int>& vertices,
                          bool hard, double weight) {
  TrackerState& state = impl_->state;
  if (object < 0 || object >= num_objects()) {
    return Status::Error("anchor '" + name + "': no object " + std::to_string(object));
  }
  if (vertices.empty()) return Status::Error("anchor '" + name + "': no vertex");
  if (state.anchors.count(name)) return Status::Error("anchor '" + name + "' exists already");
  const ObjectState& o = state.objects[object];
  Anchor a;
  a.object = object;
  a.hard = hard;
  a.weight = weight;
  a.targets.resize(static_cast<Eigen::Index>(vertices.size()), 3);
  for (size_t i = 0; i < vertices.size(); ++i) {
    if (vertices[i] < 0 || vertices[i] >= o.mesh.num_vertices()) {
      return Status::Error("anchor '" + name + "': vertex " + std::to_string(vertices[i]) + " out of range");
    }
    a.vertices.push_back(vertices[i] + o.offset);
    a.targets.row(static_cast<Eigen::Index>(i)) = o.mesh.x.row(vertices[i]);
  }
  a.origin = a.targets;
  state.anchors[name] = std::move(a);
  return Status::Ok();
}

Status Tracker::SetAnchorTargets(const std::string& name, const Vertices& targets) {
  auto it = impl_->state.anchors.find(name);
  if (it == impl_->state.anchors.end()) return Status::Error("no anchor named '" + name + "'");
  if (targets.rows() != it->second.targets.rows() || !targets.allFinite()) {
    return Status::Error("anchor '" + name + "': expected " + std::to_string(it->second.targets.rows()) +
                         " finite targets");
  }
  it->second.targets = targets;
  it->second.translations.clear();
  return Status::Ok();
}

Status Tracker::SetAnchorTrajectory(const std::string& name,
                                    const std::vector<Eigen::Vector3d>& translations) {
  auto it = impl_->state.anchors.find(name);
  if (it == impl_->state.anchors.end()) return Status::Error("no anchor named '" + name + "'");
  for (const auto& t : translations) {
    if (!t.allFinite()) return Status::Error("anchor '" + name + "': non-finite translation");
  }
  it->second.translations = translations;
  it->second.rotations.clear();
  return Status::Ok();
}

Status Tracker::SetAnchorTrajectory(const std::string& name,
                                    const std::vector<Eigen::Vector3d>& translations,
                                    const std::vector<Eigen::Vector3d>& rotations,
                                    const Eigen::Vector3d& centre) {
  if (rotations.size() != translations.size()) {
    return Status::Error("anchor '" + name + "': " + std::to_string(rotations.size()) + " rotations for " +
                         std::to_string(translations.size()) + " translations");
  }
  for (const auto& r : rotations) {
    if (!r.allFinite()) return Status::Error("anchor '" + name + "': non-finite rotation");
  }
  if (!centre.allFinite()) return Status::Error("anchor '" + name + "': non-finite centre");
  Status status = SetAnchorTrajectory(name, translations);
  if (!status.ok()) return status;
  Anchor& a = impl_->state.anchors[name];
  a.rotations = rotations;
  a.centre = centre;
  return Status::Ok();
}

Status Tracker::SetExternalLoads(int object, const Eigen::Vector3d& gravity,
                                 const std::vector<std::pair<int, Eigen::Vector3d>>& nodal_loads) {
  if (object < 0 || object >= num_objects()) {
    return Status::Error("external loads: no object " + std::to_string(object));
  }
  ObjectState& o = impl_->state.objects[object];
  if (!gravity.allFinite()) return Status::Error("external loads: non-finite gravity");
  Vertices loads;
  if (!nodal_loads.empty()) loads = Vertices::Zero(o.mesh.num_vertices(), 3);
  for (const auto& [v, f] : nodal_loads) {
    if (v < 0 || v >= o.mesh.num_vertices()) {
      return Status::Error("external loads: vertex " + std::to_string(v) + " out of range");
    }
    if (!f.allFinite()) return Status::Error("external loads: non-finite force on vertex " + std::to_string(v));
    loads.row(v) += f.transpose();
  }
  if (gravity.squaredNorm() > 0 && !(o.mesh.mass.size() == o.mesh.num_vertices() && o.mesh.mass.sum() > 0)) {
    return Status::Error("external loads: gravity needs the object's masses (a density)");
  }
  o.gravity = gravity;
  o.loads = std::move(loads);
  return Status::Ok();
}

}  // namespace femreg
