// The solver back ends behind one interface: each minimizes an energy::Problem (the frame's
// terms, src/energy/) from the current positions. The tracker calls Solve once per outer
// iteration, with rotations, correspondences and contacts held.
//
// A new back end: a class derived from Backend in solvers/<name>/, made by MakeBackend.
#ifndef FEMREG_SOLVERS_BACKEND_H_
#define FEMREG_SOLVERS_BACKEND_H_

#include <memory>
#include <string>

#include "energy/problem.h"
#include "femreg/mesh.h"
#include "femreg/solver.h"

namespace femreg {

struct BackendOptions {
  SolverBackend type = SolverBackend::kCeres;
  int max_iterations = 10;              // Ceres iterations / fast back end Gauss-Newton steps
  // Stop when a step changes the energy by less than this fraction (Ceres' function
  // tolerance).
  double relative_tolerance = 1e-6;
  // Fast back end: stop when no vertex moved more than this in a step (m; 0: off). The
  // tracker sets it from the mesh's edge length (solver.step_tolerance).
  double step_tolerance = 0.0;
  // Fast back end, equilibrium problems (energy/equilibrium.h): stop also after a whole step
  // that moved no vertex more than this (m; 0: step_tolerance alone) and lowered the energy
  // little. Each of their steps makes a new factor; the tracker sets a quarter of
  // solver.bulk_step_tolerance of a mean edge, the move its outer iterations count as settled.
  double equilibrium_step_tolerance = 0.0;
  // Fast back end: a step is first solved by conjugate gradients preconditioned with the last
  // factorization (of an earlier, similar system), for at most this many iterations; only
  // if that does not converge is the system factorized anew. 0: factorize every step.
  int max_pcg_iterations = 20;
  // Fast back end: the factor, or (kAuto: where nnz(L) >= multigrid_fill nnz(H)) multigrid.
  Preconditioner preconditioner = Preconditioner::kAuto;
  double multigrid_fill = kMultigridFill;
  int num_threads = 1;
  TrustRegion trust_region = TrustRegion::kLevenbergMarquardt;  // Ceres
  LinearSolver linear_solver = LinearSolver::kSparseNormalCholesky;  // Ceres
};

// Why an inner solve stopped.
enum class StopReason {
  kNotRun,
  kGradient,       // the gradient fell to 1e-9 of where it started (or to zero)
  kStep,           // no vertex moved more than step_tolerance (or equilibrium_step_tolerance)
  kEnergy,         // the energy fell by less than relative_tolerance
  kPredicted,      // the next step would lower it by less than that (fast back end's model)
  kNoDecrease,     // no step along the descent direction lowered the energy (round-off)
  kMaxIterations,
  kTimeLimit,
  kSolver,         // Ceres' own criteria (its message says which)
  kFailure,
};
const char* ToString(StopReason reason);

struct SolveReport {
  bool success = false;
  std::string message = "Backend::Solve was not called.";
  StopReason stop = StopReason::kNotRun;
  int iterations = 0;        // steps taken, accepted and rejected
  int factorizations = 0;    // numeric factorizations of the system
  int hierarchies = 0;       // multigrid hierarchies built (fast back end; their time in factorize_s)
  int linear_solves = 0;     // preconditioner applications (PCG's) and direct solves
  int pcg_iterations = 0;    // conjugate-gradient iterations on steps solved that way
  int pattern_rebuilds = 0;  // new symbolic analyses (a widened or new sparsity pattern)
  // Fast back end: CHOLMOD analyses of the system's pattern (orderings and symbolic
  // factorization), at most one per pattern: where the factor is used, or where the
  // preconditioner is kAuto and the vertex graph's estimate of the fill does not settle it.
  int analyses = 0;
  // The solve refused most of its steps (Ceres: an element that a step would invert shrinks
  // the trust region to nothing; the fast back end, classic or equilibrium: its one step
  // refused, or cut to less than the step tolerance; docs/theory/stopping.md#stalled). The
  // largest entry of the energy's gradient (N; with the forces estimated, the equilibrium
  // energy's) where the solve started, and where it stopped when it refused most of its steps.
  bool mostly_refused = false;
  double largest_force_before = 0.0, largest_force_after = 0.0;
  // The problem's energy where the solve started and where it ended (*x on return).
  EnergyTerms before, after;
  // Where the time went (s). Ceres: linear_solve_s includes its factorizations.
  double assemble_s = 0.0, factorize_s = 0.0, linear_solve_s = 0.0, evaluate_s = 0.0;
};

class Backend {
 public:
  virtual ~Backend() = default;
  virtual SolverBackend type() const = 0;
  // Minimizes problem from *x (#V by 3, updated in place; fixed vertices do not move).
  // time_limit_s <= 0: no limit. On failure *x is left at the last accepted iterate.
  virtual SolveReport Solve(const energy::Problem& problem, double time_limit_s, Vertices* x) = 0;
  // As Solve, for a look-ahead whose result the caller throws away: what the back end
  // carries from one solve to the next is left as it was, so that the next Solve does as it
  // would have done without this one. (The fast back end's classic solve carries its factor
  // on, as in Solve: only equilibrium problems are solved aside by the tracker.)
  virtual SolveReport SolveAside(const energy::Problem& problem, double time_limit_s, Vertices* x) {
    return Solve(problem, time_limit_s, x);
  }
};

std::unique_ptr<Backend> MakeBackend(const BackendOptions& options);

}  // namespace femreg

#endif  // FEMREG_SOLVERS_BACKEND_H_
