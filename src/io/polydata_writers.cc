// Binary writers of VTK PolyData (.vtp) and PLY: clouds and triangle surfaces, for ParaView.
#include <cstdint>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

#include "femreg/io.h"

namespace femreg {

namespace {
// One array of VTK's raw appended data: a UInt64 byte count, then the values.
template <typename T>
void AppendArray(const std::vector<T>& values, std::string* block) {
  const uint64_t bytes = values.size() * sizeof(T);
  block->append(reinterpret_cast<const char*>(&bytes), sizeof(bytes));
  block->append(reinterpret_cast<const char*>(values.data()), bytes);
}
// Both documents' start, up to their Piece of n points with `verts` vertex and `polys`
// polygon cells.
void StartPolyData(Eigen::Index n, Eigen::Index verts, Eigen::Index polys, std::ostringstream* os) {
  *os << "<?xml version=\"1.0\"?>\n"
      << "<VTKFile type=\"PolyData\" version=\"1.0\" byte_order=\"LittleEndian\" "
         "header_type=\"UInt64\">\n"
      << "  <PolyData>\n"
      << "    <Piece NumberOfPoints=\"" << n << "\" NumberOfVerts=\"" << verts
      << "\" NumberOfLines=\"0\" NumberOfStrips=\"0\" NumberOfPolys=\"" << polys << "\">\n";
}

// The cells (`cells`: Verts or Polys) and the appended data end both documents; written
// atomically.
Status FinishPolyData(const std::string& path, const char* cells, uint64_t offset_connectivity,
                      uint64_t offset_offsets, const std::string& block, std::ostringstream* os) {
  *os << "      <" << cells << ">\n"
      << "        <DataArray type=\"Int32\" Name=\"connectivity\" format=\"appended\" offset=\""
      << offset_connectivity << "\"/>\n"
      << "        <DataArray type=\"Int32\" Name=\"offsets\" format=\"appended\" offset=\""
      << offset_offsets << "\"/>\n"
      << "      </" << cells << ">\n"
      << "    </Piece>\n  </PolyData>\n"
      << "  <AppendedData encoding=\"raw\">\n   _";
  std::string text = os->str();
  text += block;
  text += "\n  </AppendedData>\n</VTKFile>\n";
  return WriteFileAtomically(path, text);
}
}  // namespace

Status WriteCloudVtp(const std::string& path, const Vertices& points_in, const Vertices* normals_in) {
  const Eigen::Index n = points_in.rows();
  if (normals_in != nullptr && normals_in->rows() != n) {
    return Status::Error(path + ": " + std::to_string(normals_in->rows()) + " normals for " + std::to_string(n) + " points");
  }
  if (n > (Eigen::Index(1) << 31) - 2) return Status::Error(path + ": too many points for a VTP");
  const bool normals = normals_in != nullptr;
  // Float32 like the clouds femreg reads (PCD F 4); little-endian like the machines it runs on.
  std::vector<float> points(static_cast<size_t>(3 * n)), normal_values;
  for (Eigen::Index i = 0; i < n; ++i) {
    for (int k = 0; k < 3; ++k) points[static_cast<size_t>(3 * i + k)] = static_cast<float>(points_in(i, k));
  }
  if (normals) {
    normal_values.resize(static_cast<size_t>(3 * n));
    for (Eigen::Index i = 0; i < n; ++i) {
      for (int k = 0; k < 3; ++k) {
        normal_values[static_cast<size_t>(3 * i + k)] = static_cast<float>((*normals_in)(i, k));
      }
    }
  }
  std::vector<int32_t> connectivity(static_cast<size_t>(n)), offsets(static_cast<size_t>(n));
  for (Eigen::Index i = 0; i < n; ++i) {
    connectivity[static_cast<size_t>(i)] = static_cast<int32_t>(i);
    offsets[static_cast<size_t>(i)] = static_cast<int32_t>(i + 1);
  }
  std::string block;
  uint64_t offset_points = 0, offset_normals = 0, offset_connectivity = 0, offset_offsets = 0;
  offset_points = block.size();
  AppendArray(points, &block);
  if (normals) {
    offset_normals = block.size();
    AppendArray(normal_values, &block);
  }
  offset_connectivity = block.size();
  AppendArray(connectivity, &block);
  offset_offsets = block.size();
  AppendArray(offsets, &block);

  std::ostringstream os;
  StartPolyData(n, n, 0, &os);
  if (normals) {
    os << "      <PointData Normals=\"normals\">\n"
       << "        <DataArray type=\"Float32\" Name=\"normals\" NumberOfComponents=\"3\" "
          "format=\"appended\" offset=\"" << offset_normals << "\"/>\n"
       << "      </PointData>\n";
  }
  os << "      <Points>\n"
     << "        <DataArray type=\"Float32\" Name=\"Points\" NumberOfComponents=\"3\" "
        "format=\"appended\" offset=\"" << offset_points << "\"/>\n"
     << "      </Points>\n";
  return FinishPolyData(path, "Verts", offset_connectivity, offset_offsets, block, &os);
}

Status WriteTrianglesVtp(const std::string& path, const Vertices& vertices, const Triangles& triangles,
                         const std::vector<std::pair<std::string, Eigen::VectorXd>>& fields) {
  const Eigen::Index n = vertices.rows(), nf = triangles.rows();
  if (n > (Eigen::Index(1) << 31) - 2 || 3 * nf > (Eigen::Index(1) << 31) - 2) {
    return Status::Error(path + ": too many vertices or triangles for a VTP");
  }
  std::vector<double> points(static_cast<size_t>(3 * n));
  for (Eigen::Index i = 0; i < n; ++i) {
    for (int k = 0; k < 3; ++k) points[static_cast<size_t>(3 * i + k)] = vertices(i, k);
  }
  std::vector<int32_t> connectivity(static_cast<size_t>(3 * nf)), offsets(static_cast<size_t>(nf));
  for (Eigen::Index f = 0; f < nf; ++f) {
    for (int k = 0; k < 3; ++k) connectivity[static_cast<size_t>(3 * f + k)] = static_cast<int32_t>(triangles(f, k));
    offsets[static_cast<size_t>(f)] = static_cast<int32_t>(3 * (f + 1));
  }
  std::string block;
  std::vector<uint64_t> field_offsets;
  const uint64_t offset_points = block.size();
  AppendArray(points, &block);
  for (const auto& field : fields) {
    if (field.second.size() != n) return Status::Error(path + ": field " + field.first + " has the wrong size");
    field_offsets.push_back(block.size());
    AppendArray(std::vector<double>(field.second.data(), field.second.data() + n), &block);
  }
  const uint64_t offset_connectivity = block.size();
  AppendArray(connectivity, &block);
  const uint64_t offset_offsets = block.size();
  AppendArray(offsets, &block);
  std::ostringstream os;
  StartPolyData(n, 0, nf, &os);
  if (!fields.empty()) {
    os << "      <PointData>\n";
    for (size_t j = 0; j < fields.size(); ++j) {
      os << "        <DataArray type=\"Float64\" Name=\"" << fields[j].first
         << "\" NumberOfComponents=\"1\" format=\"appended\" offset=\"" << field_offsets[j] << "\"/>\n";
    }
    os << "      </PointData>\n";
  }
  os << "      <Points>\n"
     << "        <DataArray type=\"Float64\" Name=\"Points\" NumberOfComponents=\"3\" "
        "format=\"appended\" offset=\"" << offset_points << "\"/>\n"
     << "      </Points>\n";
  return FinishPolyData(path, "Polys", offset_connectivity, offset_offsets, block, &os);
}

Status WriteTrianglesPly(const std::string& path, const Vertices& vertices, const Triangles& triangles) {
  std::ostringstream os;
  os << "ply\nformat binary_little_endian 1.0\ncomment femreg embedded surface\n"
     << "element vertex " << vertices.rows() << "\n"
     << "property double x\nproperty double y\nproperty double z\n"
     << "element face " << triangles.rows() << "\n"
     << "property list uchar int vertex_indices\nend_header\n";
  std::string text = os.str();
  for (Eigen::Index i = 0; i < vertices.rows(); ++i) {
    for (int k = 0; k < 3; ++k) {
      const double v = vertices(i, k);
      text.append(reinterpret_cast<const char*>(&v), sizeof(v));
    }
  }
  for (Eigen::Index f = 0; f < triangles.rows(); ++f) {
    text.push_back(static_cast<char>(3));
    for (int k = 0; k < 3; ++k) {
      const int32_t c = static_cast<int32_t>(triangles(f, k));
      text.append(reinterpret_cast<const char*>(&c), sizeof(c));
    }
  }
  return WriteFileAtomically(path, text);
}

}  // namespace femreg
