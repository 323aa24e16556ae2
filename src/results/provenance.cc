#include "results/provenance.h"

#include <cmath>
#include <filesystem>
#include <type_traits>

#include "femreg/blas_kernels.h"
#include "femreg/option_fields.h"
#include "femreg/point_cloud.h"
#include "femreg/version.h"

namespace femreg {
namespace results_internal {
namespace {

using json = nlohmann::ordered_json;

std::string Absolute(const std::string& path) {
  std::error_code ec;
  const std::filesystem::path p = std::filesystem::absolute(path, ec);
  return ec ? path : p.lexically_normal().string();
}

// A list's entries: what names each (`head`), then its table's fields.
template <class Entry, class Head>
json EntriesJson(const std::vector<Entry>& entries, Head head) {
  json list = json::array();
  for (const Entry& e : entries) {
    json j = head(e);
    j.update(FieldsJson(e));
    list.push_back(j);
  }
  return list;
}
template <class Entry>
json Named(const std::vector<Entry>& entries) {
  return EntriesJson(entries, [](const Entry& e) { return json{{"name", e.name}}; });
}

}  // namespace

json MaterialJson(const Material& material) { return FieldsJson(material); }

json RegistrationOptionsJson(const RegistrationOptions& o) {
  json j = FieldsJson(o);  // regularizer, loads, initial_pose
  j["camera"] = {{"enabled", o.camera.enabled}};
  j["camera"].update(FieldsJson(o.camera));
  const PreprocessOptions& p = o.preprocess;
  j["preprocess"] = {{"mask_dir", p.mask_dir.empty() ? json(nullptr) : json(Absolute(p.mask_dir))},
                     {"crop", p.crop}};
  j["preprocess"].update(FieldsJson(p));
  j["data"] = FieldsJson(o.data);
  j["weights"] = FieldsJson(o.weights);
  j["solver"] = FieldsJson(o.solver);
  j["forces"] = FieldsJson(o.forces);
  j["free_space"] = FieldsJson(o.free_space);
  return j;
}

json SceneOptionsJson(const Scene& scene) {
  json j;
  j["forward"] = FieldsJson(scene.forward);
  j["effects"] = {{"fracture", {{"enabled", scene.effects.fracture}}}, {"collision", scene.effects.collision}};
  j["effects"]["fracture"].update(FieldsJson(scene.effects.fracture_options));
  j["collision"] = FieldsJson(scene.collision);
  j["collision"]["pairs"] = EntriesJson(scene.collision.pairs, [](const CollisionPair& p) {
    return json{{"objects", {p.first, p.second}}};
  });
  j["collision"]["obstacles"] = Named(scene.collision.obstacles);
  json materials = json::array();
  for (const ObjectSpec& o : scene.objects) materials.push_back(MaterialJson(o.material));
  j["materials"] = materials;
  j["objects"] = Named(scene.objects);
  j["anchors"] = Named(scene.anchors);
  if (scene.synth.enabled) {
    j["synth"] = FieldsJson(scene.synth);
    j["synth"]["sensor"] = FieldsJson(scene.synth.sensor);
    j["synth"]["motion"] = Named(scene.synth.motion);
    j["synth"]["bodies"] = Named(scene.synth.bodies);
  } else {
    j["synth"] = nullptr;
  }
  return j;
}

json ProvenanceJson(const Scene& scene, const RegistrationOptions& options,
                    const std::vector<std::string>& overrides,
                    const std::vector<std::string>& frame_files,
                    const std::vector<std::string>& truth_files) {
  json j;
  j["femreg_version"] = Version();
  // The BLAS kernels round the float factor differently: a result's last digits depend on them.
  j["blas_kernels"] = BlasCoreName();
  j["scene_file"] = Absolute(scene.path);
  j["overrides"] = overrides;
  j["scene_resolved"] = SceneToYaml(scene);
  j["options"] = RegistrationOptionsJson(options);
  j["scene_options"] = SceneOptionsJson(scene);
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
