// Fine surfaces carried by coarse tetrahedra (objects[i].surface, Tracker::SetEmbeddedSurface;
// docs/theory/embedded-surfaces.md): each vertex of a fine surface is a fixed combination of
// the four vertices of one tetrahedron of its object's rest mesh. The data terms, the
// visibility and the occluders see the "data surface": per object its embedded surface, or
// its own mesh for an object without one; the elastic energy stays on the meshes.
#ifndef FEMREG_REGISTRATION_EMBEDDED_SURFACE_H_
#define FEMREG_REGISTRATION_EMBEDDED_SURFACE_H_

#include <Eigen/Core>
#include <array>
#include <vector>

#include "femreg/geometry.h"
#include "femreg/mesh.h"
#include "registration/correspondences.h"
#include "registration/tracker_state.h"

namespace femreg {

// One object's embedded surface as given, at rest, and where its vertices sit in the mesh.
struct EmbeddedSurface {
  Vertices rest;        // #S by 3, in the object's rest frame
  Triangles triangles;  // #F by 3, indices into rest
  EmbeddedPoints embedding;  // per vertex: its element of the object's mesh and coordinates
  // The largest distance (m) from a vertex outside the mesh to its element, at rest.
  double outside = 0.0;
};

// Embeds `rest` and `triangles` in `mesh`'s rest tetrahedra (coordinates extrapolated for the
// vertices just outside, so that the rest shape is reproduced exactly).
Status MakeEmbeddedSurface(const TetMesh& mesh, const Vertices& rest, const Triangles& triangles,
                           EmbeddedSurface* out);

// The data surface of a tracker's objects in one numbering (per object a run of its vertices:
// the embedded surface's, or all of the mesh's).
class DataSurface {
 public:
  // surfaces[i]: object i's embedded surface, or null (its mesh's surface). The state's
  // objects must not change topology afterwards (no fracture).
  void Build(const TrackerState& state, const std::vector<const EmbeddedSurface*>& surfaces);

  // The data surface at the coarse positions x: a TrackerState holding what the pair search,
  // the visibility and the occluders read (x, surface, surface_vertices, vertex_object,
  // num_vertices, mean_edge_length: the meshes', options); no objects. Its x is updated in place. Its
  // surface_vertices, those that pair with the cloud (model->cloud), are for an embedded
  // surface one per voxel of a third of its mesh's mean surface edge (pair_area).
  const TrackerState& Update(const Vertices& x);
  // The positions of view().surface_vertices (in that order) at the coarse positions x, as
  // Update computes them, without updating the view (the pair subsample, not the whole scan).
  Vertices PairVerticesAt(const Vertices& x) const;
  const TrackerState& view() const { return view_; }
  // The mean edge (m) of the data surface's triangles at rest (the view's mean_edge_length is
  // the meshes').
  double surface_edge() const { return surface_edge_; }
  const Vertices& rest() const { return rest_; }
  // Per data-surface vertex, its index among its object's surface vertices as they were given
  // (an embedded surface's file order, or the mesh's vertex): the view keeps an embedded
  // surface in its own spatial order.
  const std::vector<int>& source() const { return source_; }
  int offset(int object) const { return offset_[static_cast<size_t>(object)]; }
  int count(int object) const { return count_[static_cast<size_t>(object)]; }
  bool embedded(int object) const { return embedded_[static_cast<size_t>(object)] != 0; }
  // Object i's data-surface triangles in its own numbering (0 .. count(i) - 1), and its
  // positions in the view.
  Triangles ObjectSurface(int object) const;
  Vertices ObjectPositions(int object) const { return view_.x.middleRows(offset(object), count(object)); }
  // Its rows of view().surface, indices into view().x (no copy).
  Eigen::Ref<const Triangles> ObjectTriangles(int object) const {
    const auto i = static_cast<size_t>(object);
    return view_.surface.middleRows(first_triangle_[i], num_triangles_[i]);
  }

  // A point of the data surface as a combination of coarse vertices: n = 1 (a vertex of an
  // object without an embedded surface), 3 (a point on such an object's triangle) or 4 (a
  // point of an embedded surface).
  struct Stencil {
    int n = 1;
    std::array<int, 4> vertices{};  // global coarse indices
    std::array<double, 4> weights{};
  };
  // The model point of a pair found on the data surface. A point on an embedded triangle
  // is its rest position's coordinates in one of the elements of the triangle's corners, the
  // one it is least outside of (ties: the corner with the largest barycentric weight): four
  // vertices of one element, so that the data term couples no vertices the elastic term does
  // not (the sparsity pattern and its factor's analysis hold). It is the triangle's own point
  // where the triangle lies in that element; across an element's face it differs by at most
  // the triangle's size times the jump of the deformation gradient there.
  Stencil Map(const DataPair& pair) const;
  // Per data-surface vertex, the rest area (m^2) its model->cloud pair stands for: a third of
  // its triangles' for a mesh's own surface; for an embedded surface the area of the vertices in
  // its voxel (zero for the vertices not picked).
  const std::vector<double>& pair_area() const { return pair_area_; }
  // A data-surface vertex's coarse vertex with the largest weight (the per-vertex outputs).
  int Dominant(int vertex) const;

 private:
  TrackerState view_;
  Vertices updated_at_;  // the coarse positions view_.x was last computed at
  Vertices rest_;
  double surface_edge_ = 0.0;
  std::vector<double> pair_area_;
  std::vector<int> source_;
  std::vector<int> offset_, count_;
  std::vector<int> first_triangle_, num_triangles_;  // per object, its rows of view_.surface
  std::vector<char> embedded_;
  // Per data-surface vertex: its stencil (n 1 or 4) and, if embedded, its element in elements_.
  std::vector<Stencil> vertex_;
  std::vector<int> element_;
  // The embedded objects' elements: global vertices, the first vertex's rest position and the
  // inverse of the rest edge matrix (barycentric coordinates of a rest point).
  std::vector<std::array<int, 4>> elements_;
  std::vector<Eigen::Vector3d> origin_;
  std::vector<Eigen::Matrix3d> inverse_;
};

}  // namespace femreg

#endif  // FEMREG_REGISTRATION_EMBEDDED_SURFACE_H_
