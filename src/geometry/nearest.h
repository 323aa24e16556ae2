// Nearest-neighbour queries: a nanoflann k-d tree over a point set, and closest points on
// a triangle surface (through TriangleClosestPoint, femreg/geometry.h). Private to the
// library (nanoflann stays out of the public headers); used by registration, evaluation
// and the ground truth embedding.
#ifndef FEMREG_GEOMETRY_NEAREST_H_
#define FEMREG_GEOMETRY_NEAREST_H_

#include <Eigen/Core>
#include <memory>
#include <mutex>
#include <vector>

#include "femreg/mesh.h"

namespace femreg {

// A k-d tree over a copy of `points` (#P by 3).
class PointIndex {
 public:
  explicit PointIndex(const Vertices& points);
  ~PointIndex();
  PointIndex(const PointIndex&) = delete;
  PointIndex& operator=(const PointIndex&) = delete;

  int size() const { return static_cast<int>(points_.rows()); }
  const Vertices& points() const { return points_; }
  // Index of the nearest point and its squared distance; -1 when empty.
  int Nearest(const Eigen::Vector3d& query, double* squared_distance) const;
  // Whether a point lies within `max_distance` of query (a search that stops there: cheap for
  // a query far from every point).
  bool AnyWithin(const Eigen::Vector3d& query, double max_distance) const;
  // Up to k nearest, closest first.
  int KNearest(const Eigen::Vector3d& query, int k, int* indices, double* squared_distances) const;

 private:
  struct Tree;
  Vertices points_;
  std::unique_ptr<Tree> tree_;
};

// Per vertex, the triangles around it (those of `triangles` with keep[f] != 0, or all), each
// vertex's list in the triangles' order: a surface's topology, which does not change when its
// vertices move (SurfaceIndex shares it between rebuilds).
struct SurfaceRings {
  SurfaceRings(int num_vertices, const Triangles& triangles, const std::vector<char>* keep = nullptr);
  std::vector<int> offsets;  // #V + 1: vertex v's triangles are list[offsets[v] .. offsets[v + 1])
  std::vector<int> list;
  int num_vertices() const { return static_cast<int>(offsets.size()) - 1; }
  bool has(int v) const { return offsets[static_cast<size_t>(v) + 1] > offsets[static_cast<size_t>(v)]; }
};

// Area-weighted unit normals at `vertices` of the surface (x, triangles) whose rings are
// `rings`: row i is vertices[i]'s (zero for a vertex on no triangle). The same numbers as
// TrackerState::VertexNormals there (the face normals summed per vertex in face order), at the
// cost of the vertices' rings instead of the whole surface.
Eigen::MatrixXd VertexNormalsAt(const Vertices& x, const Triangles& triangles, const SurfaceRings& rings,
                                const std::vector<int>& vertices);

// Closest points on a triangle surface: candidates are the triangles around the k surface
// vertices nearest to the query, which finds the true closest triangle whenever it has a
// vertex among them (always for reasonably shaped surface triangles).
class SurfaceIndex {
 public:
  // positions: #V by 3 (all vertices); triangles: #F by 3 indices into positions.
  SurfaceIndex(const Vertices& positions, const Triangles& triangles, int candidate_vertices = 4);
  // Only the triangles f with keep[f] != 0 (#F entries, copied) are searched; hits keep
  // their index in `triangles`.
  SurfaceIndex(const Vertices& positions, const Triangles& triangles, const std::vector<char>& keep,
               int candidate_vertices = 4);
  // Every triangle, with `rings` made for them (SurfaceRings(positions.rows(), triangles)): an
  // index rebuilt where the surface moved reuses its topology.
  SurfaceIndex(const Vertices& positions, const Triangles& triangles, std::shared_ptr<const SurfaceRings> rings,
               int candidate_vertices = 4);

  struct Hit {
    int triangle = -1;
    Eigen::Vector3d barycentric = Eigen::Vector3d::Zero();
    Eigen::Vector3d point = Eigen::Vector3d::Zero();
    double squared_distance = 0.0;
  };
  // Warm-started from `start`, the triangle of an earlier hit of the same query (the last
  // outer iteration's): the closest point among the triangles around start's vertices,
  // walked on from the best of them until it stays (a few rings at most). The same as
  // Closest while the query's closest triangle is within reach of start's rings, without
  // the k-nearest search. start < 0 (or out of range): Closest(query). The walk tests at most
  // max_rings centres; *settled (if given) says whether it stayed before that (false: the
  // best found so far, which a closer triangle farther on may beat).
  Hit ClosestFrom(const Eigen::Vector3d& query, int start, int max_rings = 4, bool* settled = nullptr) const;
  // Closest's candidates for a query: the surface vertices nearest to it in the k-d tree
  // (where they were when the index was made), at most 16. Closest(query) searches the
  // triangles around them; a caller that first bounds the distance (DistanceBounds) searches
  // from the same candidates, without a second tree search.
  struct Candidates {
    int count = 0;
    int ids[16];                   // in the tree, nearest first
    double squared_distances[16];  // to the tree's positions
  };
  Candidates Nearby(const Eigen::Vector3d& query) const;
  Hit Closest(const Eigen::Vector3d& query) const { return Closest(query, Nearby(query)); }
  Hit Closest(const Eigen::Vector3d& query, const Candidates& near) const;
  // Bounds on the query's distance to the surface, and on Closest(query)'s, from its
  // candidates alone (no triangle tested): *upper, the nearest candidate's distance where it
  // is now (Closest tests the triangles around every candidate); *lower, the nearest
  // candidate's distance in the tree less the vertices' move since and the largest triangle's
  // bounding sphere (a point of a triangle has a corner within its sphere's radius).
  void DistanceBounds(const Eigen::Vector3d& query, const Candidates& near, double* lower, double* upper) const;
  // ClosestFrom(query, start, max_rings), and Closest(query) where that walk has not settled.
  Hit ClosestSeeded(const Eigen::Vector3d& query, int start, int max_rings) const {
    bool settled = true;
    const Hit hit = ClosestFrom(query, start, max_rings, &settled);
    return settled ? hit : Closest(query);
  }
  // Whether `triangle` touches vertex v's closed one-ring: one of its corners is v or shares
  // a triangle with v. v must be a vertex of `positions` (false for one on no triangle).
  bool TouchesRing(int v, int triangle) const;
  // The surface's vertices are now at most `distance` from where they were when the index was
  // made (an index kept while the surface moves a little): the queries allow for it. Not
  // while queries run.
  void SetMoved(double distance) { moved_ = distance; }
  const SurfaceRings& rings() const { return *rings_; }

 private:
  struct Tested;
  void Build();
  // Tests the triangles around vertex v not yet in *tested; *best keeps the closest.
  void TestAround(int v, const Eigen::Vector3d& query, const std::vector<Eigen::Vector4d>& spheres,
                  Tested* tested, Hit* best) const;
  // Per triangle its bounding sphere (centre, radius; zero for a triangle not searched), made
  // by the first query where the vertices were then (moved_ from where the index was made).
  const std::vector<Eigen::Vector4d>& Spheres() const;
  // The spheres' allowance for the vertices' moves: since the spheres were made, at most
  // moved_ plus the move they were made at.
  double SphereSlack() const { return moved_ + spheres_moved_; }
  // The largest of the spheres' radii (made with them).
  double LargestSphere() const;
  const Vertices& positions_;
  const Triangles& triangles_;
  int candidate_vertices_;
  std::vector<int> surface_vertex_ids_;  // index in the tree -> vertex id
  std::shared_ptr<const SurfaceRings> rings_;  // vertex id -> incident (kept) triangles
  std::vector<char> keep_;                      // empty: every triangle
  // The k-d tree over the surface vertices where they were when the index was made, built by
  // the first Closest: warm-started queries (ClosestFrom) never need it.
  const PointIndex& Tree() const;
  mutable Vertices tree_points_;  // freed once the tree is built
  mutable std::once_flag tree_once_;
  mutable std::unique_ptr<PointIndex> index_;
  mutable std::vector<Eigen::Vector4d> spheres_;
  mutable double largest_sphere_ = 0.0;
  mutable std::once_flag spheres_once_;
  double moved_ = 0.0;
  mutable double spheres_moved_ = 0.0;
};

}  // namespace femreg

#endif  // FEMREG_GEOMETRY_NEAREST_H_
