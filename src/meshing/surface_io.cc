// Surfaces in (PLY through io's one PLY reader, io/ply_reader.h; OBJ and STL through
// ReadTriangleSurface) and tetrahedral meshes out (.vtu through WriteVtu; Gmsh 2.2, MEDIT
// and VTK legacy written here).
#include <algorithm>
#include <cctype>
#include <cstdarg>
#include <cstdio>
#include <string>
#include <vector>

#include "femreg/io.h"
#include "femreg/meshing.h"
#include "io/ply_reader.h"

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
  return internal::ReadPlySurface(path, V, F);
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
