// Scene section: registration (regularizer, camera, preprocessing, data term, weights,
// solver); range checks through RegistrationOptions::IsValid.
#include <filesystem>
#include <iterator>
#include <string>
#include <vector>

#include "femreg/point_cloud.h"
#include "scene/scene_parser.h"

namespace femreg {
namespace scene_internal {

void SceneParser::ParseRegistration(const YamlValue& v) {
  v.CheckKeys(FieldKeys<RegistrationOptions>(
      {"camera", "preprocess", "data", "weights", "solver", "forces", "free_space"}));
  RegistrationOptions& r = scene_->registration;
  ParseFields(v, &r);
  if (v.Has("free_space")) {
    const YamlValue f = v["free_space"];
    f.CheckKeys(FieldKeys<FreeSpaceOptions>());
    ParseFields(f, &r.free_space);
  }
  if (v.Has("forces")) {
    const YamlValue f = v["forces"];
    f.CheckKeys(FieldKeys<ForceOptions>({"region"}));
    ParseFields(f, &r.forces);
    if (f.Has("region")) ParseForceRegion(f["region"]);
  }
  if (v.Has("camera")) {
    const YamlValue c = v["camera"];
    c.CheckKeys(FieldKeys<CameraOptions>({"intrinsics"}));
    r.camera.enabled = true;
    if (c.Has("intrinsics")) {
      // An intrinsics file, relative to the scene's folder: Open3D's PinholeCameraIntrinsic
      // JSON sets fx..height, a matrix as text (DeepDeform's intrinsics.txt) fx..cy and leaves
      // the image size to width and height beside it. Never a key the file sets beside it
      // (which would win is a guess).
      const YamlValue file = c["intrinsics"];
      std::filesystem::path path(file.AsString());
      if (path.empty()) {
        file.Fail("must name an intrinsics file (Open3D's PinholeCameraIntrinsic JSON, or the camera matrix as text)");
      }
      if (path.is_relative() && !base_dir_.empty()) path = std::filesystem::path(base_dir_) / path;
      const std::string resolved = path.lexically_normal().string();
      std::error_code missing;
      if (!std::filesystem::is_regular_file(resolved, missing)) file.Fail(resolved + ": cannot open: no such file");
      const bool json_file = LooksLikeJsonFile(resolved);
      std::vector<FieldInfo> set_by_file = {FieldOf<&CameraOptions::fx>(), FieldOf<&CameraOptions::fy>(),
                                            FieldOf<&CameraOptions::cx>(), FieldOf<&CameraOptions::cy>()};
      const FieldInfo size_fields[] = {FieldOf<&CameraOptions::width>(), FieldOf<&CameraOptions::height>()};
      if (json_file) set_by_file.insert(set_by_file.end(), std::begin(size_fields), std::end(size_fields));
      std::string keys;
      for (const FieldInfo& f : set_by_file) keys += (keys.empty() ? "" : ", ") + std::string(f.key);
      for (const FieldInfo& f : set_by_file) {
        if (c.Has(f.key)) {
          c[f.key].Fail("given beside camera.intrinsics, which sets it: give the intrinsics either in the file or as " +
                        keys);
        }
      }
      if (!json_file) {
        for (const FieldInfo& f : size_fields) {
          if (!c.Has(f.key)) {
            file.Fail(resolved + " is a camera matrix (not Open3D's JSON), which holds no image size: give " +
                      "camera.width and camera.height beside it (the depth images' size)");
          }
        }
      }
      const Status read = ReadCameraIntrinsics(resolved, &r.camera);
      if (!read.ok()) file.Fail(read.message());
    }
    ParseFields(c, &r.camera);
  }
  if (v.Has("preprocess")) {
    const YamlValue p = v["preprocess"];
    p.CheckKeys(FieldKeys<PreprocessOptions>({"mask_dir"}));
    if (p.Has("mask_dir")) {
      // Depth-image frames' masks (mask_dir/<frame name>.png), relative to the scene's folder
      // like mesh files. Whether it exists is the frame reader's concern: the scene may be
      // used with cloud frames or its masks made later.
      const YamlValue m = p["mask_dir"];
      std::filesystem::path path(m.AsString());
      if (path.empty()) m.Fail("must name a folder (leave the key out for no masks)");
      if (path.is_relative() && !base_dir_.empty()) path = std::filesystem::path(base_dir_) / path;
      r.preprocess.mask_dir = path.lexically_normal().string();
    }
    // A scene crops by giving the box, and removes a plane by giving its distance.
    const std::string crop = FieldOf<&PreprocessOptions::crop_min>().group;
    const std::string plane = FieldOf<&PreprocessOptions::plane_distance>().group;
    if (p.Has(crop) && (!HasField<&PreprocessOptions::crop_min>(p) || !HasField<&PreprocessOptions::crop_max>(p))) {
      p[crop].Fail("needs 'min' and 'max'");
    }
    if (p.Has(plane) && !HasField<&PreprocessOptions::plane_distance>(p)) p[plane].Fail("needs 'distance' (m)");
    r.preprocess.crop = p.Has(crop);
    ParseFields(p, &r.preprocess);
  }
  if (v.Has("data")) {
    const YamlValue d = v["data"];
    d.CheckKeys(FieldKeys<DataTermOptions>());
    DataTermOptions& o = r.data;
    ParseFields(d, &o);
    if (!HasField<&DataTermOptions::auto_visibility>(d) && HasField<&DataTermOptions::visibility>(d) && !o.visibility) {
      // `visibility: false` written out means every surface vertex pulls: without this, a
      // scene with a camera would still get the camera's test from auto_visibility.
      o.auto_visibility = false;
    }
  }
  if (v.Has("weights")) {
    const YamlValue w = v["weights"];
    w.CheckKeys(FieldKeys<WeightOptions>());
    const bool per_correspondence = HasField<&WeightOptions::data>(w);
    const bool per_area = HasField<&WeightOptions::data_per_area>(w);
    if (per_correspondence && per_area) {
      FieldValue<&WeightOptions::data>(w)
          .Fail("set data (legacy: N/m per correspondence, so the fit changes with the "
                "cloud's density) or data_per_area (N/m^3, per unit observed area), not both");
    }
    ParseFields(w, &r.weights);
    if (per_correspondence && !(r.weights.data >= 0)) {
      FieldValue<&WeightOptions::data>(w).Fail("must be >= 0 (N/m per correspondence)");
    }
    if (per_area) r.weights.data = -1.0;  // per unit area instead of per correspondence
  }
  if (v.Has("solver")) {
    const YamlValue s = v["solver"];
    s.CheckKeys(FieldKeys<SolverOptions>());
    SolverOptions& o = r.solver;
    ParseFields(s, &o);
    const FieldInfo ceres_only[] = {FieldOf<&SolverOptions::trust_region>(), FieldOf<&SolverOptions::linear_solver>()};
    if (!HasField<&SolverOptions::backend>(s) && (s.Has(ceres_only[0].key) || s.Has(ceres_only[1].key))) {
      o.backend = SolverBackend::kCeres;  // only Ceres has them: applied, not ignored
    }
    if (o.backend == SolverBackend::kFast) {
      for (const FieldInfo& f : ceres_only) {
        if (s.Has(f.key)) s[f.key].Fail("is a setting of the Ceres back end (solver.backend: ceres); the fast back end has none");
      }
    }
  }
  // Range checks live in RegistrationOptions::IsValid; its message starts with the field
  // ("data.loss_scale must be > 0 (got -1)"), which locates the offending node.
  std::string error;
  if (!r.IsValid(&error)) {
    const size_t space = error.find(' ');
    const std::string field = error.substr(0, space);
    std::string rest = space == std::string::npos ? std::string() : error.substr(space + 1);
    YamlValue node = v;
    std::string remaining = field;
    while (!remaining.empty()) {
      const size_t dot = remaining.find('.');
      const std::string key = remaining.substr(0, dot);
      remaining = dot == std::string::npos ? std::string() : remaining.substr(dot + 1);
      if (!node.Has(key)) break;
      node = node[key];
    }
    // Report the full field path even when only a parent is present in the file.
    YamlValue located(node.node(), v.path() + "." + field, &node.source(), node.line());
    located.Fail(rest);
  }
}

}  // namespace scene_internal
}  // namespace femreg
