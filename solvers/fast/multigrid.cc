#include "solvers/fast/multigrid.h"

#include <Eigen/Cholesky>
#include <Eigen/Dense>
#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstdint>
#include <type_traits>
#include <vector>

#ifdef __SSE__
#include <xmmintrin.h>
#endif

#include "solvers/fast/fast_backend.h"

namespace femreg {
namespace fast_backend {

namespace {

// Coarsening stops at this many unknowns, and that level is solved directly: its inverse,
// dense (~0.2 Gflop once, 2 n^2 per cycle). A coarsest level that stopped above it
// (coarsening stalled, or kMaxLevels) is inverted up to kDenseLimit unknowns, and only
// smoothed beyond.
constexpr int kCoarsest = 500;
constexpr int kDenseLimit = 1000;
constexpr int kMaxLevels = 10;
// Coarsening stops when a level keeps more than this share of the unknowns above it.
constexpr double kStall = 0.7;
// Chebyshev smoothing: degree, and the interval [lambda_max / kChebyshevRatio,
// kChebyshevSafety lambda_max] of D^-1 A it damps (lambda_max from power iterations: an
// estimate above it only weakens the smoothing; one more than ~10 % below it can make the
// V-cycle indefinite, which PCG notices (r.z <= 0) and the back end answers by refreshing
// the estimate, then by a new hierarchy).
constexpr int kChebyshevDegree = 2;
constexpr double kChebyshevRatio = 30.0;
constexpr double kChebyshevSafety = 1.1;
constexpr int kPowerIterations = 15;
// Products and block Jacobi run in parallel from this many unknowns on: a V-cycle has ~15 of them,
// each worth a team's start from here (docs/notes/2026-11-28-figures-from-code-comments.md).
constexpr int kParallelUnknowns = 4096;
// ... or this many stored entries: a coarse level has few unknowns, but many entries per
// column (docs/notes/2026-11-28-figures-from-code-comments.md).
constexpr int64_t kParallelNonzeros = 65536;

using SparseMatrix = Eigen::SparseMatrix<double>;

// Level 0's product y = A v in single precision: A's float copy (the back end's layout: both
// triangles, full 3x3 vertex blocks whose three columns share their rows), v rounded once into
// `v4` (4 floats per vertex, the 4th 0), and each column's sum in float. With SSE, a 3x3
// block's column is one 4-lane multiply-add whose 4th lane reads the next stored entry (times
// that 0; the lane is dropped from the sum, so even a non-finite entry there changes nothing);
// the last vertex's third column, whose next entry is past the end, is summed entry by entry.
// The V-cycle is an approximation of A^-1 to begin with, and PCG, in double with A itself,
// corrects it (as mixed-precision AMG does, e.g. AmgX's float preconditioner for double
// solves); what float sums cost is the V-cycle's symmetry beyond ~1e-8 relative
// (tests/backend_test.cc), which PCG does not see at its tolerance; float sums made the product and
// the V-cycle faster than double sums (docs/notes/2026-11-28-figures-from-code-comments.md).
// Each column's sums run in a fixed order: the same result on any number of threads.
void FloatBlockProduct(const Eigen::SparseMatrix<float>& A, const Eigen::VectorXd& v, int threads,
                       int parallel_from, std::vector<float>* v4, Eigen::VectorXd* y) {
  const int blocks = static_cast<int>(A.cols()) / 3;
  const int* outer = A.outerIndexPtr();
  const int* inner = A.innerIndexPtr();
  const float* values = A.valuePtr();
  const double* vv = v.data();
  v4->resize(4 * static_cast<size_t>(blocks));
  float* p = v4->data();
  y->resize(v.size());
  double* yy = y->data();
  auto convert = [&](int b) {
    for (int i = 0; i < 3; ++i) p[4 * b + i] = static_cast<float>(vv[3 * b + i]);
    p[4 * b + 3] = 0.0f;
  };
  // Block b's three columns; `lanes`: 4-lane loads (not for the last vertex).
  auto column = [&](int b, bool lanes) {
    const int begin = outer[3 * b];
    const int stride = outer[3 * b + 1] - begin;
    const float* v0 = values + begin;
    const int* rows = inner + begin;
#ifdef __SSE__
    if (lanes) {
      const float* v1 = v0 + stride;
      const float* v2 = v1 + stride;
      __m128 s0 = _mm_setzero_ps(), s1 = _mm_setzero_ps(), s2 = _mm_setzero_ps();
      for (int k = 0; k < stride; k += 3) {
        const __m128 pa = _mm_loadu_ps(p + (rows[k] / 3) * 4);
        s0 = _mm_add_ps(s0, _mm_mul_ps(_mm_loadu_ps(v0 + k), pa));
        s1 = _mm_add_ps(s1, _mm_mul_ps(_mm_loadu_ps(v1 + k), pa));
        s2 = _mm_add_ps(s2, _mm_mul_ps(_mm_loadu_ps(v2 + k), pa));
      }
      alignas(16) float t[12];
      _mm_store_ps(t, s0);
      _mm_store_ps(t + 4, s1);
      _mm_store_ps(t + 8, s2);
      yy[3 * b] = static_cast<double>((t[0] + t[1]) + t[2]);
      yy[3 * b + 1] = static_cast<double>((t[4] + t[5]) + t[6]);
      yy[3 * b + 2] = static_cast<double>((t[8] + t[9]) + t[10]);
      return;
    }
#endif
    (void)lanes;
    float sums[3];
    BlockColumnSums(v0, stride, rows, [p](int row) { return p + (row / 3) * 4; }, sums);
    for (int j = 0; j < 3; ++j) yy[3 * b + j] = sums[j];
  };
  if (threads > 1 && blocks >= parallel_from) {
#pragma omp parallel num_threads(threads)
    {
#pragma omp for schedule(static)
      for (int b = 0; b < blocks; ++b) convert(b);
#pragma omp for schedule(static)
      for (int b = 0; b < blocks; ++b) column(b, b + 1 < blocks);
    }
  } else {
    for (int b = 0; b < blocks; ++b) convert(b);
    for (int b = 0; b < blocks; ++b) column(b, b + 1 < blocks);
  }
}

// The largest eigenvalue of D^-1 A (real and positive: it is similar to D^-1/2 A D^-1/2),
// by power iterations from a fixed start.
template <class Product, class Jacobi>
double LargestEigenvalue(int n, Product product, Jacobi jacobi) {
  Eigen::VectorXd v(n), av, w;
  // A start with every frequency in it (a smooth one barely holds the largest modes).
  uint64_t state = 0x9E3779B97F4A7C15ull;
  for (int i = 0; i < n; ++i) {
    state = state * 6364136223846793005ull + 1442695040888963407ull;
    v[i] = static_cast<double>(state >> 11) * (1.0 / 9007199254740992.0) - 0.5;
  }
  v.normalize();
  double lambda = 0.0;
  for (int k = 0; k < kPowerIterations; ++k) {
    product(v, &av);
    jacobi(av, &w);
    const double norm = w.norm();
    if (!(norm > 0.0) || !std::isfinite(norm)) break;
    lambda = std::max(lambda, norm);
    v = w / norm;
  }
  return lambda > 0.0 ? lambda : 1.0;
}

// One column node's gather, any block shapes, in double: y_j = sum over its blocks B
// (row_count x nc, column-major) of B(:, j) . x(rows of B).
void GatherNode(const float* values, const int* value_at, const int* row_first, const int* row_count,
                int begin, int end, int nc, const double* x, double* y) {
  for (int j = 0; j < nc; ++j) {
    double s = 0.0;
    for (int k = begin; k < end; ++k) {
      const float* B = values + value_at[k] + j * row_count[k];
      const double* xr = x + row_first[k];
      for (int i = 0; i < row_count[k]; ++i) s += static_cast<double>(B[i]) * xr[i];
    }
    y[j] = s;
  }
}

// The shapes the hierarchy makes (R x C blocks, every block of the column node alike) in
// single precision: x in float and the column's sum in float; with SSE, each block's column
// one 4-lane multiply-add per 4 of its rows (6 rows: 4 + 2 lanes; 3 rows: 3 lanes, the 4th
// reads the next stored value and is dropped), else entry by entry (see FloatBlockProduct:
// ~1e-7 relative, as the values' own rounding). `values` holds 4 more floats than its
// blocks (the last block's 4th lane). With FloatBlockProduct at level 0, float sums made a
// whole V-cycle faster than double sums (docs/notes/2026-11-28-figures-from-code-comments.md).
template <int R, int C>
void GatherNodeFloat(const float* values, const int* value_at, const int* row_first, int begin, int end,
                     const float* x, double* y) {
  static_assert((R == 3 || R == 6) && C >= 1 && C <= 6, "the shapes the hierarchy makes");
#ifdef __SSE__
  __m128 acc[C];
  for (int j = 0; j < C; ++j) acc[j] = _mm_setzero_ps();
  for (int k = begin; k < end; ++k) {
    const float* B = values + value_at[k];
    const float* xr = x + row_first[k];
    if constexpr (R == 6) {
      const __m128 lo = _mm_loadu_ps(xr);
      const __m128 hi = _mm_loadl_pi(_mm_setzero_ps(), reinterpret_cast<const __m64*>(xr + 4));
      for (int j = 0; j < C; ++j) {
        const __m128 b_hi = _mm_loadl_pi(_mm_setzero_ps(), reinterpret_cast<const __m64*>(B + 6 * j + 4));
        acc[j] = _mm_add_ps(acc[j], _mm_add_ps(_mm_mul_ps(_mm_loadu_ps(B + 6 * j), lo), _mm_mul_ps(b_hi, hi)));
      }
    } else {
      const __m128 x3 = _mm_movelh_ps(_mm_loadl_pi(_mm_setzero_ps(), reinterpret_cast<const __m64*>(xr)),
                                      _mm_load_ss(xr + 2));
      for (int j = 0; j < C; ++j) acc[j] = _mm_add_ps(acc[j], _mm_mul_ps(_mm_loadu_ps(B + 3 * j), x3));
    }
  }
  for (int j = 0; j < C; ++j) {
    alignas(16) float t[4];
    _mm_store_ps(t, acc[j]);
    y[j] = static_cast<double>(R == 6 ? (t[0] + t[1]) + (t[2] + t[3]) : (t[0] + t[1]) + t[2]);
  }
#else
  float acc[C] = {};
  for (int k = begin; k < end; ++k) {
    const float* B = values + value_at[k];
    const float* xr = x + row_first[k];
    for (int j = 0; j < C; ++j) {
      for (int i = 0; i < R; ++i) acc[j] += B[j * R + i] * xr[i];
    }
  }
  for (int j = 0; j < C; ++j) y[j] = acc[j];
#endif
}

}  // namespace

void Multigrid::NodeBlocks::Assign(const SparseMatrix& M, const std::vector<int>& row_nodes,
                                   const std::vector<int>& col_nodes) {
  rows = static_cast<int>(M.rows());
  cols = static_cast<int>(M.cols());
  col_begin = col_nodes;
  const int num_row_nodes = static_cast<int>(row_nodes.size()) - 1;
  const int num_col_nodes = static_cast<int>(col_nodes.size()) - 1;
  std::vector<int> node_of_row(static_cast<size_t>(rows));
  for (int r = 0; r < num_row_nodes; ++r) {
    for (int i = row_nodes[static_cast<size_t>(r)]; i < row_nodes[static_cast<size_t>(r) + 1]; ++i) {
      node_of_row[static_cast<size_t>(i)] = r;
    }
  }
  block_begin.assign(1, 0);
  rows_of.clear();
  row_first.clear();
  row_count.clear();
  value_at.clear();
  values.clear();
  const int* outer = M.outerIndexPtr();
  const int* inner = M.innerIndexPtr();
  const double* v = M.valuePtr();
  auto column_end = [&](int j) { return M.isCompressed() ? outer[j + 1] : outer[j] + M.innerNonZeroPtr()[j]; };
  std::vector<int> block_of(static_cast<size_t>(num_row_nodes), -1);
  std::vector<int> touched;
  for (int c = 0; c < num_col_nodes; ++c) {
    const int c0 = col_nodes[static_cast<size_t>(c)], nc = col_nodes[static_cast<size_t>(c) + 1] - c0;
    touched.clear();
    for (int j = c0; j < c0 + nc; ++j) {
      for (int p = outer[j]; p < column_end(j); ++p) {
        const int r = node_of_row[static_cast<size_t>(inner[p])];
        if (block_of[static_cast<size_t>(r)] < 0) {
          block_of[static_cast<size_t>(r)] = 0;
          touched.push_back(r);
        }
      }
    }
    std::sort(touched.begin(), touched.end());
    for (int r : touched) {
      const int nr = row_nodes[static_cast<size_t>(r) + 1] - row_nodes[static_cast<size_t>(r)];
      block_of[static_cast<size_t>(r)] = static_cast<int>(values.size());
      row_first.push_back(row_nodes[static_cast<size_t>(r)]);
      row_count.push_back(nr);
      value_at.push_back(static_cast<int>(values.size()));
      values.resize(values.size() + static_cast<size_t>(nr) * static_cast<size_t>(nc), 0.0f);
    }
    for (int j = c0; j < c0 + nc; ++j) {
      for (int p = outer[j]; p < column_end(j); ++p) {
        const int i = inner[p];
        const int r = node_of_row[static_cast<size_t>(i)];
        const int nr = row_nodes[static_cast<size_t>(r) + 1] - row_nodes[static_cast<size_t>(r)];
        values[static_cast<size_t>(block_of[static_cast<size_t>(r)] + (j - c0) * nr +
                                   (i - row_nodes[static_cast<size_t>(r)]))] = static_cast<float>(v[p]);
      }
    }
    for (int r : touched) block_of[static_cast<size_t>(r)] = -1;
    int shared = touched.empty() ? 0 : row_count[static_cast<size_t>(block_begin.back())];
    for (size_t k = static_cast<size_t>(block_begin.back()); k < row_count.size(); ++k) {
      if (row_count[k] != shared) shared = 0;
    }
    rows_of.push_back(shared);
    block_begin.push_back(static_cast<int>(row_first.size()));
  }
  values.resize(values.size() + 4, 0.0f);  // the last block's 4th lane (GatherNodeFloat)
}

void Multigrid::NodeBlocks::AssignTransposed(const BlockRows& R, const std::vector<int>& row_nodes,
                                             const std::vector<int>& col_nodes) {
  rows = row_nodes.back();
  cols = col_nodes.back();
  col_begin = col_nodes;
  const int num_col_nodes = static_cast<int>(col_nodes.size()) - 1;
  block_begin.assign(1, 0);
  rows_of.clear();
  row_first.assign(R.col.size(), 0);
  row_count.assign(R.col.size(), 0);
  value_at.assign(R.col.size(), 0);
  values.assign(R.values.size() + 4, 0.0f);  // 4 more: the last block's 4th lane (GatherNodeFloat)
  for (int c = 0; c < num_col_nodes; ++c) {
    const int nc = R.row_size[static_cast<size_t>(c)];
    int shared = -1;
    for (int q = R.begin[static_cast<size_t>(c)]; q < R.begin[static_cast<size_t>(c) + 1]; ++q) {
      const int r = R.col[static_cast<size_t>(q)];
      const int nr = R.col_size[static_cast<size_t>(r)];
      const size_t k = static_cast<size_t>(q);
      row_first[k] = row_nodes[static_cast<size_t>(r)];
      row_count[k] = nr;
      value_at[k] = R.at[k];
      // M's block (nr x nc) is R's (nc x nr) transposed.
      const double* from = R.values.data() + R.at[k];
      float* to = values.data() + R.at[k];
      for (int j = 0; j < nc; ++j) {
        for (int i = 0; i < nr; ++i) to[i + nr * j] = static_cast<float>(from[j + nc * i]);
      }
      shared = shared == -1 || shared == nr ? nr : 0;
    }
    rows_of.push_back(std::max(shared, 0));
    block_begin.push_back(R.begin[static_cast<size_t>(c) + 1]);
  }
}

void Multigrid::NodeBlocks::Multiply(const Eigen::VectorXd& x, int threads, Eigen::VectorXd* y) {
  y->resize(cols);
  const int nodes = static_cast<int>(col_begin.size()) - 1;
  const int n = static_cast<int>(x.size());
  const double* xx = x.data();
  double* yy = y->data();
  x_float.resize(static_cast<size_t>(n));
  float* xf = x_float.data();
  const float* v = values.data();
  const int* at = value_at.data();
  const int* first = row_first.data();
  const int* count = row_count.data();
  auto node = [&](int c) {
    const int c0 = col_begin[static_cast<size_t>(c)], nc = col_begin[static_cast<size_t>(c) + 1] - c0;
    const int b = block_begin[static_cast<size_t>(c)], e = block_begin[static_cast<size_t>(c) + 1];
    // Where every block of the column node has the same rows (a coarse level's 6, the
    // vertices' 3): fixed loops in single precision; else the general loop in double.
    const int nr = rows_of[static_cast<size_t>(c)];
    if (nr == 6 && nc == 6) {
      GatherNodeFloat<6, 6>(v, at, first, b, e, xf, yy + c0);
    } else if (nr == 3 && nc == 6) {
      GatherNodeFloat<3, 6>(v, at, first, b, e, xf, yy + c0);
    } else if (nr == 6 && nc == 3) {
      GatherNodeFloat<6, 3>(v, at, first, b, e, xf, yy + c0);
    } else {
      GatherNode(v, at, first, count, b, e, nc, xx, yy + c0);
    }
  };
  if (threads > 1 && (cols >= kParallelUnknowns || static_cast<int64_t>(values.size()) >= kParallelNonzeros)) {
#pragma omp parallel num_threads(threads)
    {
#pragma omp for schedule(static)
      for (int i = 0; i < n; ++i) xf[i] = static_cast<float>(xx[i]);
#pragma omp for schedule(static)
      for (int c = 0; c < nodes; ++c) node(c);
    }
  } else {
    for (int i = 0; i < n; ++i) xf[i] = static_cast<float>(xx[i]);
    for (int c = 0; c < nodes; ++c) node(c);
  }
}

void Multigrid::Product(int level, const Eigen::VectorXd& v, Eigen::VectorXd* y) {
  Level& L = levels_[static_cast<size_t>(level)];
  if (level == 0) {
    FloatBlockProduct(L.A_f, v, threads_, kParallelUnknowns / 3, &v4_, y);
  } else {
    L.A_b.Multiply(v, threads_, y);
  }
}

void Multigrid::BlockJacobi(const Level& L, const Eigen::VectorXd& r, Eigen::VectorXd* z) const {
  z->resize(r.size());
  const int nodes = static_cast<int>(L.node_begin.size()) - 1;
  const double* rr = r.data();
  double* zz = z->data();
  auto node = [&](int k) {
    const int b = L.node_begin[static_cast<size_t>(k)];
    const int m = L.node_begin[static_cast<size_t>(k) + 1] - b;
    const double* D = L.dinv.data() + L.dinv_at[static_cast<size_t>(k)];
    for (int i = 0; i < m; ++i) {
      double s = 0.0;
      for (int j = 0; j < m; ++j) s += D[j * m + i] * rr[b + j];
      zz[b + i] = s;
    }
  };
  if (threads_ > 1 && r.size() >= kParallelUnknowns) {
#pragma omp parallel for schedule(static) num_threads(threads_)
    for (int k = 0; k < nodes; ++k) node(k);
  } else {
    for (int k = 0; k < nodes; ++k) node(k);
  }
}

bool Multigrid::PrepareSmoother(int l, const SparseMatrix& A, std::vector<double>* diagonal_norm) {
  if (!InvertDiagonalBlocks(l, A, diagonal_norm)) return false;
  EstimateLambdaMax(l);
  return true;
}

void Multigrid::EstimateLambdaMax(int l) {
  Level& L = levels_[static_cast<size_t>(l)];
  L.lambda_max = LargestEigenvalue(
      L.node_begin.back(), [&](const Eigen::VectorXd& v, Eigen::VectorXd* y) { Product(l, v, y); },
      [&](const Eigen::VectorXd& r, Eigen::VectorXd* z) { BlockJacobi(L, r, z); });
}

bool Multigrid::InvertDiagonalBlocks(int l, const SparseMatrix& A, std::vector<double>* diagonal_norm) {
  Level& L = levels_[static_cast<size_t>(l)];
  const int nodes = static_cast<int>(L.node_begin.size()) - 1;
  const int* outer = A.outerIndexPtr();
  const int* inner = A.innerIndexPtr();
  const double* values = A.valuePtr();
  // Each node's diagonal block: its Frobenius norm (for the strength of connection) and
  // its inverse (block Jacobi), at offsets fixed by the node sizes (SetFinest refills them
  // in place, once per step).
  diagonal_norm->resize(static_cast<size_t>(nodes));
  L.dinv_at.resize(static_cast<size_t>(nodes));
  size_t total = 0;
  for (int k = 0; k < nodes; ++k) {
    const int m = L.node_begin[static_cast<size_t>(k) + 1] - L.node_begin[static_cast<size_t>(k)];
    L.dinv_at[static_cast<size_t>(k)] = static_cast<int>(total);
    total += static_cast<size_t>(m) * static_cast<size_t>(m);
  }
  L.dinv.resize(total);
  // Node k's block, inverted (M: its size, Eigen::Dynamic for any).
  auto invert = [&](auto size_tag, int k) {
    constexpr int M = decltype(size_tag)::value;
    const int b = L.node_begin[static_cast<size_t>(k)];
    const int m = L.node_begin[static_cast<size_t>(k) + 1] - b;
    using Block = Eigen::Matrix<double, M, M>;
    Block D = Block::Zero(m, m);
    for (int j = 0; j < m; ++j) {  // (every level's rows are sorted)
      const int end = outer[b + j + 1];
      for (int p = static_cast<int>(std::lower_bound(inner + outer[b + j], inner + end, b) - inner);
           p < end && inner[p] < b + m; ++p) {
        D(inner[p] - b, j) = values[p];
      }
    }
    D = (0.5 * (D + D.transpose())).eval();
    (*diagonal_norm)[static_cast<size_t>(k)] = D.norm();
    Eigen::LLT<Block> llt(D);
    if (llt.info() != Eigen::Success || !(D.diagonal().minCoeff() > 0.0)) return false;
    const Block inverse = llt.solve(Block::Identity(m, m));
    if (!inverse.allFinite()) return false;
    std::copy(inverse.data(), inverse.data() + m * m, L.dinv.data() + L.dinv_at[static_cast<size_t>(k)]);
    return true;
  };
  auto node = [&](int k) {
    const int m = L.node_begin[static_cast<size_t>(k) + 1] - L.node_begin[static_cast<size_t>(k)];
    return m == 3 ? invert(std::integral_constant<int, 3>(), k) : invert(std::integral_constant<int, Eigen::Dynamic>(), k);
  };
  std::atomic<bool> positive(true);
  if (threads_ > 1 && total >= static_cast<size_t>(3 * kParallelUnknowns)) {
#pragma omp parallel for schedule(static) num_threads(threads_)
    for (int k = 0; k < nodes; ++k) {
      if (!node(k)) positive = false;
    }
  } else {
    for (int k = 0; k < nodes && positive; ++k) {
      if (!node(k)) positive = false;
    }
  }
  return positive;
}

bool Multigrid::SetFinest(const SparseMatrix& A) {
  if (levels_.empty()) return false;
  Eigen::SparseMatrix<float>& A_f = levels_[0].A_f;
  // The pattern: its size and where each column starts (a pattern change also resets the
  // back end's hierarchy; this catches a caller that did not).
  if (A.cols() != A_f.cols() || A.nonZeros() != A_f.nonZeros() || !A.isCompressed() ||
      !std::equal(A.outerIndexPtr(), A.outerIndexPtr() + A.cols() + 1, A_f.outerIndexPtr())) {
    return false;
  }
  const double* from = A.valuePtr();
  float* to = A_f.valuePtr();
  for (Eigen::Index p = 0; p < A.nonZeros(); ++p) to[p] = static_cast<float>(from[p]);
  std::vector<double> unused;
  if (!InvertDiagonalBlocks(0, A, &unused)) {
    levels_.clear();
    return false;
  }
  return true;
}

bool Multigrid::RefreshFinest() {
  if (levels_.empty()) return false;
  EstimateLambdaMax(0);
  return true;
}

namespace {

using BlockRows = Multigrid::BlockRows;

template <int M, int K, int N>
inline void AddProductFixed(const double* X, const double* Y, double* C) {
  for (int j = 0; j < N; ++j) {
    for (int l = 0; l < K; ++l) {
      const double y = Y[l + K * j];
      for (int i = 0; i < M; ++i) C[i + M * j] += X[i + M * l] * y;
    }
  }
}

// C += X Y for column-major X (m x k), Y (k x n), C (m x n); the sizes of vertex (3) and
// full aggregate (6) nodes with loops of fixed length (the same sums in the same order).
inline void AddProduct(const double* X, int m, int k, const double* Y, int n, double* C) {
  if (k == 3 && n == 6) {
    if (m == 3) return AddProductFixed<3, 3, 6>(X, Y, C);
    if (m == 6) return AddProductFixed<6, 3, 6>(X, Y, C);
  }
  if (m == 6 && k == 6 && n == 6) return AddProductFixed<6, 6, 6>(X, Y, C);
  if (m == 3 && k == 3 && n == 3) return AddProductFixed<3, 3, 3>(X, Y, C);
  for (int j = 0; j < n; ++j) {
    for (int l = 0; l < k; ++l) {
      const double y = Y[l + k * j];
      for (int i = 0; i < m; ++i) C[i + m * j] += X[i + m * l] * y;
    }
  }
}

// Runs row(r, scratch) for r in [0, rows) on `threads` threads (static schedule), each
// thread with its own scratch of `width` ints set to -1.
template <class Row>
void ForRows(int rows, int width, int threads, const Row& row) {
  if (threads > 1 && rows >= 64) {
#pragma omp parallel num_threads(threads)
    {
      std::vector<int> scratch(static_cast<size_t>(width), -1);
#pragma omp for schedule(static)
      for (int r = 0; r < rows; ++r) row(r, &scratch);
    }
  } else {
    std::vector<int> scratch(static_cast<size_t>(width), -1);
    for (int r = 0; r < rows; ++r) row(r, &scratch);
  }
}

// Row r's value offsets from its blocks' column nodes (C.begin, C.col set): C.at and the
// values' total.
void PlaceValues(BlockRows* C) {
  const int rows = static_cast<int>(C->row_size.size());
  C->at.resize(C->col.size());
  size_t total = 0;
  for (int r = 0; r < rows; ++r) {
    for (int q = C->begin[static_cast<size_t>(r)]; q < C->begin[static_cast<size_t>(r) + 1]; ++q) {
      C->at[static_cast<size_t>(q)] = static_cast<int>(total);
      total += static_cast<size_t>(C->row_size[static_cast<size_t>(r)]) *
               static_cast<size_t>(C->col_size[static_cast<size_t>(C->col[static_cast<size_t>(q)])]);
    }
  }
  C->values.assign(total, 0.0);
}

// R's pattern (begin, col, at) and zeroed values: row r's column nodes are the distinct
// ones for_each_column(r, emit) emits, sorted.
template <class ForEachColumn>
void MakePattern(int rows, int cols, int threads, const ForEachColumn& for_each_column, BlockRows* R) {
  std::vector<int> count(static_cast<size_t>(rows), 0);
  ForRows(rows, cols, threads, [&](int r, std::vector<int>* marker) {
    int n = 0;
    for_each_column(r, [&](int h) {
      if ((*marker)[static_cast<size_t>(h)] != r) {
        (*marker)[static_cast<size_t>(h)] = r;
        ++n;
      }
    });
    count[static_cast<size_t>(r)] = n;
  });
  R->begin.assign(static_cast<size_t>(rows) + 1, 0);
  for (int r = 0; r < rows; ++r) {
    R->begin[static_cast<size_t>(r) + 1] = R->begin[static_cast<size_t>(r)] + count[static_cast<size_t>(r)];
  }
  R->col.resize(static_cast<size_t>(R->begin.back()));
  ForRows(rows, cols, threads, [&](int r, std::vector<int>* marker) {
    int q = R->begin[static_cast<size_t>(r)];
    for_each_column(r, [&](int h) {
      if ((*marker)[static_cast<size_t>(h)] != r) {
        (*marker)[static_cast<size_t>(h)] = r;
        R->col[static_cast<size_t>(q++)] = h;
      }
    });
    std::sort(R->col.begin() + R->begin[static_cast<size_t>(r)], R->col.begin() + R->begin[static_cast<size_t>(r) + 1]);
  });
  PlaceValues(R);
}

// A symmetric A (column-major, both triangles) by node blocks: row node i's block A_ij
// holds A's entries with column in node i and row in node j, transposed (= A_ij, as A is
// symmetric).
BlockRows RowsOfSymmetric(const Eigen::SparseMatrix<double>& A, const std::vector<int>& node_begin,
                          int threads) {
  const int nodes = static_cast<int>(node_begin.size()) - 1;
  BlockRows R;
  R.row_size.resize(static_cast<size_t>(nodes));
  for (int k = 0; k < nodes; ++k) {
    R.row_size[static_cast<size_t>(k)] = node_begin[static_cast<size_t>(k) + 1] - node_begin[static_cast<size_t>(k)];
  }
  R.col_size = R.row_size;
  std::vector<int> node_of(static_cast<size_t>(A.cols()));
  for (int k = 0; k < nodes; ++k) {
    for (int c = node_begin[static_cast<size_t>(k)]; c < node_begin[static_cast<size_t>(k) + 1]; ++c) {
      node_of[static_cast<size_t>(c)] = k;
    }
  }
  const int* outer = A.outerIndexPtr();
  const int* inner = A.innerIndexPtr();
  const int* inner_count = A.innerNonZeroPtr();  // null when compressed
  const double* values = A.valuePtr();
  auto column_end = [&](int c) { return inner_count == nullptr ? outer[c + 1] : outer[c] + inner_count[c]; };
  MakePattern(nodes, nodes, threads, [&](int i, const auto& emit) {
    for (int c = node_begin[static_cast<size_t>(i)]; c < node_begin[static_cast<size_t>(i) + 1]; ++c) {
      for (int p = outer[c]; p < column_end(c); ++p) emit(node_of[static_cast<size_t>(inner[p])]);
    }
  }, &R);
  ForRows(nodes, nodes, threads, [&](int i, std::vector<int>* position) {
    for (int q = R.begin[static_cast<size_t>(i)]; q < R.begin[static_cast<size_t>(i) + 1]; ++q) {
      (*position)[static_cast<size_t>(R.col[static_cast<size_t>(q)])] = q;
    }
    const int first = node_begin[static_cast<size_t>(i)];
    const int m = R.row_size[static_cast<size_t>(i)];
    for (int c = first; c < node_begin[static_cast<size_t>(i) + 1]; ++c) {
      for (int p = outer[c]; p < column_end(c); ++p) {
        const int row = inner[p];
        const int j = node_of[static_cast<size_t>(row)];
        const int q = (*position)[static_cast<size_t>(j)];
        R.values[static_cast<size_t>(R.at[static_cast<size_t>(q)] + (c - first) +
                                     m * (row - node_begin[static_cast<size_t>(j)]))] = values[p];
      }
    }
  });
  return R;
}

// C = X Y (X's column nodes are Y's row nodes); each row's blocks summed in X's, then Y's
// order.
BlockRows Multiply(const BlockRows& X, const BlockRows& Y, int threads) {
  const int rows = static_cast<int>(X.row_size.size());
  const int cols = static_cast<int>(Y.col_size.size());
  BlockRows C;
  C.row_size = X.row_size;
  C.col_size = Y.col_size;
  MakePattern(rows, cols, threads, [&](int r, const auto& emit) {
    for (int q = X.begin[static_cast<size_t>(r)]; q < X.begin[static_cast<size_t>(r) + 1]; ++q) {
      const int k = X.col[static_cast<size_t>(q)];
      for (int t = Y.begin[static_cast<size_t>(k)]; t < Y.begin[static_cast<size_t>(k) + 1]; ++t) {
        emit(Y.col[static_cast<size_t>(t)]);
      }
    }
  }, &C);
  ForRows(rows, cols, threads, [&](int r, std::vector<int>* position) {
    for (int q = C.begin[static_cast<size_t>(r)]; q < C.begin[static_cast<size_t>(r) + 1]; ++q) {
      (*position)[static_cast<size_t>(C.col[static_cast<size_t>(q)])] = q;
    }
    const int m = X.row_size[static_cast<size_t>(r)];
    for (int q = X.begin[static_cast<size_t>(r)]; q < X.begin[static_cast<size_t>(r) + 1]; ++q) {
      const int k = X.col[static_cast<size_t>(q)];
      const int s = X.col_size[static_cast<size_t>(k)];
      const double* x = X.values.data() + X.at[static_cast<size_t>(q)];
      for (int t = Y.begin[static_cast<size_t>(k)]; t < Y.begin[static_cast<size_t>(k) + 1]; ++t) {
        const int h = Y.col[static_cast<size_t>(t)];
        double* c = C.values.data() + C.at[static_cast<size_t>((*position)[static_cast<size_t>(h)])];
        AddProduct(x, m, s, Y.values.data() + Y.at[static_cast<size_t>(t)], Y.col_size[static_cast<size_t>(h)], c);
      }
    }
  });
  return C;
}

// X^T by node blocks (each row's blocks in increasing column node).
BlockRows Transpose(const BlockRows& X) {
  const int rows = static_cast<int>(X.row_size.size());
  const int cols = static_cast<int>(X.col_size.size());
  BlockRows T;
  T.row_size = X.col_size;
  T.col_size = X.row_size;
  T.begin.assign(static_cast<size_t>(cols) + 1, 0);
  for (int c : X.col) ++T.begin[static_cast<size_t>(c) + 1];
  for (int c = 0; c < cols; ++c) T.begin[static_cast<size_t>(c) + 1] += T.begin[static_cast<size_t>(c)];
  T.col.resize(X.col.size());
  std::vector<int> next(T.begin.begin(), T.begin.end() - 1);
  std::vector<int> source(X.col.size());  // T's block q is X's block source[q]
  for (int r = 0; r < rows; ++r) {
    for (int q = X.begin[static_cast<size_t>(r)]; q < X.begin[static_cast<size_t>(r) + 1]; ++q) {
      const int slot = next[static_cast<size_t>(X.col[static_cast<size_t>(q)])]++;
      T.col[static_cast<size_t>(slot)] = r;
      source[static_cast<size_t>(slot)] = q;
    }
  }
  PlaceValues(&T);
  for (int c = 0; c < cols; ++c) {
    const int m = T.row_size[static_cast<size_t>(c)];
    for (int q = T.begin[static_cast<size_t>(c)]; q < T.begin[static_cast<size_t>(c) + 1]; ++q) {
      const int n = T.col_size[static_cast<size_t>(T.col[static_cast<size_t>(q)])];
      const double* x = X.values.data() + X.at[static_cast<size_t>(source[static_cast<size_t>(q)])];  // n x m
      double* t = T.values.data() + T.at[static_cast<size_t>(q)];                                      // m x n
      for (int j = 0; j < n; ++j) {
        for (int i = 0; i < m; ++i) t[i + m * j] = x[j + n * i];
      }
    }
  }
  return T;
}

// The column-major matrix M whose columns are R's rows: R is M^T by node blocks, its row
// nodes' unknowns start at col_begin, its column nodes' at row_begin.
Eigen::SparseMatrix<double> ColumnMajorOfTranspose(const BlockRows& R, const std::vector<int>& row_begin,
                                                   const std::vector<int>& col_begin) {
  const int col_nodes = static_cast<int>(R.row_size.size());
  Eigen::SparseMatrix<double> M(row_begin.back(), col_begin.back());
  int64_t nonzeros = 0;
  for (int j = 0; j < col_nodes; ++j) {
    int64_t per_column = 0;
    for (int q = R.begin[static_cast<size_t>(j)]; q < R.begin[static_cast<size_t>(j) + 1]; ++q) {
      per_column += R.col_size[static_cast<size_t>(R.col[static_cast<size_t>(q)])];
    }
    nonzeros += per_column * R.row_size[static_cast<size_t>(j)];
  }
  M.resizeNonZeros(static_cast<Eigen::Index>(nonzeros));
  int* outer = M.outerIndexPtr();
  int* inner = M.innerIndexPtr();
  double* values = M.valuePtr();
  int p = 0;
  outer[0] = 0;
  for (int j = 0; j < col_nodes; ++j) {
    const int m = R.row_size[static_cast<size_t>(j)];
    for (int a = 0; a < m; ++a) {
      for (int q = R.begin[static_cast<size_t>(j)]; q < R.begin[static_cast<size_t>(j) + 1]; ++q) {
        const int h = R.col[static_cast<size_t>(q)];
        const double* block = R.values.data() + R.at[static_cast<size_t>(q)];
        for (int b = 0; b < R.col_size[static_cast<size_t>(h)]; ++b) {
          inner[p] = row_begin[static_cast<size_t>(h)] + b;
          values[p] = block[a + m * b];
          ++p;
        }
      }
      outer[col_begin[static_cast<size_t>(j)] + a + 1] = p;
    }
  }
  return M;
}

}  // namespace

bool Multigrid::Galerkin(const SparseMatrix& A, const std::vector<int>& node_begin, const BlockRows& T,
                         const std::vector<int>& dinv_at, const std::vector<double>& dinv, double omega,
                         int threads, BlockRows* P, BlockRows* Pt, SparseMatrix* Ac) {
  const int nodes = static_cast<int>(node_begin.size()) - 1;
  const BlockRows rows_of_A = RowsOfSymmetric(A, node_begin, threads);
  // P = T - omega D^-1 (A T): A T has every block of T (A's diagonal blocks are there).
  BlockRows prolongator = Multiply(rows_of_A, T, threads);
  std::atomic<bool> complete(true);
  ForRows(nodes, 0, threads, [&](int i, std::vector<int>*) {
    const int m = prolongator.row_size[static_cast<size_t>(i)];
    const double* D = dinv.data() + dinv_at[static_cast<size_t>(i)];
    std::vector<double> column(static_cast<size_t>(m));
    const int t = T.begin[static_cast<size_t>(i)] < T.begin[static_cast<size_t>(i) + 1] ? T.begin[static_cast<size_t>(i)] : -1;
    bool found = t < 0;
    for (int q = prolongator.begin[static_cast<size_t>(i)]; q < prolongator.begin[static_cast<size_t>(i) + 1]; ++q) {
      const int g = prolongator.col[static_cast<size_t>(q)];
      const int n = prolongator.col_size[static_cast<size_t>(g)];
      double* block = prolongator.values.data() + prolongator.at[static_cast<size_t>(q)];
      const double* tentative = nullptr;
      if (t >= 0 && T.col[static_cast<size_t>(t)] == g) {
        tentative = T.values.data() + T.at[static_cast<size_t>(t)];
        found = true;
      }
      for (int j = 0; j < n; ++j) {
        for (int a = 0; a < m; ++a) {
          double s = 0.0;
          for (int b = 0; b < m; ++b) s += D[a + m * b] * block[b + m * j];
          column[static_cast<size_t>(a)] = s;
        }
        for (int a = 0; a < m; ++a) {
          block[a + m * j] = (tentative != nullptr ? tentative[a + m * j] : 0.0) - omega * column[static_cast<size_t>(a)];
        }
      }
    }
    if (!found) complete = false;
  });
  if (!complete) return false;
  BlockRows prolongator_t = Transpose(prolongator);
  BlockRows coarse = Multiply(prolongator_t, Multiply(rows_of_A, prolongator, threads), threads);
  // Symmetric: each pair of blocks (g, h) and (h, g) replaced by their mean.
  const int coarse_nodes = static_cast<int>(coarse.row_size.size());
  for (int g = 0; g < coarse_nodes; ++g) {
    const int m = coarse.row_size[static_cast<size_t>(g)];
    for (int q = coarse.begin[static_cast<size_t>(g)]; q < coarse.begin[static_cast<size_t>(g) + 1]; ++q) {
      const int h = coarse.col[static_cast<size_t>(q)];
      if (h < g) continue;
      const int n = coarse.row_size[static_cast<size_t>(h)];
      const auto first = coarse.col.begin() + coarse.begin[static_cast<size_t>(h)];
      const auto last = coarse.col.begin() + coarse.begin[static_cast<size_t>(h) + 1];
      const auto it = std::lower_bound(first, last, g);
      if (it == last || *it != g) continue;  // (P^T A P's pattern is symmetric)
      double* gh = coarse.values.data() + coarse.at[static_cast<size_t>(q)];                          // m x n
      double* hg = coarse.values.data() + coarse.at[static_cast<size_t>(it - coarse.col.begin())];    // n x m
      for (int j = 0; j < n; ++j) {
        for (int i = 0; i < m; ++i) {
          if (h == g && j <= i) continue;  // a diagonal block: each pair once
          const double mean = 0.5 * (gh[i + m * j] + hg[j + n * i]);
          gh[i + m * j] = mean;
          hg[j + n * i] = mean;
        }
      }
    }
  }
  std::vector<int> coarse_begin(static_cast<size_t>(coarse_nodes) + 1, 0);
  for (int g = 0; g < coarse_nodes; ++g) {
    coarse_begin[static_cast<size_t>(g) + 1] = coarse_begin[static_cast<size_t>(g)] + coarse.row_size[static_cast<size_t>(g)];
  }
  *Ac = ColumnMajorOfTranspose(coarse, coarse_begin, coarse_begin);
  *P = std::move(prolongator);
  *Pt = std::move(prolongator_t);
  return true;
}

bool Multigrid::Build(const SparseMatrix& A0, const Vertices& positions, int threads) {
  levels_.clear();
  coarse_inverse_.resize(0, 0);
  threads_ = std::max(1, threads);
  const int n0 = static_cast<int>(A0.cols());
  if (n0 == 0 || n0 != 3 * positions.rows() || A0.rows() != A0.cols()) return false;

  // The near null space at the finest level: the rigid motions of the positions, about
  // their centroid and in units of their extent (columns of one size).
  Eigen::MatrixXd B = Eigen::MatrixXd::Zero(n0, 6);
  {
    const Eigen::RowVector3d center = positions.colwise().mean();
    double extent = (positions.rowwise() - center).cwiseAbs().maxCoeff();
    if (!(extent > 0.0) || !std::isfinite(extent)) extent = 1.0;
    for (int v = 0; v < positions.rows(); ++v) {
      const Eigen::RowVector3d p = (positions.row(v) - center) / extent;
      for (int d = 0; d < 3; ++d) B(3 * v + d, d) = 1.0;
      // e_k x p
      B(3 * v + 1, 3) = -p.z(); B(3 * v + 2, 3) = p.y();
      B(3 * v + 0, 4) = p.z();  B(3 * v + 2, 4) = -p.x();
      B(3 * v + 0, 5) = -p.y(); B(3 * v + 1, 5) = p.x();
    }
  }
  levels_.reserve(kMaxLevels);
  levels_.emplace_back();
  levels_[0].A_f = A0.cast<float>();
  levels_[0].A_f.makeCompressed();
  levels_[0].node_begin.resize(static_cast<size_t>(positions.rows()) + 1);
  for (size_t k = 0; k < levels_[0].node_begin.size(); ++k) levels_[0].node_begin[k] = 3 * static_cast<int>(k);

  for (int l = 0;; ++l) {
    Level& L = levels_[static_cast<size_t>(l)];
    const SparseMatrix& A = l == 0 ? A0 : L.A;
    const int n = static_cast<int>(A.cols());
    const int nodes = static_cast<int>(L.node_begin.size()) - 1;
    L.nonzeros = static_cast<int>(A.nonZeros());
    const int* outer = A.outerIndexPtr();
    const int* inner = A.innerIndexPtr();
    const double* values = A.valuePtr();
    std::vector<int> node_of(static_cast<size_t>(n));
    for (int k = 0; k < nodes; ++k) {
      for (int i = L.node_begin[static_cast<size_t>(k)]; i < L.node_begin[static_cast<size_t>(k) + 1]; ++i) {
        node_of[static_cast<size_t>(i)] = k;
      }
    }
    std::vector<double> diagonal_norm;
    if (!PrepareSmoother(l, A, &diagonal_norm)) {
      levels_.clear();
      return false;
    }
    if (n <= kCoarsest || l + 1 == kMaxLevels) break;

    // The strong neighbours of each node (b != a with ||A_ab|| above round-off of the
    // diagonal blocks): the tetrahedra's couplings and the data terms', not the explicit
    // zeros of the pattern (fixed vertices, widened stencils).
    std::vector<int> adjacency_begin(static_cast<size_t>(nodes) + 1, 0);
    std::vector<int> adjacency;
    std::vector<double> strength;
    {
      std::vector<double> sum(static_cast<size_t>(nodes), 0.0);
      std::vector<char> seen(static_cast<size_t>(nodes), 0);
      std::vector<int> touched;
      for (int a = 0; a < nodes; ++a) {
        touched.clear();
        for (int c = L.node_begin[static_cast<size_t>(a)]; c < L.node_begin[static_cast<size_t>(a) + 1]; ++c) {
          for (int p = outer[c]; p < outer[c + 1]; ++p) {
            const int b = node_of[static_cast<size_t>(inner[p])];
            if (b == a) continue;
            if (!seen[static_cast<size_t>(b)]) {
              seen[static_cast<size_t>(b)] = 1;
              touched.push_back(b);
            }
            sum[static_cast<size_t>(b)] += values[p] * values[p];
          }
        }
        std::sort(touched.begin(), touched.end());
        for (int b : touched) {
          const double s = std::sqrt(sum[static_cast<size_t>(b)]) /
                           std::sqrt(diagonal_norm[static_cast<size_t>(a)] * diagonal_norm[static_cast<size_t>(b)]);
          sum[static_cast<size_t>(b)] = 0.0;
          seen[static_cast<size_t>(b)] = 0;
          if (s > 1e-10) {
            adjacency.push_back(b);
            strength.push_back(s);
          }
        }
        adjacency_begin[static_cast<size_t>(a) + 1] = static_cast<int>(adjacency.size());
      }
    }
    // Aggregation. -2: no strong neighbour (left to the smoother), -1: not yet aggregated.
    std::vector<int> aggregate(static_cast<size_t>(nodes), -1);
    int aggregates = 0;
    auto neighbours = [&](int a) {
      return std::make_pair(adjacency.data() + adjacency_begin[static_cast<size_t>(a)],
                            adjacency.data() + adjacency_begin[static_cast<size_t>(a) + 1]);
    };
    for (int a = 0; a < nodes; ++a) {
      if (adjacency_begin[static_cast<size_t>(a)] == adjacency_begin[static_cast<size_t>(a) + 1]) {
        aggregate[static_cast<size_t>(a)] = -2;
      }
    }
    for (int a = 0; a < nodes; ++a) {  // a node whose neighbours are all free, with them
      if (aggregate[static_cast<size_t>(a)] != -1) continue;
      const auto nb = neighbours(a);
      bool free = true;
      for (const int* b = nb.first; b != nb.second && free; ++b) free = aggregate[static_cast<size_t>(*b)] == -1;
      if (!free) continue;
      aggregate[static_cast<size_t>(a)] = aggregates;
      for (const int* b = nb.first; b != nb.second; ++b) aggregate[static_cast<size_t>(*b)] = aggregates;
      ++aggregates;
    }
    {  // the rest joins the aggregate it is most strongly connected to
      const std::vector<int> first = aggregate;
      for (int a = 0; a < nodes; ++a) {
        if (aggregate[static_cast<size_t>(a)] != -1) continue;
        double best = 0.0;
        for (int q = adjacency_begin[static_cast<size_t>(a)]; q < adjacency_begin[static_cast<size_t>(a) + 1]; ++q) {
          const int b = adjacency[static_cast<size_t>(q)];
          if (first[static_cast<size_t>(b)] >= 0 && strength[static_cast<size_t>(q)] > best) {
            best = strength[static_cast<size_t>(q)];
            aggregate[static_cast<size_t>(a)] = first[static_cast<size_t>(b)];
          }
        }
      }
    }
    for (int a = 0; a < nodes; ++a) {  // what is left, with its free neighbours
      if (aggregate[static_cast<size_t>(a)] != -1) continue;
      aggregate[static_cast<size_t>(a)] = aggregates;
      const auto nb = neighbours(a);
      for (const int* b = nb.first; b != nb.second; ++b) {
        if (aggregate[static_cast<size_t>(*b)] == -1) aggregate[static_cast<size_t>(*b)] = aggregates;
      }
      ++aggregates;
    }
    if (aggregates == 0) break;

    // The tentative prolongator: per aggregate, the near null space on its unknowns,
    // orthonormalized (modified Gram-Schmidt, twice; a column that is dependent on the ones
    // before it to round-off is dropped: a one-vertex aggregate keeps 3, a collinear one 5).
    std::vector<std::vector<int>> members(static_cast<size_t>(aggregates));
    for (int a = 0; a < nodes; ++a) {
      if (aggregate[static_cast<size_t>(a)] >= 0) members[static_cast<size_t>(aggregate[static_cast<size_t>(a)])].push_back(a);
    }
    // T by node blocks: node a's rows of its aggregate's basis (a row node without an
    // aggregate has none).
    BlockRows T;
    T.row_size.resize(static_cast<size_t>(nodes));
    for (int a = 0; a < nodes; ++a) {
      T.row_size[static_cast<size_t>(a)] = L.node_begin[static_cast<size_t>(a) + 1] - L.node_begin[static_cast<size_t>(a)];
    }
    std::vector<int> t_at(static_cast<size_t>(nodes), -1);
    std::vector<int> coarse_begin(1, 0);
    Eigen::MatrixXd coarse_B(6 * aggregates, 6);
    int coarse_rows = 0;
    for (int g = 0; g < aggregates; ++g) {
      std::vector<int> rows;
      for (int a : members[static_cast<size_t>(g)]) {
        for (int i = L.node_begin[static_cast<size_t>(a)]; i < L.node_begin[static_cast<size_t>(a) + 1]; ++i) rows.push_back(i);
      }
      const int m = static_cast<int>(rows.size());
      Eigen::MatrixXd Bg(m, B.cols());
      for (int i = 0; i < m; ++i) Bg.row(i) = B.row(rows[static_cast<size_t>(i)]);
      Eigen::MatrixXd Q(m, B.cols());
      Eigen::MatrixXd R = Eigen::MatrixXd::Zero(B.cols(), B.cols());
      int kept = 0;
      for (int j = 0; j < B.cols(); ++j) {
        Eigen::VectorXd q = Bg.col(j);
        const double original = q.norm();
        if (!(original > 0.0)) continue;
        Eigen::VectorXd coefficients = Eigen::VectorXd::Zero(kept);
        for (int pass = 0; pass < 2; ++pass) {
          for (int k = 0; k < kept; ++k) {
            const double c = Q.col(k).dot(q);
            q -= c * Q.col(k);
            coefficients[k] += c;
          }
        }
        // Column j is Q times its coefficients (plus q, unless dropped): the coarse near
        // null space keeps them either way (a one-vertex aggregate's rotations are
        // translations there).
        R.block(0, j, kept, 1) = coefficients;
        const double norm = q.norm();
        if (!(norm > 1e-8 * original)) continue;
        Q.col(kept) = q / norm;
        R(kept, j) = norm;
        ++kept;
      }
      if (m < kept) kept = m;
      int row = 0;
      for (int a : members[static_cast<size_t>(g)]) {
        const int size = T.row_size[static_cast<size_t>(a)];
        t_at[static_cast<size_t>(a)] = static_cast<int>(T.values.size());
        for (int k = 0; k < kept; ++k) {
          for (int i = 0; i < size; ++i) T.values.push_back(Q(row + i, k));
        }
        row += size;
      }
      T.col_size.push_back(kept);
      coarse_B.block(coarse_rows, 0, kept, B.cols()) = R.topRows(kept);
      coarse_rows += kept;
      coarse_begin.push_back(coarse_rows);
    }
    if (coarse_rows == 0 || coarse_rows > kStall * n) break;
    T.begin.assign(static_cast<size_t>(nodes) + 1, 0);
    for (int a = 0; a < nodes; ++a) {
      const bool has = aggregate[static_cast<size_t>(a)] >= 0;
      T.begin[static_cast<size_t>(a) + 1] = T.begin[static_cast<size_t>(a)] + (has ? 1 : 0);
      if (has) {
        T.col.push_back(aggregate[static_cast<size_t>(a)]);
        T.at.push_back(t_at[static_cast<size_t>(a)]);
      }
    }
    // Smoothed: P = T - omega D^-1 A T, omega = 4 / (3 lambda_max); A_c = P^T A P.
    const double omega = 4.0 / (3.0 * L.lambda_max);
    SparseMatrix Ac;
    {
      BlockRows P, Pt;
      if (!Galerkin(A, L.node_begin, T, L.dinv_at, L.dinv, omega, threads_, &P, &Pt, &Ac)) {
        levels_.clear();
        return false;
      }
      L.P_b.AssignTransposed(Pt, L.node_begin, coarse_begin);
      L.Pt_b.AssignTransposed(P, coarse_begin, L.node_begin);
    }
    if (l > 0) L.A = SparseMatrix();  // the coarse system's product is built: A_b from here on
    levels_.emplace_back();  // no reallocation: reserved
    Level& C = levels_.back();
    C.A_b.Assign(Ac, coarse_begin, coarse_begin);
    C.A = std::move(Ac);
    C.node_begin = std::move(coarse_begin);
    B = coarse_B.topRows(coarse_rows);
  }
  Level& last = levels_.back();
  const SparseMatrix& A = levels_.size() == 1 ? A0 : last.A;
  if (A.cols() <= kDenseLimit) {
    const Eigen::MatrixXd dense = Eigen::MatrixXd(A);
    Eigen::LDLT<Eigen::MatrixXd> ldlt(dense);
    if (ldlt.info() == Eigen::Success && ldlt.isPositive()) {
      coarse_inverse_ = ldlt.solve(Eigen::MatrixXd::Identity(A.rows(), A.cols()));
      if (!coarse_inverse_.allFinite()) coarse_inverse_.resize(0, 0);
    }
  }
  if (levels_.size() > 1) last.A = SparseMatrix();  // A_b from here on, as above it
  return true;
}

void Multigrid::Smooth(int level, bool zero_start) {
  Level& L = levels_[static_cast<size_t>(level)];
  const double upper = kChebyshevSafety * L.lambda_max;
  const double lower = L.lambda_max / kChebyshevRatio;
  const double theta = 0.5 * (upper + lower);
  const double delta = 0.5 * (upper - lower);
  const double sigma = theta / delta;
  double rho = 1.0 / sigma;
  if (zero_start) {
    L.r = L.b;
  } else {
    Product(level, L.x, &L.ad);
    L.r = L.b - L.ad;
  }
  Eigen::VectorXd& z = L.ad;  // reused: ad is free between products (no allocation per cycle)
  BlockJacobi(L, L.r, &L.d);
  L.d /= theta;
  for (int k = 0; k < kChebyshevDegree; ++k) {
    L.x += L.d;
    if (k + 1 == kChebyshevDegree) break;
    Product(level, L.d, &z);
    L.r -= z;
    BlockJacobi(L, L.r, &z);
    const double rho_next = 1.0 / (2.0 * sigma - rho);
    L.d = (rho_next * rho) * L.d + (2.0 * rho_next / delta) * z;
    rho = rho_next;
  }
}

void Multigrid::Cycle(int level) {
  Level& L = levels_[static_cast<size_t>(level)];
  const int n = L.node_begin.back();
  if (level + 1 == static_cast<int>(levels_.size())) {
    if (coarse_inverse_.rows() == n) {
      L.x.noalias() = coarse_inverse_ * L.b;
    } else {  // too large to solve directly: smoothing only, twice
      L.x.setZero(n);
      Smooth(level, true);
      Smooth(level, false);
    }
    return;
  }
  L.x.setZero(n);
  Smooth(level, true);
  Product(level, L.x, &L.ad);
  L.r = L.b - L.ad;
  Level& C = levels_[static_cast<size_t>(level) + 1];
  L.P_b.Multiply(L.r, threads_, &C.b);
  Cycle(level + 1);
  L.Pt_b.Multiply(C.x, threads_, &L.d);
  L.x += L.d;
  Smooth(level, false);
}

void Multigrid::Apply(const Eigen::VectorXd& r, Eigen::VectorXd* z) {
  if (levels_.empty()) {
    *z = r;
    return;
  }
  levels_[0].b = r;
  Cycle(0);
  *z = levels_[0].x;
}

double Multigrid::grid_complexity() const {
  if (levels_.empty()) return 0.0;
  double total = 0.0;
  for (const Level& L : levels_) total += L.node_begin.back();
  return total / levels_[0].node_begin.back();
}

double Multigrid::operator_complexity() const {
  if (levels_.empty()) return 0.0;
  double total = 0.0;
  for (const Level& L : levels_) total += L.nonzeros;
  return total / levels_[0].nonzeros;
}

}  // namespace fast_backend
}  // namespace femreg
