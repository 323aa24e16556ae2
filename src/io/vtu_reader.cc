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
#include "io/vtu_reader_internal.h"

namespace femreg {
namespace internal {
namespace vtu {
namespace {

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

}  // namespace

Status VtuReader::Read(VtuGrid* grid) {
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

Status VtuReader::Error(size_t offset, const std::string& message) const {
  std::ostringstream os;
  os << "byte " << offset << ": " << message;
  return FileError(path_, 0, os.str());
}

// "name" (value) of `tag` quoted for a message.
std::string VtuReader::Attr(const Tag& tag, const std::string& name) {
  return tag.name + " " + name + "=" + Quoted(tag.attributes.at(name));
}

std::string VtuReader::Get(const Tag& tag, const char* name) {
  auto it = tag.attributes.find(name);
  return it == tag.attributes.end() ? std::string() : it->second;
}

// An integer attribute (absent: `fallback`), refused when not plainly an integer or
// outside min..max.
Status VtuReader::IntAttribute(const Tag& tag, const std::string& name, long long fallback, long long min,
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

Status VtuReader::NextTag(size_t* pos, Tag* tag, bool* found) const {
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

Status VtuReader::FindAppendedData(size_t tag_start) {
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

Status VtuReader::ParseStructure() {
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

Status VtuReader::CheckFile(const Tag& tag) {
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

Status VtuReader::AddPiece(const Tag& tag) {
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

Status VtuReader::ParseArray(const Tag& tag, const std::string& parent, ArrayRef* array) const {
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

}  // namespace vtu

using vtu::VtuReader;

Status ReadVtuGrid(const std::string& path, VtuGrid* grid) {
  std::ifstream in(path, std::ios::binary);
  if (!in) return Status::Error(path + ": cannot open file");
  std::ostringstream ss;
  ss << in.rdbuf();
  if (in.bad()) return Status::Error(path + ": read error");
  return VtuReader(path, ss.str()).Read(grid);
}

}  // namespace internal
}  // namespace femreg
