// The fast back end's own supernodal factorization and substitutions on CHOLMOD's analysis
// (solvers/fast/supernodal_solve.h), against CHOLMOD's own solves.

#include <Eigen/Eigenvalues>
#include <Eigen/LU>

#include "backend_setup.h"

namespace femreg {
namespace {

using backend_testing::BeamsSystem;


// PCG's preconditioner, the back end's own substitutions with CHOLMOD's supernodal factor,
// solve the factorized system: in double to round-off, in float (the factor's values, and
// also the substitutions' work with set_single_work) to float's precision, on
// 1, 2 and 3 threads (the elimination tree cut into groups of subtrees, the same cut on any
// thread count), the same result, bit for bit, on every run and every thread count. The
// matrix: two beams' stiffness (a forest of two trees) plus a diagonal.
TEST(FastBackend, OwnSubstitutionsSolveTheFactorizedSystem) {
  const Eigen::SparseMatrix<double> H = BeamsSystem({{12, 5e4}, {7, 5e4}}, 1e-2);
  const int offset = static_cast<int>(H.rows());
  fast_backend::CholmodFactor llt;
  llt.setMode(Eigen::CholmodSupernodalLLt);
  llt.compute(H);
  ASSERT_EQ(llt.info(), Eigen::Success);
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  Eigen::VectorXd b(offset);
  for (int i = 0; i < offset; ++i) b[i] = u(rng);
  const Eigen::VectorXd expected = llt.solve(b);
  const double scale = expected.lpNorm<Eigen::Infinity>();
  Eigen::VectorXd first_x, first_y, first_w;
  for (int threads : {1, 2, 3}) {
    fast_backend::SupernodalSolve<double> exact;
    exact.set_cut_from(0);  // cut however small
    ASSERT_TRUE(exact.Load(*llt.raw(), true, threads));
    Eigen::VectorXd x;
    exact.Solve(b, &x);
    EXPECT_LE((x - expected).lpNorm<Eigen::Infinity>(), 1e-10 * scale) << threads << " threads";
    EXPECT_GT(exact.serial_fraction(), 0.0);
    EXPECT_LT(exact.serial_fraction(), 1.0);
    fast_backend::SupernodalSolve<float> single;
    single.set_cut_from(0);
    ASSERT_TRUE(single.Load(*llt.raw(), true, threads));
    Eigen::VectorXd y, again;
    single.Solve(b, &y);
    EXPECT_LE((y - expected).lpNorm<Eigen::Infinity>(), 1e-3 * scale) << threads << " threads";
    EXPECT_GT((y - expected).lpNorm<Eigen::Infinity>(), 0.0);  // float values, not a copy
    single.Solve(b, &again);
    EXPECT_EQ(y, again);
    // The substitutions in float (set_single_work): float's precision still, other bits.
    fast_backend::SupernodalSolve<float> single_work;
    single_work.set_cut_from(0);
    single_work.set_single_work(true);
    ASSERT_TRUE(single_work.Load(*llt.raw(), true, threads));
    Eigen::VectorXd w, w_again;
    single_work.Solve(b, &w);
    // Float sums add float's round-off once more: within a few times the float factor's error.
    const double factor_error = (y - expected).lpNorm<Eigen::Infinity>();
    EXPECT_LE((w - expected).lpNorm<Eigen::Infinity>(), 10.0 * factor_error) << threads << " threads";
    EXPECT_NE(w, y);
    single_work.Solve(b, &w_again);
    // Float work's reruns and thread counts agree far inside float's own error.
    const double same = 1e-3 * factor_error;
    EXPECT_LE((w - w_again).lpNorm<Eigen::Infinity>(), same);
    if (threads == 1) {
      first_x = x;
      first_y = y;
      first_w = w;
    } else {  // the same bits on every thread count
      EXPECT_EQ(x, first_x) << threads << " threads";
      EXPECT_EQ(y, first_y) << threads << " threads";
      EXPECT_LE((w - first_w).lpNorm<Eigen::Infinity>(), same) << threads << " threads";
    }
    // Uncut (the default below 100k entries of L): the serial order.
    fast_backend::SupernodalSolve<float> uncut;
    ASSERT_TRUE(uncut.Load(*llt.raw(), true, threads));
    EXPECT_EQ(uncut.serial_fraction(), 1.0);
    // New values on the same structure: the copy follows them.
    Eigen::SparseMatrix<double> H2 = 2.0 * H;
    llt.factorize(H2);
    ASSERT_TRUE(exact.Load(*llt.raw(), false, threads));
    exact.Solve(b, &x);
    EXPECT_LE((x - 0.5 * expected).lpNorm<Eigen::Infinity>(), 1e-10 * scale) << threads << " threads";
    ASSERT_TRUE(single_work.Load(*llt.raw(), false, threads));
    single_work.Solve(b, &w);
    EXPECT_LE((w - 0.5 * expected).lpNorm<Eigen::Infinity>(), 5.0 * factor_error) << threads << " threads";
    llt.factorize(H);
  }
  // A failed factorization (not positive definite): refused.
  Eigen::SparseMatrix<double> indefinite = -H;
  llt.factorize(indefinite);
  ASSERT_NE(llt.info(), Eigen::Success);
  fast_backend::SupernodalSolve<float> failed;
  EXPECT_FALSE(failed.Load(*llt.raw(), false, 2));
  EXPECT_FALSE(failed.loaded());
  // Not a supernodal LL^T factor: refused.
  fast_backend::CholmodFactor simplicial;
  simplicial.setMode(Eigen::CholmodSimplicialLLt);
  simplicial.compute(H);
  fast_backend::SupernodalSolve<float> refused;
  EXPECT_FALSE(refused.Load(*simplicial.raw(), true, 1));
  EXPECT_FALSE(refused.loaded());
}

// The back end's own factorization, on CHOLMOD's symbolic analysis alone: its solves match
// CHOLMOD's double ones (in double to round-off, in float to float's precision), on 1, 2
// and 3 threads (the subtrees of one cut in parallel) with the same factor on each; new values on the
// same structure; a matrix that is not positive definite refused. The structure may also
// come from a numeric factor. The matrix: two beams' stiffness (a forest of two trees), one
// four times stiffer, plus a diagonal (a data term's share).
// CHOLMOD's factor of H (numeric and symbolic) and its solve of a random b: what the own
// factorization is checked against.
struct CholmodReference {
  fast_backend::CholmodFactor exact, symbolic;
  Eigen::VectorXd b, expected;
  double scale = 0.0;
  bool ok = false;
  CholmodReference(const Eigen::SparseMatrix<double>& H, unsigned seed) {
    exact.setMode(Eigen::CholmodSupernodalLLt);
    exact.compute(H);
    symbolic.setMode(Eigen::CholmodSupernodalLLt);
    symbolic.analyzePattern(H);
    std::mt19937 rng(seed);
    std::uniform_real_distribution<double> u(-1.0, 1.0);
    b.resize(H.rows());
    for (Eigen::Index i = 0; i < H.rows(); ++i) b[i] = u(rng);
    ok = exact.info() == Eigen::Success && symbolic.raw() != nullptr;
    if (!ok) return;
    expected = exact.solve(b);
    scale = expected.lpNorm<Eigen::Infinity>();
  }
};

TEST(FastBackend, OwnFactorizationSolvesLikeCholmod) {
  const Eigen::SparseMatrix<double> H = BeamsSystem({{14, 5e4}, {9, 2e5}}, 1.0);
  const int offset = static_cast<int>(H.rows());
  const CholmodReference reference(H, 5);
  ASSERT_TRUE(reference.ok);
  const fast_backend::CholmodFactor& exact = reference.exact;
  const fast_backend::CholmodFactor& symbolic = reference.symbolic;
  const Eigen::VectorXd& b = reference.b;
  const Eigen::VectorXd& expected = reference.expected;
  const double scale = reference.scale;
  std::vector<float> first;
  for (int threads : {1, 2, 3}) {
    const ScopedThreads one_blas_thread(1);
    fast_backend::SupernodalSolve<double> in_double;
    in_double.set_cut_from(0);  // cut however small
    ASSERT_TRUE(in_double.Factorize(*symbolic.raw(), H, true, threads)) << threads << " threads";
    ASSERT_TRUE(in_double.loaded());
    Eigen::VectorXd x;
    in_double.Solve(b, &x);
    EXPECT_LE((x - expected).lpNorm<Eigen::Infinity>(), 1e-9 * scale) << threads << " threads";
    // In float: the error of a float factorization, its relative round-off times the
    // condition number (the PCG it preconditions corrects it).
    fast_backend::SupernodalSolve<float> in_float;
    in_float.set_cut_from(0);
    ASSERT_TRUE(in_float.Factorize(*symbolic.raw(), H, true, threads)) << threads << " threads";
    Eigen::VectorXd y;
    in_float.Solve(b, &y);
    EXPECT_LE((y - expected).lpNorm<Eigen::Infinity>(), 3e-3 * scale) << threads << " threads";
    EXPECT_GT((y - expected).lpNorm<Eigen::Infinity>(), 0.0);  // float, not CHOLMOD's values
    // Its substitutions in float too (the classic step's PCG): about as close.
    in_float.set_single_work(true);
    Eigen::VectorXd w;
    in_float.Solve(b, &w);
    EXPECT_LE((w - expected).lpNorm<Eigen::Infinity>(), 10.0 * (y - expected).lpNorm<Eigen::Infinity>());
    EXPECT_NE(w, y);
    in_float.set_single_work(false);
    // The same factor on every thread count, with the subtrees in parallel on more than one
    // (no supernode large enough for tiles: TiledFactorizationSolvesLikeCholmod).
    EXPECT_EQ(in_float.tiled_supernodes(), 0);
    EXPECT_LT(in_float.serial_fraction(), 1.0) << threads << " threads";
    if (threads == 1) {
      first = in_float.values();
    } else {
      EXPECT_TRUE(in_float.values() == first) << threads << " threads: another factor";
    }
    // New values on the same structure.
    const Eigen::SparseMatrix<double> H2 = 4.0 * H;
    ASSERT_TRUE(in_double.Factorize(*symbolic.raw(), H2, false, threads));
    in_double.Solve(b, &x);
    EXPECT_LE((x - 0.25 * expected).lpNorm<Eigen::Infinity>(), 1e-9 * scale) << threads << " threads";
    // Not positive definite: refused, nothing kept; and back.
    const Eigen::SparseMatrix<double> indefinite = -H;
    EXPECT_FALSE(in_float.Factorize(*symbolic.raw(), indefinite, false, threads));
    EXPECT_FALSE(in_float.loaded());
    ASSERT_TRUE(in_float.Factorize(*symbolic.raw(), H, false, threads));
    EXPECT_TRUE(in_float.values() == first) << threads << " threads";
  }
  // Another pattern with as many entries, without a new structure: planned again, not
  // scattered through the old plan (entry (0, 1) dropped, (0, n - 1) added, both triangles).
  {
    const ScopedThreads one_blas_thread(1);
    fast_backend::SupernodalSolve<double> reused;
    ASSERT_TRUE(reused.Factorize(*exact.raw(), H, true, 1));
    std::vector<Eigen::Triplet<double>> u;
    for (int c = 0; c < H.outerSize(); ++c) {
      for (Eigen::SparseMatrix<double>::InnerIterator it(H, c); it; ++it) {
        if ((it.row() == 0 && it.col() == 1) || (it.row() == 1 && it.col() == 0)) continue;
        u.emplace_back(it.row(), it.col(), it.value());
      }
    }
    ASSERT_EQ(H.coeff(0, offset - 1), 0.0);
    u.emplace_back(0, offset - 1, 0.0);
    u.emplace_back(offset - 1, 0, 0.0);
    Eigen::SparseMatrix<double> moved(offset, offset);
    moved.setFromTriplets(u.begin(), u.end());
    moved.makeCompressed();
    ASSERT_EQ(moved.nonZeros(), H.nonZeros());
    // (0, n - 1) joins the two beams, outside L's pattern: refused rather than written
    // through the old plan.
    EXPECT_FALSE(reused.Factorize(*exact.raw(), moved, false, 1));
  }
  // The structure of a numeric factor serves as well.
  {
    const ScopedThreads one_blas_thread(1);
    fast_backend::SupernodalSolve<double> from_numeric;
    ASSERT_TRUE(from_numeric.Factorize(*exact.raw(), H, true, 2));
    Eigen::VectorXd x;
    from_numeric.Solve(b, &x);
    EXPECT_LE((x - expected).lpNorm<Eigen::Infinity>(), 1e-9 * scale);
  }
  // A matrix with entries outside the analysed pattern: refused.
  {
    Eigen::SparseMatrix<double> wider = H;
    wider.coeffRef(0, offset - 1) = 1e-3;
    wider.coeffRef(offset - 1, 0) = 1e-3;
    wider.makeCompressed();
    fast_backend::SupernodalSolve<float> refused;
    EXPECT_FALSE(refused.Factorize(*symbolic.raw(), wider, true, 1));
    EXPECT_FALSE(refused.loaded());
  }
}

// The top's supernodes of many rows are factorized in tiles on the whole team. With tiles
// of 4 and 7 rows on a beam (every supernode of the top tiled, panels of several widths,
// their tasks shared among 2 and 3 threads, one after the other on 1), and of 44 (a top of
// tiled and untiled supernodes; the root, 87 rows, untiled): the solves match CHOLMOD's,
// every thread count gives the same factor, and a matrix that fails in the last supernode
// (the root, in the top) is refused.
TEST(FastBackend, TiledFactorizationSolvesLikeCholmod) {
  const Eigen::SparseMatrix<double> H = BeamsSystem({{20, 5e4}}, 1.0);
  const int n = static_cast<int>(H.rows());
  const CholmodReference reference(H, 11);
  ASSERT_TRUE(reference.ok);
  const fast_backend::CholmodFactor& symbolic = reference.symbolic;
  const Eigen::VectorXd& b = reference.b;
  const Eigen::VectorXd& expected = reference.expected;
  const double scale = reference.scale;
  // Not positive definite in its last pivot: the variable eliminated last, made negative.
  const int last = static_cast<const int*>(symbolic.raw()->Perm)[n - 1];
  Eigen::SparseMatrix<double> indefinite = H;
  indefinite.coeffRef(last, last) = -1e9;
  const ScopedThreads one_blas_thread(1);
  std::map<int, int> all_tiled;  // threads -> the top's supernodes with tiles of 4 rows
  for (int tile : {4, 7, 44}) {
    std::vector<float> on_one_thread;
    for (int threads : {1, 2, 3}) {
      SCOPED_TRACE(::testing::Message() << "tiles of " << tile << " rows, " << threads << " threads");
      fast_backend::SupernodalSolve<double> in_double;
      in_double.set_tile_rows(tile);
      in_double.set_cut_from(0);  // cut however small
      ASSERT_TRUE(in_double.Factorize(*symbolic.raw(), H, true, threads));
      EXPECT_GT(in_double.tiled_supernodes(), 0);
      if (tile == 4) all_tiled[threads] = in_double.tiled_supernodes();
      if (tile == 44) {  // a mixed top
        EXPECT_LT(in_double.tiled_supernodes(), all_tiled[threads]);
      }
      Eigen::VectorXd x;
      in_double.Solve(b, &x);
      EXPECT_LE((x - expected).lpNorm<Eigen::Infinity>(), 1e-9 * scale);
      fast_backend::SupernodalSolve<float> in_float;
      in_float.set_tile_rows(tile);
      in_float.set_cut_from(0);
      ASSERT_TRUE(in_float.Factorize(*symbolic.raw(), H, true, threads));
      Eigen::VectorXd y;
      in_float.Solve(b, &y);
      EXPECT_LE((y - expected).lpNorm<Eigen::Infinity>(), 3e-3 * scale);
      EXPECT_GT(in_float.serial_fraction(), 0.0);  // a top, run by the team
      EXPECT_LT(in_float.serial_fraction(), 1.0);
      const std::vector<float> first = in_float.values();
      if (threads == 1) {
        on_one_thread = first;
      } else {
        EXPECT_TRUE(first == on_one_thread) << "another factor than on one thread";
      }
      ASSERT_TRUE(in_float.Factorize(*symbolic.raw(), 2.0 * H, false, threads));
      ASSERT_TRUE(in_float.Factorize(*symbolic.raw(), H, false, threads));
      EXPECT_TRUE(in_float.values() == first) << "another factor on the same threads";
      EXPECT_FALSE(in_double.Factorize(*symbolic.raw(), indefinite, false, threads));
      EXPECT_FALSE(in_double.loaded());
      ASSERT_TRUE(in_double.Factorize(*symbolic.raw(), H, false, threads));
      in_double.Solve(b, &x);
      EXPECT_LE((x - expected).lpNorm<Eigen::Infinity>(), 1e-9 * scale);
    }
  }
}

// The largest entry of |a - b| (sizes equal) and of |a|, for factors' values.
double LargestDifference(const std::vector<float>& a, const std::vector<float>& b) {
  EXPECT_EQ(a.size(), b.size());
  double largest = 0.0;
  for (size_t k = 0; k < std::min(a.size(), b.size()); ++k) {
    largest = std::max(largest, std::abs(static_cast<double>(a[k]) - static_cast<double>(b[k])));
  }
  return largest;
}
double LargestValue(const std::vector<float>& a) {
  double largest = 0.0;
  for (float v : a) largest = std::max(largest, std::abs(static_cast<double>(v)));
  return largest;
}

// The factorization of a symmetric matrix that is not positive definite (the equilibrium
// solve's stiffness in compression): A = P^T L S L^T P without pivoting, S the pivots' signs.
// A beam's stiffness less a shift between its 5th and 6th eigenvalues has 5 negative
// eigenvalues, so (Sylvester's law of inertia) 5 negative pivots; its solves match a dense
// solve, on an uncut and a cut tree alike. A positive definite matrix has none, and solves as
// the Cholesky factorization does; a zero pivot is refused; Factorize afterwards is LL^T again.
TEST(FastBackend, OwnIndefiniteFactorizationSolvesTheShiftedSystem) {
  const Eigen::SparseMatrix<double> H = BeamsSystem({{6, 5e4}}, 1.0);
  const Eigen::MatrixXd dense = Eigen::MatrixXd(H);
  const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eigen(dense);
  ASSERT_EQ(eigen.info(), Eigen::Success);
  const double shift = 0.5 * (eigen.eigenvalues()[4] + eigen.eigenvalues()[5]);
  Eigen::SparseMatrix<double> identity(H.rows(), H.cols());
  identity.setIdentity();
  const Eigen::SparseMatrix<double> A = H - shift * identity;
  ASSERT_EQ(A.nonZeros(), H.nonZeros());  // the same pattern (H has its whole diagonal)
  fast_backend::CholmodFactor symbolic;
  symbolic.setMode(Eigen::CholmodSupernodalLLt);
  symbolic.analyzePattern(A);
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  Eigen::VectorXd b(A.rows());
  for (Eigen::Index i = 0; i < A.rows(); ++i) b[i] = u(rng);
  const Eigen::VectorXd expected = Eigen::MatrixXd(A).partialPivLu().solve(b);
  const double scale = expected.lpNorm<Eigen::Infinity>();
  const ScopedThreads one_blas_thread(1);
  for (int64_t cut_from : {int64_t{1} << 40, int64_t{0}}) {
    fast_backend::SupernodalSolve<double> in_double;
    in_double.set_cut_from(cut_from);
    ASSERT_TRUE(in_double.FactorizeIndefinite(*symbolic.raw(), A, true, 1)) << cut_from;
    EXPECT_EQ(in_double.negative_pivots(), 5) << cut_from;
    Eigen::VectorXd x;
    in_double.Solve(b, &x);
    EXPECT_LE((x - expected).lpNorm<Eigen::Infinity>(), 1e-8 * scale) << cut_from;
    fast_backend::SupernodalSolve<float> in_float;
    in_float.set_cut_from(cut_from);
    ASSERT_TRUE(in_float.FactorizeIndefinite(*symbolic.raw(), A, true, 1)) << cut_from;
    EXPECT_EQ(in_float.negative_pivots(), 5) << cut_from;
    Eigen::VectorXd y;
    in_float.Solve(b, &y);
    EXPECT_LE((y - expected).lpNorm<Eigen::Infinity>(), 5e-2 * scale) << cut_from;
    EXPECT_GT((y - expected).lpNorm<Eigen::Infinity>(), 0.0);
    // The cut's groups on 2 and 3 threads: the same factor and signs as on one (bit for bit
    // by construction; compared within a float's rounding, far below what a race would leave).
    for (int threads : {2, 3}) {
      fast_backend::SupernodalSolve<float> on_team;
      on_team.set_cut_from(cut_from);
      ASSERT_TRUE(on_team.FactorizeIndefinite(*symbolic.raw(), A, true, threads)) << cut_from;
      EXPECT_LE(LargestDifference(on_team.values(), in_float.values()), 1e-6 * LargestValue(in_float.values()))
          << cut_from << ", " << threads << " threads: another factor";
      EXPECT_EQ(on_team.negative_pivots(), 5) << cut_from << ", " << threads << " threads";
      Eigen::VectorXd w;
      on_team.Solve(b, &w);
      EXPECT_LE((w - y).lpNorm<Eigen::Infinity>(), 1e-6 * y.lpNorm<Eigen::Infinity>()) << cut_from << ", " << threads << " threads";
    }
    // Positive definite: no negative pivot, the Cholesky factorization's solve.
    ASSERT_TRUE(in_double.FactorizeIndefinite(*symbolic.raw(), H, false, 1));
    EXPECT_EQ(in_double.negative_pivots(), 0);
    Eigen::VectorXd z;
    in_double.Solve(b, &z);
    const Eigen::VectorXd h_expected = Eigen::MatrixXd(H).llt().solve(b);
    EXPECT_LE((z - h_expected).lpNorm<Eigen::Infinity>(), 1e-8 * h_expected.lpNorm<Eigen::Infinity>());
    // Its factor is the Cholesky one (every diagonal block by LAPACK's Cholesky), in float too.
    fast_backend::SupernodalSolve<float> cholesky;
    cholesky.set_cut_from(cut_from);
    ASSERT_TRUE(cholesky.Factorize(*symbolic.raw(), H, true, 1));
    ASSERT_TRUE(in_float.FactorizeIndefinite(*symbolic.raw(), H, false, 1));
    EXPECT_EQ(in_float.negative_pivots(), 0);
    EXPECT_EQ(in_float.perturbed_pivots(), 0);
    EXPECT_LE(LargestDifference(in_float.values(), cholesky.values()), 1e-6 * LargestValue(cholesky.values()))
        << cut_from;
    // Factorize is L L^T again (no signs kept): the indefinite A is refused, H solves.
    EXPECT_FALSE(in_double.Factorize(*symbolic.raw(), A, false, 1));
    ASSERT_TRUE(in_double.Factorize(*symbolic.raw(), H, false, 1));
    EXPECT_EQ(in_double.negative_pivots(), 0);
    in_double.Solve(b, &z);
    EXPECT_LE((z - h_expected).lpNorm<Eigen::Infinity>(), 1e-8 * h_expected.lpNorm<Eigen::Infinity>());
  }
  // Negative pivots inside the cut's groups, not only in its top (a shift between the 41st and
  // 42nd eigenvalues: 41 of them): on teams of 2 and 3 the same factor, signs, counts and
  // solves as on one thread; a value that is not finite fails on a team as on one thread.
  {
    const double deep = 0.5 * (eigen.eigenvalues()[40] + eigen.eigenvalues()[41]);
    const Eigen::SparseMatrix<double> D = H - deep * identity;
    fast_backend::SupernodalSolve<double> exact;
    exact.set_cut_from(0);
    ASSERT_TRUE(exact.FactorizeIndefinite(*symbolic.raw(), D, true, 3));
    EXPECT_EQ(exact.negative_pivots(), 41);
    fast_backend::SupernodalSolve<float> one;
    one.set_cut_from(0);
    ASSERT_TRUE(one.FactorizeIndefinite(*symbolic.raw(), D, true, 1));
    EXPECT_LT(one.serial_fraction(), 1.0);  // the tree is cut
    Eigen::VectorXd y1;
    one.Solve(b, &y1);
    for (int threads : {2, 3}) {
      fast_backend::SupernodalSolve<float> on_team;
      on_team.set_cut_from(0);
      ASSERT_TRUE(on_team.FactorizeIndefinite(*symbolic.raw(), D, true, threads)) << threads << " threads";
      EXPECT_LE(LargestDifference(on_team.values(), one.values()), 1e-6 * LargestValue(one.values()))
          << threads << " threads: another factor";
      EXPECT_EQ(on_team.negative_pivots(), one.negative_pivots()) << threads << " threads";
      EXPECT_EQ(on_team.perturbed_pivots(), one.perturbed_pivots()) << threads << " threads";
      Eigen::VectorXd w;
      on_team.Solve(b, &w);
      EXPECT_LE((w - y1).lpNorm<Eigen::Infinity>(), 1e-6 * y1.lpNorm<Eigen::Infinity>()) << threads << " threads";
      Eigen::SparseMatrix<double> broken = D;
      broken.coeffRef(5, 5) = std::numeric_limits<double>::quiet_NaN();
      EXPECT_FALSE(on_team.FactorizeIndefinite(*symbolic.raw(), broken, false, threads)) << threads << " threads";
      EXPECT_FALSE(on_team.loaded());
      EXPECT_EQ(on_team.negative_pivots(), 0);
    }
  }
  // A zero pivot (a row and column of zeros, in the same pattern): replaced by the floor,
  // and counted; the other unknowns solve as before (the zero column is decoupled), that
  // one gets b's component over the floor. A value that is not finite: refused.
  Eigen::SparseMatrix<double> singular = A;
  for (Eigen::Index c = 0; c < singular.outerSize(); ++c) {
    for (Eigen::SparseMatrix<double>::InnerIterator it(singular, c); it; ++it) {
      if (it.row() == 3 || it.col() == 3) it.valueRef() = 0.0;
    }
  }
  Eigen::MatrixXd reduced = Eigen::MatrixXd(singular);
  reduced(3, 3) = 1.0;
  Eigen::VectorXd b0 = b;
  b0[3] = 0.0;
  const Eigen::VectorXd reduced_expected = reduced.partialPivLu().solve(b0);
  fast_backend::SupernodalSolve<double> floored;
  ASSERT_TRUE(floored.FactorizeIndefinite(*symbolic.raw(), singular, true, 1));
  EXPECT_EQ(floored.perturbed_pivots(), 1);
  const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> reduced_eigen(reduced);
  EXPECT_EQ(floored.negative_pivots(), (reduced_eigen.eigenvalues().array() < 0.0).count());
  Eigen::VectorXd x0;
  floored.Solve(b0, &x0);
  EXPECT_LE((x0 - reduced_expected).lpNorm<Eigen::Infinity>(), 1e-8 * reduced_expected.lpNorm<Eigen::Infinity>());
  Eigen::SparseMatrix<double> not_finite = A;
  not_finite.coeffRef(5, 5) = std::numeric_limits<double>::quiet_NaN();
  EXPECT_FALSE(floored.FactorizeIndefinite(*symbolic.raw(), not_finite, false, 1));
  EXPECT_FALSE(floored.loaded());
  EXPECT_EQ(floored.negative_pivots(), 0);
}

}  // namespace
}  // namespace femreg
