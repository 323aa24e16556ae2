// The one PLY reader (ply_reader.h), and the point clouds and surfaces read through it.
#include "io/ply_reader.h"

#include <cmath>
#include <limits>
#include <sstream>
#include <string>
#include <vector>

namespace femreg {
namespace internal {
namespace {

constexpr long long kMaxCount = std::numeric_limits<int>::max();  // #V, #F are int

std::vector<std::string> Split(const std::string& line) {
  std::istringstream in(line);
  std::vector<std::string> words;
  for (std::string w; in >> w;) words.push_back(w);
  return words;
}

BinaryScalar PlyScalar(const std::string& name) {
  if (name == "char" || name == "int8") return {1, false, true};
  if (name == "uchar" || name == "uint8") return {1, false, false};
  if (name == "short" || name == "int16") return {2, false, true};
  if (name == "ushort" || name == "uint16") return {2, false, false};
  if (name == "int" || name == "int32") return {4, false, true};
  if (name == "uint" || name == "uint32") return {4, false, false};
  if (name == "float" || name == "float32") return {4, true, true};
  if (name == "double" || name == "float64") return {8, true, true};
  return {};
}

}  // namespace

Status PlyFile::Open(const std::string& path) {
  Status s = in_.Open(path, '\0');
  if (!s.ok()) return s;
  return ReadHeader();
}

int PlyFile::FindElement(const std::string& name) const {
  for (size_t e = 0; e < elements_.size(); ++e) {
    if (elements_[e].name == name) return static_cast<int>(e);
  }
  return -1;
}

int PlyFile::FindProperty(int element, const std::string& name, bool list) const {
  const std::vector<PlyProperty>& properties = elements_[static_cast<size_t>(element)].properties;
  for (size_t p = 0; p < properties.size(); ++p) {
    if (properties[p].name == name && properties[p].is_list == list) return static_cast<int>(p);
  }
  return -1;
}

Status PlyFile::ReadHeader() {
  std::vector<std::string> lines = in_.TakeLines(1);
  if (lines.empty() || Split(lines[0]).empty() || Split(lines[0])[0] != "ply") {
    return HeaderError(1, "not a PLY file (it does not start with 'ply')");
  }
  std::string format;
  while (true) {
    lines = in_.TakeLines(1);
    const int line = in_.line();
    if (lines.empty()) return HeaderError(line, "the header has no end_header line (truncated file?)");
    const std::vector<std::string> w = Split(lines[0]);
    if (w.empty() || w[0] == "comment" || w[0] == "obj_info") continue;
    if (w[0] == "end_header") break;
    if (w[0] == "format") {
      const std::string found = w.size() > 1 ? w[1] : "";
      if (w.size() > 3 || (found != "ascii" && found != "binary_little_endian" &&
                           found != "binary_big_endian")) {
        return HeaderError(line, "unknown format " + Quoted(found, 40) +
                                     " (expected ascii, binary_little_endian or binary_big_endian)");
      }
      format = found;
    } else if (w[0] == "element") {
      PlyElement e;
      if (w.size() != 3 || !ParseInt(w[2], &e.count) || e.count < 0 || e.count > kMaxCount) {
        return HeaderError(line, "bad element line (expected 'element NAME COUNT' with 0 <= COUNT < 2^31), found " +
                                     Quoted(lines[0]));
      }
      e.name = w[1];
      e.line = line;
      if (FindElement(e.name) >= 0) return HeaderError(line, "element " + Quoted(e.name, 40) + " given twice");
      elements_.push_back(e);
    } else if (w[0] == "property") {
      if (elements_.empty()) return HeaderError(line, "a property before any element");
      PlyProperty p;
      if (w.size() == 5 && w[1] == "list") {
        p.is_list = true;
        p.count_type = PlyScalar(w[2]);
        p.type = PlyScalar(w[3]);
        p.name = w[4];
        if (p.count_type.size == 0 || p.count_type.is_float || p.type.size == 0) {
          return HeaderError(line, "bad list property (expected 'property list COUNT_TYPE TYPE NAME' "
                                   "with an integer COUNT_TYPE), found " + Quoted(lines[0]));
        }
      } else if (w.size() == 3 && w[1] != "list") {
        p.type = PlyScalar(w[1]);
        p.name = w[2];
        if (p.type.size == 0) return HeaderError(line, "unknown property type " + Quoted(w[1], 40));
      } else {
        return HeaderError(line, "expected 'property TYPE NAME' or 'property list COUNT_TYPE TYPE "
                                 "NAME', found " + Quoted(lines[0]));
      }
      elements_.back().properties.push_back(p);
    } else {
      return HeaderError(line, "unknown header line " + Quoted(lines[0]));
    }
  }
  end_line_ = in_.line();
  if (format.empty()) return HeaderError(end_line_, "the header has no format line");
  ascii_ = format == "ascii";
  big_endian_ = format == "binary_big_endian";
  pos_ = in_.offset();
  // Counts the body cannot hold are refused before anything is sized from them: each
  // instance takes at least its fixed-size part (binary), or a character and a separator
  // per value (ASCII; the last value needs no separator).
  const long long left = static_cast<long long>(in_.remaining());
  const long long slack = ascii_ ? 1 : 0;
  long long at_least = 0;
  for (const PlyElement& e : elements_) {
    long long each = 0;
    for (const PlyProperty& p : e.properties) {
      each += ascii_ ? 2 : (p.is_list ? p.count_type.size : p.type.size);
    }
    if (e.count > 0 && each == 0) {
      return HeaderError(e.line, "element " + Quoted(e.name, 40) + " has no properties");
    }
    if (e.count > 0 && e.count > (left + slack) / each) {
      std::ostringstream os;
      os << "the header announces " << e.count << " " << (e.name.size() <= 40 ? e.name : Quoted(e.name, 40))
         << " records, more than the " << left << " bytes after the header can hold";
      return HeaderError(e.line, os.str());
    }
    at_least += e.count * each;  // each count fits the file: no overflow
    if (at_least > left + slack) {
      std::ostringstream os;
      os << "the header's elements need at least " << at_least - slack << " bytes, the file has "
         << left << " after the header";
      return HeaderError(e.line, os.str());
    }
  }
  return Status::Ok();
}

Status PlyFile::BodyError(const std::string& message) const {
  if (ascii_) return in_.Error(message);
  std::ostringstream os;
  os << "byte " << pos_ << ": " << message;
  return FileError(path(), 0, os.str());
}

Status PlyFile::ReadValue(const BinaryScalar& type, const std::string& what, double* value) {
  if (ascii_) {
    Token t;
    if (!in_.Next(&t)) return BodyError("the file ends before " + what + " (truncated file?)");
    if (type.is_float) {
      if (!ParseDouble(t.text, value)) {
        return BodyError("expected a number for " + what + ", got " + Quoted(t.text));
      }
    } else {
      long long v;
      if (!ParseInt(t.text, &v)) {
        return BodyError("expected an integer for " + what + ", got " + Quoted(t.text));
      }
      *value = static_cast<double>(v);
    }
    return Status::Ok();
  }
  const std::string& data = in_.data();
  if (static_cast<size_t>(type.size) > data.size() - pos_) {
    return BodyError("the file ends before " + what + " (truncated file?)");
  }
  *value = DecodeBinaryScalar(data.data() + pos_, type, big_endian_);
  pos_ += static_cast<size_t>(type.size);
  return Status::Ok();
}

Status PlyFile::ReadBody(const Visitor& visit) {
  Status s;
  PlyRow row;
  for (size_t e = 0; e < elements_.size(); ++e) {
    const PlyElement& element = elements_[e];
    row.values.assign(element.properties.size(), 0.0);
    row.lists.assign(element.properties.size(), {});
    for (long long i = 0; i < element.count; ++i) {
      for (size_t p = 0; p < element.properties.size(); ++p) {
        const PlyProperty& prop = element.properties[p];
        const std::string what = element.name + " " + std::to_string(i) + "'s " + prop.name;
        if (!prop.is_list) {
          if (!(s = ReadValue(prop.type, what, &row.values[p])).ok()) return s;
          continue;
        }
        double n;
        if (!(s = ReadValue(prop.count_type, "the length of " + what, &n)).ok()) return s;
        // Each item takes a byte per byte of its type (binary), or a character and a
        // separator (ASCII).
        const long long fits = ascii_ ? MaxItemsIn(in_.remaining(), 1)
                                      : static_cast<long long>((in_.data().size() - pos_) / prop.type.size);
        if (n < 0 || n > static_cast<double>(fits)) {
          std::ostringstream os;
          os << what << " has " << static_cast<long long>(n)
             << " entries, more than the rest of the file holds";
          return BodyError(os.str());
        }
        row.values[p] = n;
        std::vector<double>& items = row.lists[p];
        items.resize(static_cast<size_t>(n));
        for (double& item : items) {
          if (!(s = ReadValue(prop.type, what, &item)).ok()) return s;
        }
      }
      if (!(s = visit(static_cast<int>(e), i, row)).ok()) return s;
    }
  }
  return Status::Ok();
}

Status ReadPlyCloud(const std::string& path, RawCloud* cloud) {
  PlyFile ply;
  Status s = ply.Open(path);
  if (!s.ok()) return s;
  const int vertex = ply.FindElement("vertex");
  if (vertex < 0) return ply.HeaderError(ply.end_line(), "no vertex element");
  int xyz[3], normal[3];
  const char* axes[3] = {"x", "y", "z"};
  for (int k = 0; k < 3; ++k) {
    xyz[k] = ply.FindProperty(vertex, axes[k], false);
    if (xyz[k] < 0) {
      return ply.HeaderError(ply.end_line(), std::string("the vertex element has no scalar property ") + axes[k]);
    }
  }
  const char* n1[3] = {"nx", "ny", "nz"};
  const char* n2[3] = {"normal_x", "normal_y", "normal_z"};
  bool normals = true;
  for (int k = 0; k < 3; ++k) {
    normal[k] = ply.FindProperty(vertex, n1[k], false);
    if (normal[k] < 0) normal[k] = ply.FindProperty(vertex, n2[k], false);
    normals = normals && normal[k] >= 0;
  }
  const size_t n = static_cast<size_t>(ply.elements()[static_cast<size_t>(vertex)].count);
  *cloud = RawCloud();
  cloud->xyz.reserve(3 * n);
  if (normals) cloud->normals.reserve(3 * n);
  return ply.ReadBody([&](int element, long long, const PlyRow& row) {
    if (element != vertex) return Status::Ok();
    for (int k = 0; k < 3; ++k) cloud->xyz.push_back(row.values[xyz[k]]);
    if (normals) {
      for (int k = 0; k < 3; ++k) cloud->normals.push_back(row.values[normal[k]]);
    }
    return Status::Ok();
  });
}

Status ReadPlySurface(const std::string& path, Vertices* V, Triangles* F) {
  PlyFile ply;
  Status s = ply.Open(path);
  if (!s.ok()) return s;
  const int vertex = ply.FindElement("vertex");
  const int face = ply.FindElement("face");
  if (vertex < 0) return ply.HeaderError(ply.end_line(), "no 'element vertex' in the header");
  if (face < 0) {
    return ply.HeaderError(ply.end_line(), "no 'element face' in the header: a point cloud, not a surface");
  }
  const PlyElement& ve = ply.elements()[static_cast<size_t>(vertex)];
  const PlyElement& fe = ply.elements()[static_cast<size_t>(face)];
  int xyz[3];
  for (int k = 0; k < 3; ++k) {
    xyz[k] = ply.FindProperty(vertex, std::string(1, static_cast<char>('x' + k)), false);
    if (xyz[k] < 0) return ply.HeaderError(ve.line, "the vertex element lacks an x, y or z property");
  }
  int indices = ply.FindProperty(face, "vertex_indices", true);
  if (indices < 0) indices = ply.FindProperty(face, "vertex_index", true);
  if (indices < 0) {
    return ply.HeaderError(fe.line, "the face element has no 'vertex_indices' (or 'vertex_index') list");
  }
  const PlyProperty& list = fe.properties[static_cast<size_t>(indices)];
  if (list.type.is_float) return ply.HeaderError(fe.line, "the face vertex indices are not integers");
  std::vector<double> vertices;
  std::vector<int> triangles;
  vertices.reserve(3 * static_cast<size_t>(ve.count));
  triangles.reserve(3 * static_cast<size_t>(fe.count));
  s = ply.ReadBody([&](int element, long long r, const PlyRow& row) {
    if (element == vertex) {
      for (int k = 0; k < 3; ++k) {
        const double value = row.values[xyz[k]];
        if (!std::isfinite(value)) {
          return ply.BodyError("vertex " + std::to_string(r) + "'s " +
                               ve.properties[static_cast<size_t>(xyz[k])].name + " is not finite");
        }
        vertices.push_back(value);
      }
      return Status::Ok();
    }
    if (element != face) return Status::Ok();
    const std::string what = "face " + std::to_string(r) + "'s " + list.name;
    const std::vector<double>& polygon = row.lists[static_cast<size_t>(indices)];
    if (polygon.size() < 3 || polygon.size() > 1000000) {
      return ply.BodyError(what + " has " + std::to_string(polygon.size()) + " entries" +
                           (polygon.size() < 3 ? " (a face needs at least 3 corners)" : ""));
    }
    for (double value : polygon) {
      if (value < 0 || value >= static_cast<double>(ve.count)) {
        return ply.BodyError(what + " refers to vertex " + std::to_string(static_cast<long long>(value)) +
                             ", outside 0.." + std::to_string(ve.count - 1));
      }
    }
    for (size_t k = 1; k + 1 < polygon.size(); ++k) {
      triangles.insert(triangles.end(), {static_cast<int>(polygon[0]), static_cast<int>(polygon[k]),
                                         static_cast<int>(polygon[k + 1])});
    }
    return Status::Ok();
  });
  if (!s.ok()) return s;
  V->resize(static_cast<Eigen::Index>(vertices.size() / 3), 3);
  for (Eigen::Index i = 0; i < V->rows(); ++i) {
    for (int k = 0; k < 3; ++k) (*V)(i, k) = vertices[3 * static_cast<size_t>(i) + k];
  }
  F->resize(static_cast<Eigen::Index>(triangles.size() / 3), 3);
  for (Eigen::Index i = 0; i < F->rows(); ++i) {
    for (int k = 0; k < 3; ++k) (*F)(i, k) = triangles[3 * static_cast<size_t>(i) + k];
  }
  if (F->rows() == 0) return Status::Error(path + ": no face");
  return Status::Ok();
}

}  // namespace internal
}  // namespace femreg
