// femreg/fracture.h - fracture by the separation tensor (docs/theory/fracture.md, after O'Brien and
// Hodgins 1999): detection per node from the tensile and compressive parts of the
// corotational element stresses, then node replication and re-assignment of the attached
// elements by the side of the fracture plane.
//
// The separation tensor in O'Brien and Hodgins' form (docs/theory/fracture.md#detection
// writes it out, with the compressive part's clamp):
//
//   zeta_j = 1/2 ( -m(f+_j) + sum_e m(f+_{e,j}) + m(f-_j) - sum_e m(f-_{e,j}) ),
//   m(a) = a a^T / |a| (0 for a = 0),  f+-_j = sum_e f+-_{e,j},
//
// with f+-_{e,j} = R_e (V_e L_e^T sigma+-_e)_j: the element's nodal force of the tensile
// (compressive) part of sigma_e = C_e L_e (R_e^T x_e - X_e) (docs/theory/fracture.md#detection),
// rotated to the world frame. zeta_j is in newtons; the fracture measure divides its largest
// eigenvalue by the node's area A_j = (V_j)^(2/3), V_j = sum_e V_e / 4 (rest), so that it is a
// stress (Pa, roughly independent of the mesh size) and compares with the scene's toughness.
#ifndef FEMREG_FRACTURE_H_
#define FEMREG_FRACTURE_H_

#include <Eigen/Core>
#include <string>
#include <utility>
#include <vector>

#include "femreg/fem.h"
#include "femreg/field_table.h"
#include "femreg/forward.h"
#include "femreg/mesh.h"

namespace femreg {

struct FractureOptions {
  // A node fractures when its measure (Pa) exceeds its toughness: the smallest positive
  // toughness of its elements' regions. <= 0: unbreakable.
  double toughness = 0.0;
  std::vector<std::pair<int, double>> region_toughness;  // region id -> toughness (Pa)
  // An element whose other vertices lie on both sides of the plane by more than this
  // fraction of its mean edge length is crossed by the plane and removed.
  double crossing_tolerance = 0.2;
  // A split that would leave a piece with fewer elements than this fraction of the mesh's
  // is not made (no shattering into crumbs that the data cannot hold).
  double min_piece_fraction = 0.05;
  int max_splits_per_iteration = 8;  // node splits per outer iteration (or forward round)
  int max_splits_per_frame = 48;     // node splits per frame
  // Cracks that may start (0 = any number: every node above its toughness may split, as
  // in O'Brien and Hodgins). Once the mesh has this many cracks (connected sets of split
  // nodes), only nodes on a crack's front may split: nodes that share an element with a
  // split node and whose fracture plane passes near it (within 30 degrees), so that the
  // crack grows along its own surface instead of nucleating wherever the measure is high.
  // A front node whose split alone would pinch the surface (its neighbour on the same
  // plane through the body's thickness still joined) splits together with those
  // neighbours, in one step.
  int max_cracks = 0;
  // Tracker only: where the body opened, the camera sees no surface, and the seen surface
  // vertices there are far from every cloud point (a point-to-plane data term does not
  // pull them across the hole, so in a body pulled evenly the stress alone cannot tell
  // where it opened). With data_gap, a node's measure counts min(3, 1 + g /
  // data.loss_scale) times, g: by how much the distance from the seen surface vertices at
  // the node to their nearest cloud point exceeds twice its median over the seen surface.
  bool data_gap = false;
  // Once a split opens a crack, complete it across the section in the same step: the crack's
  // plane (its first node's, in the rest frame) separates the elements near it by the side
  // their centroid is on, and every vertex with elements on both sides is replicated, so the
  // cut runs along the element faces nearest the plane and leaves no half-crack. Not done
  // (the crack stays as the splits left it) when the cut would leave a piece smaller than
  // min_piece_fraction, would not separate the body, or (tracker with a camera) the data
  // shows no gap near it (NodeSeparation::gap).
  bool cut_through = false;
  // Tracker only: each frame after the object came apart, each piece is first moved rigidly
  // onto the cloud points nearest it (its own ICP), so that a piece carried away is not held
  // back by a fit made for the others. Off by default: on the bundled sequences the pieces
  // move little from frame to frame, and it cost time without lowering the error.
  bool piece_prealign = false;
  // Tracker only: when a split parts the body, each new piece held by at least three hard
  // anchors is put back in its rest shape at their rigid pose, and the frame's remaining outer
  // iterations fit the data from there: the break releases the strain the whole body held, and
  // the pieces spring back. A piece nothing holds keeps its shape and relaxes under the data.
  bool relax_pieces = true;
  bool IsValid(std::string* error) const;
};

// The scene's `effects.fracture:` keys. toughness and region_toughness come from the objects
// (their `toughness`), and min_piece_fraction is the program's; IsValid checks them by hand.
template <>
struct OptionFields<FractureOptions> {
  static constexpr const char* kSection = "effects.fracture";
  template <class Visitor>
  static constexpr void Visit(Visitor&& v) {
    using S = FractureOptions;
    v(&S::max_splits_per_iteration, FieldInfo("max_splits_per_iteration").AtLeast(1).Doc("node splits per outer iteration"));
    v(&S::max_splits_per_frame, FieldInfo("max_splits_per_frame").AtLeast(1).Doc("node splits per frame"));
    v(&S::crossing_tolerance, FieldInfo("crossing_tolerance")
                                  .AtLeast(0)
                                  .Below(1)
                                  .Doc("elements crossed by the plane by more than this fraction of their "
                                       "mean edge are removed"));
    v(&S::max_cracks, FieldInfo("max_cracks").AtLeast(0).Note("(0 = any number)").Doc("cracks that may start; 0 = any number"));
    v(&S::data_gap, FieldInfo("data_gap").Doc("tracker: the data's gaps raise the fracture measure"));
    v(&S::cut_through, FieldInfo("cut_through").Doc("complete a crack across the section in one step"));
    v(&S::piece_prealign, FieldInfo("piece_prealign").Doc("tracker: each piece moved rigidly onto its points first"));
    v(&S::relax_pieces, FieldInfo("relax_pieces").Doc("tracker: held pieces put back in their rest shape after a break"));
  }
};

// Per-vertex result of the detection.
struct NodeSeparation {
  Eigen::VectorXd measure;  // #V largest eigenvalue of zeta_j / A_j, clamped at 0 (Pa)
  Vertices normal;          // #V by 3 unit eigenvector of that eigenvalue, sign-canonical
                            // (largest |component| positive)
  Eigen::VectorXd toughness;  // #V node toughness (Pa; <= 0 unbreakable)
  // Optional, #V, >= 1: a factor on the measure in SplitNodes' test and order (the
  // tracker's evidence from the data, FractureOptions::data_gap); empty: 1.
  Eigen::VectorXd weight;
  // Optional, #V: the data's gap at each vertex in units of the data's loss scale (the
  // tracker's evidence that the body opened there; FractureOptions::cut_through cuts only
  // where some vertex near the crack has a gap of at least 0.5). Empty: no evidence needed.
  Eigen::VectorXd gap;
};

// The separation tensor of every node (3 by 3, newtons) at positions x. model's rotations
// must be current for x (ElasticModel::UpdateRotations(x)).
std::vector<Eigen::Matrix3d> SeparationTensors(const TetMesh& mesh, const ElasticModel& model,
                                               const Vertices& x);
// The measure and plane normal per node (and the node toughness from options).
void DetectFracture(const TetMesh& mesh, const ElasticModel& model, const Vertices& x,
                    const FractureOptions& options, NodeSeparation* out);

// A node split by the fracture model (docs/theory/fracture.md#splitting): where, when and by which
// plane.
struct FractureEvent {
  int frame = -1;
  int object = 0;
  int iteration = 0;       // outer iteration after whose solve it was detected
  int node = -1;           // vertex index in the object's mesh before the split
  int original_node = -1;  // the same vertex in the mesh the tracker started with
  Eigen::Vector3d normal = Eigen::Vector3d::Zero();  // fracture plane normal (world frame)
  double measure = 0.0;    // largest eigenvalue of the separation tensor / node area (Pa)
  double toughness = 0.0;  // the node's toughness (Pa)
  int removed_elements = 0;  // elements crossed by the plane and removed
  bool cut = false;          // a vertex replicated by the cut through (cut_through)
};

// What a batch of splits did to the mesh. Per-vertex arrays of the old mesh are carried to
// the new one by `source`.
struct TopologyChange {
  std::vector<int> source;             // #V_new: the old vertex each new vertex comes from
  std::vector<FractureEvent> events;   // one per split node (node = old index)
  int removed_elements = 0;            // elements crossed by a fracture plane
  double removed_volume = 0.0;         // their rest volume (m^3)
  int dropped_vertices = 0;            // vertices left without elements
  bool changed() const { return !events.empty(); }
};

// Splits up to max_splits nodes whose measure (times separation.weight) exceeds their
// toughness, highest ratio first (with options.max_cracks > 0: the highest one that is allowed, see there; the nodes
// already split are recognised by their shared rest positions) (docs/theory/fracture.md#splitting):
// the node is replicated; its elements whose vertices are all on the
// positive side of the plane (within the tolerance; ties by the centroid) go to the
// replica, the others stay; elements the plane crosses are removed. A vertex whose
// remaining elements no longer connect through faces around it is split once more per
// component (no pinched vertices); vertices without elements are dropped. The mesh's
// rest, x, tets, region and topology are rebuilt, the model's rest data only for the
// touched elements; masses are left to the caller (ComputeLumpedMasses). The plane goes
// through the node's current position x (the deformed state the measure was taken in).
void SplitNodes(const NodeSeparation& separation, const FractureOptions& options, int max_splits,
                TetMesh* mesh, ElasticModel* model, TopologyChange* change);

// The forward simulator with fracture, as used for ground truth: detection and splits run
// between quasi-static solves (not inside SolveQuasiStatic): solve, detect, split up to
// options.max_splits_per_iteration nodes, re-solve on the new topology, for at most
// max_rounds rounds or options.max_splits_per_frame splits. `problem` is carried to the
// new vertices (a clamped or prescribed vertex's copies are too), masses are recomputed
// from `density`, and `original` (#V: the vertex of the first mesh each vertex comes from)
// and `events` are updated.
Status SolveQuasiStaticWithFracture(ForwardProblem* problem, const ForwardOptions& forward,
                                    const FractureOptions& options, int max_rounds,
                                    double density, ElasticModel* model, TetMesh* mesh,
                                    std::vector<int>* original, std::vector<FractureEvent>* events,
                                    ForwardSummary* summary);

// Rows of `values` (old vertices) carried to the new vertices.
Vertices RemapRows(const Vertices& values, const std::vector<int>& source);

// Mesh checks after topology edits.
struct MeshValidity {
  int nonpositive_volumes = 0;   // rest volume <= 0
  int orphan_vertices = 0;       // in no element
  int open_edges = 0;            // surface edges with one triangle or unmatched orientation
  int nonmanifold_edges = 0;     // surface edges with more than two triangles
  int nonmanifold_vertices = 0;  // surface vertices whose triangle fan is not one cycle
  int pieces = 0;                // connected components (elements sharing a vertex)
  bool ok() const {
    return nonpositive_volumes == 0 && orphan_vertices == 0 && open_edges == 0 &&
           nonmanifold_edges == 0 && nonmanifold_vertices == 0;
  }
  std::string ToString() const;
};
MeshValidity CheckMesh(const TetMesh& mesh);

}  // namespace femreg

#endif  // FEMREG_FRACTURE_H_
