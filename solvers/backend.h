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
  int max_iterations = 10;              // Ceres iterations / fast back end factorizations
  // Stop when a step changes the energy by less than this fraction (Ceres' function
  // tolerance).
  double relative_tolerance = 1e-6;
  int num_threads = 1;
  TrustRegion trust_region = TrustRegion::kLevenbergMarquardt;  // Ceres
  LinearSolver linear_solver = LinearSolver::kSparseNormalCholesky;  // Ceres
};

struct SolveReport {
  bool success = false;
  std::string message = "Backend::Solve was not called.";
  int iterations = 0;        // steps taken, accepted and rejected
  int factorizations = 0;    // numeric factorizations of the system
  int linear_solves = 0;
  int pattern_rebuilds = 0;  // new symbolic analyses (a widened or new sparsity pattern)
};

class Backend {
 public:
  virtual ~Backend() = default;
  virtual SolverBackend type() const = 0;
  // Minimizes problem from *x (#V by 3, updated in place; fixed vertices do not move).
  // time_limit_s <= 0: no limit. On failure *x is left at the last accepted iterate.
  virtual SolveReport Solve(const energy::Problem& problem, double time_limit_s, Vertices* x) = 0;
};

std::unique_ptr<Backend> MakeBackend(const BackendOptions& options);

}  // namespace femreg

#endif  // FEMREG_SOLVERS_BACKEND_H_
