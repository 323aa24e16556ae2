// Solves with a CHOLMOD supernodal LL^T factor in the fast back end's own code, for PCG's
// preconditioner (one forward and one backward substitution per iteration).
//
// Those substitutions read all of L once each and do two flops per entry: their time is the time to
// stream L from memory (docs/notes/2026-11-28-figures-from-code-comments.md). So the values are
// kept in `Scalar`, float in the back end: half the bytes. By default the vectors and every sum
// stay in double; what changes is L itself, by a relative 6e-8 per entry, far less than the
// difference between the kept factor and the matrix PCG solves (a factor of an earlier step's
// matrix), which PCG corrects anyway. With set_single_work they are in float too (the classic
// step's PCG), where a cache-resident L made the conversions, not the memory, the limit.
//
// In parallel: the supernodal elimination tree is cut into disjoint subtrees, grouped into
// kGroups sets, and a "top" of the supernodes above them. The cut depends on L alone (not
// on the thread count; none below cut_from entries): a team of up to kGroups threads runs
// the groups, one thread runs the same steps one after the other. The forward substitution
// runs the groups in parallel, each adding its updates of the top's rows into a vector of
// its own, then the top on one thread; the backward substitution runs the top first, then
// the groups in parallel (a supernode reads only its ancestors). No two threads write one
// entry, and the order of every sum is fixed by the cut, so every thread count gives the same
// result, bit for bit.
//
// The values either come from a CHOLMOD factor (Load) or are computed here (Factorize): a
// left-looking supernodal Cholesky factorization in `Scalar` on CHOLMOD's symbolic analysis
// (the supernodes, their rows, the ordering), the subtrees of the same cut in parallel,
// then the top. The top holds the largest supernodes (on a 1k-vertex box two thirds of a
// factorization's time on 2 threads, when it ran on one): those of many rows are factorized
// in tiles, the tiles of each step on the whole team (TiledTask). Each supernode adds its
// descendants' updates in ascending order of the descendant, and a tiled one's tiles depend
// on its size alone, so every thread count gives the same factor (one thread runs the tiles
// one after the other). In float the dense
// kernels (the BLAS) do twice the flops per second, and the matrix goes into the factor
// through a map made once per analysis, where CHOLMOD permutes and transposes it again at
// every factorization.
#ifndef FEMREG_SOLVERS_FAST_SUPERNODAL_SOLVE_H_
#define FEMREG_SOLVERS_FAST_SUPERNODAL_SOLVE_H_

#include <cholmod.h>

#include <Eigen/CholmodSupport>
#include <Eigen/Core>
#include <Eigen/SparseCore>
#include <algorithm>
#include <cstdint>
#include <vector>

namespace femreg {
namespace fast_backend {

// CHOLMOD's decomposition (through Eigen) with its factor in reach: the structure (and, once
// factorized, the values) that SupernodalSolve takes.
struct CholmodFactor : Eigen::CholmodDecomposition<Eigen::SparseMatrix<double>, Eigen::Lower> {
  const cholmod_factor* raw() const { return m_cholmodFactor; }
};

template <class Scalar>
class SupernodalSolve {
 public:
  // Takes L's structure (again only when its symbolic analysis changed: `new_structure`)
  // and copies its values. False, and nothing kept, unless L is a supernodal LL^T factor
  // with int indices and real double values.
  bool Load(const cholmod_factor& L, bool new_structure, int threads);
  // Factorizes A = P^T L L^T P here, in Scalar, with the structure and the ordering of L (a
  // supernodal factor of A's pattern from CHOLMOD's analysis, symbolic or numeric; taken
  // again only when `new_structure`). A: both triangles, the pattern that was analysed.
  // False, and nothing kept, when a pivot is not positive and finite in Scalar (A is not
  // numerically positive definite at that precision) or L is not a supernodal LL^T
  // structure with int indices. The BLAS must run on one thread here (the caller's
  // ScopedThreads): the threads are this function's own.
  bool Factorize(const cholmod_factor& L, const Eigen::SparseMatrix<double>& A, bool new_structure,
                 int threads);
  // The same for a symmetric A that need not be positive definite: A = P^T L S L^T P with S
  // a diagonal of signs and L = L' |D|^(1/2) for A's L' D L'^T, without pivoting (the
  // ordering's). A supernode whose diagonal block is positive definite is factorized as
  // Factorize does (LAPACK's Cholesky; its pivots as they are), the others by panels: there a
  // pivot |D_jj| below a relative 1e-8 (float) or 1e-12 (double) of A's largest diagonal
  // entry is round-off at that precision (a free body's rigid motions, which the callers
  // project out): it is replaced by that floor, and counted. False, and
  // nothing kept, when a value is not finite. Solve then applies S between its
  // substitutions. The groups of the tree's cut on up to `threads` threads, the top on one
  // (no tiles): the same factor on any thread count. The BLAS on one thread, as in Factorize.
  bool FactorizeIndefinite(const cholmod_factor& L, const Eigen::SparseMatrix<double>& A,
                           bool new_structure, int threads);
  // The negative pivots of the last FactorizeIndefinite, and those replaced by the floor
  // (0 after Factorize or Load).
  int negative_pivots() const { return negative_pivots_; }
  int perturbed_pivots() const { return perturbed_pivots_; }
  bool loaded() const { return loaded_; }
  // The threads of the next Solve (Load and Factorize set them too); any count, the same result.
  void set_threads(int threads) { threads_ = std::max(1, threads); }
  // The rows of a tile in Factorize (tests: small tiles on small matrices). Takes effect at
  // the next Factorize.
  void set_tile_rows(int rows) { tile_rows_ = std::max(1, rows); }
  // L's entries from which the tree is cut (tests: small matrices cut). Takes effect when the
  // structure is taken again.
  void set_cut_from(int64_t entries) { cut_from_ = entries; }
  // The supernodes Factorize takes in tiles: the top's large ones (with the structure taken).
  int tiled_supernodes() const;
  // x = A^-1 b for the factorized A = P^T L L^T P. x may not alias b.
  void Solve(const Eigen::VectorXd& b, Eigen::VectorXd* x);
  // Solve's substitutions in the factor's own precision instead of double (a float factor):
  // half the bytes to stream and nothing to convert, with float's round-off in x on top of
  // the factor's. For a preconditioner of a well-conditioned matrix; a nearly singular one (a
  // free body's rigid modes under a small shift) amplifies that round-off, and PCG with it
  // takes more iterations or stalls, so the default is double.
  void set_single_work(bool on) { single_work_ = on; }
  // The share of L's entries solved on one thread while the others wait: the top (1 when the
  // tree is not cut). The same on any thread count.
  double serial_fraction() const { return serial_fraction_; }
  // L's values, supernode by supernode (CHOLMOD's layout).
  const std::vector<Scalar>& values() const { return values_; }

 private:
  // Takes L's structure and cuts the tree; false if L is not supernodal LL^T with int indices.
  bool TakeStructure(const cholmod_factor& L);
  // Factorize's and FactorizeIndefinite's start: the structure (again when new or changed)
  // and the plan for A's pattern; false if either cannot be had.
  bool Prepare(const cholmod_factor& L, const Eigen::SparseMatrix<double>& A, bool new_structure);
  // For Factorize, once per structure and pattern of A: which descendants update each
  // supernode (and with which of their rows), where A's entries go.
  bool PrepareFactorization(const Eigen::SparseMatrix<double>& A);
  // Supernode s of the factorization: A's entries, its descendants' updates, its dense
  // factorization, on group g's work vectors (map, c, signed_) and pivot counts (0: the
  // top's). False: a pivot not positive.
  bool FactorizeSupernode(int s, int g, const double* a);
  // Supernode s's dense part as L S L^T (FactorizeIndefinite), after its updates: LAPACK's
  // Cholesky of the diagonal block where it is positive definite, else the block right-looking
  // by panels (each panel's columns one by one, the block's columns right of it by a
  // product); then the rows below by a triangular solve and the signs.
  bool FactorizeIndefiniteBlock(int s, int g);
  // Supernode s's values: zeros, then A's entries; map[row] = the row's place in s.
  void Gather(int s, const double* a, int* map);
  // Subtracts the descendants' updates of s's rows [t0, t1) (whole: all of them), in
  // ascending descendant. c: the largest update.
  // signed_columns: a buffer for L S L^T's signed columns (unused by a Cholesky factorization).
  void SubtractUpdates(int s, int t0, int t1, bool whole, const int* map, Scalar* c,
                       std::vector<Scalar>* signed_columns);
  // A supernode of the top with at least two tiles' rows (tile_rows_) is factorized in tiles: its
  // updates a row tile at a time, its dense part by panels of as many columns (right-looking: the
  // panel's diagonal block, the rows below it, the columns right of it). The tasks of a phase are
  // independent and run on the whole team; the tiles depend on the supernode's size alone. Phases
  // and tasks: TiledTasks (supernodal_factorize.cc). In the subtrees, on one thread each, the whole
  // supernode's BLAS calls are faster (docs/notes/2026-11-28-figures-from-code-comments.md).
  bool Tiled(int s) const;
  int TileRows(int s) const;  // a multiple of tile_rows_: at most kMaxTiles row tiles
  int TiledPhases(int s) const;
  int TiledTasks(int s, int phase) const;
  bool TiledTask(int s, int phase, int task, const double* a, int* map, Scalar* c);
  // Work vectors of the substitutions, in double or (set_single_work) in the factor's
  // precision: the permuted right-hand side and solution, per group an accumulator of forward
  // updates (n) and a supernode's buffer (its rows).
  template <class Work>
  struct Workspace {
    typedef Eigen::Matrix<Work, Eigen::Dynamic, 1> Vector;
    Vector b, y;
    std::vector<Vector> acc, z;
    void Size(size_t groups, int n, int max_rows) {
      acc.assign(groups, Vector::Zero(n));
      z.assign(groups, Vector::Zero(max_rows));
      b.resize(n);
      y.resize(n);
    }
  };
  template <class Work>
  void Forward(int s, const Work* b, Work* acc, Work* y, Work* z) const;
  template <class Work>
  void Backward(int s, Work* y, Work* z) const;
  // Solve's top, after the groups' forward substitutions (y: the permuted solution so far).
  template <class Work>
  void SolveTop(int num_groups, Workspace<Work>* w);
  template <class Work>
  void SolveIn(const Eigen::VectorXd& b, Eigen::VectorXd* x, Workspace<Work>* w);

  // Tiles of 64 rows, and at most 8 tiles per supernode: the best of the sizes tried on box
  // meshes (bench/linear_solver_bench.cc) (docs/notes/2026-11-28-figures-from-code-comments.md).
  static constexpr int kMaxTiles = 8;
  // The groups of the cut, for teams of up to as many threads.
  static constexpr int kGroups = 4;
  // Below this many entries of L the tree is not cut: a team's start and barriers cost more
  // than the substitutions (docs/notes/2026-11-29-threads.md).
  static constexpr int64_t kCutFrom = 100000;
  bool loaded_ = false;
  int tile_rows_ = 64;
  int64_t cut_from_ = kCutFrom;
  int n_ = 0;
  int threads_ = 1;
  std::vector<int> super_, pi_, rows_, perm_;
  std::vector<int> super_of_;  // column -> its supernode
  std::vector<int64_t> px_;
  std::vector<Scalar> values_;
  // FactorizeIndefinite's S (per column of L, +1 or -1; empty after Factorize or Load), per
  // supernode whether any of its columns is -1, per group a buffer (signed columns, a diagonal
  // block's diagonal) and its counts of negative and floored pivots, and the floor of a pivot |D_jj|.
  std::vector<Scalar> sign_;
  std::vector<char> negative_;
  std::vector<std::vector<Scalar>> signed_;
  int64_t max_signed_ = 0;  // that buffer's largest use (PrepareFactorization)
  std::vector<int> group_negative_, group_perturbed_;
  int negative_pivots_ = 0, perturbed_pivots_ = 0;
  double pivot_floor_ = 0.0;
  // The factorization's plan (PrepareFactorization): per supernode s, its updates
  // [update_start_[s], update_start_[s + 1]) as (descendant, first row, end row) within the
  // descendant's rows; A's entries [a_start_[s], a_start_[s + 1]) as (index in A's values,
  // index in values_).
  bool prepared_ = false;
  std::vector<int> prepared_outer_, prepared_inner_;  // A's pattern the plan was made for
  std::vector<int> update_start_, update_d_, update_r1_, update_r2_;
  std::vector<int64_t> a_start_, a_src_, a_dst_;
  int64_t max_update_ = 0;
  // FactorizeIndefiniteBlock's panel width.
  static constexpr int kIndefinitePanel = 32;
  std::vector<std::vector<int>> map_;
  std::vector<std::vector<Scalar>> c_;
  // Per group, its supernodes in ascending order (children before parents); the top.
  std::vector<std::vector<int>> groups_;
  std::vector<int> top_;
  double serial_fraction_ = 0.0;
  int max_rows_ = 0;  // a supernode's most rows
  bool single_work_ = false;
  Workspace<double> work_;
  Workspace<Scalar> single_;  // sized at the first Solve that uses it
};

extern template class SupernodalSolve<float>;
extern template class SupernodalSolve<double>;

}  // namespace fast_backend
}  // namespace femreg

#endif  // FEMREG_SOLVERS_FAST_SUPERNODAL_SOLVE_H_
