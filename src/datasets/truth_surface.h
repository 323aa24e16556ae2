// The generators' ground truth surface: a fine mesh's boundary, compacted to its surface
// vertices, written per frame as truth/<frame>.vtu (what `femreg eval` measures against).
#ifndef FEMREG_DATASETS_TRUTH_SURFACE_H_
#define FEMREG_DATASETS_TRUTH_SURFACE_H_

#include <string>
#include <vector>

#include "femreg/eval.h"
#include "femreg/mesh.h"
#include "femreg/status.h"

namespace femreg {
namespace datasets_internal {

class TruthSurface {
 public:
  explicit TruthSurface(const TetMesh& mesh) {
    std::vector<int> compact(static_cast<size_t>(mesh.num_vertices()), -1);
    for (size_t i = 0; i < mesh.surface_vertices.size(); ++i) {
      compact[static_cast<size_t>(mesh.surface_vertices[i])] = static_cast<int>(i);
    }
    triangles_.resize(mesh.num_surface_triangles(), 3);
    for (int f = 0; f < mesh.num_surface_triangles(); ++f) {
      for (int k = 0; k < 3; ++k) triangles_(f, k) = compact[static_cast<size_t>(mesh.surface(f, k))];
    }
  }

  // The surface at mesh.x (the mesh this was made from, or one with its topology).
  Status Write(const std::string& path, const TetMesh& mesh) const {
    Vertices points(static_cast<Eigen::Index>(mesh.surface_vertices.size()), 3);
    for (size_t i = 0; i < mesh.surface_vertices.size(); ++i) {
      points.row(static_cast<Eigen::Index>(i)) = mesh.x.row(mesh.surface_vertices[i]);
    }
    return WriteVtuSurface(path, points, triangles_);
  }

 private:
  Triangles triangles_;
};

}  // namespace datasets_internal
}  // namespace femreg

#endif  // FEMREG_DATASETS_TRUTH_SURFACE_H_
