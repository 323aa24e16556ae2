// The scene parser behind ParseScene (femreg/scene.h), one file per group of sections:
//   scene_parser.cc       the document, selections, object names; ParseScene, LoadScene
//   parse_objects.cc      objects, mesh generators, materials and regions
//   parse_conditions.cc   boundary conditions, loads, forward; anchors
//   parse_registration.cc registration
//   parse_effects.cc      effects, collision
//   parse_synth.cc        synth
// Every error is a SceneError thrown by YamlValue::Fail (yaml_reader.h), located at the
// file, line and key path; ParseScene turns the first one into a Status.
#ifndef FEMREG_SCENE_SCENE_PARSER_H_
#define FEMREG_SCENE_SCENE_PARSER_H_

#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <string>
#include <type_traits>
#include <utility>
#include <vector>

#include "femreg/option_fields.h"
#include "femreg/scene.h"
#include "scene/yaml_reader.h"

namespace femreg {
namespace scene_internal {

// A number as the messages show it ("got 0.5").
std::string Number(double v);
// Checked scalars; each fails at the node ("must be > 0 (got -1)").
double PositiveDouble(const YamlValue& v);
double NonNegativeDouble(const YamlValue& v);
int IntAtLeast(const YamlValue& v, int min);

// Parses an enum through its FromString, listing the accepted names on failure.
template <typename Enum>
Enum ParseEnum(const YamlValue& v, const std::vector<Enum>& values) {
  const std::string name = v.AsString();
  Enum result = values.front();
  if (FromString(name, &result)) return result;
  std::vector<std::string> names;
  for (Enum e : values) names.push_back(ToString(e));
  const std::string suggestion = ClosestMatch(name, names);
  v.Fail("unknown value " + Quote(name) + " (" +
         (suggestion.empty() ? std::string() : "did you mean " + Quote(suggestion) + "? ") +
         "one of: " + JoinNames(names) + ")");
}

// An enum of the options' tables (femreg/option_fields.h), any of its EnumValues.
template <typename Enum>
Enum ParseEnum(const YamlValue& v) {
  return ParseEnum(v, std::vector<Enum>(EnumValues<Enum>::kAll.begin(), EnumValues<Enum>::kAll.end()));
}

// The keys of an options table between `before` and `extra` (keys its section reads
// itself), in the order messages list them.
template <class Options>
std::vector<std::string> FieldKeys(std::vector<std::string> extra = {}, std::vector<std::string> before = {}) {
  std::vector<std::string> keys = std::move(before);
  OptionFields<Options>::Visit([&](auto, const FieldInfo& f) {
    const std::string key = f.group != nullptr ? f.group : f.key;  // a group's key once
    if (std::find(keys.begin(), keys.end(), key) == keys.end()) keys.push_back(key);
  });
  keys.insert(keys.end(), extra.begin(), extra.end());
  return keys;
}

// The keys of an options table's group (FieldInfo::group), then `extra` (the group's keys
// read by hand).
template <class Options>
std::vector<std::string> GroupKeys(const std::string& group, const std::vector<std::string>& extra = {}) {
  std::vector<std::string> keys;
  OptionFields<Options>::Visit([&](auto, const FieldInfo& f) {
    if (f.group != nullptr && group == f.group) keys.push_back(f.key);
  });
  keys.insert(keys.end(), extra.begin(), extra.end());
  return keys;
}

// One field's value at `x`, by its type; with `check`, a number out of its row's range fails
// there ("must be >= 1 (got 0)").
template <class T>
void ReadField(const YamlValue& x, const FieldInfo& f, bool check, T* field) {
  if constexpr (FieldType<T>::kOptional) {  // a value the scene may leave unset: set here
    typename FieldType<T>::Value value{};
    ReadField(x, f, check, &value);
    *field = value;
  } else if constexpr (std::is_same_v<T, bool>) {
    *field = x.AsBool();
  } else if constexpr (std::is_integral_v<T>) {  // int, a seed's unsigned
    const int value = x.AsInt();
    if (check && f.checked() && !f.InRange(value)) x.Fail(f.RangeError(value));
    *field = static_cast<T>(value);
  } else if constexpr (std::is_same_v<T, double>) {
    const double value = x.AsDouble();
    if (check && f.checked() && !f.InRange(value)) x.Fail(f.RangeError(value));
    *field = value;
  } else if constexpr (std::is_same_v<T, Eigen::Vector3d>) {
    *field = x.AsVector3();
  } else {
    static_assert(std::is_enum_v<T>, "an options table holds bool, integers, double, Vector3d, enums and their optionals");
    *field = ParseEnum<T>(x);
  }
}

// Reads the fields of an options table that the section `v` sets, each by its type. With
// `check`, a number out of its row's range fails at its key ("must be >= 1 (got 0)");
// without, the ranges are checked afterwards, by IsValid, which names the field (the
// registration, whose rules across fields come with the ranges). A group's keys are checked
// here unless it is in `checked` (a group with keys of its own beside the table's, which its
// section checks). A group's switch (FieldInfo::switch_of_group) is set when the group is
// there.
template <class Options>
void ParseFields(const YamlValue& v, Options* o, bool check = false, std::vector<std::string> checked = {}) {
  OptionFields<Options>::Visit([&](auto member, const FieldInfo& f) {
    auto& field = o->*member;
    using T = std::decay_t<decltype(field)>;
    if (f.switch_of_group) {
      if constexpr (std::is_same_v<T, bool>) field = v.Has(f.key);
      return;
    }
    if (f.group != nullptr) {
      if (!v.Has(f.group)) return;
      const YamlValue g = v[f.group];
      if (std::find(checked.begin(), checked.end(), f.group) == checked.end()) {
        g.CheckKeys(GroupKeys<Options>(f.group));
        checked.push_back(f.group);
      }
      if (!g.Has(f.key)) return;
    } else if (!v.Has(f.key)) {
      return;
    }
    ReadField(f.group != nullptr ? v[f.group][f.key] : v[f.key], f, check, &field);
  });
}

// One member's key in the section `v`, for a section's rules across keys and for a key read
// elsewhere too (a region's toughness): whether `v` has it, and its value
// (HasField<&WeightOptions::data>(w)).
template <auto kMember>
bool HasField(const YamlValue& v) {
  constexpr FieldInfo f = FieldOf<kMember>();
  return f.group != nullptr ? v.Has(f.group) && v[f.group].Has(f.key) : v.Has(f.key);
}
template <auto kMember>
YamlValue FieldValue(const YamlValue& v) {
  constexpr FieldInfo f = FieldOf<kMember>();
  return f.group != nullptr ? v[f.group][f.key] : v[f.key];
}

class SceneParser {
 public:
  SceneParser(const std::string& source, const std::string& base_dir, Scene* scene)
      : source_(source), base_dir_(base_dir), scene_(scene) {}

  // The sections in the order they depend on each other: effects, objects (which the
  // collision pairs, conditions and anchors name), ..., registration (whose camera synth
  // renders from), synth.
  void Parse(const YAML::Node& root_node);

 private:
  // scene_parser.cc: shared by the sections.
  // The object a boundary condition, load or anchor applies to.
  std::string ParseObjectName(const YamlValue& entry);
  VertexSelection ParseSelection(const YamlValue& entry);

  // parse_objects.cc
  void ParseObjects(const YamlValue& v);
  ObjectSpec ParseObject(const YamlValue& v, int index);
  MeshGeneratorSpec ParseGenerator(const YamlValue& v);
  Material ParseMaterial(const YamlValue& v, const Material& defaults, bool region = false);

  // parse_conditions.cc
  void ParseBoundary(const YamlValue& list);
  void ParseLoads(const YamlValue& list);
  void ParseForward(const YamlValue& v);
  void ParseAnchors(const YamlValue& list);
  // registration.forces.region: {object, select} or a list of them.
  void ParseForceRegion(const YamlValue& v);

  // parse_registration.cc
  void ParseRegistration(const YamlValue& v);

  // parse_effects.cc
  void ParseEffects(const YamlValue& v);
  void ParseFracture(const YamlValue& v);
  void ParseCollision(const YamlValue& v);

  // parse_synth.cc
  void ParseSynth(const YamlValue& v);
  void ParseSensor(const YamlValue& v, DepthSensorOptions* sensor);
  void ParseArtefacts(const YamlValue& v, SynthSpec* synth);
  std::vector<MotionKeyframe> ParseKeyframes(const YamlValue& entry, bool rotations);

  std::string source_;
  std::string base_dir_;
  Scene* scene_;
};

// Reads a scene file's text and the folder its relative paths start from; errors name the
// path (a folder, missing, unreadable). LoadScene and the --set overrides share it.
Status ReadSceneText(const std::string& path, std::string* text, std::string* base_dir);

}  // namespace scene_internal
}  // namespace femreg

#endif  // FEMREG_SCENE_SCENE_PARSER_H_
