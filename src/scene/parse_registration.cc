// Scene section: registration (regularizer, camera, preprocessing, data term, weights,
// solver); range checks through RegistrationOptions::IsValid.
#include <filesystem>
#include <string>

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
      // An Open3D PinholeCameraIntrinsic JSON, relative to the scene's folder; instead of
      // the keys it sets, never beside them (which would win is a guess).
      for (const char* key : {"fx", "fy", "cx", "cy", "width", "height"}) {
        if (c.Has(key)) {
          c[key].Fail(std::string("given beside camera.intrinsics, which sets it: give the "
                                  "intrinsics either in the file or as fx, fy, cx, cy, width, height"));
        }
      }
      const YamlValue file = c["intrinsics"];
      std::filesystem::path path(file.AsString());
      if (path.empty()) file.Fail("must name an intrinsics file (Open3D's PinholeCameraIntrinsic JSON)");
      if (path.is_relative() && !base_dir_.empty()) path = std::filesystem::path(base_dir_) / path;
      const Status read = ReadCameraIntrinsics(path.lexically_normal().string(), &r.camera);
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
    if (p.Has("crop") && (!p["crop"].Has("min") || !p["crop"].Has("max"))) p["crop"].Fail("needs 'min' and 'max'");
    if (p.Has("plane") && !p["plane"].Has("distance")) p["plane"].Fail("needs 'distance' (m)");
    r.preprocess.crop = p.Has("crop");
    ParseFields(p, &r.preprocess);
  }
  if (v.Has("data")) {
    const YamlValue d = v["data"];
    d.CheckKeys(FieldKeys<DataTermOptions>());
    DataTermOptions& o = r.data;
    ParseFields(d, &o);
    if (!d.Has("auto_visibility") && d.Has("visibility") && !o.visibility) {
      // `visibility: false` written out means every surface vertex pulls: without this, a
      // scene with a camera would still get the camera's test from auto_visibility.
      o.auto_visibility = false;
    }
  }
  if (v.Has("weights")) {
    const YamlValue w = v["weights"];
    w.CheckKeys(FieldKeys<WeightOptions>());
    if (w.Has("data") && w.Has("data_per_area")) {
      w["data"].Fail("set data (legacy: N/m per correspondence, so the fit changes with the "
                     "cloud's density) or data_per_area (N/m^3, per unit observed area), not both");
    }
    ParseFields(w, &r.weights);
    if (w.Has("data") && !(r.weights.data >= 0)) w["data"].Fail("must be >= 0 (N/m per correspondence)");
    if (w.Has("data_per_area")) r.weights.data = -1.0;  // per unit area instead of per correspondence
  }
  if (v.Has("solver")) {
    const YamlValue s = v["solver"];
    s.CheckKeys(FieldKeys<SolverOptions>());
    SolverOptions& o = r.solver;
    ParseFields(s, &o);
    if (!s.Has("backend") && (s.Has("trust_region") || s.Has("linear_solver"))) {
      o.backend = SolverBackend::kCeres;  // only Ceres has them: applied, not ignored
    }
    if (o.backend == SolverBackend::kFast) {
      for (const char* key : {"trust_region", "linear_solver"}) {
        if (s.Has(key)) s[key].Fail("is a setting of the Ceres back end (solver.backend: ceres); the fast back end has none");
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
