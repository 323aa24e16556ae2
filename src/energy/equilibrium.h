// Equilibrium registration's term (docs/theory/equilibrium.md). The body's potential Pi(x) is
// the energy of the physics groups (elastic, loads, collision); its gradient at a vertex,
// f_v = dPi/dx_v, is the external force the shape x needs there to be in equilibrium (no
// force: x is an equilibrium of the elastic forces, gravity, loads and contacts alone). The
// registration energy does not minimize Pi: it penalizes f, vertex by vertex,
//
//   E_eq(x) = sum_v phi_v(f_v(x)),
//
// so that the data pull the shape only through forces that may act where they act: none
// inside the body or off the force region (a strong weight), any at clamps and anchors (their
// reaction), and on the free surface small ones (L2, optionally sparse: a group-L1 term makes
// them localise), optionally pushing only and within a friction cone. Its Gauss-Newton matrix
// is K^T Phi K, K = d2Pi/dx2 (the exact Hessian: energy/term.h's SecondOrder), Phi the
// penalties' curvatures; the fast back end solves with it (solvers/fast/equilibrium_step.h).
#ifndef FEMREG_ENERGY_EQUILIBRIUM_H_
#define FEMREG_ENERGY_EQUILIBRIUM_H_

#include <Eigen/Core>
#include <cstdint>
#include <vector>

#include "energy/term.h"
#include "femreg/mesh.h"

namespace femreg {
namespace energy {

class Problem;

// Where an external force may act on a vertex.
enum class ForceSite : uint8_t {
  kBalanced,  // none: inside the body, or on the surface outside the force region
  kFree,      // the free surface in the force region: penalized
  kSupport,   // a clamp's or an anchor's reaction: any force, not penalized
};

struct Equilibrium {
  // Per vertex (#V each; normal only with pushing_only).
  std::vector<ForceSite> site;
  std::vector<double> force_weight;   // alpha_v (m/N): 1/2 alpha |f|^2 on a free vertex
  std::vector<double> sparsity;       // s_v (m): s (sqrt(|f|^2 + eps^2) - eps) on a free vertex
  std::vector<double> strong_weight;  // beta_v (m/N): 1/2 beta |f|^2 on a balanced vertex, and
                                      // 1/2 beta dist(f, cone)^2 on a free one (pushing_only)
  std::vector<Eigen::Vector3d> normal;  // the surface's outward unit normal
  double sparsity_floor = 0.0;          // eps (N), > 0 where sparsity is
  bool pushing_only = false;            // a force points into the body: f . n <= 0
  double friction = -1.0;               // mu: |f_t| <= mu |f . n|; < 0: any tangential force
  // Turns a step does not make: a free body's turn about an axis its surface does not show
  // (docs/theory/stopping.md#hidden-turns). The fast back end's step dx keeps
  // sum_v (axis x (x_v - c)) . dx_v = 0 over the vertices [first, first + count), c their
  // centroid: a rigid motion of theirs, in K's null space as the preconditioner's rigid modes
  // are. With registration/prediction.h's HiddenTurnAxes as the axis, the turns the hold of
  // the outer iterations measures as hidden.
  struct HeldTurn {
    int first = 0, count = 0;
    Eigen::Vector3d axis = Eigen::Vector3d::UnitZ();
  };
  std::vector<HeldTurn> held_turns;
  // A solve of this problem makes at most this many steps (the fast back end's Gauss-Newton
  // steps, Ceres' iterations, its rejected ones included; 0: the back end's own limit): a
  // start that only has to bring the shape near (registration's smooth start before
  // forces.pushing_only, docs/theory/equilibrium.md#where-a-pushing-only-frame-starts).
  int max_steps = 0;

  // phi_v(f), its gradient and a positive semi-definite curvature (the sparse term's
  // majorizer s / sqrt(|f|^2 + eps^2) I, the cone's along the distance's direction). With
  // cone_at_bound, the cone's curvature is beta I on a free vertex wherever f is: its bound on
  // every piece (half a squared distance to a convex set has a 1-Lipschitz gradient), a
  // majorizer across the kinks.
  double Penalty(int v, const Eigen::Vector3d& f, Eigen::Vector3d* gradient,
                 Eigen::Matrix3d* curvature, bool cone_at_bound = false) const;
  // The penalty as least squares, for a back end that takes residuals (Ceres): phi_v(f) =
  // 1/2 |r|^2 + the sparse term, r = (sqrt(w) f, sqrt(beta) (f's part outside the cone)),
  // w = alpha on a free vertex and beta on a balanced one, and dr/df exact (zero at a support
  // and where f is inside the cone). The sparse term is s rho(|f|^2), rho(z) = sqrt(z + eps^2) - eps.
  void Residuals(int v, const Eigen::Vector3d& f, Eigen::Matrix<double, 6, 1>* r,
                 Eigen::Matrix<double, 6, 3>* dr_df) const;
  // Which piece of the pushing-only penalty holds at f on vertex v: 0 inside the cone (or no
  // cone), 1 beyond the half-space's face, 2 beyond the cone's side, 3 beyond its apex. Each
  // is smooth; the penalty has kinks only between them.
  int PenaltyPiece(int v, const Eigen::Vector3d& f) const;
  // alpha, beta and s times `factor` on every vertex: the penalty of forces.weight times it.
  void ScaleWeights(double factor);
  // The size of every per-vertex list is #V (normal too with pushing_only); the held turns'
  // vertices are within #V.
  bool IsValid(int num_vertices) const;
};

// The groups whose energy is the potential Pi, as a mask of 1 << TermGroup (Assembler::set_groups).
uint32_t PhysicsGroups();
// The others (data, temporal springs, anchors) and the barrier, a wall: minimized as they are.
uint32_t ObjectiveGroups();
inline bool InGroups(uint32_t mask, TermGroup group) { return (mask >> static_cast<int>(group)) & 1u; }

// f = dPi/dx at x (3 #V; zero at the problem's fixed vertices), the physics groups' blocks'
// gradients (exact: SecondOrder) added block by block, in set order, on one thread (the
// same sum on any thread count). `groups` narrows which physics groups (e.g. without the
// collision group: the forces the obstacles' contacts are part of). kGaussNewton: each
// block's least-squares gradient with its held parameters (an element's rotation), cheaper
// and, where they are current, the same.
void ForceResidual(const Problem& problem, const Vertices& x, Eigen::VectorXd* f,
                   uint32_t groups = PhysicsGroups(), Curvature curvature = Curvature::kExact);
// sum_v phi_v(f_v).
double EquilibriumEnergy(const Equilibrium& equilibrium, const Eigen::VectorXd& f);

}  // namespace energy
}  // namespace femreg

#endif  // FEMREG_ENERGY_EQUILIBRIUM_H_
