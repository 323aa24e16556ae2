// Scene sections: boundary conditions, loads and the forward solve (the simulation), and the
// anchors of registration.
#include <set>
#include <string>

#include "scene/scene_parser.h"

namespace femreg {
namespace scene_internal {

void SceneParser::ParseBoundary(const YamlValue& list) {
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

void SceneParser::ParseLoads(const YamlValue& list) {
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

void SceneParser::ParseForward(const YamlValue& v) {
  v.CheckKeys(FieldKeys<ForwardOptions>());
  ParseFields(v, &scene_->forward, /*check=*/true);  // the model and the solve's limits (femreg/forward.h)
}

void SceneParser::ParseForceRegion(const YamlValue& v) {
  auto one = [this](const YamlValue& entry) {
    entry.CheckKeys({"object", "select"});
    ForceRegionSpec region;
    region.object = ParseObjectName(entry);
    region.selection = ParseSelection(entry);
    scene_->force_regions.push_back(region);
  };
  if (v.IsSequence()) {
    for (int i = 0; i < v.size(); ++i) one(v[i]);
  } else {
    one(v);
  }
}

void SceneParser::ParseAnchors(const YamlValue& list) {
  list.RequireSequence();
  std::set<std::string> names;
  for (int i = 0; i < list.size(); ++i) {
    const YamlValue v = list[i];
    v.CheckKeys(FieldKeys<AnchorSpec>({"translations", "rotations", "centre"}, {"name", "object", "select"}));
    AnchorSpec anchor;
    anchor.name = v.Has("name") ? v["name"].AsString() : "anchor" + std::to_string(i);
    if (!names.insert(anchor.name).second) {
      v["name"].Fail("duplicate anchor name " + Quote(anchor.name));
    }
    anchor.object = ParseObjectName(v);
    anchor.selection = ParseSelection(v);
    ParseFields(v, &anchor, /*check=*/true);  // hard, weight (femreg/scene.h)
    if (v.Has("translations")) {
      const YamlValue t = v["translations"];
      if (!t.IsSequence()) t.Fail("must be a list of [x, y, z] per frame");
      for (int k = 0; k < t.size(); ++k) anchor.translations.push_back(t[k].AsVector3());
    }
    if (v.Has("rotations")) {
      const YamlValue r = v["rotations"];
      if (!r.IsSequence()) r.Fail("must be a list of [x, y, z] (axis * angle, rad) per frame");
      for (int k = 0; k < r.size(); ++k) anchor.rotations.push_back(r[k].AsVector3());
      if (anchor.rotations.size() != anchor.translations.size()) {
        r.Fail("has " + std::to_string(anchor.rotations.size()) + " entries and translations " +
               std::to_string(anchor.translations.size()) + ": one rotation per translation");
      }
      if (!v.Has("centre")) r.Fail("rotations need a centre: [x, y, z] (m) to turn about");
    }
    if (v.Has("centre")) anchor.centre = v["centre"].AsVector3();
    scene_->anchors.push_back(anchor);
  }
}

}  // namespace scene_internal
}  // namespace femreg
