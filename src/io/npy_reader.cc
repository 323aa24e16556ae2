// Depth images saved by numpy.save (.npy, format versions 1-3). The header is a Python dict
// literal, {'descr': '<f4', 'fortran_order': False, 'shape': (480, 640), }, parsed here as
// one (keys in any order, either quote), not matched as text.
#include <cerrno>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <map>
#include <string>
#include <vector>

#include "femreg/camera_io.h"
#include "io/io_internal.h"
#include "io/text_tokens.h"

namespace femreg {
namespace {

// 2^28 pixels, as for PNG depth images.
constexpr double kMaxPixels = 268435456.0;

// One value of the header dict.
struct HeaderValue {
  enum Kind { kString, kBool, kTuple } kind = kString;
  std::string text;              // kString
  bool flag = false;             // kBool
  std::vector<long long> items;  // kTuple
};

// A recursive-descent reader of the header's dict literal. Errors are "npy header, byte N:
// ..." (N counted from the start of the file) or name the key.
class HeaderParser {
 public:
  HeaderParser(const std::string& text, size_t file_offset) : s_(text), base_(file_offset) {}

  bool Parse(std::map<std::string, HeaderValue>* dict, std::string* error) {
    SkipSpace();
    if (!Take('{')) return Fail("expected '{' (the header is a Python dict)", error);
    for (;;) {
      SkipSpace();
      if (Take('}')) break;
      std::string key;
      if (!ParseString(&key)) return Fail("expected a quoted key or '}'", error);
      SkipSpace();
      if (!Take(':')) return Fail("expected ':' after the key " + internal::Quoted(key), error);
      SkipSpace();
      HeaderValue value;
      if (!ParseValue(&value, error)) return false;
      if (!dict->emplace(key, value).second) return Fail("the key " + internal::Quoted(key) + " twice", error);
      SkipSpace();
      if (Take(',')) continue;
      if (Take('}')) break;
      return Fail("expected ',' or '}'", error);
    }
    SkipSpace();
    if (pos_ != s_.size()) return Fail("text after the dict", error);
    return true;
  }

 private:
  bool Fail(const std::string& message, std::string* error) const {
    *error = "npy header, byte " + std::to_string(base_ + pos_) + ": " + message;
    return false;
  }
  void SkipSpace() {
    while (pos_ < s_.size() && (s_[pos_] == ' ' || s_[pos_] == '\t' || s_[pos_] == '\n' || s_[pos_] == '\r')) ++pos_;
  }
  bool Take(char c) {
    if (pos_ < s_.size() && s_[pos_] == c) {
      ++pos_;
      return true;
    }
    return false;
  }
  bool Word(const char* w) {
    const size_t n = std::strlen(w);
    if (s_.compare(pos_, n, w) != 0) return false;
    pos_ += n;
    return true;
  }
  // 'text' or "text"; escapes are not needed by any key or dtype of a depth image.
  bool ParseString(std::string* out) {
    if (pos_ >= s_.size() || (s_[pos_] != '\'' && s_[pos_] != '"')) return false;
    const char quote = s_[pos_];
    const size_t end = s_.find(quote, pos_ + 1);
    if (end == std::string::npos) return false;
    *out = s_.substr(pos_ + 1, end - pos_ - 1);
    pos_ = end + 1;
    return true;
  }
  bool ParseValue(HeaderValue* v, std::string* error) {
    if (pos_ < s_.size() && (s_[pos_] == '\'' || s_[pos_] == '"')) {
      v->kind = HeaderValue::kString;
      if (!ParseString(&v->text)) return Fail("an unterminated string", error);
      return true;
    }
    if (Word("True") || Word("False")) {
      v->kind = HeaderValue::kBool;
      v->flag = s_[pos_ - 4] == 'T';  // "True" ends here; "False" ends in "alse"
      return true;
    }
    if (Take('(')) {
      v->kind = HeaderValue::kTuple;
      for (;;) {
        SkipSpace();
        if (Take(')')) return true;
        const size_t start = pos_;
        while (pos_ < s_.size() && s_[pos_] >= '0' && s_[pos_] <= '9') ++pos_;
        if (pos_ == start) return Fail("expected a dimension (a non-negative integer) or ')'", error);
        if (pos_ - start > 12) return Fail("a dimension of more than 12 digits", error);
        v->items.push_back(std::stoll(s_.substr(start, pos_ - start)));
        Take('L');  // Python 2's long integers, in files numpy wrote long ago
        SkipSpace();
        if (Take(',')) continue;
        if (Take(')')) return true;
        return Fail("expected ',' or ')' in the shape", error);
      }
    }
    if (pos_ < s_.size() && s_[pos_] == '[') {
      return Fail("a structured dtype (a list of fields): not a depth image", error);
    }
    return Fail("expected a string, True, False or a tuple", error);
  }

  const std::string& s_;
  size_t base_;
  size_t pos_ = 0;
};

uint64_t LoadUnsigned(const unsigned char* p, int size, bool big_endian) {
  uint64_t v = 0;
  for (int k = 0; k < size; ++k) {
    const int byte = big_endian ? k : size - 1 - k;
    v = (v << 8) | p[byte];
  }
  return v;
}

}  // namespace

Status ReadDepthNpy(const std::string& path, RawDepthImage* image) {
  using internal::FileError;
  std::ifstream in(path, std::ios::binary);
  if (!in) return FileError(path, 0, std::string("cannot open: ") + std::strerror(errno));
  std::error_code ec;
  const uintmax_t file_size = std::filesystem::file_size(path, ec);
  if (ec) return FileError(path, 0, "cannot read its size: " + ec.message());

  // Magic, version, header length.
  unsigned char lead[12] = {0};
  in.read(reinterpret_cast<char*>(lead), 10);
  if (in.gcount() < 10 || std::memcmp(lead, "\x93NUMPY", 6) != 0) {
    return FileError(path, 0, "not a NumPy .npy file (no \\x93NUMPY magic in the first 6 bytes)");
  }
  const int major = lead[6], minor = lead[7];
  if (major < 1 || major > 3) {
    return FileError(path, 0, "npy format version " + std::to_string(major) + "." +
                                  std::to_string(minor) + ": only versions 1, 2 and 3 are read");
  }
  size_t prefix = 10;
  uint64_t header_len = LoadUnsigned(lead + 8, 2, false);
  if (major >= 2) {
    in.read(reinterpret_cast<char*>(lead + 10), 2);
    if (in.gcount() < 2) return FileError(path, 0, "the file ends inside the npy header length");
    header_len = LoadUnsigned(lead + 8, 4, false);
    prefix = 12;
  }
  if (header_len > file_size - prefix) {
    return FileError(path, 0, "npy header length " + std::to_string(header_len) + " at byte " +
                                  std::to_string(prefix - (major >= 2 ? 4 : 2)) + ": beyond the file's " +
                                  std::to_string(file_size) + " bytes");
  }
  std::string header(static_cast<size_t>(header_len), '\0');
  in.read(&header[0], static_cast<std::streamsize>(header_len));
  if (static_cast<uint64_t>(in.gcount()) != header_len) return FileError(path, 0, "cannot read the npy header");

  std::map<std::string, HeaderValue> dict;
  std::string error;
  if (!HeaderParser(header, prefix).Parse(&dict, &error)) return FileError(path, 0, error);
  for (const char* key : {"descr", "fortran_order", "shape"}) {
    if (!dict.count(key)) return FileError(path, 0, std::string("npy header: no '") + key + "' key");
  }
  if (dict.size() != 3) {
    for (const auto& entry : dict) {
      if (entry.first != "descr" && entry.first != "fortran_order" && entry.first != "shape") {
        return FileError(path, 0, "npy header: unknown key " + internal::Quoted(entry.first) +
                                      " (a .npy header has descr, fortran_order and shape)");
      }
    }
  }
  const HeaderValue& descr = dict["descr"];
  const HeaderValue& fortran = dict["fortran_order"];
  const HeaderValue& shape = dict["shape"];
  if (descr.kind != HeaderValue::kString) return FileError(path, 0, "npy header: descr: must be a string");
  if (fortran.kind != HeaderValue::kBool) {
    return FileError(path, 0, "npy header: fortran_order: must be True or False");
  }
  if (shape.kind != HeaderValue::kTuple) return FileError(path, 0, "npy header: shape: must be a tuple");

  // The dtype: float32 / float64 metres or uint16 units, either byte order.
  const std::string& d = descr.text;
  const bool known = d.size() == 3 && (d[0] == '<' || d[0] == '>') &&
                     (d.substr(1) == "f4" || d.substr(1) == "f8" || d.substr(1) == "u2");
  if (!known) {
    return FileError(path, 0, "npy header: descr " + internal::Quoted(d) +
                                  ": a depth image is float32 or float64 metres ('<f4', '<f8') "
                                  "or uint16 depth units ('<u2')");
  }
  const bool big_endian = d[0] == '>';
  const bool is_float = d[1] == 'f';
  const int item = d[2] - '0';

  std::string dims = "(";
  for (size_t k = 0; k < shape.items.size(); ++k) dims += (k ? ", " : "") + std::to_string(shape.items[k]);
  dims += shape.items.size() == 1 ? ",)" : ")";
  if (shape.items.size() != 2) {
    return FileError(path, 0, "npy header: shape " + dims + ": a depth image is (height, width)");
  }
  const long long h = shape.items[0], w = shape.items[1];
  if (h < 1 || w < 1) return FileError(path, 0, "npy header: shape " + dims + ": an empty image");
  if (static_cast<double>(h) * static_cast<double>(w) > kMaxPixels) {
    return FileError(path, 0, "npy header: shape " + dims + ": too large (at most 2^28 pixels)");
  }
  const uint64_t n = static_cast<uint64_t>(h) * static_cast<uint64_t>(w);
  const uint64_t data_offset = prefix + header_len;
  const uint64_t have = file_size - data_offset;
  if (have != n * static_cast<uint64_t>(item)) {
    return FileError(path, 0, "the data from byte " + std::to_string(data_offset) + " has " +
                                  std::to_string(have) + " bytes; shape " + dims + " of '" + d +
                                  "' needs " + std::to_string(n * item) +
                                  (have < n * static_cast<uint64_t>(item) ? " (truncated)" : ""));
  }
  std::vector<unsigned char> data(static_cast<size_t>(n * item));
  in.read(reinterpret_cast<char*>(data.data()), static_cast<std::streamsize>(data.size()));
  if (static_cast<uint64_t>(in.gcount()) != data.size()) return FileError(path, 0, "cannot read the data");

  image->width = static_cast<int>(w);
  image->height = static_cast<int>(h);
  image->values.clear();
  image->metres.clear();
  if (is_float) {
    image->metres.resize(static_cast<size_t>(n));
  } else {
    image->values.resize(static_cast<size_t>(n));
  }
  // Element k of the file is pixel (row, column) = (k / w, k % w) in C order, (k % h, k / h)
  // in Fortran order.
  for (uint64_t k = 0; k < n; ++k) {
    const uint64_t row = fortran.flag ? k % h : k / w;
    const uint64_t col = fortran.flag ? k / h : k % w;
    const size_t pixel = static_cast<size_t>(row * w + col);
    const uint64_t bits = LoadUnsigned(data.data() + k * item, item, big_endian);
    if (!is_float) {
      image->values[pixel] = static_cast<uint16_t>(bits);
    } else if (item == 4) {
      const uint32_t b32 = static_cast<uint32_t>(bits);
      float f;
      std::memcpy(&f, &b32, 4);
      image->metres[pixel] = f;
    } else {
      double f;
      std::memcpy(&f, &bits, 8);
      image->metres[pixel] = static_cast<float>(f);
    }
  }
  return Status::Ok();
}

}  // namespace femreg
