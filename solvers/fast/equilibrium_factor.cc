#include "solvers/fast/equilibrium_factor.h"

#include <algorithm>
#include <cmath>
#include <vector>

#include "parallel/signals.h"
#include "parallel/stopwatch.h"
#include "parallel/threads.h"

namespace femreg {
namespace fast_backend {

namespace {
// The shift of K~ = K + shift * mean(diag K): enough for a free body's rigid motions (K's null
// space) to factorize; raised 100-fold while the factorization fails.
constexpr double kFirstShift = 1e-8;
}  // namespace

void EquilibriumFactor::Analyse(const Eigen::SparseMatrix<double>& K) {
  if (analysed_) return;
  factor.setMode(Eigen::CholmodSupernodalLLt);
  factor.cholmod().print = 0;  // a matrix that is not positive definite is an answer here
  ConfigureAnalysis(&factor.cholmod());  // the classic solve's orderings and supernodes
  {
    const KeepSignalHandlers keep;  // METIS's signal() calls (parallel/signals.h)
    factor.analyzePattern(K);
  }
  factor_flops = factor.cholmod().fl;
  // A PCG iteration: two solves (four sweeps over L, 2 nnz(L) flops each) and two products
  // with K (2 nnz(K) each; H's is smaller, left out).
  const double iteration_flops = 8.0 * factor.cholmod().lnz + 4.0 * static_cast<double>(K.nonZeros());
  factorization_iterations_ = iteration_flops > 0 ? static_cast<int>(factor_flops / iteration_flops) : 0;
  analysed_ = true;
  structure_pending = true;
  indefinite_pending[0] = indefinite_pending[1] = true;
}

bool EquilibriumFactor::Factorize(const energy::Problem& problem, const Vertices& x, energy::Assembler* physics,
                                  energy::Assembler* projected, int threads, SolveReport* report) {
  threads_ = threads;
  use_ldlt = false;
  use_indefinite = 0;
  factor_single = false;
  if (FactorizeIndefinite(physics, report)) {
    // A negative pivot above round-off is K's own. Without one, pivots at the floor are
    // round-off on a positive definite K, where CHOLMOD's double-precision Cholesky is the
    // better preconditioner.
    const bool single = use_indefinite == 1;
    const int negative = single ? indefinite_single.negative_pivots() : indefinite_double.negative_pivots();
    const int perturbed = single ? indefinite_single.perturbed_pivots() : indefinite_double.perturbed_pivots();
    if (negative > 0 || perturbed == 0) return true;
    const int held = use_indefinite;
    use_indefinite = 0;
    if (FactorizeOf(physics, kFirstShift, kCholmodDouble, report)) return true;
    use_indefinite = held;
    return true;
  }
  if (FactorizeOf(physics, kFirstShift, kCholmodDouble, report)) return true;
  const auto t0 = Clock::now();
  if (!ldlt_analysed) {
    ldlt.setMode(Eigen::CholmodLDLt);
    ldlt.cholmod().print = 0;
    const KeepSignalHandlers keep;  // METIS's signal() calls (parallel/signals.h)
    ldlt.analyzePattern(physics->H());
    ldlt_analysed = true;
  }
  {
    const ScopedThreads one_thread(1);
    WithThreadLimit(1, [&] { ldlt.factorize(physics->H()); });
  }
  ++report->factorizations;
  report->factorize_s += Seconds(t0);
  if (ldlt.info() == Eigen::Success) {
    use_ldlt = true;
    return true;
  }
  const auto t1 = Clock::now();
  // The same blocks as `physics`: the same pattern, and the analysis holds for both.
  projected->Prepare(problem, x);
  Eigen::VectorXd unused;
  projected->AssembleSecondOrder(problem, x, energy::Curvature::kProjected, true, &unused);
  projected->Finish(problem, 0.0, &unused);
  report->assemble_s += Seconds(t1);
  return FactorizeOf(projected, 1.0, kOwnFloat | kCholmodDouble, report);
}

// The own factorizations' team: up to `threads_` by the factor's size. The tree's cut and the
// tiles depend on the factor alone, so every team gives the same factor.
int EquilibriumFactor::FactorTeam() const {
  return PhaseThreads(threads_, static_cast<long long>(factor_flops),
                      static_cast<long long>(kFactorizationFlopsPerThread));
}

// K~ (K with FactorizeOf's first shift) as L S L^T in the own supernodal code, in float,
// else in double; false if neither (a pivot too small at its precision).
bool EquilibriumFactor::FactorizeIndefinite(energy::Assembler* physics, SolveReport* report) {
  const auto t0 = Clock::now();
  Eigen::SparseMatrix<double>& K = physics->H();
  Analyse(K);
  const std::vector<int>& diagonal_at = physics->diagonal_at();
  double mean = 0.0;
  for (int at : diagonal_at) mean += std::abs(K.valuePtr()[at]);
  mean /= std::max<size_t>(1, diagonal_at.size());
  for (int at : diagonal_at) K.valuePtr()[at] += kFirstShift * mean;
  {
    const ScopedThreads one_thread(1);  // the BLAS; the groups on the factorization's own team
    const int team = FactorTeam();
    ++report->factorizations;
    if (indefinite_single.FactorizeIndefinite(*factor.raw(), K, indefinite_pending[0], team)) {
      indefinite_pending[0] = false;
      use_indefinite = 1;
      indefinite_single.set_threads(threads_);
    } else {
      ++report->factorizations;
      if (indefinite_double.FactorizeIndefinite(*factor.raw(), K, indefinite_pending[1], team)) {
        indefinite_pending[1] = false;
        use_indefinite = 2;
        indefinite_double.set_threads(threads_);
      }
    }
  }
  for (int at : diagonal_at) K.valuePtr()[at] -= kFirstShift * mean;
  report->factorize_s += Seconds(t0);
  return use_indefinite != 0;
}

// Factorizes the matrix of `a` plus shifts from kFirstShift up to max_shift of its mean
// diagonal, with the `attempts` (kOwnFloat, kCholmodDouble); false if none is positive definite.
bool EquilibriumFactor::FactorizeOf(energy::Assembler* a, double max_shift, int attempts, SolveReport* report) {
  const auto t0 = Clock::now();
  Eigen::SparseMatrix<double>& K = a->H();
  Analyse(K);
  const std::vector<int>& diagonal_at = a->diagonal_at();
  std::vector<double> diagonal(diagonal_at.size());
  double mean = 0.0;
  for (size_t c = 0; c < diagonal_at.size(); ++c) {
    diagonal[c] = K.valuePtr()[diagonal_at[c]];
    mean += std::abs(diagonal[c]);
  }
  mean /= std::max<size_t>(1, diagonal.size());
  bool valid = false;
  for (double shift = kFirstShift; shift <= max_shift && !valid; shift *= 100.0) {
    for (size_t c = 0; c < diagonal_at.size(); ++c) K.valuePtr()[diagonal_at[c]] = diagonal[c] + shift * mean;
    factor_single = false;
    if (attempts & kOwnFloat) {
      ++report->factorizations;
      const ScopedThreads one_thread(1);  // the BLAS; the factorization's own team
      factor_single = substitutions.Factorize(*factor.raw(), K, structure_pending, FactorTeam());
      substitutions.set_threads(threads_);  // PCG's substitutions: the groups on the workers
    }
    if (factor_single) {
      structure_pending = false;
      valid = true;
      break;
    }
    if (!(attempts & kCholmodDouble)) continue;
    ++report->factorizations;
    const ScopedThreads one_thread(1);
    WithThreadLimit(1, [&] { factor.factorize(K); });
    valid = factor.info() == Eigen::Success;
  }
  for (size_t c = 0; c < diagonal_at.size(); ++c) K.valuePtr()[diagonal_at[c]] = diagonal[c];
  report->factorize_s += Seconds(t0);
  return valid;
}

void EquilibriumFactor::Solve(const Eigen::VectorXd& b, Eigen::VectorXd* out) {
  if (use_indefinite == 1) {
    indefinite_single.Solve(b, out);
  } else if (use_indefinite == 2) {
    indefinite_double.Solve(b, out);
  } else if (use_ldlt) {
    *out = ldlt.solve(b);
  } else if (factor_single) {
    substitutions.Solve(b, out);
  } else {
    *out = factor.solve(b);
  }
}

}  // namespace fast_backend
}  // namespace femreg
