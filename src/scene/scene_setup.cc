// From a parsed scene to meshes and forward problems: selections, posed meshes, loads, and
// the motion script's keyframes.
#include <Eigen/Geometry>
#include <algorithm>
#include <map>
#include <sstream>

#include "femreg/geometry.h"
#include "femreg/io.h"
#include "femreg/meshing.h"
#include "femreg/scene.h"

namespace femreg {
namespace {

std::string VectorString(const Eigen::Vector3d& v) {
  std::ostringstream os;
  os << "[" << v.x() << ", " << v.y() << ", " << v.z() << "]";
  return os.str();
}

std::string Where(const VertexSelection& selection) {
  return selection.where.empty() ? std::string("selection") : selection.where;
}

// "scene.yaml: objects[0] (beam)"
std::string ObjectLabel(const Scene& scene, int object) {
  std::ostringstream os;
  os << (scene.path.empty() ? std::string("scene") : scene.path) << ": objects[" << object
     << "] (" << scene.objects[object].name << ")";
  return os.str();
}

}  // namespace

Status SelectVertices(const VertexSelection& selection, const Vertices& positions,
                      std::vector<int>* vertices) {
  vertices->clear();
  const int n = static_cast<int>(positions.rows());
  const double tol = selection.tolerance;
  switch (selection.kind) {
    case VertexSelection::Kind::kAll:
      for (int i = 0; i < n; ++i) vertices->push_back(i);
      break;
    case VertexSelection::Kind::kBox:
      for (int i = 0; i < n; ++i) {
        const Eigen::Vector3d p = positions.row(i).transpose();
        if ((p.array() >= selection.box_min.array() - tol).all() &&
            (p.array() <= selection.box_max.array() + tol).all()) {
          vertices->push_back(i);
        }
      }
      break;
    case VertexSelection::Kind::kPlane: {
      const double norm = selection.plane_normal.norm();
      if (!(norm > 0)) return Status::Error(Where(selection) + ": the plane normal is zero");
      const Eigen::Vector3d normal = selection.plane_normal / norm;
      for (int i = 0; i < n; ++i) {
        const Eigen::Vector3d p = positions.row(i).transpose();
        if ((p - selection.plane_point).dot(normal) >= -tol) vertices->push_back(i);
      }
      break;
    }
    case VertexSelection::Kind::kIndices:
      for (int index : selection.indices) {
        if (index < 0 || index >= n) {
          return Status::Error(Where(selection) + ": vertex index " + std::to_string(index) +
                               " is out of range (the mesh has " + std::to_string(n) +
                               " vertices)");
        }
        vertices->push_back(index);
      }
      std::sort(vertices->begin(), vertices->end());
      vertices->erase(std::unique(vertices->begin(), vertices->end()), vertices->end());
      break;
  }
  if (vertices->empty()) {
    std::ostringstream os;
    os << Where(selection) << ": the selection picks no vertex";
    if (n > 0) {
      os << " (the mesh spans " << VectorString(positions.colwise().minCoeff().transpose())
         << " to " << VectorString(positions.colwise().maxCoeff().transpose()) << ")";
    } else {
      os << " (the mesh has no vertices)";
    }
    return Status::Error(os.str());
  }
  return Status::Ok();
}

Status LoadObjectSurface(const Scene& scene, int object, Vertices* vertices, Triangles* triangles) {
  if (object < 0 || object >= static_cast<int>(scene.objects.size())) {
    return Status::Error("scene has no object " + std::to_string(object));
  }
  const ObjectSpec& spec = scene.objects[static_cast<size_t>(object)];
  vertices->resize(0, 3);
  triangles->resize(0, 3);
  if (spec.surface_path.empty()) return Status::Ok();
  const Status status = ReadSurface(spec.surface_path, vertices, triangles);
  if (!status.ok()) return Status::Error(ObjectLabel(scene, object) + ".surface: " + status.message());
  const Eigen::Matrix3d A = spec.scale * RotationFromVector(spec.rotation);
  for (Eigen::Index i = 0; i < vertices->rows(); ++i) {
    vertices->row(i) = (A * vertices->row(i).transpose() + spec.translation).transpose();
  }
  return Status::Ok();
}

Status LoadObjectMesh(const Scene& scene, int object, TetMesh* mesh) {
  if (object < 0 || object >= static_cast<int>(scene.objects.size())) {
    return Status::Error("scene has no object " + std::to_string(object));
  }
  const ObjectSpec& spec = scene.objects[object];
  const MeshGeneratorSpec& gen = spec.generate;
  switch (gen.shape) {
    case MeshGeneratorSpec::Shape::kNone: {
      const Status status = ReadTetMesh(spec.mesh_path, mesh);
      if (!status.ok()) return Status::Error(ObjectLabel(scene, object) + ": " + status.message());
      break;
    }
    case MeshGeneratorSpec::Shape::kBox:
      *mesh = MakeBox(gen.size, gen.cells.x(), gen.cells.y(), gen.cells.z(), gen.origin);
      break;
    case MeshGeneratorSpec::Shape::kCylinder:
      *mesh = MakeCylinder(gen.radius, gen.length, gen.radial_cells, gen.axial_cells);
      break;
    case MeshGeneratorSpec::Shape::kSphere:
      *mesh = MakeSphere(gen.radius, gen.radial_cells);
      break;
  }
  if (mesh->num_tets() == 0) {
    return Status::Error(ObjectLabel(scene, object) + ": the mesh has no tetrahedra");
  }

  // x = R * scale * X_file + t. A rotation and a positive scale keep the orientation of
  // every element, so the surface and adjacency stay valid.
  const Eigen::Matrix3d A = spec.scale * RotationFromVector(spec.rotation);
  for (int i = 0; i < mesh->num_vertices(); ++i) {
    mesh->rest.row(i) = (A * mesh->rest.row(i).transpose() + spec.translation).transpose();
  }
  mesh->x = mesh->rest;

  std::vector<std::pair<int, double>> density_per_region;
  for (const auto& [region, material] : spec.region_materials) {
    density_per_region.emplace_back(region, material.density);
  }
  ComputeLumpedMasses(mesh, spec.material.density, density_per_region);
  return Status::Ok();
}

Status BuildForwardProblem(const Scene& scene, int object, const TetMesh& mesh,
                           ForwardProblem* problem) {
  if (object < 0 || object >= static_cast<int>(scene.objects.size())) {
    return Status::Error("scene has no object " + std::to_string(object));
  }
  const std::string& name = scene.objects[object].name;
  const bool single = scene.objects.size() == 1;
  auto applies = [&](const std::string& target) {
    return target == name || (target.empty() && single);
  };

  *problem = ForwardProblem();
  problem->gravity = scene.gravity;

  // Which boundary entry claimed each vertex first, to name both in a conflict.
  std::map<int, int> claimed_by;
  std::map<int, Eigen::Vector3d> displacement_of;
  const int num_bcs = static_cast<int>(scene.boundary_conditions.size());
  for (int b = 0; b < num_bcs; ++b) {
    const BoundaryConditionSpec& bc = scene.boundary_conditions[b];
    if (!applies(bc.object)) continue;
    std::vector<int> vertices;
    Status status = SelectVertices(bc.selection, mesh.rest, &vertices);
    if (!status.ok()) return status;
    const Eigen::Vector3d u = bc.type == BoundaryConditionSpec::Type::kClamp
                                  ? Eigen::Vector3d::Zero()
                                  : bc.displacement;
    for (int v : vertices) {
      auto inserted = claimed_by.emplace(v, b);
      if (inserted.second) {
        displacement_of[v] = u;
        continue;
      }
      const BoundaryConditionSpec& other = scene.boundary_conditions[inserted.first->second];
      const bool same_kind = other.type == bc.type;
      if (same_kind && (displacement_of[v] - u).norm() == 0) continue;  // agreeing overlap
      auto describe = [](const BoundaryConditionSpec& c, const Eigen::Vector3d& d) {
        return c.type == BoundaryConditionSpec::Type::kClamp ? std::string("clamped")
                                                             : "displaced by " + VectorString(d);
      };
      std::ostringstream os;
      os << Where(bc.selection) << ": vertex " << v << " at "
         << VectorString(mesh.rest.row(v).transpose()) << " is " << describe(other, displacement_of[v])
         << " by " << Where(other.selection) << " and " << describe(bc, u) << " by "
         << Where(bc.selection) << "; a vertex takes one boundary condition";
      return Status::Error(os.str());
    }
  }
  for (const auto& [v, b] : claimed_by) {
    if (scene.boundary_conditions[b].type == BoundaryConditionSpec::Type::kClamp) {
      problem->clamped.push_back(v);
    } else {
      problem->prescribed.emplace_back(v, displacement_of[v]);
    }
  }

  std::map<int, Eigen::Vector3d> loads;
  for (const LoadSpec& load : scene.loads) {
    if (!applies(load.object)) continue;
    std::vector<int> vertices;
    Status status = SelectVertices(load.selection, mesh.rest, &vertices);
    if (!status.ok()) return status;
    const Eigen::Vector3d share = load.force / static_cast<double>(vertices.size());
    for (int v : vertices) {
      auto it = loads.emplace(v, Eigen::Vector3d::Zero()).first;
      it->second += share;
    }
  }
  for (const auto& [v, f] : loads) problem->nodal_loads.emplace_back(v, f);
  return Status::Ok();
}

Status CopyMaterials(const Scene& from, Scene* scene) {
  for (ObjectSpec& o : scene->objects) {
    const auto it = std::find_if(from.objects.begin(), from.objects.end(),
                                 [&](const ObjectSpec& f) { return f.name == o.name; });
    if (it == from.objects.end()) {
      return Status::Error(from.path + ": no object named '" + o.name + "' (the scene " + scene->path + " has it)");
    }
    o.material = it->material;
    o.region_materials = it->region_materials;
    o.model = it->model;
    o.volume = it->volume;
  }
  return Status::Ok();
}

std::vector<std::string> ChooseForwardElements(Scene* scene) {
  std::vector<std::string> lines;
  if (scene->forward.model) return lines;  // forward.model chosen: every object keeps it
  for (ObjectSpec& o : scene->objects) {
    if (o.ElementChosen()) continue;  // by the file, or by a call before: no second line
    double nu = o.material.poisson_ratio;
    for (const auto& r : o.region_materials) nu = std::max(nu, r.second.poisson_ratio);
    if (nu < kNearlyIncompressibleNu) continue;
    o.model = MaterialModel::kNeoHookean;
    o.volume = MaterialVolume::kNodal;
    std::ostringstream line;
    line << o.name << ": nu " << nu << " >= " << kNearlyIncompressibleNu
         << " (nearly incompressible), where linear tetrahedra lock: using the neo-Hookean "
            "element with nodal volume (material: {model: neo_hookean, volume: nodal}); "
            "write material.model: hooke to keep the linear element";
    lines.push_back(line.str());
  }
  return lines;
}

std::vector<std::string> ChooseRegistrationElements(Scene* scene) {
  std::vector<std::string> lines;
  if (scene->registration.regularizer != Regularizer::kCorotational) return lines;
  for (ObjectSpec& o : scene->objects) {
    if (o.ElementChosen()) continue;
    double nu = o.material.poisson_ratio;
    for (const auto& r : o.region_materials) nu = std::max(nu, r.second.poisson_ratio);
    if (nu < kNearlyIncompressibleNu) continue;
    o.model = MaterialModel::kNeoHookean;  // chosen: a second call changes nothing
    o.volume.reset();  // element volumes
    std::ostringstream line;
    line << o.name << ": nu " << nu << " >= " << kNearlyIncompressibleNu
         << " (nearly incompressible), where linear tetrahedra lock: registering with the "
            "neo-Hookean element and nu ";
    if (scene->registration.forces.estimate) {
      // The estimated forces are the elements' own: a softer nu would shrink them
      // (docs/notes/2026-11-29-forces-and-the-element.md).
      line << "as given (forces are estimated); write material.model: hooke to use the linear element";
      lines.push_back(line.str());
      continue;
    }
    const double cap = kRegistrationPoissonRatio;
    o.material.poisson_ratio = std::min(o.material.poisson_ratio, cap);
    for (auto& r : o.region_materials) {
      r.second.poisson_ratio = std::min(r.second.poisson_ratio, cap);
    }
    line << cap << " in its elastic term; write material.model: hooke or neo_hookean to use "
            "the element and nu as given";
    lines.push_back(line.str());
  }
  return lines;
}

void InterpolateKeyframes(const std::vector<MotionKeyframe>& keyframes, int frame,
                          Eigen::Vector3d* translation, Eigen::Vector3d* rotation) {
  translation->setZero();
  rotation->setZero();
  if (keyframes.empty()) return;
  if (frame <= keyframes.front().frame) {
    *translation = keyframes.front().translation;
    *rotation = keyframes.front().rotation;
    return;
  }
  for (size_t k = 1; k < keyframes.size(); ++k) {
    const MotionKeyframe& a = keyframes[k - 1];
    const MotionKeyframe& b = keyframes[k];
    if (frame <= b.frame) {
      const double s = static_cast<double>(frame - a.frame) / (b.frame - a.frame);
      *translation = (1 - s) * a.translation + s * b.translation;
      *rotation = (1 - s) * a.rotation + s * b.rotation;
      return;
    }
  }
  *translation = keyframes.back().translation;
  *rotation = keyframes.back().rotation;
}

}  // namespace femreg
