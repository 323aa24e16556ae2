// PCD and PLY point clouds, read here rather than by PCL.
//
// PCL's PCDReader trusts the header: `FIELDS label x y z` against a SIZE/TYPE line of three
// entries crashed it (SIGSEGV) in ASCII, binary and binary_compressed files alike, and a PCD
// without its FIELDS line read as 0 points without an error. Checking the header well
// enough to make PCL safe means parsing all of it (field lists of one length, sizes and types
// that agree, WIDTH x HEIGHT = POINTS, a data section long enough, a plausible compressed
// size) and then the data section is a few lines more; reading it here also keeps the
// VIEWPOINT and names the line or byte of every error. The same holds for PLY, whose element
// counts PCL sizes buffers from.
#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>
#include <set>
#include <sstream>
#include <vector>

#include "femreg/point_cloud.h"
#include "io/io_internal.h"
#include "io/text_tokens.h"

namespace femreg {
namespace internal {
namespace {

constexpr long long kMaxPoints = std::numeric_limits<int>::max();  // PointCloud::size() is int

using Scalar = BinaryScalar;

std::vector<std::string> Split(const std::string& line) {
  std::istringstream in(line);
  std::vector<std::string> words;
  for (std::string w; in >> w;) words.push_back(w);
  return words;
}

// A label value: an integer in the range of int.
bool LabelFrom(double v, int* label) {
  if (!std::isfinite(v) || v != std::floor(v) || std::abs(v) > std::numeric_limits<int>::max()) {
    return false;
  }
  *label = static_cast<int>(v);
  return true;
}

// Fills *cloud from the collected coordinates.
void Store(const std::vector<double>& xyz, const std::vector<double>& normals,
           const std::vector<int>& labels, PointCloud* cloud) {
  const Eigen::Index n = static_cast<Eigen::Index>(xyz.size() / 3);
  cloud->points.resize(n, 3);
  cloud->normals.resize(normals.empty() ? 0 : n, 3);
  cloud->labels.resize(labels.empty() ? 0 : n);
  for (Eigen::Index i = 0; i < n; ++i) {
    for (int k = 0; k < 3; ++k) {
      cloud->points(i, k) = xyz[3 * i + k];
      if (!normals.empty()) cloud->normals(i, k) = normals[3 * i + k];
    }
    if (!labels.empty()) cloud->labels(i) = labels[i];
  }
}

// Decompresses LZF (the format of PCD binary_compressed) with every read and write bounds
// checked; false on a corrupt stream or when it does not fill `out` exactly.
bool LzfDecompress(const unsigned char* in, size_t in_size, unsigned char* out, size_t out_size) {
  size_t ip = 0, op = 0;
  while (ip < in_size) {
    const unsigned int ctrl = in[ip++];
    if (ctrl < 32) {  // a run of ctrl + 1 literal bytes
      const size_t len = ctrl + 1;
      if (len > in_size - ip || len > out_size - op) return false;
      std::memcpy(out + op, in + ip, len);
      ip += len;
      op += len;
      continue;
    }
    size_t len = ctrl >> 5;  // a back reference
    if (len == 7) {
      if (ip >= in_size) return false;
      len += in[ip++];
    }
    len += 2;
    if (ip >= in_size) return false;
    const size_t distance = ((static_cast<size_t>(ctrl & 0x1f) << 8) | in[ip++]) + 1;
    if (distance > op || len > out_size - op) return false;
    for (size_t k = 0; k < len; ++k, ++op) out[op] = out[op - distance];  // may overlap
  }
  return op == out_size;
}

// ---------------------------------------------------------------------------------------
// PCD

struct PcdField {
  std::string name;
  int size = 0;
  char type = '?';
  long long count = 1;
  size_t offset = 0;  // in a binary point
};

class PcdReader {
 public:
  explicit PcdReader(const std::string& path) : path_(path) {}

  Status Read(PointCloud* cloud, SensorPose* sensor) {
    Status s = in_.Open(path_, '\0');
    if (!s.ok()) return s;
    if (!(s = ReadHeader()).ok()) return s;
    if (!(s = CheckHeader()).ok()) return s;
    std::vector<double> xyz, normals;
    std::vector<int> labels;
    if (data_ == "ascii") {
      s = ReadAscii(&xyz, &normals, &labels);
    } else {
      s = ReadBinary(data_ == "binary_compressed", &xyz, &normals, &labels);
    }
    if (!s.ok()) return s;
    Store(xyz, normals, labels, cloud);
    if (sensor != nullptr) *sensor = sensor_;
    return Status::Ok();
  }

 private:
  Status LineError(const std::string& message) const { return FileError(path_, line_, message); }
  Status ByteError(size_t offset, const std::string& message) const {
    std::ostringstream os;
    os << "byte " << offset << ": " << message;
    return FileError(path_, 0, os.str());
  }

  Status ReadHeader() {
    while (true) {
      const std::vector<std::string> lines = in_.TakeLines(1);
      if (lines.empty()) {
        line_ = in_.line();
        return LineError("the header ends without a DATA line (truncated file?)");
      }
      line_ = in_.line();
      const std::vector<std::string> words = Split(lines[0]);
      if (words.empty() || words[0][0] == '#') continue;
      const std::string& key = words[0];
      const std::vector<std::string> args(words.begin() + 1, words.end());
      if (!seen_.insert(key).second) return LineError(Quoted(key, 20) + " given twice");
      Status s;
      if (key == "VERSION") {
        // Any version: the fields below say what the file holds.
      } else if (key == "FIELDS") {
        names_ = args;
        fields_line_ = line_;
      } else if (key == "SIZE" || key == "TYPE" || key == "COUNT") {
        (key == "SIZE" ? sizes_ : key == "TYPE" ? types_ : counts_) = args;
        (key == "SIZE" ? sizes_line_ : key == "TYPE" ? types_line_ : counts_line_) = line_;
      } else if (key == "WIDTH" || key == "HEIGHT" || key == "POINTS") {
        long long v;
        if (args.size() != 1 || !ParseInt(args[0], &v) || v < 0 || v > kMaxPoints) {
          return LineError(key + " must be one integer from 0 to " + std::to_string(kMaxPoints) +
                           ", found " + Quoted(lines[0]));
        }
        (key == "WIDTH" ? width_ : key == "HEIGHT" ? height_ : points_) = v;
      } else if (key == "VIEWPOINT") {
        if (!(s = ReadViewpoint(args, lines[0])).ok()) return s;
      } else if (key == "DATA") {
        if (args.size() != 1 || (args[0] != "ascii" && args[0] != "binary" &&
                                 args[0] != "binary_compressed")) {
          return LineError("DATA must be ascii, binary or binary_compressed, found " +
                           Quoted(lines[0]));
        }
        data_ = args[0];
        data_line_ = line_;
        return Status::Ok();
      } else {
        return LineError("unknown PCD header line " + Quoted(lines[0]) + " (is this a PCD file?)");
      }
    }
  }

  Status ReadViewpoint(const std::vector<std::string>& args, const std::string& line) {
    double v[7];
    if (args.size() != 7) return LineError("VIEWPOINT needs 7 numbers (tx ty tz qw qx qy qz), found " + Quoted(line));
    for (int k = 0; k < 7; ++k) {
      if (!ParseDouble(args[k], &v[k]) || !std::isfinite(v[k])) {
        return LineError("VIEWPOINT value " + std::to_string(k + 1) + " is not a finite number: " +
                         Quoted(args[k]));
      }
    }
    Eigen::Quaterniond q(v[3], v[4], v[5], v[6]);
    if (!(q.norm() > 1e-12)) return LineError("VIEWPOINT orientation is a zero quaternion");
    sensor_.known = true;
    sensor_.origin = Eigen::Vector3d(v[0], v[1], v[2]);
    sensor_.orientation = q.normalized();
    return Status::Ok();
  }

  Status CheckHeader() {
    line_ = data_line_;
    if (names_.empty()) return LineError("no FIELDS line before DATA");
    if (sizes_.empty()) return LineError("no SIZE line before DATA");
    if (types_.empty()) return LineError("no TYPE line before DATA");
    const size_t n = names_.size();
    auto mismatch = [&](const char* key, size_t found, int line) {
      std::ostringstream os;
      os << key << " has " << found << " entries, FIELDS (line " << fields_line_ << ") has " << n;
      return FileError(path_, line, os.str());
    };
    if (sizes_.size() != n) return mismatch("SIZE", sizes_.size(), sizes_line_);
    if (types_.size() != n) return mismatch("TYPE", types_.size(), types_line_);
    if (!counts_.empty() && counts_.size() != n) return mismatch("COUNT", counts_.size(), counts_line_);
    std::set<std::string> names;
    size_t offset = 0;
    for (size_t f = 0; f < n; ++f) {
      PcdField field;
      field.name = names_[f];
      long long size;
      if (!ParseInt(sizes_[f], &size) || (size != 1 && size != 2 && size != 4 && size != 8)) {
        return FileError(path_, sizes_line_, "SIZE of field " + Quoted(field.name, 40) +
                                                 " must be 1, 2, 4 or 8, found " + Quoted(sizes_[f]));
      }
      field.size = static_cast<int>(size);
      if (types_[f] != "F" && types_[f] != "I" && types_[f] != "U") {
        return FileError(path_, types_line_, "TYPE of field " + Quoted(field.name, 40) +
                                                 " must be F, I or U, found " + Quoted(types_[f]));
      }
      field.type = types_[f][0];
      if (field.type == 'F' && field.size != 4 && field.size != 8) {
        return FileError(path_, sizes_line_, "field " + Quoted(field.name, 40) +
                                                 " of TYPE F must have SIZE 4 or 8");
      }
      if (!counts_.empty() &&
          (!ParseInt(counts_[f], &field.count) || field.count < 1 || field.count > (1 << 16))) {
        return FileError(path_, counts_line_, "COUNT of field " + Quoted(field.name, 40) +
                                                  " must be from 1 to 65536, found " + Quoted(counts_[f]));
      }
      if (field.name != "_" && !names.insert(field.name).second) {
        return FileError(path_, fields_line_, "field " + Quoted(field.name, 40) + " appears twice");
      }
      field.offset = offset;
      offset += static_cast<size_t>(field.size * field.count);  // at most 2^16 * 8 per field
      if (offset > (1u << 24)) return FileError(path_, fields_line_, "a point is larger than 16 MB");
      fields_.push_back(field);
    }
    point_size_ = offset;
    for (const char* axis : {"x", "y", "z"}) {
      const int f = Find(axis);
      if (f < 0) return FileError(path_, fields_line_, std::string("no field ") + axis + " (FIELDS must have x y z)");
      if (fields_[f].type != 'F' || fields_[f].count != 1) {
        return FileError(path_, fields_line_, std::string("field ") + axis +
                                                  " must be one float or double (TYPE F, COUNT 1)");
      }
    }
    normals_ = true;
    for (const char* axis : {"normal_x", "normal_y", "normal_z"}) {
      const int f = Find(axis);
      normals_ = normals_ && f >= 0 && fields_[f].type == 'F' && fields_[f].count == 1;
    }
    const int label = Find("label");
    labels_ = label >= 0 && fields_[label].count == 1;
    // WIDTH x HEIGHT = POINTS (PCD 0.6 files have POINTS only).
    if (width_ < 0 && points_ < 0) return LineError("no WIDTH or POINTS line before DATA");
    if (width_ < 0) width_ = points_;
    if (height_ < 0) height_ = 1;
    if (width_ != 0 && height_ > kMaxPoints / width_) {
      return LineError("WIDTH x HEIGHT is more than " + std::to_string(kMaxPoints) + " points");
    }
    if (points_ >= 0 && points_ != width_ * height_) {
      std::ostringstream os;
      os << "POINTS " << points_ << " is not WIDTH x HEIGHT = " << width_ << " x " << height_;
      return LineError(os.str());
    }
    points_ = width_ * height_;
    return Status::Ok();
  }

  int Find(const std::string& name) const {
    for (size_t f = 0; f < fields_.size(); ++f) {
      if (fields_[f].name == name) return static_cast<int>(f);
    }
    return -1;
  }

  Status ReadAscii(std::vector<double>* xyz, std::vector<double>* normals, std::vector<int>* labels) {
    long long values_per_point = 0;
    for (const PcdField& f : fields_) values_per_point += f.count;
    if (points_ > MaxItemsIn(in_.remaining(), values_per_point)) {
      std::ostringstream os;
      os << points_ << " points of " << values_per_point << " values cannot fit in the "
         << in_.remaining() << " bytes after the header (truncated file?)";
      return LineError(os.str());
    }
    const int fx = Find("x"), fy = Find("y"), fz = Find("z");
    const int nx = Find("normal_x"), ny = Find("normal_y"), nz = Find("normal_z");
    const int fl = Find("label");
    // First value of each field within a point's values.
    std::vector<long long> first(fields_.size());
    for (size_t f = 0, v = 0; f < fields_.size(); v += fields_[f].count, ++f) first[f] = v;
    std::vector<double> values;
    long long read = 0;
    Token t;
    while (in_.Next(&t)) {
      line_ = t.line;
      if (read == points_) return LineError("more points than POINTS says (" + std::to_string(points_) + ")");
      std::vector<Token> tokens = in_.RestOfLine();
      tokens.insert(tokens.begin(), t);
      if (static_cast<long long>(tokens.size()) != values_per_point) {
        std::ostringstream os;
        os << "point " << read << ": " << tokens.size() << " values, the fields need "
           << values_per_point;
        return LineError(os.str());
      }
      values.resize(tokens.size());
      for (size_t k = 0; k < tokens.size(); ++k) {
        if (!ParseDouble(tokens[k].text, &values[k])) {
          return LineError("point " + std::to_string(read) + ": not a number: " + Quoted(tokens[k].text));
        }
      }
      xyz->insert(xyz->end(), {values[first[fx]], values[first[fy]], values[first[fz]]});
      if (normals_) normals->insert(normals->end(), {values[first[nx]], values[first[ny]], values[first[nz]]});
      if (labels_) {
        int label;
        if (!LabelFrom(values[first[fl]], &label)) {
          return LineError("point " + std::to_string(read) + ": label " + Quoted(tokens[first[fl]].text) +
                           " is not an integer in the range of int");
        }
        labels->push_back(label);
      }
      ++read;
    }
    if (read != points_) {
      line_ = in_.line();
      std::ostringstream os;
      os << "the file ends after " << read << " of " << points_ << " points (truncated file?)";
      return LineError(os.str());
    }
    return Status::Ok();
  }

  static Scalar ScalarOf(const PcdField& f) {
    return {f.size, f.type == 'F', f.type == 'I'};
  }

  Status ReadBinary(bool compressed, std::vector<double>* xyz, std::vector<double>* normals,
                    std::vector<int>* labels) {
    const std::string& data = in_.data();
    size_t at = in_.offset();  // just after the DATA line
    const uint64_t needed = static_cast<uint64_t>(points_) * point_size_;  // < 2^31 * 2^24
    std::vector<unsigned char> unpacked;
    const unsigned char* body = nullptr;
    if (!compressed) {
      if (needed > data.size() - at) {
        std::ostringstream os;
        os << "binary data of " << points_ << " points of " << point_size_ << " bytes needs "
           << needed << " bytes, the file has " << data.size() - at << " after the header";
        return ByteError(at, os.str());
      }
      body = reinterpret_cast<const unsigned char*>(data.data() + at);
    } else {
      if (data.size() - at < 8) return ByteError(at, "binary_compressed data without its two sizes");
      uint32_t sizes[2];
      std::memcpy(sizes, data.data() + at, 8);  // little-endian, as PCL writes them
      const uint64_t packed = sizes[0], unpacked_size = sizes[1];
      at += 8;
      if (packed > data.size() - at) {
        std::ostringstream os;
        os << "compressed size " << packed << " is more than the " << data.size() - at
           << " bytes after the header";
        return ByteError(at - 8, os.str());
      }
      if (unpacked_size != needed) {
        std::ostringstream os;
        os << "uncompressed size " << unpacked_size << " is not POINTS x point size = " << points_
           << " x " << point_size_ << " = " << needed;
        return ByteError(at - 4, os.str());
      }
      // LZF turns at most 3 bytes into 264: a larger ratio is a corrupt size.
      if (unpacked_size > 90 * packed + 64) {
        std::ostringstream os;
        os << "uncompressed size " << unpacked_size << " cannot come out of " << packed
           << " compressed bytes";
        return ByteError(at - 4, os.str());
      }
      unpacked.resize(static_cast<size_t>(unpacked_size));
      if (unpacked_size > 0 &&
          !LzfDecompress(reinterpret_cast<const unsigned char*>(data.data() + at),
                         static_cast<size_t>(packed), unpacked.data(), unpacked.size())) {
        return ByteError(at, "corrupt compressed data (LZF stream does not decode to the stated size)");
      }
      body = unpacked.data();
    }
    // Where value `f` of point `i` is: interleaved per point, or field after field (compressed).
    std::vector<size_t> start(fields_.size());
    for (size_t f = 0, s = 0; f < fields_.size(); ++f) {
      start[f] = s;
      s += static_cast<size_t>(points_) * fields_[f].size * fields_[f].count;
    }
    auto at_value = [&](int f, long long i) {
      const size_t bytes = static_cast<size_t>(fields_[f].size * fields_[f].count);
      return reinterpret_cast<const char*>(
          body + (compressed ? start[f] + i * bytes : i * point_size_ + fields_[f].offset));
    };
    const int fx = Find("x"), fy = Find("y"), fz = Find("z");
    const int nx = Find("normal_x"), ny = Find("normal_y"), nz = Find("normal_z");
    const int fl = Find("label");
    xyz->resize(3 * static_cast<size_t>(points_));
    if (normals_) normals->resize(3 * static_cast<size_t>(points_));
    if (labels_) labels->resize(static_cast<size_t>(points_));
    for (long long i = 0; i < points_; ++i) {
      (*xyz)[3 * i] = DecodeBinaryScalar(at_value(fx, i), ScalarOf(fields_[fx]), false);
      (*xyz)[3 * i + 1] = DecodeBinaryScalar(at_value(fy, i), ScalarOf(fields_[fy]), false);
      (*xyz)[3 * i + 2] = DecodeBinaryScalar(at_value(fz, i), ScalarOf(fields_[fz]), false);
      if (normals_) {
        (*normals)[3 * i] = DecodeBinaryScalar(at_value(nx, i), ScalarOf(fields_[nx]), false);
        (*normals)[3 * i + 1] = DecodeBinaryScalar(at_value(ny, i), ScalarOf(fields_[ny]), false);
        (*normals)[3 * i + 2] = DecodeBinaryScalar(at_value(nz, i), ScalarOf(fields_[nz]), false);
      }
      if (labels_) {
        const double v = DecodeBinaryScalar(at_value(fl, i), ScalarOf(fields_[fl]), false);
        if (!LabelFrom(v, &(*labels)[i])) {
          std::ostringstream os;
          os << "point " << i << ": label " << v << " is not an integer in the range of int";
          return FileError(path_, 0, os.str());
        }
      }
    }
    return Status::Ok();
  }

  const std::string path_;
  TokenStream in_;
  int line_ = 0;
  std::set<std::string> seen_;
  std::vector<std::string> names_, sizes_, types_, counts_;
  int fields_line_ = 0, sizes_line_ = 0, types_line_ = 0, counts_line_ = 0, data_line_ = 0;
  long long width_ = -1, height_ = -1, points_ = -1;
  std::string data_;
  std::vector<PcdField> fields_;
  size_t point_size_ = 0;
  bool normals_ = false, labels_ = false;
  SensorPose sensor_;
};

// ---------------------------------------------------------------------------------------
// PLY

struct PlyProperty {
  std::string name;
  Scalar type;
  bool is_list = false;
  Scalar count_type;  // lists only
};

struct PlyElement {
  std::string name;
  long long count = 0;
  std::vector<PlyProperty> properties;
};

Scalar PlyScalar(const std::string& name) {
  if (name == "char" || name == "int8") return {1, false, true};
  if (name == "uchar" || name == "uint8") return {1, false, false};
  if (name == "short" || name == "int16") return {2, false, true};
  if (name == "ushort" || name == "uint16") return {2, false, false};
  if (name == "int" || name == "int32") return {4, false, true};
  if (name == "uint" || name == "uint32") return {4, false, false};
  if (name == "float" || name == "float32") return {4, true, true};
  if (name == "double" || name == "float64") return {8, true, true};
  return {};
}

class PlyReader {
 public:
  explicit PlyReader(const std::string& path) : path_(path) {}

  Status Read(PointCloud* cloud) {
    Status s = in_.Open(path_, '\0');
    if (!s.ok()) return s;
    if (!(s = ReadHeader()).ok()) return s;
    std::vector<double> xyz, normals;
    for (const PlyElement& element : elements_) {
      const bool vertex = element.name == "vertex";
      if (vertex) {
        xyz.reserve(3 * static_cast<size_t>(element.count));
        if (normals_) normals.reserve(3 * static_cast<size_t>(element.count));
      }
      std::vector<double> values(element.properties.size());
      for (long long i = 0; i < element.count; ++i) {
        for (size_t p = 0; p < element.properties.size(); ++p) {
          if (!(s = ReadProperty(element, i, element.properties[p], &values[p])).ok()) return s;
        }
        if (!vertex) continue;
        for (int k = 0; k < 3; ++k) xyz.push_back(values[xyz_[k]]);
        if (normals_) {
          for (int k = 0; k < 3; ++k) normals.push_back(values[normal_[k]]);
        }
      }
    }
    Store(xyz, normals, {}, cloud);
    return Status::Ok();
  }

 private:
  Status LineError(int line, const std::string& message) const { return FileError(path_, line, message); }
  Status ByteError(const std::string& message) const {
    std::ostringstream os;
    os << "byte " << pos_ << ": " << message;
    return FileError(path_, 0, os.str());
  }

  Status ReadHeader() {
    std::vector<std::string> lines = in_.TakeLines(1);
    if (lines.empty() || lines[0] != "ply") return LineError(1, "not a PLY file (no 'ply' line)");
    std::string format;
    while (true) {
      lines = in_.TakeLines(1);
      const int line = in_.line();
      if (lines.empty()) return LineError(line, "the header ends without end_header (truncated file?)");
      const std::vector<std::string> w = Split(lines[0]);
      if (w.empty() || w[0] == "comment" || w[0] == "obj_info") continue;
      if (w[0] == "end_header") break;
      if (w[0] == "format") {
        if (w.size() != 3 || (w[1] != "ascii" && w[1] != "binary_little_endian" &&
                              w[1] != "binary_big_endian")) {
          return LineError(line, "format must be ascii, binary_little_endian or binary_big_endian, found " +
                                     Quoted(lines[0]));
        }
        format = w[1];
      } else if (w[0] == "element") {
        PlyElement e;
        if (w.size() != 3 || !ParseInt(w[2], &e.count) || e.count < 0 || e.count > kMaxPoints) {
          return LineError(line, "expected 'element NAME COUNT' with a COUNT from 0 to " +
                                     std::to_string(kMaxPoints) + ", found " + Quoted(lines[0]));
        }
        e.name = w[1];
        for (const PlyElement& other : elements_) {
          if (other.name == e.name) return LineError(line, "element " + Quoted(e.name, 40) + " given twice");
        }
        elements_.push_back(e);
        element_lines_.push_back(line);
      } else if (w[0] == "property") {
        if (elements_.empty()) return LineError(line, "a property before any element");
        PlyProperty p;
        if (w.size() == 5 && w[1] == "list") {
          p.is_list = true;
          p.count_type = PlyScalar(w[2]);
          p.type = PlyScalar(w[3]);
          p.name = w[4];
          if (p.count_type.size == 0 || p.count_type.is_float || p.type.size == 0) {
            return LineError(line, "bad list property " + Quoted(lines[0]));
          }
        } else if (w.size() == 3) {
          p.type = PlyScalar(w[1]);
          p.name = w[2];
          if (p.type.size == 0) return LineError(line, "unknown property type " + Quoted(w[1]));
        } else {
          return LineError(line, "expected 'property TYPE NAME', found " + Quoted(lines[0]));
        }
        elements_.back().properties.push_back(p);
      } else {
        return LineError(line, "unknown PLY header line " + Quoted(lines[0]));
      }
    }
    const int end_line = in_.line();
    if (format.empty()) return LineError(end_line, "no format line");
    ascii_ = format == "ascii";
    big_endian_ = format == "binary_big_endian";
    pos_ = in_.offset();
    // Every element instance takes at least a byte per scalar (binary) or a token per
    // property (ASCII): the counts must fit in what is left of the file.
    const long long left = static_cast<long long>(in_.data().size() - pos_);
    long long need = 0;
    for (size_t e = 0; e < elements_.size(); ++e) {
      const PlyElement& el = elements_[e];
      long long each = 0;
      for (const PlyProperty& p : el.properties) each += ascii_ ? 2 : (p.is_list ? p.count_type.size : p.type.size);
      if (el.count > 0 && each == 0) return LineError(element_lines_[e], "element " + Quoted(el.name, 40) + " has no properties");
      if (el.count > 0 && (el.count > (left + 1) / each || need + el.count * each > left + 1)) {
        std::ostringstream os;
        os << "element " << Quoted(el.name, 40) << " count " << el.count
           << " is more than the " << left << " bytes after the header can hold";
        return LineError(element_lines_[e], os.str());
      }
      need += el.count * each;
    }
    const PlyElement* vertex = nullptr;
    for (const PlyElement& el : elements_) {
      if (el.name == "vertex") vertex = &el;
    }
    if (vertex == nullptr) return LineError(end_line, "no vertex element");
    auto find = [&](const char* name) {
      for (size_t p = 0; p < vertex->properties.size(); ++p) {
        if (vertex->properties[p].name == name && !vertex->properties[p].is_list) return static_cast<int>(p);
      }
      return -1;
    };
    const char* axes[3] = {"x", "y", "z"};
    for (int k = 0; k < 3; ++k) {
      xyz_[k] = find(axes[k]);
      if (xyz_[k] < 0) return LineError(end_line, std::string("the vertex element has no scalar property ") + axes[k]);
    }
    const char* n1[3] = {"nx", "ny", "nz"};
    const char* n2[3] = {"normal_x", "normal_y", "normal_z"};
    normals_ = true;
    for (int k = 0; k < 3; ++k) {
      normal_[k] = find(n1[k]) >= 0 ? find(n1[k]) : find(n2[k]);
      normals_ = normals_ && normal_[k] >= 0;
    }
    return Status::Ok();
  }

  // One scalar (or, for a list, its length; items are skipped) of element instance i.
  Status ReadProperty(const PlyElement& element, long long i, const PlyProperty& p, double* value) {
    Status s;
    if (!(s = ReadScalar(element, i, p.is_list ? p.count_type : p.type, value)).ok()) return s;
    if (!p.is_list) return Status::Ok();
    const double n = *value;
    const long long left = ascii_ ? MaxItemsIn(in_.remaining(), 1)
                                  : static_cast<long long>((in_.data().size() - pos_) / p.type.size);
    if (!(n >= 0) || n > static_cast<double>(left)) {
      std::ostringstream os;
      os << element.name << " " << i << ": list " << Quoted(p.name, 40) << " of " << n
         << " items, more than the rest of the file holds";
      return ascii_ ? in_.Error(os.str()) : ByteError(os.str());
    }
    double item;
    for (long long k = 0; k < static_cast<long long>(n); ++k) {
      if (!(s = ReadScalar(element, i, p.type, &item)).ok()) return s;
    }
    return Status::Ok();
  }

  Status ReadScalar(const PlyElement& element, long long i, const Scalar& type, double* value) {
    if (ascii_) {
      Token t;
      if (!in_.Next(&t)) {
        std::ostringstream os;
        os << "the file ends inside " << element.name << " " << i << " of " << element.count
           << " (truncated file?)";
        return in_.Error(os.str());
      }
      if (!ParseDouble(t.text, value)) return in_.Error("not a number: " + Quoted(t.text));
      return Status::Ok();
    }
    const std::string& data = in_.data();
    if (static_cast<size_t>(type.size) > data.size() - pos_) {
      std::ostringstream os;
      os << "the file ends inside " << element.name << " " << i << " of " << element.count
         << " (truncated file?)";
      return ByteError(os.str());
    }
    *value = DecodeBinaryScalar(data.data() + pos_, type, big_endian_);
    pos_ += static_cast<size_t>(type.size);
    return Status::Ok();
  }

  const std::string path_;
  TokenStream in_;
  std::vector<PlyElement> elements_;
  std::vector<int> element_lines_;
  bool ascii_ = true, big_endian_ = false, normals_ = false;
  int xyz_[3] = {-1, -1, -1}, normal_[3] = {-1, -1, -1};
  size_t pos_ = 0;  // binary: the next byte
};

}  // namespace

Status ReadPcdFile(const std::string& path, PointCloud* cloud, SensorPose* sensor) {
  return PcdReader(path).Read(cloud, sensor);
}

Status ReadPlyFile(const std::string& path, PointCloud* cloud) { return PlyReader(path).Read(cloud); }

}  // namespace internal
}  // namespace femreg
