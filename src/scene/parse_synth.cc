// Scene section: synth (femreg synth: the ground truth simulation, the virtual sensor, the
// motion script and rigid bodies).
#include <filesystem>
#include <set>
#include <string>

#include "scene/scene_parser.h"

namespace femreg {
namespace scene_internal {

void SceneParser::ParseSynth(const YamlValue& v) {
  v.CheckKeys(FieldKeys<SynthSpec>({"ground_truth", "sensor", "background", "motion", "bodies", "artefacts"}));
  SynthSpec& s = scene_->synth;
  s.enabled = true;
  s.source_name = std::filesystem::path(source_).filename().string();
  if (scene_->objects.size() != 1) {
    v.Fail("femreg synth simulates one object (the scene has " +
           std::to_string(scene_->objects.size()) + ")");
  }
  const ObjectSpec& object = scene_->objects[0];
  if (!scene_->registration.camera.enabled) {
    v.Fail("needs registration.camera: the virtual depth camera renders from it");
  }
  ParseFields(v, &s, /*check=*/true);  // frames, seed, sanity_check (femreg/scene.h)
  s.material = object.material;
  s.ground_truth_where = v.Location() + " (" + v.path() + ")";
  if (v.Has("ground_truth")) {
    const YamlValue g = v["ground_truth"];
    if (s.sanity_check) {
      g.Fail("a sanity check tracks the data with the very mesh and material that made it: "
             "remove ground_truth or sanity_check");
    }
    g.CheckKeys({"refinement", "mesh", "generate", "material"});
    s.ground_truth_where = g.Location() + " (" + g.path() + ")";
    if (g.Has("refinement") + g.Has("mesh") + g.Has("generate") > 1) {
      g.Fail("needs at most one of refinement, mesh or generate");
    }
    if (g.Has("refinement")) {
      s.refinement = IntAtLeast(g["refinement"], 1);
      if (object.generate.shape == MeshGeneratorSpec::Shape::kNone) {
        g["refinement"].Fail("refines a generated object, and objects[0] reads a mesh file: "
                             "give ground_truth.mesh (a finer mesh of the same shape)");
      }
    }
    if (g.Has("mesh")) {
      std::filesystem::path path(g["mesh"].AsString());
      if (path.is_relative() && !base_dir_.empty()) path = std::filesystem::path(base_dir_) / path;
      s.mesh_path = path.lexically_normal().string();
      std::error_code ec;
      if (!std::filesystem::is_regular_file(path, ec)) g["mesh"].Fail("mesh file not found: " + s.mesh_path);
    }
    if (g.Has("generate")) s.generate = ParseGenerator(g["generate"]);
    if (g.Has("material")) s.material = ParseMaterial(g["material"], object.material);
  }
  const bool same_mesh =
      s.refinement == 1 && s.mesh_path.empty() && s.generate.shape == MeshGeneratorSpec::Shape::kNone;
  const bool same_material = s.material.youngs_modulus == object.material.youngs_modulus &&
                             s.material.poisson_ratio == object.material.poisson_ratio &&
                             s.material.density == object.material.density;
  if (same_mesh && same_material && !s.sanity_check) {
    (v.Has("ground_truth") ? v["ground_truth"] : v)
        .Fail("the ground truth would come from the tracked mesh and material (an inverse "
              "crime): refine it (ground_truth: {refinement: 2}), give another mesh or "
              "material, or label the run 'sanity_check: true'");
  }
  s.sensor.camera = scene_->registration.camera;
  if (v.Has("sensor")) ParseSensor(v["sensor"], &s.sensor);
  if (v.Has("artefacts")) ParseArtefacts(v["artefacts"], &s);
  if (v.Has("background")) {
    const YamlValue b = v["background"];
    b.CheckKeys({"point", "normal", "size"});
    s.background = true;
    if (b.Has("point")) s.background_point = b["point"].AsVector3();
    if (b.Has("normal")) s.background_normal = b["normal"].AsVector3();
    if (!(s.background_normal.norm() > 0)) b["normal"].Fail("must not be zero");
    if (b.Has("size")) s.background_size = PositiveDouble(b["size"]);
  }
  std::set<std::string> names;
  if (v.Has("motion")) {
    const YamlValue list = v["motion"];
    list.RequireSequence();
    for (int i = 0; i < list.size(); ++i) {
      const YamlValue t = list[i];
      t.CheckKeys({"name", "select", "centre", "keyframes", "anchor"});
      MotionTrackSpec track;
      track.name = t.Has("name") ? t["name"].AsString() : "track" + std::to_string(i);
      if (!names.insert(track.name).second) t["name"].Fail("duplicate name " + Quote(track.name));
      track.selection = ParseSelection(t);
      if (t.Has("centre")) {
        track.has_centre = true;
        track.centre = t["centre"].AsVector3();
      }
      track.keyframes = ParseKeyframes(t, true);
      if (t.Has("anchor")) {
        const YamlValue a = t["anchor"];
        const std::string kind = a.AsString();
        if (kind == "hard") {
          track.anchor = MotionTrackSpec::Anchor::kHard;
        } else if (kind == "soft") {
          track.anchor = MotionTrackSpec::Anchor::kSoft;
        } else if (kind != "none") {
          a.Fail("unknown value " + Quote(kind) + " (one of: none, hard, soft)");
        }
        for (const MotionKeyframe& k : track.keyframes) {
          if (track.anchor != MotionTrackSpec::Anchor::kNone && k.rotation.norm() > 0 && !track.has_centre) {
            a.Fail("this track rotates: its anchor turns about the track's centre, so give centre: [x, y, z]");
          }
        }
      }
      s.motion.push_back(track);
    }
  }
  if (v.Has("bodies")) {
    const YamlValue list = v["bodies"];
    list.RequireSequence();
    for (int i = 0; i < list.size(); ++i) {
      const YamlValue b = list[i];
      b.CheckKeys(FieldKeys<SynthBodySpec>({}, {"name", "box", "keyframes"}));
      SynthBodySpec body;
      body.name = b.Has("name") ? b["name"].AsString() : "body" + std::to_string(i);
      if (!names.insert(body.name).second) b["name"].Fail("duplicate name " + Quote(body.name));
      if (!b.Has("box")) b.Fail("needs 'box: {min: [x, y, z], max: [x, y, z]}'");
      const YamlValue box = b["box"];
      box.CheckKeys({"min", "max"});
      if (!box.Has("min") || !box.Has("max")) box.Fail("needs 'min' and 'max'");
      body.box_min = box["min"].AsVector3();
      body.box_max = box["max"].AsVector3();
      if ((body.box_min.array() >= body.box_max.array()).any()) {
        box["max"].Fail("must be > min in every coordinate");
      }
      if (b.Has("keyframes")) body.keyframes = ParseKeyframes(b, false);
      ParseFields(b, &body, /*check=*/true);
      s.bodies.push_back(body);
    }
  }
}

void SceneParser::ParseSensor(const YamlValue& v, DepthSensorOptions* sensor) {
  v.CheckKeys(FieldKeys<DepthSensorOptions>());
  ParseFields(v, sensor, /*check=*/true);  // each key at its line (femreg/synth.h)
  std::string error;
  if (!sensor->IsValid(&error)) v.Fail(error);  // the camera, the artefacts
}

// artefacts: {NAME: STRENGTH} or {NAME: {KEY: value, ...}}, names and keys from
// SynthArtefactKeys (shared with the writer and femreg synth --artefact).
void SceneParser::ParseArtefacts(const YamlValue& v, SynthSpec* synth) {
  v.RequireMap();
  std::vector<std::string> names;
  for (const SynthArtefactKey& k : SynthArtefactKeys()) {
    if (names.empty() || names.back() != k.artefact) names.push_back(k.artefact);
  }
  v.CheckKeys(names);
  for (const std::string& name : names) {
    if (!v.Has(name)) continue;
    const YamlValue a = v[name];
    if (!a.IsMap()) {
      const Status status = SetSynthArtefactValue(name, "", a.AsDouble(), synth);
      if (!status.ok()) a.Fail(status.message());
      continue;
    }
    std::vector<std::string> keys;
    for (const SynthArtefactKey& k : SynthArtefactKeys()) {
      if (name == k.artefact) keys.push_back(k.key);
    }
    a.CheckKeys(keys);
    for (const std::string& key : keys) {
      if (!a.Has(key)) continue;
      const Status status = SetSynthArtefactValue(name, key, a[key].AsDouble(), synth);
      if (!status.ok()) a[key].Fail(status.message());
    }
  }
}

// keyframes: [{frame: 0, translation: [..], rotation: [..]}, ...], frames increasing.
std::vector<MotionKeyframe> SceneParser::ParseKeyframes(const YamlValue& entry, bool rotations) {
  if (!entry.Has("keyframes")) entry.Fail("needs 'keyframes: [{frame: 0, translation: [x, y, z]}, ...]'");
  const YamlValue list = entry["keyframes"];
  if (!list.IsSequence() || list.size() == 0) list.Fail("must be a non-empty list of keyframes");
  std::vector<MotionKeyframe> keyframes;
  for (int k = 0; k < list.size(); ++k) {
    const YamlValue f = list[k];
    if (rotations) {
      f.CheckKeys({"frame", "translation", "rotation"});
    } else {
      f.CheckKeys({"frame", "translation"});
    }
    if (!f.Has("frame")) f.Fail("needs 'frame'");
    MotionKeyframe key;
    key.frame = IntAtLeast(f["frame"], 0);
    if (!keyframes.empty() && key.frame <= keyframes.back().frame) {
      f["frame"].Fail("must be greater than the previous keyframe's (" +
                      std::to_string(keyframes.back().frame) + ")");
    }
    if (f.Has("translation")) key.translation = f["translation"].AsVector3();
    if (f.Has("rotation")) key.rotation = f["rotation"].AsVector3();
    keyframes.push_back(key);
  }
  return keyframes;
}

}  // namespace scene_internal
}  // namespace femreg
