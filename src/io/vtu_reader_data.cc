// femreg's own VTU reader, its second half (vtu_reader_internal.h): the arrays' data,
// ASCII, base64 or raw, plain or in zlib blocks, each size checked against the bytes the
// file has, and the pieces read from them; and MergePieces.
#include <zlib.h>

#include <algorithm>
#include <cctype>
#include <cstdint>
#include <cstring>
#include <fstream>
#include <limits>
#include <map>
#include <sstream>
#include <vector>

#include "io/io_internal.h"
#include "io/text_tokens.h"
#include "io/vtu_reader_internal.h"

namespace femreg {
namespace internal {
namespace vtu {
namespace {

int Base64Value(unsigned char c) {
  if (c >= 'A' && c <= 'Z') return c - 'A';
  if (c >= 'a' && c <= 'z') return c - 'a' + 26;
  if (c >= '0' && c <= '9') return c - '0' + 52;
  if (c == '+') return 62;
  if (c == '/') return 63;
  return -1;
}

}  // namespace

// Bytes of binary data: raw from the file, or decoded from base64 text as they are taken.
// A base64 stream may be several padded parts one after the other (VTK encodes a
// compression header apart from the blocks): each group of four characters is decoded on
// its own.
class VtuReader::ByteStream {
 public:
  ByteStream(const std::string& data, size_t begin, size_t end, bool base64)
      : data_(data), pos_(begin), end_(end), base64_(base64) {}

  // At most this many bytes are left (base64: white space counted as data).
  uint64_t Available() const {
    const uint64_t left = end_ - pos_;
    return base64_ ? pending_.size() - pending_pos_ + left / 4 * 3 : left;
  }
  size_t offset() const { return pos_; }

  // The next n bytes into *out; false (and *bad the offset of the problem) when the data
  // ends first or holds a character that is not base64.
  bool Take(size_t n, std::string* out, size_t* bad) {
    out->clear();
    if (n > Available()) {
      *bad = pos_;
      return false;
    }
    if (!base64_) {
      out->assign(data_, pos_, n);
      pos_ += n;
      return true;
    }
    out->reserve(n);
    const size_t from_pending = std::min(n, pending_.size() - pending_pos_);
    out->append(pending_, pending_pos_, from_pending);
    pending_pos_ += from_pending;
    while (out->size() < n) {
      unsigned char bytes[3];
      int count = 0;
      if (!DecodeGroup(bytes, &count, bad)) return false;
      const size_t use = std::min(static_cast<size_t>(count), n - out->size());
      out->append(reinterpret_cast<const char*>(bytes), use);
      if (use < static_cast<size_t>(count)) {
        pending_.assign(reinterpret_cast<const char*>(bytes) + use, static_cast<size_t>(count) - use);
        pending_pos_ = 0;
      }
    }
    return true;
  }

 private:
  bool DecodeGroup(unsigned char bytes[3], int* count, size_t* bad) {
    int values[4];
    int chars = 0, padding = 0;
    while (chars < 4) {
      while (pos_ < end_ && std::isspace(static_cast<unsigned char>(data_[pos_]))) ++pos_;
      if (pos_ >= end_) {
        *bad = pos_;
        return false;
      }
      const unsigned char c = static_cast<unsigned char>(data_[pos_]);
      if (c == '=' && chars >= 2) {
        ++padding;
        values[chars++] = 0;
      } else {
        const int v = Base64Value(c);
        if (v < 0 || padding > 0) {
          *bad = pos_;
          return false;
        }
        values[chars++] = v;
      }
      ++pos_;
    }
    const uint32_t word = (static_cast<uint32_t>(values[0]) << 18) | (static_cast<uint32_t>(values[1]) << 12) |
                          (static_cast<uint32_t>(values[2]) << 6) | static_cast<uint32_t>(values[3]);
    bytes[0] = static_cast<unsigned char>(word >> 16);
    bytes[1] = static_cast<unsigned char>(word >> 8);
    bytes[2] = static_cast<unsigned char>(word);
    *count = 3 - padding;
    return true;
  }

  const std::string& data_;
  size_t pos_, end_;
  bool base64_;
  std::string pending_;  // decoded bytes not yet taken
  size_t pending_pos_ = 0;
};

// A header word (UInt32 or UInt64, in the file's byte order).
uint64_t VtuReader::Word(const char* p) const {
  uint64_t v = 0;
  for (int i = 0; i < header_size_; ++i) {
    const int k = big_endian_ ? i : header_size_ - 1 - i;
    v = (v << 8) | static_cast<unsigned char>(p[k]);
  }
  return v;
}

std::string VtuReader::Describe(const ArrayRef& a) {
  return a.format + " DataArray " + Quoted(a.name, 40);
}

Status VtuReader::ReadAscii(const ArrayRef& a, long long values, std::vector<double>* out) const {
  const size_t text = a.content_end - a.content;
  if (values > MaxItemsIn(text, 1)) {
    std::ostringstream os;
    os << "ascii DataArray " << Quoted(a.name, 40) << " needs " << values << " values, its text has "
       << text << " bytes";
    return Error(a.begin, os.str());
  }
  // Plain decimal only: hexadecimal floats, "nan" and "inf" are not what VTK writes.
  const bool integer = !a.scalar.is_float;
  out->clear();
  out->reserve(static_cast<size_t>(values));
  size_t p = a.content;
  while (static_cast<long long>(out->size()) < values) {
    while (p < a.content_end && std::isspace(static_cast<unsigned char>(data_[p]))) ++p;
    const size_t begin = p;
    while (p < a.content_end && !std::isspace(static_cast<unsigned char>(data_[p]))) ++p;
    if (begin == p) {
      std::ostringstream os;
      os << "ascii DataArray " << Quoted(a.name, 40) << " has " << out->size()
         << " values, the header's counts need " << values;
      return Error(a.begin, os.str());
    }
    const std::string token = data_.substr(begin, p - begin);
    long long i = 0;
    double d = 0.0;
    const bool decimal = token.find_first_not_of("0123456789+-.eE") == std::string::npos;
    if (!decimal || (integer ? !ParseInt(token, &i) : !ParseDouble(token, &d))) {
      std::ostringstream os;
      os << "ascii DataArray " << Quoted(a.name, 40) << " value " << out->size() << " is not "
         << (integer ? "an integer" : "a number") << ": " << Quoted(token);
      return Error(begin, os.str());
    }
    out->push_back(integer ? static_cast<double>(i) : d);
  }
  return Status::Ok();
}

// The bytes of a binary or appended array: a byte count and the data, or a zlib
// compression header and the compressed blocks. At least `bytes` bytes.
Status VtuReader::ReadBinaryBytes(const ArrayRef& a, uint64_t bytes, std::string* out) const {
  const bool inline_data = a.format == "binary";
  const size_t begin = inline_data ? a.content : appended_begin_ + static_cast<size_t>(a.offset);
  const size_t end = inline_data ? a.content_end : appended_end_;
  ByteStream in(data_, begin, end, inline_data || appended_base64_);
  std::ostringstream where;
  where << Describe(a);
  if (!inline_data) where << " at offset " << a.offset;
  where << ": ";
  std::string header;
  size_t bad = 0;
  auto take = [&](size_t n, std::string* into, const char* what) -> Status {
    if (in.Take(n, into, &bad)) return Status::Ok();
    if (bad < end && !std::isspace(static_cast<unsigned char>(data_[bad]))) {
      return Error(bad, where.str() + Quoted(data_.substr(bad, 1)) + " is not base64");
    }
    std::ostringstream os;
    os << where.str() << what << " runs past the end of the data (" << n << " bytes, at most "
       << in.Available() << " left)";
    return Error(bad, os.str());
  };
  Status s;
  if (!compressed_) {
    if (!(s = take(static_cast<size_t>(header_size_), &header, "its byte count")).ok()) return s;
    const uint64_t count = Word(header.data());
    if (count > in.Available()) {
      std::ostringstream os;
      os << where.str() << "says " << count << " bytes, " << in.Available() << " are left";
      return Error(begin, os.str());
    }
    if (count < bytes) {
      std::ostringstream os;
      os << where.str() << "holds " << count << " bytes, the header's counts need " << bytes;
      return Error(begin, os.str());
    }
    return take(static_cast<size_t>(bytes), out, "its data");
  }
  // [number of blocks, block size, last block size, compressed size of each block]
  if (!(s = take(3 * static_cast<size_t>(header_size_), &header, "its compression header")).ok()) return s;
  const uint64_t blocks = Word(header.data()), block_size = Word(header.data() + header_size_),
                 last_size = Word(header.data() + 2 * header_size_);
  if (blocks > in.Available() / static_cast<uint64_t>(header_size_)) {
    std::ostringstream os;
    os << where.str() << blocks << " compressed blocks, more than the data holds";
    return Error(begin, os.str());
  }
  if ((blocks == 0 && last_size != 0) ||
      (blocks > 0 && (block_size == 0 || last_size > block_size ||
                      block_size > static_cast<uint64_t>(std::numeric_limits<int>::max())))) {
    std::ostringstream os;
    os << where.str() << "block size " << block_size << " and last block size " << last_size
       << " are inconsistent";
    return Error(begin, os.str());
  }
  std::string sizes;
  if (!(s = take(static_cast<size_t>(blocks * header_size_), &sizes, "its block sizes")).ok()) return s;
  uint64_t compressed_total = 0;
  for (uint64_t b = 0; b < blocks; ++b) {
    const uint64_t block = Word(sizes.data() + b * header_size_);
    compressed_total += std::min<uint64_t>(block, in.Available() + 1);  // no overflow
  }
  if (compressed_total > in.Available()) {
    std::ostringstream os;
    os << where.str() << "its compressed blocks need " << compressed_total << " bytes, "
       << in.Available() << " are left";
    return Error(begin, os.str());
  }
  const uint64_t uncompressed =
      blocks == 0 ? 0 : (blocks - 1) * block_size + (last_size == 0 ? block_size : last_size);
  if (uncompressed < bytes) {
    std::ostringstream os;
    os << where.str() << "holds " << uncompressed << " bytes, the header's counts need " << bytes;
    return Error(begin, os.str());
  }
  out->clear();
  std::string compressed;
  for (uint64_t b = 0; b < blocks && out->size() < bytes; ++b) {
    const uint64_t size = Word(sizes.data() + b * header_size_);
    const uint64_t expected = b + 1 < blocks || last_size == 0 ? block_size : last_size;
    if (expected / kMaxCompressionRatio > size + 1) {
      std::ostringstream os;
      os << where.str() << "block " << b << ": " << expected << " bytes cannot come out of " << size
         << " compressed ones";
      return Error(in.offset(), os.str());
    }
    const size_t block_at = in.offset();
    if (!(s = take(static_cast<size_t>(size), &compressed, "a compressed block")).ok()) return s;
    const size_t before = out->size();
    out->resize(before + static_cast<size_t>(expected));
    uLongf length = static_cast<uLongf>(expected);
    const int z = uncompress(reinterpret_cast<Bytef*>(&(*out)[before]), &length,
                             reinterpret_cast<const Bytef*>(compressed.data()), static_cast<uLong>(size));
    if (z != Z_OK || length != expected) {
      std::ostringstream os;
      os << where.str() << "block " << b << " does not decompress to its " << expected << " bytes ("
         << (z == Z_OK ? std::to_string(length) + " bytes" : std::string("zlib: ") + zError(z)) << ")";
      return Error(block_at, os.str());
    }
  }
  out->resize(static_cast<size_t>(bytes));
  return Status::Ok();
}

// `values` values of array `a` as doubles.
Status VtuReader::ReadValues(const ArrayRef& a, long long values, std::vector<double>* out) const {
  if (a.format == "ascii") return ReadAscii(a, values, out);
  const uint64_t bytes = static_cast<uint64_t>(values) * static_cast<uint64_t>(a.scalar.size);
  std::string raw;
  Status s = ReadBinaryBytes(a, bytes, &raw);
  if (!s.ok()) return s;
  out->resize(static_cast<size_t>(values));
  for (long long i = 0; i < values; ++i) {
    (*out)[static_cast<size_t>(i)] =
        DecodeBinaryScalar(raw.data() + static_cast<size_t>(i) * a.scalar.size, a.scalar, big_endian_);
  }
  return Status::Ok();
}

const ArrayRef* VtuReader::Find(const PieceRef& piece, const std::string& section, const char* name) const {
  for (const ArrayRef& a : piece.arrays) {
    if (a.section == section && (name == nullptr || a.name == name)) return &a;
  }
  return nullptr;
}

Status VtuReader::ReadPiece(int index, const PieceRef& ref, VtuPiece* piece) const {
  std::ostringstream prefix;
  prefix << "piece " << index << ": ";
  Status s;
  // Points.
  if (ref.points > 0) {
    const ArrayRef* points = Find(ref, "Points", nullptr);
    if (points == nullptr) {
      return Error(ref.begin, prefix.str() + "no <Points> DataArray for its " + std::to_string(ref.points) + " points");
    }
    std::vector<double> values;
    if (!(s = ReadValues(*points, ref.points * 3, &values)).ok()) return s;
    piece->points.resize(static_cast<size_t>(ref.points));
    for (size_t i = 0; i < piece->points.size(); ++i) {
      for (int k = 0; k < 3; ++k) piece->points[i][k] = values[3 * i + static_cast<size_t>(k)];
    }
  }
  // Cells: offsets and types first, then as much connectivity as the last offset says.
  piece->offsets.assign(1, 0);
  if (ref.cells > 0) {
    const ArrayRef* offsets = Find(ref, "Cells", "offsets");
    const ArrayRef* types = Find(ref, "Cells", "types");
    const ArrayRef* connectivity = Find(ref, "Cells", "connectivity");
    if (offsets == nullptr || types == nullptr || connectivity == nullptr) {
      return Error(ref.begin, prefix.str() + "<Cells> needs DataArrays named 'connectivity', 'offsets' and 'types' for its " +
                                  std::to_string(ref.cells) + " cells");
    }
    std::vector<double> values;
    if (!(s = ReadValues(*offsets, ref.cells, &values)).ok()) return s;
    piece->offsets.reserve(values.size() + 1);
    for (size_t c = 0; c < values.size(); ++c) {
      const double v = values[c];
      if (!(v >= static_cast<double>(piece->offsets.back()) && v <= static_cast<double>(kMaxItems)) ||
          v != static_cast<double>(static_cast<long long>(v))) {
        std::ostringstream os;
        os << prefix.str() << "cell " << c << " ends at offset " << v << ", not an integer from "
           << piece->offsets.back() << " (where it starts) to " << kMaxItems;
        return Error(offsets->begin, os.str());
      }
      piece->offsets.push_back(static_cast<long long>(v));
    }
    if (!(s = ReadValues(*types, ref.cells, &values)).ok()) return s;
    piece->types.resize(values.size());
    for (size_t c = 0; c < values.size(); ++c) {
      const double v = values[c];
      // A type outside 0..255 is no cell femreg keeps.
      piece->types[c] = v >= 0 && v <= 255 ? static_cast<int>(v) : -1;
    }
    if (!(s = ReadValues(*connectivity, piece->offsets.back(), &values)).ok()) return s;
    piece->connectivity.resize(values.size());
    for (size_t i = 0; i < values.size(); ++i) {
      const double v = values[i];
      // Indices are compared with the number of points later; beyond int they are all bad.
      piece->connectivity[i] = v >= -1e15 && v <= 1e15 ? static_cast<long long>(v) : -1;
    }
  }
  // Point and cell arrays.
  for (const ArrayRef& a : ref.arrays) {
    if (a.section != "PointData" && a.section != "CellData") continue;
    const long long tuples = a.section == "PointData" ? ref.points : ref.cells;
    VtuArray array;
    array.name = a.name;
    array.components = a.components;
    if (tuples * a.components > kMaxItems) {
      std::ostringstream os;
      os << prefix.str() << Describe(a) << " would have " << tuples * a.components << " values";
      return Error(a.begin, os.str());
    }
    if (!(s = ReadValues(a, tuples * a.components, &array.values)).ok()) return s;
    (a.section == "PointData" ? piece->point_data : piece->cell_data).push_back(std::move(array));
  }
  return Status::Ok();
}

}  // namespace vtu

VtuPiece MergePieces(VtuGrid grid) {
  if (grid.pieces.size() == 1) return std::move(grid.pieces[0]);
  VtuPiece merged;
  // The arrays every piece has: the first of each name in piece 0, kept while each later
  // piece has one of that name and component count.
  auto common = [&](std::vector<VtuArray> VtuPiece::*section) {
    std::vector<VtuArray> out;
    if (grid.pieces.empty()) return out;
    for (const VtuArray& first : grid.pieces[0].*section) {
      bool everywhere = std::none_of(out.begin(), out.end(),
                                     [&](const VtuArray& a) { return a.name == first.name; });
      VtuArray joined{first.name, first.components, {}};
      for (size_t p = 0; everywhere && p < grid.pieces.size(); ++p) {
        const std::vector<VtuArray>& arrays = grid.pieces[p].*section;
        const auto it = std::find_if(arrays.begin(), arrays.end(),
                                     [&](const VtuArray& a) { return a.name == first.name; });
        everywhere = it != arrays.end() && it->components == first.components;
        if (everywhere) joined.values.insert(joined.values.end(), it->values.begin(), it->values.end());
      }
      if (everywhere) out.push_back(std::move(joined));
    }
    return out;
  };
  merged.point_data = common(&VtuPiece::point_data);
  merged.cell_data = common(&VtuPiece::cell_data);
  long long base = 0;
  for (const VtuPiece& piece : grid.pieces) {
    const long long np = static_cast<long long>(piece.points.size());
    merged.points.insert(merged.points.end(), piece.points.begin(), piece.points.end());
    const long long shift = static_cast<long long>(merged.connectivity.size());
    for (long long v : piece.connectivity) merged.connectivity.push_back(v >= 0 && v < np ? v + base : -1);
    for (size_t c = 1; c < piece.offsets.size(); ++c) merged.offsets.push_back(piece.offsets[c] + shift);
    merged.types.insert(merged.types.end(), piece.types.begin(), piece.types.end());
    base += np;
  }
  return merged;
}

}  // namespace internal
}  // namespace femreg
