// VTK legacy ASCII UNSTRUCTURED_GRID: tetrahedra (cell type 10) kept, other cells skipped;
// a CELL_DATA scalar or field array named like "region"/"tag" gives the region ids.
// BINARY legacy files go through VTK's own reader.
#include <algorithm>
#include <cctype>
#include <cmath>
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

class VtkLegacyReader {
 public:
  VtkLegacyReader(TokenStream* in, RawTetMesh* raw) : in_(*in), raw_(*raw) {}

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
          return in_.Error("dataset " + type + " is not supported (UNSTRUCTURED_GRID is)");
        }
      } else if (keyword == "POINTS") {
        s = ReadPoints();
        saw_points = true;
      } else if (keyword == "CELLS") {
        s = ReadCells();
        saw_cells = true;
      } else if (keyword == "CELL_TYPES") {
        s = ReadCellTypes();
        saw_types = true;
      } else if (keyword == "CELL_DATA" || keyword == "POINT_DATA") {
        long long n;
        s = in_.NextInt("the number of data values", &n);
        per_cell_ = keyword == "CELL_DATA";
        attribute_count_ = n;
      } else if (keyword == "SCALARS") {
        s = ReadScalars();
      } else if (keyword == "VECTORS" || keyword == "NORMALS") {
        s = SkipNamedArray(3);
      } else if (keyword == "TENSORS") {
        s = SkipNamedArray(9);
      } else if (keyword == "TEXTURE_COORDINATES") {
        std::string name;
        long long dim;
        if (!(s = in_.NextWord("the array name", &name)).ok()) return s;
        if (!(s = in_.NextInt("the dimension", &dim)).ok()) return s;
        s = SkipNamedArrayValues(dim);
      } else if (keyword == "COLOR_SCALARS") {
        std::string name;
        long long m;
        if (!(s = in_.NextWord("the array name", &name)).ok()) return s;
        if (!(s = in_.NextInt("the number of values", &m)).ok()) return s;
        s = SkipValues(m * attribute_count_);
      } else if (keyword == "LOOKUP_TABLE") {
        std::string name;
        long long size;
        if (!(s = in_.NextWord("the table name", &name)).ok()) return s;
        if (!(s = in_.NextInt("the table size", &size)).ok()) return s;
        s = SkipValues(4 * size);
      } else if (keyword == "FIELD") {
        s = ReadField();
      } else if (keyword == "METADATA") {
        // Skipped up to the next keyword.
        while (in_.Peek(&t) && Keywords().count(Upper(t.text)) == 0) in_.Next(&t);
      } else {
        return in_.Error("unexpected '" + t.text + "'");
      }
      if (!s.ok()) return s;
    }
    if (!saw_points) return in_.Error("no POINTS (truncated file?)");
    if (!saw_cells || !saw_types) return in_.Error("no CELLS or CELL_TYPES (truncated file?)");
    return Build();
  }

 private:
  Status SkipValues(long long n) {
    Token t;
    for (long long i = 0; i < n; ++i) {
      if (!in_.Next(&t)) return in_.Error("unexpected end of file inside a data array");
    }
    return Status::Ok();
  }

  Status SkipNamedArray(long long components) {
    std::string name;
    Status s = in_.NextWord("the array name", &name);
    if (!s.ok()) return s;
    return SkipNamedArrayValues(components);
  }
  Status SkipNamedArrayValues(long long components) {
    std::string type;
    Status s = in_.NextWord("the data type", &type);
    if (!s.ok()) return s;
    return SkipValues(components * attribute_count_);
  }

  Status ReadPoints() {
    long long n;
    std::string type;
    Status s = in_.NextInt("the number of points", &n);
    if (!s.ok()) return s;
    if (!(s = in_.NextWord("the point type", &type)).ok()) return s;
    raw_.vertices.resize(static_cast<size_t>(std::max(0LL, n)));
    for (long long i = 0; i < n; ++i) {
      for (int k = 0; k < 3; ++k) {
        if (!(s = in_.NextDouble("a point coordinate", &raw_.vertices[i][k])).ok()) return s;
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
      os << "cell refers to point " << id << ", outside 0.." << raw_.vertices.size() - 1
         << " (index out of range)";
      return in_.Error(os.str());
    }
    return Status::Ok();
  }

  Status ReadCells() {
    long long a, b;
    Status s = in_.NextInt("the number of cells", &a);
    if (!s.ok()) return s;
    if (!(s = in_.NextInt("the size of the cell list", &b)).ok()) return s;
    Token t;
    if (in_.Peek(&t) && Upper(t.text) == "OFFSETS") {
      // Version 5: OFFSETS then CONNECTIVITY; a is the number of offsets (cells + 1).
      std::string type;
      in_.Next(&t);
      if (!(s = in_.NextWord("the offsets type", &type)).ok()) return s;
      std::vector<long long> offsets(static_cast<size_t>(std::max(0LL, a)));
      for (auto& o : offsets) {
        if (!(s = in_.NextInt("an offset", &o)).ok()) return s;
      }
      if (!in_.Next(&t) || Upper(t.text) != "CONNECTIVITY") return in_.Error("expected CONNECTIVITY");
      if (!(s = in_.NextWord("the connectivity type", &type)).ok()) return s;
      std::vector<long long> ids(static_cast<size_t>(std::max(0LL, b)));
      std::vector<int> lines(ids.size());
      for (size_t i = 0; i < ids.size(); ++i) {
        if (!(s = in_.NextInt("a point id", &ids[i])).ok()) return s;
        if (!(s = CheckPointId(ids[i])).ok()) return s;
        lines[i] = in_.line();
      }
      for (size_t c = 0; c + 1 < offsets.size(); ++c) {
        if (offsets[c] < 0 || offsets[c + 1] < offsets[c] || offsets[c + 1] > b) {
          return in_.Error("invalid cell offsets");
        }
        cells_.emplace_back(ids.begin() + offsets[c], ids.begin() + offsets[c + 1]);
        cell_lines_.push_back(offsets[c] < b ? lines[offsets[c]] : in_.line());
      }
      return Status::Ok();
    }
    for (long long c = 0; c < a; ++c) {
      long long count;
      if (!(s = in_.NextInt("the number of points of a cell", &count)).ok()) return s;
      const int line = in_.line();
      if (count < 0) return in_.Error("negative number of points in a cell");
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

  Status ReadCellTypes() {
    long long n;
    Status s = in_.NextInt("the number of cell types", &n);
    if (!s.ok()) return s;
    if (n != static_cast<long long>(cells_.size())) {
      return in_.Error("CELL_TYPES count does not match the number of CELLS");
    }
    cell_types_.resize(static_cast<size_t>(n));
    for (auto& type : cell_types_) {
      long long v;
      if (!(s = in_.NextInt("a cell type", &v)).ok()) return s;
      type = static_cast<int>(v);
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
    if (in_.Peek(&t) && t.line == in_.line()) {
      if (!(s = in_.NextInt("the number of components", &components)).ok()) return s;
    }
    if (in_.Peek(&t) && Upper(t.text) == "LOOKUP_TABLE") {
      in_.Next(&t);
      std::string table;
      if (!(s = in_.NextWord("the lookup table name", &table)).ok()) return s;
    }
    return ReadArrayValues(name, components, attribute_count_);
  }

  Status ReadField() {
    std::string name;
    long long arrays;
    Status s = in_.NextWord("the field name", &name);
    if (!s.ok()) return s;
    if (!(s = in_.NextInt("the number of arrays", &arrays)).ok()) return s;
    for (long long i = 0; i < arrays; ++i) {
      std::string array_name, type;
      long long components, tuples;
      if (!(s = in_.NextWord("the array name", &array_name)).ok()) return s;
      if (!(s = in_.NextInt("the number of components", &components)).ok()) return s;
      if (!(s = in_.NextInt("the number of tuples", &tuples)).ok()) return s;
      if (!(s = in_.NextWord("the data type", &type)).ok()) return s;
      if (!(s = ReadArrayValues(array_name, components, tuples)).ok()) return s;
    }
    return Status::Ok();
  }

  Status ReadArrayValues(const std::string& name, long long components, long long tuples) {
    const bool is_region = per_cell_ && components == 1 && region_.empty() &&
                           LooksLikeRegionName(name);
    Status s;
    for (long long i = 0; i < components * tuples; ++i) {
      double v;
      if (!(s = in_.NextDouble("a data value", &v)).ok()) return s;
      if (is_region) region_.push_back(std::isfinite(v) ? static_cast<int>(std::lround(v)) : 0);
    }
    return Status::Ok();
  }

  Status Build() {
    if (!region_.empty() && region_.size() != cells_.size()) region_.clear();
    for (size_t c = 0; c < cells_.size(); ++c) {
      if (cell_types_[c] != kVtkTetra) continue;
      if (cells_[c].size() != 4) {
        return in_.ErrorAt(cell_lines_[c], "a tetrahedron (cell type 10) needs 4 points");
      }
      raw_.tets.push_back({static_cast<int>(cells_[c][0]), static_cast<int>(cells_[c][1]),
                           static_cast<int>(cells_[c][2]), static_cast<int>(cells_[c][3])});
      raw_.tet_lines.push_back(cell_lines_[c]);
      raw_.regions.push_back(region_.empty() ? 0 : region_[c]);
    }
    return Status::Ok();
  }

  TokenStream& in_;
  RawTetMesh& raw_;
  std::vector<std::vector<long long>> cells_;
  std::vector<int> cell_lines_;
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
  if (encoding == "BINARY") return ReadLegacyVtkWithVtk(path, raw);
  if (encoding != "ASCII") return FileError(path, 3, "expected ASCII or BINARY");
  return VtkLegacyReader(&in, raw).Read();
}

}  // namespace internal
}  // namespace femreg
