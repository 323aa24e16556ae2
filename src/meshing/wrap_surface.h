// A closed surface around a broken one (CGAL's 3D Alpha Wrapping), private to src/meshing/:
// femreg mesh --wrap. The only other file that includes CGAL is remesh_surface.cc.
#ifndef FEMREG_MESHING_WRAP_SURFACE_H_
#define FEMREG_MESHING_WRAP_SURFACE_H_

#include <string>

#include "femreg/mesh.h"
#include "femreg/status.h"

namespace femreg {
namespace internal {

// The alpha wrap of the triangles (V, F), taken as a soup (holes, crossing, coinciding or
// degenerate triangles and non-manifold edges are all fine): a closed, 2-manifold surface
// without self-intersections, oriented outwards, that encloses the input at a distance of
// about `offset`. `alpha` sets the detail: gaps, holes and openings narrower than about alpha
// are closed over, and so are the input's details finer than it. Both > 0 (same units as V).
// Errors start with `source`.
// What a refusal of a broken surface adds: the way round it.
inline constexpr const char* kWrapHint =
    "  a scan's or an export's surface can be wrapped first into a closed one around it: femreg mesh "
    "--wrap ALPHA (MeshingOptions::wrap), ALPHA about the narrowest gap or detail to keep "
    "(docs/guide/meshing.md#broken-surfaces)";

Status WrapSurface(const Vertices& V, const Triangles& F, double alpha, double offset,
                   const std::string& source, Vertices* wrapped_vertices, Triangles* wrapped_triangles);

}  // namespace internal
}  // namespace femreg

#endif  // FEMREG_MESHING_WRAP_SURFACE_H_
