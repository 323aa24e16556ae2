// What a run's summary.json records so that the run can be told apart and repeated: the
// version, the resolved options, the inputs.
#ifndef FEMREG_RESULTS_PROVENANCE_H_
#define FEMREG_RESULTS_PROVENANCE_H_

#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "femreg/registration.h"
#include "femreg/scene.h"

namespace femreg {
namespace results_internal {

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
