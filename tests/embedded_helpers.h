// Helpers of the embedded-surface tests: a mesh's surface as a scan, one object's state.
#ifndef FEMREG_TESTS_EMBEDDED_HELPERS_H_
#define FEMREG_TESTS_EMBEDDED_HELPERS_H_

#include <vector>

#include "femreg/mesh.h"
#include "registration/tracker_state.h"

namespace femreg {

// The surface of a mesh, compacted to its surface vertices.
inline void SurfaceOf(const TetMesh& mesh, const Vertices& x, Vertices* vertices, Triangles* triangles) {
  std::vector<int> compact(static_cast<size_t>(mesh.num_vertices()), -1);
  vertices->resize(static_cast<Eigen::Index>(mesh.surface_vertices.size()), 3);
  for (size_t i = 0; i < mesh.surface_vertices.size(); ++i) {
    compact[static_cast<size_t>(mesh.surface_vertices[i])] = static_cast<int>(i);
    vertices->row(static_cast<Eigen::Index>(i)) = x.row(mesh.surface_vertices[i]);
  }
  triangles->resize(mesh.num_surface_triangles(), 3);
  for (int f = 0; f < mesh.num_surface_triangles(); ++f) {
    for (int k = 0; k < 3; ++k) (*triangles)(f, k) = compact[static_cast<size_t>(mesh.surface(f, k))];
  }
}

// A state of one object for DataSurface.
inline void OneObject(const TetMesh& mesh, TrackerState* state) {
  state->objects.resize(1);
  state->objects[0].mesh = mesh;
  state->RebuildGlobalArrays();
  state->x = mesh.rest;
}

}  // namespace femreg

#endif  // FEMREG_TESTS_EMBEDDED_HELPERS_H_
