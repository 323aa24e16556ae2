// Writing scenes (femreg/scene.h WriteScene): the YAML layout of scene_parser.cc, built as a
// yaml-cpp node tree and written by its emitter. Options are written only where they differ
// from the defaults the parser starts from; what defines a thing (a generator's shape, a
// camera, a plane, a selection) is written in full. Sections are blocks, their entries flow
// maps, so that a written scene reads like the hand-written ones.
// The forward and registration options are written by scene_writer_options.cc, the helpers
// both use are in scene_writer_internal.h.
#include <yaml-cpp/yaml.h>

#include <filesystem>
#include <sstream>
#include <string>
#include <vector>

#include "femreg/io.h"
#include "femreg/scene.h"
#include "scene/scene_writer_internal.h"

namespace fs = std::filesystem;

namespace femreg {
namespace internal {
namespace scene_writer {

YAML::Node SelectionNode(const VertexSelection& s) {
  YAML::Node n = FlowMap();
  switch (s.kind) {
    case VertexSelection::Kind::kBox: {
      YAML::Node box = FlowMap();
      box["min"] = Vec(s.box_min);
      box["max"] = Vec(s.box_max);
      n["box"] = box;
      break;
    }
    case VertexSelection::Kind::kPlane: {
      YAML::Node plane = FlowMap();
      plane["point"] = Vec(s.plane_point);
      plane["normal"] = Vec(s.plane_normal);
      n["plane"] = plane;
      break;
    }
    case VertexSelection::Kind::kIndices: {
      YAML::Node indices = FlowSeq();
      for (int i : s.indices) indices.push_back(i);
      n["indices"] = indices;
      break;
    }
    case VertexSelection::Kind::kAll:
      n["all"] = true;
      break;
  }
  Put(n, "tolerance", s.tolerance, VertexSelection().tolerance);
  return n;
}

}  // namespace scene_writer
}  // namespace internal

namespace {

using namespace internal::scene_writer;  // NOLINT(build/namespaces)

// The material's keys that differ from `base` (the object's material for a region).
YAML::Node MaterialNode(const Material& m, const Material& base) {
  YAML::Node n = FlowMap();
  PutFields(n, m, {}, false, base);
  return n;
}

YAML::Node GeneratorNode(const MeshGeneratorSpec& g) {
  YAML::Node n = FlowMap();
  n["shape"] = ToString(g.shape);
  switch (g.shape) {
    case MeshGeneratorSpec::Shape::kBox:
      n["size"] = Vec(g.size);
      n["cells"] = Vec(g.cells);
      Put(n, "origin", g.origin, Eigen::Vector3d::Zero());
      break;
    case MeshGeneratorSpec::Shape::kCylinder: {
      n["radius"] = Number(g.radius);
      n["length"] = Number(g.length);
      YAML::Node cells = FlowSeq();
      cells.push_back(g.radial_cells);
      cells.push_back(g.axial_cells);
      n["cells"] = cells;
      break;
    }
    case MeshGeneratorSpec::Shape::kSphere:
      n["radius"] = Number(g.radius);
      n["cells"] = g.radial_cells;
      break;
    case MeshGeneratorSpec::Shape::kNone:
      break;
  }
  return n;
}

// The object a condition applies to: left out where the reader infers it (one object).
void PutObject(YAML::Node entry, const Scene& scene, const std::string& object) {
  if (object.empty()) return;
  if (scene.objects.size() == 1 && object == scene.objects[0].name) return;
  entry["object"] = object;
}

// A keyframe: frame (unless it is a pose), translation and rotation where not zero.
YAML::Node KeyframeNode(int frame, bool with_frame, const Eigen::Vector3d& translation,
                        const Eigen::Vector3d& rotation, bool with_rotation) {
  YAML::Node n = FlowMap();
  if (with_frame) n["frame"] = frame;
  Put(n, "translation", translation, Eigen::Vector3d::Zero());
  if (with_rotation) Put(n, "rotation", rotation, Eigen::Vector3d::Zero());
  return n;
}

YAML::Node MotionKeyframes(const std::vector<MotionKeyframe>& keyframes, bool rotations) {
  YAML::Node list = FlowSeq();
  for (const MotionKeyframe& k : keyframes) {
    list.push_back(KeyframeNode(k.frame, true, k.translation, k.rotation, rotations));
  }
  return list;
}

YAML::Node ObjectNode(const ObjectSpec& o, const std::string& base_dir) {
  YAML::Node n = Map();
  n["name"] = o.name;
  if (o.generate.shape != MeshGeneratorSpec::Shape::kNone) {
    n["generate"] = GeneratorNode(o.generate);
  } else {
    n["mesh"] = FilePath(o.mesh_path, base_dir);
  }
  PutFieldsBefore(n, o);  // scale, pose, material.model and material.volume (femreg/scene.h)
  {
    // The material's own keys (Material's table), then the element's rows, set or not.
    const char* group = FieldOf<&ObjectSpec::model>().group;
    YAML::Node material = MaterialNode(o.material, Material());
    const YAML::Node element = static_cast<const YAML::Node&>(n)[group];
    if (element.IsDefined()) {
      for (const auto& row : element) material[row.first.Scalar()] = row.second.Scalar();
    }
    PutMap(n, group, material);
  }
  if (!o.region_materials.empty()) {
    YAML::Node regions = FlowMap();
    for (const auto& [region, material] : o.region_materials) {
      YAML::Node entry = MaterialNode(material, o.material);
      for (const auto& [id, toughness] : o.region_toughness) {
        if (id == region) entry[FieldOf<&ObjectSpec::toughness>().key] = Number(toughness);  // the object's row
      }
      regions[std::to_string(region)] = entry;
    }
    n["regions"] = regions;
  }
  PutFieldsAfter(n, o);  // toughness, label
  if (!o.surface_path.empty()) n["surface"] = FilePath(o.surface_path, base_dir);
  return n;
}

// Anchors without a trajectory fit on one line; a trajectory gets a line per frame.
YAML::Node AnchorNode(const Scene& scene, const AnchorSpec& a) {
  YAML::Node n = a.translations.empty() ? FlowMap() : Map();
  n["name"] = a.name;
  PutObject(n, scene, a.object);
  n["select"] = SelectionNode(a.selection);
  PutFields(n, a);  // hard, weight (femreg/scene.h)
  if (!a.translations.empty()) {
    YAML::Node list(YAML::NodeType::Sequence);
    for (const Eigen::Vector3d& t : a.translations) list.push_back(Vec(t));
    n["translations"] = list;
  }
  if (!a.rotations.empty()) {
    YAML::Node list(YAML::NodeType::Sequence);
    for (const Eigen::Vector3d& r : a.rotations) list.push_back(Vec(r));
    n["rotations"] = list;
    n["centre"] = Vec(a.centre);
  }
  return n;
}

YAML::Node EffectsNode(const EffectsSpec& e) {
  YAML::Node fracture = FlowMap();
  PutFields(fracture, e.fracture_options);
  YAML::Node n = FlowMap();
  if (fracture.size() > 0) {
    if (!e.fracture) fracture["enabled"] = false;
    n["fracture"] = fracture;
  } else if (e.fracture) {
    n["fracture"] = true;
  }
  if (e.collision) n["collision"] = true;
  return n;
}

YAML::Node ObstacleNode(const ObstacleSpec& o, const std::string& base_dir) {
  YAML::Node n = o.keyframes.size() > 1 ? Map() : FlowMap();
  n["name"] = o.name;
  switch (o.kind) {
    case ObstacleSpec::Kind::kPlane: {
      YAML::Node plane = FlowMap();
      plane["point"] = Vec(o.plane_point);
      plane["normal"] = Vec(o.plane_normal);
      n["plane"] = plane;
      break;
    }
    case ObstacleSpec::Kind::kBox: {
      YAML::Node box = FlowMap();
      box["size"] = Vec(o.box_size);
      n["box"] = box;
      break;
    }
    case ObstacleSpec::Kind::kMesh:
      if (o.surface) {  // no file to name (WriteScene refuses it): the text says what it was
        n["mesh"] = "(in memory: " + std::to_string(o.surface->vertices.rows()) + " vertices, " +
                    std::to_string(o.surface->triangles.rows()) + " triangles)";
      } else {
        n["mesh"] = FilePath(o.mesh_path, base_dir);
      }
      break;
  }
  PutFields(n, o);  // scale, friction (femreg/collision_spec.h)
  if (!o.objects.empty()) {
    YAML::Node objects = FlowSeq();
    for (const std::string& name : o.objects) objects.push_back(name);
    n["objects"] = objects;
  }
  if (o.keyframes.size() == 1 && o.keyframes[0].frame == 0) {  // a fixed pose
    const ObstacleKeyframe& k = o.keyframes[0];
    n["pose"] = KeyframeNode(0, false, k.translation, k.rotation, true);
  } else if (!o.keyframes.empty()) {
    YAML::Node keyframes = FlowSeq();
    for (const ObstacleKeyframe& k : o.keyframes) {
      keyframes.push_back(KeyframeNode(k.frame, true, k.translation, k.rotation, true));
    }
    n["keyframes"] = keyframes;
  }
  return n;
}

YAML::Node CollisionNode(const CollisionSpec& c, const std::string& base_dir) {
  YAML::Node n = Map();
  if (!c.pairs.empty()) {
    YAML::Node pairs = FlowSeq();
    for (const CollisionPair& p : c.pairs) {
      YAML::Node pair = FlowSeq();
      pair.push_back(p.first);
      pair.push_back(p.second);
      YAML::Node entry = FlowMap();  // {objects: [a, b], friction: mu}
      entry["objects"] = pair;
      PutFields(entry, p);  // friction (femreg/collision_spec.h)
      pairs.push_back(entry.size() > 1 ? entry : pair);
    }
    n["pairs"] = pairs;
  }
  PutFields(n, c);
  if (!c.obstacles.empty()) {
    YAML::Node obstacles(YAML::NodeType::Sequence);
    for (const ObstacleSpec& o : c.obstacles) obstacles.push_back(ObstacleNode(o, base_dir));
    n["obstacles"] = obstacles;
  }
  return n;
}

YAML::Node SynthNode(const Scene& scene, const std::string& base_dir) {
  const SynthSpec& s = scene.synth;
  const SynthSpec d;
  YAML::Node n = Map();
  PutFieldsBefore(n, s);  // frames, seed, sanity_check, ground_truth.refinement
  const char* truth_group = FieldOf<&SynthSpec::refinement>().group;
  const YAML::Node refined = static_cast<const YAML::Node&>(n)[truth_group];
  YAML::Node truth = refined.IsDefined() ? refined : FlowMap();
  if (!s.mesh_path.empty()) truth["mesh"] = FilePath(s.mesh_path, base_dir);
  if (s.generate.shape != MeshGeneratorSpec::Shape::kNone) truth["generate"] = GeneratorNode(s.generate);
  if (!scene.objects.empty()) PutMap(truth, "material", MaterialNode(s.material, scene.objects[0].material));
  PutMap(n, truth_group, truth);
  YAML::Node sensor = FlowMap();
  PutFields(sensor, s.sensor);
  PutMap(n, "sensor", sensor);
  PutFieldsAfter(n, s);  // background
  if (!s.motion.empty()) {
    YAML::Node motion(YAML::NodeType::Sequence);
    for (const MotionTrackSpec& t : s.motion) {
      YAML::Node track = Map();
      track["name"] = t.name;
      track["select"] = SelectionNode(t.selection);
      if (t.has_centre) track["centre"] = Vec(t.centre);
      YAML::Node keyframes(YAML::NodeType::Sequence);
      for (const MotionKeyframe& k : t.keyframes) {
        keyframes.push_back(KeyframeNode(k.frame, true, k.translation, k.rotation, true));
      }
      track["keyframes"] = keyframes;
      PutFields(track, t);  // anchor (femreg/scene.h)
      motion.push_back(track);
    }
    n["motion"] = motion;
  }
  if (!s.bodies.empty()) {
    YAML::Node bodies(YAML::NodeType::Sequence);
    for (const SynthBodySpec& b : s.bodies) {
      YAML::Node body = FlowMap();
      body["name"] = b.name;
      PutFieldsBefore(body, b);  // box
      if (!b.keyframes.empty()) body["keyframes"] = MotionKeyframes(b.keyframes, false);
      PutFieldsAfter(body, b);  // in_cloud, press, contact_tolerance
      bodies.push_back(body);
    }
    n["bodies"] = bodies;
  }
  YAML::Node artefacts = Map();
  for (const SynthArtefactKey& k : SynthArtefactKeys()) {
    if (k.get(s) == k.get(d)) continue;
    if (!artefacts[k.artefact]) artefacts[k.artefact] = FlowMap();
    YAML::Node artefact = artefacts[k.artefact];
    artefact[k.key] = Number(k.get(s));
  }
  PutMap(n, "artefacts", artefacts);
  return n;
}

}  // namespace

std::string SceneToYaml(const Scene& scene, const std::string& base_dir,
                        const std::string& comment) {
  YAML::Node root = Map();
  if (!scene.description.empty()) root["description"] = scene.description;
  YAML::Node objects(YAML::NodeType::Sequence);
  for (const ObjectSpec& o : scene.objects) objects.push_back(ObjectNode(o, base_dir));
  root["objects"] = objects;
  Put(root, "gravity", scene.gravity, Eigen::Vector3d::Zero());
  if (!scene.boundary_conditions.empty()) {
    YAML::Node list(YAML::NodeType::Sequence);
    for (const BoundaryConditionSpec& bc : scene.boundary_conditions) {
      YAML::Node entry = FlowMap();
      PutObject(entry, scene, bc.object);
      entry["select"] = SelectionNode(bc.selection);
      if (bc.type == BoundaryConditionSpec::Type::kClamp) {
        entry["clamp"] = true;
      } else {
        entry["displacement"] = Vec(bc.displacement);
      }
      list.push_back(entry);
    }
    root["boundary"] = list;
  }
  if (!scene.loads.empty()) {
    YAML::Node list(YAML::NodeType::Sequence);
    for (const LoadSpec& load : scene.loads) {
      YAML::Node entry = FlowMap();
      PutObject(entry, scene, load.object);
      entry["select"] = SelectionNode(load.selection);
      entry["force"] = Vec(load.force);
      list.push_back(entry);
    }
    root["loads"] = list;
  }
  PutMap(root, "forward", ForwardNode(scene));
  PutMap(root, "registration", RegistrationNode(scene.registration, scene.force_regions, base_dir));
  if (!scene.anchors.empty()) {
    YAML::Node list(YAML::NodeType::Sequence);
    for (const AnchorSpec& a : scene.anchors) list.push_back(AnchorNode(scene, a));
    root["anchors"] = list;
  }
  PutMap(root, "effects", EffectsNode(scene.effects));
  PutMap(root, "collision", CollisionNode(scene.collision, base_dir));
  if (scene.synth.enabled) root["synth"] = SynthNode(scene, base_dir);

  std::ostringstream text;
  std::istringstream lines(comment);
  for (std::string line; std::getline(lines, line);) text << (line.empty() ? "#" : "# " + line) << "\n";
  YAML::Emitter emitter;
  emitter << root;
  text << emitter.c_str() << "\n";
  return text.str();
}

Status WriteScene(const Scene& scene, const std::string& path, const std::string& comment) {
  // A scene file that LoadScene could not read back is refused rather than written.
  for (const ObstacleSpec& o : scene.collision.obstacles) {
    if (o.kind == ObstacleSpec::Kind::kMesh && o.surface) {
      return Status::Error(path + ": collision.obstacles '" + o.name +
                           "' has its surface in memory, and a scene names a file: write the surface "
                           "to an OBJ or STL file and set its mesh_path instead");
    }
  }
  const fs::path parent = fs::path(path).parent_path();
  return WriteFileAtomically(path, SceneToYaml(scene, parent.empty() ? "." : parent.string(), comment));
}

}  // namespace femreg
