// The equilibrium step's preconditioner factor (solvers/fast/equilibrium_step.h): of K~ = K +
// a small shift of the mean diagonal (a free body's rigid motions), K the potential's exact
// Hessian as the step linearized it. Where K is not positive definite (compressed or turning
// elements) K Phi K is still positive definite and K^-1 Phi^-1 K^-1 its inverse. K~ is
// factorized as L S L^T without pivoting (the own supernodal code on CHOLMOD's analysis, in
// float, else in double; its positive definite supernodes by LAPACK's Cholesky, so that on a
// positive definite K it is the Cholesky factor at a Cholesky's cost); where that shows no
// negative pivot but some at its floor (round-off on a positive definite K), CHOLMOD's
// Cholesky in double is tried first. If the L S L^T fails: CHOLMOD's Cholesky in double, then
// its simplicial L D L^T of K itself, then K's projection (energy/term.h, Curvature) with a
// shift raised until it factorizes (docs/theory/equilibrium.md#solving-it).
#ifndef FEMREG_SOLVERS_FAST_EQUILIBRIUM_FACTOR_H_
#define FEMREG_SOLVERS_FAST_EQUILIBRIUM_FACTOR_H_

#include <Eigen/Core>
#include <Eigen/SparseCore>

#include "energy/assembler.h"
#include "energy/problem.h"
#include "solvers/backend.h"
#include "solvers/fast/fast_backend_internal.h"
#include "solvers/fast/supernodal_solve.h"

namespace femreg {
namespace fast_backend {

class EquilibriumFactor {
 public:
  // Factorizes K~ with K the matrix `physics` holds (linearized last at x; its values are left
  // as they were); `projected` assembles K's projection at x where nothing else factorizes.
  // The own factorizations run on a team of up to `threads`, sized by the factor's flops.
  // False if nothing factorizes.
  bool Factorize(const energy::Problem& problem, const Vertices& x, energy::Assembler* physics,
                 energy::Assembler* projected, int threads, SolveReport* report);
  // *out = K~^-1 b with the last factor.
  void Solve(const Eigen::VectorXd& b, Eigen::VectorXd* out);
  // Another pattern (a new mesh or set of terms): the next Factorize analyses it.
  void Reset() {
    analysed_ = false;
    ldlt_analysed = false;
  }
  // The PCG iterations (two solves, two products with K) that cost about as many flops as a
  // factorization; known once a factorization has analysed the pattern.
  int factorization_iterations() const { return factorization_iterations_; }

 private:
  void Analyse(const Eigen::SparseMatrix<double>& K);
  int FactorTeam() const;
  bool FactorizeIndefinite(energy::Assembler* physics, SolveReport* report);
  // The Cholesky factorizations FactorizeOf tries at each shift, in this order.
  static constexpr int kOwnFloat = 1, kCholmodDouble = 2;
  bool FactorizeOf(energy::Assembler* a, double max_shift, int attempts, SolveReport* report);

  int threads_ = 1;
  // CHOLMOD's analysis and its supernodal factor in double (where float fails), and the own
  // Cholesky factor in float on the same analysis.
  CholmodFactor factor;
  SupernodalSolve<float> substitutions;
  CholmodFactor ldlt;  // of an indefinite K (simplicial), where the own L S L^T fails
  bool ldlt_analysed = false, use_ldlt = false;
  // The own L S L^T of an indefinite K on the same analysis: in float, else in double; which
  // one holds the factor (0: neither), and whether each must take the structure again.
  SupernodalSolve<float> indefinite_single;
  SupernodalSolve<double> indefinite_double;
  int use_indefinite = 0;
  bool indefinite_pending[2] = {false, false};
  bool analysed_ = false, structure_pending = false, factor_single = false;
  double factor_flops = 0.0;  // CHOLMOD's flop count of one factorization (Analyse)
  int factorization_iterations_ = 0;
};

}  // namespace fast_backend
}  // namespace femreg

#endif  // FEMREG_SOLVERS_FAST_EQUILIBRIUM_FACTOR_H_
