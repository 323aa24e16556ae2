// Helpers shared by the mesh readers and writers (not part of the public API).
#ifndef FEMREG_IO_IO_INTERNAL_H_
#define FEMREG_IO_IO_INTERNAL_H_

#include <algorithm>
#include <array>
#include <cctype>
#include <filesystem>
#include <ios>
#include <string>
#include <vector>

#include "femreg/mesh.h"
#include "femreg/status.h"

namespace femreg {

namespace internal {

// A path's extension in lower case (".PCD" -> ".pcd"), the dot included; "" without one.
inline std::string LowercaseExtension(const std::string& path) {
  std::string ext = std::filesystem::path(path).extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  return ext;
}

// A scalar type of a binary file (VTK legacy BINARY, PCD binary, PLY binary): its size in
// bytes (1, 2, 4 or 8; 0: a type that cannot be read), float or integer, signed or not.
struct BinaryScalar {
  int size = 0;
  bool is_float = false;
  bool is_signed = false;
};

// The value of one scalar of `type` stored at p, in either byte order.
double DecodeBinaryScalar(const char* p, const BinaryScalar& type, bool big_endian);

// A mesh as a reader found it, before unused vertices are dropped and it is finalized.
struct RawTetMesh {
  std::vector<std::array<double, 3>> vertices;  // #V positions
  std::vector<std::array<int, 4>> tets;         // #T 0-based indices into vertices
  std::vector<int> regions;                     // #T region ids, or empty (all 0)
  std::vector<int> tet_lines;                   // #T source line of each tet, or empty
  std::string lines_file;  // the file tet_lines refer to, when not the one read (TetGen .ele)
};

// Builds `mesh` from `raw`: checks indices and coordinates, drops vertices that no tet
// uses (renumbering the tets), rejects degenerate elements (naming the line when known)
// and calls FinalizeMesh. Messages start with `path`.
Status FinishRawMesh(const std::string& path, RawTetMesh raw, TetMesh* mesh);

// "path:line: message" (or "path: message" when line <= 0).
Status FileError(const std::string& path, int line, const std::string& message);

// An intrinsics file is a few hundred bytes; anything much larger is another file.
constexpr std::streamoff kMaxIntrinsicsBytes = 1 << 20;

// v with every digit a double holds (17 significant), for messages that quote a file's number.
std::string ExactNumber(double v);

// The whole of a small file (at most max_bytes; `what` names the kind in the error, e.g.
// "an intrinsics file") in *text. Errors name the file.
Status ReadSmallFile(const std::string& path, std::streamoff max_bytes, const std::string& what,
                     std::string* text);

// A VTK XML unstructured grid (.vtu) as femreg's own reader found it (vtu_reader.cc), one
// VtuPiece per <Piece> of the file: indices in a piece's connectivity refer to its own points.
struct VtuArray {
  std::string name;
  int components = 1;
  std::vector<double> values;  // tuple-major: #tuples x components
};
struct VtuPiece {
  std::vector<std::array<double, 3>> points;
  std::vector<long long> offsets = {0};  // #cells + 1: cell c is connectivity[offsets[c], offsets[c + 1])
  std::vector<long long> connectivity;   // point indices as in the file (not checked against #points)
  std::vector<int> types;                // VTK cell type of each cell (-1: outside 0..255)
  std::vector<VtuArray> point_data, cell_data;  // in file order
};
struct VtuGrid {
  std::vector<VtuPiece> pieces;
};
// Reads every piece, point and cell of a .vtu, each header count, size, offset and
// compressed block checked against the bytes the file has before anything is sized from
// it. Errors name the file and the byte offset of the problem.
Status ReadVtuGrid(const std::string& path, VtuGrid* grid);
// The pieces one after the other as one piece: points, cells and the arrays that every piece
// has (same name and components; the first of that name in each). A point index is shifted
// by the points of the pieces before; one outside its own piece becomes -1 (out of range
// for any reader). One piece comes back as it is.
VtuPiece MergePieces(VtuGrid grid);
// A .vtu as a tetrahedral mesh (vtu_io.cc): tetrahedra (VTK type 10) kept, other cells
// skipped, the pieces merged (MergePieces); the first one-component cell array named like a
// region gives the region ids.
Status ReadVtuFile(const std::string& path, RawTetMesh* raw);

// Text readers (mesh_readers.cc).
Status ReadGmshFile(const std::string& path, RawTetMesh* raw);
Status ReadTetGenFiles(const std::string& path, RawTetMesh* raw);
Status ReadMeditFile(const std::string& path, RawTetMesh* raw);
Status ReadVtkLegacyFile(const std::string& path, RawTetMesh* raw);

// A point cloud as a file has it, before registration makes it a PointCloud
// (registration/cloud_files.h).
struct RawCloud {
  std::vector<double> xyz;      // 3 per point
  std::vector<double> normals;  // 3 per point, or empty
  std::vector<int> labels;      // 1 per point, or empty
  bool viewpoint_known = false;  // a PCD VIEWPOINT line
  std::array<double, 3> origin = {0, 0, 0};
  std::array<double, 4> orientation = {1, 0, 0, 0};  // w x y z, normalized
};
// PCD (pcd_reader.cc): ASCII, binary and binary_compressed, every header count checked
// against the file's length first. PLY clouds: ReadPlyCloud (ply_reader.h).
Status ReadPcdCloud(const std::string& path, RawCloud* cloud);
// Text clouds (xyz_reader.cc): 'x y z' or 'x y z nx ny nz' a line, split by spaces, tabs,
// commas or semicolons; '#' comments. Every line has the first data line's column count.
Status ReadXyzCloud(const std::string& path, RawCloud* cloud);

// What a cloud file holds, by its first bytes (xyz_reader.cc): "ply", a PCD header keyword,
// or else text. Only a file that cannot be opened is an error.
enum class CloudFileFormat { kPly, kPcd, kText };
Status DetectCloudFormat(const std::string& path, CloudFileFormat* format);

// A fresh temporary file name in the folder of `path` (for write-and-rename).
std::string TemporaryPathFor(const std::string& path);

// A region id from a value read from a file, rounded to the nearest integer: false when it
// is not finite or outside the range of int.
bool RegionIdFrom(double value, int* id);

// True when a cell/field name looks like a region id ("region", "tag", "material", ...).
bool LooksLikeRegionName(const std::string& name);

// Before VTK writes anything: its SMP tools on one thread. VTK 9.1 is built with the TBB
// back end, which otherwise starts a pool of worker threads (one per core) the first time a
// writer computes an array's range; femreg owns its threads (solver.num_threads), and
// writing a frame is not where parallel work pays.
void UseSequentialVtk();

}  // namespace internal
}  // namespace femreg

#endif  // FEMREG_IO_IO_INTERNAL_H_
