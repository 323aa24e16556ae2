// The fast back end: Gauss-Newton / Levenberg-Marquardt over a directly assembled sparse
// system, the robust losses by iterative reweighting. The energy layer's assembler
// (energy/assembler.h) scatters each block's gradient and Gauss-Newton blocks into a fixed
// sparsity pattern, which starts from the problem's coupling (the meshes' tetrahedra) and
// widens once for blocks that couple other vertices (contacts between objects), so CHOLMOD's
// symbolic analysis is reused across iterations and frames until the topology changes.
// Blocks whose Jacobian is constant and whose set has no robust loss (the elastic elements
// with their rotations held, springs) are assembled once per Solve.
#ifndef FEMREG_SOLVERS_FAST_FAST_BACKEND_H_
#define FEMREG_SOLVERS_FAST_FAST_BACKEND_H_

#include <Eigen/SparseCore>
#include <memory>
#include <vector>

#include "solvers/backend.h"

namespace femreg {
namespace fast_backend {

// Conjugate gradients stop at this relative residual |H dx + g| / |g|: an inexact Newton step whose
// error the next step removes; the line search and the stop criteria see the energy. The outer
// iterations (new rotations and pairs) converge only linearly, so a residual far below their rate
// is not seen in the result; looser was no better
// (docs/notes/2026-11-28-figures-from-code-comments.md).
inline constexpr double kPcgTolerance = 1e-2;

// Backtracking along dx from *x: alpha = 1, 1/2, ... (at most `halvings` tries; after an
// infinite energy, energy::UprightFraction's cut instead where even the last try left would
// bring an element below its target) until the problem's energy is finite and at most
// `energy`. Accepted: *x moved by alpha dx, and the energy there, its terms and the largest
// vertex move returned. `trial`: scratch, kept by the caller across steps. Both
// fast-back-end steps.
struct Backtracked {
  bool accepted = false;
  double alpha = 0.0, energy = 0.0, largest_move = 0.0;
  EnergyTerms terms;
};
Backtracked Backtrack(const energy::Problem& problem, const Eigen::VectorXd& dx, double energy, int halvings,
                      int threads, Vertices* trial, Vertices* x, SolveReport* report);

class FastBackend : public Backend {
 public:
  explicit FastBackend(const BackendOptions& options);
  ~FastBackend() override;
  SolverBackend type() const override { return SolverBackend::kFast; }
  SolveReport Solve(const energy::Problem& problem, double time_limit_s, Vertices* x) override;
  SolveReport SolveAside(const energy::Problem& problem, double time_limit_s, Vertices* x) override;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

// y = H p for a symmetric H stored column-major with both triangles and full 3x3 vertex
// blocks (the three columns of a vertex share their row pattern), the back end's system;
// in parallel on `threads` from `parallel_from` vertices on (below, PCG's product alone
// does not pay for a team's start). Equal to Eigen's H * p up to round-off, the same on
// any thread count. The blocks' rows come from `block_rows` (energy::BlockRowVertices of
// H's pattern, the assembler's block_rows()): H's per-entry row indices are not streamed.
void BlockProduct(const Eigen::SparseMatrix<double>& H, const std::vector<int>& block_rows,
                  const Eigen::VectorXd& p, int threads, Eigen::VectorXd* y,
                  int parallel_from = 8192);

// One vertex's three column sums in that layout, entry by entry: the column block's values
// start at v0 (its three columns `stride` apart), and at(q) the address of the vector's three
// entries for the column block's q-th 3x3 block's rows, each stored value read as value(v)
// (a narrower storage widened). (The product above in double; the multigrid V-cycle's in
// float from bfloat16, where its SSE lanes stop.)
template <class Value, class At, class Sum, class Widen>
void BlockColumnSums(const Value* v0, int stride, At at, Sum* s, Widen value) {
  const Value* v1 = v0 + stride;
  const Value* v2 = v1 + stride;
  Sum s0 = 0, s1 = 0, s2 = 0;
  for (int k = 0, q = 0; k < stride; k += 3, ++q) {
    const auto* pa = at(q);
    s0 += value(v0[k]) * pa[0] + value(v0[k + 1]) * pa[1] + value(v0[k + 2]) * pa[2];
    s1 += value(v1[k]) * pa[0] + value(v1[k + 1]) * pa[1] + value(v1[k + 2]) * pa[2];
    s2 += value(v2[k]) * pa[0] + value(v2[k + 1]) * pa[1] + value(v2[k + 2]) * pa[2];
  }
  s[0] = s0;
  s[1] = s1;
  s[2] = s2;
}
template <class Value, class Sum, class At>
void BlockColumnSums(const Value* v0, int stride, At at, Sum* s) {
  BlockColumnSums(v0, stride, at, s, [](Value value) { return value; });
}

}  // namespace fast_backend
}  // namespace femreg

#endif  // FEMREG_SOLVERS_FAST_FAST_BACKEND_H_
