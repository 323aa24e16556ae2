// The fast back end's factor (FastBackend::Impl, fast_backend_internal.h): CHOLMOD's symbolic
// analysis of the pattern and the PCG budget from its counts, the fill estimate from the vertex
// graph (for the choice of preconditioner), and the factorizations, CHOLMOD's in double and the
// back end's own in single precision (solvers/fast/supernodal_solve.h). fast_backend.cc has the
// steps that use them.
#include <Eigen/CholmodSupport>
#include <Eigen/SparseCore>
#include <algorithm>
#include <cstdlib>
#include <vector>

#include "parallel/signals.h"
#include "parallel/threads.h"
#include "solvers/fast/fast_backend_internal.h"

namespace femreg {
namespace fast_backend {

namespace {

// CHOLMOD's supernodal factorization is faster than its simplicial one on these systems at
// every size measured, so it is always used (docs/notes/2026-11-28-figures-from-code-comments.md).

// Every factorization allocates and frees CHOLMOD's workspace: a permuted copy of H and the largest
// update matrix. Above glibc's mmap threshold (128 KiB until a larger mapped block has been freed)
// each is a fresh mapping, faulted in page by page on every factorization, which slowed
// factorizations markedly (docs/notes/2026-11-28-figures-from-code-comments.md). glibc raises the
// threshold when a mapped block of up to 32 MiB is freed (and then keeps up to twice that much
// freed heap before trimming): one block of the workspace's size, allocated and freed once per
// analysis, lets it do so. (Until this was written the same had happened by accident, through the
// triplets of the pattern's build.) Elsewhere than glibc: an allocation and a free, nothing more.
void PrimeAllocator(const cholmod_factor& L, const Eigen::SparseMatrix<double>& H) {
  const size_t copy = static_cast<size_t>(H.nonZeros()) * (sizeof(double) + sizeof(int)) +
                      static_cast<size_t>(H.cols() + 1) * sizeof(int);
  const size_t update = L.is_super ? L.maxcsize * sizeof(double) : 0;
  // glibc raises the threshold only for a freed mapping of at most 32 MiB, header included.
  const size_t bytes = std::min<size_t>(std::max(copy, update), (size_t{32} << 20) - (size_t{64} << 10));
  if (bytes == 0) return;
  void* block = std::malloc(bytes);
  if (block == nullptr) return;
  static_cast<volatile char*>(block)[0] = 0;  // not optimized away
  std::free(block);
}

// The fill-reducing ordering: AMD and METIS both, CHOLMOD keeps the one with the smaller
// nnz(L). Neither wins everywhere (AMD on slender beams, METIS on compact bodies), and
// CHOLMOD's default tries METIS only past a flops-per-entry threshold that compact bodies
// can miss (docs/notes/2026-11-28-figures-from-code-comments.md).
void OrderWithAmdAndMetis(cholmod_common* common) {
  common->nmethods = 2;
  common->method[0].ordering = CHOLMOD_AMD;
  common->method[1].ordering = CHOLMOD_METIS;
}

}  // namespace

void ConfigureAnalysis(cholmod_common* common) {
  OrderWithAmdAndMetis(common);
  // Relaxed amalgamation a little beyond CHOLMOD's defaults ({4, 16, 48} columns with {0.8, 0.1,
  // 0.05} of explicit zeros): with 3 unknowns per vertex, its first threshold merges little more
  // than one vertex, which leaves many small supernodes, each a BLAS call too small to run at
  // speed; larger settings slowed the substitutions
  // (docs/notes/2026-11-28-figures-from-code-comments.md).
  common->nrelax[0] = 6;
  common->nrelax[1] = 24;
  common->nrelax[2] = 64;
  common->zrelax[0] = 0.8;
  common->zrelax[1] = 0.15;
  common->zrelax[2] = 0.06;
}

void FastBackend::Impl::Analyse() {
  if (analysed) return;
  factor.setMode(Eigen::CholmodSupernodalLLt);
  cholmod_common& common = factor.cholmod();
  ConfigureAnalysis(&common);
  {
    const KeepSignalHandlers keep;  // METIS's signal() calls (parallel/signals.h)
    factor.analyzePattern(H);
  }
  analysed = true;
  ++analyses;
  // A PCG iteration: two triangular solves (2 x 2 nnz(L) flops) and a product with H
  // (2 nnz(H)); the factorization: CHOLMOD's count, at kSingleFactorizationSpeed times
  // the substitutions' rate.
  if (factor.raw() != nullptr) PrimeAllocator(*factor.raw(), H);
  fill = H.nonZeros() > 0 ? common.lnz / static_cast<double>(H.nonZeros()) : 0.0;
  factor_flops = common.fl;
  const double iteration_flops = 4.0 * common.lnz + 2.0 * static_cast<double>(H.nonZeros());
  pcg_budget_double = iteration_flops > 0 ? static_cast<int>(common.fl / iteration_flops) : 0;
  pcg_budget_single = iteration_flops > 0
                          ? static_cast<int>(common.fl / iteration_flops / kSingleFactorizationSpeed)
                          : 0;
  structure_pending = true;
}

double FastBackend::Impl::EstimateFill() const {
  // H's vertex graph (its 3x3 blocks are whole, their rows sorted: every third row of a
  // vertex's first column), its lower triangle, analysed with the same two orderings
  // without supernodes: nnz(L) of the vertex graph, each entry below the diagonal a 3x3
  // block of H's L and each diagonal one its lower triangle (6). Supernodal padding and the
  // orderings' ties make the analysis of H itself give a little more.
  const int vertices = static_cast<int>(H.cols()) / 3;
  if (vertices == 0 || H.nonZeros() == 0) return 0.0;
  const int* outer = H.outerIndexPtr();
  const int* inner = H.innerIndexPtr();
  std::vector<Eigen::Triplet<double>> entries;
  entries.reserve(static_cast<size_t>(H.nonZeros() / 18 + vertices));
  for (int v = 0; v < vertices; ++v) {
    for (int p = outer[3 * v]; p < outer[3 * v + 1]; p += 3) {
      const int w = inner[p] / 3;
      if (w >= v) entries.emplace_back(w, v, w == v ? 1.0 : 0.0);
    }
  }
  Eigen::SparseMatrix<double> graph(vertices, vertices);
  graph.setFromTriplets(entries.begin(), entries.end());
  CholmodFactor estimate;
  estimate.setMode(Eigen::CholmodSimplicialLLt);
  cholmod_common& common = estimate.cholmod();
  OrderWithAmdAndMetis(&common);
  {
    const KeepSignalHandlers keep;  // METIS's signal() calls (parallel/signals.h)
    estimate.analyzePattern(graph);
  }
  const double lnz = 9.0 * (common.lnz - vertices) + 6.0 * vertices;
  return lnz / static_cast<double>(H.nonZeros());
}

bool FastBackend::Impl::Factorize(SolveReport* report) {
  const auto t0 = Clock::now();
  Analyse();
  // On one thread, the BLAS under CHOLMOD as its own OpenMP teams (copies into the supernodes), as
  // the triangular solves in Pcg: the supernodes of these systems are too small to share, and both
  // on several threads fought over the cores (docs/notes/2026-11-28-figures-from-code-comments.md).
  {
    const ScopedThreads one_thread(1);
    WithThreadLimit(1, [&] { factor.factorize(H); });
  }
  pcg_since_factor = 0;
  factor_single = false;
  ++report->factorizations;
  report->factorize_s += Seconds(t0);
  factor_valid = factor.info() == Eigen::Success;
  // PCG's substitutions: the factor's values in single precision, on the back end's threads (half
  // the bytes to stream: solvers/fast/supernodal_solve.h)
  // (docs/notes/2026-11-28-figures-from-code-comments.md).
  if (factor_valid && substitutions.Load(*factor.raw(), structure_pending, threads)) {
    structure_pending = false;
  } else {
    substitutions = SupernodalSolve<float>();
  }
  // Substituted in float too: H's float factor already errs by H's condition number times
  // float's round-off, which the temporal masses and the data bound; the float work adds as much
  // (supernodal_solve.h). The equilibrium step's nearly singular K keeps double work.
  substitutions.set_single_work(true);
  return factor_valid;
}

bool FastBackend::Impl::FactorizeSingle(SolveReport* report) {
  const auto t0 = Clock::now();
  Analyse();
  pcg_since_factor = 0;
  factor_single = true;
  ++report->factorizations;
  // Its BLAS calls on one thread; its own team, of up to `threads` by its size.
  {
    const ScopedThreads one_thread(1);
    const int team = PhaseThreads(threads, static_cast<long long>(factor_flops),
                                  static_cast<long long>(kFactorizationFlopsPerThread));
    factor_valid = factor.raw() != nullptr &&
                   substitutions.Factorize(*factor.raw(), H, structure_pending, team);
    substitutions.set_threads(threads);  // the substitutions' groups as before
    substitutions.set_single_work(true);
  }
  if (factor_valid) structure_pending = false;
  report->factorize_s += Seconds(t0);
  return factor_valid;
}

}  // namespace fast_backend
}  // namespace femreg
