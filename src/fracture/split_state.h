// What fracture's node splits share (node_split.cc: SplitNodes and the working state's
// queries; cut_through.cc: the cut through a section): the working state of one batch of
// splits, and the sign convention of split normals.
#ifndef FEMREG_FRACTURE_SPLIT_STATE_H_
#define FEMREG_FRACTURE_SPLIT_STATE_H_

#include <Eigen/Core>
#include <array>
#include <vector>

#include "femreg/fracture.h"

namespace femreg {
namespace fracture_internal {

// A split normal's sign: its largest component positive, so that a plane has one normal
// whatever sign the eigen-solver returns.
inline Eigen::Vector3d CanonicalSign(Eigen::Vector3d n) {
  int k = 0;
  n.cwiseAbs().maxCoeff(&k);
  return n(k) < 0 ? Eigen::Vector3d(-n) : n;
}

// Working state of one batch of splits: elements are flagged instead of erased and the
// vertex stars kept up to date, so indices stay put until the final compaction.
struct SplitState {
  TetMesh* mesh;
  std::vector<std::array<int, 4>> tets;
  std::vector<char> removed;
  std::vector<std::vector<int>> star;  // vertex -> live elements
  std::vector<int> source;             // vertex -> old vertex
  std::vector<Eigen::Vector3d> rest, x;
  std::vector<char> touched;           // element
  std::vector<char> crack;             // vertex: a copy of a split node (on a crack)

  int AddReplica(int v);
  // Marks the vertices of earlier splits: a split leaves copies with the same rest position.
  void FindCracks();
  // Cracks: the crack vertices connected through their elements and through their copies.
  int CountCracks() const;
  // Whether j is on a crack's front, and the plane to split it by (world normal). j must
  // not be split yet and must share an element with a crack vertex. The crack's surface
  // near j (rest coordinates) is fitted to the crack vertices within 2.5 mean edge lengths
  // h of j: their plane, or where they lie on a line the plane through it closest to j's
  // own (j's normal taken to the rest frame by an element's rotation), or j's own plane
  // through a single vertex. j must lie within h/2 of that plane and its own normal within
  // 45 degrees of the plane's; it then splits by that plane, so that the crack grows along
  // its own surface.
  bool OnFront(int j, const Eigen::Vector3d& n, const ElasticModel& model,
               Eigen::Vector3d* split_normal) const;
  void Reassign(int e, int from, int to);
  void Remove(int e);
  // Whether the boundary triangles around u (faces of its elements seen once) form one
  // closed fan: then every surface edge at u has two triangles and u is not pinched.
  bool ManifoldAt(int u) const;
  // Elements in the smallest connected piece (elements sharing a vertex).
  int SmallestPiece() const;
  // Connected pieces (elements sharing a vertex).
  int CountPieces() const;
  Eigen::Vector3d RestCentroid(int e) const;
  // The cut through (FractureOptions::cut_through) from crack node j with rest-frame plane
  // normal m: the live elements reachable from j's through shared vertices whose rest
  // centroid lies within one mean edge of the plane through j are parted by the side of
  // their centroid, and every vertex with elements on both sides gets a replica for the
  // positive side. Returns the replicated vertices (empty: nothing done).
  std::vector<int> CutThrough(int j, const Eigen::Vector3d& m);
  // Gives each face-connected component of v's star but the first its own copy of v.
  int SplitPinched(int v);
};

// After SplitNodes' splits, with FractureOptions::cut_through: the cut through the section
// at the crack's first event (change->events.front()), kept only if the data shows a gap
// near it (NodeSeparation::gap, when given), it separates the body, every vertex stays
// manifold and no piece is under options.min_piece_fraction of the nt elements; its
// replicated vertices are added to change->events as cut events. nv: the vertices before
// the splits.
void CutThroughSection(const NodeSeparation& sep, const FractureOptions& options,
                       const ElasticModel& model, int nv, int nt, SplitState* st,
                       TopologyChange* change);

}  // namespace fracture_internal
}  // namespace femreg

#endif  // FEMREG_FRACTURE_SPLIT_STATE_H_
