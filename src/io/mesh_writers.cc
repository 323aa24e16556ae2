// Atomic text writers: PVD collections, PLY and OBJ surfaces.
#include <cerrno>
#include <cstdio>
#include <cstring>
#include <sstream>

#include "femreg/io.h"
#include "io/io_internal.h"

namespace femreg {
namespace {

std::string XmlEscape(const std::string& s) {
  std::string out;
  for (char c : s) {
    switch (c) {
      case '&': out += "&amp;"; break;
      case '<': out += "&lt;"; break;
      case '>': out += "&gt;"; break;
      case '"': out += "&quot;"; break;
      case '\'': out += "&apos;"; break;
      default: out += c;
    }
  }
  return out;
}

// The surface as its own vertex list: `local` maps mesh vertex -> surface vertex.
struct SurfaceView {
  std::vector<int> vertices;  // mesh indices of the surface vertices
  std::vector<int> local;
};

SurfaceView MakeSurfaceView(const TetMesh& mesh) {
  SurfaceView view;
  view.local.assign(mesh.num_vertices(), -1);
  for (int f = 0; f < mesh.num_surface_triangles(); ++f) {
    for (int k = 0; k < 3; ++k) {
      const int v = mesh.surface(f, k);
      if (view.local[v] < 0) {
        view.local[v] = static_cast<int>(view.vertices.size());
        view.vertices.push_back(v);
      }
    }
  }
  return view;
}

Status CheckPositions(const std::string& path, const TetMesh& mesh, const Vertices& positions) {
  if (positions.rows() != mesh.num_vertices()) {
    std::ostringstream os;
    os << path << ": positions have " << positions.rows() << " rows, the mesh "
       << mesh.num_vertices() << " vertices";
    return Status::Error(os.str());
  }
  return Status::Ok();
}

}  // namespace

Status WriteFileAtomically(const std::string& path, const std::string& contents) {
  const std::string temp = internal::TemporaryPathFor(path);
  std::FILE* file = std::fopen(temp.c_str(), "wb");
  if (file == nullptr) {
    return Status::Error(path + ": cannot create file: " + std::strerror(errno));
  }
  const size_t written = std::fwrite(contents.data(), 1, contents.size(), file);
  const bool write_ok = written == contents.size() && std::fflush(file) == 0;
  const int write_errno = errno;
  if (std::fclose(file) != 0 || !write_ok) {
    std::remove(temp.c_str());
    return Status::Error(path + ": write failed: " + std::strerror(write_errno));
  }
  if (std::rename(temp.c_str(), path.c_str()) != 0) {
    const int rename_errno = errno;
    std::remove(temp.c_str());
    return Status::Error(path + ": cannot rename the temporary file into place: " +
                         std::strerror(rename_errno));
  }
  return Status::Ok();
}

Status WritePvd(const std::string& path, const std::vector<PvdEntry>& entries) {
  std::ostringstream os;
  os.precision(17);
  os << "<?xml version=\"1.0\"?>\n"
     << "<VTKFile type=\"Collection\" version=\"0.1\" byte_order=\"LittleEndian\">\n"
     << "  <Collection>\n";
  for (const PvdEntry& e : entries) {
    os << "    <DataSet timestep=\"" << e.time << "\" group=\"\" part=\"0\" file=\""
       << XmlEscape(e.file) << "\"/>\n";
  }
  os << "  </Collection>\n</VTKFile>\n";
  return WriteFileAtomically(path, os.str());
}

Status WritePlySurface(const std::string& path, const TetMesh& mesh, const Vertices& positions) {
  Status s = CheckPositions(path, mesh, positions);
  if (!s.ok()) return s;
  const SurfaceView view = MakeSurfaceView(mesh);
  std::ostringstream os;
  os.precision(17);
  os << "ply\nformat ascii 1.0\ncomment femreg boundary surface\n"
     << "element vertex " << view.vertices.size() << "\n"
     << "property double x\nproperty double y\nproperty double z\n"
     << "element face " << mesh.num_surface_triangles() << "\n"
     << "property list uchar int vertex_indices\nend_header\n";
  for (int v : view.vertices) {
    os << positions(v, 0) << " " << positions(v, 1) << " " << positions(v, 2) << "\n";
  }
  for (int f = 0; f < mesh.num_surface_triangles(); ++f) {
    os << "3 " << view.local[mesh.surface(f, 0)] << " " << view.local[mesh.surface(f, 1)] << " "
       << view.local[mesh.surface(f, 2)] << "\n";
  }
  return WriteFileAtomically(path, os.str());
}

Status WriteObjSurface(const std::string& path, const TetMesh& mesh, const Vertices& positions) {
  Status s = CheckPositions(path, mesh, positions);
  if (!s.ok()) return s;
  const SurfaceView view = MakeSurfaceView(mesh);
  std::ostringstream os;
  os.precision(17);
  os << "# femreg boundary surface: " << view.vertices.size() << " vertices, "
     << mesh.num_surface_triangles() << " triangles\n";
  for (int v : view.vertices) {
    os << "v " << positions(v, 0) << " " << positions(v, 1) << " " << positions(v, 2) << "\n";
  }
  for (int f = 0; f < mesh.num_surface_triangles(); ++f) {
    os << "f " << view.local[mesh.surface(f, 0)] + 1 << " " << view.local[mesh.surface(f, 1)] + 1
       << " " << view.local[mesh.surface(f, 2)] + 1 << "\n";
  }
  return WriteFileAtomically(path, os.str());
}

}  // namespace femreg
