// PCD point clouds (ASCII, binary, binary_compressed), read here rather than by PCL.
//
// PCL's PCDReader trusts the header: `FIELDS label x y z` against a SIZE/TYPE line of three
// entries crashed it (SIGSEGV) in ASCII, binary and binary_compressed files alike, and a PCD
// without its FIELDS line read as 0 points without an error. Checking the header well
// enough to make PCL safe means parsing all of it (field lists of one length, sizes and types
// that agree, WIDTH x HEIGHT = POINTS, a data section long enough, a plausible compressed
// size) and then the data section is a few lines more; reading it here also keeps the
// VIEWPOINT and names the line or byte of every error. PLY clouds are read by the one PLY
// reader (ply_reader.cc), whose element counts PCL would size buffers from.
#include <Eigen/Geometry>
#include <array>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>
#include <set>
#include <sstream>
#include <utility>
#include <vector>

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

  Status Read(RawCloud* cloud) {
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
    cloud->xyz = std::move(xyz);
    cloud->normals = std::move(normals);
    cloud->labels = std::move(labels);
    cloud->viewpoint_known = viewpoint_known_;
    cloud->origin = origin_;
    cloud->orientation = orientation_;
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
    viewpoint_known_ = true;
    origin_ = {v[0], v[1], v[2]};
    q.normalize();
    orientation_ = {q.w(), q.x(), q.y(), q.z()};
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
  bool viewpoint_known_ = false;
  std::array<double, 3> origin_ = {0, 0, 0};
  std::array<double, 4> orientation_ = {1, 0, 0, 0};  // w x y z
};

}  // namespace

Status ReadPcdCloud(const std::string& path, RawCloud* cloud) { return PcdReader(path).Read(cloud); }

}  // namespace internal
}  // namespace femreg
