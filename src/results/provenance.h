// What a run's summary.json records so that the run can be told apart and repeated: the
// version, the resolved options, the inputs; and the options' blocks every run file writes
// from their tables (FieldsJson).
#ifndef FEMREG_RESULTS_PROVENANCE_H_
#define FEMREG_RESULTS_PROVENANCE_H_

#include <Eigen/Core>
#include <cmath>
#include <nlohmann/json.hpp>
#include <string>
#include <type_traits>
#include <vector>

#include "femreg/field_table.h"
#include "femreg/registration.h"
#include "femreg/scene.h"

namespace femreg {
namespace results_internal {

// JSON has no infinity or NaN: those become null (the crop box's open sides are +-1e30).
inline nlohmann::ordered_json Number(double v) {
  return std::isfinite(v) ? nlohmann::ordered_json(v) : nlohmann::ordered_json(nullptr);
}
inline nlohmann::ordered_json Vector(const Eigen::Vector3d& v) {
  return nlohmann::ordered_json::array({Number(v.x()), Number(v.y()), Number(v.z())});
}

// A field's value: an enum by name, a vector as a list, an unset optional as null.
template <class T>
nlohmann::ordered_json FieldJson(const T& value) {
  if constexpr (FieldType<T>::kOptional) {
    return value.has_value() ? FieldJson(*value) : nlohmann::ordered_json(nullptr);
  } else if constexpr (std::is_enum_v<T>) {
    return ToString(value);
  } else if constexpr (std::is_same_v<T, Eigen::Vector3d>) {
    return Vector(value);
  } else if constexpr (std::is_floating_point_v<T>) {
    return Number(value);
  } else {
    return value;
  }
}

// Every field of an options table (femreg/field_table.h) by its scene key (a grouped one by
// its Python name, "outlier_neighbors": one flat object per section). A new row of the table
// appears here, and so in every file that writes the block, with no other change.
template <class Options>
nlohmann::ordered_json FieldsJson(const Options& o) {
  nlohmann::ordered_json j = nlohmann::ordered_json::object();
  OptionFields<Options>::Visit([&](auto member, const FieldInfo& f) {
    j[f.group != nullptr ? f.python_name() : f.key] = FieldJson(o.*member);
  });
  return j;
}

// Every field of the options, as the scene file names them (registration.*), after the
// scene, --set and command-line flags were applied.
nlohmann::ordered_json RegistrationOptionsJson(const RegistrationOptions& options);

// A material's fields by their table's keys (femreg/fem.h): {"youngs_modulus", ...}.
nlohmann::ordered_json MaterialJson(const Material& material);

// The scene's other options, every field of their tables (femreg/field_table.h) by its scene
// key: {"forward", "effects": {"fracture": {"enabled", ...}, "collision"}, "collision" (with
// "pairs" and "obstacles"), "materials": [per object], "objects" and "anchors" (each entry's
// name and table), "synth" (with "sensor", "motion" and "bodies"; null without a synth
// section)}.
nlohmann::ordered_json SceneOptionsJson(const Scene& scene);

// {"femreg_version", "scene": path, "overrides": [--set ...], "scene_resolved": the scene as
// YAML after the overrides (SceneToYaml: what differs from the defaults), "options": the
// resolved registration options, "scene_options" (SceneOptionsJson), "frame_files", "mask_dir" and "mask_files" (the depth
// frames' masks; null without), "ground_truth_files"}.
nlohmann::ordered_json ProvenanceJson(const Scene& scene, const RegistrationOptions& options,
                              const std::vector<std::string>& overrides,
                              const std::vector<std::string>& frame_files,
                              const std::vector<std::string>& truth_files);

}  // namespace results_internal
}  // namespace femreg

#endif  // FEMREG_RESULTS_PROVENANCE_H_
