#include "solvers/fast/supernodal_solve.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <numeric>
#include <type_traits>

#include "parallel/threads.h"

// The BLAS and LAPACK (Fortran interface, as CHOLMOD calls them).
extern "C" {
void spotrf_(const char* uplo, const int* n, float* a, const int* lda, int* info);
void dpotrf_(const char* uplo, const int* n, double* a, const int* lda, int* info);
void strsm_(const char* side, const char* uplo, const char* transa, const char* diag, const int* m,
            const int* n, const float* alpha, const float* a, const int* lda, float* b, const int* ldb);
void dtrsm_(const char* side, const char* uplo, const char* transa, const char* diag, const int* m,
            const int* n, const double* alpha, const double* a, const int* lda, double* b, const int* ldb);
void ssyrk_(const char* uplo, const char* trans, const int* n, const int* k, const float* alpha,
            const float* a, const int* lda, const float* beta, float* c, const int* ldc);
void dsyrk_(const char* uplo, const char* trans, const int* n, const int* k, const double* alpha,
            const double* a, const int* lda, const double* beta, double* c, const int* ldc);
void sgemm_(const char* transa, const char* transb, const int* m, const int* n, const int* k,
            const float* alpha, const float* a, const int* lda, const float* b, const int* ldb,
            const float* beta, float* c, const int* ldc);
void dgemm_(const char* transa, const char* transb, const int* m, const int* n, const int* k,
            const double* alpha, const double* a, const int* lda, const double* b, const int* ldb,
            const double* beta, double* c, const int* ldc);
}

namespace femreg {
namespace fast_backend {

namespace {

inline int Potrf(int n, float* a, int lda) {
  int info = 0;
  spotrf_("L", &n, a, &lda, &info);
  return info;
}
inline int Potrf(int n, double* a, int lda) {
  int info = 0;
  dpotrf_("L", &n, a, &lda, &info);
  return info;
}
// b (m x n) = b L^-T, L the n x n lower triangle of a.
template <class T>
inline void TrsmRightLowerTransposed(int m, int n, const T* a, int lda, T* b, int ldb) {
  const T one = 1;
  if constexpr (std::is_same_v<T, float>) {
    strsm_("R", "L", "T", "N", &m, &n, &one, a, &lda, b, &ldb);
  } else {
    dtrsm_("R", "L", "T", "N", &m, &n, &one, a, &lda, b, &ldb);
  }
}
// c (lower n x n) = a a^T, a n x k.
template <class T>
inline void SyrkLower(int n, int k, const T* a, int lda, T* c, int ldc) {
  const T one = 1, zero = 0;
  if constexpr (std::is_same_v<T, float>) {
    ssyrk_("L", "N", &n, &k, &one, a, &lda, &zero, c, &ldc);
  } else {
    dsyrk_("L", "N", &n, &k, &one, a, &lda, &zero, c, &ldc);
  }
}
// c (m x n) = a b^T, a m x k, b n x k.
template <class T>
inline void GemmNT(int m, int n, int k, const T* a, int lda, const T* b, int ldb, T* c, int ldc) {
  const T one = 1, zero = 0;
  if constexpr (std::is_same_v<T, float>) {
    sgemm_("N", "T", &m, &n, &k, &one, a, &lda, b, &ldb, &zero, c, &ldc);
  } else {
    dgemm_("N", "T", &m, &n, &k, &one, a, &lda, b, &ldb, &zero, c, &ldc);
  }
}

// c (m x n) -= a b^T, a m x k, b n x k.
template <class T>
inline void GemmNTSubtract(int m, int n, int k, const T* a, int lda, const T* b, int ldb, T* c, int ldc) {
  const T minus_one = -1, one = 1;
  if constexpr (std::is_same_v<T, float>) {
    sgemm_("N", "T", &m, &n, &k, &minus_one, a, &lda, b, &ldb, &one, c, &ldc);
  } else {
    dgemm_("N", "T", &m, &n, &k, &minus_one, a, &lda, b, &ldb, &one, c, &ldc);
  }
}

// Cuts the supernodal elimination tree for `threads` groups: subtrees grouped into one
// set per group (owner[s] = its group) and the rest, the top (owner -1), which runs after
// them: on one thread in the substitutions, and in the factorization its large supernodes
// in tiles on the whole team, the others on one thread. (The cost below still counts the
// top as serial, as it is for the substitutions the cut is made for.) Starting from the roots, the heaviest subtree is split (its root goes to the top,
// its children become subtrees) while that lowers the cost top + largest group; the groups
// are filled heaviest subtree first into the lightest group. Empty: no cut beats one thread.
std::vector<int> CutTree(const std::vector<int>& parent, const std::vector<double>& work,
                         int threads) {
  const int nsuper = static_cast<int>(parent.size());
  std::vector<double> subtree(work);
  std::vector<std::vector<int>> children(static_cast<size_t>(nsuper));
  std::vector<int> candidates;
  for (int s = 0; s < nsuper; ++s) {  // a parent comes after its children
    if (parent[s] >= 0) {
      subtree[static_cast<size_t>(parent[s])] += subtree[static_cast<size_t>(s)];
      children[static_cast<size_t>(parent[s])].push_back(s);
    } else {
      candidates.push_back(s);
    }
  }
  const double total = std::accumulate(work.begin(), work.end(), 0.0);
  std::vector<int> top, best_top, best_candidates;
  std::vector<int> best_bin_of;
  double top_work = 0.0, best_cost = total;  // everything on one thread
  auto by_weight = [&](int a, int b) {
    return subtree[static_cast<size_t>(a)] > subtree[static_cast<size_t>(b)] ||
           (subtree[static_cast<size_t>(a)] == subtree[static_cast<size_t>(b)] && a < b);
  };
  for (int round = 0; round < nsuper && !candidates.empty(); ++round) {
    std::sort(candidates.begin(), candidates.end(), by_weight);
    std::vector<double> bins(static_cast<size_t>(threads), 0.0);
    std::vector<int> bin_of(candidates.size());
    for (size_t k = 0; k < candidates.size(); ++k) {
      const size_t lightest = static_cast<size_t>(std::min_element(bins.begin(), bins.end()) - bins.begin());
      bins[lightest] += subtree[static_cast<size_t>(candidates[k])];
      bin_of[k] = static_cast<int>(lightest);
    }
    const double cost = top_work + *std::max_element(bins.begin(), bins.end());
    if (cost < best_cost) {
      best_cost = cost;
      best_top = top;
      best_candidates = candidates;
      best_bin_of = bin_of;
    }
    // Split the heaviest subtree, unless it is a leaf or already small, or the top alone
    // already costs as much as the best cut (it only grows).
    const int heaviest = candidates.front();
    if (children[static_cast<size_t>(heaviest)].empty() || top_work + work[static_cast<size_t>(heaviest)] >= best_cost ||
        subtree[static_cast<size_t>(heaviest)] < 0.25 * total / threads) {
      break;
    }
    candidates.erase(candidates.begin());
    top.push_back(heaviest);
    top_work += work[static_cast<size_t>(heaviest)];
    for (int c : children[static_cast<size_t>(heaviest)]) candidates.push_back(c);
  }
  if (best_candidates.empty()) return {};  // no cut does better than one thread
  std::vector<int> owner(static_cast<size_t>(nsuper), -2);
  for (int s : best_top) owner[static_cast<size_t>(s)] = -1;
  for (size_t k = 0; k < best_candidates.size(); ++k) {
    owner[static_cast<size_t>(best_candidates[k])] = best_bin_of[k];
  }
  for (int s = nsuper - 1; s >= 0; --s) {  // below a subtree's root: its owner
    if (owner[static_cast<size_t>(s)] == -2) owner[static_cast<size_t>(s)] = owner[static_cast<size_t>(parent[s])];
  }
  return owner;
}

}  // namespace

template <class Scalar>
bool SupernodalSolve<Scalar>::TakeStructure(const cholmod_factor& L) {
  // (CHOLMOD's supernodal factors are always LL^T; a symbolic one need not say so yet.)
  if (!L.is_super || L.itype != CHOLMOD_INT || L.super == nullptr || L.pi == nullptr ||
      L.px == nullptr || L.s == nullptr) {
    return false;
  }
  prepared_ = false;
  n_ = static_cast<int>(L.n);
  const int nsuper = static_cast<int>(L.nsuper);
  const int* super = static_cast<const int*>(L.super);
  const int* pi = static_cast<const int*>(L.pi);
  const int* px = static_cast<const int*>(L.px);
  const int* s = static_cast<const int*>(L.s);
  const int* perm = static_cast<const int*>(L.Perm);
  super_.assign(super, super + nsuper + 1);
  pi_.assign(pi, pi + nsuper + 1);
  px_.assign(px, px + nsuper + 1);
  rows_.assign(s, s + L.ssize);
  if (perm != nullptr) {
    perm_.assign(perm, perm + n_);
  } else {
    perm_.resize(static_cast<size_t>(n_));
    std::iota(perm_.begin(), perm_.end(), 0);
  }
  // The supernodal tree: a supernode's parent holds the first row below its diagonal
  // block. Work: the supernode's entries.
  super_of_.assign(static_cast<size_t>(n_), 0);
  for (int k = 0; k < nsuper; ++k) {
    for (int c = super[k]; c < super[k + 1]; ++c) super_of_[static_cast<size_t>(c)] = k;
  }
  std::vector<int> parent(static_cast<size_t>(nsuper), -1);
  std::vector<double> work(static_cast<size_t>(nsuper));
  double total = 0.0;
  for (int k = 0; k < nsuper; ++k) {
    const int ncol = super[k + 1] - super[k], nrow = pi[k + 1] - pi[k];
    if (nrow > ncol) parent[static_cast<size_t>(k)] = super_of_[static_cast<size_t>(s[pi[k] + ncol])];
    work[static_cast<size_t>(k)] = static_cast<double>(nrow) * ncol - 0.5 * ncol * (ncol - 1);
    total += work[static_cast<size_t>(k)];
  }
  groups_.assign(1, {});
  top_.clear();
  serial_fraction_ = 0.0;
  // The cut depends on L alone, never on the thread count: the same sums in the same order on
  // any number of threads (docs/notes/2026-11-29-threads.md).
  const std::vector<int> owner =
      total < static_cast<double>(cut_from_) ? std::vector<int>() : CutTree(parent, work, kGroups);
  if (owner.empty()) {  // too small to share, or no cut worth a team: the serial order
    groups_[0].resize(static_cast<size_t>(nsuper));
    std::iota(groups_[0].begin(), groups_[0].end(), 0);
    serial_fraction_ = 1.0;
  } else {
    groups_.assign(static_cast<size_t>(kGroups), {});
    for (int k = 0; k < nsuper; ++k) {
      const int o = owner[static_cast<size_t>(k)];
      if (o < 0) {
        top_.push_back(k);
        serial_fraction_ += work[static_cast<size_t>(k)] / std::max(total, 1.0);
      } else {
        groups_[static_cast<size_t>(o)].push_back(k);
      }
    }
  }
  int max_rows = 0;
  for (int k = 0; k < nsuper; ++k) max_rows = std::max(max_rows, pi[k + 1] - pi[k]);
  acc_.assign(groups_.size(), Eigen::VectorXd::Zero(n_));
  z_.assign(groups_.size(), Eigen::VectorXd::Zero(max_rows));
  b_.resize(n_);
  y_.resize(n_);
  return true;
}

template <class Scalar>
bool SupernodalSolve<Scalar>::Load(const cholmod_factor& L, bool new_structure, int threads) {
  if (!L.is_super || !L.is_ll || L.itype != CHOLMOD_INT || L.xtype != CHOLMOD_REAL ||
      L.dtype != CHOLMOD_DOUBLE || L.x == nullptr || L.minor != L.n) {
    loaded_ = false;
    return false;
  }
  threads_ = std::max(1, threads);
  if (new_structure || !loaded_ || n_ != static_cast<int>(L.n) || super_.size() != L.nsuper + 1 ||
      values_.size() != L.xsize) {
    loaded_ = false;  // until the structure is whole again
    if (!TakeStructure(L)) return false;
  }
  const double* x = static_cast<const double*>(L.x);
  values_.resize(L.xsize);
  for (size_t k = 0; k < L.xsize; ++k) values_[k] = static_cast<Scalar>(x[k]);
  loaded_ = true;
  return true;
}

template <class Scalar>
bool SupernodalSolve<Scalar>::PrepareFactorization(const Eigen::SparseMatrix<double>& A) {
  prepared_ = false;
  if (A.rows() != n_ || A.cols() != n_ || !A.isCompressed()) return false;
  const int nsuper = static_cast<int>(super_.size()) - 1;
  // The updates: descendant d updates, with its rows [r1, r2) (below its diagonal block),
  // the supernode that holds row r1 and with the rows [r1, end) the entries below. Listed
  // by target, in ascending d.
  std::vector<std::vector<std::array<int, 3>>> by_target(static_cast<size_t>(nsuper));
  max_update_ = 0;
  for (int d = 0; d < nsuper; ++d) {
    const int ncol = super_[d + 1] - super_[d];
    const int nrow = pi_[d + 1] - pi_[d];
    const int* rows = rows_.data() + pi_[d];
    int r = ncol;
    while (r < nrow) {
      const int t = super_of_[static_cast<size_t>(rows[r])];
      if (t <= d) return false;  // not a supernodal structure
      int r2 = r;
      while (r2 < nrow && rows[r2] < super_[t + 1]) ++r2;
      by_target[static_cast<size_t>(t)].push_back({d, r, r2});
      max_update_ = std::max<int64_t>(max_update_, static_cast<int64_t>(nrow - r) * (r2 - r));
      r = r2;
    }
  }
  update_start_.assign(1, 0);
  update_d_.clear();
  update_r1_.clear();
  update_r2_.clear();
  for (int t = 0; t < nsuper; ++t) {
    for (const auto& u : by_target[static_cast<size_t>(t)]) {
      update_d_.push_back(u[0]);
      update_r1_.push_back(u[1]);
      update_r2_.push_back(u[2]);
    }
    update_start_.push_back(static_cast<int>(update_d_.size()));
  }
  // A's entries on or below the permuted diagonal, by supernode, and where each goes.
  std::vector<int> inverse(static_cast<size_t>(n_));
  for (int k = 0; k < n_; ++k) inverse[static_cast<size_t>(perm_[static_cast<size_t>(k)])] = k;
  std::vector<int> position(static_cast<size_t>(n_), -1);
  const int* outer = A.outerIndexPtr();
  const int* inner = A.innerIndexPtr();
  a_start_.assign(1, 0);
  a_src_.clear();
  a_dst_.clear();
  for (int k = 0; k < nsuper; ++k) {
    const int k1 = super_[k], ncol = super_[k + 1] - k1, nrow = pi_[k + 1] - pi_[k];
    const int* rows = rows_.data() + pi_[k];
    for (int i = 0; i < nrow; ++i) position[static_cast<size_t>(rows[i])] = i;
    for (int j = 0; j < ncol; ++j) {
      const int column = perm_[static_cast<size_t>(k1 + j)];
      for (int p = outer[column]; p < outer[column + 1]; ++p) {
        const int row = inverse[static_cast<size_t>(inner[p])];
        if (row < k1 + j) continue;  // the upper triangle
        const int i = position[static_cast<size_t>(row)];
        if (i < 0 || rows[i] != row) return false;  // not in L's pattern: another matrix
        a_src_.push_back(p);
        a_dst_.push_back(px_[k] + static_cast<int64_t>(j) * nrow + i);
      }
    }
    for (int i = 0; i < nrow; ++i) position[static_cast<size_t>(rows[i])] = -1;
    a_start_.push_back(static_cast<int64_t>(a_src_.size()));
  }
  map_.assign(groups_.size(), std::vector<int>(static_cast<size_t>(n_), 0));
  c_.assign(groups_.size(), std::vector<Scalar>(static_cast<size_t>(max_update_)));
  prepared_outer_.assign(A.outerIndexPtr(), A.outerIndexPtr() + A.cols() + 1);
  prepared_inner_.assign(A.innerIndexPtr(), A.innerIndexPtr() + A.nonZeros());
  prepared_ = true;
  return true;
}

// Below this many multiply-adds an update is formed by plain loops: a BLAS call costs more.
constexpr int64_t kBlasUpdate = 4096;

template <class Scalar>
void SupernodalSolve<Scalar>::Gather(int s, const double* a, int* map) {
  const int ncol = super_[s + 1] - super_[s], nrow = pi_[s + 1] - pi_[s];
  const int* rows = rows_.data() + pi_[s];
  Scalar* L = values_.data() + px_[s];
  std::fill(L, L + static_cast<int64_t>(nrow) * ncol, Scalar(0));
  for (int64_t e = a_start_[s]; e < a_start_[s + 1]; ++e) {
    values_[static_cast<size_t>(a_dst_[static_cast<size_t>(e)])] =
        static_cast<Scalar>(a[a_src_[static_cast<size_t>(e)]]);
  }
  for (int i = 0; i < nrow; ++i) map[rows[i]] = i;
}

template <class Scalar>
void SupernodalSolve<Scalar>::SubtractUpdates(int s, int t0, int t1, bool whole, const int* map,
                                              Scalar* c) {
  const int k1 = super_[s], nrow = pi_[s + 1] - pi_[s];
  Scalar* L = values_.data() + px_[s];
  for (int u = update_start_[s]; u < update_start_[s + 1]; ++u) {
    const int d = update_d_[static_cast<size_t>(u)];
    const int r1 = update_r1_[static_cast<size_t>(u)], r2 = update_r2_[static_cast<size_t>(u)];
    const int dcol = super_[d + 1] - super_[d], drow = pi_[d + 1] - pi_[d];
    const int* drows = rows_.data() + pi_[d] + r1;
    const Scalar* D = values_.data() + px_[d] + r1;  // rows r1.. of d, drow apart
    const int m = drow - r1, n = r2 - r1;  // the update: m x n, lower part
    // Its rows [ilo, ihi) land in [t0, t1) (its rows ascend, so do their places).
    int ilo = 0, ihi = m;
    if (!whole) {
      ilo = static_cast<int>(
          std::partition_point(drows, drows + m, [&](int row) { return map[row] < t0; }) - drows);
      ihi = static_cast<int>(
          std::partition_point(drows + ilo, drows + m, [&](int row) { return map[row] < t1; }) - drows);
    }
    if (ilo >= ihi) continue;
    const int jn = std::min(n, ihi);  // columns j <= i
    if (static_cast<int64_t>(m) * n * dcol < kBlasUpdate) {
      for (int j = 0; j < jn; ++j) {
        Scalar* target = L + static_cast<int64_t>(drows[j] - k1) * nrow;
        const int i0 = std::max(j, ilo);
        for (int i = i0; i < ihi; ++i) c[i] = 0;
        for (int k = 0; k < dcol; ++k) {
          const Scalar* column = D + static_cast<int64_t>(k) * drow;
          const Scalar djk = column[j];
          for (int i = i0; i < ihi; ++i) c[i] += column[i] * djk;
        }
        for (int i = i0; i < ihi; ++i) target[map[drows[i]]] -= c[i];
      }
      continue;
    }
    // c: (ihi - ilo) x jn, row i - ilo, column j. The whole update: its diagonal part as a
    // rank update and the rows below as a product; a tile's rows: one product (also above
    // the diagonal: a rank update of the tile's part cost more than it saved).
    const int mt = ihi - ilo;
    if (whole) {
      SyrkLower(n, dcol, D, drow, c, m);
      if (m > n) GemmNT(m - n, n, dcol, D + n, drow, D, drow, c + n, m);
    } else {
      GemmNT(mt, jn, dcol, D + ilo, drow, D, drow, c, mt);
    }
    for (int j = 0; j < jn; ++j) {
      Scalar* target = L + static_cast<int64_t>(drows[j] - k1) * nrow;
      const Scalar* cj = c + static_cast<int64_t>(j) * mt;
      for (int i = std::max(j, ilo); i < ihi; ++i) target[map[drows[i]]] -= cj[i - ilo];
    }
  }
}

template <class Scalar>
bool SupernodalSolve<Scalar>::FactorizeSupernode(int s, const double* a, int* map, Scalar* c) {
  const int ncol = super_[s + 1] - super_[s], nrow = pi_[s + 1] - pi_[s];
  Scalar* L = values_.data() + px_[s];
  Gather(s, a, map);
  SubtractUpdates(s, 0, nrow, /*whole=*/true, map, c);
  if (Potrf(ncol, L, nrow) != 0) return false;
  for (int j = 0; j < ncol; ++j) {
    const Scalar pivot = L[static_cast<int64_t>(j) * nrow + j];
    if (!(pivot > 0) || !std::isfinite(static_cast<double>(pivot))) return false;
  }
  if (nrow > ncol) TrsmRightLowerTransposed(nrow - ncol, ncol, L, nrow, L + ncol, nrow);
  return true;
}

template <class Scalar>
bool SupernodalSolve<Scalar>::Tiled(int s) const {
  return pi_[s + 1] - pi_[s] >= 2 * tile_rows_;
}

template <class Scalar>
int SupernodalSolve<Scalar>::tiled_supernodes() const {
  int count = 0;
  if (groups_.size() > 1) {
    for (int s : top_) count += Tiled(s) ? 1 : 0;
  }
  return count;
}

template <class Scalar>
int SupernodalSolve<Scalar>::TileRows(int s) const {
  const int nrow = pi_[s + 1] - pi_[s];
  const int even = (nrow + kMaxTiles - 1) / kMaxTiles;
  return (even + tile_rows_ - 1) / tile_rows_ * tile_rows_;  // a multiple of tile_rows_
}

template <class Scalar>
int SupernodalSolve<Scalar>::TiledPhases(int s) const {
  const int ncol = super_[s + 1] - super_[s], R = TileRows(s);
  return 2 + 3 * ((ncol + R - 1) / R);
}

// Phase 0: A's entries (1 task); 1: the descendants' updates, one task per row tile; then
// per panel p of TileRows(s) columns, 2 + 3p: its diagonal block's Cholesky factor (1 task),
// 3 + 3p: the rows below it solved, 4 + 3p: the columns right of it updated (a task per
// chunk of those rows: the rest of the panel's tile, then each tile below).
template <class Scalar>
int SupernodalSolve<Scalar>::TiledTasks(int s, int phase) const {
  const int R = TileRows(s);
  const int ncol = super_[s + 1] - super_[s], nrow = pi_[s + 1] - pi_[s];
  const int tiles = (nrow + R - 1) / R;
  if (phase == 0) return 1;
  if (phase == 1) return tiles;
  const int p = (phase - 2) / 3;
  if ((phase - 2) % 3 == 0) return 1;
  const int below = std::min(ncol, (p + 1) * R);  // the first row below the panel's diagonal block
  return below < nrow ? tiles - below / R : 0;
}

template <class Scalar>
bool SupernodalSolve<Scalar>::TiledTask(int s, int phase, int task, const double* a, int* map,
                                        Scalar* c) {
  const int R = TileRows(s);
  const int ncol = super_[s + 1] - super_[s], nrow = pi_[s + 1] - pi_[s];
  Scalar* L = values_.data() + px_[s];
  if (phase == 0) {
    Gather(s, a, map);
    return true;
  }
  if (phase == 1) {  // the updates of the rows [task R, task R + R)
    SubtractUpdates(s, task * R, std::min(nrow, (task + 1) * R), /*whole=*/false, map, c);
    return true;
  }
  const int p = (phase - 2) / 3;
  const int c0 = p * R, w = std::min(ncol, c0 + R) - c0;
  Scalar* panel = L + static_cast<int64_t>(c0) * nrow;  // its columns, from row 0
  if ((phase - 2) % 3 == 0) {
    if (Potrf(w, panel + c0, nrow) != 0) return false;
    for (int j = c0; j < c0 + w; ++j) {
      Scalar* column = L + static_cast<int64_t>(j) * nrow;
      const Scalar pivot = column[j];
      if (!(pivot > 0) || !std::isfinite(static_cast<double>(pivot))) return false;
      // Above the diagonal: zeros (what the trailing updates wrote there is not part of L).
      std::fill(column, column + j, Scalar(0));
    }
    return true;
  }
  const int below = c0 + w;
  const int r0 = std::max(below, (below / R + task) * R), r1 = std::min(nrow, (below / R + task + 1) * R);
  if ((phase - 2) % 3 == 1) {
    TrsmRightLowerTransposed(r1 - r0, w, panel + c0, nrow, panel + r0, nrow);
    return true;
  }
  // Columns [below, min(ncol, r1)) of the rows [r0, r1) (entries above the diagonal too,
  // cleared when their panel is factorized).
  const int e1 = std::min(ncol, r1);
  if (below < e1) {
    GemmNTSubtract(r1 - r0, e1 - below, w, panel + r0, nrow, panel + below, nrow,
                   L + static_cast<int64_t>(below) * nrow + r0, nrow);
  }
  return true;
}

template <class Scalar>
bool SupernodalSolve<Scalar>::Factorize(const cholmod_factor& L, const Eigen::SparseMatrix<double>& A,
                                        bool new_structure, int threads) {
  threads_ = std::max(1, threads);
  if (new_structure || n_ != static_cast<int>(L.n) || super_.size() != L.nsuper + 1 || px_.empty() ||
      px_.back() != static_cast<int64_t>(L.xsize)) {
    loaded_ = false;
    if (!TakeStructure(L)) return false;
  }
  loaded_ = false;
  // The plan holds for the pattern it was made for (compared whole: a pass over A's
  // indices, a few percent of a factorization).
  const bool same_pattern =
      prepared_ && A.cols() + 1 == static_cast<Eigen::Index>(prepared_outer_.size()) &&
      A.nonZeros() == static_cast<Eigen::Index>(prepared_inner_.size()) &&
      std::equal(prepared_outer_.begin(), prepared_outer_.end(), A.outerIndexPtr()) &&
      std::equal(prepared_inner_.begin(), prepared_inner_.end(), A.innerIndexPtr());
  if (!same_pattern) {
    if (!PrepareFactorization(A)) return false;
  }
  values_.resize(static_cast<size_t>(px_.back()));
  const double* a = A.valuePtr();
  const int num_groups = static_cast<int>(groups_.size());
  bool ok = true;
  if (num_groups == 1) {
    for (int s : groups_[0]) {
      if (!FactorizeSupernode(s, a, map_[0].data(), c_[0].data())) return false;
    }
  } else if (threads_ == 1) {  // the same groups, top and tiles, one after the other
    for (size_t g = 0; g < groups_.size() && ok; ++g) {
      for (int s : groups_[g]) {
        if (!FactorizeSupernode(s, a, map_[g].data(), c_[g].data())) {
          ok = false;
          break;
        }
      }
    }
    for (size_t k = 0; k < top_.size() && ok; ++k) {
      const int s = top_[k];
      if (!Tiled(s)) {
        ok = FactorizeSupernode(s, a, map_[0].data(), c_[0].data());
        continue;
      }
      const int phases = TiledPhases(s);
      for (int phase = 0; phase < phases && ok; ++phase) {
        const int tasks = TiledTasks(s, phase);
        for (int task = 0; task < tasks && ok; ++task) ok = TiledTask(s, phase, task, a, map_[0].data(), c_[0].data());
      }
    }
  } else {
    const int team = std::min(threads_, num_groups);
    std::vector<char> group_ok(static_cast<size_t>(num_groups), 1);
#pragma omp parallel for schedule(static, 1) num_threads(team)
    for (int g = 0; g < num_groups; ++g) {
      for (int s : groups_[static_cast<size_t>(g)]) {
        if (!FactorizeSupernode(s, a, map_[static_cast<size_t>(g)].data(), c_[static_cast<size_t>(g)].data())) {
          group_ok[static_cast<size_t>(g)] = 0;
          break;
        }
      }
    }
    for (char g : group_ok) ok = ok && g;
    // The top on the whole team: a large supernode's tiles of each phase in parallel (each
    // task's result is the same whichever thread runs it), the others on one thread. After
    // a failure the remaining tasks do nothing (every thread still meets every barrier).
    int failed = ok ? 0 : 1;
    if (ok && !top_.empty()) {
#pragma omp parallel num_threads(team)
      {
        const int t = TeamThread();
        Scalar* c = c_[static_cast<size_t>(t)].data();
        int* map = map_[0].data();
        auto fail = [&] {
#pragma omp atomic write
          failed = 1;
        };
        auto has_failed = [&] {
          int f;
#pragma omp atomic read
          f = failed;
          return f != 0;
        };
        for (int s : top_) {
          if (!Tiled(s)) {
#pragma omp single
            {
              if (!has_failed() && !FactorizeSupernode(s, a, map, c)) fail();
            }
            continue;
          }
          const int phases = TiledPhases(s);
          for (int phase = 0; phase < phases; ++phase) {
            const int tasks = TiledTasks(s, phase);
#pragma omp for schedule(dynamic, 1)
            for (int task = 0; task < tasks; ++task) {
              if (!has_failed() && !TiledTask(s, phase, task, a, map, c)) fail();
            }
          }
        }
      }
    }
    ok = failed == 0;
  }
  loaded_ = ok;
  return ok;
}

namespace {

// The dense kernels of one supernode: L its nrow x ncol block (column-major, the diagonal
// block on top), z its rows. Columns go four at a time: one pass over the rows below a
// block of four updates them (forward) or forms their four dot products (backward), so z
// is read once per four columns. The rows go four at a time in GCC's vector types (two SSE
// registers each by default, one AVX register in the x86-64-v3 clone); a dot product keeps
// four lane sums added in a fixed order at the end, so the result does not depend on the
// clone (up to the fused multiply-adds the compiler forms).
// The helpers take and give them through pointers and references: a vector passed by
// value would have one calling convention in the AVX2 clone and another in the default one.
typedef double Double4 __attribute__((vector_size(32)));
typedef float Float4 __attribute__((vector_size(16)));

inline void Load4(const double* p, Double4* v) { __builtin_memcpy(v, p, sizeof(*v)); }
inline void Load4(const float* p, Double4* v) {
  Float4 f;
  __builtin_memcpy(&f, p, sizeof(f));
  *v = __builtin_convertvector(f, Double4);
}
inline void Store4(double* p, const Double4& v) { __builtin_memcpy(p, &v, sizeof(v)); }
inline double Sum(const Double4& v) { return (v[0] + v[1]) + (v[2] + v[3]); }
// Rows i..i+3 of z and of the four columns starting at c0 (nrow apart).
template <class Scalar>
inline void LoadRows(const Scalar* c0, int nrow, int i, const double* z, Double4* zi, Double4* l) {
  Load4(z + i, zi);
  for (int k = 0; k < 4; ++k) Load4(c0 + static_cast<int64_t>(k) * nrow + i, l + k);
}

template <class Scalar>
__attribute__((target_clones("arch=x86-64-v3", "default"))) void ForwardKernel(
    const Scalar* L, int nrow, int ncol, double* z) {
  int j0 = 0;
  for (; j0 + 4 <= ncol; j0 += 4) {
    const Scalar* c0 = L + static_cast<int64_t>(j0) * nrow;
    const Scalar* c1 = c0 + nrow;
    const Scalar* c2 = c1 + nrow;
    const Scalar* c3 = c2 + nrow;
    const double z0 = z[j0] / c0[j0];
    const double z1 = (z[j0 + 1] - c0[j0 + 1] * z0) / c1[j0 + 1];
    const double z2 = (z[j0 + 2] - c0[j0 + 2] * z0 - c1[j0 + 2] * z1) / c2[j0 + 2];
    const double z3 = (z[j0 + 3] - c0[j0 + 3] * z0 - c1[j0 + 3] * z1 - c2[j0 + 3] * z2) / c3[j0 + 3];
    z[j0] = z0;
    z[j0 + 1] = z1;
    z[j0 + 2] = z2;
    z[j0 + 3] = z3;
    int i = j0 + 4;
    for (; i + 4 <= nrow; i += 4) {
      Double4 zi, l[4];
      LoadRows(c0, nrow, i, z, &zi, l);
      Store4(z + i, zi - ((l[0] * z0 + l[1] * z1) + (l[2] * z2 + l[3] * z3)));
    }
    for (; i < nrow; ++i) {
      z[i] -= (static_cast<double>(c0[i]) * z0 + static_cast<double>(c1[i]) * z1) +
              (static_cast<double>(c2[i]) * z2 + static_cast<double>(c3[i]) * z3);
    }
  }
  for (int j = j0; j < ncol; ++j) {
    const Scalar* c = L + static_cast<int64_t>(j) * nrow;
    const double zj = z[j] / c[j];
    z[j] = zj;
    int i = j + 1;
    for (; i + 4 <= nrow; i += 4) {
      Double4 zi, l;
      Load4(z + i, &zi);
      Load4(c + i, &l);
      Store4(z + i, zi - l * zj);
    }
    for (; i < nrow; ++i) z[i] -= static_cast<double>(c[i]) * zj;
  }
}

// sum_{i in [begin, nrow)} c[i] z[i], in four lanes.
template <class Scalar>
inline double Dot(const Scalar* c, const double* z, int begin, int nrow) {
  Double4 a = {0.0, 0.0, 0.0, 0.0};
  int i = begin;
  for (; i + 4 <= nrow; i += 4) {
    Double4 l, zi;
    Load4(c + i, &l);
    Load4(z + i, &zi);
    a += l * zi;
  }
  for (int l = 0; i < nrow; ++i, ++l) a[l] += static_cast<double>(c[i]) * z[i];
  return Sum(a);
}

template <class Scalar>
__attribute__((target_clones("arch=x86-64-v3", "default"))) void BackwardKernel(
    const Scalar* L, int nrow, int ncol, double* z) {
  // The columns past the last full block of four, last first; then the blocks.
  const int blocks_end = ncol - ncol % 4;
  for (int j = ncol - 1; j >= blocks_end; --j) {
    const Scalar* c = L + static_cast<int64_t>(j) * nrow;
    z[j] = (z[j] - Dot(c, z, j + 1, nrow)) / c[j];
  }
  for (int j0 = blocks_end - 4; j0 >= 0; j0 -= 4) {
    const Scalar* c0 = L + static_cast<int64_t>(j0) * nrow;
    const Scalar* c1 = c0 + nrow;
    const Scalar* c2 = c1 + nrow;
    const Scalar* c3 = c2 + nrow;
    Double4 a0 = {0.0, 0.0, 0.0, 0.0}, a1 = a0, a2 = a0, a3 = a0;
    int i = j0 + 4;
    for (; i + 4 <= nrow; i += 4) {
      Double4 zi, l[4];
      LoadRows(c0, nrow, i, z, &zi, l);
      a0 += l[0] * zi;
      a1 += l[1] * zi;
      a2 += l[2] * zi;
      a3 += l[3] * zi;
    }
    for (int l = 0; i < nrow; ++i, ++l) {
      a0[l] += static_cast<double>(c0[i]) * z[i];
      a1[l] += static_cast<double>(c1[i]) * z[i];
      a2[l] += static_cast<double>(c2[i]) * z[i];
      a3[l] += static_cast<double>(c3[i]) * z[i];
    }
    const double s0 = Sum(a0), s1 = Sum(a1), s2 = Sum(a2), s3 = Sum(a3);
    const double z3 = (z[j0 + 3] - s3) / c3[j0 + 3];
    const double z2 = (z[j0 + 2] - s2 - c2[j0 + 3] * z3) / c2[j0 + 2];
    const double z1 = (z[j0 + 1] - s1 - c1[j0 + 2] * z2 - c1[j0 + 3] * z3) / c1[j0 + 1];
    const double z0 = (z[j0] - s0 - c0[j0 + 1] * z1 - c0[j0 + 2] * z2 - c0[j0 + 3] * z3) / c0[j0];
    z[j0] = z0;
    z[j0 + 1] = z1;
    z[j0 + 2] = z2;
    z[j0 + 3] = z3;
  }
}

}  // namespace

// Supernode s of L y = b: its columns' values from b less the updates `acc` holds, then
// its own updates of the rows below into `acc`.
template <class Scalar>
void SupernodalSolve<Scalar>::Forward(int s, const double* b, double* acc, double* y,
                                      double* z) const {
  const int k0 = super_[static_cast<size_t>(s)];
  const int ncol = super_[static_cast<size_t>(s) + 1] - k0;
  const int nrow = pi_[static_cast<size_t>(s) + 1] - pi_[static_cast<size_t>(s)];
  const int* rows = rows_.data() + pi_[static_cast<size_t>(s)];
  for (int j = 0; j < ncol; ++j) z[j] = b[k0 + j] - acc[k0 + j];
  for (int i = ncol; i < nrow; ++i) z[i] = 0.0;
  ForwardKernel(values_.data() + px_[static_cast<size_t>(s)], nrow, ncol, z);
  for (int j = 0; j < ncol; ++j) y[k0 + j] = z[j];
  for (int i = ncol; i < nrow; ++i) acc[rows[i]] -= z[i];
}

// Supernode s of L^T x = y, in place: its rows below hold their solution already.
template <class Scalar>
void SupernodalSolve<Scalar>::Backward(int s, double* y, double* z) const {
  const int k0 = super_[static_cast<size_t>(s)];
  const int ncol = super_[static_cast<size_t>(s) + 1] - k0;
  const int nrow = pi_[static_cast<size_t>(s) + 1] - pi_[static_cast<size_t>(s)];
  const int* rows = rows_.data() + pi_[static_cast<size_t>(s)];
  for (int j = 0; j < ncol; ++j) z[j] = y[k0 + j];
  for (int i = ncol; i < nrow; ++i) z[i] = y[rows[i]];
  BackwardKernel(values_.data() + px_[static_cast<size_t>(s)], nrow, ncol, z);
  for (int j = 0; j < ncol; ++j) y[k0 + j] = z[j];
}

// The top: the groups' updates of its rows summed (in group order), then its forward and
// backward substitutions.
template <class Scalar>
void SupernodalSolve<Scalar>::SolveTop(int num_groups, double* y) {
  double* acc = acc_[0].data();
  for (int s : top_) {
    for (int c = super_[static_cast<size_t>(s)]; c < super_[static_cast<size_t>(s) + 1]; ++c) {
      for (int g = 1; g < num_groups; ++g) acc[c] += acc_[static_cast<size_t>(g)][c];
    }
  }
  double* z = z_[0].data();
  for (int s : top_) Forward(s, b_.data(), acc, y, z);
  for (auto it = top_.rbegin(); it != top_.rend(); ++it) Backward(*it, y, z);
}

template <class Scalar>
void SupernodalSolve<Scalar>::Solve(const Eigen::VectorXd& b, Eigen::VectorXd* x) {
  const int* perm = perm_.data();
  for (int k = 0; k < n_; ++k) b_[k] = b[perm[k]];
  double* y = y_.data();
  const int num_groups = static_cast<int>(groups_.size());
  if (num_groups == 1) {
    double* acc = acc_[0].data();
    double* z = z_[0].data();
    acc_[0].setZero();
    for (int s : groups_[0]) Forward(s, b_.data(), acc, y, z);
    for (auto it = groups_[0].rbegin(); it != groups_[0].rend(); ++it) Backward(*it, y, z);
  } else if (threads_ == 1) {  // the team's steps below, one after the other
    for (int g = 0; g < num_groups; ++g) {
      acc_[static_cast<size_t>(g)].setZero();
      for (int s : groups_[static_cast<size_t>(g)]) {
        Forward(s, b_.data(), acc_[static_cast<size_t>(g)].data(), y, z_[static_cast<size_t>(g)].data());
      }
    }
    SolveTop(num_groups, y);
    for (int g = 0; g < num_groups; ++g) {
      const std::vector<int>& group = groups_[static_cast<size_t>(g)];
      for (auto it = group.rbegin(); it != group.rend(); ++it) Backward(*it, y, z_[static_cast<size_t>(g)].data());
    }
  } else {
#pragma omp parallel num_threads(std::min(threads_, num_groups))
    {
      const int t = TeamThread(), team = TeamSize();
      for (int g = t; g < num_groups; g += team) {
        acc_[static_cast<size_t>(g)].setZero();
        for (int s : groups_[static_cast<size_t>(g)]) {
          Forward(s, b_.data(), acc_[static_cast<size_t>(g)].data(), y, z_[static_cast<size_t>(g)].data());
        }
      }
#pragma omp barrier
#pragma omp single
      SolveTop(num_groups, y);  // a barrier
      for (int g = t; g < num_groups; g += team) {
        const std::vector<int>& group = groups_[static_cast<size_t>(g)];
        for (auto it = group.rbegin(); it != group.rend(); ++it) {
          Backward(*it, y, z_[static_cast<size_t>(g)].data());
        }
      }
    }
  }
  x->resize(n_);
  for (int k = 0; k < n_; ++k) (*x)[perm[k]] = y[k];
}

template class SupernodalSolve<float>;
template class SupernodalSolve<double>;

}  // namespace fast_backend
}  // namespace femreg
