// femreg/eval.h - evaluation against ground truth: VTU geometry in file order, triangle
// surfaces, and the distance between two surfaces.
#ifndef FEMREG_EVAL_H_
#define FEMREG_EVAL_H_

#include <string>
#include <vector>

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

}  // namespace femreg

#endif  // FEMREG_EVAL_H_
