// The press case of the CalculiX contact comparison (tools/compare_calculix.sh): a soft block
// pressed by its top face onto a soft block clamped at its bottom, or onto a rigid plane, then
// optionally slid along x with friction. SolvePressCase runs femreg's forward solve on it;
// WritePressDeck writes the same meshes and loads as a CalculiX deck (*CONTACT PAIR).
// Shared by femreg_forward_probe and tests/contact_press_test.cc.
#ifndef FEMREG_TOOLS_PRESS_CASE_H_
#define FEMREG_TOOLS_PRESS_CASE_H_

#include <Eigen/Core>
#include <map>
#include <ostream>
#include <string>
#include <vector>

#include "femreg/mesh.h"
#include "femreg/status.h"

namespace femreg {

struct PressOptions {
  bool plane = false;  // the support: a clamped soft block, or a rigid plane at its top
  double base_modulus = 6e4, top_modulus = 3e4, poisson_ratio = 0.3;  // Pa
  // The stable neo-Hookean element against ccx's *HYPERELASTIC, NEO HOOKE (the same
  // small-strain moduli), or the corotational one against *ELASTIC, which NLGEOM makes
  // St. Venant-Kirchhoff: the two laws part by tens of percent at 15 % compression.
  bool neo_hookean = true;
  double gap = 5e-4;     // m: the pressed block starts this far above the support
  double press = 1.5e-3; // m: the top face's move down (frame 0, in load_steps)
  double slide = 0.0;    // m: then its move along x, in slide_frames frames of one step
  int slide_frames = 12;
  int load_steps = 8;
  int max_iterations = 100;  // Newton iterations per load step
  // femreg's contacts: k (N/m per contact), D (m), Coulomb mu, the friction slip eps (m).
  double stiffness = 1e5, distance = 1e-3, friction = 0.0, friction_slip = 2e-5;
  // CalculiX: the linear pressure-overclosure slope (Pa/m) and the stick slope (Pa/m).
  double ccx_stiffness = 1e9, ccx_stick_slope = 5e7;
  int num_threads = 1;
};

struct PressResult {
  // Both blocks, the support's first (the deck's numbering: node = index + 1); femreg solves
  // the pressed block alone against a plane obstacle when options.plane.
  TetMesh deck;
  int top_offset = 0;            // the pressed block's first vertex in `deck`
  int top_first_tet = 0;         // ... and its first element
  Vertices top_rest, top_x;      // the pressed block, at rest and solved
  std::vector<int> top_face;     // the pressed face (top_offset-based deck indices)
  std::vector<int> clamped;      // the support's held nodes (deck indices)
  std::vector<int> base_surface, top_surface;  // deck indices of the contact faces' vertices
  std::vector<char> free_surface;  // per pressed-block vertex: on its sides (not top, not bottom)
  // The support's force on the pressed block (N): all of it and its friction part, and the
  // force the prescribed top face takes (the reaction there).
  Eigen::Vector3d contact_force = Eigen::Vector3d::Zero(), friction_force = Eigen::Vector3d::Zero();
  Eigen::Vector3d top_reaction = Eigen::Vector3d::Zero();
  bool converged = false;
  int newton_iterations = 0, frames = 0;
  double max_penetration = 0.0;  // m, at the result
  std::string report;            // each frame's ForwardSummary::BriefReport
};

// The options from key=value arguments (femreg_forward_probe's, tools/compare_calculix.py's
// cases): support=block|plane model=neo_hookean|corotational E E_base nu gap press slide slide_frames load_steps stiffness
// distance mu slip ccx_stiffness ccx_stick max_iterations; other keys are left alone.
Status ParsePressOptions(const std::map<std::string, std::string>& args, PressOptions* options);

// Builds the meshes and solves (corotational model), frame by frame.
Status SolvePressCase(const PressOptions& options, PressResult* result);

// The same case as a CalculiX deck: C3D4, NLGEOM, *CONTACT PAIR surface to surface with a
// linear penalty (and *FRICTION when options.friction > 0); the plane is the support block
// with every node held. Prints the pressed block's displacements and the reactions' totals.
void WritePressDeck(const PressOptions& options, const PressResult& result, std::ostream& out);

}  // namespace femreg

#endif  // FEMREG_TOOLS_PRESS_CASE_H_
