#include "solvers/fast/multigrid.h"

#include <Eigen/Cholesky>
#include <Eigen/Dense>
#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <type_traits>
#include <vector>

#ifdef __SSE2__
#include <emmintrin.h>
#endif

#include "parallel/pool.h"
#include "solvers/fast/fast_backend.h"
#include "solvers/fast/multigrid_internal.h"

namespace femreg {
namespace fast_backend {

namespace {

using multigrid_internal::kParallelEntries;
using multigrid_internal::kParallelVectorEntries;
using multigrid_internal::kParallelNonzeros;
using multigrid_internal::kParallelUnknowns;

// Chebyshev smoothing: degree, and the interval [lambda_max / kChebyshevRatio,
// kChebyshevSafety lambda_max] of D^-1 A it damps (lambda_max from power iterations: an
// estimate above it only weakens the smoothing; one more than ~10 % below it can make the
// V-cycle indefinite, which PCG notices (r.z <= 0) and the back end answers by refreshing
// the estimate, then by a new hierarchy).
constexpr int kChebyshevDegree = 2;
constexpr double kChebyshevRatio = 30.0;
constexpr double kChebyshevSafety = 1.1;
constexpr int kPowerIterations = 15;

using SparseMatrix = Eigen::SparseMatrix<double>;

// Level 0's product y = A v in single precision: A's values in bfloat16 (`half`, its columns
// from column_starts; the back end's layout: both triangles, full 3x3 vertex blocks whose
// three columns share their rows), v rounded once into `v4` (4 floats per vertex, the 4th
// 0), and each column's sum in float.
// With SSE2, a 3x3 block's column is four bfloat16 widened to floats and one 4-lane
// multiply-add whose 4th lane reads the next stored entry (times that 0; the lane is dropped
// from the sum, so even a non-finite entry there changes nothing); the last vertex, whose
// third column's next entry is past the end, is summed entry by entry (so is every vertex
// without SSE2).
// The V-cycle is an approximation of A^-1 to begin with, and PCG, in double with A itself,
// corrects it (as mixed-precision AMG does, e.g. AmgX's float preconditioner for double
// solves); what float sums cost is the V-cycle's symmetry beyond ~1e-8 relative
// (tests/multigrid_test.cc), which PCG does not see at its tolerance; float sums made the product and
// the V-cycle faster than double sums (docs/notes/2026-11-28-figures-from-code-comments.md).
// Each column's sums run in a fixed order: the same result on any number of threads. The
// blocks' rows come from `block_rows` (energy::BlockRowVertices of A): A's per-entry row
// indices stay unread.
void FloatBlockProduct(const std::vector<int>& column_starts, const std::vector<uint16_t>& half,
                       const std::vector<int>& block_rows, const Eigen::VectorXd& v, int threads,
                       int parallel_from, std::vector<float>* v4, Eigen::VectorXd* y) {
  const int blocks = static_cast<int>(column_starts.size() - 1) / 3;
  const int* outer = column_starts.data();
  const uint16_t* halves = half.data();
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
#ifdef __SSE2__
    if (lanes) {
      const uint16_t* h0 = halves + begin;
      const uint16_t* h1 = h0 + stride;
      const uint16_t* h2 = h1 + stride;
      const int* at = block_rows.data() + begin / 9;
      __m128 s0 = _mm_setzero_ps(), s1 = _mm_setzero_ps(), s2 = _mm_setzero_ps();
      for (int k = 0, q = 0; k < stride; k += 3, ++q) {
        const __m128 pa = _mm_loadu_ps(p + 4 * at[q]);
        s0 = _mm_add_ps(s0, _mm_mul_ps(multigrid_internal::LoadBfloat16x4(h0 + k), pa));
        s1 = _mm_add_ps(s1, _mm_mul_ps(multigrid_internal::LoadBfloat16x4(h1 + k), pa));
        s2 = _mm_add_ps(s2, _mm_mul_ps(multigrid_internal::LoadBfloat16x4(h2 + k), pa));
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
    const int* at = block_rows.data() + begin / 9;
    BlockColumnSums(
        halves + begin, stride, [p, at](int q) { return p + 4 * at[q]; }, sums,
        [](uint16_t h) { return multigrid_internal::FromBfloat16(h); });
    for (int j = 0; j < 3; ++j) yy[3 * b + j] = sums[j];
  };
  if (threads > 1 && blocks >= parallel_from) {
    // Pieces, not halves: a mesh generator numbers the interior vertices (with more neighbours)
    // last, and a static half each left one thread 1.6 times the entries of the other.
    ParallelFor(threads, blocks, 1, [&](int64_t b) { convert(static_cast<int>(b)); });
    ParallelFor(threads, blocks, 1, [&](int64_t b) { column(static_cast<int>(b), b + 1 < blocks); });
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

}  // namespace

namespace multigrid_internal {

void RoundToBfloat16(const double* from, int64_t n, int threads, uint16_t* half) {
  ParallelSpans(threads, n, kParallelEntries, [from, half](int64_t begin, int64_t end) {
    for (int64_t p = begin; p < end; ++p) half[p] = ToBfloat16(from[p]);
  });
}

}  // namespace multigrid_internal

void Multigrid::Product(int level, const Eigen::VectorXd& v, Eigen::VectorXd* y) {
  Level& L = levels_[static_cast<size_t>(level)];
  if (level == 0) {
    FloatBlockProduct(L.outer, L.A_h, L.block_rows, v, threads_, kParallelUnknowns / 3, &v4_, y);
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
    ParallelFor(threads_, nodes, 1, [&](int64_t k) { node(static_cast<int>(k)); });
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
    ParallelFor(threads_, nodes, 1, [&](int64_t k) {
      if (!node(static_cast<int>(k))) positive = false;
    });
  } else {
    for (int k = 0; k < nodes && positive; ++k) {
      if (!node(k)) positive = false;
    }
  }
  return positive;
}

bool Multigrid::SetFinest(const SparseMatrix& A) {
  if (levels_.empty()) return false;
  const std::vector<int>& outer = levels_[0].outer;
  // The pattern: its size and where each column starts (a pattern change also resets the
  // back end's hierarchy; this catches a caller that did not).
  if (static_cast<size_t>(A.cols()) + 1 != outer.size() || !A.isCompressed() ||
      !std::equal(A.outerIndexPtr(), A.outerIndexPtr() + A.cols() + 1, outer.begin())) {
    return false;
  }
  std::vector<uint16_t>& A_h = levels_[0].A_h;
  A_h.resize(static_cast<size_t>(A.nonZeros()));
  multigrid_internal::RoundToBfloat16(A.valuePtr(), A.nonZeros(), threads_, A_h.data());
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

void Multigrid::Smooth(int level, bool zero_start) {
  Level& L = levels_[static_cast<size_t>(level)];
  const double upper = kChebyshevSafety * L.lambda_max;
  const double lower = L.lambda_max / kChebyshevRatio;
  const double theta = 0.5 * (upper + lower);
  const double delta = 0.5 * (upper - lower);
  const double sigma = theta / delta;
  double rho = 1.0 / sigma;
  // The vector updates in spans on the team on the finer levels: each entry depends on its own
  // index only, and each span is the Eigen expression the whole vector had, so every thread
  // count gives the same bits.
  const Eigen::Index n = L.b.size();
  eigen_assert(L.x.size() == n);
  auto spans = [&](auto&& update) {
    ParallelSpans(threads_, n, kParallelVectorEntries, [&update](int64_t begin, int64_t end) {
      update(static_cast<Eigen::Index>(begin), static_cast<Eigen::Index>(end - begin));
    });
  };
  L.r.resize(n);
  if (zero_start) {
    spans([&](Eigen::Index b, Eigen::Index m) { L.r.segment(b, m) = L.b.segment(b, m); });
  } else {
    Product(level, L.x, &L.ad);
    spans([&](Eigen::Index b, Eigen::Index m) {
      L.r.segment(b, m) = L.b.segment(b, m) - L.ad.segment(b, m);
    });
  }
  Eigen::VectorXd& z = L.ad;  // reused: ad is free between products (no allocation per cycle)
  BlockJacobi(L, L.r, &L.d);
  spans([&](Eigen::Index b, Eigen::Index m) { L.d.segment(b, m) /= theta; });
  for (int k = 0; k < kChebyshevDegree; ++k) {
    spans([&](Eigen::Index b, Eigen::Index m) { L.x.segment(b, m) += L.d.segment(b, m); });
    if (k + 1 == kChebyshevDegree) break;
    Product(level, L.d, &z);
    spans([&](Eigen::Index b, Eigen::Index m) { L.r.segment(b, m) -= z.segment(b, m); });
    BlockJacobi(L, L.r, &z);
    const double rho_next = 1.0 / (2.0 * sigma - rho);
    spans([&](Eigen::Index b, Eigen::Index m) {
      L.d.segment(b, m) =
          (rho_next * rho) * L.d.segment(b, m) + (2.0 * rho_next / delta) * z.segment(b, m);
    });
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
