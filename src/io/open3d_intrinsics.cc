// Open3D's PinholeCameraIntrinsic as JSON (open3d.io.write_pinhole_camera_intrinsic):
// {"width": W, "height": H, "intrinsic_matrix": [fx, 0, 0, 0, fy, 0, cx, cy, 1]}, the
// matrix column-major. Parsed with nlohmann/json.
#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstring>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>

#include "femreg/camera_io.h"
#include "femreg/io.h"
#include "io/io_internal.h"
#include "io/text_tokens.h"

namespace femreg {
namespace {

using json = nlohmann::json;

using internal::ExactNumber;

// What a JSON value is, for "got ..." parts (containers by their size: dumping a deeply
// nested one would recurse as deep).
std::string Describe(const json& v) {
  if (v.is_number()) return ExactNumber(v.get<double>());
  if (v.is_string()) return "the string " + internal::Quoted(v.get<std::string>());
  if (v.is_array()) return "a list of " + std::to_string(v.size()) + " values";
  if (v.is_object()) return "an object";
  if (v.is_boolean()) return v.get<bool>() ? "true" : "false";
  return "null";
}

// Why a JSON value is not a positive integer ("" when it is one that fits an int).
std::string NotPositiveInt(const json& v, int* out) {
  if (!v.is_number()) return "must be a positive integer (got " + Describe(v) + ")";
  const double d = v.get<double>();
  if (!(d >= 1) || d > 1e9 || std::floor(d) != d) return "must be a positive integer (got " + ExactNumber(d) + ")";
  *out = static_cast<int>(d);
  return "";
}

}  // namespace

Status ReadOpen3dIntrinsics(const std::string& path, PinholeIntrinsics* intrinsics) {
  using internal::FileError;
  std::string text;
  if (Status read = internal::ReadSmallFile(path, internal::kMaxIntrinsicsBytes, "an intrinsics file", &text); !read.ok()) return read;

  json doc;
  try {
    doc = json::parse(text);
  } catch (const json::exception& e) {
    // e.what(): "[json.exception.parse_error.101] parse error at line 3, column 2: ...", or
    // "[json.exception.out_of_range.406] number overflow parsing '1e999'"; keep what follows
    // the tag, capped (the last token read may be long). A syntax error has its line.
    std::string what = e.what();
    const size_t tag = what.find("] ");
    if (tag != std::string::npos) what = what.substr(tag + 2);
    int line = 0;
    if (const auto* syntax = dynamic_cast<const json::parse_error*>(&e)) {
      const size_t at = std::min<size_t>(syntax->byte > 0 ? syntax->byte - 1 : 0, text.size());
      line = 1 + static_cast<int>(std::count(text.begin(), text.begin() + at, '\n'));
    }
    return FileError(path, line, "not JSON: " + internal::Quoted(what, 200));
  }
  if (!doc.is_object()) {
    return FileError(path, 0, "must be a JSON object with width, height and intrinsic_matrix "
                              "(Open3D's PinholeCameraIntrinsic)");
  }
  PinholeIntrinsics k;
  for (const char* key : {"width", "height"}) {
    if (!doc.contains(key)) return FileError(path, 0, std::string(key) + ": missing");
    const std::string why = NotPositiveInt(doc[key], key[0] == 'w' ? &k.width : &k.height);
    if (!why.empty()) return FileError(path, 0, std::string(key) + ": " + why);
  }
  if (!doc.contains("intrinsic_matrix")) return FileError(path, 0, "intrinsic_matrix: missing");
  const json& m = doc["intrinsic_matrix"];
  if (!m.is_array() || m.size() != 9) {
    return FileError(path, 0, "intrinsic_matrix: must be a list of 9 numbers, the 3x3 matrix "
                              "column by column (got " + Describe(m) + ")");
  }
  double a[9];
  for (int i = 0; i < 9; ++i) {
    if (!m[i].is_number() || !std::isfinite(m[i].get<double>())) {
      return FileError(path, 0, "intrinsic_matrix[" + std::to_string(i) + "]: must be a finite number (got " +
                                    Describe(m[i]) + ")");
    }
    a[i] = m[i].get<double>();
  }
  // Column-major: a[0] = fx, a[4] = fy, a[6] = cx, a[7] = cy, a[8] = 1; a[3] is the skew.
  if ((a[2] != 0 || a[5] != 0) && a[6] == 0 && a[7] == 0) {
    return FileError(path, 0, "intrinsic_matrix: cx and cy are at [2] and [5], where a row-major "
                              "matrix has them; Open3D writes the matrix column by column, "
                              "[fx, 0, 0, 0, fy, 0, cx, cy, 1]");
  }
  const char* names[9] = {"fx", "", "", "the skew", "fy", "", "cx", "cy", ""};
  for (int i : {0, 4}) {
    if (!(a[i] > 0)) {
      return FileError(path, 0, "intrinsic_matrix[" + std::to_string(i) + "] (" + names[i] +
                                    "): must be > 0 (got " + ExactNumber(a[i]) + ")");
    }
  }
  for (int i : {1, 2, 3, 5}) {
    if (a[i] != 0) {
      return FileError(path, 0, "intrinsic_matrix[" + std::to_string(i) + "]" +
                                    (names[i][0] ? std::string(" (") + names[i] + ")" : std::string()) +
                                    ": must be 0 in a pinhole matrix [fx, 0, 0, 0, fy, 0, cx, cy, 1] "
                                    "(got " + ExactNumber(a[i]) + ")");
    }
  }
  if (a[8] != 1) {
    return FileError(path, 0, "intrinsic_matrix[8]: must be 1 (got " + ExactNumber(a[8]) + ")");
  }
  k.fx = a[0];
  k.fy = a[4];
  k.cx = a[6];
  k.cy = a[7];
  *intrinsics = k;
  return Status::Ok();
}

Status WriteOpen3dIntrinsics(const std::string& path, const PinholeIntrinsics& k) {
  if (k.width <= 0 || k.height <= 0 || !(k.fx > 0) || !(k.fy > 0) || !std::isfinite(k.fx) ||
      !std::isfinite(k.fy) || !std::isfinite(k.cx) || !std::isfinite(k.cy)) {
    return internal::FileError(path, 0, "intrinsics need width, height, fx and fy > 0 and finite cx, cy");
  }
  json doc;
  doc["width"] = k.width;
  doc["height"] = k.height;
  doc["intrinsic_matrix"] = {k.fx, 0.0, 0.0, 0.0, k.fy, 0.0, k.cx, k.cy, 1.0};
  return WriteFileAtomically(path, doc.dump(1, '\t') + "\n");
}

}  // namespace femreg
