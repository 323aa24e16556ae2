// A closed surface around a broken one (CGAL's 3D Alpha Wrapping), private to src/meshing/:
// femreg mesh --wrap. The only other file that includes CGAL is remesh_surface.cc.
#ifndef FEMREG_MESHING_WRAP_SURFACE_H_
#define FEMREG_MESHING_WRAP_SURFACE_H_

#include <string>

#include "femreg/mesh.h"
#include "femreg/meshing.h"
#include "femreg/status.h"

namespace femreg {
namespace internal {

// A refusal of a surface that does not bound a volume (not of unreadable input: no triangle,
// a vertex not finite, a corner out of range, every vertex at one point) with the way round
// it added: the wrap.
Status WithWrapHint(const Status& refusal);

// MeshingOptions' wrap of (V, F) for TetrahedralizeSurface and MakeCage: its offset wrap_offset,
// or wrap / 30; timed; into *report's wrap fields. Input CGAL cannot take (corners out of
// range, coordinates not finite) is refused first.
Status WrapForMeshing(const Vertices& V, const Triangles& F, const MeshingOptions& options,
                      const std::string& source, Vertices* wrapped_vertices, Triangles* wrapped_triangles,
                      MeshingReport* report);
// The wrap fields of `from` (wrapped ... wrap_seconds) into *to.
void CopyWrapReport(const MeshingReport& from, MeshingReport* to);

// TetrahedralizeSurface, and whether its refusals suggest the wrap (not where the input is a
// wrap already).
Status Tetrahedralize(const Vertices& V, const Triangles& F, const MeshingOptions& options, TetMesh* mesh,
                      MeshingReport* report, const std::string& source, bool wrap_hint);

// The alpha wrap of the triangles (V, F), taken as a soup (holes, crossing, coinciding or
// degenerate triangles and non-manifold edges are all fine): a closed, 2-manifold surface
// without self-intersections, oriented outwards, that encloses the input at a distance of
// about `offset`. `alpha` sets the detail: gaps, holes and openings narrower than about alpha
// are closed over, and so are the input's details finer than it. Both > 0 (same units as V).
// Errors start with `source`.
Status WrapSurface(const Vertices& V, const Triangles& F, double alpha, double offset,
                   const std::string& source, Vertices* wrapped_vertices, Triangles* wrapped_triangles);

}  // namespace internal
}  // namespace femreg

#endif  // FEMREG_MESHING_WRAP_SURFACE_H_
