// VTK legacy UNSTRUCTURED_GRID, ASCII or BINARY (big-endian), versions up to 5.1
// (OFFSETS/CONNECTIVITY): tetrahedra (cell type 10) kept, other cells skipped; a
// CELL_DATA scalar or field array named like "region"/"tag" gives the region ids.
//
// BINARY files are read here too, not by VTK's vtkUnstructuredGridReader: that reader sizes
// its arrays from the header counts without comparing them with the file (a count of
// -2147483649 or one larger than the file crashed it), so every count is checked against
// the bytes that are left before anything is allocated or read.
#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>
#include <set>
#include <sstream>

#include "io/io_internal.h"
#include "io/text_tokens.h"

namespace femreg {
namespace internal {
namespace {

constexpr int kVtkTetra = 10;

std::string Upper(std::string s) {
  std::transform(s.begin(), s.end(), s.begin(),
                 [](unsigned char c) { return static_cast<char>(std::toupper(c)); });
  return s;
}

const std::set<std::string>& Keywords() {
  static const std::set<std::string> keywords = {
      "POINTS",  "CELLS",   "CELL_TYPES", "CELL_DATA",          "POINT_DATA",
      "SCALARS", "VECTORS", "NORMALS",    "TENSORS",            "TEXTURE_COORDINATES",
      "FIELD",   "LOOKUP_TABLE", "COLOR_SCALARS", "METADATA",    "DATASET"};
  return keywords;
}

// A legacy data type: its size in a BINARY file (values are big-endian).
using ValueType = BinaryScalar;

ValueType TypeOf(const std::string& name) {
  const std::string t = Upper(name);
  if (t == "FLOAT") return {4, true, true};
  if (t == "DOUBLE") return {8, true, true};
  if (t == "CHAR" || t == "SIGNED_CHAR") return {1, false, true};
  if (t == "UNSIGNED_CHAR") return {1, false, false};
  if (t == "SHORT") return {2, false, true};
  if (t == "UNSIGNED_SHORT") return {2, false, false};
  if (t == "INT" || t == "VTKTYPEINT32") return {4, false, true};
  if (t == "UNSIGNED_INT" || t == "VTKTYPEUINT32") return {4, false, false};
  if (t == "LONG" || t == "VTKTYPEINT64" || t == "VTKIDTYPE") return {8, false, true};
  if (t == "UNSIGNED_LONG" || t == "VTKTYPEUINT64") return {8, false, false};
  return {};
}


class VtkLegacyReader {
 public:
  VtkLegacyReader(TokenStream* in, bool binary, RawTetMesh* raw)
      : in_(*in), binary_(binary), raw_(*raw) {}

  Status Read() {
    Token t;
    Status s;
    bool saw_points = false, saw_cells = false, saw_types = false;
    while (in_.Next(&t)) {
      const std::string keyword = Upper(t.text);
      if (keyword == "DATASET") {
        std::string type;
        if (!(s = in_.NextWord("the dataset type", &type)).ok()) return s;
        if (Upper(type) != "UNSTRUCTURED_GRID") {
          return in_.Error("dataset " + Quoted(type) + " is not supported (UNSTRUCTURED_GRID is)");
        }
      } else if (keyword == "POINTS") {
        if (saw_points) return in_.Error("a second POINTS section");
        s = ReadPoints();
        saw_points = true;
      } else if (keyword == "CELLS") {
        if (saw_cells) return in_.Error("a second CELLS section");
        s = ReadCells();
        saw_cells = true;
      } else if (keyword == "CELL_TYPES") {
        if (saw_types) return in_.Error("a second CELL_TYPES section");
        s = ReadCellTypes();
        saw_types = true;
      } else if (keyword == "CELL_DATA" || keyword == "POINT_DATA") {
        long long n;
        if (!(s = in_.NextInt("the number of data values", &n)).ok()) return s;
        if (n < 0) return in_.Error(keyword + " count is negative");
        per_cell_ = keyword == "CELL_DATA";
        attribute_count_ = n;
      } else if (keyword == "SCALARS") {
        s = ReadScalars();
      } else if (keyword == "VECTORS" || keyword == "NORMALS") {
        s = SkipNamedArray(3);
      } else if (keyword == "TENSORS") {
        s = SkipNamedArray(9);
      } else if (keyword == "TEXTURE_COORDINATES") {
        std::string name, type;
        long long dim;
        if (!(s = in_.NextWord("the array name", &name)).ok()) return s;
        if (!(s = in_.NextInt("the dimension", &dim)).ok()) return s;
        if (dim < 1 || dim > 3) return in_.Error("texture coordinates have 1 to 3 dimensions");
        if (!(s = in_.NextWord("the data type", &type)).ok()) return s;
        s = ReadArray("TEXTURE_COORDINATES", type, dim, attribute_count_, nullptr);
      } else if (keyword == "COLOR_SCALARS") {
        std::string name;
        long long m;
        if (!(s = in_.NextWord("the array name", &name)).ok()) return s;
        if (!(s = in_.NextInt("the number of values", &m)).ok()) return s;
        if (m < 1 || m > 4) return in_.Error("color scalars have 1 to 4 values");
        s = ReadArray("COLOR_SCALARS", binary_ ? "unsigned_char" : "float", m, attribute_count_,
                      nullptr);
      } else if (keyword == "LOOKUP_TABLE") {
        std::string name;
        long long size;
        if (!(s = in_.NextWord("the table name", &name)).ok()) return s;
        if (!(s = in_.NextInt("the table size", &size)).ok()) return s;
        s = ReadArray("LOOKUP_TABLE", binary_ ? "unsigned_char" : "float", 4, size, nullptr);
      } else if (keyword == "FIELD") {
        s = ReadField();
      } else if (keyword == "METADATA") {
        // Text even in binary files; skipped up to the next keyword.
        while (in_.Peek(&t) && Keywords().count(Upper(t.text)) == 0) in_.Next(&t);
      } else {
        return in_.Error("unexpected " + Quoted(t.text));
      }
      if (!s.ok()) return s;
    }
    if (!saw_points) return in_.Error("no POINTS (truncated file?)");
    if (!saw_cells || !saw_types) return in_.Error("no CELLS or CELL_TYPES (truncated file?)");
    return Build();
  }

 private:
  // Reads tuples * components values of `type`, in text or in binary as the file is; keeps
  // them in *values unless it is null. Every count is checked against what is left of the
  // file before anything is allocated.
  Status ReadArray(const char* what, const std::string& type, long long components,
                   long long tuples, std::vector<double>* values) {
    std::ostringstream os;
    if (components < 0 || tuples < 0) {
      os << what << ": negative size (" << tuples << " tuples of " << components << ")";
      return in_.Error(os.str());
    }
    if (components > 0 && tuples > std::numeric_limits<long long>::max() / components) {
      os << what << ": " << tuples << " tuples of " << components << " components overflow";
      return in_.Error(os.str());
    }
    const long long count = components * tuples;
    if (values != nullptr) values->clear();
    if (!binary_) {
      if (count > MaxItemsIn(in_.remaining(), 1)) {
        os << what << ": " << tuples << " tuples of " << components << " values cannot fit in the "
           << in_.remaining() << " bytes left in the file";
        return in_.Error(os.str());
      }
      Status s;
      if (values != nullptr) values->reserve(static_cast<size_t>(count));
      for (long long i = 0; i < count; ++i) {
        double v;
        if (!(s = in_.NextDouble("a data value", &v)).ok()) return s;
        if (values != nullptr) values->push_back(v);
      }
      return Status::Ok();
    }
    const ValueType vt = TypeOf(type);
    if (vt.size == 0) {
      return in_.Error(std::string(what) + ": data type " + Quoted(type) +
                       " cannot be read from a BINARY file");
    }
    if (count > static_cast<long long>(in_.remaining() / static_cast<size_t>(vt.size))) {
      os << what << ": " << count << " values of " << vt.size << " bytes, more than the "
         << in_.remaining() << " bytes left in the file";
      return in_.Error(os.str());
    }
    const char* data = nullptr;
    Status s = in_.TakeBytes(what, static_cast<size_t>(count) * vt.size, &data);
    if (!s.ok()) return s;
    if (values != nullptr) {
      values->resize(static_cast<size_t>(count));
      for (long long i = 0; i < count; ++i) (*values)[i] = DecodeBinaryScalar(data + i * vt.size, vt, /*big_endian=*/true);
    }
    return Status::Ok();
  }

  // Integers (cell lists, offsets, types): like ReadArray, refusing non-integer values.
  Status ReadIntegers(const char* what, const std::string& type, long long count,
                      std::vector<long long>* values) {
    if (!binary_) {
      Status s = in_.CheckCount(what, count, 1);
      if (!s.ok()) return s;
      values->assign(static_cast<size_t>(count), 0);
      for (auto& v : *values) {
        if (!(s = in_.NextInt(what, &v)).ok()) return s;
      }
      return Status::Ok();
    }
    if (TypeOf(type).is_float) {
      return in_.Error(std::string(what) + " must have an integer type, not " + Quoted(type));
    }
    std::vector<double> doubles;
    Status s = ReadArray(what, type, 1, count, &doubles);
    if (!s.ok()) return s;
    values->resize(doubles.size());
    for (size_t i = 0; i < doubles.size(); ++i) {
      // Integers read as doubles are exact up to 2^53, far beyond any valid index.
      const double d = doubles[i];
      (*values)[i] = std::abs(d) < 9.0e15 ? static_cast<long long>(d) : -1;
    }
    return Status::Ok();
  }

  Status SkipNamedArray(long long components) {
    std::string name, type;
    Status s = in_.NextWord("the array name", &name);
    if (!s.ok()) return s;
    if (!(s = in_.NextWord("the data type", &type)).ok()) return s;
    return ReadArray(name.c_str(), type, components, attribute_count_, nullptr);
  }

  Status ReadPoints() {
    long long n;
    std::string type;
    Status s = in_.NextInt("the number of points", &n);
    if (!s.ok()) return s;
    if (!(s = in_.NextWord("the point type", &type)).ok()) return s;
    std::vector<double> xyz;
    if (!(s = ReadArray("POINTS", type, 3, n, &xyz)).ok()) return s;
    raw_.vertices.resize(static_cast<size_t>(n));
    for (long long i = 0; i < n; ++i) {
      for (int k = 0; k < 3; ++k) {
        raw_.vertices[i][k] = xyz[3 * i + k];
        if (!std::isfinite(raw_.vertices[i][k])) {
          std::ostringstream os;
          os << "point " << i << " has a non-finite coordinate";
          return in_.Error(os.str());
        }
      }
    }
    return Status::Ok();
  }

  Status CheckPointId(long long id) {
    if (id < 0 || id >= static_cast<long long>(raw_.vertices.size())) {
      std::ostringstream os;
      os << "cell refers to point " << id << ", outside 0.."
         << static_cast<long long>(raw_.vertices.size()) - 1 << " (index out of range)";
      return in_.Error(os.str());
    }
    return Status::Ok();
  }

  Status ReadCells() {
    long long a, b;
    Status s = in_.NextInt("the number of cells", &a);
    if (!s.ok()) return s;
    if (!(s = in_.NextInt("the size of the cell list", &b)).ok()) return s;
    if (a < 0 || b < 0) return in_.Error("CELLS counts are negative");
    Token t;
    if (in_.Peek(&t) && Upper(t.text) == "OFFSETS") {
      // Version 5: OFFSETS then CONNECTIVITY; a is the number of offsets (cells + 1).
      std::string type;
      in_.Next(&t);
      if (!(s = in_.NextWord("the offsets type", &type)).ok()) return s;
      std::vector<long long> offsets;
      if (!(s = ReadIntegers("OFFSETS", type, a, &offsets)).ok()) return s;
      if (!in_.Next(&t) || Upper(t.text) != "CONNECTIVITY") return in_.Error("expected CONNECTIVITY");
      if (!(s = in_.NextWord("the connectivity type", &type)).ok()) return s;
      const int first_line = in_.line();
      std::vector<long long> ids;
      if (!(s = ReadIntegers("CONNECTIVITY", type, b, &ids)).ok()) return s;
      for (long long id : ids) {
        if (!(s = CheckPointId(id)).ok()) return s;
      }
      for (size_t c = 0; c + 1 < offsets.size(); ++c) {
        if (offsets[c] < 0 || offsets[c + 1] < offsets[c] || offsets[c + 1] > b) {
          std::ostringstream os;
          os << "invalid cell offsets (cell " << c << ": " << offsets[c] << " to " << offsets[c + 1]
             << " of " << b << ")";
          return in_.Error(os.str());
        }
        cells_.emplace_back(ids.begin() + offsets[c], ids.begin() + offsets[c + 1]);
        cell_lines_.push_back(binary_ ? 0 : first_line);
      }
      return Status::Ok();
    }
    // Version 4: per cell, its number of points then the ids; b numbers in all.
    std::vector<long long> list;
    if (!binary_) {
      if (!(s = in_.CheckCount("the size of the cell list", b, 1)).ok()) return s;
      if (a > b) return in_.Error("more cells than numbers in the cell list");
      for (long long c = 0; c < a; ++c) {
        long long count;
        if (!(s = in_.NextInt("the number of points of a cell", &count)).ok()) return s;
        const int line = in_.line();
        if (count < 0) return in_.Error("negative number of points in a cell");
        if (!(s = in_.CheckCount("the number of points of a cell", count, 1)).ok()) return s;
        std::vector<long long> ids(static_cast<size_t>(count));
        for (auto& id : ids) {
          if (!(s = in_.NextInt("a point id", &id)).ok()) return s;
          if (!(s = CheckPointId(id)).ok()) return s;
        }
        cells_.push_back(std::move(ids));
        cell_lines_.push_back(line);
      }
      return Status::Ok();
    }
    if (!(s = ReadIntegers("CELLS", "int", b, &list)).ok()) return s;
    size_t pos = 0;
    for (long long c = 0; c < a; ++c) {
      if (pos >= list.size()) return in_.Error("the cell list ends before its last cell");
      const long long count = list[pos++];
      if (count < 0 || count > static_cast<long long>(list.size() - pos)) {
        std::ostringstream os;
        os << "cell " << c << " has " << count << " points, more than the cell list holds";
        return in_.Error(os.str());
      }
      std::vector<long long> ids(list.begin() + pos, list.begin() + pos + count);
      pos += static_cast<size_t>(count);
      for (long long id : ids) {
        if (!(s = CheckPointId(id)).ok()) return s;
      }
      cells_.push_back(std::move(ids));
      cell_lines_.push_back(0);
    }
    return Status::Ok();
  }

  Status ReadCellTypes() {
    long long n;
    Status s = in_.NextInt("the number of cell types", &n);
    if (!s.ok()) return s;
    if (n != static_cast<long long>(cells_.size())) {
      return in_.Error("CELL_TYPES count does not match the number of CELLS");
    }
    std::vector<long long> types;
    if (!(s = ReadIntegers("CELL_TYPES", "int", n, &types)).ok()) return s;
    cell_types_.resize(types.size());
    for (size_t i = 0; i < types.size(); ++i) {
      cell_types_[i] = types[i] == kVtkTetra ? kVtkTetra : -1;
    }
    return Status::Ok();
  }

  Status ReadScalars() {
    std::string name, type;
    Status s = in_.NextWord("the array name", &name);
    if (!s.ok()) return s;
    if (!(s = in_.NextWord("the data type", &type)).ok()) return s;
    long long components = 1;
    Token t;
    if (in_.Peek(&t) && t.line == in_.line() && Upper(t.text) != "LOOKUP_TABLE") {
      if (!(s = in_.NextInt("the number of components", &components)).ok()) return s;
      if (components < 1 || components > 4) return in_.Error("SCALARS have 1 to 4 components");
    }
    if (in_.Peek(&t) && Upper(t.text) == "LOOKUP_TABLE") {
      in_.Next(&t);
      std::string table;
      if (!(s = in_.NextWord("the lookup table name", &table)).ok()) return s;
    }
    return ReadNamedValues(name, type, components, attribute_count_);
  }

  Status ReadField() {
    std::string name;
    long long arrays;
    Status s = in_.NextWord("the field name", &name);
    if (!s.ok()) return s;
    if (!(s = in_.NextInt("the number of arrays", &arrays)).ok()) return s;
    // Each array has at least a name, two counts and a type.
    if (!(s = in_.CheckCount("the number of arrays", arrays, 4)).ok()) return s;
    for (long long i = 0; i < arrays; ++i) {
      std::string array_name, type;
      long long components, tuples;
      if (!(s = in_.NextWord("the array name", &array_name)).ok()) return s;
      if (!(s = in_.NextInt("the number of components", &components)).ok()) return s;
      if (!(s = in_.NextInt("the number of tuples", &tuples)).ok()) return s;
      if (!(s = in_.NextWord("the data type", &type)).ok()) return s;
      if (!(s = ReadNamedValues(array_name, type, components, tuples)).ok()) return s;
    }
    return Status::Ok();
  }

  Status ReadNamedValues(const std::string& name, const std::string& type, long long components,
                         long long tuples) {
    const bool is_region = per_cell_ && components == 1 && region_.empty() &&
                           LooksLikeRegionName(name);
    std::vector<double> values;
    Status s = ReadArray(("array " + Quoted(name)).c_str(), type, components, tuples,
                         is_region ? &values : nullptr);
    if (!s.ok() || !is_region) return s;
    region_.resize(values.size());
    for (size_t i = 0; i < values.size(); ++i) {
      if (!RegionIdFrom(values[i], &region_[i])) {
        std::ostringstream os;
        os << "array " << Quoted(name) << ": value " << i << " (" << values[i]
           << ") is not a region id (an integer in the range of int)";
        return in_.Error(os.str());
      }
    }
    return Status::Ok();
  }

  Status Build() {
    if (!region_.empty() && region_.size() != cells_.size()) region_.clear();
    for (size_t c = 0; c < cells_.size(); ++c) {
      if (cell_types_[c] != kVtkTetra) continue;
      if (cells_[c].size() != 4) {
        std::ostringstream os;
        os << "cell " << c << ": a tetrahedron (cell type 10) needs 4 points, it has "
           << cells_[c].size();
        return binary_ ? FileError(in_.path(), 0, os.str()) : in_.ErrorAt(cell_lines_[c], os.str());
      }
      raw_.tets.push_back({static_cast<int>(cells_[c][0]), static_cast<int>(cells_[c][1]),
                           static_cast<int>(cells_[c][2]), static_cast<int>(cells_[c][3])});
      raw_.tet_lines.push_back(cell_lines_[c]);
      raw_.regions.push_back(region_.empty() ? 0 : region_[c]);
    }
    return Status::Ok();
  }

  TokenStream& in_;
  const bool binary_;
  RawTetMesh& raw_;
  std::vector<std::vector<long long>> cells_;
  std::vector<int> cell_lines_;  // 0 in binary files
  std::vector<int> cell_types_;
  std::vector<int> region_;
  bool per_cell_ = false;
  long long attribute_count_ = 0;
};

}  // namespace

Status ReadVtkLegacyFile(const std::string& path, RawTetMesh* raw) {
  TokenStream in;
  Status s = in.Open(path, '\0');
  if (!s.ok()) return s;
  const std::vector<std::string> header = in.TakeLines(3);
  if (header.size() < 3) return FileError(path, static_cast<int>(header.size()), "truncated header");
  if (header[0].rfind("# vtk", 0) != 0) return FileError(path, 1, "not a VTK legacy file");
  const std::string encoding = Upper(header[2].substr(0, header[2].find_last_not_of(" \t") + 1));
  if (encoding != "ASCII" && encoding != "BINARY") {
    return FileError(path, 3, "expected ASCII or BINARY, found " + Quoted(header[2]));
  }
  return VtkLegacyReader(&in, encoding == "BINARY", raw).Read();
}

}  // namespace internal
}  // namespace femreg
