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
  const ForwardOptions& f = scene.forward;
  const ForwardOptions d;
  YAML::Node n = FlowMap();
  if (scene.forward_model != ElasticModelType::kCorotational || scene.forward_model_chosen) {
    n["model"] = ToString(scene.forward_model);
  }
  Put(n, "max_iterations", f.max_iterations, d.max_iterations);
  Put(n, "load_steps", f.load_steps, d.load_steps);
  Put(n, "tolerance", f.relative_tolerance, d.relative_tolerance);
  Put(n, "absolute_tolerance", f.absolute_tolerance, d.absolute_tolerance);
  return n;
}

YAML::Node RegistrationNode(const RegistrationOptions& r, const std::vector<ForceRegionSpec>& regions,
                            const std::string& base_dir) {
  const RegistrationOptions d;
  YAML::Node n = Map();
  if (r.regularizer != d.regularizer) n["regularizer"] = ToString(r.regularizer);
  if (r.loads != d.loads) n["loads"] = r.loads;
  if (r.initial_pose != d.initial_pose) n["initial_pose"] = ToString(r.initial_pose);
  if (r.camera.enabled) {
    const CameraOptions& c = r.camera;
    YAML::Node camera = FlowMap();
    camera["position"] = Vec(c.position);
    camera["target"] = Vec(c.target);
    camera["up"] = Vec(c.up);
    camera["fx"] = Number(c.fx);
    camera["fy"] = Number(c.fy);
    camera["cx"] = Number(c.cx);
    camera["cy"] = Number(c.cy);
    camera["width"] = c.width;
    camera["height"] = c.height;
    n["camera"] = camera;
  }
  const PreprocessOptions& p = r.preprocess;
  YAML::Node preprocess = FlowMap();
  if (!p.mask_dir.empty()) preprocess["mask_dir"] = FilePath(p.mask_dir, base_dir);
  Put(preprocess, "scale", p.scale, d.preprocess.scale);
  if (!p.translation.isZero(0) || !p.rotation.isZero(0)) {
    YAML::Node transform = FlowMap();
    transform["translation"] = Vec(p.translation);
    transform["rotation"] = Vec(p.rotation);
    preprocess["transform"] = transform;
  }
  if (p.crop) {
    YAML::Node crop = FlowMap();
    crop["min"] = Vec(p.crop_min);
    crop["max"] = Vec(p.crop_max);
    preprocess["crop"] = crop;
  }
  if (p.plane_distance != d.preprocess.plane_distance ||
      p.plane_iterations != d.preprocess.plane_iterations) {
    YAML::Node plane = FlowMap();
    plane["distance"] = Number(p.plane_distance);
    Put(plane, "iterations", p.plane_iterations, d.preprocess.plane_iterations);
    preprocess["plane"] = plane;
  }
  Put(preprocess, "voxel_size", p.voxel_size, d.preprocess.voxel_size);
  Put(preprocess, "auto_voxel", p.auto_voxel, d.preprocess.auto_voxel);
  Put(preprocess, "auto_voxel_min_ratio", p.auto_voxel_min_ratio, d.preprocess.auto_voxel_min_ratio);
  YAML::Node outliers = FlowMap();
  Put(outliers, "neighbors", p.outlier_neighbors, d.preprocess.outlier_neighbors);
  Put(outliers, "stddev", p.outlier_stddev, d.preprocess.outlier_stddev);
  PutMap(preprocess, "outliers", outliers);
  YAML::Node normals = FlowMap();
  Put(normals, "neighbors", p.normal_neighbors, d.preprocess.normal_neighbors);
  PutMap(preprocess, "normals", normals);
  PutMap(n, "preprocess", preprocess);

  const DataTermOptions& a = r.data;
  YAML::Node data = FlowMap();
  Put(data, "model_to_cloud", a.model_to_cloud, d.data.model_to_cloud);
  Put(data, "cloud_to_model", a.cloud_to_model, d.data.cloud_to_model);
  Put(data, "max_distance", a.max_distance, d.data.max_distance);
  if (a.loss != d.data.loss) data["loss"] = ToString(a.loss);
  Put(data, "loss_scale", a.loss_scale, d.data.loss_scale);
  if (a.metric != d.data.metric) data["metric"] = ToString(a.metric);
  Put(data, "visibility", a.visibility, d.data.visibility);
  Put(data, "cloud_stride", a.cloud_stride, d.data.cloud_stride);
  Put(data, "auto_visibility", a.auto_visibility, d.data.auto_visibility);
  Put(data, "reciprocity", a.reciprocity, d.data.reciprocity);
  Put(data, "hold_pairs_after", a.hold_pairs_after, d.data.hold_pairs_after);
  Put(data, "occluders", a.occluders, d.data.occluders);
  Put(data, "occluder_margin", a.occluder_margin, d.data.occluder_margin);
  Put(data, "max_strain_step", a.max_strain_step, d.data.max_strain_step);
  Put(data, "min_points", a.min_points, d.data.min_points);
  Put(data, "min_points_per_surface_vertex", a.min_points_per_surface_vertex,
      d.data.min_points_per_surface_vertex);
  Put(data, "lost_coverage", a.lost_coverage, d.data.lost_coverage);
  PutMap(n, "data", data);

  YAML::Node weights = FlowMap();
  // Which of the two is written also selects the weighting: written whenever the weighting
  // differs from the default's, else only when its value does.
  if (r.weights.data < 0) {
    if (d.weights.data >= 0 || r.weights.data_per_area != d.weights.data_per_area) {
      weights["data_per_area"] = Number(r.weights.data_per_area);
    }
  } else if (d.weights.data < 0 || r.weights.data != d.weights.data) {
    weights["data"] = Number(r.weights.data);
  }
  Put(weights, "model_to_cloud_share", r.weights.model_to_cloud_share, d.weights.model_to_cloud_share);
  Put(weights, "model_to_cloud_area_cap", r.weights.model_to_cloud_area_cap,
      d.weights.model_to_cloud_area_cap);
  Put(weights, "model_to_cloud_balance", r.weights.model_to_cloud_balance,
      d.weights.model_to_cloud_balance);
  Put(weights, "elastic", r.weights.elastic, d.weights.elastic);
  Put(weights, "barrier", r.weights.barrier, d.weights.barrier);
  Put(weights, "barrier_volume", r.weights.barrier_volume, d.weights.barrier_volume);
  Put(weights, "temporal", r.weights.temporal, d.weights.temporal);
  Put(weights, "anchor", r.weights.anchor, d.weights.anchor);
  PutMap(n, "weights", weights);

  YAML::Node forces = FlowMap();
  Put(forces, "estimate", r.forces.estimate, d.forces.estimate);
  Put(forces, "weight", r.forces.weight, d.forces.weight);
  Put(forces, "sparsity", r.forces.sparsity, d.forces.sparsity);
  Put(forces, "pushing_only", r.forces.pushing_only, d.forces.pushing_only);
  Put(forces, "friction", r.forces.friction, d.forces.friction);
  Put(forces, "balance", r.forces.balance, d.forces.balance);
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
  Put(free_space, "enabled", r.free_space.enabled, d.free_space.enabled);
  Put(free_space, "tolerance", r.free_space.tolerance, d.free_space.tolerance);
  Put(free_space, "weight", r.free_space.weight, d.free_space.weight);
  PutMap(n, "free_space", free_space);

  const SolverOptions& s = r.solver;
  YAML::Node solver = FlowMap();
  if (s.backend != d.solver.backend) solver["backend"] = ToString(s.backend);
  Put(solver, "max_outer_iterations", s.max_outer_iterations, d.solver.max_outer_iterations);
  Put(solver, "max_inner_iterations", s.max_inner_iterations, d.solver.max_inner_iterations);
  Put(solver, "relative_energy_tolerance", s.relative_energy_tolerance,
      d.solver.relative_energy_tolerance);
  Put(solver, "inner_tolerance", s.inner_tolerance, d.solver.inner_tolerance);
  Put(solver, "step_tolerance", s.step_tolerance, d.solver.step_tolerance);
  Put(solver, "bulk_step_tolerance", s.bulk_step_tolerance, d.solver.bulk_step_tolerance);
  Put(solver, "max_pcg_iterations", s.max_pcg_iterations, d.solver.max_pcg_iterations);
  if (s.preconditioner != d.solver.preconditioner) solver["preconditioner"] = ToString(s.preconditioner);
  Put(solver, "time_budget_s", s.time_budget_s, d.solver.time_budget_s);
  if (s.backend == SolverBackend::kCeres) {  // Ceres' own settings (refused beside backend: fast)
    if (s.trust_region != d.solver.trust_region) solver["trust_region"] = ToString(s.trust_region);
    if (s.linear_solver != d.solver.linear_solver) solver["linear_solver"] = ToString(s.linear_solver);
  }
  Put(solver, "threads", s.num_threads, d.solver.num_threads);
  Put(solver, "predict_motion", s.predict_motion, d.solver.predict_motion);
  Put(solver, "backtrack", s.backtrack, d.solver.backtrack);
  Put(solver, "rigid_prealign", s.rigid_prealign, d.solver.rigid_prealign);
  Put(solver, "rigid_iterations", s.rigid_iterations, d.solver.rigid_iterations);
  PutMap(n, "solver", solver);
  return n;
}

}  // namespace scene_writer
}  // namespace internal
}  // namespace femreg
