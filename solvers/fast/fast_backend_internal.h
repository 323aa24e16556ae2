// The fast back end's state (FastBackend::Impl, fast_backend.h), shared by its two files:
// fast_backend.cc has the steps (PCG with the kept factor or the multigrid hierarchy, the
// line search) and Solve, fast_backend_factor.cc the factor's management (CHOLMOD's analysis,
// the fill estimate, the double and single-precision factorizations). fast_backend.cc's
// opening comment has the method.
#ifndef FEMREG_SOLVERS_FAST_FAST_BACKEND_INTERNAL_H_
#define FEMREG_SOLVERS_FAST_FAST_BACKEND_INTERNAL_H_

#include <Eigen/SparseCore>
#include <chrono>
#include <cstdint>
#include <memory>
#include <vector>

#include "energy/assembler.h"
#include "parallel/stopwatch.h"
#include "solvers/fast/equilibrium_step.h"
#include "solvers/fast/fast_backend.h"
#include "solvers/fast/multigrid.h"
#include "solvers/fast/supernodal_solve.h"

namespace femreg {
namespace fast_backend {

using Clock = std::chrono::steady_clock;
// The single-precision factorization (SupernodalSolve::Factorize) does its flops about this many
// times faster than PCG's iterations do theirs (memory-bound substitutions and products), so the
// factorization's flop count divided by an iteration's, over this, is the PCG iterations a
// factorization costs; 3 did better per frame than 1 and 2
// (docs/notes/2026-11-28-figures-from-code-comments.md), and again than 2 once the substitutions
// ran in float (docs/notes/2026-12-04-float-substitutions.md).
constexpr double kSingleFactorizationSpeed = 3.0;

// The own factorization's team: one thread per this many flops (CHOLMOD's count). Below it the
// team's start and the barriers of its tiled top cost more than the second thread saves
// (docs/notes/2026-11-30-factorization-team.md, 2026-11-30-team-threshold.md).
constexpr double kFactorizationFlopsPerThread = 1e8;

// After a single-precision factorization failed (or PCG did not converge with it), this many
// factorizations are CHOLMOD's in double before single precision is tried again: a matrix
// too ill-conditioned for float (the 1:1000 flat plate of tests/hard_cases_test.cc) stays so
// for a while, and each try costs a factorization and PCG iterations; a frame or two later
// the next try is cheap.
constexpr int kSingleBackoff = 8;

// kAuto decides without analysing H itself (AMD and METIS on every unknown, and the factor's
// workspace: a large share of the first frame on large meshes) where the vertex graph's estimate of
// the fill (EstimateFill) is this far above multigrid_fill. The estimate matched the analysis's
// fill closely on every mesh tried (docs/notes/2026-11-28-figures-from-code-comments.md), so only
// meshes that clearly take multigrid skip the analysis, and the choice is the one the analysis
// would make.
constexpr double kFillEstimateMargin = 1.5;
// ... and only from this many vertices: below, the estimate (METIS's fixed costs) takes about as
// long as the analysis it could save, and it would be done on top of it
// (docs/notes/2026-11-28-figures-from-code-comments.md).
constexpr int kFillEstimateFrom = 8192;

// The supernodal analysis's settings for these systems (3 unknowns per vertex): AMD and METIS
// both, and supernodes amalgamated a little beyond CHOLMOD's defaults. For the back end's
// supernodal factors, the equilibrium step's too (fast_backend_factor.cc says why).
void ConfigureAnalysis(cholmod_common* common);

struct FastBackend::Impl {
  BackendOptions options;
  int threads = 1;

  // The system's pattern and values (energy/assembler.h), and the pattern's revision that
  // the state below was made for.
  energy::Assembler assembler;
  Eigen::SparseMatrix<double>& H = assembler.H();
  const std::vector<int>& diagonal_at = assembler.diagonal_at();  // per column
  uint64_t pattern_revision = 0;
  // After the pattern changed: no analysis, factor or hierarchy of the old one is kept.
  void PatternChanged() {
    pattern_revision = assembler.pattern_revision();
    analysed = false;
    fill_estimate = -1.0;
    factor_valid = false;
    single_backoff = 0;
    multigrid = Multigrid();
  }

  // CHOLMOD's analysis of the pattern (and its double factor, where single precision
  // failed); the kept factor of the matrix at some earlier step (factor_valid), in single
  // precision, factorized there or copied from CHOLMOD's, for PCG's substitutions
  // (solvers/fast/supernodal_solve.h).
  CholmodFactor factor;
  SupernodalSolve<float> substitutions;
  bool analysed = false;
  bool factor_valid = false;
  // The analysis changed since `substitutions` last took L's structure.
  bool structure_pending = false;
  // Factorizations left to CHOLMOD in double before single precision is tried again: set
  // to kSingleBackoff when a single-precision factorization failed, or PCG did not converge
  // with a new one (H too ill-conditioned for float, or not positive definite at all).
  int single_backoff = 0;
  // The kept factor is a single-precision one (else CHOLMOD's).
  bool factor_single = false;
  // PCG iterations that cost as much as a factorization (CHOLMOD's flop counts, from the
  // analysis; for the single-precision one over kSingleFactorizationSpeed): beyond them a
  // new factor is cheaper.
  int pcg_budget_double = 0, pcg_budget_single = 0;
  int PcgBudget() const { return factor_single ? pcg_budget_single : pcg_budget_double; }
  // PCG iterations run with the kept factor since it was made. Once they have cost as much as a
  // factorization, the next step factorizes anew (the ski-rental rule: never more than twice the
  // cost of the better choice in hindsight) (docs/notes/2026-11-28-figures-from-code-comments.md).
  int pcg_since_factor = 0;

  // The multigrid preconditioner (solvers/fast/multigrid.h), where the factor would fill in
  // (options.multigrid_fill): a hierarchy of an earlier step's H, kept while the PCG solves
  // with it take few iterations more than the first one after it was built.
  Multigrid multigrid;
  int multigrid_fresh_iterations = -1;  // the first solved step's after the build (-1: none yet)
  int multigrid_last_iterations = 0;   // the last solve's
  const Vertices* positions = nullptr;  // the rigid motions' centre: the current iterate
  // PCG did not converge even with a new hierarchy: the factor for the rest of the Solve.
  bool multigrid_failed = false;
  // The last Pcg failed because r.z <= 0: the preconditioner is not positive definite.
  bool pcg_indefinite = false;
  // nnz(L) / nnz(H) from the analysis of the pattern.
  double fill = 0.0;
  double factor_flops = 0.0;  // CHOLMOD's flop count of one factorization (Analyse)
  int analyses = 0;  // Analyse's, over the back end's life (SolveReport::analyses per solve)
  // Before that analysis, for kAuto: an estimate of it from the vertex graph (-1: not yet
  // made for this pattern), see EstimateFill.
  double fill_estimate = -1.0;
  double EstimateFill() const;
  bool UseMultigrid() {
    if (options.max_pcg_iterations <= 0 || multigrid_failed) return false;
    switch (options.preconditioner) {
      case Preconditioner::kFactor:
        return false;
      case Preconditioner::kMultigrid:
        return true;
      case Preconditioner::kAuto:
        if (!analysed && assembler.num_vertices() >= kFillEstimateFrom) {
          if (fill_estimate < 0.0) fill_estimate = EstimateFill();
          if (fill_estimate >= kFillEstimateMargin * options.multigrid_fill) return true;
        }
        Analyse();  // once per pattern (the factor path needs it anyway)
        return fill >= options.multigrid_fill;
    }
    return false;
  }

  // CHOLMOD's symbolic analysis of the pattern, unless done; the PCG budget from its counts.
  void Analyse();
  // Factorizes H in double with CHOLMOD (its values also copied to `substitutions` for
  // PCG); false if H is not positive definite.
  bool Factorize(SolveReport* report);
  // Factorizes H in single precision into `substitutions` (the preconditioner, and the
  // first PCG iteration after it the step); false if that fails (not positive definite in
  // float), and nothing is kept.
  bool FactorizeSingle(SolveReport* report);
  // dx = -H^-1 g: by PCG with the kept factor, else with a new factorization. kNegligible:
  // PCG's first iteration gained less than `negligible` (the Gauss-Newton model's decrease;
  // <= 0: never), and no step was made.
  enum class Outcome { kSolved, kNegligible, kFailed };
  Outcome SolveStep(const Eigen::VectorXd& g, double negligible, Eigen::VectorXd* dx,
                    SolveReport* report);
  // The step by PCG with the multigrid hierarchy (built anew when stale); kFailed: leave
  // the step to the factorization.
  Outcome SolveStepMultigrid(const Eigen::VectorXd& g, double negligible, Eigen::VectorXd* dx,
                             SolveReport* report);
  // PCG on H x = b, preconditioned by the kept factor, or the multigrid hierarchy.
  Outcome Pcg(const Eigen::VectorXd& b, double negligible, int max_iterations, Eigen::VectorXd* x,
              SolveReport* report, bool with_multigrid = false);
  // The last step PCG solved (kSolved): the Gauss-Newton model's decrease along it,
  // 1/2 x.(b + r) = b.x - 1/2 x^T H x with r = b - H x (-1: no such step, e.g. a direct
  // solve), its residual r and whether multigrid preconditioned it.
  double pcg_model_gain = -1.0;
  Eigen::VectorXd pcg_residual;
  bool pcg_with_multigrid = false;
  // What a further step on the same model would gain: 1/2 r^T M^-1 r, with the
  // preconditioner M of that PCG (H, or an earlier H, approximately).
  double ResidualGain(SolveReport* report);
  // z = M^-1 r: the multigrid V-cycle, or the kept factor's substitutions (CHOLMOD's where
  // the single-precision copy could not be made); counted as a linear solve.
  void Precondition(const Eigen::VectorXd& r, bool with_multigrid, Eigen::VectorXd* z, SolveReport* report);
  // Problems with an equilibrium (energy/equilibrium.h) go to their own solve, made at the first.
  std::unique_ptr<EquilibriumSolver> equilibrium;
  // Every part's threads (the results do not depend on them).
  void SetThreads(int n) {
    threads = n;
    assembler.set_threads(n);
    substitutions.set_threads(n);
  }
};

}  // namespace fast_backend
}  // namespace femreg

#endif  // FEMREG_SOLVERS_FAST_FAST_BACKEND_INTERNAL_H_
