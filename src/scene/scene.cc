// Reading scene files (YAML). The layout, with defaults; every key is optional unless
// marked "required", and a key that is not listed here is an error:
//
//   description: "free text"
//   objects:                                   # required, at least one
//     - name: beam                             # unique; default object0, object1, ...
//       mesh: beam.msh                         # relative to the scene file's folder, or:
//       generate: {shape: box, size: [1, 0.1, 0.1], cells: [20, 2, 2], origin: [0, 0, 0]}
//       #         {shape: cylinder, radius: 0.05, length: 1, cells: [2, 20]}  # radial, axial; +z
//       #         {shape: sphere, radius: 0.1, cells: 4}                     # centred at 0
//       scale: 1.0                             # > 0, applied to the file's coordinates
//       pose: {translation: [0, 0, 0], rotation: [0, 0, 0]}  # rotation: axis * angle (rad)
//       material: {youngs_modulus: 1e5, poisson_ratio: 0.3, density: 1000}  # Pa, -, kg/m^3
//       regions: {2: {youngs_modulus: 5e5}}    # per region id; unset fields inherit
//       toughness: 0                           # Pa, for fracture (later)
//       label: -1                              # cloud points with this PCD label are its own
//   gravity: [0, 0, 0]                         # m/s^2
//   boundary:
//     - {object: beam, select: SELECTION, clamp: true}
//     - {object: beam, select: SELECTION, displacement: [0, 0, 0.1]}   # m, from rest
//   loads:
//     - {object: beam, select: SELECTION, force: [0, 0, -1]}  # N in total, spread evenly
//   forward: {model: corotational|linear, max_iterations: 100, load_steps: 1,
//             tolerance: 1e-8, absolute_tolerance: 1e-12}
//   registration:
//     regularizer: corotational|linear|mass_spring|none
//     camera: {position: [0, 0, 1], target: [0, 0, 0], up: [0, -1, 0], fx: 525, fy: 525,
//              cx: 319.5, cy: 239.5, width: 640, height: 480}  # present = a known camera
//     preprocess: {crop: {min: [..], max: [..]}, plane: {distance: 0.005, iterations: 200},
//                  voxel_size: 0,
//                  outliers: {neighbors: 0, stddev: 1}, normals: {neighbors: 0}}
//     data: {model_to_cloud: true, cloud_to_model: true, max_distance: 0.03,
//            loss: huber|cauchy|tukey|none, loss_scale: 0.005,
//            metric: point_to_plane|point_to_point, visibility: false, cloud_stride: 1}
//     weights: {data: 200, elastic: 1, temporal: 1, anchor: 1e4}
//     solver: {max_outer_iterations: 5, max_inner_iterations: 10,
//              relative_energy_tolerance: 1e-3, time_budget_s: 0,
//              trust_region: levenberg_marquardt|dogleg,
//              linear_solver: sparse_normal_cholesky|conjugate_gradients, threads: 1,
//              rigid_prealign: false, rigid_iterations: 20, predict_motion: true,
//              backend: ceres|fast}
//   anchors:
//     - {name: gripper, object: beam, select: SELECTION, hard: false, weight: 0,
//        translations: [[0, 0, 0], [0, 0, 0.01]]}   # per frame; the last one repeats
//   effects: {fracture: false, collision: false}   # fracture: true or a map of limits
//   collision:                                 # used when effects.collision is true
//     pairs: [[a, b]]                          # object pairs; default: every pair
//     stiffness: 1e4                           # k (N/m) per contact
//     distance: 0.002                          # D (m), proximity threshold
//     obstacles:                               # rigid; objects: [..] (default: all)
//       - {name: table, plane: {point: [0, 0, 0], normal: [0, 0, 1]}}
//       - {name: block, box: {size: [x, y, z]}, pose: {translation: [..], rotation: [..]}}
//       - {name: tool, mesh: tool.stl, scale: 1,        # OBJ or STL (ASCII or binary)
//          keyframes: [{frame: 0, translation: [..], rotation: [..]}, {frame: 9, ...}]}
//   synth:                                     # femreg synth (ground truth sequences); one object
//     frames: 30                               # >= 1
//     seed: 1                                  # noise seed (>= 0); the output is deterministic
//     ground_truth: {refinement: 2,            # the object's generator with cells * 2, or
//                    mesh: fine.msh,           # a finer mesh file, or generate: {...}; the
//                    material: {poisson_ratio: 0.42}}   # object's scale and pose apply;
//                                              # material overrides the object's
//     sanity_check: false                      # true: simulate with the tracked mesh and
//                                              # material (labelled in the outputs); without
//                                              # it that is an error (an inverse crime)
//     sensor: {noise_coefficient: 2.85e-3, grazing_angle_deg: 80, pixel_stride: 1,
//              outlier_fraction: 0, outlier_margin: 0.05, near: 0.05}  # camera: registration.camera
//     background: {point: [0, 0, 0], normal: [0, 0, 1], size: 1}   # a square table in view
//     motion:                                  # vertex sets of the ground truth mesh moved rigidly
//       - {name: grip, select: SELECTION, centre: [x, y, z],   # centre default: the centroid
//          keyframes: [{frame: 0}, {frame: 9, translation: [..], rotation: [..]}],
//          anchor: none}                       # hard|soft: the tracking scene gets an anchor
//                                              # following the translations (no rotation)
//     bodies:                                  # rigid boxes rendered with the object
//       - {name: tool, box: {min: [..], max: [..]}, keyframes: [{frame: 0, translation: [..]}],
//          in_cloud: false,                    # false: hides points but returns none
//          press: false, contact_tolerance: 0.001}   # press: moves the top vertices under
//                                              # its footprint down to its bottom face (-z)
//   Keyframes interpolate linearly and hold before the first and after the last; a rotation
//   (axis * angle) turns about the centre, then the translation applies, both from rest.
//   boundary, loads, gravity and forward drive the simulation (on the ground truth mesh).
//
// SELECTION is exactly one of
//   {box: {min: [x, y, z], max: [x, y, z]}}
//   {plane: {point: [x, y, z], normal: [x, y, z]}}     # the side the normal points to
//   {indices: [0, 1, 2]}
//   {all: true}
// plus an optional tolerance (m, default 1e-9) added around boxes and planes. Selections
// are evaluated on the posed rest positions. `object` may be left out when the scene has
// one object.
#include "femreg/scene.h"

#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <map>
#include <set>
#include <sstream>

#include "scene/yaml_reader.h"

namespace femreg {

using scene_internal::ClosestMatch;
using scene_internal::JoinNames;
using scene_internal::SceneError;
using scene_internal::YamlValue;

const char* ToString(MeshGeneratorSpec::Shape shape) {
  switch (shape) {
    case MeshGeneratorSpec::Shape::kNone:
      return "none";
    case MeshGeneratorSpec::Shape::kBox:
      return "box";
    case MeshGeneratorSpec::Shape::kCylinder:
      return "cylinder";
    case MeshGeneratorSpec::Shape::kSphere:
      return "sphere";
  }
  return "unknown";
}

namespace {

std::string Number(double v) {
  std::ostringstream os;
  os << v;
  return os.str();
}

double PositiveDouble(const YamlValue& v) {
  const double value = v.AsDouble();
  if (!(value > 0)) v.Fail("must be > 0 (got " + Number(value) + ")");
  return value;
}

double NonNegativeDouble(const YamlValue& v) {
  const double value = v.AsDouble();
  if (!(value >= 0)) v.Fail("must be >= 0 (got " + Number(value) + ")");
  return value;
}

int IntAtLeast(const YamlValue& v, int min) {
  const int value = v.AsInt();
  if (value < min) v.Fail("must be >= " + std::to_string(min) + " (got " + std::to_string(value) + ")");
  return value;
}

// Parses an enum through its FromString, listing the accepted names on failure.
template <typename Enum>
Enum ParseEnum(const YamlValue& v, const std::vector<Enum>& values) {
  const std::string name = v.AsString();
  Enum result = values.front();
  if (FromString(name, &result)) return result;
  std::vector<std::string> names;
  for (Enum e : values) names.push_back(ToString(e));
  const std::string suggestion = ClosestMatch(name, names);
  v.Fail("unknown value '" + name + "' (" +
         (suggestion.empty() ? std::string() : "did you mean '" + suggestion + "'? ") +
         "one of: " + JoinNames(names) + ")");
}

class SceneParser {
 public:
  SceneParser(const std::string& source, const std::string& base_dir, Scene* scene)
      : source_(source), base_dir_(base_dir), scene_(scene) {}

  void Parse(const YAML::Node& root_node) {
    YamlValue root(root_node, "", &source_, 1);
    if (!root_node.IsDefined() || root_node.IsNull()) root.Fail("the scene is empty");
    root.CheckKeys({"description", "objects", "gravity", "boundary", "loads", "forward",
                    "registration", "anchors", "effects", "synth", "collision"});
    if (root.Has("effects")) ParseEffects(root["effects"]);
    ParseObjects(root["objects"]);
    if (root.Has("collision")) ParseCollision(root["collision"]);
    if (root.Has("gravity")) scene_->gravity = root["gravity"].AsVector3();
    if (root.Has("boundary")) ParseBoundary(root["boundary"]);
    if (root.Has("loads")) ParseLoads(root["loads"]);
    if (root.Has("forward")) ParseForward(root["forward"]);
    if (root.Has("registration")) ParseRegistration(root["registration"]);
    if (root.Has("anchors")) ParseAnchors(root["anchors"]);
    if (root.Has("synth")) ParseSynth(root["synth"], root_node);
  }

 private:
  void ParseEffects(const YamlValue& v) {
    v.CheckKeys({"fracture", "collision"});
    scene_->effects = EffectsSpec();
    if (v.Has("fracture")) ParseFracture(v["fracture"]);
    if (v.Has("collision")) scene_->effects.collision = v["collision"].AsBool();
  }

  // effects.fracture: true/false, or a map of limits (which turns it on).
  void ParseFracture(const YamlValue& v) {
    EffectsSpec& e = scene_->effects;
    if (!v.node().IsMap()) {
      e.fracture = v.AsBool();
      return;
    }
    v.CheckKeys({"enabled", "max_splits_per_iteration", "max_splits_per_frame",
                 "crossing_tolerance", "max_cracks", "data_gap"});
    e.fracture = v.Has("enabled") ? v["enabled"].AsBool() : true;
    FractureOptions& f = e.fracture_options;
    if (v.Has("max_splits_per_iteration")) f.max_splits_per_iteration = IntAtLeast(v["max_splits_per_iteration"], 1);
    if (v.Has("max_splits_per_frame")) f.max_splits_per_frame = IntAtLeast(v["max_splits_per_frame"], 1);
    if (v.Has("max_cracks")) f.max_cracks = IntAtLeast(v["max_cracks"], 0);
    if (v.Has("data_gap")) f.data_gap = v["data_gap"].AsBool();
    if (v.Has("crossing_tolerance")) {
      f.crossing_tolerance = NonNegativeDouble(v["crossing_tolerance"]);
      if (f.crossing_tolerance >= 1) v["crossing_tolerance"].Fail("must be < 1");
    }
  }

  // The collision section (pairs of object names, penalty, rigid obstacles).
  void ParseCollision(const YamlValue& v) {
    v.CheckKeys({"pairs", "stiffness", "distance", "obstacles"});
    CollisionSpec& c = scene_->collision;
    auto object_name = [&](const YamlValue& n) {
      const std::string name = n.AsString();
      std::vector<std::string> names;
      for (const ObjectSpec& o : scene_->objects) {
        if (o.name == name) return name;
        names.push_back(o.name);
      }
      const std::string suggestion = ClosestMatch(name, names);
      n.Fail("unknown object '" + name + "' (" +
             (suggestion.empty() ? std::string() : "did you mean '" + suggestion + "'? ") +
             "objects: " + JoinNames(names) + ")");
    };
    if (v.Has("pairs")) {
      const YamlValue pairs = v["pairs"];
      pairs.RequireSequence();
      for (int i = 0; i < pairs.size(); ++i) {
        const YamlValue p = pairs[i];
        if (!p.IsSequence() || p.size() != 2) p.Fail("must be a pair of object names [a, b]");
        const std::string a = object_name(p[0]), b = object_name(p[1]);
        if (a == b) p.Fail("an object cannot be paired with itself ('" + a + "')");
        c.pairs.emplace_back(a, b);
      }
    }
    if (v.Has("stiffness")) c.stiffness = PositiveDouble(v["stiffness"]);
    if (v.Has("distance")) c.distance = PositiveDouble(v["distance"]);
    if (v.Has("obstacles")) {
      const YamlValue list = v["obstacles"];
      list.RequireSequence();
      std::set<std::string> names;
      for (int i = 0; i < list.size(); ++i) {
        const YamlValue o = list[i];
        o.CheckKeys({"name", "plane", "box", "mesh", "scale", "objects", "pose", "keyframes"});
        ObstacleSpec spec;
        spec.name = o.Has("name") ? o["name"].AsString() : "obstacle" + std::to_string(i);
        if (!names.insert(spec.name).second) o["name"].Fail("duplicate obstacle name '" + spec.name + "'");
        const int kinds = o.Has("plane") + o.Has("box") + o.Has("mesh");
        if (kinds != 1) o.Fail("needs exactly one of 'plane', 'box' or 'mesh'");
        if (o.Has("plane")) {
          const YamlValue p = o["plane"];
          p.CheckKeys({"point", "normal"});
          spec.kind = ObstacleSpec::Kind::kPlane;
          if (p.Has("point")) spec.plane_point = p["point"].AsVector3();
          if (p.Has("normal")) spec.plane_normal = p["normal"].AsVector3();
          if (!(spec.plane_normal.norm() > 0)) p["normal"].Fail("must not be zero");
        } else if (o.Has("box")) {
          const YamlValue b = o["box"];
          b.CheckKeys({"size"});
          spec.kind = ObstacleSpec::Kind::kBox;
          if (!b.Has("size")) b.Fail("needs 'size' (m)");
          spec.box_size = b["size"].AsVector3();
          if ((spec.box_size.array() <= 0).any()) b["size"].Fail("every edge length must be > 0");
        } else {
          spec.kind = ObstacleSpec::Kind::kMesh;
          const YamlValue mesh = o["mesh"];
          std::filesystem::path path(mesh.AsString());
          if (path.is_relative() && !base_dir_.empty()) path = std::filesystem::path(base_dir_) / path;
          spec.mesh_path = path.lexically_normal().string();
          std::error_code ec;
          if (!std::filesystem::is_regular_file(path, ec)) mesh.Fail("mesh file not found: " + spec.mesh_path);
          Vertices vertices;
          Triangles triangles;
          const Status status = ReadTriangleSurface(spec.mesh_path, &vertices, &triangles);
          if (!status.ok()) mesh.Fail(status.message());
        }
        if (o.Has("scale")) spec.scale = PositiveDouble(o["scale"]);
        if (o.Has("objects")) {
          const YamlValue objects = o["objects"];
          objects.RequireSequence();
          for (int k = 0; k < objects.size(); ++k) spec.objects.push_back(object_name(objects[k]));
        }
        if (o.Has("pose") && o.Has("keyframes")) o.Fail("has both 'pose' and 'keyframes'; use one");
        auto keyframe = [&](const YamlValue& k, bool with_frame) {
          k.CheckKeys(with_frame ? std::vector<std::string>{"frame", "translation", "rotation"}
                                 : std::vector<std::string>{"translation", "rotation"});
          ObstacleKeyframe key;
          if (with_frame) {
            if (!k.Has("frame")) k.Fail("needs 'frame'");
            key.frame = IntAtLeast(k["frame"], 0);
          }
          if (k.Has("translation")) key.translation = k["translation"].AsVector3();
          if (k.Has("rotation")) key.rotation = k["rotation"].AsVector3();
          return key;
        };
        if (o.Has("pose")) spec.keyframes.push_back(keyframe(o["pose"], false));
        if (o.Has("keyframes")) {
          const YamlValue keys = o["keyframes"];
          keys.RequireSequence();
          for (int k = 0; k < keys.size(); ++k) {
            spec.keyframes.push_back(keyframe(keys[k], true));
            if (k > 0 && spec.keyframes[k].frame <= spec.keyframes[k - 1].frame) {
              keys[k]["frame"].Fail("keyframes must be in increasing frame order");
            }
          }
        }
        c.obstacles.push_back(spec);
      }
    }
  }

  void ParseObjects(const YamlValue& v) {
    if (v.IsNull()) v.Fail("required: at least one object");
    v.RequireSequence();
    if (v.size() == 0) v.Fail("required: at least one object");
    std::map<std::string, int> seen;
    for (int i = 0; i < v.size(); ++i) {
      ObjectSpec object = ParseObject(v[i], i);
      auto inserted = seen.emplace(object.name, i);
      if (!inserted.second) {
        v[i]["name"].Fail("duplicate object name '" + object.name + "' (also objects[" +
                          std::to_string(inserted.first->second) + "])");
      }
      scene_->objects.push_back(object);
    }
  }

  ObjectSpec ParseObject(const YamlValue& v, int index) {
    v.CheckKeys({"name", "mesh", "generate", "scale", "pose", "material", "regions",
                 "toughness", "label"});
    ObjectSpec object;
    object.name = v.Has("name") ? v["name"].AsString() : "object" + std::to_string(index);
    if (object.name.empty()) v["name"].Fail("must not be empty");
    if (v.Has("mesh") == v.Has("generate")) {
      v.Fail("needs exactly one of 'mesh' (a file) or 'generate' (a box, cylinder or sphere)");
    }
    if (v.Has("mesh")) {
      const YamlValue mesh = v["mesh"];
      std::filesystem::path path(mesh.AsString());
      if (path.is_relative() && !base_dir_.empty()) path = std::filesystem::path(base_dir_) / path;
      object.mesh_path = path.lexically_normal().string();
      std::error_code ec;
      if (!std::filesystem::is_regular_file(path, ec)) {
        mesh.Fail("mesh file not found: " + object.mesh_path);
      }
    } else {
      object.generate = ParseGenerator(v["generate"]);
    }
    if (v.Has("scale")) object.scale = PositiveDouble(v["scale"]);
    if (v.Has("pose")) {
      const YamlValue pose = v["pose"];
      pose.CheckKeys({"translation", "rotation"});
      if (pose.Has("translation")) object.translation = pose["translation"].AsVector3();
      if (pose.Has("rotation")) object.rotation = pose["rotation"].AsVector3();
    }
    if (v.Has("material")) object.material = ParseMaterial(v["material"], object.material);
    if (v.Has("regions")) {
      const YamlValue regions = v["regions"];
      regions.RequireMap();
      for (auto it = regions.node().begin(); it != regions.node().end(); ++it) {
        YamlValue key(it->first, regions.path(), &source_, regions.line());
        const int region = key.AsInt();
        YamlValue entry(it->second, regions.path() + "." + std::to_string(region), &source_,
                        key.line());
        for (const auto& existing : object.region_materials) {
          if (existing.first == region) key.Fail("region " + std::to_string(region) + " listed twice");
        }
        object.region_materials.emplace_back(region, ParseMaterial(entry, object.material, true));
        if (entry.Has("toughness")) {
          object.region_toughness.emplace_back(region, NonNegativeDouble(entry["toughness"]));
        }
      }
    }
    if (v.Has("toughness")) object.toughness = NonNegativeDouble(v["toughness"]);
    if (v.Has("label")) object.label = IntAtLeast(v["label"], -1);
    return object;
  }

  MeshGeneratorSpec ParseGenerator(const YamlValue& v) {
    v.RequireMap();
    MeshGeneratorSpec spec;
    if (!v.Has("shape")) v.Fail("needs 'shape' (box, cylinder or sphere)");
    const YamlValue shape = v["shape"];
    const std::string name = shape.AsString();
    if (name == "box") {
      v.CheckKeys({"shape", "size", "cells", "origin"});
      spec.shape = MeshGeneratorSpec::Shape::kBox;
      if (v.Has("size")) {
        spec.size = v["size"].AsVector3();
        if ((spec.size.array() <= 0).any()) v["size"].Fail("every edge length must be > 0");
      }
      if (v.Has("cells")) {
        spec.cells = v["cells"].AsVector3i();
        if ((spec.cells.array() < 1).any()) v["cells"].Fail("every cell count must be >= 1");
      }
      if (v.Has("origin")) spec.origin = v["origin"].AsVector3();
    } else if (name == "cylinder") {
      v.CheckKeys({"shape", "radius", "length", "cells"});
      spec.shape = MeshGeneratorSpec::Shape::kCylinder;
      if (v.Has("radius")) spec.radius = PositiveDouble(v["radius"]);
      if (v.Has("length")) spec.length = PositiveDouble(v["length"]);
      if (v.Has("cells")) {
        const YamlValue cells = v["cells"];
        const std::vector<int> n = cells.AsIntList();
        if (n.size() != 2 || n[0] < 1 || n[1] < 1) {
          cells.Fail("must be [radial, axial] with both >= 1");
        }
        spec.radial_cells = n[0];
        spec.axial_cells = n[1];
      }
    } else if (name == "sphere") {
      v.CheckKeys({"shape", "radius", "cells"});
      spec.shape = MeshGeneratorSpec::Shape::kSphere;
      if (v.Has("radius")) spec.radius = PositiveDouble(v["radius"]);
      if (v.Has("cells")) spec.radial_cells = IntAtLeast(v["cells"], 1);
    } else {
      const std::string suggestion = ClosestMatch(name, {"box", "cylinder", "sphere"});
      shape.Fail("unknown shape '" + name + "' (" +
                 (suggestion.empty() ? std::string() : "did you mean '" + suggestion + "'? ") +
                 "one of: box, cylinder, sphere)");
    }
    return spec;
  }

  Material ParseMaterial(const YamlValue& v, const Material& defaults, bool region = false) {
    if (region) {
      v.CheckKeys({"youngs_modulus", "poisson_ratio", "density", "toughness"});
    } else {
      v.CheckKeys({"youngs_modulus", "poisson_ratio", "density"});
    }
    Material m = defaults;
    if (v.Has("youngs_modulus")) {
      m.youngs_modulus = v["youngs_modulus"].AsDouble();
      if (!(m.youngs_modulus > 0)) {
        v["youngs_modulus"].Fail("must be > 0 (got " + Number(m.youngs_modulus) + ")");
      }
    }
    if (v.Has("poisson_ratio")) {
      const YamlValue nu = v["poisson_ratio"];
      m.poisson_ratio = nu.AsDouble();
      if (!(m.poisson_ratio < 0.5)) {
        nu.Fail("must be < 0.5 (got " + Number(m.poisson_ratio) + ")");
      }
      if (!(m.poisson_ratio > -1.0)) {
        nu.Fail("must be > -1 (got " + Number(m.poisson_ratio) + ")");
      }
    }
    if (v.Has("density")) {
      m.density = v["density"].AsDouble();
      if (!(m.density > 0)) v["density"].Fail("must be > 0 (got " + Number(m.density) + ")");
    }
    return m;
  }

  // The object a boundary condition, load or anchor applies to.
  std::string ParseObjectName(const YamlValue& entry) {
    if (!entry.Has("object")) {
      if (scene_->objects.size() == 1) return scene_->objects[0].name;
      std::vector<std::string> names;
      for (const ObjectSpec& o : scene_->objects) names.push_back(o.name);
      entry.Fail("needs 'object' when the scene has several objects (" + JoinNames(names) + ")");
    }
    const YamlValue v = entry["object"];
    const std::string name = v.AsString();
    std::vector<std::string> names;
    for (const ObjectSpec& o : scene_->objects) {
      if (o.name == name) return name;
      names.push_back(o.name);
    }
    const std::string suggestion = ClosestMatch(name, names);
    v.Fail("unknown object '" + name + "' (" +
           (suggestion.empty() ? std::string() : "did you mean '" + suggestion + "'? ") +
           "objects: " + JoinNames(names) + ")");
  }

  VertexSelection ParseSelection(const YamlValue& entry) {
    if (!entry.Has("select")) {
      entry.Fail("needs 'select' (box, plane, indices or all: true)");
    }
    const YamlValue v = entry["select"];
    v.CheckKeys({"box", "plane", "indices", "all", "tolerance"});
    VertexSelection s;
    s.where = v.Location() + " (" + v.path() + ")";
    const int count = v.Has("box") + v.Has("plane") + v.Has("indices") + v.Has("all");
    if (count != 1) v.Fail("needs exactly one of box, plane, indices or all");
    if (v.Has("box")) {
      const YamlValue box = v["box"];
      box.CheckKeys({"min", "max"});
      if (!box.Has("min") || !box.Has("max")) box.Fail("needs 'min' and 'max'");
      s.kind = VertexSelection::Kind::kBox;
      s.box_min = box["min"].AsVector3();
      s.box_max = box["max"].AsVector3();
      if ((s.box_min.array() > s.box_max.array()).any()) {
        box["max"].Fail("must be >= min in every coordinate");
      }
    } else if (v.Has("plane")) {
      const YamlValue plane = v["plane"];
      plane.CheckKeys({"point", "normal"});
      if (!plane.Has("point") || !plane.Has("normal")) plane.Fail("needs 'point' and 'normal'");
      s.kind = VertexSelection::Kind::kPlane;
      s.plane_point = plane["point"].AsVector3();
      s.plane_normal = plane["normal"].AsVector3();
      if (s.plane_normal.norm() == 0) plane["normal"].Fail("must not be zero");
      s.plane_normal.normalize();
    } else if (v.Has("indices")) {
      const YamlValue indices = v["indices"];
      s.kind = VertexSelection::Kind::kIndices;
      s.indices = indices.AsIntList();
      if (s.indices.empty()) indices.Fail("must not be empty");
      for (int i = 0; i < static_cast<int>(s.indices.size()); ++i) {
        if (s.indices[i] < 0) indices[i].Fail("must be >= 0 (got " + std::to_string(s.indices[i]) + ")");
      }
    } else {
      if (!v["all"].AsBool()) v["all"].Fail("must be true (or use another selection)");
      s.kind = VertexSelection::Kind::kAll;
    }
    if (v.Has("tolerance")) s.tolerance = NonNegativeDouble(v["tolerance"]);
    return s;
  }

  void ParseBoundary(const YamlValue& list) {
    list.RequireSequence();
    for (int i = 0; i < list.size(); ++i) {
      const YamlValue v = list[i];
      v.CheckKeys({"object", "select", "clamp", "displacement"});
      BoundaryConditionSpec bc;
      bc.object = ParseObjectName(v);
      bc.selection = ParseSelection(v);
      const bool clamp = v.Has("clamp") && v["clamp"].AsBool();
      if (clamp && v.Has("displacement")) {
        v.Fail("has both 'clamp: true' and 'displacement'; use one (a clamp is a zero displacement)");
      }
      if (clamp) {
        bc.type = BoundaryConditionSpec::Type::kClamp;
      } else if (v.Has("displacement")) {
        bc.type = BoundaryConditionSpec::Type::kDisplacement;
        bc.displacement = v["displacement"].AsVector3();
      } else {
        v.Fail("needs 'clamp: true' or 'displacement: [x, y, z]'");
      }
      scene_->boundary_conditions.push_back(bc);
    }
  }

  void ParseLoads(const YamlValue& list) {
    list.RequireSequence();
    for (int i = 0; i < list.size(); ++i) {
      const YamlValue v = list[i];
      v.CheckKeys({"object", "select", "force"});
      LoadSpec load;
      load.object = ParseObjectName(v);
      load.selection = ParseSelection(v);
      if (!v.Has("force")) v.Fail("needs 'force: [x, y, z]' (N, the total over the selection)");
      load.force = v["force"].AsVector3();
      scene_->loads.push_back(load);
    }
  }

  void ParseForward(const YamlValue& v) {
    v.CheckKeys({"model", "max_iterations", "load_steps", "tolerance", "absolute_tolerance"});
    if (v.Has("model")) {
      scene_->forward_model =
          ParseEnum(v["model"], std::vector<ElasticModelType>{ElasticModelType::kCorotational,
                                                              ElasticModelType::kLinear});
    }
    ForwardOptions& f = scene_->forward;
    if (v.Has("max_iterations")) f.max_iterations = IntAtLeast(v["max_iterations"], 1);
    if (v.Has("load_steps")) f.load_steps = IntAtLeast(v["load_steps"], 1);
    if (v.Has("tolerance")) f.relative_tolerance = PositiveDouble(v["tolerance"]);
    if (v.Has("absolute_tolerance")) {
      f.absolute_tolerance = NonNegativeDouble(v["absolute_tolerance"]);
    }
  }

  void ParseRegistration(const YamlValue& v) {
    v.CheckKeys({"regularizer", "camera", "preprocess", "data", "weights", "solver"});
    RegistrationOptions& r = scene_->registration;
    if (v.Has("regularizer")) {
      r.regularizer = ParseEnum(v["regularizer"],
                                std::vector<Regularizer>{Regularizer::kCorotational,
                                                         Regularizer::kLinear,
                                                         Regularizer::kMassSpring,
                                                         Regularizer::kNone});
    }
    if (v.Has("camera")) {
      const YamlValue c = v["camera"];
      c.CheckKeys({"position", "target", "up", "fx", "fy", "cx", "cy", "width", "height"});
      r.camera.enabled = true;
      if (c.Has("position")) r.camera.position = c["position"].AsVector3();
      if (c.Has("target")) r.camera.target = c["target"].AsVector3();
      if (c.Has("up")) r.camera.up = c["up"].AsVector3();
      if (c.Has("fx")) r.camera.fx = c["fx"].AsDouble();
      if (c.Has("fy")) r.camera.fy = c["fy"].AsDouble();
      if (c.Has("cx")) r.camera.cx = c["cx"].AsDouble();
      if (c.Has("cy")) r.camera.cy = c["cy"].AsDouble();
      if (c.Has("width")) r.camera.width = c["width"].AsInt();
      if (c.Has("height")) r.camera.height = c["height"].AsInt();
    }
    if (v.Has("preprocess")) {
      const YamlValue p = v["preprocess"];
      p.CheckKeys({"crop", "plane", "voxel_size", "outliers", "normals"});
      if (p.Has("crop")) {
        const YamlValue crop = p["crop"];
        crop.CheckKeys({"min", "max"});
        if (!crop.Has("min") || !crop.Has("max")) crop.Fail("needs 'min' and 'max'");
        r.preprocess.crop = true;
        r.preprocess.crop_min = crop["min"].AsVector3();
        r.preprocess.crop_max = crop["max"].AsVector3();
      }
      if (p.Has("plane")) {
        const YamlValue plane = p["plane"];
        plane.CheckKeys({"distance", "iterations"});
        if (!plane.Has("distance")) plane.Fail("needs 'distance' (m)");
        r.preprocess.plane_distance = plane["distance"].AsDouble();
        if (plane.Has("iterations")) r.preprocess.plane_iterations = plane["iterations"].AsInt();
      }
      if (p.Has("voxel_size")) r.preprocess.voxel_size = p["voxel_size"].AsDouble();
      if (p.Has("outliers")) {
        const YamlValue o = p["outliers"];
        o.CheckKeys({"neighbors", "stddev"});
        if (o.Has("neighbors")) r.preprocess.outlier_neighbors = o["neighbors"].AsInt();
        if (o.Has("stddev")) r.preprocess.outlier_stddev = o["stddev"].AsDouble();
      }
      if (p.Has("normals")) {
        const YamlValue n = p["normals"];
        n.CheckKeys({"neighbors"});
        if (n.Has("neighbors")) r.preprocess.normal_neighbors = n["neighbors"].AsInt();
      }
    }
    if (v.Has("data")) {
      const YamlValue d = v["data"];
      d.CheckKeys({"model_to_cloud", "cloud_to_model", "max_distance", "loss", "loss_scale",
                   "metric", "visibility", "cloud_stride"});
      DataTermOptions& o = r.data;
      if (d.Has("model_to_cloud")) o.model_to_cloud = d["model_to_cloud"].AsBool();
      if (d.Has("cloud_to_model")) o.cloud_to_model = d["cloud_to_model"].AsBool();
      if (d.Has("max_distance")) o.max_distance = d["max_distance"].AsDouble();
      if (d.Has("loss")) {
        o.loss = ParseEnum(d["loss"], std::vector<RobustLoss>{RobustLoss::kHuber,
                                                              RobustLoss::kCauchy,
                                                              RobustLoss::kTukey,
                                                              RobustLoss::kNone});
      }
      if (d.Has("loss_scale")) o.loss_scale = d["loss_scale"].AsDouble();
      if (d.Has("metric")) {
        o.metric = ParseEnum(d["metric"], std::vector<DataMetric>{DataMetric::kPointToPoint,
                                                                  DataMetric::kPointToPlane});
      }
      if (d.Has("visibility")) o.visibility = d["visibility"].AsBool();
      if (d.Has("cloud_stride")) o.cloud_stride = d["cloud_stride"].AsInt();
    }
    if (v.Has("weights")) {
      const YamlValue w = v["weights"];
      w.CheckKeys({"data", "elastic", "temporal", "anchor"});
      if (w.Has("data")) r.weights.data = w["data"].AsDouble();
      if (w.Has("elastic")) r.weights.elastic = w["elastic"].AsDouble();
      if (w.Has("temporal")) r.weights.temporal = w["temporal"].AsDouble();
      if (w.Has("anchor")) r.weights.anchor = w["anchor"].AsDouble();
    }
    if (v.Has("solver")) {
      const YamlValue s = v["solver"];
      s.CheckKeys({"max_outer_iterations", "max_inner_iterations", "relative_energy_tolerance",
                   "time_budget_s", "trust_region", "linear_solver", "threads",
                   "rigid_prealign", "rigid_iterations", "predict_motion", "backend"});
      SolverOptions& o = r.solver;
      if (s.Has("max_outer_iterations")) o.max_outer_iterations = s["max_outer_iterations"].AsInt();
      if (s.Has("max_inner_iterations")) o.max_inner_iterations = s["max_inner_iterations"].AsInt();
      if (s.Has("relative_energy_tolerance")) {
        o.relative_energy_tolerance = s["relative_energy_tolerance"].AsDouble();
      }
      if (s.Has("time_budget_s")) o.time_budget_s = s["time_budget_s"].AsDouble();
      if (s.Has("trust_region")) {
        o.trust_region = ParseEnum(s["trust_region"],
                                   std::vector<TrustRegion>{TrustRegion::kLevenbergMarquardt,
                                                            TrustRegion::kDogleg});
      }
      if (s.Has("linear_solver")) {
        o.linear_solver = ParseEnum(
            s["linear_solver"], std::vector<LinearSolver>{LinearSolver::kSparseNormalCholesky,
                                                          LinearSolver::kConjugateGradients});
      }
      if (s.Has("threads")) o.num_threads = s["threads"].AsInt();
      if (s.Has("predict_motion")) o.predict_motion = s["predict_motion"].AsBool();
      if (s.Has("backend")) {
        o.backend = ParseEnum(s["backend"],
                              std::vector<SolverBackend>{SolverBackend::kCeres, SolverBackend::kFast});
      }
      if (s.Has("rigid_prealign")) o.rigid_prealign = s["rigid_prealign"].AsBool();
      if (s.Has("rigid_iterations")) o.rigid_iterations = s["rigid_iterations"].AsInt();
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

  void ParseAnchors(const YamlValue& list) {
    list.RequireSequence();
    std::set<std::string> names;
    for (int i = 0; i < list.size(); ++i) {
      const YamlValue v = list[i];
      v.CheckKeys({"name", "object", "select", "hard", "weight", "translations"});
      AnchorSpec anchor;
      anchor.name = v.Has("name") ? v["name"].AsString() : "anchor" + std::to_string(i);
      if (!names.insert(anchor.name).second) {
        v["name"].Fail("duplicate anchor name '" + anchor.name + "'");
      }
      anchor.object = ParseObjectName(v);
      anchor.selection = ParseSelection(v);
      if (v.Has("hard")) anchor.hard = v["hard"].AsBool();
      if (v.Has("weight")) anchor.weight = NonNegativeDouble(v["weight"]);
      if (v.Has("translations")) {
        const YamlValue t = v["translations"];
        if (!t.IsSequence()) t.Fail("must be a list of [x, y, z] per frame");
        for (int k = 0; k < t.size(); ++k) anchor.translations.push_back(t[k].AsVector3());
      }
      scene_->anchors.push_back(anchor);
    }
  }

  // ---- synth: the ground truth simulation and the virtual sensor (femreg synth) ----
  void ParseSynth(const YamlValue& v, const YAML::Node& root) {
    v.CheckKeys({"frames", "seed", "sanity_check", "ground_truth", "sensor", "background",
                 "motion", "bodies"});
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
    if (v.Has("frames")) s.frames = IntAtLeast(v["frames"], 1);
    if (v.Has("seed")) s.seed = static_cast<uint64_t>(IntAtLeast(v["seed"], 0));
    if (v.Has("sanity_check")) s.sanity_check = v["sanity_check"].AsBool();
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
        if (!names.insert(track.name).second) t["name"].Fail("duplicate name '" + track.name + "'");
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
            a.Fail("unknown value '" + kind + "' (one of: none, hard, soft)");
          }
          for (const MotionKeyframe& k : track.keyframes) {
            if (track.anchor != MotionTrackSpec::Anchor::kNone && k.rotation.norm() > 0) {
              a.Fail("anchors follow translations only, and this track rotates");
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
        b.CheckKeys({"name", "box", "keyframes", "in_cloud", "press", "contact_tolerance"});
        SynthBodySpec body;
        body.name = b.Has("name") ? b["name"].AsString() : "body" + std::to_string(i);
        if (!names.insert(body.name).second) b["name"].Fail("duplicate name '" + body.name + "'");
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
        if (b.Has("in_cloud")) body.in_cloud = b["in_cloud"].AsBool();
        if (b.Has("press")) body.press = b["press"].AsBool();
        if (b.Has("contact_tolerance")) {
          body.contact_tolerance = NonNegativeDouble(b["contact_tolerance"]);
        }
        s.bodies.push_back(body);
      }
    }
    s.tracking_scene_yaml = TrackingSceneYaml(v, root);
  }

  void ParseSensor(const YamlValue& v, DepthSensorOptions* sensor) {
    v.CheckKeys({"noise_coefficient", "grazing_angle_deg", "pixel_stride", "outlier_fraction",
                 "outlier_margin", "near"});
    if (v.Has("noise_coefficient")) sensor->noise_coefficient = v["noise_coefficient"].AsDouble();
    if (v.Has("grazing_angle_deg")) sensor->grazing_angle_deg = v["grazing_angle_deg"].AsDouble();
    if (v.Has("pixel_stride")) sensor->pixel_stride = v["pixel_stride"].AsInt();
    if (v.Has("outlier_fraction")) sensor->outlier_fraction = v["outlier_fraction"].AsDouble();
    if (v.Has("outlier_margin")) sensor->outlier_margin = NonNegativeDouble(v["outlier_margin"]);
    if (v.Has("near")) sensor->near = v["near"].AsDouble();
    std::string error;
    if (!sensor->IsValid(&error)) {
      // "sensor.pixel_stride must be >= 1 (got 0)": locate the key.
      const size_t dot = error.find('.'), space = error.find(' ');
      const std::string key =
          dot != std::string::npos && dot < space ? error.substr(dot + 1, space - dot - 1) : "";
      const YamlValue node = !key.empty() && v.Has(key) ? v[key] : v;
      node.Fail(space == std::string::npos ? error : error.substr(space + 1));
    }
  }

  // keyframes: [{frame: 0, translation: [..], rotation: [..]}, ...], frames increasing.
  std::vector<MotionKeyframe> ParseKeyframes(const YamlValue& entry, bool rotations) {
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

  // The tracking scene femreg synth writes: this file without its simulation-only keys,
  // with mesh files by name (synth copies them) and an anchor per known gripper.
  std::string TrackingSceneYaml(const YamlValue& synth, const YAML::Node& root) {
    const SynthSpec& s = scene_->synth;
    YAML::Node out(YAML::NodeType::Map);
    std::string description = "Tracking scene written by femreg synth from " + s.source_name +
                              " (seed " + std::to_string(s.seed) + ")";
    description += s.sanity_check
                       ? ". SANITY CHECK: the data were made with this very mesh and material"
                       : "; the ground truth comes from another mesh or material";
    out["description"] = description;
    for (auto it = root.begin(); it != root.end(); ++it) {
      const std::string key = it->first.Scalar();
      if (key == "description" || key == "synth" || key == "boundary" || key == "loads" ||
          key == "forward" || key == "gravity") {
        continue;
      }
      out[key] = YAML::Clone(it->second);
    }
    YAML::Node objects = out["objects"];
    for (size_t i = 0; i < objects.size(); ++i) {
      if (objects[i]["mesh"]) {
        objects[i]["mesh"] = std::filesystem::path(objects[i]["mesh"].Scalar()).filename().string();
      }
    }
    auto number = [](double x) {
      char buf[32];
      std::snprintf(buf, sizeof(buf), "%.9g", x == 0 ? 0.0 : x);
      return std::string(buf);
    };
    for (size_t i = 0; i < s.motion.size(); ++i) {
      const MotionTrackSpec& track = s.motion[i];
      if (track.anchor == MotionTrackSpec::Anchor::kNone) continue;
      YAML::Node anchor(YAML::NodeType::Map);
      anchor.SetStyle(YAML::EmitterStyle::Flow);
      anchor["name"] = track.name;
      anchor["select"] = YAML::Clone(root["synth"]["motion"][i]["select"]);
      anchor["hard"] = track.anchor == MotionTrackSpec::Anchor::kHard ? "true" : "false";
      std::vector<std::string> rows;
      for (int f = 0; f < s.frames; ++f) {
        Eigen::Vector3d t, r;
        InterpolateKeyframes(track.keyframes, f, &t, &r);
        rows.push_back("[" + number(t.x()) + ", " + number(t.y()) + ", " + number(t.z()) + "]");
      }
      while (rows.size() > 1 && rows[rows.size() - 1] == rows[rows.size() - 2]) rows.pop_back();
      YAML::Node translations(YAML::NodeType::Sequence);
      for (const std::string& row : rows) translations.push_back(YAML::Load(row));
      anchor["translations"] = translations;
      out["anchors"].push_back(anchor);
    }
    YAML::Emitter emitter;
    emitter << out;
    if (!emitter.good()) synth.Fail("cannot write the tracking scene: " + emitter.GetLastError());
    return std::string(emitter.c_str()) + "\n";
  }

  std::string source_;
  std::string base_dir_;
  Scene* scene_;
};

}  // namespace

Status ParseScene(const std::string& yaml_text, const std::string& source,
                  const std::string& base_dir, Scene* scene) {
  Scene parsed;
  parsed.path = source;
  try {
    const YAML::Node root = YAML::Load(yaml_text);
    SceneParser parser(source, base_dir, &parsed);
    parser.Parse(root);
  } catch (const SceneError& e) {
    return Status::Error(e.what());
  } catch (const YAML::Exception& e) {
    // Syntax errors: yaml-cpp's mark is 0-based.
    std::ostringstream os;
    os << source;
    if (!e.mark.is_null()) os << ":" << e.mark.line + 1 << ":" << e.mark.column + 1;
    os << ": " << e.msg;
    return Status::Error(os.str());
  }
  *scene = std::move(parsed);
  return Status::Ok();
}

Status LoadScene(const std::string& path, Scene* scene) {
  std::error_code ec;
  if (std::filesystem::is_directory(path, ec)) {
    return Status::Error(path + ": is a folder, not a scene file");
  }
  std::ifstream in(path, std::ios::binary);
  if (!in) return Status::Error(path + ": cannot open the scene file (missing or unreadable)");
  std::ostringstream text;
  text << in.rdbuf();
  const std::filesystem::path parent = std::filesystem::path(path).parent_path();
  return ParseScene(text.str(), path, parent.empty() ? "." : parent.string(), scene);
}

}  // namespace femreg
