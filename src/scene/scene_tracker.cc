// Tracker::Create(const Scene&): a scene's objects (meshes, materials per region, labels),
// anchors, boundary clamps, gravity and loads and effects handed to the tracker. It lives with the scene module,
// above registration, so that the tracker needs no scene.
#include <string>
#include <vector>

#include "femreg/scene.h"
#include "femreg/tracker.h"

namespace femreg {
namespace {

// The object a boundary entry or an anchor names ("" with one object: that one).
int ObjectIndex(const Scene& scene, const std::string& name) {
  for (size_t i = 0; i < scene.objects.size(); ++i) {
    if (scene.objects[i].name == name) return static_cast<int>(i);
  }
  return 0;
}

}  // namespace

Status Tracker::Create(const Scene& given, std::unique_ptr<Tracker>* tracker) {
  Scene scene = given;
  ChooseRegistrationElements(&scene);  // nearly incompressible objects (register logs it)
  std::vector<TetMesh> meshes(scene.objects.size());
  std::vector<ObjectMaterial> materials;
  for (size_t i = 0; i < scene.objects.size(); ++i) {
    Status status = LoadObjectMesh(scene, static_cast<int>(i), &meshes[i]);
    if (!status.ok()) return status;
    materials.push_back(scene.objects[i].Materials());
  }
  std::unique_ptr<Tracker> t;
  Status status = Create(meshes, materials, scene.registration, &t);
  if (!status.ok()) return status;
  for (size_t i = 0; i < scene.objects.size(); ++i) {
    status = t->SetObjectLabel(static_cast<int>(i), scene.objects[i].label);
    if (!status.ok()) return status;
  }
  for (size_t i = 0; i < scene.objects.size(); ++i) {
    if (scene.objects[i].surface_path.empty()) continue;
    Vertices vertices;
    Triangles triangles;
    status = LoadObjectSurface(scene, static_cast<int>(i), &vertices, &triangles);
    if (!status.ok()) return Status::Error(scene.path + ": " + status.message());
    status = t->SetEmbeddedSurface(static_cast<int>(i), vertices, triangles);
    if (!status.ok()) return Status::Error(scene.path + ": objects[" + std::to_string(i) + "].surface: " + status.message());
  }
  if (scene.effects.fracture) {
    std::vector<FractureOptions> fracture;
    for (const ObjectSpec& o : scene.objects) {
      FractureOptions f = scene.effects.fracture_options;
      f.toughness = o.toughness;
      f.region_toughness = o.region_toughness;
      fracture.push_back(f);
    }
    status = t->EnableFracture(fracture);
    if (!status.ok()) return Status::Error(scene.path + ": effects.fracture: " + status.message());
  }
  if (scene.effects.collision) {
    std::vector<std::string> names;
    for (const ObjectSpec& o : scene.objects) names.push_back(o.name);
    status = t->EnableCollision(scene.collision, names);
    if (!status.ok()) return Status::Error(scene.path + ": " + status.message());
  }
  for (const AnchorSpec& a : scene.anchors) {
    const int object = ObjectIndex(scene, a.object);
    std::vector<int> vertices;
    status = SelectVertices(a.selection, t->mesh(object).rest, &vertices);
    if (!status.ok()) return status;
    status = t->AddAnchor(a.name, object, vertices, a.hard, a.weight);
    if (!status.ok()) return status;
    if (!a.rotations.empty()) {
      status = t->SetAnchorTrajectory(a.name, a.translations, a.rotations, a.centre);
      if (!status.ok()) return status;
    } else if (!a.translations.empty()) {
      status = t->SetAnchorTrajectory(a.name, a.translations);
      if (!status.ok()) return status;
    }
  }
  // Where estimated forces may act (registration.forces.region): the union of an object's selections.
  {
    std::vector<std::vector<int>> regions(scene.objects.size());
    for (const ForceRegionSpec& r : scene.force_regions) {
      const int object = ObjectIndex(scene, r.object);
      std::vector<int> vertices;
      status = SelectVertices(r.selection, t->mesh(object).rest, &vertices);
      if (!status.ok()) return status;
      regions[object].insert(regions[object].end(), vertices.begin(), vertices.end());
    }
    for (size_t i = 0; i < regions.size(); ++i) {
      if (regions[i].empty()) continue;
      status = t->SetForceRegion(static_cast<int>(i), regions[i]);
      if (!status.ok()) return Status::Error(scene.path + ": registration.forces.region: " + status.message());
    }
  }
  // Clamps hold their vertices where the mesh starts, as simulate holds them at rest: hard
  // anchors named "boundary[i]". Prescribed displacements drive a simulation and are not
  // used here (femreg register refuses them; a support that moves is an anchor with
  // translations).
  for (size_t i = 0; i < scene.boundary_conditions.size(); ++i) {
    const BoundaryConditionSpec& b = scene.boundary_conditions[i];
    if (b.type != BoundaryConditionSpec::Type::kClamp) continue;
    const int object = ObjectIndex(scene, b.object);
    std::vector<int> vertices;
    status = SelectVertices(b.selection, t->mesh(object).rest, &vertices);
    if (status.ok()) {
      status = t->AddAnchor("boundary[" + std::to_string(i) + "]", object, vertices, /*hard=*/true);
    }
    if (!status.ok()) return Status::Error(b.selection.where + ": " + status.message());
  }
  // The scene's gravity and nodal loads, resolved as simulate resolves them.
  if (scene.registration.loads && (scene.gravity.squaredNorm() > 0 || !scene.loads.empty())) {
    for (size_t i = 0; i < scene.objects.size(); ++i) {
      ForwardProblem forward;
      status = BuildForwardProblem(scene, static_cast<int>(i), t->mesh(static_cast<int>(i)), &forward);
      if (status.ok()) status = t->SetExternalLoads(static_cast<int>(i), forward.gravity, forward.nodal_loads);
      if (!status.ok()) return Status::Error(scene.path + ": object '" + scene.objects[i].name + "': " + status.message());
    }
  }
  *tracker = std::move(t);
  return Status::Ok();
}

}  // namespace femreg
