// The multigrid's block-sparse storage and its products: NodeBlocks (the V-cycle's matrices
// below level 0, by dense node blocks, and their gathers), BlockRows (a matrix by rows of
// node blocks) and the Galerkin product P^T A P formed with them.
#include <Eigen/Dense>
#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstdint>
#include <type_traits>
#include <vector>

#ifdef __SSE2__
#include <emmintrin.h>
#endif

#include "parallel/pool.h"
#include "solvers/fast/fast_backend.h"
#include "solvers/fast/multigrid.h"
#include "solvers/fast/multigrid_internal.h"

namespace femreg {
namespace fast_backend {

namespace {

using multigrid_internal::FromBfloat16;
using multigrid_internal::kParallelNonzeros;
using multigrid_internal::kParallelUnknowns;
using multigrid_internal::ToBfloat16;
using SparseMatrix = Eigen::SparseMatrix<double>;

// One column node's gather, any block shapes, in double: y_j = sum over its blocks B
// (row_count x nc, column-major, bfloat16) of B(:, j) . x(rows of B).
void GatherNode(const uint16_t* values, const int* value_at, const int* row_first, const int* row_count,
                int begin, int end, int nc, const double* x, double* y) {
  for (int j = 0; j < nc; ++j) {
    double s = 0.0;
    for (int k = begin; k < end; ++k) {
      const uint16_t* B = values + value_at[k] + j * row_count[k];
      const double* xr = x + row_first[k];
      for (int i = 0; i < row_count[k]; ++i) s += static_cast<double>(FromBfloat16(B[i])) * xr[i];
    }
    y[j] = s;
  }
}

// The shapes the hierarchy makes (R x C blocks, every block of the column node alike) in
// single precision: the values widened from bfloat16, x in float and the column's sum in
// float; with SSE2, each block's column one 4-lane multiply-add per 4 of its rows (6 rows:
// 4 + 2 lanes; 3 rows: 3 lanes, the 4th reads the next stored value and is dropped), else
// entry by entry (see FloatBlockProduct: ~1e-7 relative). `values` holds 4 more than its
// blocks (the last block's 4th lane). With FloatBlockProduct at level 0, float sums made a
// whole V-cycle faster than double sums (docs/notes/2026-11-28-figures-from-code-comments.md).
template <int R, int C>
void GatherNodeFloat(const uint16_t* values, const int* value_at, const int* row_first, int begin, int end,
                     const float* x, double* y) {
  static_assert((R == 3 || R == 6) && C >= 1 && C <= 6, "the shapes the hierarchy makes");
#ifdef __SSE2__
  using multigrid_internal::LoadBfloat16x2;
  using multigrid_internal::LoadBfloat16x4;
  __m128 acc[C];
  for (int j = 0; j < C; ++j) acc[j] = _mm_setzero_ps();
  for (int k = begin; k < end; ++k) {
    const uint16_t* B = values + value_at[k];
    const float* xr = x + row_first[k];
    if constexpr (R == 6) {
      const __m128 lo = _mm_loadu_ps(xr);
      const __m128 hi = _mm_loadl_pi(_mm_setzero_ps(), reinterpret_cast<const __m64*>(xr + 4));
      for (int j = 0; j < C; ++j) {
        acc[j] = _mm_add_ps(acc[j], _mm_add_ps(_mm_mul_ps(LoadBfloat16x4(B + 6 * j), lo),
                                                 _mm_mul_ps(LoadBfloat16x2(B + 6 * j + 4), hi)));
      }
    } else {
      const __m128 x3 = _mm_movelh_ps(_mm_loadl_pi(_mm_setzero_ps(), reinterpret_cast<const __m64*>(xr)),
                                      _mm_load_ss(xr + 2));
      for (int j = 0; j < C; ++j) acc[j] = _mm_add_ps(acc[j], _mm_mul_ps(LoadBfloat16x4(B + 3 * j), x3));
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
    const uint16_t* B = values + value_at[k];
    const float* xr = x + row_first[k];
    for (int j = 0; j < C; ++j) {
      for (int i = 0; i < R; ++i) acc[j] += FromBfloat16(B[j * R + i]) * xr[i];
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
      values.resize(values.size() + static_cast<size_t>(nr) * static_cast<size_t>(nc), 0);
    }
    for (int j = c0; j < c0 + nc; ++j) {
      for (int p = outer[j]; p < column_end(j); ++p) {
        const int i = inner[p];
        const int r = node_of_row[static_cast<size_t>(i)];
        const int nr = row_nodes[static_cast<size_t>(r) + 1] - row_nodes[static_cast<size_t>(r)];
        values[static_cast<size_t>(block_of[static_cast<size_t>(r)] + (j - c0) * nr +
                                   (i - row_nodes[static_cast<size_t>(r)]))] = ToBfloat16(v[p]);
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
  values.resize(values.size() + 4, 0);  // the last block's 4th lane (GatherNodeFloat)
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
  values.assign(R.values.size() + 4, 0);  // 4 more: the last block's 4th lane (GatherNodeFloat)
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
      uint16_t* to = values.data() + R.at[k];
      for (int j = 0; j < nc; ++j) {
        for (int i = 0; i < nr; ++i) to[i + nr * j] = ToBfloat16(from[j + nc * i]);
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
  const uint16_t* v = values.data();
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
    ParallelFor(threads, n, 1, [&](int64_t i) { xf[i] = static_cast<float>(xx[i]); });
    ParallelFor(threads, nodes, 1, [&](int64_t c) { node(static_cast<int>(c)); });
  } else {
    for (int i = 0; i < n; ++i) xf[i] = static_cast<float>(xx[i]);
    for (int c = 0; c < nodes; ++c) node(c);
  }
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

// Runs row(r, scratch) for r in [0, rows) on `threads` threads, in 16 pieces, each piece with
// its own scratch of `width` ints set to -1.
template <class Row>
void ForRows(int rows, int width, int threads, const Row& row) {
  if (threads > 1 && rows >= 64) {
    ParallelRanges(threads, rows, SpanGrain(rows), [&](int64_t begin, int64_t end) {
      std::vector<int> scratch(static_cast<size_t>(width), -1);
      for (int64_t r = begin; r < end; ++r) row(static_cast<int>(r), &scratch);
    });
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

}  // namespace fast_backend
}  // namespace femreg
