#include "results/provenance.h"

#include <cmath>
#include <filesystem>

#include "femreg/point_cloud.h"
#include "femreg/version.h"

namespace femreg {
namespace results_internal {
namespace {

using json = nlohmann::ordered_json;

// JSON has no infinity or NaN: those become null (the crop box's open sides are +-1e30).
json Number(double v) { return std::isfinite(v) ? json(v) : json(nullptr); }
json Vector(const Eigen::Vector3d& v) { return json::array({Number(v.x()), Number(v.y()), Number(v.z())}); }

std::string Absolute(const std::string& path) {
  std::error_code ec;
  const std::filesystem::path p = std::filesystem::absolute(path, ec);
  return ec ? path : p.lexically_normal().string();
}

}  // namespace

json RegistrationOptionsJson(const RegistrationOptions& o) {
  json j;
  j["regularizer"] = ToString(o.regularizer);
  const CameraOptions& c = o.camera;
  j["camera"] = {{"enabled", c.enabled},  {"position", Vector(c.position)},
                 {"target", Vector(c.target)}, {"up", Vector(c.up)},
                 {"fx", c.fx}, {"fy", c.fy}, {"cx", c.cx}, {"cy", c.cy},
                 {"width", c.width}, {"height", c.height}};
  const PreprocessOptions& p = o.preprocess;
  j["preprocess"] = {{"mask_dir", p.mask_dir.empty() ? json(nullptr) : json(Absolute(p.mask_dir))},
                     {"crop", p.crop},
                     {"crop_min", Vector(p.crop_min)},
                     {"crop_max", Vector(p.crop_max)},
                     {"voxel_size", p.voxel_size},
                     {"outlier_neighbors", p.outlier_neighbors},
                     {"outlier_stddev", p.outlier_stddev},
                     {"normal_neighbors", p.normal_neighbors},
                     {"plane_distance", p.plane_distance},
                     {"plane_iterations", p.plane_iterations}};
  const DataTermOptions& d = o.data;
  j["data"] = {{"model_to_cloud", d.model_to_cloud}, {"cloud_to_model", d.cloud_to_model},
               {"max_distance", d.max_distance},     {"loss", ToString(d.loss)},
               {"loss_scale", d.loss_scale},         {"metric", ToString(d.metric)},
               {"visibility", d.visibility},         {"cloud_stride", d.cloud_stride}};
  const WeightOptions& w = o.weights;
  j["weights"] = {{"data", w.data}, {"elastic", w.elastic}, {"temporal", w.temporal},
                  {"anchor", w.anchor}, {"data_per_area", w.data_per_area},
                  {"model_to_cloud_share", w.model_to_cloud_share},
                  {"model_to_cloud_area_cap", w.model_to_cloud_area_cap},
                  {"model_to_cloud_balance", w.model_to_cloud_balance}};
  j["loads"] = o.loads;
  j["initial_pose"] = ToString(o.initial_pose);
  const SolverOptions& s = o.solver;
  j["solver"] = {{"backend", ToString(s.backend)},
                 {"max_outer_iterations", s.max_outer_iterations},
                 {"max_inner_iterations", s.max_inner_iterations},
                 {"inner_tolerance", s.inner_tolerance},
                 {"relative_energy_tolerance", s.relative_energy_tolerance},
                 {"step_tolerance", s.step_tolerance},
                 {"bulk_step_tolerance", s.bulk_step_tolerance},
                 {"time_budget_s", s.time_budget_s},
                 {"trust_region", ToString(s.trust_region)},
                 {"linear_solver", ToString(s.linear_solver)},
                 {"max_pcg_iterations", s.max_pcg_iterations},
                 {"preconditioner", ToString(s.preconditioner)},
                 {"threads", s.num_threads},
                 {"predict_motion", s.predict_motion},
                 {"backtrack", s.backtrack},
                 {"rigid_prealign", s.rigid_prealign},
                 {"rigid_iterations", s.rigid_iterations}};
  return j;
}

json ProvenanceJson(const Scene& scene, const RegistrationOptions& options,
                    const std::vector<std::string>& overrides,
                    const std::vector<std::string>& frame_files,
                    const std::vector<std::string>& truth_files) {
  json j;
  j["femreg_version"] = Version();
  j["scene_file"] = Absolute(scene.path);
  j["overrides"] = overrides;
  j["scene_resolved"] = SceneToYaml(scene);
  j["options"] = RegistrationOptionsJson(options);
  json objects = json::array();
  for (const ObjectSpec& o : scene.objects) {
    objects.push_back({{"name", o.name},
                       {"mesh", o.mesh_path.empty() ? json(nullptr) : json(Absolute(o.mesh_path))}});
  }
  j["object_meshes"] = objects;
  json frames = json::array();
  for (const std::string& f : frame_files) frames.push_back(Absolute(f));
  j["frame_files"] = frames;
  // The depth frames' masks (--mask-dir or registration.preprocess.mask_dir): the folder and
  // each frame's mask, in the frames' order; null without masks.
  const std::string& mask_dir = options.preprocess.mask_dir;
  j["mask_dir"] = mask_dir.empty() ? json(nullptr) : json(Absolute(mask_dir));
  json masks = json::array();
  for (const std::string& f : frame_files) {
    if (mask_dir.empty()) break;
    masks.push_back(Absolute(MaskPathFor(mask_dir, f)));
  }
  j["mask_files"] = mask_dir.empty() ? json(nullptr) : masks;
  json truth = json::array();
  for (size_t i = 0; i < truth_files.size() && i < frame_files.size(); ++i) {
    truth.push_back(Absolute(truth_files[i]));  // the frames' own: a folder may hold more
  }
  j["ground_truth_files"] = truth;
  return j;
}

}  // namespace results_internal
}  // namespace femreg
