// Scene sections: objects (mesh file or generator, scale, pose), materials and regions.
#include <cctype>
#include <filesystem>
#include <map>
#include <string>
#include <utility>

#include "scene/scene_parser.h"

namespace femreg {

std::string ObjectElementError(const ObjectSpec& object) {
  if (object.NodalVolume() && object.Model() != MaterialModel::kNeoHookean) {
    return "'nodal' needs 'model: neo_hookean' (the nodal volume is the neo-Hookean element's remedy for locking)";
  }
  return "";
}

namespace scene_internal {

void SceneParser::ParseObjects(const YamlValue& v) {
  if (v.IsNull()) v.Fail("required: at least one object");
  v.RequireSequence();
  if (v.size() == 0) v.Fail("required: at least one object");
  std::map<std::string, int> seen;
  for (int i = 0; i < v.size(); ++i) {
    ObjectSpec object = ParseObject(v[i], i);
    auto inserted = seen.emplace(object.name, i);
    if (!inserted.second) {
      v[i]["name"].Fail("duplicate object name " + Quote(object.name) + " (also objects[" +
                        std::to_string(inserted.first->second) + "])");
    }
    scene_->objects.push_back(object);
  }
}

ObjectSpec SceneParser::ParseObject(const YamlValue& v, int index) {
  v.CheckKeys(FieldKeys<ObjectSpec>({"surface"}, {"name", "mesh", "generate", "material", "regions"}));
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
  if (v.Has("surface")) {
    const YamlValue surface = v["surface"];
    std::filesystem::path path(surface.AsString());
    if (path.is_relative() && !base_dir_.empty()) path = std::filesystem::path(base_dir_) / path;
    object.surface_path = path.lexically_normal().string();
    std::string ext = path.extension().string();
    for (char& c : ext) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
    if (ext != ".ply" && ext != ".obj" && ext != ".stl") {
      surface.Fail("an embedded surface is a .ply, .obj or .stl file (got " + object.surface_path + ")");
    }
    std::error_code ec;
    if (!std::filesystem::is_regular_file(path, ec)) surface.Fail("surface file not found: " + object.surface_path);
  }
  // scale, pose, material.model and material.volume, toughness, label (femreg/scene.h); the
  // material's own keys are Material's table, checked with the group's rows by ParseMaterial.
  const char* material_group = FieldOf<&ObjectSpec::model>().group;
  ParseFields(v, &object, /*check=*/true, {material_group});
  // The element's rule at the row that breaks it: a model the file wrote against its volume,
  // else the volume the default model cannot take.
  const std::string element_error = ObjectElementError(object);
  if (!element_error.empty()) {
    if (object.model) FieldValue<&ObjectSpec::model>(v).Fail(element_error);
    FieldValue<&ObjectSpec::volume>(v).Fail(element_error);
  }
  if (v.Has(material_group)) object.material = ParseMaterial(v[material_group], object.material);
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
      if (HasField<&ObjectSpec::toughness>(entry)) {  // the object's row
        double toughness = 0.0;
        ReadField(FieldValue<&ObjectSpec::toughness>(entry), FieldOf<&ObjectSpec::toughness>(), true, &toughness);
        object.region_toughness.emplace_back(region, toughness);
      }
    }
  }
  return object;
}

MeshGeneratorSpec SceneParser::ParseGenerator(const YamlValue& v) {
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
    shape.Fail("unknown shape " + Quote(name) + " (" +
               (suggestion.empty() ? std::string() : "did you mean " + Quote(suggestion) + "? ") +
               "one of: box, cylinder, sphere)");
  }
  return spec;
}

Material SceneParser::ParseMaterial(const YamlValue& v, const Material& defaults, bool region) {
  v.CheckKeys(FieldKeys<Material>(region ? std::vector<std::string>{FieldOf<&ObjectSpec::toughness>().key}
                                          : GroupKeys<ObjectSpec>(FieldOf<&ObjectSpec::model>().group)));
  // The keys and ranges are Material's table (femreg/fem.h); a bad value fails at its line:
  // "beam.yaml:6: objects[0].material.poisson_ratio: must be in (-1, 0.5) (got 0.5)".
  Material m = defaults;
  std::string error;
  if (!m.IsValid(&error)) v.Fail(error);
  ParseFields(v, &m, /*check=*/true);
  return m;
}

}  // namespace scene_internal
}  // namespace femreg
