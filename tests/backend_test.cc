// Both back ends reach the same minimum of the same energy::Problem: every term (corotational
// elastic, edge springs, data point-to-point and point-to-plane through each robust loss,
// temporal and anchor springs, contacts against an obstacle and between objects, hard-fixed
// vertices), from the same start.

#include "backend_setup.h"
#include "energy/assembler.h"

namespace femreg {
namespace {

using backend_testing::BeamsSystem;
using backend_testing::ExpectSameEnergies;
using backend_testing::MakeSetup;
using backend_testing::Minimize;
using backend_testing::Setup;
using energy::TermGroup;

struct Case {
  RobustLoss loss;
  bool springs, fixed, contacts;
  bool loads = false;
  bool neo_hookean = false;
};

class BackendTest : public ::testing::TestWithParam<Case> {};

TEST_P(BackendTest, BothReachTheSameMinimum) {
  const Case c = GetParam();
  auto s = MakeSetup(c.loss, c.springs, c.fixed, c.contacts, 3, c.loads, 1, c.neo_hookean);
  const Vertices start = s->mesh.rest;
  const Vertices x_ceres = Minimize(SolverBackend::kCeres, s->problem, start);
  const Vertices x_fast = Minimize(SolverBackend::kFast, s->problem, start);
  const double e_ceres = s->problem.Evaluate(x_ceres).total();
  const double e_fast = s->problem.Evaluate(x_fast).total();
  const double e_start = s->problem.Evaluate(start).total();
  ASSERT_GT(e_start - e_ceres, 1e-6) << "the problem must not start at its minimum";
  if (c.contacts) {
    EXPECT_GT(s->problem.Evaluate(x_ceres).collision, 0.0);
  }
  if (c.loads) {  // the loads pull the beam down against the data
    auto unloaded = MakeSetup(c.loss, c.springs, c.fixed, c.contacts, 3, false);
    const Vertices x_unloaded = Minimize(SolverBackend::kFast, unloaded->problem, start);
    EXPECT_LT(x_fast.col(2).mean(), x_unloaded.col(2).mean() - 1e-4);
  }
  // Both stop where a step no longer lowers the energy by 1e-15 relative: their energies
  // agree to far better than 1e-7, their positions to well under a micrometre.
  EXPECT_NEAR(e_fast, e_ceres, 1e-7 * e_ceres + 1e-12);
  // Tukey is not convex: the two may stop in different (equally good) minima.
  if (c.loss != RobustLoss::kTukey) {
    EXPECT_LT((x_fast - x_ceres).cwiseAbs().maxCoeff(), 1e-6);
  }
  if (c.fixed) {
    for (int v = 0; v < start.rows(); ++v) {
      if (s->problem.is_fixed(v)) {
        EXPECT_EQ((x_fast.row(v) - start.row(v)).norm(), 0.0);
        EXPECT_EQ((x_ceres.row(v) - start.row(v)).norm(), 0.0);
      }
    }
  }
}

INSTANTIATE_TEST_SUITE_P(AllTerms, BackendTest,
                         ::testing::Values(Case{RobustLoss::kNone, false, false, false},
                                           Case{RobustLoss::kHuber, false, false, false},
                                           Case{RobustLoss::kCauchy, false, true, false},
                                           Case{RobustLoss::kTukey, false, false, false},
                                           Case{RobustLoss::kHuber, true, true, false},
                                           Case{RobustLoss::kHuber, false, false, true},
                                           Case{RobustLoss::kNone, true, true, true},
                                           Case{RobustLoss::kHuber, false, true, false, true},
                                           Case{RobustLoss::kNone, true, true, true, true},
                                           Case{RobustLoss::kHuber, false, true, false, false, true},
                                           Case{RobustLoss::kNone, false, false, true, true, true}));

// The PCG product: full 3x3 vertex blocks on a random symmetric pattern (some vertices with
// no neighbour), against Eigen's product, serial and on 2 threads above the parallel size.
TEST(FastBackend, BlockProductIsTheMatrixProduct) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  for (int vertices : {5, 9000}) {
    std::vector<Eigen::Triplet<double>> t;
    auto block = [&](int a, int b) {
      for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j) {
          const double v = u(rng);
          t.emplace_back(3 * a + i, 3 * b + j, v);
          t.emplace_back(3 * b + j, 3 * a + i, v);
        }
    };
    for (int v = 0; v < vertices; ++v) block(v, v);
    std::uniform_int_distribution<int> pick(0, vertices - 1);
    for (int k = 0; k < 4 * vertices; ++k) {
      const int a = pick(rng), b = pick(rng);
      if (a != b) block(a, b);
    }
    Eigen::SparseMatrix<double> H(3 * vertices, 3 * vertices);
    H.setFromTriplets(t.begin(), t.end());
    H.makeCompressed();
    Eigen::VectorXd p(3 * vertices);
    for (int i = 0; i < p.size(); ++i) p[i] = u(rng);
    const Eigen::VectorXd expected = H * p;
    // One row vertex per 3x3 block, from the matrix's layout.
    ASSERT_TRUE(energy::FullVertexBlocks(H));
    const std::vector<int> block_rows = energy::BlockRowVertices(H);
    ASSERT_EQ(static_cast<Eigen::Index>(9 * block_rows.size()), H.nonZeros());
    for (int threads : {1, 2}) {
      Eigen::VectorXd y;
      fast_backend::BlockProduct(H, block_rows, p, threads, &y);
      ASSERT_EQ(y.size(), expected.size());
      EXPECT_LE((y - expected).lpNorm<Eigen::Infinity>(), 1e-12 * expected.lpNorm<Eigen::Infinity>())
          << vertices << " vertices, " << threads << " threads";
    }
    // An entry short of a full block is not that layout.
    Eigen::SparseMatrix<double> partial = H;
    partial.coeffRef(0, 0) = 0.0;
    partial.prune([](Eigen::Index r, Eigen::Index c, double) { return !(r == 2 && c == 1); });
    partial.makeCompressed();
    EXPECT_FALSE(energy::FullVertexBlocks(partial)) << vertices << " vertices";
  }
}

// The fast back end with the multigrid preconditioner reaches the minimum the factor's
// reaches, on a mesh large enough for a hierarchy (2352 unknowns: two levels), every term
// included, with hard-fixed vertices (rows of the identity: left to the smoother).
TEST(FastBackend, MultigridReachesTheFactorsMinimum) {
  for (const Case& c : {Case{RobustLoss::kHuber, true, true, true}, Case{RobustLoss::kNone, false, false, false, true}}) {
    auto s = MakeSetup(c.loss, c.springs, c.fixed, c.contacts, 3, c.loads, 3);
    ASSERT_GT(3 * s->mesh.num_vertices(), 2000);
    const Vertices start = s->mesh.rest;
    const Vertices x_factor = Minimize(SolverBackend::kFast, s->problem, start, Preconditioner::kFactor);
    SolveReport report;
    const Vertices x_multigrid =
        Minimize(SolverBackend::kFast, s->problem, start, Preconditioner::kMultigrid, &report);
    // Every step by multigrid: a hierarchy, no factorization (the fallback).
    EXPECT_GE(report.iterations, 2);
    EXPECT_GE(report.hierarchies, 1);
    EXPECT_EQ(report.factorizations, 0);
    EXPECT_GE(report.pcg_iterations, report.iterations);
    const double e_start = s->problem.Evaluate(start).total();
    const double e_factor = s->problem.Evaluate(x_factor).total();
    const double e_multigrid = s->problem.Evaluate(x_multigrid).total();
    ASSERT_GT(e_start - e_factor, 1e-6);
    EXPECT_NEAR(e_multigrid, e_factor, 1e-7 * e_factor);
    EXPECT_LT((x_multigrid - x_factor).cwiseAbs().maxCoeff(), 1e-6);
  }
}

// `auto` takes the factor on a small mesh (its factor holds few entries per entry of the
// system) and multigrid on a compact one of 5239 vertices (the factor would fill in).
TEST(FastBackend, AutoTakesMultigridWhereTheFactorFillsIn) {
  for (int refine : {1, 6}) {
    auto s = MakeSetup(RobustLoss::kHuber, false, true, false, 3, false, refine);
    BackendOptions options;
    options.type = SolverBackend::kFast;
    ASSERT_EQ(options.preconditioner, Preconditioner::kAuto);
    Vertices x = s->mesh.rest;
    const SolveReport report = MakeBackend(options)->Solve(s->problem, 0.0, &x);
    ASSERT_TRUE(report.success) << report.message;
    // The fill decides, from CHOLMOD's analysis (below 8192 vertices no estimate is made).
    EXPECT_EQ(report.analyses, 1);
    if (refine == 1) {
      EXPECT_EQ(report.hierarchies, 0);
      EXPECT_GE(report.factorizations, 1);
    } else {
      ASSERT_GT(s->mesh.num_vertices(), 5000);
      EXPECT_GE(report.hierarchies, 1);
      EXPECT_EQ(report.factorizations, 0);
      // Even with a switch its fill clears by far
      // (docs/notes/2026-11-28-figures-from-code-comments.md), the analysis: too small a mesh for
      // the estimate to pay.
      options.multigrid_fill = 2.0;
      Vertices y = s->mesh.rest;
      const SolveReport with = MakeBackend(options)->Solve(s->problem, 0.0, &y);
      ASSERT_TRUE(with.success) << with.message;
      EXPECT_EQ(with.analyses, 1);
      EXPECT_LE((y - x).cwiseAbs().maxCoeff(), 1e-12) << "the same solve";
    }
  }
  // 11849 vertices: where the vertex graph's estimate is 1.5 times the switch or more,
  // multigrid without the analysis (the same solve as with it); below, the analysis, and
  // here the factor from its fill.
  auto s = MakeSetup(RobustLoss::kHuber, false, true, false, 3, false, 8);
  ASSERT_GE(s->mesh.num_vertices(), 8192);
  auto solve = [&](Preconditioner preconditioner, double multigrid_fill, Vertices* x) {
    BackendOptions options;
    options.type = SolverBackend::kFast;
    options.preconditioner = preconditioner;
    options.multigrid_fill = multigrid_fill;
    *x = s->mesh.rest;
    const SolveReport report = MakeBackend(options)->Solve(s->problem, 0.0, x);
    EXPECT_TRUE(report.success) << report.message;
    return report;
  };
  Vertices x, y, z;
  const SolveReport skipped = solve(Preconditioner::kAuto, 2.0, &x);
  EXPECT_EQ(skipped.analyses, 0);
  EXPECT_GE(skipped.hierarchies, 1);
  EXPECT_EQ(skipped.factorizations, 0);
  solve(Preconditioner::kMultigrid, 2.0, &y);
  EXPECT_LE((y - x).cwiseAbs().maxCoeff(), 1e-12) << "the same solve as multigrid chosen outright";
  const SolveReport analysed = solve(Preconditioner::kAuto, 100.0, &z);
  EXPECT_EQ(analysed.analyses, 1);
  EXPECT_EQ(analysed.hierarchies, 0);
  EXPECT_GE(analysed.factorizations, 1);
}


// The parallel assembly (sets of 32768 3x3 blocks and more, split into a region of vertices
// per thread: here the 6400 elements) builds the serial system bit for bit (each entry adds
// its blocks in block order): one Gauss-Newton step, solved directly, lands in the same
// place on 1 and 2 threads, and the
// energy it starts from is the problem's. With anchors (their rows and columns) and a robust loss; the box numbered along its length,
// then in random order (where a split by vertex numbers left most elements straddling).
TEST(FastBackend, TwoThreadsTakeTheSameStep) {
  for (bool shuffled : {false, true}) {
    SCOPED_TRACE(shuffled ? "shuffled" : "ordered");
    auto s = MakeSetup(RobustLoss::kHuber, true, true, false, 11, false, 4, false, shuffled);
    ASSERT_GE(s->model.num_elements(), 4096);
    auto step = [&](int threads) {
      BackendOptions options;
      options.type = SolverBackend::kFast;
      options.max_iterations = 1;
      options.max_pcg_iterations = 0;
      options.num_threads = threads;
      std::unique_ptr<Backend> backend = MakeBackend(options);
      Vertices x = s->mesh.rest;
      const SolveReport report = backend->Solve(s->problem, 0.0, &x);
      EXPECT_TRUE(report.success);
      // The starting energy from the (parallel) assembly: Evaluate's.
      const EnergyTerms evaluated = s->problem.Evaluate(s->mesh.rest);
      ExpectSameEnergies(report.before, evaluated, evaluated.total());
      return x;
    };
    const Vertices one = step(1), two = step(2);
    const double moved = (one - s->mesh.rest).cwiseAbs().maxCoeff();
    ASSERT_GT(moved, 1e-4);
    EXPECT_TRUE(one == two) << "1 and 2 threads " << (one - two).cwiseAbs().maxCoeff() << " m apart";
  }
}

// A step whose Gauss-Newton gain (predicted along the kept factor's direction) is
// negligible against the relative tolerance is not taken, and the solve says so. A
// quadratic problem (no robust loss, no springs, no contacts) solved once; its rotations
// change (a new outer iteration); solved again, the first step is PCG preconditioned with
// the old factor, to PCG's tolerance: what a second step would add is round-off.
TEST(FastBackend, StopsBeforeAStepThatWouldGainNothing) {
  // Refined so that a factorization costs more than a few PCG iterations.
  auto s = MakeSetup(RobustLoss::kNone, false, false, false, 9, false, 3);
  BackendOptions options;
  options.type = SolverBackend::kFast;
  options.relative_tolerance = 1e-3;
  std::unique_ptr<Backend> backend = MakeBackend(options);
  Vertices x = s->mesh.rest;
  ASSERT_TRUE(backend->Solve(s->problem, 0.0, &x).success);
  Vertices twisted = s->mesh.rest;
  for (int v = 0; v < twisted.rows(); ++v) {
    const double angle = 0.3 * twisted(v, 0) / 0.1;
    const double y = twisted(v, 1) - 0.02, z = twisted(v, 2) - 0.02;
    twisted(v, 1) = 0.02 + std::cos(angle) * y - std::sin(angle) * z;
    twisted(v, 2) = 0.02 + std::sin(angle) * y + std::cos(angle) * z;
  }
  s->model.UpdateRotations(twisted);
  const Vertices start = x;
  const SolveReport report = backend->Solve(s->problem, 0.0, &x);
  ASSERT_TRUE(report.success) << report.message;
  EXPECT_EQ(report.stop, StopReason::kPredicted) << report.message;
  EXPECT_EQ(report.iterations, 1);
  EXPECT_EQ(report.factorizations, 0);  // the first step by PCG with the kept factor
  EXPECT_GT(report.pcg_iterations, 1);
  const double e_min = s->problem.Evaluate(Minimize(SolverBackend::kFast, s->problem, start)).total();
  EXPECT_LT(e_min, report.before.total() * (1 - 1e-3));  // the first step gained more than the tolerance
  EXPECT_LE(report.after.total() - e_min, 1e-5 * e_min);
  // Without a tolerance, the second step is taken.
  options.relative_tolerance = 0.0;
  backend = MakeBackend(options);
  x = start;
  ASSERT_TRUE(backend->Solve(s->problem, 0.0, &x).success);  // a factor, of this system
  s->model.UpdateRotations(s->mesh.rest);
  x = start;
  EXPECT_NE(backend->Solve(s->problem, 0.0, &x).stop, StopReason::kPredicted);
}

// A full step whose decrease the Gauss-Newton model predicted ends the solve when what its
// PCG left (1/2 r^T M^-1 r) is below the tolerance: the step after it would gain less than
// the tolerance (and end the loop), and is not taken. The setup above (a kept factor, then
// twisted rotations: the first step is PCG with the old factor, to PCG's 1e-2), with the
// tolerance 10x what one step leaves above the minimum: one step, kPredicted, the energy
// within the tolerance of the minimum (with the negligible-gain test alone, a second step
// was taken: the gap is 10x its threshold). With the tolerance 1/10 of the gap, the solve
// goes on. Only where the model predicted the step to round-off: with a Huber loss and
// outliers past its scale (weights that change along the step) and the tolerance half the
// first step's gain, the quadratic problem stops after one step and the Huber one goes on;
// so does the neo-Hookean element far from its minimum.
TEST(FastBackend, AStepTheModelPredictedEndsTheSolveWhenPcgLeftLessThanTheTolerance) {
  Vertices bent, twisted;
  for (const RobustLoss loss : {RobustLoss::kNone, RobustLoss::kHuber}) {
    SCOPED_TRACE(loss == RobustLoss::kNone ? "quadratic" : "Huber");
    auto s = MakeSetup(loss, false, false, false, 9, false, 3);
    bent = s->mesh.rest;  // MakeSetup's rotations, and a twist
    twisted = s->mesh.rest;
    for (int v = 0; v < twisted.rows(); ++v) {
      bent(v, 2) += 0.02 * std::pow(bent(v, 0) / 0.1, 2);
      const double angle = 0.3 * twisted(v, 0) / 0.1;
      const double y = twisted(v, 1) - 0.02, z = twisted(v, 2) - 0.02;
      twisted(v, 1) = 0.02 + std::cos(angle) * y - std::sin(angle) * z;
      twisted(v, 2) = 0.02 + std::sin(angle) * y + std::cos(angle) * z;
    }
    // A back end with a factor of the bent rotations' system, then a solve with the twisted
    // rotations from `start` (the first such solve's end).
    Vertices start;
    auto twisted_solve = [&](double tolerance, int max_iterations, Vertices* x) {
      s->model.UpdateRotations(bent);
      BackendOptions options;
      options.type = SolverBackend::kFast;
      options.relative_tolerance = tolerance;
      options.max_iterations = max_iterations;
      std::unique_ptr<Backend> backend = MakeBackend(options);
      *x = s->mesh.rest;
      EXPECT_TRUE(backend->Solve(s->problem, 0.0, x).success);
      if (start.rows() == 0) start = *x;
      s->model.UpdateRotations(twisted);
      *x = start;
      return backend->Solve(s->problem, 0.0, x);
    };
    Vertices one_step, x;
    const SolveReport first = twisted_solve(0.0, 1, &one_step);
    ASSERT_EQ(first.iterations, 1);
    EXPECT_EQ(first.factorizations, 0);  // PCG with the kept factor
    EXPECT_GT(first.pcg_iterations, 1);
    const double e_one = s->problem.Evaluate(one_step).total();
    const double first_gain = first.before.total() - e_one;
    ASSERT_GT(first_gain, 0.0);

    SolveReport report = twisted_solve(0.5 * first_gain / e_one, 10, &x);
    ASSERT_TRUE(report.success) << report.message;
    if (loss == RobustLoss::kHuber) {
      EXPECT_GT(report.iterations, 1) << report.message;
      continue;
    }
    EXPECT_EQ(report.stop, StopReason::kPredicted) << report.message;
    EXPECT_EQ(report.iterations, 1);

    const double e_min = s->problem.Evaluate(Minimize(SolverBackend::kFast, s->problem, start)).total();
    const double gap = e_one - e_min;
    ASSERT_GT(gap, 0.0);
    ASSERT_GT(first_gain, 100.0 * gap);  // the first step gained far more
    report = twisted_solve(10.0 * gap / e_one, 10, &x);
    ASSERT_TRUE(report.success) << report.message;
    EXPECT_EQ(report.stop, StopReason::kPredicted) << report.message;
    EXPECT_EQ(report.iterations, 1);
    EXPECT_LE(report.after.total() - e_min, 10.0 * gap);
    report = twisted_solve(0.1 * gap / e_one, 10, &x);
    ASSERT_TRUE(report.success) << report.message;
    EXPECT_GT(report.iterations, 1) << report.message;
  }

  auto neo = MakeSetup(RobustLoss::kNone, false, false, false, 9, false, 3, /*neo_hookean=*/true);
  BackendOptions options;
  options.type = SolverBackend::kFast;
  options.relative_tolerance = 1e-3;
  Vertices x = twisted;  // far from the minimum: the element's energy is not quadratic there
  const SolveReport report = MakeBackend(options)->Solve(neo->problem, 0.0, &x);
  ASSERT_TRUE(report.success) << report.message;
  EXPECT_GT(report.iterations, 1) << report.message;
}

// CHOLMOD's analysis runs METIS, whose GKlib traps SIGTERM and SIGABRT with signal() and
// puts the old handlers back with System V semantics (reset after one delivery): a host's
// handler fired once and the next SIGTERM killed the process. The back end leaves the
// dispositions as they were, flags and all.
void IgnoreSignal(int) {}
TEST(FastBackend, LeavesTheHostsSignalHandlersAsTheyWere) {
  struct sigaction mine {}, before {}, after {};
  mine.sa_handler = IgnoreSignal;
  sigemptyset(&mine.sa_mask);
  mine.sa_flags = SA_RESTART;
  ASSERT_EQ(sigaction(SIGTERM, &mine, &before), 0);
  auto s = MakeSetup(RobustLoss::kNone, false, false, false, 3, false, 2);
  BackendOptions options;
  options.type = SolverBackend::kFast;
  Vertices x = s->mesh.rest;
  EXPECT_TRUE(MakeBackend(options)->Solve(s->problem, 0.0, &x).success);
  ASSERT_EQ(sigaction(SIGTERM, &before, &after), 0);
  EXPECT_EQ(after.sa_handler, &IgnoreSignal);
  EXPECT_EQ(after.sa_flags & (SA_RESETHAND | SA_NODEFER | SA_RESTART), SA_RESTART);
}

// The slots of a stencil met before are the ones a search finds: the data sets are made
// anew each outer iteration, mostly on triangles met before, and the back end takes their
// slots from what it found then. One exact Gauss-Newton step (CHOLMOD's factor, no PCG) on
// a problem whose data sets were rebuilt (new targets), by a back end that solved the old
// ones, equals a fresh back end's step to round-off.
TEST(FastBackend, RebuiltDataSetsScatterWhereASearchWould) {
  auto s = MakeSetup(RobustLoss::kNone, false, false, false, 13);
  BackendOptions options;
  options.type = SolverBackend::kFast;
  options.max_iterations = 1;
  options.max_pcg_iterations = 0;
  std::unique_ptr<Backend> seasoned = MakeBackend(options);
  Vertices x = s->mesh.rest;
  ASSERT_TRUE(seasoned->Solve(s->problem, 0.0, &x).success);

  std::vector<energy::PointToPlane<3>> planes;
  std::vector<energy::PointToPoint<3>> points;
  energy::Loss loss;
  s->problem.ForEachSet([&](const auto& set) {
    using T = typename std::decay_t<decltype(set)>::Block;
    if constexpr (std::is_same_v<T, energy::PointToPlane<3>>) {
      planes.insert(planes.end(), set.blocks().begin(), set.blocks().end());
      loss = set.loss();
    } else if constexpr (std::is_same_v<T, energy::PointToPoint<3>>) {
      points.insert(points.end(), set.blocks().begin(), set.blocks().end());
    }
  });
  ASSERT_GT(planes.size() + points.size(), 10u);
  s->problem.Clear(TermGroup::kData);
  auto& l3 = s->problem.AddSet<energy::PointToPlane<3>>(TermGroup::kData, loss);
  auto& p3 = s->problem.AddSet<energy::PointToPoint<3>>(TermGroup::kData, loss);
  // The same stencils in another order, pulled elsewhere.
  for (auto it = planes.rbegin(); it != planes.rend(); ++it) {
    energy::PointToPlane<3> b = *it;
    b.target += Eigen::Vector3d(0.0, 0.003, -0.002);
    l3.Add(b);
  }
  for (auto it = points.rbegin(); it != points.rend(); ++it) {
    energy::PointToPoint<3> b = *it;
    b.target += Eigen::Vector3d(0.002, 0.0, 0.004);
    p3.Add(b);
  }
  Vertices a = s->mesh.rest, b = s->mesh.rest;
  ASSERT_TRUE(seasoned->Solve(s->problem, 0.0, &a).success);
  ASSERT_TRUE(MakeBackend(options)->Solve(s->problem, 0.0, &b).success);
  const double moved = (b - s->mesh.rest).cwiseAbs().maxCoeff();
  ASSERT_GT(moved, 1e-4);
  EXPECT_LE((a - b).cwiseAbs().maxCoeff(), 1e-9 * moved);
}

// The fast back end keeps its pattern and analysis while the coupling holds, and widens it
// once for a contact between vertices outside it.
TEST(FastBackend, PatternIsReusedAndWidenedOnce) {
  auto s = MakeSetup(RobustLoss::kHuber, false, false, true, 5);
  BackendOptions options;
  options.type = SolverBackend::kFast;
  std::unique_ptr<Backend> backend = MakeBackend(options);
  Vertices x = s->mesh.rest;
  SolveReport first = backend->Solve(s->problem, 0.0, &x);
  EXPECT_EQ(first.pattern_rebuilds, 2);  // the coupling, then the contact pair
  SolveReport second = backend->Solve(s->problem, 0.0, &x);
  EXPECT_EQ(second.pattern_rebuilds, 0);
  EXPECT_TRUE(second.success);
}

// On the bundled beam_bend, from the softest to the stiffest material the two back ends
// reach the same minimum of each frame's energy: four frames, each one outer iteration from
// the same start (the Ceres result of the frame before), so that both minimize the same
// pairs, solved to convergence. (Over frames and outer iterations each back end finds its
// pairs again at its own result, and a pair gated in or out by a hair moves a body as soft
// as E = 100 Pa by centimetres: nearly no regularizer.)
TEST(Backends, SameMinimumFromSoftToStiff) {
  const std::string dir = std::string(FEMREG_DATASETS_DIR) + "/beam_bend";
  constexpr int kFrames = 4;
  std::vector<PointCloud> clouds(kFrames);
  std::vector<GroundTruthFrame> truth(kFrames);
  for (int f = 0; f < kFrames; ++f) {
    char name[32];
    std::snprintf(name, sizeof(name), "frame_%04d", f);
    ASSERT_TRUE(ReadPointCloud(dir + "/clouds/" + name + ".pcd", &clouds[f]).ok());
    ASSERT_TRUE(ReadGroundTruthFrame(dir + "/ground_truth/" + name + ".csv", &truth[f]).ok());
  }
  for (double E : {1e2, 1e3, 1e4, 1e5, 1e6, 1e7, 1e8, 1e9}) {
    std::unique_ptr<Tracker> tracker[2];
    for (int b = 0; b < 2; ++b) {
      Scene scene;
      ASSERT_TRUE(LoadScene(dir + "/scene.yaml", &scene).ok());
      scene.objects[0].material.youngs_modulus = E;
      SolverOptions& solver = scene.registration.solver;
      solver.backend = b == 0 ? SolverBackend::kCeres : SolverBackend::kFast;
      solver.max_outer_iterations = 1;
      solver.max_inner_iterations = 500;
      solver.inner_tolerance = 1e-14;
      solver.step_tolerance = 0.0;  // only the energy criterion, as Ceres
      solver.predict_motion = false;
      ASSERT_TRUE(Tracker::Create(scene, &tracker[b]).ok());
    }
    double worst = 0.0, worst_energy = 0.0, worst_error = 0.0;
    for (int f = 0; f < kFrames; ++f) {
      ASSERT_TRUE(tracker[1]->SetVertices(0, tracker[0]->vertices(0)).ok());
      FrameSummary summary[2];
      for (int b = 0; b < 2; ++b) {
        ASSERT_TRUE(tracker[b]->Track(clouds[f], &summary[b]).ok());
        ASSERT_TRUE(summary[b].IsSolutionUsable()) << summary[b].BriefReport();
      }
      ASSERT_EQ(summary[0].cloud_to_model, summary[1].cloud_to_model);
      const Vertices& x0 = tracker[0]->vertices(0);
      const Vertices& x1 = tracker[1]->vertices(0);
      worst = std::max(worst, (x1 - x0).rowwise().norm().maxCoeff());
      const double e0 = summary[0].final.total(), e1 = summary[1].final.total();
      worst_energy = std::max(worst_energy, std::abs(e1 - e0) / e0);
      // At 100 Pa the data crush elements into the inversion barrier: Ceres' steps (Gauss-
      // Newton on the barrier's residual) stall against it, the fast back end's (its projected
      // Newton Hessian) do not. It must end no higher.
      if (E < 1e3) {
        EXPECT_LE(e1, e0 * (1.0 + 1e-6)) << "E = " << E << ", frame " << f;
      }
      const double a0 = ComputeVertexErrors(x0, truth[f]).all.mean;
      const double a1 = ComputeVertexErrors(x1, truth[f]).all.mean;
      worst_error = std::max(worst_error, std::abs(a1 - a0) / a0);
    }
    std::printf("E = %.0e Pa: largest vertex difference %.2e m, energies %.1e and errors %.1e apart (relative)\n",
                E, worst, worst_energy, worst_error);
    if (E < 1e3) continue;
    // Each back end stops where a step changes the energy by less than 1e-14: the vertices
    // agree to well under a micrometre, the energies and errors to far below a percent.
    EXPECT_LT(worst, 1e-5) << "E = " << E;
    EXPECT_LT(worst_energy, 1e-6) << "E = " << E;
    EXPECT_LT(worst_error, 1e-3) << "E = " << E;
  }
}

}  // namespace
}  // namespace femreg
