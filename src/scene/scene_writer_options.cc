// Writing scenes, the options' part (scene_writer.cc has the layout and the rest): the forward
// solve's section and the registration's (camera, preprocess, data, weights, forces, solver),
// each option written only where it differs from the default.
#include <string>
#include <vector>

#include "femreg/scene.h"
#include "scene/scene_writer_internal.h"

namespace femreg {
namespace internal {
namespace scene_writer {

YAML::Node ForwardNode(const Scene& scene) {
  YAML::Node n = FlowMap();
  PutFields(n, scene.forward);  // femreg/forward.h's table; a model set is written, even corotational
  return n;
}

YAML::Node RegistrationNode(const RegistrationOptions& r, const std::vector<ForceRegionSpec>& regions,
                            const std::string& base_dir) {
  const RegistrationOptions d;
  YAML::Node n = Map();
  PutFields(n, r);  // regularizer, loads, initial_pose
  if (r.camera.enabled) {
    YAML::Node camera = FlowMap();
    PutFields(camera, r.camera, {}, /*all=*/true);  // a camera is written in full
    n["camera"] = camera;
  }
  const PreprocessOptions& p = r.preprocess;
  YAML::Node preprocess = FlowMap();
  if (!p.mask_dir.empty()) preprocess["mask_dir"] = FilePath(p.mask_dir, base_dir);
  const FieldInfo crop_min = FieldOf<&PreprocessOptions::crop_min>();
  const FieldInfo crop_max = FieldOf<&PreprocessOptions::crop_max>();
  PutFields(preprocess, p, {crop_min.path(), crop_max.path()});
  if (p.crop) {  // the group is the switch
    YAML::Node crop = FlowMap();
    crop[crop_min.key] = Vec(p.crop_min);
    crop[crop_max.key] = Vec(p.crop_max);
    preprocess[crop_min.group] = crop;
  }
  PutMap(n, "preprocess", preprocess);

  YAML::Node data = FlowMap();
  PutFields(data, r.data);
  PutMap(n, "data", data);

  YAML::Node weights = FlowMap();
  // Which of the two is written also selects the weighting: written whenever the weighting
  // differs from the default's, else only when its value does.
  const FieldInfo per_correspondence = FieldOf<&WeightOptions::data>();
  const FieldInfo per_area = FieldOf<&WeightOptions::data_per_area>();
  if (r.weights.data < 0) {
    if (d.weights.data >= 0 || r.weights.data_per_area != d.weights.data_per_area) {
      weights[per_area.key] = Number(r.weights.data_per_area);
    }
  } else if (d.weights.data < 0 || r.weights.data != d.weights.data) {
    weights[per_correspondence.key] = Number(r.weights.data);
  }
  PutFields(weights, r.weights, {per_correspondence.path(), per_area.path()});
  PutMap(n, "weights", weights);

  YAML::Node forces = FlowMap();
  PutFields(forces, r.forces);
  if (!regions.empty()) {
    YAML::Node list(YAML::NodeType::Sequence);
    for (const ForceRegionSpec& region : regions) {
      YAML::Node entry = FlowMap();
      if (!region.object.empty()) entry["object"] = region.object;
      entry["select"] = SelectionNode(region.selection);
      list.push_back(entry);
    }
    forces["region"] = list;
  }
  PutMap(n, "forces", forces);

  YAML::Node free_space = FlowMap();
  PutFields(free_space, r.free_space);
  PutMap(n, "free_space", free_space);

  YAML::Node solver = FlowMap();
  std::vector<std::string> skip;  // Ceres' own settings: refused beside backend: fast
  if (r.solver.backend != SolverBackend::kCeres) {
    skip = {FieldOf<&SolverOptions::trust_region>().path(), FieldOf<&SolverOptions::linear_solver>().path()};
  }
  PutFields(solver, r.solver, skip);
  PutMap(n, "solver", solver);
  return n;
}

}  // namespace scene_writer
}  // namespace internal
}  // namespace femreg
