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
//     loads: true                                  # the scene's gravity and loads act
//     camera: {position: [0, 0, 1], target: [0, 0, 0], up: [0, -1, 0], fx: 525, fy: 525,
//              cx: 319.5, cy: 239.5, width: 640, height: 480}  # present = a known camera
//              # or intrinsics: camera.json (Open3D's PinholeCameraIntrinsic) for fx..height
//              # or intrinsics: intrinsics.txt (the matrix as text) for fx..cy, with width, height
//     preprocess: {mask_dir: masks,               # depth frames: mask_dir/<frame name>.png
//                  crop: {min: [..], max: [..]}, plane: {distance: 0.005, iterations: 200},
//                  voxel_size: 0,
//                  outliers: {neighbors: 0, stddev: 1}, normals: {neighbors: 0}}
//     data: {model_to_cloud: true, cloud_to_model: true, max_distance: 0.03,
//            loss: huber|cauchy|tukey|none, loss_scale: 0.005,
//            metric: point_to_plane|point_to_point, visibility: false, cloud_stride: 1}
//     weights: {data: 200 | data_per_area: 2e7, model_to_cloud_share: 0.03,
//               model_to_cloud_area_cap: 0, model_to_cloud_balance: true, elastic: 1,
//               temporal: 1, anchor: 1e4}
//     solver: {max_outer_iterations: 8, max_inner_iterations: 10,
//              relative_energy_tolerance: 1e-3, time_budget_s: 0,
//              trust_region: levenberg_marquardt|dogleg,
//              linear_solver: sparse_normal_cholesky|conjugate_gradients, threads: 1,
//              rigid_prealign: false, rigid_iterations: 20, predict_motion: true,
//              backtrack: true, cut_reversals: true, backend: ceres|fast}
//   anchors:
//     - {name: gripper, object: beam, select: SELECTION, hard: false, weight: 0,
//        translations: [[0, 0, 0], [0, 0, 0.01]],   # per frame; the last one repeats
//        rotations: [[0, 0, 0], [0, 0.3, 0]], centre: [x, y, z]}   # optional, about centre
//   effects: {fracture: false, collision: false}   # fracture: true or a map of limits
//   collision:                                 # used when effects.collision is true
//     pairs: [[a, b]]                          # object pairs; default: every pair
//     stiffness: 1e4                           # k (N/m) per contact
//     distance: 0.002                          # D (m), detection distance (not a standoff)
//     tolerance: 0.0002                        # m, the penetration a contact may keep
//     augmented: true                          # multiplier updates between outer iterations
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
//     artefacts: {flying_pixels: 0.5,          # NAME: strength, or NAME: {KEY: value, ..};
//                 multipath: {bias: 0.003, radius: 0.03}}   # names, keys: SynthArtefactKeys
//     motion:                                  # vertex sets of the ground truth mesh moved rigidly
//       - {name: grip, select: SELECTION, centre: [x, y, z],   # centre default: the centroid
//          keyframes: [{frame: 0}, {frame: 9, translation: [..], rotation: [..]}],
//          anchor: none}                       # hard|soft: the tracking scene gets an anchor
//                                              # following the motion (rotating: needs centre)
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

#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "scene/scene_parser.h"
#include "scene/yaml_reader.h"

namespace femreg {

ObjectMaterial ObjectSpec::Materials() const {
  ObjectMaterial m;
  m.material = material;
  m.regions = region_materials;
  m.model = Model();
  m.nodal_volume = NodalVolume();
  return m;
}

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

const char* ToString(MotionTrackSpec::Anchor anchor) {
  switch (anchor) {
    case MotionTrackSpec::Anchor::kNone:
      return "none";
    case MotionTrackSpec::Anchor::kHard:
      return "hard";
    case MotionTrackSpec::Anchor::kSoft:
      return "soft";
  }
  return "unknown";
}

bool FromString(const std::string& name, MotionTrackSpec::Anchor* anchor) {
  for (MotionTrackSpec::Anchor a : EnumValues<MotionTrackSpec::Anchor>::kAll) {
    if (name == ToString(a)) {
      *anchor = a;
      return true;
    }
  }
  return false;
}

namespace scene_internal {

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

void SceneParser::Parse(const YAML::Node& root_node) {
  YamlValue root(root_node, "", &source_, 1);
  if (!root_node.IsDefined() || root_node.IsNull()) root.Fail("the scene is empty");
  root.CheckKeys({"description", "objects", "gravity", "boundary", "loads", "forward",
                  "registration", "anchors", "effects", "synth", "collision"});
  if (root.Has("description")) scene_->description = root["description"].AsString();
  if (root.Has("effects")) ParseEffects(root["effects"]);
  ParseObjects(root["objects"]);
  if (root.Has("collision")) ParseCollision(root["collision"]);
  if (root.Has("gravity")) scene_->gravity = root["gravity"].AsVector3();
  if (root.Has("boundary")) ParseBoundary(root["boundary"]);
  if (root.Has("loads")) ParseLoads(root["loads"]);
  if (root.Has("forward")) ParseForward(root["forward"]);
  if (root.Has("registration")) ParseRegistration(root["registration"]);
  if (root.Has("anchors")) ParseAnchors(root["anchors"]);
  if (root.Has("synth")) ParseSynth(root["synth"]);
}

// The object a boundary condition, load or anchor applies to.
std::string SceneParser::ParseObjectName(const YamlValue& entry) {
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
  v.Fail("unknown object " + Quote(name) + " (" +
         (suggestion.empty() ? std::string() : "did you mean " + Quote(suggestion) + "? ") +
         "objects: " + JoinNames(names) + ")");
}

VertexSelection SceneParser::ParseSelection(const YamlValue& entry) {
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

}  // namespace scene_internal

Status ParseScene(const std::string& yaml_text, const std::string& source,
                  const std::string& base_dir, Scene* scene) {
  Scene parsed;
  parsed.path = source;
  try {
    const YAML::Node root = YAML::Load(yaml_text);
    scene_internal::SceneParser parser(source, base_dir, &parsed);
    parser.Parse(root);
  } catch (const scene_internal::SceneError& e) {
    return Status::Error(e.what());
  } catch (const YAML::Exception& e) {
    return scene_internal::YamlErrorStatus(source, e);
  }
  *scene = std::move(parsed);
  return Status::Ok();
}

namespace scene_internal {

Status ReadSceneText(const std::string& path, std::string* text, std::string* base_dir) {
  std::error_code ec;
  if (std::filesystem::is_directory(path, ec)) {
    return Status::Error(path + ": is a folder, not a scene file");
  }
  std::ifstream in(path, std::ios::binary);
  if (!in) return Status::Error(path + ": cannot open the scene file (missing or unreadable)");
  std::ostringstream os;
  os << in.rdbuf();
  *text = os.str();
  const std::filesystem::path parent = std::filesystem::path(path).parent_path();
  *base_dir = parent.empty() ? "." : parent.string();
  return Status::Ok();
}

}  // namespace scene_internal

Status LoadScene(const std::string& path, Scene* scene) {
  std::string text, base_dir;
  const Status status = scene_internal::ReadSceneText(path, &text, &base_dir);
  if (!status.ok()) return status;
  return ParseScene(text, path, base_dir, scene);
}

}  // namespace femreg
