// femreg/io.h - reading and writing meshes: tetrahedral meshes and triangle surfaces (OBJ,
// STL) in, VTU/PVD/PLY/OBJ/VTP out; atomic writes and file lists. Depth images, masks,
// intrinsics and recordings: femreg/camera_io.h.
#ifndef FEMREG_IO_H_
#define FEMREG_IO_H_

#include <Eigen/Core>
#include <string>
#include <utility>
#include <vector>

#include "femreg/mesh.h"
#include "femreg/status.h"

namespace femreg {

enum class MeshFormat {
  kUnknown,
  kGmsh,       // MSH 1, 2.2 or 4.1 ASCII
  kTetGen,     // .node + .ele
  kMedit,      // .mesh
  kVtkLegacy,  // "# vtk DataFile" unstructured grid, ASCII or BINARY
  kVtu,        // VTK XML UnstructuredGrid
};
const char* ToString(MeshFormat format);

// Looks at the file's first bytes, not its extension (a .vtk may hold XML).
MeshFormat DetectMeshFormat(const std::string& path);

// Reads a tetrahedral mesh of any supported format (cells other than tetrahedra are
// skipped; physical tags become region ids) and finalizes it (FinalizeMesh). Every count,
// size and offset in a file is checked against the file's length before anything is
// allocated or read; errors name the file and the line (text) or byte offset (binary), and
// quote a bad token by at most 80 characters. `mesh` is left as it was on error.
Status ReadTetMesh(const std::string& path, TetMesh* mesh);

// Reads a triangle surface (a rigid obstacle, a surface to mesh) by its extension: OBJ (v / f
// lines, polygons fanned, negative indices, v/vt/vn forms) or STL (ASCII or binary, corners
// merged by exact position). No triangle is an error.
Status ReadTriangleSurface(const std::string& path, Vertices* vertices, Triangles* triangles);

// A field written with a mesh: `values` has one row per vertex (point field) or per
// element (cell field), and 1 (scalar) or 3 (vector) columns.
struct MeshField {
  std::string name;
  Eigen::MatrixXd values;
  bool per_cell = false;
};

// Writes the tetrahedra at `positions` with the given fields (and always the region id)
// as a VTU file. Written to a temporary file and renamed, so a reader never sees half a
// file.
Status WriteVtu(const std::string& path, const TetMesh& mesh, const Vertices& positions,
                const std::vector<MeshField>& fields = {});

// A ParaView collection: one (time, relative file) entry per frame. Atomic like WriteVtu.
struct PvdEntry {
  double time = 0.0;
  std::string file;
};
Status WritePvd(const std::string& path, const std::vector<PvdEntry>& entries);

// The boundary surface at `positions`, as PLY (ASCII) or OBJ. Atomic.
Status WritePlySurface(const std::string& path, const TetMesh& mesh, const Vertices& positions);
Status WriteObjSurface(const std::string& path, const TetMesh& mesh, const Vertices& positions);

// Points (and their normals, the same rows, when given) as VTK PolyData (.vtp: float32 in raw
// appended binary, a vertex cell per point) that ParaView opens. Atomic.
Status WriteCloudVtp(const std::string& path, const Vertices& points, const Vertices* normals = nullptr);
// A triangle surface (an embedded surface's frame) as VTK PolyData (Float64 points, a polygon
// per triangle), with per-vertex scalar fields (name, #V values) beside it. Atomic.
Status WriteTrianglesVtp(const std::string& path, const Vertices& vertices, const Triangles& triangles,
                         const std::vector<std::pair<std::string, Eigen::VectorXd>>& fields = {});
// The same as binary little-endian PLY (double x, y, z; int corners). Atomic.
Status WriteTrianglesPly(const std::string& path, const Vertices& vertices, const Triangles& triangles);

// Writes `contents` to `path` through a temporary file in the same folder and a rename.
Status WriteFileAtomically(const std::string& path, const std::string& contents);

// The files of folder `dir_or_glob` with one of `extensions` (lower case, with the dot;
// matched in any case), or, when it is not a folder, the matches of it as a glob pattern;
// sorted by name in natural order ("frame_10" after "frame_9"). None is an error naming
// the folder or the pattern.
Status ListFiles(const std::string& dir_or_glob, const std::vector<std::string>& extensions,
                 std::vector<std::string>* files);

// Generators (for tests and data), finalized, with rest = x and zero masses.
// A box [origin, origin + size] of nx * ny * nz cubes, each split into 6 tetrahedra
// that conform across cubes.
TetMesh MakeBox(const Eigen::Vector3d& size, int nx, int ny, int nz,
                const Eigen::Vector3d& origin = Eigen::Vector3d::Zero());
// A cylinder along +z from z = 0 to `length`, of `radius`, with about n_radial cells
// across the radius and n_axial along the axis.
TetMesh MakeCylinder(double radius, double length, int n_radial, int n_axial);
// A ball of `radius` centred at the origin with about `n` cells across its radius.
TetMesh MakeSphere(double radius, int n);

}  // namespace femreg

#endif  // FEMREG_IO_H_
