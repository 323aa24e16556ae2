// The synth artefacts by name: one table that the scene parser, the scene writer and
// `femreg synth --artefact` share, so the three spell every artefact and key the same.
#include <cmath>
#include <cstdlib>
#include <sstream>
#include <string>
#include <vector>

#include "femreg/scene.h"

namespace femreg {

namespace {

#define FEMREG_SENSOR_KEY(artefact, key, field, realistic, lo, hi)                      \
  SynthArtefactKey {                                                                     \
    artefact, key, realistic, lo, hi, false,                                             \
        [](const SynthSpec& s) { return s.sensor.artefacts.field; },                     \
        [](SynthSpec* s, double v) { s->sensor.artefacts.field = v; }                    \
  }

std::vector<SynthArtefactKey> MakeKeys() {
  return {
      FEMREG_SENSOR_KEY("flying_pixels", "fraction", flying_fraction, 0.5, 0, 1),
      FEMREG_SENSOR_KEY("flying_pixels", "jump", flying_jump, 0.02, 1e-6, 10),
      FEMREG_SENSOR_KEY("quantisation", "step", disparity_step, 0.125, 0, 10),
      FEMREG_SENSOR_KEY("quantisation", "baseline", baseline, 0.075, 1e-4, 10),
      FEMREG_SENSOR_KEY("dark_holes", "fraction", dark_fraction, 0.05, 0, 1),
      FEMREG_SENSOR_KEY("dark_holes", "radius", dark_radius, 0.01, 1e-5, 10),
      FEMREG_SENSOR_KEY("specular_holes", "angle_deg", specular_angle_deg, 5, 0, 90),
      FEMREG_SENSOR_KEY("grazing_holes", "angle_deg", grazing_holes_deg, 65, 0, 90),
      FEMREG_SENSOR_KEY("grazing_holes", "blob_px", hole_blob_px, 6, 1, 1e4),
      FEMREG_SENSOR_KEY("multipath", "bias", multipath_bias, 0.003, 0, 1),
      FEMREG_SENSOR_KEY("multipath", "radius", multipath_radius, 0.03, 1e-4, 10),
      FEMREG_SENSOR_KEY("flicker", "offset", flicker_offset, 0.001, 0, 1),
      FEMREG_SENSOR_KEY("flicker_dropout", "fraction", flicker_dropout, 0.02, 0, 1),
      {"occluder", "radius", 0.03, 0, 10, false,
       [](const SynthSpec& s) { return s.occluder_radius; },
       [](SynthSpec* s, double v) { s->occluder_radius = v; }},
      {"occluder", "standoff", 0.03, 0, 10, false,
       [](const SynthSpec& s) { return s.occluder_standoff; },
       [](SynthSpec* s, double v) { s->occluder_standoff = v; }},
      {"leave_view", "frames", 5, 0, 1e6, true,
       [](const SynthSpec& s) { return static_cast<double>(s.leave_frames); },
       [](SynthSpec* s, double v) { s->leave_frames = static_cast<int>(v); }},
      {"leave_view", "start", -1, -1, 1e6, true,
       [](const SynthSpec& s) { return static_cast<double>(s.leave_start); },
       [](SynthSpec* s, double v) { s->leave_start = static_cast<int>(v); }},
  };
}

#undef FEMREG_SENSOR_KEY

std::string Number(double v) {
  std::ostringstream os;
  os << v;
  return os.str();
}

Status SetKey(const SynthArtefactKey& k, double value, SynthSpec* synth) {
  if (!(value >= k.min && value <= k.max) || (k.integer && value != std::floor(value))) {
    return Status::Error(std::string(k.artefact) + "." + k.key + " must be " +
                         (k.integer ? "an integer " : "") + "in [" + Number(k.min) + ", " +
                         Number(k.max) + "] (got " + Number(value) + ")");
  }
  k.set(synth, value);
  return Status::Ok();
}

}  // namespace

const std::vector<SynthArtefactKey>& SynthArtefactKeys() {
  static const std::vector<SynthArtefactKey> keys = MakeKeys();
  return keys;
}

Status SetSynthArtefact(const std::string& spec, SynthSpec* synth) {
  const std::vector<SynthArtefactKey>& keys = SynthArtefactKeys();
  if (spec == "all") {
    for (const SynthArtefactKey& k : keys) k.set(synth, k.realistic);
    return Status::Ok();
  }
  const size_t eq = spec.find('=');
  const std::string lhs = spec.substr(0, eq);
  const size_t dot = lhs.find('.');
  const std::string name = lhs.substr(0, dot);
  const std::string key = dot == std::string::npos ? "" : lhs.substr(dot + 1);
  std::string names;
  bool known = false;
  for (const SynthArtefactKey& k : keys) {
    if (names.find(std::string(k.artefact) + ",") == std::string::npos) {
      names += std::string(k.artefact) + ", ";
    }
    known = known || name == k.artefact;
  }
  if (!known) {
    return Status::Error("unknown artefact '" + name + "' (one of: " + names + "all)");
  }
  if (eq == std::string::npos) {
    if (!key.empty()) return Status::Error("'" + spec + "' needs a value: " + lhs + "=VALUE");
    for (const SynthArtefactKey& k : keys) {
      if (name == k.artefact) k.set(synth, k.realistic);
    }
    return Status::Ok();
  }
  const std::string text = spec.substr(eq + 1);
  char* end = nullptr;
  const double value = std::strtod(text.c_str(), &end);
  if (text.empty() || end == nullptr || *end != '\0') {
    return Status::Error("'" + spec + "': '" + text + "' is not a number");
  }
  return SetSynthArtefactValue(name, key, value, synth);
}

Status SetSynthArtefactValue(const std::string& artefact, const std::string& key, double value,
                             SynthSpec* synth) {
  const std::vector<SynthArtefactKey>& keys = SynthArtefactKeys();
  bool first = true;
  std::string known_keys;
  for (const SynthArtefactKey& k : keys) {
    if (artefact != k.artefact) continue;
    if ((key.empty() && first) || key == k.key) return SetKey(k, value, synth);
    first = false;
    known_keys += (known_keys.empty() ? "" : ", ") + std::string(k.key);
  }
  if (first) return Status::Error("unknown artefact '" + artefact + "'");
  return Status::Error("artefact " + artefact + " has no key '" + key + "' (one of: " +
                       known_keys + ")");
}

std::string SynthArtefactSummary(const SynthSpec& synth) {
  const std::vector<SynthArtefactKey>& keys = SynthArtefactKeys();
  std::string out;
  for (size_t i = 0; i < keys.size(); ++i) {
    // The first key of each artefact is its strength: 0 means off.
    if (i > 0 && std::string(keys[i - 1].artefact) == keys[i].artefact) continue;
    if (keys[i].get(synth) == 0) continue;
    out += (out.empty() ? "" : "; ") + std::string(keys[i].artefact);
    for (size_t j = i; j < keys.size() && std::string(keys[j].artefact) == keys[i].artefact; ++j) {
      out += std::string(" ") + keys[j].key + " " + Number(keys[j].get(synth));
    }
  }
  return out;
}

}  // namespace femreg
