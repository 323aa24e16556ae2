// femreg/meshing.h - from a closed triangle surface (a scan, a CAD export) to a tetrahedral
// mesh: surface files in, checks that the surface bounds a volume, TetGen's quality
// tetrahedralization, tetrahedral meshes out.
//
//   Vertices V;   // #V by 3
//   Triangles F;  // #F by 3
//   Status s = ReadSurface("scan.stl", &V, &F);
//   MeshingOptions options;           // edge length from the surface, TetGen's quality
//   options.edge_length = 0.005;      // 5 mm: the surface is remeshed to 5 mm first
//   TetMesh mesh;
//   MeshingReport report;
//   if (s.ok()) s = TetrahedralizeSurface(V, F, options, &mesh, &report, "scan.stl");
//   if (s.ok()) s = WriteTetMesh("scan.vtu", mesh);
#ifndef FEMREG_MESHING_H_
#define FEMREG_MESHING_H_

#include <string>

#include "femreg/mesh.h"
#include "femreg/status.h"

namespace femreg {

// How to tetrahedralize. Lengths in metres (or whatever unit the surface is in: nothing
// here assumes metres except the names).
struct MeshingOptions {
  // Target edge length of the tetrahedra. 0: the surface's mean edge length (the surface is
  // then meshed as it is). It sets the volume bound (below), and, with `remesh`, the length the
  // surface is remeshed to first, so that the mean edge comes out near L on and inside the
  // solid. Without remeshing TetGen does not coarsen the surface: near a surface finer than L,
  // the elements are as fine as it.
  double edge_length = 0.0;
  // With edge_length > 0 and not keep_surface: remesh the surface to edge_length first
  // (CGAL's isotropic remeshing: split, collapse, flip, smooth, project back onto the input),
  // then let TetGen keep that surface (-Y). Off: TetGen gets the input surface.
  bool remesh = true;
  // Edges where the normals of the two triangles differ by more than this (degrees) are
  // feature lines the remeshed surface keeps (a box's edges; a dome's rim); where three or
  // more meet, the vertex stays. A connected set of such edges shorter than 2 edge_length in
  // all is not kept (a scan's noise). 180: none. In (0, 180].
  double feature_angle_deg = 60.0;
  // Rounds of the remeshing (each splits, collapses, flips and smooths once). 1 to 100.
  int remesh_iterations = 5;
  // Largest tetrahedron volume. 0: from edge_length, L^3 / (4 sqrt 2), 1.5 times the regular
  // tetrahedron's (refinement makes elements smaller than the bound). When both are set, the
  // smaller bound applies.
  double max_volume = 0.0;
  // Quality bound: the largest circumradius-to-shortest-edge ratio of a tetrahedron
  // (TetGen's -q; the regular tetrahedron has 0.61). TetGen's default is 2.0; smaller is
  // rounder and more elements. At least 1.1 (below that TetGen may not terminate).
  double radius_edge_ratio = 1.5;
  // Smallest dihedral angle TetGen aims for (degrees; TetGen's -q ratio/angle). 0: no
  // bound beyond the ratio's. At most 18 (above that TetGen may not terminate).
  double min_dihedral_deg = 0.0;
  // Keep the surface triangles as they are (TetGen's -Y: no point added on the surface; no
  // remeshing): the mesh's boundary is the input's, triangle for triangle. Off: TetGen may
  // split surface triangles (in their plane) for quality and size. Either way the mesh fills
  // exactly the solid the triangles it gets bound (nearly coplanar triangles are never merged,
  // TetGen's -M).
  bool keep_surface = false;
  // Vertices closer than this are merged before anything else (STL stores every corner
  // of every triangle). Negative: 1e-9 times the bounding box diagonal. 0: only exact
  // copies.
  double merge_distance = -1.0;
  // Each closed shell's solid gets its own region id (0, 1, ... by the order of its first
  // triangle); off: every element is in region 0. Shells inside another shell's solid are
  // cavities either way (they are not meshed).
  bool region_per_shell = true;
  // > 0: the surface is first replaced by its alpha wrap (CGAL's 3D Alpha Wrapping) at this
  // alpha, then meshed as a clean one: a closed, 2-manifold surface without crossings around
  // the input, whatever its holes, crossing or coinciding triangles and non-manifold edges (a
  // scan's). Gaps, holes and openings narrower than about alpha are closed over, and details
  // finer than it are smoothed away. Without an edge_length (and not keep_surface) the wrap
  // is meshed at edge_length = wrap. 0: the surface as it is, refused if it is broken.
  double wrap = 0.0;
  // How far outside the input the wrap lies. 0: wrap / 30 (CGAL's own choice).
  double wrap_offset = 0.0;
  // Look for triangles that cross or touch each other before calling TetGen (TetGen also
  // stops on one, but cannot say which). Off only to save time on a surface known clean.
  bool check_self_intersections = true;
  // Refuse to start when the volume bound implies at least this many tetrahedra.
  int max_tets = 20000000;
  // Stop TetGen after this many seconds (wall clock). 0: no limit.
  double time_limit_seconds = 0.0;

  // False with a message naming the field when a value is out of range.
  bool IsValid(std::string* error) const;
};

// What TetrahedralizeSurface found and did.
struct MeshingReport {
  // The input as given.
  int input_vertices = 0;
  int input_triangles = 0;
  // The alpha wrap that replaced the input (MeshingOptions::wrap), when it did.
  bool wrapped = false;
  double wrap_alpha = 0.0;
  double wrap_offset = 0.0;
  int wrapped_vertices = 0;
  int wrapped_triangles = 0;
  // The cleaned surface.
  int merged_vertices = 0;  // vertices merged into another one within merge_distance
  int unused_vertices = 0;  // vertices no triangle uses (dropped)
  int surface_vertices = 0;
  int shells = 0;               // closed components of the surface
  int cavities = 0;             // shells inside another shell's solid: holes, not meshed
  double merge_distance = 0.0;  // the distance used
  double surface_area = 0.0;
  double surface_volume = 0.0;  // enclosed: solids minus cavities
  double surface_mean_edge_length = 0.0;
  // The remeshed surface, when it was remeshed (MeshingOptions::remesh): TetGen's input.
  bool remeshed = false;
  int remeshed_vertices = 0;
  int remeshed_triangles = 0;
  int sharp_edges = 0;          // input edges kept as feature lines
  int dropped_sharp_edges = 0;  // sharp, but in a connected set shorter than 2 L in all: noise
  int corner_vertices = 0;      // input vertices kept in place (where 3+ feature lines meet)
  int short_edges = 0;  // edges below L / 10 left between feature lines, remeshed around again
  double remeshed_volume = 0.0;
  double remeshed_mean_edge_length = 0.0;
  // The settings passed to TetGen.
  double edge_length = 0.0;  // the target used
  double max_volume = 0.0;   // the volume bound used
  double radius_edge_ratio = 0.0;
  double min_dihedral_deg = 0.0;
  std::string tetgen_switches;  // e.g. "pq1.5/0a1.2e-07MA"
  std::string tetgen_log;       // what TetGen printed: stages, statistics, warnings
  std::string tetgen_warnings;  // the lines of the log that warn, if any
  // The mesh.
  int vertices = 0;
  int tets = 0;
  int regions = 0;
  int boundary_triangles = 0;
  double mesh_volume = 0.0;
  double min_edge_length = 0.0;
  double mean_edge_length = 0.0;
  double max_edge_length = 0.0;
  MeshQuality quality;
  // Share of the tetrahedra with a dihedral angle below 10 degrees or above 170 (slivers).
  double small_dihedral_share = 0.0;
  double large_dihedral_share = 0.0;
  // Wall-clock seconds.
  double wrap_seconds = 0.0;    // the alpha wrap
  double check_seconds = 0.0;   // reading excluded: merging, checks, shells
  double remesh_seconds = 0.0;  // remeshing and checking the remeshed surface
  double tetgen_seconds = 0.0;  // TetGen in its child process, the mesh sent back
  double finish_seconds = 0.0;  // FinalizeMesh, quality and edge statistics
  double total_seconds = 0.0;
};

// Tetrahedralizes the solid bounded by the closed triangle surface (V, F) with TetGen.
//   V  #V by 3 vertex positions
//   F  #F by 3 triangles, rows of V (either orientation, consistent across the surface)
// First merges duplicate vertices and drops unused ones, then checks that the surface
// bounds a volume (and remeshes it to options.edge_length, checked again), and refuses with a message (starting with `source`) that says what is
// wrong and where: boundary edges (an open surface), edges with more than two triangles,
// vertices where two sheets meet, inconsistently oriented neighbours, zero-area
// triangles, triangles that cross or touch each other, a shell with no volume. Several
// closed shells are fine: disjoint ones become separate pieces (regions), nested ones
// cavities. The mesh is finalized (FinalizeMesh: positively oriented, surface and
// adjacency built, x = rest, no masses). `report` may be null; it is filled as far as the
// work got, also on failure. TetGen runs in a child process (fork): when it gives up, it
// crashes (TetGen 1.5.0 frees its memory twice) or hits an assertion, the caller gets an
// error, not the crash.
Status TetrahedralizeSurface(const Vertices& V, const Triangles& F, const MeshingOptions& options,
                             TetMesh* mesh, MeshingReport* report,
                             const std::string& source = "surface");

// A coarse tetrahedral cage around the solid bounded by (V, F), for carrying that surface as
// an embedded one (objects[i].surface; femreg mesh --cage N): TetrahedralizeSurface with the
// surface remeshed to an edge length chosen, over a few passes, so that the mesh has about
// `target_vertices` vertices; then the mesh's boundary vertices moved out along their normals
// until every vertex of (V, F) is inside it (a few rounds; each corner by as much as the input
// sticks out over its triangles; a move is halved until no element turns over). The remeshed surface's vertices lie on the input and its triangles cut chords
// across it, so without the move parts of the input stick out by up to the chords' sagitta.
struct CageReport {
  MeshingReport meshing;       // the last pass's
  int passes = 0;              // meshing passes run
  double edge_length = 0.0;    // the last pass's target edge length
  double offset = 0.0;         // the largest move of a boundary vertex
  int outside_vertices = 0;    // vertices of (V, F) still outside the cage
  double outside_max = 0.0;    // the farthest of them from it (0 when all are inside)
  int outside_before = 0;      // the same before the move
  double outside_max_before = 0.0;
};
Status MakeCage(const Vertices& V, const Triangles& F, int target_vertices, const MeshingOptions& options,
                TetMesh* mesh, CageReport* report, const std::string& source = "surface");

// Reads a triangle surface by its extension: .ply (ASCII or binary, faces with 3 or more
// corners fanned into triangles), .obj, .stl (ASCII or binary; corners welded by exact
// position). Errors name the file and the line (or byte offset).
Status ReadSurface(const std::string& path, Vertices* V, Triangles* F);

// Writes a tetrahedral mesh (rest positions and region ids) in the format its extension
// names: .vtu (VTK XML), .msh (Gmsh 2.2 ASCII, region as physical tag), .mesh (MEDIT,
// region as reference), .vtk (VTK legacy ASCII, region as cell data). Every one of them
// is read back by ReadTetMesh. Written to a temporary file and renamed: a failure leaves
// whatever was at `path` untouched.
Status WriteTetMesh(const std::string& path, const TetMesh& mesh);

}  // namespace femreg

#endif  // FEMREG_MESHING_H_
