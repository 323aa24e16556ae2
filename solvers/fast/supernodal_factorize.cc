// The supernodal solve's numeric factorization (supernodal_solve.h): each supernode's
// columns gathered from A, the updates of its descendants subtracted, its diagonal block
// factored and the rows below solved; large supernodes of the top in tiles on the team.
#include <algorithm>
#include <array>
#include <cmath>
#include <numeric>
#include <type_traits>

#include "parallel/threads.h"
#include "solvers/fast/supernodal_solve.h"

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
// A supernode's dense part (its ncol columns of nrow rows, lower triangle) as Cholesky's: the
// diagonal block by LAPACK, the rows below by a triangular solve. False, the rows below left
// as they were, when a pivot is not positive and finite.
template <class T>
bool CholeskyBlock(int ncol, int nrow, T* L) {
  if (Potrf(ncol, L, nrow) != 0) return false;
  for (int j = 0; j < ncol; ++j) {
    const T pivot = L[static_cast<int64_t>(j) * nrow + j];
    if (!(pivot > 0) || !std::isfinite(static_cast<double>(pivot))) return false;
  }
  if (nrow > ncol) TrsmRightLowerTransposed(nrow - ncol, ncol, L, nrow, L + ncol, nrow);
  return true;
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

}  // namespace

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
                                              Scalar* c, std::vector<Scalar>* signed_columns) {
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
    // L S L^T (FactorizeIndefinite): d's columns carry their signs where any is negative.
    const Scalar* sign = !sign_.empty() && negative_[static_cast<size_t>(d)] ? sign_.data() + super_[d] : nullptr;
    if (static_cast<int64_t>(m) * n * dcol < kBlasUpdate) {
      for (int j = 0; j < jn; ++j) {
        Scalar* target = L + static_cast<int64_t>(drows[j] - k1) * nrow;
        const int i0 = std::max(j, ilo);
        for (int i = i0; i < ihi; ++i) c[i] = 0;
        for (int k = 0; k < dcol; ++k) {
          const Scalar* column = D + static_cast<int64_t>(k) * drow;
          const Scalar djk = sign != nullptr ? column[j] * sign[k] : column[j];
          for (int i = i0; i < ihi; ++i) c[i] += column[i] * djk;
        }
        for (int i = i0; i < ihi; ++i) target[map[drows[i]]] -= c[i];
      }
      continue;
    }
    if (sign != nullptr) {  // W = D S (its m rows), then c = W D^T: a product, not a rank update
      signed_columns->resize(std::max(signed_columns->size(), static_cast<size_t>(m) * dcol));
      Scalar* W = signed_columns->data();
      for (int k = 0; k < dcol; ++k) {
        const Scalar* column = D + static_cast<int64_t>(k) * drow;
        Scalar* wk = W + static_cast<int64_t>(k) * m;
        for (int i = 0; i < m; ++i) wk[i] = column[i] * sign[k];
      }
      const int mt = ihi - ilo;
      GemmNT(mt, jn, dcol, W + ilo, m, D, drow, c, mt);
      for (int j = 0; j < jn; ++j) {
        Scalar* target = L + static_cast<int64_t>(drows[j] - k1) * nrow;
        const Scalar* cj = c + static_cast<int64_t>(j) * mt;
        for (int i = std::max(j, ilo); i < ihi; ++i) target[map[drows[i]]] -= cj[i - ilo];
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
bool SupernodalSolve<Scalar>::FactorizeSupernode(int s, int g, const double* a) {
  const int ncol = super_[s + 1] - super_[s], nrow = pi_[s + 1] - pi_[s];
  Scalar* L = values_.data() + px_[s];
  int* map = map_[static_cast<size_t>(g)].data();
  Gather(s, a, map);
  SubtractUpdates(s, 0, nrow, /*whole=*/true, map, c_[static_cast<size_t>(g)].data(), &signed_[static_cast<size_t>(g)]);
  if (!sign_.empty()) return FactorizeIndefiniteBlock(s, g);
  return CholeskyBlock(ncol, nrow, L);
}

template <class Scalar>
bool SupernodalSolve<Scalar>::FactorizeIndefiniteBlock(int s, int g) {
  constexpr int kPanel = kIndefinitePanel;
  const int k0 = super_[s], ncol = super_[s + 1] - k0, nrow = pi_[s + 1] - pi_[s];
  Scalar* L = values_.data() + px_[s];
  // Most blocks are positive definite (a negative pivot is where elements turn or are
  // compressed): LAPACK's Cholesky first. The block is kept for the panels if it fails: its
  // strict lower triangle in the strict upper one (zeros until here: Gather and the updates
  // write the lower triangle), transposed, its diagonal in the group's buffer (at least ncol).
  // A block that factorizes has signs +1, and a positive pivot is taken as it is, as
  // Factorize takes it.
  Scalar* diagonal = signed_[static_cast<size_t>(g)].data();
  for (int j = 0; j < ncol; ++j) {
    diagonal[j] = L[static_cast<int64_t>(j) * nrow + j];
    for (int i = j + 1; i < ncol; ++i) L[static_cast<int64_t>(i) * nrow + j] = L[static_cast<int64_t>(j) * nrow + i];
  }
  if (CholeskyBlock(ncol, nrow, L)) {
    for (int j = 1; j < ncol; ++j) std::fill(L + static_cast<int64_t>(j) * nrow, L + static_cast<int64_t>(j) * nrow + j, Scalar(0));
    negative_[static_cast<size_t>(s)] = 0;
    return true;
  }
  for (int j = 0; j < ncol; ++j) {
    L[static_cast<int64_t>(j) * nrow + j] = diagonal[j];
    for (int i = j + 1; i < ncol; ++i) L[static_cast<int64_t>(j) * nrow + i] = L[static_cast<int64_t>(i) * nrow + j];
  }
  bool negative = false;
  // The diagonal block A11 = L11 S L11^T, by panels (rows < ncol only).
  for (int p0 = 0; p0 < ncol; p0 += kPanel) {
    const int p1 = std::min(ncol, p0 + kPanel);
    for (int j = p0; j < p1; ++j) {
      Scalar* cj = L + static_cast<int64_t>(j) * nrow;
      Scalar pivot = cj[j];
      if (!std::isfinite(static_cast<double>(pivot))) return false;
      if (!(std::abs(static_cast<double>(pivot)) > pivot_floor_)) {  // round-off's: the floor
        pivot = static_cast<Scalar>(pivot_floor_);
        ++group_perturbed_[static_cast<size_t>(g)];
      }
      const Scalar sign = pivot > 0 ? Scalar(1) : Scalar(-1);
      const Scalar root = std::sqrt(std::abs(pivot));
      sign_[static_cast<size_t>(k0 + j)] = sign;
      if (sign < 0) {
        negative = true;
        ++group_negative_[static_cast<size_t>(g)];
      }
      cj[j] = root;
      const Scalar scale = sign / root;  // L_ij = a_ij s_j / |d_j|^(1/2)
      for (int i = j + 1; i < ncol; ++i) cj[i] *= scale;
      for (int k = j + 1; k < p1; ++k) {  // the panel's later columns: a_ik -= L_ij s_j L_kj
        Scalar* ck = L + static_cast<int64_t>(k) * nrow;
        const Scalar lkj = cj[k] * sign;
        for (int i = k; i < ncol; ++i) ck[i] -= cj[i] * lkj;
      }
    }
    if (p1 < ncol) {  // the block's columns right of the panel, rows from p1: -= (L S) L^T
      const int m = ncol - p1, w = p1 - p0;
      std::vector<Scalar>& buffer = signed_[static_cast<size_t>(g)];
      buffer.resize(std::max(buffer.size(), static_cast<size_t>(m) * w));
      Scalar* W = buffer.data();
      for (int k = 0; k < w; ++k) {
        const Scalar* column = L + static_cast<int64_t>(p0 + k) * nrow + p1;
        const Scalar sign = sign_[static_cast<size_t>(k0 + p0 + k)];
        Scalar* wk = W + static_cast<int64_t>(k) * m;
        for (int i = 0; i < m; ++i) wk[i] = column[i] * sign;
      }
      GemmNTSubtract(m, m, w, W, m, L + static_cast<int64_t>(p0) * nrow + p1, nrow,
                     L + static_cast<int64_t>(p1) * nrow + p1, nrow);
    }
  }
  // The rows below: A21 = L21 S L11^T, so L21 = A21 L11^-T S.
  if (nrow > ncol) {
    TrsmRightLowerTransposed(nrow - ncol, ncol, L, nrow, L + ncol, nrow);
    if (negative) {
      for (int j = 0; j < ncol; ++j) {
        if (sign_[static_cast<size_t>(k0 + j)] > 0) continue;
        Scalar* below = L + static_cast<int64_t>(j) * nrow + ncol;
        for (int i = 0; i < nrow - ncol; ++i) below[i] = -below[i];
      }
    }
  }
  // Above the diagonal: zeros (the products wrote there; it is not part of L).
  for (int j = 1; j < ncol; ++j) std::fill(L + static_cast<int64_t>(j) * nrow, L + static_cast<int64_t>(j) * nrow + j, Scalar(0));
  negative_[static_cast<size_t>(s)] = negative ? 1 : 0;
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
    SubtractUpdates(s, task * R, std::min(nrow, (task + 1) * R), /*whole=*/false, map, c, nullptr);
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
bool SupernodalSolve<Scalar>::Prepare(const cholmod_factor& L, const Eigen::SparseMatrix<double>& A,
                                      bool new_structure) {
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
  return true;
}

template <class Scalar>
bool SupernodalSolve<Scalar>::FactorizeIndefinite(const cholmod_factor& L, const Eigen::SparseMatrix<double>& A,
                                                  bool new_structure, int threads) {
  threads_ = std::max(1, threads);
  sign_.clear();
  negative_pivots_ = perturbed_pivots_ = 0;
  if (!Prepare(L, A, new_structure)) return false;
  double largest = 0.0;
  for (Eigen::Index c = 0; c < A.outerSize(); ++c) {
    for (Eigen::SparseMatrix<double>::InnerIterator it(A, c); it; ++it) {
      if (it.row() == c) largest = std::max(largest, std::abs(it.value()));
    }
  }
  // In float a pivot below 1e-8 of the diagonal is round-off: the size of the shift that
  // lets a free body's rigid motions factorize, which the callers project out.
  pivot_floor_ = (std::is_same_v<Scalar, float> ? 1e-8 : 1e-12) * largest;
  sign_.assign(static_cast<size_t>(n_), Scalar(1));
  negative_.assign(super_.size() - 1, 0);
  group_negative_.assign(groups_.size(), 0);
  group_perturbed_.assign(groups_.size(), 0);
  // The signed buffers at their largest before the team starts (no allocation inside it).
  for (std::vector<Scalar>& buffer : signed_) {
    if (static_cast<int64_t>(buffer.size()) < max_signed_) buffer.resize(static_cast<size_t>(max_signed_));
  }
  const double* a = A.valuePtr();
  const int num_groups = static_cast<int>(groups_.size());
  std::vector<char> group_ok(static_cast<size_t>(num_groups), 1);
  // Children before parents: the groups (each writes only its own supernodes, signs and
  // counts), then the top on one thread (no tiles).
  auto factorize_group = [&](int g) {
    for (int s : groups_[static_cast<size_t>(g)]) {
      if (!FactorizeSupernode(s, g, a)) {
        group_ok[static_cast<size_t>(g)] = 0;
        break;
      }
    }
  };
  bool ok = largest > 0.0 && std::isfinite(largest);
  const int team = std::min(threads_, num_groups);
  if (ok && team > 1) {
#pragma omp parallel for schedule(static, 1) num_threads(team)
    for (int g = 0; g < num_groups; ++g) factorize_group(g);
  } else if (ok) {
    for (int g = 0; g < num_groups; ++g) factorize_group(g);
  }
  ok = ok && std::all_of(group_ok.begin(), group_ok.end(), [](char c) { return c != 0; });
  for (size_t k = 0; k < top_.size() && ok; ++k) ok = FactorizeSupernode(top_[k], 0, a);
  for (int g = 0; g < num_groups; ++g) {
    negative_pivots_ += group_negative_[static_cast<size_t>(g)];
    perturbed_pivots_ += group_perturbed_[static_cast<size_t>(g)];
  }
  if (!ok) {
    sign_.clear();
    negative_pivots_ = perturbed_pivots_ = 0;
    return false;
  }
  loaded_ = true;
  return true;
}

template <class Scalar>
bool SupernodalSolve<Scalar>::Factorize(const cholmod_factor& L, const Eigen::SparseMatrix<double>& A,
                                        bool new_structure, int threads) {
  threads_ = std::max(1, threads);
  sign_.clear();
  negative_pivots_ = perturbed_pivots_ = 0;
  if (!Prepare(L, A, new_structure)) return false;
  const double* a = A.valuePtr();
  const int num_groups = static_cast<int>(groups_.size());
  bool ok = true;
  if (num_groups == 1) {
    for (int s : groups_[0]) {
      if (!FactorizeSupernode(s, 0, a)) return false;
    }
  } else if (threads_ == 1) {  // the same groups, top and tiles, one after the other
    for (size_t g = 0; g < groups_.size() && ok; ++g) {
      for (int s : groups_[g]) {
        if (!FactorizeSupernode(s, static_cast<int>(g), a)) {
          ok = false;
          break;
        }
      }
    }
    for (size_t k = 0; k < top_.size() && ok; ++k) {
      const int s = top_[k];
      if (!Tiled(s)) {
        ok = FactorizeSupernode(s, 0, a);
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
        if (!FactorizeSupernode(s, g, a)) {
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
              if (!has_failed() && !FactorizeSupernode(s, 0, a)) fail();
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

template void SupernodalSolve<float>::Gather(int, const double*, int*);
template void SupernodalSolve<float>::SubtractUpdates(int, int, int, bool, const int*, float*, std::vector<float>*);
template bool SupernodalSolve<float>::FactorizeSupernode(int, int, const double*);
template bool SupernodalSolve<float>::Tiled(int) const;
template int SupernodalSolve<float>::tiled_supernodes() const;
template int SupernodalSolve<float>::TileRows(int) const;
template int SupernodalSolve<float>::TiledPhases(int) const;
template int SupernodalSolve<float>::TiledTasks(int, int) const;
template bool SupernodalSolve<float>::TiledTask(int, int, int, const double*, int*, float*);
template bool SupernodalSolve<float>::Factorize(const cholmod_factor&, const Eigen::SparseMatrix<double>&, bool, int);
template bool SupernodalSolve<float>::FactorizeIndefinite(const cholmod_factor&, const Eigen::SparseMatrix<double>&, bool, int);
template bool SupernodalSolve<float>::FactorizeIndefiniteBlock(int, int);
template bool SupernodalSolve<float>::Prepare(const cholmod_factor&, const Eigen::SparseMatrix<double>&, bool);
template void SupernodalSolve<double>::Gather(int, const double*, int*);
template void SupernodalSolve<double>::SubtractUpdates(int, int, int, bool, const int*, double*, std::vector<double>*);
template bool SupernodalSolve<double>::FactorizeSupernode(int, int, const double*);
template bool SupernodalSolve<double>::Tiled(int) const;
template int SupernodalSolve<double>::tiled_supernodes() const;
template int SupernodalSolve<double>::TileRows(int) const;
template int SupernodalSolve<double>::TiledPhases(int) const;
template int SupernodalSolve<double>::TiledTasks(int, int) const;
template bool SupernodalSolve<double>::TiledTask(int, int, int, const double*, int*, double*);
template bool SupernodalSolve<double>::Factorize(const cholmod_factor&, const Eigen::SparseMatrix<double>&, bool, int);
template bool SupernodalSolve<double>::FactorizeIndefinite(const cholmod_factor&, const Eigen::SparseMatrix<double>&, bool, int);
template bool SupernodalSolve<double>::FactorizeIndefiniteBlock(int, int);
template bool SupernodalSolve<double>::Prepare(const cholmod_factor&, const Eigen::SparseMatrix<double>&, bool);

}  // namespace fast_backend
}  // namespace femreg
