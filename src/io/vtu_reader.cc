// femreg's own reader of VTK XML unstructured grids (.vtu), in place of VTK's
// vtkXMLUnstructuredGridReader.
//
// VTK's reader trusts the header: NumberOfComponents="-4" made it throw std::bad_alloc from
// inside VTK, NumberOfComponents="4294967299" made it loop for minutes, and a token it could
// not parse, two arrays of one name or a compression header of no blocks with a last block
// made it read through a null pointer (SIGSEGV); each fuzzing run found one more such input
// past the checks that once ran before it. Here every number anything is sized from is
// parsed strictly and compared with the bytes the file holds for it before allocating:
// inline ASCII and base64 text, raw or base64 appended blocks, their byte-count headers and
// zlib compression headers (block counts and sizes, and each block's decompressed size).
//
// Supported: VTKFile type="UnstructuredGrid", byte_order LittleEndian/BigEndian,
// header_type UInt32/UInt64, compressor vtkZLibDataCompressor or none (LZ4 and LZMA are
// refused by name); DataArray format ascii, binary (base64) and appended (AppendedData
// encoding raw or base64), of the numeric VTK types. Several <Piece>s are kept one by one
// (VtuGrid::pieces); callers concatenate them. FieldData is skipped.
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

namespace femreg {
namespace internal {
namespace {

// Largest expansion of one compressed byte: zlib's deflate reaches about 1032:1.
constexpr long long kMaxCompressionRatio = 1100;
constexpr long long kMaxComponents = 1024;  // VTK's own arrays have at most 9 (tensors)
constexpr long long kMaxItems = std::numeric_limits<int>::max();  // femreg indexes with int

struct Tag {
  std::string name;
  std::map<std::string, std::string> attributes;
  size_t begin = 0;      // offset of '<'
  size_t content = 0;    // offset after '>'
  bool closing = false;  // </name>
  bool empty = false;    // <name ... />
};

// A DataArray of a piece, its header checked.
struct ArrayRef {
  std::string section;  // Points, Cells, PointData or CellData
  std::string name;
  std::string type;
  BinaryScalar scalar;
  int components = 1;
  std::string format;  // ascii, binary or appended
  size_t begin = 0;    // offset of the tag, for messages
  size_t content = 0;  // inline: first byte of the content
  size_t content_end = 0;
  long long offset = -1;  // appended: offset into the appended data
};

struct PieceRef {
  long long points = 0, cells = 0;
  size_t begin = 0;
  std::vector<ArrayRef> arrays;
};

BinaryScalar ScalarOf(const std::string& type) {
  if (type == "Int8" || type == "Char") return {1, false, true};
  if (type == "UInt8") return {1, false, false};
  if (type == "Int16") return {2, false, true};
  if (type == "UInt16") return {2, false, false};
  if (type == "Int32") return {4, false, true};
  if (type == "UInt32") return {4, false, false};
  if (type == "Int64") return {8, false, true};
  if (type == "UInt64") return {8, false, false};
  if (type == "Float32") return {4, true, true};
  if (type == "Float64") return {8, true, true};
  return {};
}

// The five predefined XML entities in an attribute value (names such as "a&amp;b").
std::string DecodeEntities(const std::string& text) {
  if (text.find('&') == std::string::npos) return text;
  static const std::pair<const char*, char> kEntities[] = {
      {"&amp;", '&'}, {"&lt;", '<'}, {"&gt;", '>'}, {"&quot;", '"'}, {"&apos;", '\''}};
  std::string out;
  for (size_t i = 0; i < text.size();) {
    bool replaced = false;
    for (const auto& [entity, ch] : kEntities) {
      const size_t n = std::strlen(entity);
      if (text.compare(i, n, entity) == 0) {
        out += ch;
        i += n;
        replaced = true;
        break;
      }
    }
    if (!replaced) out += text[i++];
  }
  return out;
}

int Base64Value(unsigned char c) {
  if (c >= 'A' && c <= 'Z') return c - 'A';
  if (c >= 'a' && c <= 'z') return c - 'a' + 26;
  if (c >= '0' && c <= '9') return c - '0' + 52;
  if (c == '+') return 62;
  if (c == '/') return 63;
  return -1;
}

class VtuReader {
 public:
  VtuReader(const std::string& path, std::string data) : path_(path), data_(std::move(data)) {}

  Status Read(VtuGrid* grid) {
    Status s = ParseStructure();
    if (!s.ok()) return s;
    grid->pieces.clear();
    grid->pieces.reserve(pieces_.size());
    for (size_t p = 0; p < pieces_.size(); ++p) {
      grid->pieces.emplace_back();
      if (!(s = ReadPiece(static_cast<int>(p), pieces_[p], &grid->pieces.back())).ok()) return s;
    }
    return Status::Ok();
  }

 private:
  Status Error(size_t offset, const std::string& message) const {
    std::ostringstream os;
    os << "byte " << offset << ": " << message;
    return FileError(path_, 0, os.str());
  }

  // ---- The XML part: tags and their attributes -------------------------------------------

  // "name" (value) of `tag` quoted for a message.
  static std::string Attr(const Tag& tag, const std::string& name) {
    return tag.name + " " + name + "=" + Quoted(tag.attributes.at(name));
  }

  static std::string Get(const Tag& tag, const char* name) {
    auto it = tag.attributes.find(name);
    return it == tag.attributes.end() ? std::string() : it->second;
  }

  // An integer attribute (absent: `fallback`), refused when not plainly an integer or
  // outside min..max.
  Status IntAttribute(const Tag& tag, const std::string& name, long long fallback, long long min,
                      long long max, long long* value) const {
    auto it = tag.attributes.find(name);
    if (it == tag.attributes.end()) {
      *value = fallback;
      return Status::Ok();
    }
    long long v;
    std::string text = it->second;
    while (!text.empty() && (text.back() == ' ' || text.back() == '\t')) text.pop_back();
    while (!text.empty() && (text.front() == ' ' || text.front() == '\t')) text.erase(0, 1);
    if (!ParseInt(text, &v)) return Error(tag.begin, Attr(tag, name) + " is not an integer");
    if (v < min || v > max) {
      std::ostringstream os;
      os << Attr(tag, name) << " is out of range (" << min << " to " << max << ")";
      return Error(tag.begin, os.str());
    }
    *value = v;
    return Status::Ok();
  }

  Status NextTag(size_t* pos, Tag* tag, bool* found) const {
    while (true) {
      const size_t lt = data_.find('<', *pos);
      if (lt == std::string::npos || lt >= xml_end_) {
        *found = false;
        return Status::Ok();
      }
      if (data_.compare(lt, 4, "<!--") == 0) {
        const size_t end = data_.find("-->", lt + 4);
        if (end == std::string::npos || end >= xml_end_) return Error(lt, "unterminated comment");
        *pos = end + 3;
        continue;
      }
      if (data_.compare(lt, 2, "<?") == 0 || data_.compare(lt, 2, "<!") == 0) {
        const size_t end = data_.find('>', lt);
        if (end == std::string::npos || end >= xml_end_) return Error(lt, "unterminated declaration");
        *pos = end + 1;
        continue;
      }
      size_t p = lt + 1;
      tag->begin = lt;
      tag->attributes.clear();
      tag->empty = false;
      tag->closing = p < xml_end_ && data_[p] == '/';
      if (tag->closing) ++p;
      const size_t name_start = p;
      while (p < xml_end_ && !std::isspace(static_cast<unsigned char>(data_[p])) && data_[p] != '>' &&
             data_[p] != '/') {
        ++p;
      }
      tag->name = data_.substr(name_start, p - name_start);
      if (tag->name.empty()) return Error(lt, "malformed tag");
      // Attributes: name = "value" or 'value'.
      while (true) {
        while (p < xml_end_ && std::isspace(static_cast<unsigned char>(data_[p]))) ++p;
        if (p >= xml_end_) return Error(lt, "unterminated tag <" + Quoted(tag->name, 40) + ">");
        if (data_[p] == '>') {
          ++p;
          break;
        }
        if (data_[p] == '/' && p + 1 < xml_end_ && data_[p + 1] == '>') {
          tag->empty = true;
          p += 2;
          break;
        }
        const size_t attr_start = p;
        while (p < xml_end_ && data_[p] != '=' && data_[p] != '>' &&
               !std::isspace(static_cast<unsigned char>(data_[p]))) {
          ++p;
        }
        const std::string attr = data_.substr(attr_start, p - attr_start);
        while (p < xml_end_ && std::isspace(static_cast<unsigned char>(data_[p]))) ++p;
        if (p >= xml_end_ || data_[p] != '=') {
          return Error(attr_start, "malformed attribute in <" + Quoted(tag->name, 40) + ">");
        }
        ++p;
        while (p < xml_end_ && std::isspace(static_cast<unsigned char>(data_[p]))) ++p;
        if (p >= xml_end_ || (data_[p] != '"' && data_[p] != '\'')) {
          return Error(attr_start, "attribute " + Quoted(attr, 40) + " has no quoted value");
        }
        const char quote = data_[p++];
        const size_t end = data_.find(quote, p);
        if (end == std::string::npos || end >= xml_end_) return Error(attr_start, "unterminated attribute value");
        if (!tag->attributes.emplace(attr, DecodeEntities(data_.substr(p, end - p))).second) {
          return Error(attr_start, "attribute " + Quoted(attr, 40) + " given twice");
        }
        p = end + 1;
      }
      tag->content = p;
      *pos = p;
      *found = true;
      return Status::Ok();
    }
  }

  Status FindAppendedData(size_t tag_start) {
    const size_t close = data_.find('>', tag_start);
    if (close == std::string::npos) return Error(tag_start, "unterminated <AppendedData> tag");
    const std::string tag = data_.substr(tag_start, close - tag_start);
    const bool raw = tag.find("encoding=\"raw\"") != std::string::npos;
    appended_base64_ = tag.find("encoding=\"base64\"") != std::string::npos;
    if (raw == appended_base64_) {
      return Error(tag_start, "<AppendedData> must have encoding=\"raw\" or encoding=\"base64\"");
    }
    const size_t underscore = data_.find('_', close);
    if (underscore == std::string::npos) return Error(close, "appended data without its '_' marker");
    for (size_t p = close + 1; p < underscore; ++p) {
      if (!std::isspace(static_cast<unsigned char>(data_[p]))) {
        return Error(p, "a byte other than white space before the appended data's '_' marker");
      }
    }
    appended_begin_ = underscore + 1;
    const size_t end_tag = data_.rfind("</AppendedData>");
    appended_end_ = end_tag == std::string::npos || end_tag < appended_begin_ ? data_.size() : end_tag;
    has_appended_ = true;
    return Status::Ok();
  }

  Status ParseStructure() {
    // The XML part ends where the appended data starts (raw data may hold any byte).
    const size_t appended_tag = data_.find("<AppendedData");
    xml_end_ = appended_tag == std::string::npos ? data_.size() : appended_tag;
    Status s;
    if (appended_tag != std::string::npos && !(s = FindAppendedData(appended_tag)).ok()) return s;
    if (data_.find("<!DOCTYPE") < xml_end_ || data_.find("<!ENTITY") < xml_end_) {
      return Error(data_.find("<!"), "a DOCTYPE or ENTITY declaration (not in a VTK file)");
    }
    size_t pos = 0;
    std::vector<std::string> open;
    bool saw_file = false;
    while (true) {
      Tag tag;
      bool found = false;
      if (!(s = NextTag(&pos, &tag, &found)).ok()) return s;
      if (!found) break;
      if (tag.closing) {
        if (!open.empty() && open.back() == tag.name) open.pop_back();
        continue;
      }
      const std::string parent = open.empty() ? "" : open.back();
      bool in_field_data = false;
      for (const std::string& o : open) in_field_data = in_field_data || o == "FieldData";
      if (tag.name == "VTKFile") {
        if (saw_file) return Error(tag.begin, "a second <VTKFile> element");
        if (!(s = CheckFile(tag)).ok()) return s;
        saw_file = true;
      } else if (!saw_file) {
        return Error(tag.begin, "<" + Quoted(tag.name, 40) + "> before the <VTKFile> element");
      } else if (tag.name == "Piece") {
        if (!(s = AddPiece(tag)).ok()) return s;
      } else if (tag.name == "DataArray" && !in_field_data) {
        const bool in_piece = std::find(open.begin(), open.end(), "Piece") != open.end();
        const bool section = parent == "Points" || parent == "Cells" || parent == "PointData" ||
                             parent == "CellData";
        ArrayRef array;
        if (!(s = ParseArray(tag, parent, &array)).ok()) return s;
        if (in_piece && section) pieces_.back().arrays.push_back(std::move(array));
      }
      if (!tag.empty) open.push_back(tag.name);
      if (tag.name == "DataArray" && !tag.empty) {
        // Skip the array's content (text or base64) to its end tag.
        const size_t end = data_.find("</DataArray", tag.content);
        pos = end == std::string::npos || end > xml_end_ ? xml_end_ : end;
      }
    }
    if (!saw_file) return Error(0, "no <VTKFile> element");
    if (pieces_.empty()) return Error(0, "no <Piece> element");
    return Status::Ok();
  }

  Status CheckFile(const Tag& tag) {
    if (Get(tag, "type") != "UnstructuredGrid") {
      return Error(tag.begin, "VTKFile type=" + Quoted(Get(tag, "type")) + " is not UnstructuredGrid");
    }
    const std::string order = Get(tag, "byte_order");
    if (!order.empty() && order != "LittleEndian" && order != "BigEndian") {
      return Error(tag.begin, "VTKFile byte_order=" + Quoted(order) + " is not LittleEndian or BigEndian");
    }
    big_endian_ = order == "BigEndian";
    const std::string header = Get(tag, "header_type");
    if (!header.empty() && header != "UInt32" && header != "UInt64") {
      return Error(tag.begin, "VTKFile header_type=" + Quoted(header) + " is not UInt32 or UInt64");
    }
    header_size_ = header == "UInt64" ? 8 : 4;
    const std::string compressor = Get(tag, "compressor");
    if (compressor == "vtkLZ4DataCompressor" || compressor == "vtkLZMADataCompressor") {
      return Error(tag.begin, "VTKFile compressor=" + Quoted(compressor) +
                                  " is not supported (only vtkZLibDataCompressor)");
    }
    if (!compressor.empty() && compressor != "vtkZLibDataCompressor") {
      return Error(tag.begin, "VTKFile compressor=" + Quoted(compressor) + " is not one VTK has");
    }
    compressed_ = !compressor.empty();
    return Status::Ok();
  }

  Status AddPiece(const Tag& tag) {
    // Uncompressed, every point or cell takes at least a byte somewhere in the file;
    // compressed, at most kMaxCompressionRatio times that.
    const long long size = static_cast<long long>(data_.size());
    const long long bound = std::min(kMaxItems, compressed_ ? size * kMaxCompressionRatio : size);
    PieceRef piece;
    piece.begin = tag.begin;
    Status s = IntAttribute(tag, "NumberOfPoints", 0, 0, bound, &piece.points);
    if (!s.ok()) return s;
    if (!(s = IntAttribute(tag, "NumberOfCells", 0, 0, bound, &piece.cells)).ok()) return s;
    // Running totals (each at most kMaxItems, so the sums cannot overflow).
    if (total_points_ + piece.points > kMaxItems || total_cells_ + piece.cells > kMaxItems) {
      return Error(tag.begin, "the pieces have more than 2147483647 points or cells in all");
    }
    total_points_ += piece.points;
    total_cells_ += piece.cells;
    pieces_.push_back(piece);
    return Status::Ok();
  }

  Status ParseArray(const Tag& tag, const std::string& parent, ArrayRef* array) const {
    array->section = parent;
    array->name = Get(tag, "Name");
    array->type = Get(tag, "type");
    array->scalar = ScalarOf(array->type);
    array->begin = tag.begin;
    if (array->scalar.size == 0) {
      return Error(tag.begin, "DataArray type=" + Quoted(array->type) + " is not a numeric VTK type");
    }
    long long components, tuples;
    Status s = IntAttribute(tag, "NumberOfComponents", 1, 1, kMaxComponents, &components);
    if (!s.ok()) return s;
    array->components = static_cast<int>(components);
    if (parent == "Points" && components != 3) {
      return Error(tag.begin, "the Points array must have NumberOfComponents=\"3\", not " +
                                  std::to_string(components));
    }
    if (parent == "Cells" && components != 1) {
      return Error(tag.begin, "a Cells array must have one component, not " + std::to_string(components));
    }
    const long long size = static_cast<long long>(data_.size());
    const long long tuple_bound = std::min(kMaxItems, compressed_ ? size * kMaxCompressionRatio : size);
    if (!(s = IntAttribute(tag, "NumberOfTuples", -1, 0, tuple_bound, &tuples)).ok()) return s;
    array->format = Get(tag, "format");
    if (array->format == "ascii" || array->format == "binary") {
      if (tag.empty) {
        array->content = array->content_end = tag.content;
      } else {
        const size_t end = data_.find("</DataArray", tag.content);
        array->content = tag.content;
        array->content_end = end == std::string::npos || end > xml_end_ ? xml_end_ : end;
      }
      return Status::Ok();
    }
    if (array->format != "appended") {
      return Error(tag.begin, "DataArray format=" + Quoted(array->format) + " is not ascii, binary or appended");
    }
    if (!has_appended_) return Error(tag.begin, "format=\"appended\" but the file has no <AppendedData>");
    const long long length = static_cast<long long>(appended_end_ - appended_begin_);
    if (!(s = IntAttribute(tag, "offset", -1, 0, std::max(0LL, length - 1), &array->offset)).ok()) return s;
    if (array->offset < 0) return Error(tag.begin, "appended DataArray without an offset");
    return Status::Ok();
  }

  // ---- Array data ------------------------------------------------------------------------

  // Bytes of binary data: raw from the file, or decoded from base64 text as they are taken.
  // A base64 stream may be several padded parts one after the other (VTK encodes a
  // compression header apart from the blocks): each group of four characters is decoded on
  // its own.
  class ByteStream {
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
  uint64_t Word(const char* p) const {
    uint64_t v = 0;
    for (int i = 0; i < header_size_; ++i) {
      const int k = big_endian_ ? i : header_size_ - 1 - i;
      v = (v << 8) | static_cast<unsigned char>(p[k]);
    }
    return v;
  }

  static std::string Describe(const ArrayRef& a) {
    return a.format + " DataArray " + Quoted(a.name, 40);
  }

  Status ReadAscii(const ArrayRef& a, long long values, std::vector<double>* out) const {
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
  Status ReadBinaryBytes(const ArrayRef& a, uint64_t bytes, std::string* out) const {
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
  Status ReadValues(const ArrayRef& a, long long values, std::vector<double>* out) const {
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

  const ArrayRef* Find(const PieceRef& piece, const std::string& section, const char* name) const {
    for (const ArrayRef& a : piece.arrays) {
      if (a.section == section && (name == nullptr || a.name == name)) return &a;
    }
    return nullptr;
  }

  Status ReadPiece(int index, const PieceRef& ref, VtuPiece* piece) const {
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

  const std::string path_;
  const std::string data_;
  size_t xml_end_ = 0;
  bool has_appended_ = false, appended_base64_ = false;
  size_t appended_begin_ = 0, appended_end_ = 0;
  bool big_endian_ = false, compressed_ = false;
  int header_size_ = 4;
  std::vector<PieceRef> pieces_;
  long long total_points_ = 0, total_cells_ = 0;  // over pieces_
};

}  // namespace

Status ReadVtuGrid(const std::string& path, VtuGrid* grid) {
  std::ifstream in(path, std::ios::binary);
  if (!in) return Status::Error(path + ": cannot open file");
  std::ostringstream ss;
  ss << in.rdbuf();
  if (in.bad()) return Status::Error(path + ": read error");
  return VtuReader(path, ss.str()).Read(grid);
}

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
