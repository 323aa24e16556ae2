// femreg/eval.h - evaluation against ground truth: VTU geometry in file order, triangle
// surfaces, the distance between two surfaces, and the errors of a mesh that broke into
// pieces (the per-piece ground truth of the fracture sequences). The per-frame ground truth
// and the vertex errors are in femreg/ground_truth.h.
#ifndef FEMREG_EVAL_H_
#define FEMREG_EVAL_H_

#include <Eigen/Core>
#include <string>
#include <vector>

#include "femreg/ground_truth.h"
#include "femreg/mesh.h"
#include "femreg/status.h"

namespace femreg {

// The points of a VTU file in file order (no reordering, no dropped vertices) and its
// triangle surface: the triangle cells, plus the boundary faces of the tetrahedra (faces
// that one tetrahedron alone uses). Other cells are ignored.
struct VtuGeometry {
  Vertices points;     // #P by 3, in file order
  Tets tets;           // #T by 4 tetrahedra of the file
  Triangles surface;   // #F by 3
  // The point field "original_vertex" (`femreg register` with fracture: the vertex of the
  // first mesh each vertex comes from); empty when the file has none.
  std::vector<int> original;
  // The rest positions, points minus the point field "displacement" (`femreg register`'s);
  // empty when the file has none.
  Vertices rest;
};
Status ReadVtuGeometry(const std::string& path, VtuGeometry* geometry);

// Writes a triangle surface (points as 32-bit floats, zlib-compressed) as a VTU of
// triangle cells, atomically. `points` #P by 3, `triangles` #F by 3.
Status WriteVtuSurface(const std::string& path, const Vertices& points, const Triangles& triangles);

// Boundary faces of tetrahedra (faces used by one element only), outward for positively
// oriented elements.
Triangles BoundaryFaces(const Tets& tets);

// Distance between surfaces A and B (m), from samples on each (the vertices and the
// triangle centroids), each sample to the closest point of the other surface.
struct SurfaceDistance {
  double a_to_b_mean = 0.0, b_to_a_mean = 0.0;
  double mean = 0.0;       // symmetric: (a_to_b_mean + b_to_a_mean) / 2
  double hausdorff = 0.0;  // the largest sample distance either way
  int samples_a = 0, samples_b = 0;
};
SurfaceDistance ComputeSurfaceDistance(const Vertices& points_a, const Triangles& triangles_a,
                                       const Vertices& points_b, const Triangles& triangles_b);

// Ground truth for a mesh that may have split. The CSV of a frame keeps one row per
// original tracked vertex; a side file frame_NNNN_pieces.csv ("vertex,piece,x,y,z") lists,
// once the ground truth's own mesh has broken, the position of each original vertex on
// every ground-truth piece it touches. Matching: every tracked vertex maps to its original
// vertex; each tracked piece is matched to the ground-truth piece that most of its
// unambiguous vertices lie on, and a vertex takes its original's position on that piece
// (the CSV row when the side file has none). A vertex the tracker split whose original has
// rows, but none on its piece's match (a tracked crack on the tracked mesh's own nodes, a cell
// from the truth's), takes the rigid motion of its piece's 12 nearest vertices that have one
// (ties included; the best fit of their rest to their true positions), not another piece's
// position.
struct PieceTruthRow {
  int vertex = 0;  // original vertex id
  int piece = 0;   // ground-truth piece
  Eigen::Vector3d position = Eigen::Vector3d::Zero();
};
Status ReadPieceTruth(const std::string& path, std::vector<PieceTruthRow>* rows);
Status WritePieceTruth(const std::string& path, const std::vector<PieceTruthRow>& rows);

struct PieceErrors {
  VertexErrors all;                 // over every tracked vertex
  std::vector<ErrorStats> pieces;   // per tracked piece (ConnectedPieces order)
  std::vector<ErrorStats> pieces_seen, pieces_hidden;  // the same, seen / hidden vertices
  std::vector<int> piece_vertices;  // tracked vertices per piece
  GroundTruthFrame matched;         // per tracked vertex: the truth it was compared with
};
// positions: #V tracked; original: #V original ids (rows of truth).
PieceErrors ComputePieceErrors(const TetMesh& mesh, const Vertices& positions,
                               const std::vector<int>& original, const GroundTruthFrame& truth,
                               const std::vector<PieceTruthRow>& piece_truth);

// Several objects against one ground truth frame that holds every object's initial
// vertices in scene order (and side-file rows in that numbering): object i takes the
// `initial` rows after those of the objects before it. Pieces are numbered object by
// object; `all` and `matched` cover every tracked vertex in object order.
struct TrackedObject {
  const TetMesh* mesh = nullptr;              // its elements (for the pieces)
  const Vertices* positions = nullptr;        // #V tracked positions
  const std::vector<int>* original = nullptr; // #V original ids
  int initial = 0;                            // its vertices before any split
};
Status ComputePieceErrors(const std::vector<TrackedObject>& objects, const GroundTruthFrame& truth,
                          const std::vector<PieceTruthRow>& piece_truth, PieceErrors* out);

}  // namespace femreg

#endif  // FEMREG_EVAL_H_
