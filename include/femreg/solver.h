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
  kAuto,       // the factor below kMultigridFromVertices (3000) vertices, multigrid from there
  kFactor,     // a sparse Cholesky factor of an earlier step's system, kept while it serves
  kMultigrid,  // smoothed-aggregation algebraic multigrid (cost linear in the mesh's size)
};

// Where `auto` changes from the factor to multigrid (vertices of the frame's problem).
// Measured (median ms per frame, factor against multigrid): the 2197-vertex organ_patch
// body 84 / 91 against 103 / 92 (2 threads), the 3375-vertex one 209 / 210 against
// 141 / 166; the scaling benchmark's boxes (one thread) at 5049 vertices 301 against 274,
// at 20034 vertices 2978 against 1478, at 69741 vertices 33.6 s against 11.2 s.
constexpr int kMultigridFromVertices = 3000;

}  // namespace femreg

#endif  // FEMREG_SOLVER_H_
