// Isotropic remeshing of a checked surface to a target edge length (CGAL's
// Polygon_mesh_processing), private to src/meshing/. Only remesh_surface.cc and
// wrap_surface.cc include CGAL, so that its templates are compiled once.
#ifndef FEMREG_MESHING_REMESH_SURFACE_H_
#define FEMREG_MESHING_REMESH_SURFACE_H_

#include <string>

#include "femreg/mesh.h"
#include "femreg/meshing.h"
#include "femreg/status.h"
#include "meshing/surface_check.h"

namespace femreg {
namespace internal {

struct RemeshSettings {
  double edge_length = 0.0;        // target edge length (> 0)
  double feature_angle_deg = 60.0;  // edges whose faces' normals differ by more are kept
                                    // as feature lines; >= 180: none
  int iterations = 5;              // split / collapse / flip / smooth rounds
};

struct RemeshResult {
  Vertices vertices;
  Triangles triangles;  // oriented as the input's
  int sharp_edges = 0;          // input edges kept as feature lines
  int dropped_sharp_edges = 0;  // sharp, but in a set of sharp edges shorter than 2 L in all
  int corner_vertices = 0;      // input vertices that do not move (three or more lines meet)
  int short_edges = 0;          // edges below L / 10 after remeshing, remeshed again around
};

// Remeshes the closed, consistently oriented, manifold surface (V, F) so that its edges are
// about settings.edge_length: edges are split, collapsed and flipped, vertices smoothed
// tangentially and projected back onto the input. Edges sharper than the feature angle stay
// on their polylines (split and collapsed along them only), unless a connected set of them is
// shorter than 2 L in all (noise, or a detail below the target); corners stay where they are.
// Errors start with `source`.
Status RemeshSurface(const Vertices& V, const Triangles& F, const RemeshSettings& settings,
                     const std::string& source, RemeshResult* out);

// TetrahedralizeSurface's remeshing step: `surface` (checked) remeshed to
// options.edge_length with options' feature angle and iterations, then checked again as the
// input was (closed, manifold, oriented, no crossing triangles, the same number of shells),
// into `out`. Fills the report's remeshed part and remesh_seconds. Errors start with `source`
// and say what to change.
Status RemeshCheckedSurface(const CheckedSurface& surface, const MeshingOptions& options,
                            const std::string& source, CheckedSurface* out,
                            MeshingReport* report);

}  // namespace internal
}  // namespace femreg

#endif  // FEMREG_MESHING_REMESH_SURFACE_H_
