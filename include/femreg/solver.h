// femreg/solver.h - which solver back end minimizes a frame's energy, and how (the names
// are in femreg/registration.h with the options that use them).
#ifndef FEMREG_SOLVER_H_
#define FEMREG_SOLVER_H_

namespace femreg {

enum class SolverBackend {
  kCeres,  // the reference: Ceres with the options below
  kFast,   // Gauss-Newton on a directly assembled system, CHOLMOD pattern reused
};
enum class TrustRegion { kLevenbergMarquardt, kDogleg };  // Ceres only
enum class LinearSolver {                                 // Ceres only
  kSparseNormalCholesky,  // SuiteSparse CHOLMOD through Ceres
  kConjugateGradients,    // Ceres' CGNR with a Jacobi preconditioner
};

// Fast back end: what preconditions the conjugate gradients that solve each step.
enum class Preconditioner {
  kAuto,       // multigrid where the factor would fill in (kMultigridFill), else the factor
  kFactor,     // a sparse Cholesky factor of an earlier step's system, kept while it serves
  kMultigrid,  // smoothed-aggregation algebraic multigrid (cost linear in the mesh's size)
};

// Where `auto` changes from the factor to multigrid: where the sparse Cholesky factor (from
// CHOLMOD's analysis of the system's pattern) would hold this many entries or more per entry of the
// system. A PCG iteration with the factor streams the factor twice; one with multigrid costs about
// 7 products with the system, and the factor's share grows with the mesh (a 3-D mesh's factor has
// O(V^4/3) entries), at a rate set by its shape, so a vertex count would not do; the measured
// crossover is near 6 (docs/dev/fast-backend.md,
// docs/notes/2026-11-28-figures-from-code-comments.md).
constexpr double kMultigridFill = 6.0;

}  // namespace femreg

#endif  // FEMREG_SOLVER_H_
