#include "scene/yaml_reader.h"

#include <algorithm>
#include <cmath>
#include <set>
#include <sstream>

#include "io/text_tokens.h"

namespace femreg {
namespace scene_internal {

std::string Quote(const std::string& s) { return internal::Quoted(s); }

Status YamlErrorStatus(const std::string& source, const YAML::Exception& e) {
  std::ostringstream os;
  os << source;
  // yaml-cpp's mark is 0-based.
  if (!e.mark.is_null()) os << ":" << e.mark.line + 1 << ":" << e.mark.column + 1;
  os << ": " << e.msg;
  // yaml-cpp's parser messages name the grammar, not the mistake, which is most often the
  // indentation: a key indented unlike its siblings, a list item's '-' out of line.
  if (dynamic_cast<const YAML::ParserException*>(&e) != nullptr && e.msg.find("flow") == std::string::npos &&
      e.msg.find("quote") == std::string::npos) {
    os << " (YAML nests by indentation: check that this line and the one before it are indented "
          "like their siblings, with spaces, not tabs)";
  }
  return Status::Error(os.str());
}

int EditDistance(const std::string& a, const std::string& b) {
  std::vector<int> row(b.size() + 1);
  for (size_t j = 0; j <= b.size(); ++j) row[j] = static_cast<int>(j);
  for (size_t i = 1; i <= a.size(); ++i) {
    int diagonal = row[0];
    row[0] = static_cast<int>(i);
    for (size_t j = 1; j <= b.size(); ++j) {
      const int up = row[j];
      row[j] = std::min({row[j] + 1, row[j - 1] + 1, diagonal + (a[i - 1] == b[j - 1] ? 0 : 1)});
      diagonal = up;
    }
  }
  return row[b.size()];
}

std::string ClosestMatch(const std::string& word, const std::vector<std::string>& candidates) {
  std::string best;
  int best_distance = 1 << 30;
  for (const std::string& candidate : candidates) {
    int distance = EditDistance(word, candidate);
    // A prefix ("poisson" for "poisson_ratio") is a typo too.
    const bool prefix = word.size() >= 3 && (candidate.rfind(word, 0) == 0 ||
                                             word.rfind(candidate, 0) == 0);
    if (prefix) distance = std::min(distance, 1);
    if (distance < best_distance) {
      best_distance = distance;
      best = candidate;
    }
  }
  const int limit = std::max(2, static_cast<int>(word.size()) / 3);
  return best_distance <= limit ? best : std::string();
}

std::string JoinNames(const std::vector<std::string>& names) {
  std::string out;
  for (size_t i = 0; i < names.size(); ++i) {
    if (i > 0) out += ", ";
    out += names[i];
  }
  return out;
}

int YamlValue::line() const {
  if (node_.IsDefined()) {
    const YAML::Mark mark = node_.Mark();
    if (!mark.is_null()) return mark.line + 1;
  }
  return fallback_line_;
}

std::string YamlValue::Location() const {
  const int l = line();
  return l > 0 ? *source_ + ":" + std::to_string(l) : *source_;
}

void YamlValue::Fail(const std::string& message) const {
  const std::string where = Location();
  throw SceneError(path_.empty() ? where + ": " + message
                                 : where + ": " + path_ + ": " + message);
}

std::string YamlValue::Describe() const {
  if (!node_.IsDefined() || node_.IsNull()) return "nothing";
  if (node_.IsMap()) return "a map";
  if (node_.IsSequence()) return "a list of " + std::to_string(node_.size());
  return Quote(node_.Scalar());
}

void YamlValue::RequireMap() const {
  if (!node_.IsDefined() || !node_.IsMap()) Fail("must be a map of keys (got " + Describe() + ")");
}

void YamlValue::RequireSequence() const {
  if (!node_.IsDefined() || node_.IsNull()) return;
  if (!node_.IsSequence()) Fail("must be a list (got " + Describe() + ")");
}

void YamlValue::CheckKeys(const std::vector<std::string>& allowed) const {
  if (node_.IsDefined() && node_.IsNull()) return;  // "effects:" alone: an empty map
  RequireMap();
  std::set<std::string> seen;
  for (auto it = node_.begin(); it != node_.end(); ++it) {
    YamlValue key(it->first, path_, source_, line());
    if (!it->first.IsScalar()) key.Fail("keys must be names (got " + key.Describe() + ")");
    const std::string name = it->first.Scalar();
    const std::string key_path = path_.empty() ? name : path_ + "." + name;
    YamlValue named(it->first, key_path, source_, line());
    if (std::find(allowed.begin(), allowed.end(), name) == allowed.end()) {
      const std::string suggestion = ClosestMatch(name, allowed);
      if (!suggestion.empty()) {
        named.Fail("unknown key (did you mean " + Quote(suggestion) + "?)");
      }
      named.Fail("unknown key (allowed: " + JoinNames(allowed) + ")");
    }
    if (!seen.insert(name).second) named.Fail("duplicate key");
  }
}

bool YamlValue::Has(const std::string& key) const {
  if (!node_.IsDefined() || !node_.IsMap()) return false;
  const YAML::Node& self = node_;
  // A key written without a value ("density:") counts as present, so that it fails as
  // "must be a number (got nothing)" instead of being ignored.
  return self[key].IsDefined();
}

YamlValue YamlValue::operator[](const std::string& key) const {
  const std::string child_path = path_.empty() ? key : path_ + "." + key;
  if (!node_.IsDefined() || !node_.IsMap()) {
    return YamlValue(YAML::Node(YAML::NodeType::Undefined), child_path, source_, line());
  }
  const YAML::Node& self = node_;
  return YamlValue(self[key], child_path, source_, line());
}

int YamlValue::size() const {
  return node_.IsDefined() && node_.IsSequence() ? static_cast<int>(node_.size()) : 0;
}

YamlValue YamlValue::operator[](int i) const {
  const YAML::Node& self = node_;
  return YamlValue(self[static_cast<size_t>(i)], path_ + "[" + std::to_string(i) + "]", source_,
                   line());
}

double YamlValue::AsDouble() const {
  if (!node_.IsDefined() || !node_.IsScalar()) Fail("must be a number (got " + Describe() + ")");
  double value = 0.0;
  try {
    value = node_.as<double>();
  } catch (const YAML::Exception&) {
    Fail("must be a number (got " + Describe() + ")");
  }
  if (!std::isfinite(value)) Fail("must be a finite number (got " + Describe() + ")");
  return value;
}

int YamlValue::AsInt() const {
  if (!node_.IsDefined() || !node_.IsScalar()) {
    Fail("must be an integer (got " + Describe() + ")");
  }
  try {
    return node_.as<int>();
  } catch (const YAML::Exception&) {
  }
  // Accept integral values written as numbers (1e3, 10.0).
  double value = 0.0;
  try {
    value = node_.as<double>();
  } catch (const YAML::Exception&) {
    Fail("must be an integer (got " + Describe() + ")");
  }
  if (!std::isfinite(value) || value != std::floor(value) || std::fabs(value) > 2e9) {
    Fail("must be an integer (got " + Describe() + ")");
  }
  return static_cast<int>(value);
}

bool YamlValue::AsBool() const {
  if (!node_.IsDefined() || !node_.IsScalar()) Fail("must be true or false (got " + Describe() + ")");
  try {
    return node_.as<bool>();
  } catch (const YAML::Exception&) {
    Fail("must be true or false (got " + Describe() + ")");
  }
}

std::string YamlValue::AsString() const {
  if (!node_.IsDefined() || !node_.IsScalar()) Fail("must be a string (got " + Describe() + ")");
  return node_.Scalar();
}

Eigen::Vector3d YamlValue::AsVector3() const {
  if (!node_.IsDefined() || !node_.IsSequence() || node_.size() != 3) {
    Fail("must be a list of 3 numbers [x, y, z] (got " + Describe() + ")");
  }
  Eigen::Vector3d v;
  for (int i = 0; i < 3; ++i) v[i] = (*this)[i].AsDouble();
  return v;
}

Eigen::Vector3i YamlValue::AsVector3i() const {
  if (!node_.IsDefined() || !node_.IsSequence() || node_.size() != 3) {
    Fail("must be a list of 3 integers (got " + Describe() + ")");
  }
  Eigen::Vector3i v;
  for (int i = 0; i < 3; ++i) v[i] = (*this)[i].AsInt();
  return v;
}

std::vector<int> YamlValue::AsIntList() const {
  if (!node_.IsDefined() || !node_.IsSequence()) {
    Fail("must be a list of integers (got " + Describe() + ")");
  }
  std::vector<int> values;
  for (int i = 0; i < size(); ++i) values.push_back((*this)[i].AsInt());
  return values;
}

}  // namespace scene_internal
}  // namespace femreg
