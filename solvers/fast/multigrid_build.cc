// The multigrid hierarchy's construction (Multigrid::Build): strength, aggregation, the
// near null space, the tentative and smoothed prolongators, the coarse systems and the
// coarsest level's dense inverse (multigrid.h has the method).
#include <Eigen/Cholesky>
#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <vector>

#include "energy/assembler.h"
#include "solvers/fast/fast_backend.h"
#include "solvers/fast/multigrid.h"
#include "solvers/fast/multigrid_internal.h"

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

using SparseMatrix = Eigen::SparseMatrix<double>;

}  // namespace

bool Multigrid::Build(const SparseMatrix& A0, const Vertices& positions, int threads) {
  levels_.clear();
  coarse_inverse_.resize(0, 0);
  threads_ = std::max(1, threads);
  const int n0 = static_cast<int>(A0.cols());
  // Compressed, as SetFinest requires: its column starts bound the values here and below.
  if (n0 == 0 || n0 != 3 * positions.rows() || A0.rows() != A0.cols() || !A0.isCompressed()) return false;
  // The level-0 product reads one row per 3x3 block.
  if (!energy::FullVertexBlocks(A0)) return false;

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
  levels_[0].outer.assign(A0.outerIndexPtr(), A0.outerIndexPtr() + A0.cols() + 1);
  levels_[0].A_h.resize(static_cast<size_t>(A0.nonZeros()));
  multigrid_internal::RoundToBfloat16(A0.valuePtr(), A0.nonZeros(), threads_, levels_[0].A_h.data());
  levels_[0].block_rows = energy::BlockRowVertices(A0);
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

}  // namespace fast_backend
}  // namespace femreg
