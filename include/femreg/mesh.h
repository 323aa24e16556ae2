// femreg/mesh.h - tetrahedral meshes: positions, elements, surface, adjacency, masses.
#ifndef FEMREG_MESH_H_
#define FEMREG_MESH_H_

#include <Eigen/Core>
#include <string>
#include <vector>

#include "femreg/status.h"

namespace femreg {

// Row-major so that a #V by 3 block is one contiguous array of xyz triples: vertex i is
// data() + 3 * i, which is what a solver parameter block wants.
using Vertices = Eigen::Matrix<double, Eigen::Dynamic, 3, Eigen::RowMajor>;
using Tets = Eigen::Matrix<int, Eigen::Dynamic, 4, Eigen::RowMajor>;
using Triangles = Eigen::Matrix<int, Eigen::Dynamic, 3, Eigen::RowMajor>;

struct TetMesh {
  Vertices rest;             // #V by 3 rest positions X
  Vertices x;                // #V by 3 current positions
  Tets tets;                 // #T by 4 vertex indices, positively oriented
  Eigen::VectorXi region;    // #T region id per element (physical tag; 0 when absent)
  Triangles surface;         // #F by 3 boundary triangles, counter-clockwise seen from outside
  std::vector<int> surface_vertices;  // sorted indices of the vertices on the surface
  Eigen::VectorXd mass;      // #V lumped masses (kg), filled by ComputeLumpedMasses

  // Vertex -> element adjacency in compressed form: the elements around vertex v are
  // vertex_tets[vertex_tet_offsets[v] .. vertex_tet_offsets[v + 1]).
  std::vector<int> vertex_tet_offsets;
  std::vector<int> vertex_tets;

  int num_vertices() const { return static_cast<int>(rest.rows()); }
  int num_tets() const { return static_cast<int>(tets.rows()); }
  int num_surface_triangles() const { return static_cast<int>(surface.rows()); }
};

// Signed volume of the tetrahedron (a, b, c, d): positive when d lies on the side of the
// triangle (a, b, c) that its right-hand normal points to... i.e. det[b-a, c-a, d-a] / 6.
double SignedTetVolume(const Eigen::Vector3d& a, const Eigen::Vector3d& b, const Eigen::Vector3d& c,
                       const Eigen::Vector3d& d);

// Completes a mesh whose rest, tets and (optionally) region are set: checks indices and
// coordinates, flips negatively oriented elements, rejects degenerate ones, sets x = rest,
// builds the outward surface and the adjacency. `source` names the mesh in messages.
// Elements with |volume| <= degenerate_tolerance * (mean edge length)^3 are degenerate.
Status FinalizeMesh(TetMesh* mesh, const std::string& source = "mesh",
                    double degenerate_tolerance = 1e-12);

// Rebuilds surface triangles, surface_vertices and the vertex adjacency from tets (used
// by FinalizeMesh and after topology changes). Does not touch positions.
void BuildTopology(TetMesh* mesh);

// Connected component of each vertex (elements sharing a vertex are connected); components
// numbered by their smallest vertex. Returns the number of components. (A mesh breaks into
// pieces under fracture; the pieces are compared with the ground truth's.)
int ConnectedPieces(const TetMesh& mesh, std::vector<int>* vertex_piece);

// Lumped masses: each element gives a quarter of density * volume to each of its vertices.
// density_per_region maps region id -> density; regions not listed use default_density.
void ComputeLumpedMasses(TetMesh* mesh, double default_density,
                         const std::vector<std::pair<int, double>>& density_per_region = {});

// Total rest volume.
double RestVolume(const TetMesh& mesh);

// Element quality for reports.
struct MeshQuality {
  double min_dihedral_deg = 0.0;  // smallest dihedral angle over all elements
  double max_dihedral_deg = 0.0;  // largest dihedral angle over all elements
  double max_aspect_ratio = 0.0;  // longest edge / (2 * sqrt(6) * inradius); 1 for regular
  double mean_aspect_ratio = 0.0;
  int num_inverted = 0;           // elements with negative volume in `positions`
  int num_degenerate = 0;         // elements with |volume| below tolerance
  std::vector<int> inverted;      // their indices (capped at 100)
  std::vector<int> degenerate;
};
MeshQuality ComputeQuality(const TetMesh& mesh, const Vertices& positions);

}  // namespace femreg

#endif  // FEMREG_MESH_H_
