// The one PLY reader: ASCII and binary (either byte order) PLY, any elements, scalar and
// list properties. Point clouds (ReadPlyCloud) and triangle surfaces (ReadPlySurface) are
// read through it.
#ifndef FEMREG_IO_PLY_READER_H_
#define FEMREG_IO_PLY_READER_H_

#include <functional>
#include <string>
#include <vector>

#include "femreg/status.h"
#include "io/io_internal.h"
#include "io/text_tokens.h"

namespace femreg {
namespace internal {

struct PlyProperty {
  std::string name;
  BinaryScalar type;        // the value, or a list's item type
  bool is_list = false;
  BinaryScalar count_type;  // lists only: the length's type (an integer)
};

struct PlyElement {
  std::string name;
  long long count = 0;
  std::vector<PlyProperty> properties;
  int line = 0;  // of its header line
};

// One element instance as the body has it.
struct PlyRow {
  std::vector<double> values;              // per property: the value (a list: its length)
  std::vector<std::vector<double>> lists;  // per property: a list's items (a scalar: empty)
};

// A PLY file: Open reads the header and checks every element count against the bytes after
// it, before anything is sized from a count; ReadBody then reads the instances in order.
// Errors name the file and the line (header, ASCII body) or the byte (binary body).
class PlyFile {
 public:
  Status Open(const std::string& path);

  const std::string& path() const { return in_.path(); }
  const std::vector<PlyElement>& elements() const { return elements_; }
  int end_line() const { return end_line_; }  // the end_header line
  // The element called `name`, or -1.
  int FindElement(const std::string& name) const;
  // The scalar (list = false) or list property `name` of element `element`, or -1.
  int FindProperty(int element, const std::string& name, bool list) const;

  // Reads every instance of every element, in file order, and hands it to `visit`, which
  // may refuse it (its Status is returned).
  using Visitor = std::function<Status(int element, long long index, const PlyRow& row)>;
  Status ReadBody(const Visitor& visit);

  // "path:line: message" for the header.
  Status HeaderError(int line, const std::string& message) const { return FileError(path(), line, message); }
  // "path:line: message" at the last token read (ASCII), "path: byte N: message" after the
  // last value read (binary).
  Status BodyError(const std::string& message) const;

 private:
  Status ReadHeader();
  Status ReadValue(const BinaryScalar& type, const std::string& what, double* value);

  TokenStream in_;
  std::vector<PlyElement> elements_;
  bool ascii_ = true, big_endian_ = false;
  int end_line_ = 0;
  size_t pos_ = 0;  // binary: the next byte
};

// A PLY point cloud: the vertex element's x, y, z and, when all three are there, nx, ny, nz
// (or normal_x, normal_y, normal_z); other elements and properties are read and skipped.
Status ReadPlyCloud(const std::string& path, RawCloud* cloud);

// A PLY surface: the vertex element's x, y, z (finite) and the face element's
// vertex_indices (or vertex_index) lists, polygons split into fans of triangles.
Status ReadPlySurface(const std::string& path, Vertices* V, Triangles* F);

}  // namespace internal
}  // namespace femreg

#endif  // FEMREG_IO_PLY_READER_H_
