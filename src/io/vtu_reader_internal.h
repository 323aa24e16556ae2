// femreg's own reader of VTK XML unstructured grids (.vtu), shared by its two files:
// vtu_reader.cc reads the XML structure (tags, attributes, the pieces and their arrays'
// headers), vtu_reader_data.cc the arrays' data (ASCII, base64, raw, zlib blocks) and
// the pieces (vtu_reader.cc's opening comment has what is checked and why).
#ifndef FEMREG_IO_VTU_READER_INTERNAL_H_
#define FEMREG_IO_VTU_READER_INTERNAL_H_

#include <cstdint>
#include <limits>
#include <map>
#include <string>
#include <utility>
#include <vector>

#include "io/io_internal.h"

namespace femreg {
namespace internal {
namespace vtu {

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

class VtuReader {
 public:
  VtuReader(const std::string& path, std::string data) : path_(path), data_(std::move(data)) {}

  Status Read(VtuGrid* grid);

 private:
  Status Error(size_t offset, const std::string& message) const;

  // ---- The XML part: tags and their attributes -------------------------------------------

  // "name" (value) of `tag` quoted for a message.
  static std::string Attr(const Tag& tag, const std::string& name);

  static std::string Get(const Tag& tag, const char* name);

  // An integer attribute (absent: `fallback`), refused when not plainly an integer or
  // outside min..max.
  Status IntAttribute(const Tag& tag, const std::string& name, long long fallback, long long min,
                      long long max, long long* value) const;

  Status NextTag(size_t* pos, Tag* tag, bool* found) const;

  Status FindAppendedData(size_t tag_start);

  Status ParseStructure();

  Status CheckFile(const Tag& tag);

  Status AddPiece(const Tag& tag);

  Status ParseArray(const Tag& tag, const std::string& parent, ArrayRef* array) const;

  // ---- Array data ------------------------------------------------------------------------

  // Bytes of binary data: raw from the file, or decoded from base64 text as they are taken.
  // A base64 stream may be several padded parts one after the other (VTK encodes a
  // compression header apart from the blocks): each group of four characters is decoded on
  // its own.
  class ByteStream;

  // A header word (UInt32 or UInt64, in the file's byte order).
  uint64_t Word(const char* p) const;

  static std::string Describe(const ArrayRef& a);

  Status ReadAscii(const ArrayRef& a, long long values, std::vector<double>* out) const;

  // The bytes of a binary or appended array: a byte count and the data, or a zlib
  // compression header and the compressed blocks. At least `bytes` bytes.
  Status ReadBinaryBytes(const ArrayRef& a, uint64_t bytes, std::string* out) const;

  // `values` values of array `a` as doubles.
  Status ReadValues(const ArrayRef& a, long long values, std::vector<double>* out) const;

  const ArrayRef* Find(const PieceRef& piece, const std::string& section, const char* name) const;

  Status ReadPiece(int index, const PieceRef& ref, VtuPiece* piece) const;

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

}  // namespace vtu
}  // namespace internal
}  // namespace femreg

#endif  // FEMREG_IO_VTU_READER_INTERNAL_H_
