// Scene section: synth (femreg synth: the ground truth simulation, the virtual sensor, the
// motion script and rigid bodies).
#include <filesystem>
#include <set>
#include <string>

#include "scene/scene_parser.h"

namespace femreg {
namespace scene_internal {

void SceneParser::ParseSynth(const YamlValue& v) {
  v.CheckKeys(FieldKeys<SynthSpec>({"sensor", "motion", "bodies", "artefacts"}));
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
  // The ground truth's keys beside its refinement (the table's) are read here.
  const char* truth_group = FieldOf<&SynthSpec::refinement>().group;
  if (v.Has(truth_group)) v[truth_group].CheckKeys(GroupKeys<SynthSpec>(truth_group, {"mesh", "generate", "material"}));
  // frames, seed, sanity_check, ground_truth.refinement, background (femreg/scene.h)
  ParseFields(v, &s, /*check=*/true, {truth_group});
  s.material = object.material;
  s.ground_truth_where = v.Location() + " (" + v.path() + ")";
  if (v.Has(truth_group)) {
    const YamlValue g = v[truth_group];
    if (s.sanity_check) {
      g.Fail("a sanity check tracks the data with the very mesh and material that made it: "
             "remove ground_truth or sanity_check");
    }
    s.ground_truth_where = g.Location() + " (" + g.path() + ")";
    const bool refined = HasField<&SynthSpec::refinement>(v);
    if (refined + g.Has("mesh") + g.Has("generate") > 1) {
      g.Fail("needs at most one of refinement, mesh or generate");
    }
    if (refined && object.generate.shape == MeshGeneratorSpec::Shape::kNone) {
      FieldValue<&SynthSpec::refinement>(v)
          .Fail("refines a generated object, and objects[0] reads a mesh file: "
                "give ground_truth.mesh (a finer mesh of the same shape)");
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
  if (s.background && !(s.background_normal.norm() > 0)) {
    FieldValue<&SynthSpec::background_normal>(v).Fail("must not be zero");
  }
  std::set<std::string> names;
  if (v.Has("motion")) {
    const YamlValue list = v["motion"];
    list.RequireSequence();
    for (int i = 0; i < list.size(); ++i) {
      const YamlValue t = list[i];
      t.CheckKeys(FieldKeys<MotionTrackSpec>({}, {"name", "select", "centre", "keyframes"}));
      MotionTrackSpec track;
      track.name = t.Has("name") ? t["name"].AsString() : "track" + std::to_string(i);
      if (!names.insert(track.name).second) t["name"].Fail("duplicate name " + Quote(track.name));
      track.selection = ParseSelection(t);
      if (t.Has("centre")) {
        track.has_centre = true;
        track.centre = t["centre"].AsVector3();
      }
      track.keyframes = ParseKeyframes(t, true);
      ParseFields(t, &track, /*check=*/true);  // anchor (femreg/scene.h)
      for (const MotionKeyframe& k : track.keyframes) {
        if (track.anchor != MotionTrackSpec::Anchor::kNone && k.rotation.norm() > 0 && !track.has_centre) {
          FieldValue<&MotionTrackSpec::anchor>(t)
              .Fail("this track rotates: its anchor turns about the track's centre, so give centre: [x, y, z]");
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
      b.CheckKeys(FieldKeys<SynthBodySpec>({"keyframes"}, {"name"}));
      SynthBodySpec body;
      body.name = b.Has("name") ? b["name"].AsString() : "body" + std::to_string(i);
      if (!names.insert(body.name).second) b["name"].Fail("duplicate name " + Quote(body.name));
      const char* box = FieldOf<&SynthBodySpec::box_min>().group;
      if (!b.Has(box)) b.Fail("needs 'box: {min: [x, y, z], max: [x, y, z]}'");
      if (!HasField<&SynthBodySpec::box_min>(b) || !HasField<&SynthBodySpec::box_max>(b)) {
        b[box].CheckKeys(GroupKeys<SynthBodySpec>(box));
        b[box].Fail("needs 'min' and 'max'");
      }
      ParseFields(b, &body, /*check=*/true);  // box, in_cloud, press, contact_tolerance (femreg/scene.h)
      if ((body.box_min.array() >= body.box_max.array()).any()) {
        FieldValue<&SynthBodySpec::box_max>(b).Fail("must be > min in every coordinate");
      }
      if (b.Has("keyframes")) body.keyframes = ParseKeyframes(b, false);
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
