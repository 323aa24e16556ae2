// Checks a VTK XML unstructured grid against its own length before VTK's reader sees it.
//
// vtkXMLUnstructuredGridReader trusts the header: NumberOfComponents="-4" made it throw
// std::bad_alloc from inside VTK (an abort), NumberOfComponents="4294967299" made it loop
// for minutes, and the counts of a Piece size its arrays before any data is read. Here every
// number VTK will size something from is parsed strictly and compared with the bytes the
// file holds for it: inline ASCII and base64 text, or raw appended blocks (whose byte-count
// and compression headers are read and checked too).
#include <algorithm>
#include <cctype>
#include <cstdint>
#include <cstring>
#include <fstream>
#include <limits>
#include <map>
#include <set>
#include <sstream>
#include <vector>

#include "io/io_internal.h"
#include "io/text_tokens.h"

namespace femreg {
namespace internal {
namespace {

// Largest expansion of one compressed byte: zlib's deflate reaches about 1032:1, LZ4
// about 255:1, LZMA more (about 7000:1 on constant data): the bound for all three.
constexpr long long kMaxCompressionRatio = 8192;
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

class VtuChecker {
 public:
  VtuChecker(const std::string& path, std::string data) : path_(path), data_(std::move(data)) {}

  Status Check() {
    // The XML part ends where the appended data starts.
    const size_t appended_tag = data_.find("<AppendedData");
    xml_end_ = appended_tag == std::string::npos ? data_.size() : appended_tag;
    Status s;
    if (appended_tag != std::string::npos && !(s = FindAppendedData(appended_tag)).ok()) return s;
    if (data_.find("<!DOCTYPE") < xml_end_ || data_.find("<!ENTITY") < xml_end_) {
      return Error(data_.find("<!"), "a DOCTYPE or ENTITY declaration (not in a VTK file)");
    }
    size_t pos = 0;
    std::vector<std::string> open;
    bool saw_file = false, saw_piece = false;
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
      if (tag.name == "VTKFile") {
        if (!(s = CheckFile(tag)).ok()) return s;
        saw_file = true;
      } else if (tag.name == "Piece") {
        if (!(s = CheckPiece(tag)).ok()) return s;
        saw_piece = true;
      } else if (tag.name == "DataArray") {
        if (!(s = CheckArray(tag, parent, open)).ok()) return s;
        // Two arrays of one name in one section made VTK 9.1 read through a null pointer
        // (vtkXMLUnstructuredGridReader::ReadArrayForCells).
        auto name = tag.attributes.find("Name");
        if (name != tag.attributes.end() && !section_names_.insert(name->second).second) {
          return Error(tag.begin, "a second DataArray named " + Quoted(name->second, 40) + " in <" + parent + ">");
        }
      }
      if (tag.name != "DataArray") section_names_.clear();  // a new section
      if (!tag.empty) open.push_back(tag.name);
      if (tag.name == "DataArray" && !tag.empty) {
        // Skip the array's content (text or base64) to its end tag.
        const size_t end = data_.find("</DataArray", tag.content);
        pos = end == std::string::npos || end > xml_end_ ? xml_end_ : end;
      }
    }
    if (!saw_file) return Error(0, "no <VTKFile> element");
    if (!saw_piece) return Error(0, "no <Piece> element");
    return Status::Ok();
  }

 private:
  Status Error(size_t offset, const std::string& message) const {
    std::ostringstream os;
    os << "byte " << offset << ": " << message;
    return FileError(path_, 0, os.str());
  }

  // "name" (value) of `tag` quoted for a message.
  static std::string Attr(const Tag& tag, const std::string& name) {
    return tag.name + " " + name + "=" + Quoted(tag.attributes.at(name));
  }

  // A non-negative integer attribute (absent: `fallback`), refused when not plainly an
  // integer or above `max`.
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
        if (p >= xml_end_ || data_[p] != '=') return Error(attr_start, "malformed attribute in <" + tag->name + ">");
        ++p;
        while (p < xml_end_ && std::isspace(static_cast<unsigned char>(data_[p]))) ++p;
        if (p >= xml_end_ || (data_[p] != '"' && data_[p] != '\'')) {
          return Error(attr_start, "attribute " + Quoted(attr, 40) + " has no quoted value");
        }
        const char quote = data_[p++];
        const size_t end = data_.find(quote, p);
        if (end == std::string::npos || end >= xml_end_) return Error(attr_start, "unterminated attribute value");
        if (!tag->attributes.emplace(attr, data_.substr(p, end - p)).second) {
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
    // Only white space before the marker: VTK's own scan for it reads other bytes otherwise
    // (a NUL there made it take a block count of 1.6e9 and allocate 6 GB).
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

  Status CheckFile(const Tag& tag) {
    auto get = [&](const char* name) {
      auto it = tag.attributes.find(name);
      return it == tag.attributes.end() ? std::string() : it->second;
    };
    if (get("type") != "UnstructuredGrid") {
      return Error(tag.begin, "VTKFile type=" + Quoted(get("type")) + " is not UnstructuredGrid");
    }
    const std::string order = get("byte_order");
    if (!order.empty() && order != "LittleEndian" && order != "BigEndian") {
      return Error(tag.begin, "VTKFile byte_order=" + Quoted(order) + " is not LittleEndian or BigEndian");
    }
    big_endian_ = order == "BigEndian";
    const std::string header = get("header_type");
    if (!header.empty() && header != "UInt32" && header != "UInt64") {
      return Error(tag.begin, "VTKFile header_type=" + Quoted(header) + " is not UInt32 or UInt64");
    }
    header_size_ = header == "UInt64" ? 8 : 4;
    const std::string compressor = get("compressor");
    if (!compressor.empty() && compressor != "vtkZLibDataCompressor" &&
        compressor != "vtkLZ4DataCompressor" && compressor != "vtkLZMADataCompressor") {
      return Error(tag.begin, "VTKFile compressor=" + Quoted(compressor) + " is not one VTK has");
    }
    compressed_ = !compressor.empty();
    return Status::Ok();
  }

  Status CheckPiece(const Tag& tag) {
    // Uncompressed, every point or cell takes at least a byte somewhere in the file;
    // compressed, at most kMaxCompressionRatio times that.
    const long long size = static_cast<long long>(data_.size());
    const long long bound = std::min(kMaxItems, compressed_ ? size * kMaxCompressionRatio : size);
    Status s = IntAttribute(tag, "NumberOfPoints", 0, 0, bound, &points_);
    if (!s.ok()) return s;
    return IntAttribute(tag, "NumberOfCells", 0, 0, bound, &cells_);
  }

  static int TypeSize(const std::string& type) {
    if (type == "Int8" || type == "UInt8" || type == "Char") return 1;
    if (type == "Int16" || type == "UInt16") return 2;
    if (type == "Int32" || type == "UInt32" || type == "Float32") return 4;
    if (type == "Int64" || type == "UInt64" || type == "Float64") return 8;
    return 0;
  }

  // A header word (UInt32 or UInt64, in the file's byte order) at `offset`.
  uint64_t Word(size_t offset) const {
    uint64_t v = 0;
    for (int i = 0; i < header_size_; ++i) {
      const int k = big_endian_ ? i : header_size_ - 1 - i;
      v = (v << 8) | static_cast<unsigned char>(data_[offset + static_cast<size_t>(k)]);
    }
    return v;
  }

  Status CheckArray(const Tag& tag, const std::string& parent, const std::vector<std::string>& open) {
    auto get = [&](const char* name) {
      auto it = tag.attributes.find(name);
      return it == tag.attributes.end() ? std::string() : it->second;
    };
    const std::string type = get("type");
    const int type_size = TypeSize(type);
    if (type_size == 0) {
      return Error(tag.begin, "DataArray type=" + Quoted(type) + " is not a numeric VTK type");
    }
    long long components, tuples_attr, offset;
    Status s = IntAttribute(tag, "NumberOfComponents", 1, 1, kMaxComponents, &components);
    if (!s.ok()) return s;
    // VTK refuses other shapes here, but leaks the arrays it had made on the way.
    if (parent == "Points" && components != 3) {
      return Error(tag.begin, "the Points array must have NumberOfComponents=\"3\", not " +
                                  std::to_string(components));
    }
    if (parent == "Cells" && components != 1) {
      return Error(tag.begin, "a Cells array must have one component, not " + std::to_string(components));
    }
    const long long size = static_cast<long long>(data_.size());
    const long long tuple_bound = std::min(kMaxItems, compressed_ ? size * kMaxCompressionRatio : size);
    if (!(s = IntAttribute(tag, "NumberOfTuples", -1, 0, tuple_bound, &tuples_attr)).ok()) return s;
    // How many tuples VTK will expect (-1: not known from the header, e.g. connectivity).
    long long tuples = tuples_attr;
    const std::string name = get("Name");
    bool in_field_data = false;
    for (const std::string& o : open) in_field_data = in_field_data || o == "FieldData";
    if (!in_field_data) {
      if (parent == "Points" || parent == "PointData") tuples = points_;
      if (parent == "CellData" || (parent == "Cells" && (name == "offsets" || name == "types"))) {
        tuples = cells_;
      }
    }
    // Values and bytes the array needs: at most 2^31 tuples of 1024 components of 8 bytes.
    const long long values = tuples >= 0 ? tuples * components : 0;
    const long long bytes = values * type_size;
    const std::string format = get("format");
    if (format == "ascii") {
      const size_t end = data_.find("</DataArray", tag.content);
      const size_t text = (end == std::string::npos || end > xml_end_ ? xml_end_ : end) - tag.content;
      if (values > MaxItemsIn(text, 1)) {
        std::ostringstream os;
        os << "ascii DataArray " << Quoted(name, 40) << " needs " << values
           << " values, its text has " << text << " bytes";
        return Error(tag.begin, os.str());
      }
      // Every value a number of the array's kind: VTK 9.1 dereferences a null pointer
      // (SIGSEGV in vtkXMLDataReader::ReadPieceData) after a token it cannot parse.
      const bool integer = type.find("Float") == std::string::npos;
      long long count = 0;
      size_t p = tag.content;
      const size_t stop = tag.content + text;
      while (p < stop) {
        while (p < stop && std::isspace(static_cast<unsigned char>(data_[p]))) ++p;
        const size_t begin = p;
        while (p < stop && !std::isspace(static_cast<unsigned char>(data_[p]))) ++p;
        if (begin == p) break;
        const std::string token = data_.substr(begin, p - begin);
        long long i;
        double d;
        // Plain decimal only: hexadecimal floats, "nan" and "inf" are what strtod takes but
        // not necessarily VTK's parser.
        const bool decimal = token.find_first_not_of("0123456789+-.eE") == std::string::npos;
        if (!decimal || (integer ? !ParseInt(token, &i) : !ParseDouble(token, &d))) {
          std::ostringstream os;
          os << "ascii DataArray " << Quoted(name, 40) << " value " << count << " is not "
             << (integer ? "an integer" : "a number") << ": " << Quoted(token);
          return Error(begin, os.str());
        }
        ++count;
      }
      if (count < values) {
        std::ostringstream os;
        os << "ascii DataArray " << Quoted(name, 40) << " has " << count << " values, the header's counts need "
           << values;
        return Error(tag.begin, os.str());
      }
      return Status::Ok();
    }
    if (format == "binary") {
      const size_t end = data_.find("</DataArray", tag.content);
      const long long text =
          static_cast<long long>((end == std::string::npos || end > xml_end_ ? xml_end_ : end) - tag.content);
      const long long decoded = text / 4 * 3 + 3;
      if (bytes > (compressed_ ? decoded * kMaxCompressionRatio : decoded)) {
        std::ostringstream os;
        os << "binary DataArray " << Quoted(name, 40) << " needs " << bytes << " bytes, its "
           << text << " bytes of base64 cannot hold them";
        return Error(tag.begin, os.str());
      }
      return Status::Ok();
    }
    if (format != "appended") {
      return Error(tag.begin, "DataArray format=" + Quoted(format) + " is not ascii, binary or appended");
    }
    if (!has_appended_) return Error(tag.begin, "format=\"appended\" but the file has no <AppendedData>");
    const long long length = static_cast<long long>(appended_end_ - appended_begin_);
    if (!(s = IntAttribute(tag, "offset", -1, 0, std::max(0LL, length - 1), &offset)).ok()) return s;
    if (offset < 0) return Error(tag.begin, "appended DataArray without an offset");
    if (appended_base64_) {
      const long long decoded = (length - offset) / 4 * 3 + 3;
      if (bytes > (compressed_ ? decoded * kMaxCompressionRatio : decoded)) {
        return Error(tag.begin, "appended DataArray " + Quoted(name, 40) + " is longer than the appended data");
      }
      return Status::Ok();
    }
    // Raw appended data: a byte count, or the compression header, then the bytes.
    const size_t at = appended_begin_ + static_cast<size_t>(offset);
    const long long left = length - offset;
    std::ostringstream os;
    os << "appended DataArray " << Quoted(name, 40) << " at offset " << offset << ": ";
    if (!compressed_) {
      if (left < header_size_) return Error(at, os.str() + "its byte count runs past the end of the data");
      const uint64_t count = Word(at);
      if (count > static_cast<uint64_t>(left - header_size_)) {
        os << "says " << count << " bytes, " << left - header_size_ << " are left";
        return Error(at, os.str());
      }
      if (static_cast<long long>(count) < bytes) {
        os << "holds " << count << " bytes, the header's counts need " << bytes;
        return Error(at, os.str());
      }
      return Status::Ok();
    }
    // [number of blocks, block size, last block size, compressed size of each block]
    if (left < 3LL * header_size_) return Error(at, os.str() + "its compression header runs past the end");
    const uint64_t blocks = Word(at), block_size = Word(at + header_size_),
                   last_size = Word(at + 2 * header_size_);
    if (blocks > static_cast<uint64_t>((left - 3LL * header_size_) / header_size_)) {
      os << blocks << " compressed blocks, more than the data holds";
      return Error(at, os.str());
    }
    // No blocks with a last block of some size made VTK 9.1 read through a null pointer.
    if ((blocks == 0 && last_size != 0) ||
        (blocks > 0 && (block_size == 0 || last_size > block_size ||
                        block_size > static_cast<uint64_t>(std::numeric_limits<int>::max())))) {
      os << "block size " << block_size << " and last block size " << last_size << " are inconsistent";
      return Error(at, os.str());
    }
    uint64_t compressed_total = 0;
    for (uint64_t b = 0; b < blocks; ++b) {
      const uint64_t block = Word(at + (3 + b) * header_size_);
      if (block > static_cast<uint64_t>(left)) {
        compressed_total = static_cast<uint64_t>(left) + 1;
        break;
      }
      compressed_total += block;  // both <= left: no overflow
      if (compressed_total > static_cast<uint64_t>(left)) break;
    }
    const long long data_left = left - static_cast<long long>((3 + blocks) * header_size_);
    if (compressed_total > static_cast<uint64_t>(data_left)) {
      os << "its compressed blocks need " << compressed_total << " bytes, " << data_left << " are left";
      return Error(at, os.str());
    }
    const uint64_t uncompressed =
        blocks == 0 ? 0 : (blocks - 1) * block_size + (last_size == 0 ? block_size : last_size);
    if (uncompressed / kMaxCompressionRatio > compressed_total + 1) {
      os << uncompressed << " bytes cannot come out of " << compressed_total << " compressed ones";
      return Error(at, os.str());
    }
    if (static_cast<long long>(uncompressed) < bytes) {
      os << "holds " << uncompressed << " bytes, the header's counts need " << bytes;
      return Error(at, os.str());
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
  long long points_ = 0, cells_ = 0;
  std::set<std::string> section_names_;  // array names in the current section
};

}  // namespace

Status CheckVtuFile(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) return Status::Error(path + ": cannot open file");
  std::ostringstream ss;
  ss << in.rdbuf();
  if (in.bad()) return Status::Error(path + ": read error");
  return VtuChecker(path, ss.str()).Check();
}

}  // namespace internal
}  // namespace femreg
