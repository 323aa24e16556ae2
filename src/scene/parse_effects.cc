// Scene sections: effects (fracture, collision) and the collision section (object pairs,
// penalty, rigid obstacles).
#include <filesystem>
#include <set>
#include <string>

#include "femreg/io.h"  // ReadTriangleSurface
#include "scene/scene_parser.h"

namespace femreg {
namespace scene_internal {

void SceneParser::ParseEffects(const YamlValue& v) {
  v.CheckKeys({"fracture", "collision"});
  scene_->effects = EffectsSpec();
  if (v.Has("fracture")) ParseFracture(v["fracture"]);
  if (v.Has("collision")) scene_->effects.collision = v["collision"].AsBool();
}

// effects.fracture: true/false, or a map of limits (which turns it on).
void SceneParser::ParseFracture(const YamlValue& v) {
  EffectsSpec& e = scene_->effects;
  if (!v.node().IsMap()) {
    e.fracture = v.AsBool();
    return;
  }
  v.CheckKeys(FieldKeys<FractureOptions>({}, {"enabled"}));
  e.fracture = v.Has("enabled") ? v["enabled"].AsBool() : true;
  ParseFields(v, &e.fracture_options, /*check=*/true);  // the limits (femreg/fracture.h)
}

// The collision section (pairs of object names, penalty, rigid obstacles).
void SceneParser::ParseCollision(const YamlValue& v) {
  v.CheckKeys(FieldKeys<CollisionSpec>({"obstacles"}, {"pairs"}));
  CollisionSpec& c = scene_->collision;
  ParseFields(v, &c, /*check=*/true);  // the penalty and friction (femreg/collision_spec.h)
  auto object_name = [&](const YamlValue& n) {
    const std::string name = n.AsString();
    std::vector<std::string> names;
    for (const ObjectSpec& o : scene_->objects) {
      if (o.name == name) return name;
      names.push_back(o.name);
    }
    const std::string suggestion = ClosestMatch(name, names);
    n.Fail("unknown object " + Quote(name) + " (" +
           (suggestion.empty() ? std::string() : "did you mean " + Quote(suggestion) + "? ") +
           "objects: " + JoinNames(names) + ")");
  };
  if (v.Has("pairs")) {
    const YamlValue pairs = v["pairs"];
    pairs.RequireSequence();
    for (int i = 0; i < pairs.size(); ++i) {
      const YamlValue entry = pairs[i];
      CollisionPair pair;  // [a, b], or with its own friction: {objects: [a, b], friction: mu}
      if (entry.IsMap()) {
        entry.CheckKeys(FieldKeys<CollisionPair>({}, {"objects"}));
        if (!entry.Has("objects")) entry.Fail("needs 'objects' (a pair of object names [a, b])");
        ParseFields(entry, &pair, /*check=*/true);  // friction (femreg/collision_spec.h)
      }
      const YamlValue p = entry.IsMap() ? entry["objects"] : entry;
      if (!p.IsSequence() || p.size() != 2) p.Fail("must be a pair of object names [a, b]");
      pair.first = object_name(p[0]);
      pair.second = object_name(p[1]);
      if (pair.first == pair.second) p.Fail("an object cannot be paired with itself (" + Quote(pair.first) + ")");
      c.pairs.push_back(pair);
    }
  }
  if (v.Has("obstacles")) {
    const YamlValue list = v["obstacles"];
    list.RequireSequence();
    std::set<std::string> names;
    for (int i = 0; i < list.size(); ++i) {
      const YamlValue o = list[i];
      o.CheckKeys(FieldKeys<ObstacleSpec>({"objects", "pose", "keyframes"}, {"name", "plane", "box", "mesh"}));
      ObstacleSpec spec;
      spec.name = o.Has("name") ? o["name"].AsString() : "obstacle" + std::to_string(i);
      if (!names.insert(spec.name).second) o["name"].Fail("duplicate obstacle name " + Quote(spec.name));
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
      ParseFields(o, &spec, /*check=*/true);  // scale, friction (femreg/collision_spec.h)
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

}  // namespace scene_internal
}  // namespace femreg
