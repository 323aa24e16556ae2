// Cleaning and checking a triangle surface before it is tetrahedralized (private to
// src/meshing/).
#ifndef FEMREG_MESHING_SURFACE_CHECK_H_
#define FEMREG_MESHING_SURFACE_CHECK_H_

#include <Eigen/Core>
#include <string>
#include <utility>
#include <vector>

#include "femreg/mesh.h"
#include "femreg/status.h"

namespace femreg {
namespace internal {

// A closed component of the surface.
struct SurfaceShell {
  std::vector<int> triangles;  // rows of the surface's triangle list
  double signed_volume = 0.0;  // > 0 when its triangles face outwards
  double area = 0.0;
  int depth = 0;  // how many other shells enclose it (odd: a cavity)
  Eigen::Vector3d inside_point = Eigen::Vector3d::Zero();  // strictly inside it, near its surface
};

// The surface after merging, with what the checks measured.
struct CheckedSurface {
  Vertices vertices;    // #V by 3, merged, unused ones dropped
  Triangles triangles;  // #F by 3, the input's rows in the input's order, renumbered
  int merged_vertices = 0;
  int unused_vertices = 0;
  double merge_distance = 0.0;
  double area = 0.0;
  double mean_edge_length = 0.0;
  double bounding_box_diagonal = 0.0;
  std::vector<SurfaceShell> shells;
};

// Merges vertices closer than merge_distance (negative: 1e-9 of the bounding box
// diagonal), drops unused ones, and checks that the triangles bound a volume: no
// zero-area triangle, every edge in exactly two triangles that traverse it in opposite
// directions, one fan of triangles around each vertex, no two triangles crossing or
// touching (when check_self_intersections), every shell enclosing a volume. Finds the
// shells, their nesting and a point inside each. On failure the message starts with
// `source` and lists every problem found with a count and an example.
Status CheckSurface(const Vertices& V, const Triangles& F, double merge_distance,
                    bool check_self_intersections, const std::string& source, CheckedSurface* out);

// Generalized winding number of `p` with respect to the closed triangle set `triangles`
// (rows of F): +-1 inside, 0 outside (sum of signed solid angles / 4 pi).
double WindingNumber(const Eigen::Vector3d& p, const Vertices& V, const Triangles& F,
                     const std::vector<int>& triangles);

}  // namespace internal
}  // namespace femreg

#endif  // FEMREG_MESHING_SURFACE_CHECK_H_
