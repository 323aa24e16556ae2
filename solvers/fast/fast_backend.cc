// The fast back end: Gauss-Newton on the frame's energy with a sparse Cholesky factor that
// is kept and reused: CHOLMOD's symbolic analysis (ordering, supernodes), the numeric
// factorization in single precision by the back end itself (solvers/fast/supernodal_solve.h),
// CHOLMOD's double one where that fails.
//
// A step solves H dx = -g, H the Gauss-Newton Hessian (sum of w rho' J^T J over the blocks),
// g the gradient. The factorization of H is what costs; H changes little from one step to
// the next (robust weights), from one outer iteration to the next (rotations, pairs) and
// from one frame to the next. So a step is first solved by conjugate gradients
// preconditioned with the last factor: when that factor is of a similar matrix, a few
// iterations (each a product with H and two triangular solves) reach the tolerance; when
// not, or once the iterations run with a factor have cost as much as a factorization, H is
// factorized, the step solved by PCG with the new factor (one or two iterations: the
// factor's float round-off), and the factor kept for the steps after. The symbolic
// analysis is done once per sparsity pattern (the mesh's topology, widened by contact
// stencils).
//
// Steps are taken with a backtracking line search on the energy (the Gauss-Newton direction
// is a descent direction: H is positive semi-definite by construction). A failed
// factorization (H not numerically positive definite in float) is done again by CHOLMOD in
// double, and retried with Marquardt damping if H is not positive definite there either.
//
// H and g come from the energy layer's assembler (energy/assembler.h).
//
// The back end's state is declared in fast_backend_internal.h; the factor's management
// (analysis, fill estimate, factorizations) is in fast_backend_factor.cc.
#include "solvers/fast/fast_backend.h"

#include <Eigen/CholmodSupport>
#include <Eigen/SparseCore>
#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <limits>
#include <map>
#include <type_traits>
#include <unordered_map>
#include <utility>
#include <vector>

#include "energy/assembler.h"
#include "parallel/signals.h"
#include "solvers/fast/equilibrium_step.h"
#include "solvers/fast/fast_backend_internal.h"
#include "parallel/pool.h"
#include "parallel/threads.h"
#include "solvers/fast/multigrid.h"
#include "solvers/fast/supernodal_solve.h"

namespace femreg {
namespace fast_backend {

namespace {

// A step predicted to lower the energy by less than this fraction of the inner tolerance
// (BackendOptions::relative_tolerance) is not taken: it re-solves the linearization the
// step before it solved (to PCG's tolerance, with robust weights that did not change).
// Steps between this and the tolerance are taken: they move contacts and robust weights,
// and skipping them changed the end state of non-converging contact cases
// (tests/hard_cases_test.cc) (docs/notes/2026-11-28-figures-from-code-comments.md).
// (Unless the step before was predicted by the model, which leaves such a step's gain to
// what PCG left: Solve, after the line search.)
constexpr double kNegligibleGain = 1e-2;

// A full step whose energy decrease the Gauss-Newton model predicted to this fraction of itself is
// taken as a step on a quadratic (Solve: the next step is then skipped if what PCG left is below
// the tolerance): where the energy is quadratic the model is exact to round-off, where robust
// weights change it is not, and skipping those steps too moved the errors
// (docs/notes/2026-11-28-figures-from-code-comments.md).
constexpr double kQuadraticAgreement = 1e-6;

// With the multigrid preconditioner (large meshes, BackendOptions::preconditioner), a step's
// PCG runs up to this many iterations with the kept hierarchy (again after refreshing its
// smoother, if PCG found it indefinite), then as many with a new one; if that does not
// converge either, the step goes to the factorization.
constexpr int kMultigridMaxIterations = 100;
// Below what a new hierarchy costs in PCG iterations with it: 28-60 from 4k to 64k vertices
// (bench/linear_solver_bench.cc, MultigridBuild against MultigridCycle plus BlockProduct). A
// count, not a timing: the same choices, and so the same result, on any machine.
constexpr int kMultigridBuildIterations = 25;

}  // namespace

// H is symmetric, so y_c = H(:, c) . p: each entry a gather over its column, in parallel
// without races and in the same order on any number of threads; a 3x3 block costs one row
// vertex (block_rows) instead of nine row indices.
void BlockProduct(const Eigen::SparseMatrix<double>& H, const std::vector<int>& block_rows,
                  const Eigen::VectorXd& p, int threads, Eigen::VectorXd* y, int parallel_from) {
  eigen_assert(static_cast<Eigen::Index>(9 * block_rows.size()) == H.nonZeros());
  const int blocks = static_cast<int>(H.cols()) / 3;
  const int* outer = H.outerIndexPtr();
  const int* rows = block_rows.data();
  const double* values = H.valuePtr();
  const double* pp = p.data();
  y->resize(p.size());
  double* yy = y->data();
  auto column = [&](int b) {
    const int begin = outer[3 * b];
    const int* at = rows + begin / 9;
    BlockColumnSums(
        values + begin, outer[3 * b + 1] - begin, [pp, at](int q) { return pp + 3 * at[q]; },
        yy + 3 * b);
  };
  if (threads > 1 && blocks >= parallel_from) {
    ParallelRanges(threads, blocks, SpanGrain(blocks), [&](int64_t begin, int64_t end) {
      for (int64_t b = begin; b < end; ++b) column(static_cast<int>(b));
    });
  } else {
    for (int b = 0; b < blocks; ++b) column(b);
  }
}

FastBackend::FastBackend(const BackendOptions& options) : impl_(new Impl) {
  impl_->options = options;
  impl_->threads = ResolveThreadCount(options.num_threads);
  impl_->assembler.set_threads(impl_->threads);
}
FastBackend::~FastBackend() = default;

namespace {
constexpr int kPcgProductParallelFrom = 1024;
}  // namespace

FastBackend::Impl::Outcome FastBackend::Impl::Pcg(const Eigen::VectorXd& b, double negligible,
                                                  int max_iterations, Eigen::VectorXd* x,
                                                  SolveReport* report, bool with_multigrid) {
  // The substitutions are the back end's own (`substitutions`, on its threads); CHOLMOD's, only if
  // that copy could not be made, on one BLAS thread: too small to share
  // (docs/notes/2026-11-28-figures-from-code-comments.md).
  const ScopedThreads one_thread(1);
  pcg_indefinite = false;
  pcg_model_gain = -1.0;
  const double b_norm = b.norm();
  x->setZero(b.size());
  if (b_norm == 0.0) return Outcome::kSolved;
  Eigen::VectorXd r = b;
  Eigen::VectorXd z;
  auto precondition = [&] { Precondition(r, with_multigrid, &z, report); };
  precondition();
  Eigen::VectorXd p = z;
  Eigen::VectorXd q(b.size());
  double rz = r.dot(z);
  for (int k = 0; k < max_iterations; ++k) {
    // Between two substitutions on the same workers (they poll for the next job, parallel/pool.h):
    // a product from 1024 vertices on pays for them.
    BlockProduct(H, assembler.block_rows(), p, threads, &q, kPcgProductParallelFrom);
    const double pq = p.dot(q);
    // (rz <= 0: the preconditioner is not positive definite, e.g. a multigrid smoother
    // whose eigenvalue bound fell short.)
    if (!(pq > 0.0) || !(rz > 0.0) || !std::isfinite(rz)) {
      pcg_indefinite = std::isfinite(rz) && !(rz > 0.0);
      return Outcome::kFailed;
    }
    // The first iteration minimizes the model 1/2 dx^T H dx - b.dx along z: it gains
    // 1/2 (b.z)^2 / (z^T H z), a lower bound on the whole step's gain.
    if (k == 0 && 0.5 * rz * rz / pq < negligible) return Outcome::kNegligible;
    const double alpha = rz / pq;
    *x += alpha * p;
    r -= alpha * q;
    ++report->pcg_iterations;
    if (!with_multigrid) ++pcg_since_factor;
    if (r.norm() <= kPcgTolerance * b_norm) {
      pcg_model_gain = 0.5 * x->dot(b + r);
      pcg_residual.swap(r);
      pcg_with_multigrid = with_multigrid;
      return Outcome::kSolved;
    }
    precondition();
    const double rz_next = r.dot(z);
    p = z + (rz_next / rz) * p;
    rz = rz_next;
  }
  return Outcome::kFailed;
}

void FastBackend::Impl::Precondition(const Eigen::VectorXd& r, bool with_multigrid, Eigen::VectorXd* z,
                                     SolveReport* report) {
  if (with_multigrid) {
    multigrid.Apply(r, z);
  } else if (substitutions.loaded()) {
    substitutions.Solve(r, z);
  } else {
    *z = factor.solve(r);
  }
  ++report->linear_solves;
}

double FastBackend::Impl::ResidualGain(SolveReport* report) {
  const auto t0 = Clock::now();
  const ScopedThreads one_thread(1);  // as in Pcg
  Eigen::VectorXd z;
  Precondition(pcg_residual, pcg_with_multigrid, &z, report);
  report->linear_solve_s += Seconds(t0);
  return 0.5 * pcg_residual.dot(z);
}

FastBackend::Impl::Outcome FastBackend::Impl::SolveStepMultigrid(const Eigen::VectorXd& g,
                                                                 double negligible,
                                                                 Eigen::VectorXd* dx,
                                                                 SolveReport* report) {
  // The kept hierarchy while the last solve with it took at most twice, or at most
  // kMultigridBuildIterations more than, the iterations of the first solve after its build:
  // a new one would cost more than it saves. If PCG finds the V-cycle not positive
  // definite for this H (the finest smoother's eigenvalue bound is an earlier H's), once
  // more with that bound estimated for this H.
  auto solve = [&](double* seconds) {
    const auto t0 = Clock::now();
    const int before = report->pcg_iterations;
    const Outcome outcome = Pcg(-g, negligible, kMultigridMaxIterations, dx, report, true);
    *seconds += Seconds(t0);
    const int iterations = report->pcg_iterations - before;
    if (outcome == Outcome::kSolved) {
      multigrid_last_iterations = iterations;
      if (multigrid_fresh_iterations < 0) multigrid_fresh_iterations = iterations;
    }
    return outcome;
  };
  const int fresh = std::max(multigrid_fresh_iterations, 0);
  // The V-cycle's reduced-precision copy of this step's H (bfloat16), timed with the hierarchy.
  auto set_finest = [&] {
    const auto t0 = Clock::now();
    const bool set = multigrid.SetFinest(H);
    report->factorize_s += Seconds(t0);
    return set;
  };
  if (multigrid.built() && multigrid_last_iterations <= std::max(2 * fresh, fresh + kMultigridBuildIterations) &&
      set_finest()) {
    Outcome outcome = solve(&report->linear_solve_s);
    if (outcome == Outcome::kFailed && pcg_indefinite) {
      const auto t0 = Clock::now();
      const bool refreshed = multigrid.RefreshFinest();  // H is set: set_finest()
      report->factorize_s += Seconds(t0);
      if (refreshed) outcome = solve(&report->linear_solve_s);
    }
    if (outcome == Outcome::kNegligible) return outcome;
    if (outcome == Outcome::kSolved && dx->allFinite()) return Outcome::kSolved;
  }
  const auto t0 = Clock::now();
  const bool built = positions != nullptr && multigrid.Build(H, *positions, threads);
  report->factorize_s += Seconds(t0);
  if (!built) {
    multigrid_failed = true;
    return Outcome::kFailed;
  }
  ++report->hierarchies;
  multigrid_fresh_iterations = -1;  // the next solved step's count
  multigrid_last_iterations = 0;
  const Outcome outcome = solve(&report->linear_solve_s);
  if (outcome == Outcome::kNegligible) return outcome;
  if (outcome == Outcome::kSolved && dx->allFinite()) return Outcome::kSolved;
  // Not even a fresh hierarchy: the factor for the rest of this Solve (H itself may be
  // indefinite, which the factor path answers with damping).
  multigrid = Multigrid();
  multigrid_failed = true;
  return Outcome::kFailed;
}

FastBackend::Impl::Outcome FastBackend::Impl::SolveStep(const Eigen::VectorXd& g, double negligible,
                                                        Eigen::VectorXd* dx, SolveReport* report) {
  pcg_model_gain = -1.0;  // known only for a step PCG solves
  if (UseMultigrid()) {
    const Outcome outcome = SolveStepMultigrid(g, negligible, dx, report);
    if (outcome != Outcome::kFailed) return outcome;
  }
  const auto t0 = Clock::now();
  if (factor_valid && options.max_pcg_iterations > 0 && pcg_since_factor < PcgBudget()) {
    const Outcome outcome =
        Pcg(-g, negligible, std::min(options.max_pcg_iterations, std::max(1, PcgBudget())), dx, report);
    report->linear_solve_s += Seconds(t0);
    if (outcome == Outcome::kNegligible) return outcome;
    if (outcome == Outcome::kSolved && dx->allFinite()) return Outcome::kSolved;
  }
  // A new factor in single precision, and the step by PCG with it (its first iteration is
  // the solve with the factor; PCG corrects the factor's float round-off, in one or two
  // more: up to max_pcg_iterations, whatever the budget for a kept factor).
  if (options.max_pcg_iterations > 0 && single_backoff == 0) {
    if (FactorizeSingle(report)) {
      const auto t1 = Clock::now();
      const Outcome outcome = Pcg(-g, 0.0, options.max_pcg_iterations, dx, report);
      report->linear_solve_s += Seconds(t1);
      if (outcome == Outcome::kSolved && dx->allFinite()) return Outcome::kSolved;
    }
    single_backoff = kSingleBackoff;
  } else if (single_backoff > 0) {
    --single_backoff;
  }
  // Else (or with max_pcg_iterations 0) CHOLMOD's factor in double, and the step solved
  // with it; if H is not numerically positive definite, Marquardt damping until it is.
  std::vector<double> diagonal(diagonal_at.size());
  for (size_t c = 0; c < diagonal_at.size(); ++c) diagonal[c] = H.valuePtr()[diagonal_at[c]];
  double lambda = 0.0;
  bool ok = Factorize(report);
  for (int attempt = 0; !ok && attempt < 12; ++attempt) {
    lambda = lambda == 0.0 ? 1e-6 : lambda * 100.0;
    for (size_t c = 0; c < diagonal_at.size(); ++c) {
      H.valuePtr()[diagonal_at[c]] = diagonal[c] * (1.0 + lambda);
    }
    ok = Factorize(report);
  }
  for (size_t c = 0; c < diagonal_at.size(); ++c) H.valuePtr()[diagonal_at[c]] = diagonal[c];
  if (!ok) return Outcome::kFailed;
  const auto t1 = Clock::now();
  const ScopedThreads one_thread(1);  // as in Pcg
  *dx = factor.solve(-g);
  ++report->linear_solves;
  report->linear_solve_s += Seconds(t1);
  return dx->allFinite() ? Outcome::kSolved : Outcome::kFailed;
}

Backtracked Backtrack(const energy::Problem& problem, const Eigen::VectorXd& dx, double energy, int halvings,
                      int threads, Vertices* trial, Vertices* x, SolveReport* report) {
  Backtracked b;
  const int n = static_cast<int>(x->rows());
  double alpha = 1.0;
  double checked_last_try = -1.0;  // the last try left whose cut was looked for
  for (int halving = 0; halving < halvings; ++halving) {
    *trial = *x;
    for (int v = 0; v < n; ++v) trial->row(v) += alpha * dx.segment<3>(3 * v).transpose();
    const auto t0 = Clock::now();
    b.terms = problem.Evaluate(*trial, threads);
    report->evaluate_s += Seconds(t0);
    b.energy = b.terms.total();
    if (std::isfinite(b.energy) && b.energy <= energy) {
      b.accepted = true;
      break;
    }
    // An element the step flattens: halving, unless even the last try left would bring an
    // element below half the barrier's threshold volume (or half its own inside the zone);
    // then the cut to there (docs/theory/inversion.md#why-no-step-crosses-it). Cutting every
    // time left elements deep in the zone and slowed fine meshes' later solves
    // (docs/notes/2026-12-04-barrier-cut-only-where-halving-fails.md). While halving, the
    // last try stays the same, and so does its answer: checked once.
    const double half = 0.5 * alpha;
    alpha = half;
    const int left = halvings - halving - 1;
    if (!std::isfinite(b.energy) && left > 0) {
      const double last_try = std::ldexp(half, 1 - left);
      if (last_try != checked_last_try) {
        checked_last_try = last_try;
        const double upright =
            energy::UprightFraction(problem.SetsOf<energy::InversionBarrier>(), *x, dx, last_try);
        if (upright < last_try) alpha = upright;
      }
    }
  }
  if (!b.accepted) return b;
  b.alpha = alpha;
  for (int v = 0; v < n; ++v) b.largest_move = std::max(b.largest_move, dx.segment<3>(3 * v).norm());
  b.largest_move *= alpha;
  x->swap(*trial);
  return b;
}

SolveReport FastBackend::SolveAside(const energy::Problem& problem, double time_limit_s, Vertices* x) {
  Impl& m = *impl_;
  if (problem.equilibrium() == nullptr || !m.equilibrium || x->rows() != problem.num_vertices()) {
    return Solve(problem, time_limit_s, x);
  }
  if (m.options.num_threads <= 0) m.SetThreads(ResolveThreadCount(0));
  m.equilibrium->set_threads(m.threads);
  return m.equilibrium->SolveAside(problem, time_limit_s, x);
}

SolveReport FastBackend::Solve(const energy::Problem& problem, double time_limit_s, Vertices* x) {
  const auto start = Clock::now();
  Impl& m = *impl_;
  SolveReport report;
  if (x->rows() != problem.num_vertices()) {
    report.message = "fast back end: the problem has " + std::to_string(problem.num_vertices()) +
                     " vertices, x has " + std::to_string(x->rows());
    report.stop = StopReason::kFailure;
    return report;
  }
  if (m.options.num_threads <= 0) m.SetThreads(ResolveThreadCount(0));  // the caller's, per solve
  if (problem.equilibrium() != nullptr) {
    if (!m.equilibrium) m.equilibrium = std::make_unique<EquilibriumSolver>(m.options, m.threads);
    m.equilibrium->set_threads(m.threads);
    return m.equilibrium->Solve(problem, time_limit_s, x);
  }
  const ScopedThreads threads(m.threads);  // OpenMP here and the BLAS under CHOLMOD
  const int analyses_before = m.analyses;
  auto t0 = Clock::now();
  // Every block's slots; pairs outside the pattern widen it (and redo the analysis).
  report.pattern_rebuilds += m.assembler.Prepare(problem, *x);
  if (m.assembler.pattern_revision() != m.pattern_revision) m.PatternChanged();

  Eigen::VectorXd g, dx;
  m.positions = x;
  m.multigrid_failed = false;
  // The energy at the start from the assembly's linearization (an evaluation less per solve).
  m.assembler.AssembleGaussNewton(problem, *x, /*first=*/true, &g, &report.before);
  report.assemble_s += Seconds(t0);
  report.after = report.before;
  double energy = report.before.total();
  const double first_gradient = g.lpNorm<Eigen::Infinity>();
  report.success = true;
  report.stop = StopReason::kMaxIterations;
  Vertices trial;
  double first_alpha = 1.0;
  for (int step = 0; step < m.options.max_iterations; ++step) {
    const double gradient = g.lpNorm<Eigen::Infinity>();
    if (gradient == 0.0 || (step > 0 && gradient <= 1e-9 * first_gradient)) {
      report.stop = StopReason::kGradient;
      break;
    }
    // After the first step, a step that would gain less than kNegligibleGain of the
    // tolerance is not taken (see there): PCG's first iteration tells. Its gain is a lower
    // bound on the step's, looser by up to the preconditioner's condition number: ~1 with
    // a factor of a similar H, a few with a multigrid V-cycle, so that a step skipped there
    // would still gain less than the tolerance.
    const double negligible =
        step > 0 ? kNegligibleGain * m.options.relative_tolerance * energy : 0.0;
    const Impl::Outcome outcome = m.SolveStep(g, negligible, &dx, &report);
    if (outcome == Impl::Outcome::kNegligible) {
      report.stop = StopReason::kPredicted;
      break;
    }
    if (outcome == Impl::Outcome::kFailed) {
      report.success = false;
      report.stop = StopReason::kFailure;
      report.message = "fast back end: the system is not positive definite even with damping";
      break;
    }
    ++report.iterations;
    // Backtracking on the energy along the step.
    const Backtracked b = Backtrack(problem, dx, energy, 8, m.threads, &trial, x, &report);
    if (!b.accepted) {
      report.stop = StopReason::kNoDecrease;
      break;
    }
    const double largest = b.largest_move, alpha = b.alpha;
    if (report.iterations == 1) first_alpha = alpha;
    const double gain = energy - b.energy;
    const double decrease = gain / std::max(energy, 1e-300);
    energy = b.energy;
    report.after = b.terms;
    if (largest <= m.options.step_tolerance || largest == 0.0) {
      report.stop = StopReason::kStep;
      break;
    }
    if (decrease < m.options.relative_tolerance) {
      report.stop = StopReason::kEnergy;
      break;
    }
    // The full step lowered the energy by what the Gauss-Newton model said, to round-off
    // (kQuadraticAgreement): the energy is quadratic along it (held rotations and pairs,
    // robust weights in their quadratic part), and a next step on this model gains only what
    // PCG left, 1/2 r^T M^-1 r. Below the tolerance that step would end the loop (kEnergy)
    // after an assembly and a PCG solve; it is not taken. See kQuadraticAgreement.
    if (alpha == 1.0 && m.pcg_model_gain > 0.0 && !m.pcg_with_multigrid) {
      const double model_error = std::abs(gain - m.pcg_model_gain);
      const double limit = m.options.relative_tolerance * energy;
      if (model_error <= kQuadraticAgreement * m.pcg_model_gain &&
          model_error + m.ResidualGain(&report) < limit) {
        report.stop = StopReason::kPredicted;
        break;
      }
    }
    if (time_limit_s > 0 && Seconds(start) >= time_limit_s) {
      report.stop = StopReason::kTimeLimit;
      break;
    }
    if (step + 1 == m.options.max_iterations) break;
    t0 = Clock::now();
    m.assembler.AssembleGaussNewton(problem, *x, /*first=*/false, &g);
    report.assemble_s += Seconds(t0);
  }
  m.positions = nullptr;
  // Its one step refused, or cut (an element in the way) to less than the step tolerance: g
  // was assembled where the solve stopped, or a step shorter than that tolerance before.
  report.largest_force_before = first_gradient;
  if (report.iterations == 1 &&
      (report.stop == StopReason::kNoDecrease || (report.stop == StopReason::kStep && first_alpha < 1.0))) {
    report.mostly_refused = true;
    report.largest_force_after = g.lpNorm<Eigen::Infinity>();
  }
  if (report.success) report.message = std::string("fast back end: ") + ToString(report.stop);
  if (!x->allFinite()) {
    report.success = false;
    report.stop = StopReason::kFailure;
    report.message = "fast back end: the step made the positions non-finite";
  }
  report.analyses = m.analyses - analyses_before;
  return report;
}

}  // namespace fast_backend
}  // namespace femreg
