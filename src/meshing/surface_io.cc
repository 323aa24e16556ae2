// Surfaces in (PLY here; OBJ and STL through ReadTriangleSurface) and tetrahedral meshes out
// (.vtu through WriteVtu; Gmsh 2.2, MEDIT and VTK legacy written here).
#include <algorithm>
#include <cctype>
#include <cerrno>
#include <cmath>
#include <cstdarg>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <limits>
#include <sstream>
#include <string>
#include <vector>

#include "femreg/collision_spec.h"  // ReadTriangleSurface (OBJ, STL)
#include "femreg/io.h"
#include "femreg/meshing.h"

namespace femreg {
namespace {

std::string Lower(std::string s) {
  for (char& c : s) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return s;
}

std::string Extension(const std::string& path) {
  const size_t slash = path.find_last_of('/');
  const size_t dot = path.find_last_of('.');
  if (dot == std::string::npos || (slash != std::string::npos && dot < slash)) return "";
  return Lower(path.substr(dot));
}

// A token as the file has it, shortened for messages.
std::string Quote(const std::string& token) {
  if (token.size() <= 40) return "'" + token + "'";
  return "'" + token.substr(0, 40) + "...' (" + std::to_string(token.size()) + " bytes)";
}

// ---------------------------------------------------------------------------------------
// PLY.

enum class PlyType { kInt8, kUint8, kInt16, kUint16, kInt32, kUint32, kFloat32, kFloat64 };

bool ParsePlyType(const std::string& name, PlyType* type) {
  static const std::pair<const char*, PlyType> kTypes[] = {
      {"char", PlyType::kInt8},      {"int8", PlyType::kInt8},       {"uchar", PlyType::kUint8},
      {"uint8", PlyType::kUint8},    {"short", PlyType::kInt16},     {"int16", PlyType::kInt16},
      {"ushort", PlyType::kUint16},  {"uint16", PlyType::kUint16},   {"int", PlyType::kInt32},
      {"int32", PlyType::kInt32},    {"uint", PlyType::kUint32},     {"uint32", PlyType::kUint32},
      {"float", PlyType::kFloat32},  {"float32", PlyType::kFloat32}, {"double", PlyType::kFloat64},
      {"float64", PlyType::kFloat64}};
  for (const auto& t : kTypes) {
    if (name == t.first) {
      *type = t.second;
      return true;
    }
  }
  return false;
}

size_t PlySize(PlyType type) {
  switch (type) {
    case PlyType::kInt8:
    case PlyType::kUint8:
      return 1;
    case PlyType::kInt16:
    case PlyType::kUint16:
      return 2;
    case PlyType::kInt32:
    case PlyType::kUint32:
    case PlyType::kFloat32:
      return 4;
    case PlyType::kFloat64:
      return 8;
  }
  return 1;
}

bool PlyIsInteger(PlyType type) { return type != PlyType::kFloat32 && type != PlyType::kFloat64; }

struct PlyProperty {
  std::string name;
  bool is_list = false;
  PlyType count_type = PlyType::kUint8;  // lists only
  PlyType type = PlyType::kFloat32;      // the value (or list item) type
};

struct PlyElement {
  std::string name;
  long long count = 0;
  std::vector<PlyProperty> properties;
  int line = 0;
};

// Reads the values of a PLY body one at a time, ASCII or binary, tracking where it is.
class PlyBody {
 public:
  PlyBody(const std::string& path, const std::string& bytes, size_t offset, int line, bool ascii,
          bool big_endian)
      : path_(path),
        bytes_(bytes),
        pos_(offset),
        line_(line),
        ascii_(ascii),
        big_endian_(big_endian) {}

  Status Read(PlyType type, const std::string& what, double* value) {
    if (ascii_) {
      std::string token;
      if (!NextToken(&token)) return Error("the file ends before " + what);
      char* end = nullptr;
      errno = 0;
      if (PlyIsInteger(type)) {
        const long long v = std::strtoll(token.c_str(), &end, 10);
        if (*end != '\0' || errno != 0)
          return Error("expected an integer for " + what + ", got " + Quote(token));
        *value = static_cast<double>(v);
      } else {
        *value = std::strtod(token.c_str(), &end);
        if (*end != '\0' || token.empty())
          return Error("expected a number for " + what + ", got " + Quote(token));
      }
      return Status::Ok();
    }
    const size_t size = PlySize(type);
    if (bytes_.size() - pos_ < size) return Error("the file ends before " + what);
    unsigned char b[8];
    std::memcpy(b, bytes_.data() + pos_, size);
    if (big_endian_) std::reverse(b, b + size);
    pos_ += size;
    switch (type) {
      case PlyType::kInt8:
        *value = static_cast<int8_t>(b[0]);
        break;
      case PlyType::kUint8:
        *value = b[0];
        break;
      case PlyType::kInt16: {
        int16_t v;
        std::memcpy(&v, b, 2);
        *value = v;
        break;
      }
      case PlyType::kUint16: {
        uint16_t v;
        std::memcpy(&v, b, 2);
        *value = v;
        break;
      }
      case PlyType::kInt32: {
        int32_t v;
        std::memcpy(&v, b, 4);
        *value = v;
        break;
      }
      case PlyType::kUint32: {
        uint32_t v;
        std::memcpy(&v, b, 4);
        *value = v;
        break;
      }
      case PlyType::kFloat32: {
        float v;
        std::memcpy(&v, b, 4);
        *value = v;
        break;
      }
      case PlyType::kFloat64: {
        double v;
        std::memcpy(&v, b, 8);
        *value = v;
        break;
      }
    }
    return Status::Ok();
  }

  // "path:line: message" for ASCII, "path: byte N: message" for binary.
  Status Error(const std::string& message) const {
    if (ascii_) return Status::Error(path_ + ":" + std::to_string(token_line_) + ": " + message);
    return Status::Error(path_ + ": byte " + std::to_string(pos_) + ": " + message);
  }

 private:
  bool NextToken(std::string* token) {
    while (pos_ < bytes_.size() && std::isspace(static_cast<unsigned char>(bytes_[pos_]))) {
      if (bytes_[pos_] == '\n') ++line_;
      ++pos_;
    }
    token_line_ = line_;
    if (pos_ >= bytes_.size()) return false;
    const size_t begin = pos_;
    while (pos_ < bytes_.size() && !std::isspace(static_cast<unsigned char>(bytes_[pos_]))) ++pos_;
    token->assign(bytes_, begin, pos_ - begin);
    return true;
  }

  const std::string& path_;
  const std::string& bytes_;
  size_t pos_;
  int line_;
  int token_line_ = 0;
  bool ascii_, big_endian_;
};

Status ReadPly(const std::string& path, const std::string& bytes, Vertices* V, Triangles* F) {
  auto error = [&path](int line, const std::string& message) {
    return Status::Error(path + ":" + std::to_string(line) + ": " + message);
  };
  // Header: lines up to end_header.
  size_t pos = 0;
  int line = 0;
  std::string format;
  std::vector<PlyElement> elements;
  bool ended = false;
  while (!ended) {
    if (pos >= bytes.size()) return error(line, "the header has no end_header line");
    size_t eol = bytes.find('\n', pos);
    if (eol == std::string::npos) eol = bytes.size();
    std::string text = bytes.substr(pos, eol - pos);
    if (!text.empty() && text.back() == '\r') text.pop_back();
    pos = std::min(eol + 1, bytes.size());
    ++line;
    std::istringstream ls(text);
    std::string keyword;
    ls >> keyword;
    if (line == 1) {
      if (keyword != "ply") return error(1, "not a PLY file (it does not start with 'ply')");
      continue;
    }
    if (keyword.empty() || keyword == "comment" || keyword == "obj_info") continue;
    if (keyword == "format") {
      std::string version;
      ls >> format >> version;
      if (format != "ascii" && format != "binary_little_endian" && format != "binary_big_endian") {
        return error(line, "unknown format " + Quote(format) +
                               " (expected ascii, binary_little_endian or binary_big_endian)");
      }
    } else if (keyword == "element") {
      PlyElement e;
      std::string count;
      ls >> e.name >> count;
      char* end = nullptr;
      errno = 0;
      e.count = std::strtoll(count.c_str(), &end, 10);
      if (e.name.empty() || count.empty() || *end != '\0' || errno != 0 || e.count < 0 ||
          e.count > std::numeric_limits<int>::max()) {
        return error(line,
                     "bad element line (expected 'element NAME COUNT' with 0 <= COUNT < 2^31)");
      }
      e.line = line;
      elements.push_back(e);
    } else if (keyword == "property") {
      if (elements.empty()) return error(line, "a property before any element");
      PlyProperty p;
      std::string type;
      ls >> type;
      if (type == "list") {
        std::string count_type, item_type;
        ls >> count_type >> item_type >> p.name;
        p.is_list = true;
        if (!ParsePlyType(count_type, &p.count_type) || !PlyIsInteger(p.count_type) ||
            !ParsePlyType(item_type, &p.type)) {
          return error(line,
                       "bad list property (expected 'property list COUNT_TYPE TYPE NAME' "
                       "with an integer COUNT_TYPE)");
        }
      } else {
        ls >> p.name;
        if (!ParsePlyType(type, &p.type))
          return error(line, "unknown property type " + Quote(type));
      }
      if (p.name.empty()) return error(line, "a property without a name");
      elements.back().properties.push_back(p);
    } else if (keyword == "end_header") {
      ended = true;
    } else {
      return error(line, "unknown header line starting with " + Quote(keyword));
    }
  }
  if (format.empty()) return error(line, "the header has no format line");
  const bool ascii = format == "ascii";

  // Which element and properties hold what.
  int vertex_element = -1, face_element = -1;
  for (size_t e = 0; e < elements.size(); ++e) {
    if (elements[e].name == "vertex" && vertex_element < 0) vertex_element = static_cast<int>(e);
    if (elements[e].name == "face" && face_element < 0) face_element = static_cast<int>(e);
  }
  if (vertex_element < 0) return error(line, "no 'element vertex' in the header");
  if (face_element < 0) {
    return error(line, "no 'element face' in the header: a point cloud, not a surface");
  }
  int xyz[3] = {-1, -1, -1};
  const PlyElement& ve = elements[static_cast<size_t>(vertex_element)];
  for (size_t p = 0; p < ve.properties.size(); ++p) {
    for (int k = 0; k < 3; ++k) {
      if (ve.properties[p].name == std::string(1, static_cast<char>('x' + k)) &&
          !ve.properties[p].is_list) {
        xyz[k] = static_cast<int>(p);
      }
    }
  }
  if (xyz[0] < 0 || xyz[1] < 0 || xyz[2] < 0) {
    return error(ve.line, "the vertex element lacks an x, y or z property");
  }
  int indices = -1;
  const PlyElement& fe = elements[static_cast<size_t>(face_element)];
  for (size_t p = 0; p < fe.properties.size(); ++p) {
    if (fe.properties[p].is_list &&
        (fe.properties[p].name == "vertex_indices" || fe.properties[p].name == "vertex_index")) {
      indices = static_cast<int>(p);
    }
  }
  if (indices < 0) {
    return error(fe.line, "the face element has no 'vertex_indices' (or 'vertex_index') list");
  }
  if (!PlyIsInteger(fe.properties[static_cast<size_t>(indices)].type)) {
    return error(fe.line, "the face vertex indices are not integers");
  }

  // Counts the body cannot hold are refused before anything is allocated: each record
  // takes at least its fixed-size part (binary) or one byte per value (ASCII, with spaces).
  size_t at_least = 0;
  for (const PlyElement& e : elements) {
    size_t record = 0;
    for (const PlyProperty& p : e.properties) {
      record += ascii ? 2 : (p.is_list ? PlySize(p.count_type) : PlySize(p.type));
    }
    if (record > 0 && static_cast<unsigned long long>(e.count) > (bytes.size() - pos) / record) {
      return error(e.line, "the header announces " + std::to_string(e.count) + " " + e.name +
                               " records, more than the " + std::to_string(bytes.size() - pos) +
                               " bytes after the header can hold");
    }
    at_least += record * static_cast<size_t>(e.count);
  }
  if (at_least > bytes.size() - pos) {
    return error(line, "the header's elements need at least " + std::to_string(at_least) +
                           " bytes, the file has " + std::to_string(bytes.size() - pos) +
                           " after the header");
  }

  PlyBody body(path, bytes, pos, line + 1, ascii, format == "binary_big_endian");
  std::vector<double> vertices;
  std::vector<int> triangles;
  Status s;
  for (size_t e = 0; e < elements.size(); ++e) {
    const PlyElement& el = elements[e];
    const bool is_vertex = static_cast<int>(e) == vertex_element;
    const bool is_face = static_cast<int>(e) == face_element;
    if (is_vertex) vertices.reserve(3 * static_cast<size_t>(el.count));
    if (is_face) triangles.reserve(3 * static_cast<size_t>(el.count));
    std::vector<int> polygon;
    for (long long r = 0; r < el.count; ++r) {
      double point[3] = {0, 0, 0};
      for (size_t p = 0; p < el.properties.size(); ++p) {
        const PlyProperty& prop = el.properties[p];
        const std::string what = el.name + " " + std::to_string(r) + "'s " + prop.name;
        if (!prop.is_list) {
          double value;
          if (!(s = body.Read(prop.type, what, &value)).ok()) return s;
          for (int k = 0; k < 3; ++k) {
            if (is_vertex && static_cast<int>(p) == xyz[k]) {
              if (!std::isfinite(value)) return body.Error(what + " is not finite");
              point[k] = value;
            }
          }
          continue;
        }
        double n;
        if (!(s = body.Read(prop.count_type, "the length of " + what, &n)).ok()) return s;
        const bool wanted = is_face && static_cast<int>(p) == indices;
        if (n < 0 || (wanted && n < 3) || n > 1e6) {
          return body.Error(what + " has " + std::to_string(static_cast<long long>(n)) +
                            " entries" + (wanted ? " (a face needs at least 3 corners)" : ""));
        }
        polygon.clear();
        for (long long i = 0; i < static_cast<long long>(n); ++i) {
          double value;
          if (!(s = body.Read(prop.type, what, &value)).ok()) return s;
          if (wanted) {
            if (value < 0 || value >= static_cast<double>(ve.count)) {
              return body.Error(what + " refers to vertex " +
                                std::to_string(static_cast<long long>(value)) + ", outside 0.." +
                                std::to_string(ve.count - 1));
            }
            polygon.push_back(static_cast<int>(value));
          }
        }
        for (size_t k = 1; wanted && k + 1 < polygon.size(); ++k) {
          triangles.insert(triangles.end(), {polygon[0], polygon[k], polygon[k + 1]});
        }
      }
      if (is_vertex) vertices.insert(vertices.end(), point, point + 3);
    }
  }
  V->resize(static_cast<Eigen::Index>(vertices.size() / 3), 3);
  std::copy(vertices.begin(), vertices.end(), V->data());
  F->resize(static_cast<Eigen::Index>(triangles.size() / 3), 3);
  std::copy(triangles.begin(), triangles.end(), F->data());
  if (F->rows() == 0) return Status::Error(path + ": no face");
  return Status::Ok();
}

// ---------------------------------------------------------------------------------------
// Tetrahedral meshes out.

void AppendF(std::string* out, const char* format, ...) __attribute__((format(printf, 2, 3)));
void AppendF(std::string* out, const char* format, ...) {
  char buf[256];
  va_list args;
  va_start(args, format);
  const int n = std::vsnprintf(buf, sizeof(buf), format, args);
  va_end(args);
  if (n > 0) out->append(buf, static_cast<size_t>(std::min(n, static_cast<int>(sizeof(buf)) - 1)));
}

std::string GmshText(const TetMesh& mesh) {
  std::string s = "$MeshFormat\n2.2 0 8\n$EndMeshFormat\n$Nodes\n";
  AppendF(&s, "%d\n", mesh.num_vertices());
  for (int v = 0; v < mesh.num_vertices(); ++v) {
    AppendF(&s, "%d %.17g %.17g %.17g\n", v + 1, mesh.rest(v, 0), mesh.rest(v, 1), mesh.rest(v, 2));
  }
  AppendF(&s, "$EndNodes\n$Elements\n%d\n", mesh.num_tets());
  for (int t = 0; t < mesh.num_tets(); ++t) {
    // Type 4: a 4-node tetrahedron; tags: physical group (the region), elementary entity.
    const int region = mesh.region.size() == mesh.num_tets() ? mesh.region(t) : 0;
    AppendF(&s, "%d 4 2 %d %d %d %d %d %d\n", t + 1, region, region + 1, mesh.tets(t, 0) + 1,
            mesh.tets(t, 1) + 1, mesh.tets(t, 2) + 1, mesh.tets(t, 3) + 1);
  }
  s += "$EndElements\n";
  return s;
}

std::string MeditText(const TetMesh& mesh) {
  std::string s = "MeshVersionFormatted 2\nDimension 3\nVertices\n";
  AppendF(&s, "%d\n", mesh.num_vertices());
  for (int v = 0; v < mesh.num_vertices(); ++v) {
    AppendF(&s, "%.17g %.17g %.17g 0\n", mesh.rest(v, 0), mesh.rest(v, 1), mesh.rest(v, 2));
  }
  AppendF(&s, "Tetrahedra\n%d\n", mesh.num_tets());
  for (int t = 0; t < mesh.num_tets(); ++t) {
    const int region = mesh.region.size() == mesh.num_tets() ? mesh.region(t) : 0;
    AppendF(&s, "%d %d %d %d %d\n", mesh.tets(t, 0) + 1, mesh.tets(t, 1) + 1, mesh.tets(t, 2) + 1,
            mesh.tets(t, 3) + 1, region);
  }
  s += "End\n";
  return s;
}

std::string VtkLegacyText(const TetMesh& mesh) {
  std::string s =
      "# vtk DataFile Version 3.0\nfemreg tetrahedral mesh\nASCII\n"
      "DATASET UNSTRUCTURED_GRID\n";
  AppendF(&s, "POINTS %d double\n", mesh.num_vertices());
  for (int v = 0; v < mesh.num_vertices(); ++v) {
    AppendF(&s, "%.17g %.17g %.17g\n", mesh.rest(v, 0), mesh.rest(v, 1), mesh.rest(v, 2));
  }
  AppendF(&s, "CELLS %d %d\n", mesh.num_tets(), 5 * mesh.num_tets());
  for (int t = 0; t < mesh.num_tets(); ++t) {
    AppendF(&s, "4 %d %d %d %d\n", mesh.tets(t, 0), mesh.tets(t, 1), mesh.tets(t, 2),
            mesh.tets(t, 3));
  }
  AppendF(&s, "CELL_TYPES %d\n", mesh.num_tets());
  for (int t = 0; t < mesh.num_tets(); ++t) s += "10\n";  // VTK_TETRA
  AppendF(&s, "CELL_DATA %d\nSCALARS region int 1\nLOOKUP_TABLE default\n", mesh.num_tets());
  for (int t = 0; t < mesh.num_tets(); ++t) {
    AppendF(&s, "%d\n", mesh.region.size() == mesh.num_tets() ? mesh.region(t) : 0);
  }
  return s;
}

}  // namespace

Status ReadSurface(const std::string& path, Vertices* V, Triangles* F) {
  const std::string ext = Extension(path);
  if (ext == ".obj" || ext == ".stl") return ReadTriangleSurface(path, V, F);
  if (ext != ".ply") {
    return Status::Error(path + ": unknown surface format '" + ext +
                         "' (expected .ply, .obj or .stl)");
  }
  std::ifstream in(path, std::ios::binary);
  if (!in) return Status::Error(path + ": cannot open");
  std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  return ReadPly(path, bytes, V, F);
}

Status WriteTetMesh(const std::string& path, const TetMesh& mesh) {
  const std::string ext = Extension(path);
  if (mesh.num_tets() == 0) return Status::Error(path + ": the mesh has no tetrahedra to write");
  if (ext == ".vtu") return WriteVtu(path, mesh, mesh.rest);
  if (ext == ".msh") return WriteFileAtomically(path, GmshText(mesh));
  if (ext == ".mesh") return WriteFileAtomically(path, MeditText(mesh));
  if (ext == ".vtk") return WriteFileAtomically(path, VtkLegacyText(mesh));
  return Status::Error(path + ": unknown mesh format '" + ext +
                       "' (expected .vtu, .msh, .mesh or .vtk)");
}

}  // namespace femreg
