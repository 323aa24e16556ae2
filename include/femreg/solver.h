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

}  // namespace femreg

#endif  // FEMREG_SOLVER_H_
