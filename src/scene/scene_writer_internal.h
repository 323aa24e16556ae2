// The YAML helpers shared by scene_writer.cc (objects, conditions, anchors, effects, collision,
// synth; SceneToYaml) and scene_writer_options.cc (the forward and registration options):
// numbers that read back exactly, flow maps and sequences, PutFields, which writes an options
// table's keys (femreg/field_table.h), and Put, which writes a key of what has no table (a
// list entry's) only where its value differs from the default.
#ifndef FEMREG_SCENE_SCENE_WRITER_INTERNAL_H_
#define FEMREG_SCENE_SCENE_WRITER_INTERNAL_H_

#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <charconv>
#include <cstdlib>
#include <filesystem>
#include <string>
#include <type_traits>
#include <vector>

#include "femreg/field_table.h"
#include "femreg/option_fields.h"
#include "femreg/scene.h"

namespace femreg {
namespace internal {
namespace scene_writer {

// The shortest decimal that reads back to the same double: fixed notation for magnitudes
// in [1e-4, 1e7), else "d.ddde-N" (with a '.' and a signed exponent, which every YAML
// reader takes for a number).
inline std::string Number(double x) {
  char buf[64];
  const std::to_chars_result r =
      std::to_chars(buf, buf + sizeof(buf), x, std::chars_format::scientific);
  std::string sci(buf, r.ptr);  // "-1.2345e-05": shortest round-trip digits
  std::string sign;
  if (!sci.empty() && sci[0] == '-') {
    sign = "-";
    sci.erase(0, 1);
  }
  if (sci == "inf" || sci == "nan") return sign + "." + sci;  // YAML's .inf / .nan
  const size_t e = sci.find('e');
  std::string digits = sci.substr(0, e);
  const int exponent = std::atoi(sci.c_str() + e + 1);
  if (digits.size() > 1) digits.erase(1, 1);  // drop the '.'
  const double magnitude = std::abs(x);
  if (magnitude == 0.0 || (magnitude >= 1e-4 && magnitude < 1e7)) {
    std::string fixed;
    if (exponent < 0) {
      fixed = "0." + std::string(static_cast<size_t>(-exponent - 1), '0') + digits;
    } else if (static_cast<int>(digits.size()) <= exponent + 1) {
      fixed = digits + std::string(static_cast<size_t>(exponent + 1) - digits.size(), '0');
    } else {
      fixed = digits.substr(0, exponent + 1) + "." + digits.substr(exponent + 1);
    }
    return sign + fixed;
  }
  const std::string mantissa = digits.substr(0, 1) + "." + (digits.size() > 1 ? digits.substr(1) : "0");
  return sign + mantissa + "e" + (exponent < 0 ? "-" : "+") + std::to_string(std::abs(exponent));
}

inline YAML::Node Flow(YAML::Node node) {
  node.SetStyle(YAML::EmitterStyle::Flow);
  return node;
}

inline YAML::Node Map() { return YAML::Node(YAML::NodeType::Map); }
inline YAML::Node FlowMap() { return Flow(Map()); }
inline YAML::Node FlowSeq() { return Flow(YAML::Node(YAML::NodeType::Sequence)); }

inline YAML::Node Vec(const Eigen::Vector3d& v) {
  YAML::Node n = FlowSeq();
  for (int k = 0; k < 3; ++k) n.push_back(Number(v[k]));
  return n;
}

inline YAML::Node Vec(const Eigen::Vector3i& v) {
  YAML::Node n = FlowSeq();
  for (int k = 0; k < 3; ++k) n.push_back(v[k]);
  return n;
}

// map[key] = value where it differs from the default.
inline void Put(YAML::Node map, const char* key, double value, double default_value) {
  if (value != default_value) map[key] = Number(value);
}
inline void Put(YAML::Node map, const char* key, int value, int default_value) {
  if (value != default_value) map[key] = value;
}
inline void Put(YAML::Node map, const char* key, bool value, bool default_value) {
  if (value != default_value) map[key] = value;
}
inline void Put(YAML::Node map, const char* key, const Eigen::Vector3d& value,
         const Eigen::Vector3d& default_value) {
  if (value != default_value) map[key] = Vec(value);
}
// A field's value as the scene file writes it (an optional's value: PutFields writes no
// unset one).
template <class T>
YAML::Node FieldNode(const T& value) {
  if constexpr (FieldType<T>::kOptional) {
    return FieldNode(*value);
  } else if constexpr (std::is_enum_v<T>) {
    return YAML::Node(ToString(value));
  } else if constexpr (std::is_same_v<T, double>) {
    return YAML::Node(Number(value));
  } else if constexpr (std::is_same_v<T, Eigen::Vector3d>) {
    return Vec(value);
  } else {
    static_assert(std::is_integral_v<T>, "an options table holds bool, integers, double, Vector3d, enums and their optionals");
    return YAML::Node(value);
  }
}

// Which of a table's rows PutFields writes: every one, or those before or after the
// entries the section writes by hand (FieldInfo::after).
enum class Rows { kAll, kBefore, kAfter };

// Every field of an options table (femreg/field_table.h) that differs from `d` (the
// struct's defaults unless given; every field with `all`), in the table's order, but those in
// `skip` (which the section writes itself) and those `rows` leaves out.
// A group (FieldInfo::group) is written, as a flow map, when any of its fields differs: the
// fields that differ and those the group needs (FieldInfo::required: a plane's distance).
// A group with a switch (FieldInfo::switch_of_group) is written in full when the switch is
// on, and not at all when it is off.
// An optional field (FieldType) is written when it is set, and never when it is not.
// `skip` names fields by their path in the section ("crop.min").
template <class Options>
void PutFields(YAML::Node map, const Options& value, const std::vector<std::string>& skip = {},
               bool all = false, const Options& d = Options(), Rows rows = Rows::kAll) {
  std::vector<std::string> changed_groups, on_groups, off_groups;
  OptionFields<Options>::Visit([&](auto member, const FieldInfo& f) {
    if (f.group != nullptr && value.*member != d.*member) changed_groups.push_back(f.group);
    if constexpr (std::is_same_v<std::decay_t<decltype(value.*member)>, bool>) {
      if (f.switch_of_group) (value.*member ? on_groups : off_groups).push_back(f.key);
    }
  });
  auto in = [](const std::vector<std::string>& groups, const char* group) {
    return std::find(groups.begin(), groups.end(), group) != groups.end();
  };
  OptionFields<Options>::Visit([&](auto member, const FieldInfo& f) {
    if ((rows == Rows::kBefore && f.after) || (rows == Rows::kAfter && !f.after)) return;
    for (const std::string& key : skip) {
      if (key == f.path()) return;
    }
    if constexpr (FieldType<std::decay_t<decltype(value.*member)>>::kOptional) {
      if (!(value.*member).has_value()) return;  // unset: the file leaves the key out
    }
    if (f.switch_of_group) {
      if (in(on_groups, f.key)) map[f.key] = FlowMap();
      return;
    }
    if (f.group == nullptr) {
      if (all || value.*member != d.*member) map[f.key] = FieldNode(value.*member);
      return;
    }
    if (in(off_groups, f.group)) return;
    const bool full = all || in(on_groups, f.group);
    if (!full && !in(changed_groups, f.group)) return;
    if (!full && !f.required && value.*member == d.*member) return;
    if (!map[f.group].IsDefined() || map[f.group].IsNull()) map[f.group] = FlowMap();
    map[f.group][f.key] = FieldNode(value.*member);
  });
}

// The rows before (or after) the entries a section writes by hand, where they differ from
// the defaults.
template <class Options>
void PutFieldsBefore(YAML::Node map, const Options& value, const Options& d = Options()) {
  PutFields(map, value, {}, false, d, Rows::kBefore);
}
template <class Options>
void PutFieldsAfter(YAML::Node map, const Options& value, const Options& d = Options()) {
  PutFields(map, value, {}, false, d, Rows::kAfter);
}

// map[key] = child when the child has entries.
inline void PutMap(YAML::Node map, const char* key, const YAML::Node& child) {
  if (child.size() > 0) map[key] = child;
}

// A file path as the scene file's reader resolves it: relative to base_dir.
inline std::string FilePath(const std::string& path, const std::string& base_dir) {
  if (base_dir.empty() || path.empty()) return path;
  std::error_code ec;
  std::filesystem::path base = std::filesystem::absolute(base_dir, ec).lexically_normal();
  if (base.has_parent_path() && base.filename().empty()) base = base.parent_path();  // "dir/"
  const std::filesystem::path file = std::filesystem::absolute(path, ec).lexically_normal();
  const std::filesystem::path relative = file.lexically_relative(base);
  return relative.empty() ? file.string() : relative.generic_string();
}

// Defined in scene_writer.cc: a vertex selection (box, plane, indices or all).
YAML::Node SelectionNode(const VertexSelection& s);

// Defined in scene_writer_options.cc: the forward and registration sections.
YAML::Node ForwardNode(const Scene& scene);
YAML::Node RegistrationNode(const RegistrationOptions& r, const std::vector<ForceRegionSpec>& regions,
                            const std::string& base_dir);

}  // namespace scene_writer
}  // namespace internal
}  // namespace femreg

#endif  // FEMREG_SCENE_SCENE_WRITER_INTERNAL_H_
