// Equilibrium registration (energy/equilibrium.h, solvers/fast/equilibrium_step.h; the
// penalties are equilibrium_penalty_test.cc's): the force residual's invariants (zero at rest
// and under rigid motion, force balance), both back ends' solves reaching the same stationary
// point of the energy, and their stops (the tracker's recovery of a known load:
// equilibrium_registration_test.cc).
#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <cmath>
#include <cstdio>
#include <limits>
#include <memory>
#include <random>
#include <string>
#include <vector>

#include "energy/contact.h"
#include "energy/equilibrium.h"
#include "energy/problem.h"
#include "femreg/io.h"
#include "solvers/backend.h"

namespace femreg {
namespace {

// A 2 x 1 x 1 box of corotational elements, optionally under gravity on its lumped masses.
struct BoxProblem {
  TetMesh mesh;
  ElasticModel model;
  energy::Problem problem;
  Material material;
  explicit BoxProblem(int n = 2) : BoxProblem(Eigen::Vector3d(0.2, 0.1, 0.1), 2 * n, n, n) {}
  BoxProblem(const Eigen::Vector3d& size, int nx, int ny, int nz) {
    mesh = MakeBox(size, nx, ny, nz);
    material.youngs_modulus = 2e4;
    material.poisson_ratio = 0.3;
    material.density = 1000.0;
    ComputeLumpedMasses(&mesh, material.density);
    model.Build(mesh, ElasticModelType::kCorotational, material);
    problem.Reset(mesh.num_vertices());
    std::vector<std::array<int, 4>> cells;
    auto& set = problem.AddSet<energy::ElasticElement>(energy::TermGroup::kElastic);
    for (int e = 0; e < mesh.num_tets(); ++e) {
      energy::ElasticElement b;
      for (int k = 0; k < 4; ++k) b.vertices[k] = mesh.tets(e, k);
      b.rest = &model.rest(e);
      b.rotation = &model.rotation(e);
      set.Add(b);
      cells.push_back(b.vertices);
    }
    problem.SetCoupling(cells);
  }
  void AddGravity(const Vertices& origin) {
    auto& loads = problem.AddSet<energy::ExternalLoad>(energy::TermGroup::kLoad);
    for (int v = 0; v < mesh.num_vertices(); ++v) {
      energy::ExternalLoad block;
      if (energy::MakeExternalLoad(v, mesh.mass(v) * Eigen::Vector3d(0, 0, -9.81), origin.row(v).transpose(), 0.05,
                                   &block)) {
        loads.Add(block);
      }
    }
  }
};

TEST(ForceResidual, ZeroAtRestAndUnderRigidMotion) {
  BoxProblem box;
  Eigen::VectorXd f;
  energy::ForceResidual(box.problem, box.mesh.rest, &f);
  const double scale = box.material.youngs_modulus * 0.05 * 0.05;  // N: E times an element's face
  EXPECT_LT(f.lpNorm<Eigen::Infinity>(), 1e-12 * scale);
  const Eigen::Matrix3d R = Eigen::AngleAxisd(0.8, Eigen::Vector3d(1, -2, 0.5).normalized()).toRotationMatrix();
  const Vertices moved = (box.mesh.rest * R.transpose()).rowwise() + Eigen::RowVector3d(0.3, -0.1, 2.0);
  energy::ForceResidual(box.problem, moved, &f);
  EXPECT_LT(f.lpNorm<Eigen::Infinity>(), 1e-9 * scale);
}

// The elastic forces are internal: the residuals of all vertices add up to minus the loads,
// whatever the shape (with a clamp, its reactions close the balance).
TEST(ForceResidual, ForcesBalanceTheLoads) {
  BoxProblem box;
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> jitter(-0.01, 0.01);
  Vertices x = box.mesh.rest;
  for (int v = 0; v < x.rows(); ++v) x.row(v) += Eigen::RowVector3d(jitter(rng), jitter(rng), jitter(rng));
  box.AddGravity(x);
  Eigen::VectorXd f;
  energy::ForceResidual(box.problem, x, &f);
  Eigen::Vector3d sum = Eigen::Vector3d::Zero();
  for (int v = 0; v < x.rows(); ++v) sum += f.segment<3>(3 * v);
  const Eigen::Vector3d weight(0, 0, -9.81 * box.mesh.mass.sum());
  EXPECT_LT((sum + weight).norm(), 1e-9 * weight.norm()) << sum.transpose();
  // Clamp one end: the free residuals, the reactions and the weight still balance.
  box.problem.fixed().assign(static_cast<size_t>(x.rows()), 0);
  for (int v = 0; v < x.rows(); ++v) box.problem.fixed()[v] = box.mesh.rest(v, 0) < 1e-9;
  Eigen::VectorXd free_f;
  energy::ForceResidual(box.problem, x, &free_f);
  Eigen::Vector3d free_sum = Eigen::Vector3d::Zero(), reactions = Eigen::Vector3d::Zero();
  for (int v = 0; v < x.rows(); ++v) {
    (box.problem.is_fixed(v) ? reactions : free_sum) += (box.problem.is_fixed(v) ? f : free_f).segment<3>(3 * v);
  }
  EXPECT_LT((free_sum + reactions + weight).norm(), 1e-9 * weight.norm());
}

// The fast back end with its own stops only (the inner tolerance out of play), up to 50 steps.
BackendOptions FastSolveToTheEnd() {
  BackendOptions options;
  options.type = SolverBackend::kFast;
  options.max_iterations = 50;
  options.relative_tolerance = 1e-12;
  return options;
}

// A cantilever box clamped at x = 0 under gravity, its far end's vertices pulled 1 cm down
// and sideways by the data, free to take a force anywhere but at the clamp.
void SetUpPulledCantilever(BoxProblem* box) {
  const int n = box->mesh.num_vertices();
  box->problem.fixed().assign(static_cast<size_t>(n), 0);
  for (int v = 0; v < n; ++v) box->problem.fixed()[v] = box->mesh.rest(v, 0) < 1e-9;
  box->AddGravity(box->mesh.rest);
  auto& data = box->problem.AddSet<energy::PointToPoint<1>>(energy::TermGroup::kData);
  for (int v = 0; v < n; ++v) {
    if (box->mesh.rest(v, 0) < 0.2 - 1e-9) continue;
    energy::PointToPoint<1> b;
    b.vertices = {{v}};
    b.barycentric = {{1.0}};
    b.weight = 500.0;
    b.target = box->mesh.rest.row(v).transpose() + Eigen::Vector3d(0, 0.004, -0.01);
    data.Add(b);
  }
  auto eq = std::make_shared<energy::Equilibrium>();
  eq->site.assign(n, energy::ForceSite::kFree);
  eq->force_weight.assign(n, 1e-2);
  eq->strong_weight.assign(n, 1e2);
  for (int v = 0; v < n; ++v) {
    if (box->problem.is_fixed(v)) eq->site[v] = energy::ForceSite::kSupport;
  }
  box->problem.SetEquilibrium(eq);
}

// Forces on the cantilever's top face only, pushing down (the rest balanced): the data pull
// the end down (and sideways, which friction may take).
void PushOnlyOnTheTopFace(BoxProblem* box, double friction, double sparsity) {
  const int n = box->mesh.num_vertices();
  auto eq = std::make_shared<energy::Equilibrium>(*box->problem.equilibrium());
  eq->pushing_only = true;
  eq->friction = friction;
  eq->normal.assign(n, Eigen::Vector3d::UnitZ());
  for (int v = 0; v < n; ++v) {
    if (eq->site[v] == energy::ForceSite::kFree && box->mesh.rest(v, 2) < 0.1 - 1e-9) {
      eq->site[v] = energy::ForceSite::kBalanced;
    }
  }
  if (sparsity > 0) {
    eq->sparsity.assign(n, sparsity);
    eq->sparsity_floor = 1e-3;
  }
  box->problem.SetEquilibrium(eq);
}

// Both back ends stop where the energy is stationary: its gradient (central differences of
// Problem::Evaluate) a small fraction of where it started; and at the same shape. With the L2
// penalty alone, and pushing only on the top face (frictionless with the sparse term, and
// within a friction cone: on this 12-vertex box a factorization costs less than a PCG
// iteration, and the fast back end's re-solve across the cone's kinks needs its floor of
// iterations to get there).
TEST(EquilibriumSolve, BothBackEndsReachTheSameStationaryPointOfTheEnergy) {
  struct Case {
    const char* name;
    bool pushing_only;
    double friction, sparsity;
  };
  for (const Case& c : {Case{"L2 penalty", false, -1.0, 0.0},
                        Case{"pushing only, frictionless, sparse", true, 0.0, 1e-2},
                        Case{"pushing only, friction 0.5", true, 0.5, 0.0}}) {
    SCOPED_TRACE(c.name);
    BoxProblem box(1);
    const int n = box.mesh.num_vertices();
    SetUpPulledCantilever(&box);
    if (c.pushing_only) PushOnlyOnTheTopFace(&box, c.friction, c.sparsity);
    auto gradient = [&](const Vertices& x) {
      Eigen::VectorXd g(3 * n);
      const double h = 1e-7;
      for (int v = 0; v < n; ++v) {
        for (int k = 0; k < 3; ++k) {
          Vertices xp = x, xm = x;
          xp(v, k) += h;
          xm(v, k) -= h;
          g[3 * v + k] = box.problem.is_fixed(v)
                             ? 0.0
                             : (box.problem.Evaluate(xp).total() - box.problem.Evaluate(xm).total()) / (2 * h);
        }
      }
      return g;
    };
    const double before = gradient(box.mesh.rest).norm();
    std::vector<Vertices> results;
    for (const SolverBackend type : {SolverBackend::kCeres, SolverBackend::kFast}) {
      SCOPED_TRACE(type == SolverBackend::kFast ? "fast" : "Ceres");
      BackendOptions options = FastSolveToTheEnd();
      options.type = type;
      Vertices x = box.mesh.rest;
      const SolveReport report = MakeBackend(options)->Solve(box.problem, 0.0, &x);
      ASSERT_TRUE(report.success) << report.message;
      EXPECT_LT(report.after.total(), report.before.total());
      EXPECT_GT(report.after.equilibrium, 0.0);
      EXPECT_LT(gradient(x).norm(), 1e-3 * before) << report.message;
      results.push_back(x);
    }
    // The same shape: within a thousandth of the data's 1 cm pull.
    ASSERT_EQ(results.size(), 2u);
    EXPECT_LT((results[0] - results[1]).rowwise().norm().maxCoeff(), 1e-5);
  }
}

// The pulled cantilever and its solve to the end, which the stops below are held to.
struct PulledCantilever {
  BoxProblem box{1};
  Vertices full;
  SolveReport exact;
  PulledCantilever() {
    SetUpPulledCantilever(&box);
    full = box.mesh.rest;
    exact = MakeBackend(FastSolveToTheEnd())->Solve(box.problem, 0.0, &full);
  }
};

// equilibrium_step_tolerance ends the solve after the first whole step that moves no vertex
// more than it (and lowers the energy by less than 10 %): fewer steps, and a shape within a
// few such moves of the full solve's.
TEST(EquilibriumSolve, StopsAfterAStepBelowTheEquilibriumStepTolerance) {
  PulledCantilever c;
  ASSERT_TRUE(c.exact.success) << c.exact.message;
  BoxProblem& box = c.box;
  const Vertices& full = c.full;
  const SolveReport& exact = c.exact;
  BackendOptions options = FastSolveToTheEnd();
  const double tolerance = 2e-4;  // m: of the 1 cm pull
  options.equilibrium_step_tolerance = tolerance;
  Vertices x = box.mesh.rest;
  const SolveReport early = MakeBackend(options)->Solve(box.problem, 0.0, &x);
  ASSERT_TRUE(early.success) << early.message;
  std::printf("steps: %d without the tolerance, %d with it; largest difference %.3g mm\n", exact.iterations,
              early.iterations, 1e3 * (x - full).rowwise().norm().maxCoeff());
  EXPECT_EQ(early.stop, StopReason::kStep) << early.message;
  EXPECT_LT(early.iterations, exact.iterations);
  EXPECT_LT((x - full).rowwise().norm().maxCoeff(), 4 * tolerance);
  EXPECT_GT((x - box.mesh.rest).rowwise().norm().maxCoeff(), 0.005);
  // Not after a step that lowered the energy by more than a tenth, however short: the first
  // step from rest lowers it by most of it.
  options.equilibrium_step_tolerance = 1.0;  // m: longer than any step here
  Vertices y = box.mesh.rest;
  const SolveReport any_move = MakeBackend(options)->Solve(box.problem, 0.0, &y);
  ASSERT_TRUE(any_move.success) << any_move.message;
  EXPECT_GT(any_move.iterations, 1);
  EXPECT_LT((y - full).rowwise().norm().maxCoeff(), 4 * tolerance);
}

// Equilibrium::max_steps caps a solve's steps on both back ends (the tracker's smooth start
// before the pushing-only penalty takes two), and the solve still goes downhill.
TEST(EquilibriumSolve, MakesAtMostTheProblemsMaxSteps) {
  PulledCantilever c;
  ASSERT_TRUE(c.exact.success) << c.exact.message;
  const std::shared_ptr<const energy::Equilibrium> uncapped = c.box.problem.shared_equilibrium();
  auto eq = std::make_shared<energy::Equilibrium>(*uncapped);
  eq->max_steps = 2;
  for (const SolverBackend type : {SolverBackend::kCeres, SolverBackend::kFast}) {
    SCOPED_TRACE(type == SolverBackend::kFast ? "fast" : "Ceres");
    BackendOptions options = FastSolveToTheEnd();
    options.type = type;
    // Without the cap this back end takes more than two.
    c.box.problem.SetEquilibrium(uncapped);
    Vertices full = c.box.mesh.rest;
    ASSERT_GT(MakeBackend(options)->Solve(c.box.problem, 0.0, &full).iterations, 2);
    c.box.problem.SetEquilibrium(eq);
    Vertices x = c.box.mesh.rest;
    const SolveReport report = MakeBackend(options)->Solve(c.box.problem, 0.0, &x);
    ASSERT_TRUE(report.success) << report.message;
    EXPECT_LE(report.iterations, 2);
    EXPECT_LT(report.after.total(), report.before.total());
  }
}

// A step that moves no vertex more than solver.step_tolerance ends the solve at once, but
// pushing only, where the penalty's first steps move little while they still trade the pulls
// it forbids for pushes, only once it lowers the energy by less than a tenth
// (docs/notes/2026-12-05-pushing-only-smooth-start.md).
TEST(EquilibriumSolve, PushingOnlyATinyStepEndsTheSolveOnceItGainsLittle) {
  for (const bool pushing_only : {false, true}) {
    SCOPED_TRACE(pushing_only ? "pushing only" : "L2 penalty");
    BoxProblem box(1);
    SetUpPulledCantilever(&box);
    if (pushing_only) PushOnlyOnTheTopFace(&box, 0.0, 0.0);
    BackendOptions options = FastSolveToTheEnd();
    options.step_tolerance = 1.0;  // m: longer than any step here
    Vertices x = box.mesh.rest;
    const SolveReport report = MakeBackend(options)->Solve(box.problem, 0.0, &x);
    ASSERT_TRUE(report.success) << report.message;
    EXPECT_EQ(report.stop, StopReason::kStep) << report.message;
    if (!pushing_only) {
      EXPECT_EQ(report.iterations, 1);
      continue;
    }
    ASSERT_GT(report.iterations, 1);
    // Each step but the last gained at least a tenth of the energy before it; the last less.
    std::vector<double> energies = {report.before.total()};
    for (int steps = 1; steps <= report.iterations; ++steps) {
      Vertices y = box.mesh.rest;
      options.max_iterations = steps;
      const SolveReport shorter = MakeBackend(options)->Solve(box.problem, 0.0, &y);
      ASSERT_TRUE(shorter.success) << shorter.message;
      energies.push_back(shorter.after.total());
    }
    EXPECT_NEAR(energies.back(), report.after.total(), 1e-12 * report.after.total());
    for (int step = 1; step <= report.iterations; ++step) {
      const double decrease = (energies[step - 1] - energies[step]) / energies[step - 1];
      std::printf("step %d: the energy %.4g -> %.4g (%.1f %% lower)\n", step, energies[step - 1], energies[step],
                  100 * decrease);
      if (step < report.iterations) {
        EXPECT_GE(decrease, 0.1) << "step " << step;
      } else {
        EXPECT_LT(decrease, 0.1);
      }
    }
  }
}

// A whole step whose model promised what the energy gave, with what PCG left, within the
// solve's tolerance ends the solve: the next step would gain about that. On the pulled
// cantilever the last step taken lowers the energy by more than the tolerance, so the decrease
// alone would take another, and the solve ends within the tolerance of the end's energy.
TEST(EquilibriumSolve, EndsWhereTheStepModelPromisedWhatTheEnergyGave) {
  PulledCantilever c;
  ASSERT_TRUE(c.exact.success) << c.exact.message;
  BoxProblem& box = c.box;
  const SolveReport& exact = c.exact;
  BackendOptions options = FastSolveToTheEnd();
  const double tolerance = 1e-3;
  options.relative_tolerance = tolerance;
  Vertices x = box.mesh.rest;
  const SolveReport early = MakeBackend(options)->Solve(box.problem, 0.0, &x);
  ASSERT_TRUE(early.success) << early.message;
  const double excess = (early.after.total() - exact.after.total()) / exact.after.total();
  EXPECT_EQ(early.stop, StopReason::kPredicted) << early.message;
  EXPECT_LT(early.iterations, exact.iterations);
  // Its last step lowered the energy by more than the tolerance: the decrease alone would have
  // taken another.
  Vertices one_less = box.mesh.rest;
  options.max_iterations = early.iterations - 1;
  const SolveReport shorter = MakeBackend(options)->Solve(box.problem, 0.0, &one_less);
  ASSERT_TRUE(shorter.success) << shorter.message;
  const double last = (shorter.after.total() - early.after.total()) / shorter.after.total();
  std::printf("steps: %d to the end, %d with the tolerance %.0e; the last one's decrease %.3g;"
              " energy %.3g above the end's\n",
              exact.iterations, early.iterations, tolerance, last, excess);
  EXPECT_GT(last, tolerance);
  EXPECT_LT(excess, tolerance);
}

// The cantilever's pulled end meets a table 4 mm below it. The contacts' force is piecewise
// linear in the positions, and a step's model without the contacts it closes overshoots them
// and the line search cuts it short; with them closed in the model
// (solvers/fast/closing_contacts.h) the steps are whole, and the solve ends in fewer of them.
TEST(EquilibriumSolve, StepsThroughTheContactsTheyClose) {
  BoxProblem box(1);
  SetUpPulledCantilever(&box);
  const int n = box.mesh.num_vertices();
  const double table = box.mesh.rest.col(2).minCoeff() - 0.004;
  auto& contacts = box.problem.AddSet<energy::ContactPenalty<3>>(energy::TermGroup::kCollision);
  int touching = 0;
  for (int v = 0; v < n; ++v) {
    if (box.mesh.rest(v, 0) < 0.2 - 1e-9 || box.mesh.rest(v, 2) > table + 0.004 + 1e-9) continue;
    energy::ContactPenalty<3> b;
    b.vertices = {{v, (v + 1) % n, (v + 2) % n}};  // a point contact: the other two weigh 0
    b.coefficients = {{1.0, 0.0, 0.0}};
    b.normal = Eigen::Vector3d::UnitZ();
    b.offset = table;  // delta = table - z_v: > 0 below the table
    b.weight = 1e5;    // N/m
    contacts.Add(b);
    ++touching;
  }
  ASSERT_GT(touching, 0);
  BackendOptions options = FastSolveToTheEnd();
  Vertices x = box.mesh.rest;
  const SolveReport report = MakeBackend(options)->Solve(box.problem, 0.0, &x);
  ASSERT_TRUE(report.success) << report.message;
  double lowest = std::numeric_limits<double>::infinity();
  for (int v = 0; v < n; ++v) {
    if (box.mesh.rest(v, 0) > 0.2 - 1e-9) lowest = std::min(lowest, x(v, 2));
  }
  std::printf("%d steps, %d factorizations, stopped by %s; the end's lowest vertex %.3f mm below the table\n",
              report.iterations, report.factorizations, ToString(report.stop), 1e3 * (table - lowest));
  EXPECT_LT(table - lowest, 1e-4);  // resting on the table: pressed in, not through
  EXPECT_GT(table - lowest, 0.0);
  // Without the closing contacts in the model it takes about twice as many
  // (docs/notes/2026-12-01-equilibrium-inexact-solves.md#contacts-closed-within-a-step).
  EXPECT_LE(report.iterations, 5);
}

// A free box whose data ask for a turn about z and x and a shift: with z held
// (Equilibrium::held_turns), the solve makes the shift and the turn about x but not the held one.
TEST(EquilibriumSolve, MakesNoHeldTurn) {
  const double angle = 0.02;
  const Eigen::Vector3d shift(0.004, -0.002, 0.003);
  const Eigen::Matrix3d turn =
      (Eigen::AngleAxisd(angle, Eigen::Vector3d::UnitZ()) * Eigen::AngleAxisd(angle, Eigen::Vector3d::UnitX()))
          .toRotationMatrix();
  BoxProblem reference(2);
  const Vertices& rest = reference.mesh.rest;
  const int n = reference.mesh.num_vertices();
  const Eigen::Vector3d centre = rest.colwise().mean().transpose();
  auto solve = [&](bool hold, Vertices* x) {
    BoxProblem box(2);
    auto& data = box.problem.AddSet<energy::PointToPoint<1>>(energy::TermGroup::kData);
    for (int v = 0; v < n; ++v) {
      energy::PointToPoint<1> b;
      b.vertices = {{v}};
      b.barycentric = {{1.0}};
      b.weight = 500.0;
      b.target = centre + turn * (rest.row(v).transpose() - centre) + shift;
      data.Add(b);
    }
    auto eq = std::make_shared<energy::Equilibrium>();
    eq->site.assign(n, energy::ForceSite::kFree);
    eq->force_weight.assign(n, 1e-2);
    eq->strong_weight.assign(n, 1e2);
    if (hold) eq->held_turns.push_back({0, n, Eigen::Vector3d::UnitZ()});
    ASSERT_TRUE(eq->IsValid(n));
    box.problem.SetEquilibrium(eq);
    BackendOptions options;
    options.type = SolverBackend::kFast;
    options.max_iterations = 20;
    options.relative_tolerance = 1e-10;
    *x = rest;
    const SolveReport report = MakeBackend(options)->Solve(box.problem, 0.0, x);
    ASSERT_TRUE(report.success) << report.message;
    EXPECT_LT(report.after.total(), report.before.total());
  };
  // The least-squares turn about axis a through the centroid.
  auto turn_about = [&](const Vertices& x, const Eigen::Vector3d& a) {
    double num = 0.0, den = 0.0;
    for (int v = 0; v < n; ++v) {
      const Eigen::Vector3d m = a.cross(rest.row(v).transpose() - centre);
      num += m.dot((x.row(v) - rest.row(v)).transpose());
      den += m.squaredNorm();
    }
    return num / den;
  };
  Vertices free_x, held_x;
  ASSERT_NO_FATAL_FAILURE(solve(false, &free_x));
  ASSERT_NO_FATAL_FAILURE(solve(true, &held_x));
  const Eigen::Vector3d free_shift = (free_x - rest).colwise().mean().transpose();
  const Eigen::Vector3d held_shift = (held_x - rest).colwise().mean().transpose();
  std::printf("turn about z: free %.5f, held %.2e rad; about x: free %.5f, held %.5f; shift error %.2e / %.2e m\n",
              turn_about(free_x, Eigen::Vector3d::UnitZ()), turn_about(held_x, Eigen::Vector3d::UnitZ()),
              turn_about(free_x, Eigen::Vector3d::UnitX()), turn_about(held_x, Eigen::Vector3d::UnitX()),
              (free_shift - shift).norm(), (held_shift - shift).norm());
  EXPECT_NEAR(turn_about(free_x, Eigen::Vector3d::UnitZ()), angle, 0.05 * angle);
  EXPECT_LT(std::abs(turn_about(held_x, Eigen::Vector3d::UnitZ())), 1e-3 * angle);
  EXPECT_NEAR(turn_about(held_x, Eigen::Vector3d::UnitX()), angle, 0.1 * angle);
  EXPECT_LT((held_shift - shift).norm(), 0.05 * shift.norm());
}

// A slender cantilever (80 cm long, 2 cm across) whose top is pulled into a bend by data: its
// bending modes are soft, K Phi K is tiny along them and the data are not, and K~'s factor alone
// preconditions them one PCG iteration each. After a step that took more than 60, the next
// factorizes K~ + s H: the same step from the same shape, a fraction of the iterations.
TEST(EquilibriumSolve, DataHeldSoftModesTakeFewPcgIterations) {
  BoxProblem beam(Eigen::Vector3d(0.8, 0.02, 0.02), 80, 2, 2);
  const int n = beam.mesh.num_vertices();
  beam.problem.fixed().assign(static_cast<size_t>(n), 0);
  for (int v = 0; v < n; ++v) beam.problem.fixed()[v] = beam.mesh.rest(v, 0) < 1e-9;
  auto& data = beam.problem.AddSet<energy::PointToPoint<1>>(energy::TermGroup::kData);
  for (int v = 0; v < n; ++v) {
    if (beam.mesh.rest(v, 2) < 0.02 - 1e-9) continue;  // the top face
    const double s = beam.mesh.rest(v, 0) / 0.8;
    energy::PointToPoint<1> b;
    b.vertices = {{v}};
    b.barycentric = {{1.0}};
    b.weight = 200.0;
    b.target = beam.mesh.rest.row(v).transpose() + Eigen::Vector3d(0, 0.01 * s * s, 0.02 * std::sin(3.0 * s));
    data.Add(b);
  }
  auto eq = std::make_shared<energy::Equilibrium>();
  eq->site.assign(n, energy::ForceSite::kFree);
  eq->force_weight.assign(n, 1.0);
  eq->strong_weight.assign(n, 1e3);
  for (int v = 0; v < n; ++v) {
    if (beam.problem.is_fixed(v)) eq->site[v] = energy::ForceSite::kSupport;
  }
  beam.problem.SetEquilibrium(eq);
  BackendOptions options;
  options.type = SolverBackend::kFast;
  options.max_iterations = 1;  // one Gauss-Newton step a solve
  const auto primed = MakeBackend(options);
  Vertices x = beam.mesh.rest;
  const SolveReport first = primed->Solve(beam.problem, 0.0, &x);
  ASSERT_TRUE(first.success) << first.message;
  ASSERT_GT(first.pcg_iterations, 60);
  // The second step from x: on K~'s factor (a new back end) and on K~ + s H's (the primed one).
  Vertices x_plain = x, x_shifted = x;
  const SolveReport plain = MakeBackend(options)->Solve(beam.problem, 0.0, &x_plain);
  const SolveReport shifted = primed->Solve(beam.problem, 0.0, &x_shifted);
  ASSERT_TRUE(plain.success && shifted.success);
  std::printf("PCG iterations: first step %d, second step %d on K's factor, %d on K + s H's; energy %.4g -> %.4g / %.4g\n",
              first.pcg_iterations, plain.pcg_iterations, shifted.pcg_iterations, plain.before.total(),
              plain.after.total(), shifted.after.total());
  EXPECT_LT(3 * shifted.pcg_iterations, plain.pcg_iterations);
  // The same step to PCG's tolerance: the same decrease, within a tenth.
  const double gain = plain.before.total() - plain.after.total();
  ASSERT_GT(gain, 0.0);
  EXPECT_NEAR(shifted.after.total(), plain.after.total(), 0.1 * gain);
}

}  // namespace
}  // namespace femreg
