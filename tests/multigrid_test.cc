// The fast back end's smoothed-aggregation multigrid (solvers/fast/multigrid.h): the
// V-cycle as a preconditioner, the block-sparse products and the Galerkin products.

#include "backend_setup.h"

#include <cmath>
#include <cstring>
#include <limits>

#include "solvers/fast/multigrid_internal.h"

namespace femreg {
namespace {

// A value as the V-cycle stores it below level 0 (and reads level 0's): in bfloat16.
double Bfloat16(double value) {
  using fast_backend::multigrid_internal::FromBfloat16;
  using fast_backend::multigrid_internal::ToBfloat16;
  return FromBfloat16(ToBfloat16(value));
}

// A box's corotational stiffness (R = I) with full 3x3 vertex blocks, plus a diagonal of
// `diagonal` x (1 .. 5); the vertices at x = 0 fixed as the back end fixes them (identity
// rows and columns).
Eigen::SparseMatrix<double> BoxSystem(const TetMesh& mesh, double diagonal) {
  Material material;
  material.youngs_modulus = 5e4;
  material.poisson_ratio = 0.45;
  ElasticModel model;
  model.Build(mesh, ElasticModelType::kCorotational, material);
  std::vector<Eigen::Triplet<double>> t;
  model.AddStiffnessTriplets(&t);
  const int n = 3 * mesh.num_vertices();
  for (int i = 0; i < n; ++i) t.emplace_back(i, i, diagonal * (1 + i % 5));
  Eigen::SparseMatrix<double> H(n, n);
  H.setFromTriplets(t.begin(), t.end());
  H.makeCompressed();
  for (int c = 0; c < n; ++c) {
    for (Eigen::SparseMatrix<double>::InnerIterator it(H, c); it; ++it) {
      if (mesh.rest(c / 3, 0) < 1e-9 || mesh.rest(it.row() / 3, 0) < 1e-9) it.valueRef() = it.row() == c ? 1.0 : 0.0;
    }
  }
  return H;
}

// PCG iterations to a relative residual of 1e-8 with one V-cycle as the preconditioner.
int MultigridPcgIterations(const Eigen::SparseMatrix<double>& H, fast_backend::Multigrid* mg,
                           const Eigen::VectorXd& b, Eigen::VectorXd* x) {
  x->setZero(b.size());
  Eigen::VectorXd r = b, z, q;
  mg->Apply(r, &z);
  Eigen::VectorXd p = z;
  double rz = r.dot(z);
  for (int k = 1; k <= 500; ++k) {
    q = H * p;
    const double alpha = rz / p.dot(q);
    *x += alpha * p;
    r -= alpha * q;
    if (r.norm() <= 1e-8 * b.norm()) return k;
    mg->Apply(r, &z);
    const double rz_next = r.dot(z);
    p = z + (rz_next / rz) * p;
    rz = rz_next;
  }
  return 1000;
}

// The multigrid preconditioner: a symmetric positive definite operator (PCG's requirement;
// symmetric to float round-off: level 0's products sum in single precision), the same on 1
// and 2 threads, and a preconditioner whose PCG iterations do not grow much
// with the mesh (6.8 times the vertices, half the element size: at most 1.6 times the
// iterations; 19 and 26 here), where Jacobi's double with each halving of the element size.
TEST(Multigrid, SymmetricPositiveAndIndependentOfSize) {
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  std::vector<int> iterations;
  for (int k : {5, 10}) {
    const TetMesh mesh = MakeBox(Eigen::Vector3d(0.2, 0.1, 0.05), 4 * k, 2 * k, k);
    const Eigen::SparseMatrix<double> H = BoxSystem(mesh, 1e-2);
    const int n = static_cast<int>(H.rows());
    fast_backend::Multigrid mg;
    ASSERT_TRUE(mg.Build(H, mesh.rest, 1));
    EXPECT_GE(mg.num_levels(), 2) << n << " unknowns";
    EXPECT_LT(mg.operator_complexity(), 2.0);
    Eigen::VectorXd a(n), b(n), ma, mb;
    for (int i = 0; i < n; ++i) a[i] = u(rng), b[i] = u(rng);
    mg.Apply(a, &ma);
    mg.Apply(b, &mb);
    // The same again after another vector: nothing of the last cycle (its work vectors, level
    // 0's float copy of a product's vector) carries into the next.
    Eigen::VectorXd again;
    mg.Apply(a, &again);
    EXPECT_EQ(again, ma);
    EXPECT_NEAR(a.dot(mb), b.dot(ma), 1e-7 * a.norm() * mb.norm());
    EXPECT_GT(a.dot(ma), 0.0);
    EXPECT_GT(b.dot(mb), 0.0);
    // On 2 threads (the products run in parallel from 4096 unknowns or 65536 entries).
    fast_backend::Multigrid two;
    ASSERT_TRUE(two.Build(H, mesh.rest, 2));
    // A system on another pattern is refused, and the hierarchy stays as it was.
    EXPECT_FALSE(two.SetFinest(Eigen::SparseMatrix<double>(n + 3, n + 3)));
    Eigen::VectorXd ma2;
    two.Apply(a, &ma2);
    EXPECT_LE((ma2 - ma).lpNorm<Eigen::Infinity>(), 1e-12 * ma.lpNorm<Eigen::Infinity>());
    Eigen::VectorXd x;
    iterations.push_back(MultigridPcgIterations(H, &mg, b, &x));
    EXPECT_LE((H * x - b).norm(), 1e-8 * b.norm());
  }
  EXPECT_LT(iterations[0], 60);
  EXPECT_LE(iterations[1], 1.6 * iterations[0]) << iterations[0] << " then " << iterations[1];
}

// A hierarchy kept for a later system on its pattern (SetFinest) smooths with that system's
// own block-Jacobi inverses: where data pairs join at some surface vertices (their diagonal
// blocks stiffer by the largest diagonal entry, as a 200 N/m pair on a soft body's vertex),
// PCG with the kept V-cycle converges in 67 iterations (20 on the system it was built for;
// 1000 = not in 500, with the build's inverses, which D^-1 A then had eigenvalues far above
// the bound of: at 16k-64k vertices a quarter of a kept hierarchy's solves failed once and
// were repeated after RefreshFinest).
TEST(Multigrid, AKeptHierarchySmoothsWithTheCurrentDiagonal) {
  const TetMesh mesh = MakeBox(Eigen::Vector3d(0.2, 0.1, 0.05), 20, 10, 5);
  const Eigen::SparseMatrix<double> H = BoxSystem(mesh, 1e-2);
  const int n = static_cast<int>(H.rows());
  fast_backend::Multigrid mg;
  // An uncompressed system (gaps between its columns' values) is refused, as by SetFinest.
  Eigen::SparseMatrix<double> uncompressed = H;
  uncompressed.uncompress();
  EXPECT_FALSE(mg.Build(uncompressed, mesh.rest, 1));
  EXPECT_FALSE(mg.built());
  ASSERT_TRUE(mg.Build(H, mesh.rest, 1));
  EXPECT_FALSE(mg.SetFinest(uncompressed));
  ASSERT_TRUE(mg.Build(H, mesh.rest, 1));
  Eigen::SparseMatrix<double> stiffer = H;
  double largest = 0.0;
  for (int c = 0; c < n; ++c) largest = std::max(largest, stiffer.coeff(c, c));
  for (int v = 0; v < mesh.num_vertices(); v += 7) {
    if (mesh.rest(v, 2) < 0.05 - 1e-9 || mesh.rest(v, 0) < 1e-9) continue;  // the top face, not the clamped end
    for (int d = 0; d < 3; ++d) stiffer.coeffRef(3 * v + d, 3 * v + d) += largest;
  }
  ASSERT_TRUE(mg.SetFinest(stiffer));
  std::mt19937 rng(9);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  for (int trial = 0; trial < 5; ++trial) {
    Eigen::VectorXd a(n), ma;
    for (int i = 0; i < n; ++i) a[i] = u(rng);
    mg.Apply(a, &ma);
    EXPECT_GT(a.dot(ma), 0.0) << "trial " << trial;
  }
  Eigen::VectorXd b(n), x;
  for (int i = 0; i < n; ++i) b[i] = u(rng);
  const int iterations = MultigridPcgIterations(stiffer, &mg, b, &x);
  EXPECT_LT(iterations, 100);
  EXPECT_LE((stiffer * x - b).norm(), 1e-8 * b.norm());
}

// Level 0's values as the V-cycle reads them (multigrid_internal.h): rounded to bfloat16, to
// nearest with ties to even, within 2^-8 of each value (relative), as ToBfloat16 rounds one;
// zeros, signs and infinities kept, float's largest rounded up to infinity, a
// subnormal rounded like the others; the same on 2 threads (enough values for two spans).
TEST(Multigrid, Level0ValuesRoundToBfloat16) {
  auto from_bits = [](uint32_t bits) {
    float f;
    std::memcpy(&f, &bits, sizeof f);
    return static_cast<double>(f);
  };
  const double inf = std::numeric_limits<double>::infinity();
  std::vector<double> from = {
      0.0, -0.0, 1.0, -2.5,
      1.0 + std::ldexp(1.0, -8),        // halfway between 1 and 1 + 2^-7: down, to the even 1
      1.0 + 3.0 * std::ldexp(1.0, -8),  // halfway up to 1 + 2^-6: up, to the even one
      from_bits(0x3fff8000u),           // halfway below 2, from an odd last bit: up across to 2
      from_bits(0x7f7fffffu),           // float's largest: past bfloat16's, to infinity
      std::ldexp(1.5, -133),            // a subnormal halfway: up to 2^-132
      -inf, std::numeric_limits<double>::quiet_NaN()};
  const size_t special = from.size();
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> u(-1e5, 1e5);
  const int64_t spans = 2 * fast_backend::multigrid_internal::kParallelEntries + 1;
  while (static_cast<int64_t>(from.size()) < spans) from.push_back(u(rng));
  const int64_t n = static_cast<int64_t>(from.size());
  std::vector<uint16_t> half(from.size()), half2(from.size());
  fast_backend::multigrid_internal::RoundToBfloat16(from.data(), n, 1, half.data());
  fast_backend::multigrid_internal::RoundToBfloat16(from.data(), n, 2, half2.data());
  EXPECT_EQ(half, half2);
  std::vector<float> to(from.size());
  for (int64_t i = 0; i < n; ++i) {
    to[i] = fast_backend::multigrid_internal::FromBfloat16(half[i]);
    uint32_t bits;
    std::memcpy(&bits, &to[i], sizeof bits);
    ASSERT_EQ(bits >> 16, half[i]) << i;  // widened: the bfloat16 in the upper half
    ASSERT_EQ(bits & 0xffffu, 0u) << i;
    ASSERT_EQ(fast_backend::multigrid_internal::ToBfloat16(from[i]), half[i]) << i;
    if (static_cast<size_t>(i) >= special) {
      ASSERT_LE(std::abs(to[i] - from[i]), std::ldexp(std::abs(from[i]), -8)) << from[i];
    }
  }
  EXPECT_EQ(to[0], 0.0f);
  EXPECT_FALSE(std::signbit(to[0]));
  EXPECT_EQ(to[1], 0.0f);
  EXPECT_TRUE(std::signbit(to[1]));
  EXPECT_EQ(to[2], 1.0f);
  EXPECT_EQ(to[3], -2.5f);
  EXPECT_EQ(to[4], 1.0f);
  EXPECT_EQ(to[5], static_cast<float>(1.0 + std::ldexp(1.0, -6)));
  EXPECT_EQ(to[6], 2.0f);
  EXPECT_EQ(to[7], std::numeric_limits<float>::infinity());
  EXPECT_EQ(to[8], static_cast<float>(std::ldexp(1.0, -132)));
  EXPECT_EQ(to[9], -std::numeric_limits<float>::infinity());
  EXPECT_TRUE(std::isnan(to[10]));
}

// The V-cycle's block storage: random sparse matrices with row and column nodes of 1 to 7
// unknowns (the uniform 3 and 6 of vertices and aggregates take their own loops, the rest
// the general ones) multiply like Eigen's M^T x on their values rounded to bfloat16 (to
// float's precision: the fixed loops sum in float), and the same on 2 threads.
TEST(Multigrid, NodeBlocksMultiplyLikeTheSparseMatrix) {
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  auto partition = [&](const std::vector<int>& sizes, int repeat) {
    std::vector<int> begin(1, 0);
    for (int k = 0; k < repeat; ++k) {
      for (int m : sizes) begin.push_back(begin.back() + m);
    }
    return begin;
  };
  // Mixed: rows vertices (3) then mixed, columns aggregates (6), mixed, one of 7 (the general
  // loop, mostly); then the shapes the hierarchy makes, every block of a column alike (the
  // fixed loops, single precision with SSE): 6 by 6 (a coarse system), 3 by 6 (P^T from
  // vertices), 6 by 3 (P into vertices).
  struct Shape {
    std::vector<int> rows, cols;
  };
  const Shape shapes[] = {{partition({3, 3, 3, 3, 1, 2, 4, 5, 6, 7}, 60), partition({6, 6, 6, 3, 2, 1, 4, 5, 7}, 50)},
                          {partition({6}, 300), partition({6}, 300)},
                          {partition({3}, 600), partition({6}, 200)},
                          {partition({6}, 200), partition({3}, 400)}};
  for (const Shape& shape : shapes) {
    const int rows = shape.rows.back(), cols = shape.cols.back();
    std::vector<Eigen::Triplet<double>> entries;
    for (int j = 0; j < cols; ++j) {
      for (int k = 0; k < 40; ++k) entries.emplace_back(static_cast<int>(rng() % rows), j, u(rng));
    }
    Eigen::SparseMatrix<double> M(rows, cols);
    M.setFromTriplets(entries.begin(), entries.end());
    fast_backend::Multigrid::NodeBlocks blocks;
    blocks.Assign(M, shape.rows, shape.cols);
    Eigen::VectorXd x(rows);
    for (int i = 0; i < rows; ++i) x[i] = u(rng);
    Eigen::SparseMatrix<double> rounded = M;
    for (int k = 0; k < rounded.nonZeros(); ++k) rounded.valuePtr()[k] = Bfloat16(rounded.valuePtr()[k]);
    const Eigen::VectorXd expected = rounded.transpose() * x;
    // Per entry, a sum of ~40 products of magnitude <= 1: in float, well within 1e-5.
    Eigen::VectorXd y1, y2;
    blocks.Multiply(x, 1, &y1);
    ASSERT_EQ(y1.size(), cols);
    EXPECT_LE((y1 - expected).lpNorm<Eigen::Infinity>(), 1e-5 * expected.lpNorm<Eigen::Infinity>())
        << rows << " by " << cols;
    blocks.Multiply(x, 2, &y2);
    EXPECT_EQ((y1 - y2).lpNorm<Eigen::Infinity>(), 0.0);
  }
}

// The hierarchy's construction by node blocks: P = T - omega D^-1 A T and A_c = P^T A P
// (symmetrized) from a random symmetric A whose nodes have 3 or 6 unknowns (a vertex, a full
// aggregate) or others (the general loops), some nodes without an aggregate, against the
// same products with dense matrices; the same bits on 2 threads; and P's and P^T's block
// storage (NodeBlocks::AssignTransposed) multiplying like P itself.
TEST(Multigrid, GalerkinProductsMatchTheDenseOnes) {
  using BlockRows = fast_backend::Multigrid::BlockRows;
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  const std::vector<int> sizes = {3, 3, 6, 3, 2, 6, 3, 5, 3, 3, 1, 6, 3, 4, 3, 3};
  const int nodes = 48, aggregates = 9;
  std::vector<int> node_begin(1, 0);
  for (int k = 0; k < nodes; ++k) node_begin.push_back(node_begin.back() + sizes[static_cast<size_t>(k) % sizes.size()]);
  const int n = node_begin.back();
  // A: symmetric, block pattern random (about 1 in 5 pairs of nodes), every diagonal block.
  Eigen::MatrixXd A = Eigen::MatrixXd::Zero(n, n);
  for (int a = 0; a < nodes; ++a) {
    for (int b = a; b < nodes; ++b) {
      if (a != b && rng() % 5 != 0) continue;
      for (int i = node_begin[a]; i < node_begin[a + 1]; ++i) {
        for (int j = node_begin[b]; j < node_begin[b + 1]; ++j) A(i, j) = A(j, i) = u(rng);
      }
    }
  }
  Eigen::SparseMatrix<double> A_sparse = A.sparseView(0.0, 0.0);
  A_sparse.makeCompressed();
  // T: node k in aggregate k % aggregates, except every 7th node (none); each aggregate's
  // column count 6, or 1 to 5.
  BlockRows T;
  std::vector<int> coarse_begin(1, 0);
  for (int g = 0; g < aggregates; ++g) {
    T.col_size.push_back(g % 3 == 0 ? 1 + g % 5 : 6);
    coarse_begin.push_back(coarse_begin.back() + T.col_size.back());
  }
  Eigen::MatrixXd T_dense = Eigen::MatrixXd::Zero(n, coarse_begin.back());
  T.begin.assign(1, 0);
  for (int k = 0; k < nodes; ++k) {
    const int m = node_begin[k + 1] - node_begin[k];
    T.row_size.push_back(m);
    if (k % 7 != 3) {
      const int g = k % aggregates;
      T.col.push_back(g);
      T.at.push_back(static_cast<int>(T.values.size()));
      for (int j = 0; j < T.col_size[g]; ++j) {
        for (int i = 0; i < m; ++i) {
          T.values.push_back(u(rng));
          T_dense(node_begin[k] + i, coarse_begin[g] + j) = T.values.back();
        }
      }
    }
    T.begin.push_back(static_cast<int>(T.col.size()));
  }
  // D^-1: any blocks will do for the algebra.
  std::vector<int> dinv_at;
  std::vector<double> dinv;
  Eigen::MatrixXd D_dense = Eigen::MatrixXd::Zero(n, n);
  for (int k = 0; k < nodes; ++k) {
    const int m = node_begin[k + 1] - node_begin[k];
    dinv_at.push_back(static_cast<int>(dinv.size()));
    for (int j = 0; j < m; ++j) {
      for (int i = 0; i < m; ++i) {
        dinv.push_back(u(rng));
        D_dense(node_begin[k] + i, node_begin[k] + j) = dinv.back();
      }
    }
  }
  const double omega = 0.7;
  const Eigen::MatrixXd P_expected = T_dense - omega * D_dense * A * T_dense;
  Eigen::MatrixXd Ac_expected = P_expected.transpose() * A * P_expected;
  Ac_expected = (0.5 * (Ac_expected + Ac_expected.transpose())).eval();

  auto dense = [](const BlockRows& R, const std::vector<int>& row_begin, const std::vector<int>& col_begin) {
    Eigen::MatrixXd M = Eigen::MatrixXd::Zero(row_begin.back(), col_begin.back());
    for (size_t r = 0; r + 1 < R.begin.size(); ++r) {
      for (int q = R.begin[r]; q < R.begin[r + 1]; ++q) {
        EXPECT_TRUE(q == R.begin[r] || R.col[q - 1] < R.col[q]) << "row " << r << " not sorted";
        const int c = R.col[q], m = R.row_size[r];
        for (int j = 0; j < R.col_size[c]; ++j) {
          for (int i = 0; i < m; ++i) M(row_begin[r] + i, col_begin[c] + j) = R.values[R.at[q] + i + m * j];
        }
      }
    }
    return M;
  };
  BlockRows P1, Pt1, P2, Pt2;
  Eigen::SparseMatrix<double> Ac1, Ac2;
  ASSERT_TRUE(fast_backend::Multigrid::Galerkin(A_sparse, node_begin, T, dinv_at, dinv, omega, 1, &P1, &Pt1, &Ac1));
  const double scale = Ac_expected.cwiseAbs().maxCoeff();
  EXPECT_LE((dense(P1, node_begin, coarse_begin) - P_expected).cwiseAbs().maxCoeff(),
            1e-13 * P_expected.cwiseAbs().maxCoeff());
  EXPECT_LE((dense(Pt1, coarse_begin, node_begin) - P_expected.transpose()).cwiseAbs().maxCoeff(),
            1e-13 * P_expected.cwiseAbs().maxCoeff());
  const Eigen::MatrixXd Ac1_dense = Eigen::MatrixXd(Ac1);
  EXPECT_LE((Ac1_dense - Ac_expected).cwiseAbs().maxCoeff(), 1e-12 * scale);
  EXPECT_EQ((Ac1_dense - Ac1_dense.transpose()).cwiseAbs().maxCoeff(), 0.0);  // symmetric exactly
  for (int c = 0; c < Ac1.outerSize(); ++c) {  // rows sorted in every column
    for (int p = Ac1.outerIndexPtr()[c] + 1; p < Ac1.outerIndexPtr()[c + 1]; ++p) {
      EXPECT_LT(Ac1.innerIndexPtr()[p - 1], Ac1.innerIndexPtr()[p]);
    }
  }
  ASSERT_TRUE(fast_backend::Multigrid::Galerkin(A_sparse, node_begin, T, dinv_at, dinv, omega, 2, &P2, &Pt2, &Ac2));
  EXPECT_EQ(P1.values, P2.values);
  EXPECT_EQ(P1.col, P2.col);
  EXPECT_EQ(Eigen::MatrixXd(Ac2), Ac1_dense);
  // The V-cycle's storage of P (gathers P^T x) and P^T (gathers P x).
  fast_backend::Multigrid::NodeBlocks p_blocks, pt_blocks;
  p_blocks.AssignTransposed(Pt1, node_begin, coarse_begin);
  pt_blocks.AssignTransposed(P1, coarse_begin, node_begin);
  Eigen::VectorXd x(n), y(coarse_begin.back()), px, ptx;
  for (int i = 0; i < n; ++i) x[i] = u(rng);
  for (int i = 0; i < y.size(); ++i) y[i] = u(rng);
  p_blocks.Multiply(x, 1, &ptx);   // P^T x
  pt_blocks.Multiply(y, 1, &px);   // P y
  // Against P's values rounded to bfloat16, as the V-cycle stores them: the same numbers in P
  // and P^T (the V-cycle stays symmetric).
  const Eigen::MatrixXd P_rounded = P_expected.unaryExpr([](double v) { return Bfloat16(v); });
  const Eigen::VectorXd ptx_expected = P_rounded.transpose() * x, px_expected = P_rounded * y;
  EXPECT_LE((ptx - ptx_expected).lpNorm<Eigen::Infinity>(), 1e-5 * ptx_expected.lpNorm<Eigen::Infinity>());
  EXPECT_LE((px - px_expected).lpNorm<Eigen::Infinity>(), 1e-5 * px_expected.lpNorm<Eigen::Infinity>());
  // A row node of T without A's diagonal block is refused.
  Eigen::SparseMatrix<double> no_diagonal = A_sparse;
  for (int c = node_begin[5]; c < node_begin[6]; ++c) {
    for (Eigen::SparseMatrix<double>::InnerIterator it(no_diagonal, c); it; ++it) {
      if (it.row() >= node_begin[5] && it.row() < node_begin[6]) it.valueRef() = 0.0;
    }
  }
  no_diagonal.prune(0.0);
  BlockRows P3, Pt3;
  Eigen::SparseMatrix<double> Ac3;
  EXPECT_FALSE(fast_backend::Multigrid::Galerkin(no_diagonal, node_begin, T, dinv_at, dinv, omega, 1, &P3, &Pt3, &Ac3));
}

}  // namespace
}  // namespace femreg
