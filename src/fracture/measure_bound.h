// The fracture measure where it matters: a cheap upper bound per node, and the full
// evaluation (DetectFracture's) only at the nodes whose bound reaches a given fraction of their
// toughness (docs/theory/fracture.md#before-the-break). The tracker's detection uses it; its
// outputs ask for the full measure at the last detection.
#ifndef FEMREG_FRACTURE_MEASURE_BOUND_H_
#define FEMREG_FRACTURE_MEASURE_BOUND_H_

#include <Eigen/Core>
#include <array>
#include <vector>

#include "femreg/fracture.h"

namespace femreg {
namespace fracture_internal {

// What the bound reads of a mesh, its model and the options, gathered once per topology: per
// node the area and the toughness, per element of a corotated model the few numbers the bound
// needs, side by side (the bound runs after every outer iteration).
// The values copied (or computed) as the bound read them from the model, so kept or rebuilt
// it gives the same bound.
struct BoundData {
  struct Element {
    std::array<int, 4> vertices;
    Eigen::Matrix3d dm_inv;
    std::array<Eigen::Vector3d, 4> g;  // the shape functions' gradients (ShapeGradients)
    std::array<double, 4> g2, g1;      // their squared norms and norms
    double volume, lambda, mu;
  };
  int num_vertices = -1, num_elements = -1;
  Eigen::VectorXd area, toughness;  // per node, as DetectFracture finds them
  std::vector<Element> elements;    // corotated models only (a linear element's stress is read)
  // Built for a mesh with these counts (a split changes them; the caller drops it then too).
  bool Fits(const TetMesh& mesh, const ElasticModel& model) const {
    return num_vertices == mesh.num_vertices() && num_elements == model.num_elements();
  }
};
void BuildBoundData(const TetMesh& mesh, const ElasticModel& model, const FractureOptions& options,
                    BoundData* data);

// Per node, an upper bound of DetectFracture's measure (Pa) at x: half the sum over its
// elements of a bound of V_e |sigma_e+ grad N_j|, over the node's area. It needs no element
// rotation (the corotational stress is a function of F^T F) and no eigen-decomposition.
Eigen::VectorXd MeasureBound(const TetMesh& mesh, const ElasticModel& model, const Vertices& x);

// DetectFracture at the nodes where it can reach `floor` times their toughness: out->toughness
// at every node; out->measure and out->normal as DetectFracture's at every node of positive
// toughness whose bound reaches floor times it, measure 0 and normal 0 at the others (their
// measure is below floor times their toughness, or they cannot break). Returns the nodes
// evaluated. rotations_current: the model's rotations are current for x; else the evaluated
// elements' are found from them as ElasticModel::UpdateRotations would, and the model's are
// left as they are.
int DetectFractureAbove(const TetMesh& mesh, const ElasticModel& model, const Vertices& x,
                        const FractureOptions& options, double floor, bool rotations_current,
                        NodeSeparation* out);
// The same with BoundData built for this mesh, model and options (data.Fits them).
int DetectFractureAbove(const TetMesh& mesh, const ElasticModel& model, const Vertices& x, double floor,
                        bool rotations_current, const BoundData& data, NodeSeparation* out);

// DetectFracture with the element rotations given (the model's are not read).
void DetectFractureWith(const TetMesh& mesh, const ElasticModel& model,
                        const std::vector<Eigen::Matrix3d>& rotations, const Vertices& x,
                        const FractureOptions& options, NodeSeparation* out);

// Each element's rotation at x, from the model's as the start (as ElasticModel::UpdateRotations
// finds them, without changing the model's).
std::vector<Eigen::Matrix3d> RotationsAt(const ElasticModel& model, const Vertices& x);

}  // namespace fracture_internal
}  // namespace femreg

#endif  // FEMREG_FRACTURE_MEASURE_BOUND_H_
