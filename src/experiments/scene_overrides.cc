// --set key.path=value: overrides applied to a scene's YAML document before the scene parser
// runs, so that an overridden value is checked exactly like one written in the file.
#include <yaml-cpp/yaml.h>

#include <cctype>
#include <string>
#include <vector>

#include "femreg/experiment.h"
#include "scene/scene_parser.h"
#include "scene/yaml_reader.h"

namespace femreg {
namespace {

// One step of a key path: a map key, or a list index.
struct KeyStep {
  std::string key;
  int index = -1;  // >= 0: a list entry
};

// "objects[0].material.youngs_modulus" -> objects, [0], material, youngs_modulus.
Status SplitKey(const std::string& key, std::vector<KeyStep>* steps) {
  steps->clear();
  const std::string where = "--set " + key + ": ";
  size_t i = 0;
  bool expect_name = true;
  while (i < key.size()) {
    if (key[i] == '[') {
      const size_t close = key.find(']', i);
      if (close == std::string::npos || close == i + 1) {
        return Status::Error(where + "a list index is written [N] (at character " +
                             std::to_string(i + 1) + ")");
      }
      const std::string digits = key.substr(i + 1, close - i - 1);
      for (char c : digits) {
        if (!std::isdigit(static_cast<unsigned char>(c))) {
          return Status::Error(where + "list index '" + digits + "' is not a number >= 0");
        }
      }
      if (steps->empty() || digits.size() > 6) {
        return Status::Error(where + "list index [" + digits + "] needs a list key before it and "
                             "at most 6 digits");
      }
      KeyStep step;
      step.index = std::stoi(digits);
      steps->push_back(step);
      i = close + 1;
      expect_name = false;
      if (i < key.size() && key[i] != '.' && key[i] != '[') {
        return Status::Error(where + "expected '.' or '[' after ']' (at character " +
                             std::to_string(i + 1) + ")");
      }
      continue;
    }
    if (key[i] == '.') {
      if (expect_name) return Status::Error(where + "empty key between dots");
      expect_name = true;
      ++i;
      continue;
    }
    size_t end = i;
    while (end < key.size() && key[end] != '.' && key[end] != '[') ++end;
    KeyStep step;
    step.key = key.substr(i, end - i);
    steps->push_back(step);
    expect_name = false;
    i = end;
  }
  if (steps->empty() || expect_name) return Status::Error(where + "empty key");
  return Status::Ok();
}

// A deep copy of `node` without source marks: the parser then locates an overridden value at
// its parent's line in the file, and the message gets the --set that gave it.
YAML::Node Unmarked(const YAML::Node& node) {
  switch (node.Type()) {
    case YAML::NodeType::Scalar: {
      YAML::Node out(node.Scalar());
      return out;
    }
    case YAML::NodeType::Sequence: {
      YAML::Node out(YAML::NodeType::Sequence);
      for (const YAML::Node& child : node) out.push_back(Unmarked(child));
      return out;
    }
    case YAML::NodeType::Map: {
      YAML::Node out(YAML::NodeType::Map);
      for (const auto& kv : node) out[kv.first.Scalar()] = Unmarked(kv.second);
      return out;
    }
    default:
      return YAML::Node(YAML::NodeType::Null);
  }
}

// The path of steps[0..n) as the parser names keys.
std::string PathText(const std::vector<KeyStep>& steps, size_t n) {
  std::string out;
  for (size_t i = 0; i < n; ++i) {
    if (steps[i].index >= 0) {
      out += "[" + std::to_string(steps[i].index) + "]";
    } else {
      out += (out.empty() ? "" : ".") + steps[i].key;
    }
  }
  return out;
}

// Sets steps[i..] below `node` (a handle: writes go to the document) to `value`.
// *created: the number of steps up to the first key this added (the whole path when it only
// replaced a value), for naming the --set in errors.
Status SetAt(YAML::Node node, const std::vector<KeyStep>& steps, size_t i, const YAML::Node& value,
             const SceneOverride& o, size_t* created) {
  const KeyStep& step = steps[i];
  const bool last = i + 1 == steps.size();
  const std::string where = "--set " + o.Text() + ": ";
  if (step.index >= 0) {
    if (!node.IsSequence()) {
      return Status::Error(where + PathText(steps, i) + " is not a list in the scene");
    }
    if (step.index >= static_cast<int>(node.size())) {
      return Status::Error(where + PathText(steps, i) + " has " + std::to_string(node.size()) +
                           " entries; [" + std::to_string(step.index) + "] does not exist");
    }
    if (last) {
      node[static_cast<size_t>(step.index)] = value;
      return Status::Ok();
    }
    YAML::Node child = node[static_cast<size_t>(step.index)];
    return SetAt(child, steps, i + 1, value, o, created);
  }
  if (node.IsNull() || !node.IsDefined()) {
    node = YAML::Node(YAML::NodeType::Map);  // an empty section ("registration:") or a new one
  }
  if (!node.IsMap()) {
    return Status::Error(where + (i == 0 ? std::string("the scene") : PathText(steps, i)) +
                         " is " + (node.IsSequence() ? "a list (index it with [N])" : "a value") +
                         ", not a map with key '" + step.key + "'");
  }
  if (!node[step.key].IsDefined() && *created == steps.size()) *created = i + 1;
  if (last) {
    node[step.key] = value;
    return Status::Ok();
  }
  if (!node[step.key].IsDefined() || node[step.key].IsNull()) {
    node[step.key] = YAML::Node(YAML::NodeType::Map);
  }
  YAML::Node child = node[step.key];
  return SetAt(child, steps, i + 1, value, o, created);
}

// Parser errors name "source:line: key.path: ..."; an error at an overridden key (or below
// it) gets the --set that gave the value.
std::string Attribute(const std::string& message, const std::vector<SceneOverride>& overrides,
                      const std::vector<std::string>& paths) {
  for (size_t k = overrides.size(); k-- > 0;) {
    const std::string& p = paths[k];
    for (const char* suffix : {": ", ".", "["}) {
      if (message.find(" " + p + suffix) != std::string::npos) {
        return message + " (from --set " + overrides[k].Text() + ")";
      }
    }
  }
  return message;
}

}  // namespace

Status ParseSceneOverride(const std::string& text, SceneOverride* override_out) {
  const size_t eq = text.find('=');
  if (eq == std::string::npos || eq == 0) {
    return Status::Error("--set " + text + ": expected key.path=value, e.g. "
                         "registration.solver.backend=fast");
  }
  SceneOverride o;
  o.key = text.substr(0, eq);
  o.value = text.substr(eq + 1);
  std::vector<KeyStep> steps;
  Status status = SplitKey(o.key, &steps);
  if (!status.ok()) return status;
  *override_out = o;
  return Status::Ok();
}

Status LoadSceneWithOverrides(const std::string& path, const std::vector<SceneOverride>& overrides,
                              Scene* scene) {
  if (overrides.empty()) return LoadScene(path, scene);
  std::string text, base_dir;
  const Status read = scene_internal::ReadSceneText(path, &text, &base_dir);
  if (!read.ok()) return read;

  std::vector<std::string> paths;
  Scene parsed;
  parsed.path = path;
  try {
    YAML::Node root = YAML::Load(text);
    for (const SceneOverride& o : overrides) {
      std::vector<KeyStep> steps;
      Status status = SplitKey(o.key, &steps);
      if (!status.ok()) return status;
      YAML::Node value;
      try {
        value = Unmarked(YAML::Load(o.value));
      } catch (const YAML::Exception& e) {
        return Status::Error("--set " + o.Text() + ": the value is not valid YAML: " + e.msg);
      }
      if (!root.IsDefined() || root.IsNull()) root = YAML::Node(YAML::NodeType::Map);
      size_t created = steps.size();
      status = SetAt(root, steps, 0, value, o, &created);
      if (!status.ok()) return status;
      paths.push_back(PathText(steps, created));
    }
    scene_internal::SceneParser parser(path, base_dir, &parsed);
    parser.Parse(root);
  } catch (const scene_internal::SceneError& e) {
    return Status::Error(Attribute(e.what(), overrides, paths));
  } catch (const YAML::Exception& e) {
    return scene_internal::YamlErrorStatus(path, e);
  }
  *scene = std::move(parsed);
  return Status::Ok();
}

}  // namespace femreg
