// Typed, located access to a YAML document: every error names the source, the 1-based
// line and the key path ("beam.yaml:14: objects[0].material.poisson_ratio: ...").
#ifndef FEMREG_SCENE_YAML_READER_H_
#define FEMREG_SCENE_YAML_READER_H_

#include <yaml-cpp/yaml.h>

#include <Eigen/Core>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include "femreg/status.h"

namespace femreg {
namespace scene_internal {

// Thrown by the reader and caught at the API boundary (ParseScene), where it becomes a
// Status; yaml-cpp throws as well, so the parser is written exception-safe anyway.
class SceneError : public std::runtime_error {
 public:
  explicit SceneError(const std::string& message) : std::runtime_error(message) {}
};

// What yaml-cpp threw (a syntax error in the document) as a Status naming the source and,
// when yaml-cpp knows it, the 1-based line and column: "beam.yaml:3:7: illegal map value".
Status YamlErrorStatus(const std::string& source, const YAML::Exception& e);

// Edit distance, for "did you mean" suggestions.
int EditDistance(const std::string& a, const std::string& b);

// A value from the file for a message, in quotes: whole up to 80 characters, else its first
// 80 and its length, so that a 4 MB value (or a whole document) is not echoed whole.
std::string Quote(const std::string& s);
// The candidate closest to `word` when it looks like a typo of it, else "".
std::string ClosestMatch(const std::string& word, const std::vector<std::string>& candidates);
// "a, b, c".
std::string JoinNames(const std::vector<std::string>& names);

// A node together with its key path and the source it came from.
class YamlValue {
 public:
  // fallback_line: reported when the node has no position (a missing key: the parent's).
  YamlValue(YAML::Node node, std::string path, const std::string* source, int fallback_line = 0)
      : node_(std::move(node)), path_(std::move(path)), source_(source),
        fallback_line_(fallback_line) {}

  const YAML::Node& node() const { return node_; }
  const std::string& path() const { return path_; }
  const std::string& source() const { return *source_; }
  int line() const;  // 1-based; 0 when unknown
  // "beam.yaml:14"
  std::string Location() const;
  // "beam.yaml:14: objects[0].x: message"
  [[noreturn]] void Fail(const std::string& message) const;

  bool IsMap() const { return node_.IsMap(); }
  bool IsSequence() const { return node_.IsSequence(); }
  bool IsNull() const { return !node_.IsDefined() || node_.IsNull(); }

  // Requires a map whose keys are all in `allowed` (no duplicates). A key that is not
  // allowed fails at its own line with the closest allowed key as a suggestion.
  void CheckKeys(const std::vector<std::string>& allowed) const;
  // The map entry `key` (the value may be undefined: check Has).
  bool Has(const std::string& key) const;
  YamlValue operator[](const std::string& key) const;
  // The sequence element i.
  int size() const;
  YamlValue operator[](int i) const;
  // Requires a sequence (a missing or null node counts as empty).
  void RequireSequence() const;
  void RequireMap() const;

  // Scalars. Each fails with "must be a number (got 'abc')" and the like.
  double AsDouble() const;
  int AsInt() const;
  bool AsBool() const;
  std::string AsString() const;
  // A list of exactly 3 numbers.
  Eigen::Vector3d AsVector3() const;
  Eigen::Vector3i AsVector3i() const;
  // A list of integers of any length.
  std::vector<int> AsIntList() const;

 private:
  std::string Describe() const;  // what the node is, for "got ..." parts
  YAML::Node node_;
  std::string path_;
  const std::string* source_;
  int fallback_line_ = 0;
};

}  // namespace scene_internal
}  // namespace femreg

#endif  // FEMREG_SCENE_YAML_READER_H_
