// The cut case of the CalculiX comparison (tools/compare_calculix.sh --only cut): a soft beam
// clamped at one end and bent by a gripper at the other (intact), then a thin slab of its
// elements removed while the gripper carries the free end on (separation). SolveCutCase runs
// femreg's forward solve on it (the corotational element; the slab's elements dropped from the
// mesh between the two steps, as the beam_cut sequence's ground truth does); WriteCutDeck writes
// the same mesh and motions as a CalculiX deck, the slab removed by *MODEL CHANGE, TYPE=ELEMENT,
// REMOVE in its second step.
#ifndef FEMREG_TOOLS_CUT_CASE_H_
#define FEMREG_TOOLS_CUT_CASE_H_

#include <Eigen/Core>
#include <map>
#include <ostream>
#include <string>
#include <vector>

#include "femreg/mesh.h"
#include "femreg/status.h"

namespace femreg {

struct CutOptions {
  // The beam: 200 x 30 x 30 mm in 40 x 6 x 6 cells (faces at the slab's ends), as beam_cut's
  // ground truth; E and nu as its foam.
  double length = 0.2, width = 0.03;
  int cells_along = 40, cells_across = 6;
  double youngs_modulus = 5e4, poisson_ratio = 0.35;
  // The gripper holds the vertices with x >= grip_x; step 1 turns it by `bend` (rad, about y)
  // along the circular arc of a pure bending, in load_steps; step 2 carries it on by `carry` (m).
  double grip_x = 0.185, bend = 0.4;
  Eigen::Vector3d carry = Eigen::Vector3d(0.016, 0.0, 0.012);
  int load_steps = 8;
  // The slab removed in step 2: the elements whose rest centroid lies between cut_lo and cut_hi.
  double cut_lo = 0.07, cut_hi = 0.075;
  int max_iterations = 100;
};

struct CutResult {
  TetMesh mesh;                   // the intact beam (the deck's numbering: node = index + 1)
  std::vector<int> clamped, gripped;
  std::vector<int> slab;          // the removed elements
  Vertices u_bent, u_cut;         // displacements after step 1 and step 2 (#V by 3)
  std::vector<int> piece;         // per vertex after the cut: 0 on the clamped piece, 1 on the free one
  Vertices grip_bent, grip_cut;   // the gripped vertices' prescribed displacements per step
  bool converged = false;
  int newton_iterations = 0;
  std::string report;
};

// key=value arguments: E nu bend carry_x carry_z load_steps max_iterations; others are left alone.
Status ParseCutOptions(const std::map<std::string, std::string>& args, CutOptions* options);

Status SolveCutCase(const CutOptions& options, CutResult* result);

// C3D4, *ELASTIC under NLGEOM (St. Venant-Kirchhoff), the clamp and the gripper's displacements
// per node, step 2 with *MODEL CHANGE, TYPE=ELEMENT, REMOVE of the slab. Prints U at the end of
// each step.
void WriteCutDeck(const CutOptions& options, const CutResult& result, std::ostream& out);

}  // namespace femreg

#endif  // FEMREG_TOOLS_CUT_CASE_H_
