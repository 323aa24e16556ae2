// femreg/geometry.h - exact closest points between points, segments and triangles, and an
// AABB hierarchy over the triangles of a surface (docs/theory/contact.md#detection). Used by
// collision detection; the nearest-point search over point sets and surfaces builds on the same
// point-triangle routine.
#ifndef FEMREG_GEOMETRY_H_
#define FEMREG_GEOMETRY_H_

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <utility>
#include <vector>

#include "femreg/mesh.h"

namespace femreg {

// The rotation of a rotation vector r (axis * angle, rad; the scene files' `rotation`);
// the identity for r = 0.
inline Eigen::Matrix3d RotationFromVector(const Eigen::Vector3d& r) {
  const double angle = r.norm();
  return angle > 0 ? Eigen::AngleAxisd(angle, r / angle).toRotationMatrix() : Eigen::Matrix3d::Identity();
}

// ---------------------------------------------------------------------------------------
// Exact closest-point queries.

// Closest point of triangle (a, b, c) to p (Voronoi regions; degenerate triangles by their
// edges); *barycentric (may be null) gets its weights (sum 1, all >= 0).
Eigen::Vector3d TriangleClosestPoint(const Eigen::Vector3d& p, const Eigen::Vector3d& a,
                                     const Eigen::Vector3d& b, const Eigen::Vector3d& c,
                                     Eigen::Vector3d* barycentric = nullptr);

// Closest points p0 + s (p1 - p0) and q0 + t (q1 - q0) of two segments, s, t in [0, 1];
// parallel and degenerate (point-like) segments included. Returns the distance.
double ClosestSegmentSegment(const Eigen::Vector3d& p0, const Eigen::Vector3d& p1,
                             const Eigen::Vector3d& q0, const Eigen::Vector3d& q1, double* s,
                             double* t);

struct TrianglePairDistance {
  double distance = 0.0;
  Eigen::Vector3d p = Eigen::Vector3d::Zero(), q = Eigen::Vector3d::Zero();  // on T1, on T2
  Eigen::Vector3d bary_p = Eigen::Vector3d(1, 0, 0), bary_q = Eigen::Vector3d(1, 0, 0);
  bool intersecting = false;  // the triangles cut each other (distance 0, p = q on the cut)
};

// Closest points of two triangles t1[0..2], t2[0..2]: an edge of one through the other's
// face (intersection), else the best of the 6 vertex-face and 9 edge-edge pairs; coplanar,
// parallel and touching triangles included.
TrianglePairDistance TriangleTriangleDistance(const Eigen::Vector3d* t1, const Eigen::Vector3d* t2);

// ---------------------------------------------------------------------------------------
// AABB hierarchy over the triangles of a surface.

class AabbTree {
 public:
  struct Node {
    Eigen::AlignedBox3d box;
    int left = -1, right = -1;  // children (both -1 at a leaf)
    int triangle = -1;          // leaf: the triangle (row of the triangle list)
  };

  // Top-down build (median split on the longest axis of the centroids). x: #V by 3,
  // triangles: #F by 3 rows of x. Call again after a topology change.
  void Build(const Vertices& x, const Triangles& triangles);
  // Recomputes the boxes bottom-up for moved vertices (same topology).
  void Refit(const Vertices& x);
  // Triangle pairs (this, other) whose boxes come within `margin` of each other, found by
  // descending both trees from the roots (coarse to fine).
  void Overlapping(const AabbTree& other, double margin,
                   std::vector<std::pair<int, int>>* pairs) const;
  // Triangles whose box comes within `margin` of `box`.
  void Overlapping(const Eigen::AlignedBox3d& box, double margin, std::vector<int>* triangles) const;

  bool empty() const { return nodes_.empty(); }
  int num_nodes() const { return static_cast<int>(nodes_.size()); }
  const Eigen::AlignedBox3d& bounds() const { return nodes_.front().box; }
  const std::vector<Node>& nodes() const { return nodes_; }
  const Triangles& triangles() const { return triangles_; }

 private:
  int BuildRange(const Vertices& x, std::vector<int>* order, int begin, int end);
  std::vector<Node> nodes_;  // children after their parent, so a reverse sweep refits
  Triangles triangles_;
};

// Locates points (given in a mesh's rest frame) in its tetrahedra: for each point, the
// element and barycentric coordinates. A point outside goes to the nearest element (the one
// whose smallest coordinate is largest): with `clamp`, onto that element (coordinates clipped
// to >= 0 and renormalised: the generators' ground truth, a point always in the body); without,
// its coordinates are extrapolated, so that the rest position is reproduced exactly (an
// embedded surface a little outside its cage keeps its shape).
struct EmbeddedPoints {
  std::vector<int> element;
  std::vector<Eigen::Vector4d> barycentric;
};
EmbeddedPoints EmbedPoints(const TetMesh& mesh, const Vertices& points, bool clamp = true);
// The embedded points at the mesh's vertex positions `positions` (#V by 3).
Vertices InterpolateEmbedded(const TetMesh& mesh, const Vertices& positions, const EmbeddedPoints& embedded);

}  // namespace femreg

#endif  // FEMREG_GEOMETRY_H_
