#include "solvers/fast/equilibrium_step.h"

#include <Eigen/Cholesky>
#include <Eigen/Geometry>
#include <Eigen/LU>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <string>
#include <vector>

#include "energy/assembler.h"
#include "energy/equilibrium.h"
#include "parallel/stopwatch.h"
#include "parallel/threads.h"
#include "solvers/fast/closing_contacts.h"
#include "solvers/fast/data_shift.h"
#include "solvers/fast/equilibrium_factor.h"
#include "solvers/fast/fast_backend.h"
#include "solvers/fast/fast_backend_internal.h"
#include "solvers/fast/penalty_pieces.h"
#include "solvers/fast/step_modes.h"
#include "solvers/fast/supernodal_solve.h"

namespace femreg {
namespace fast_backend {

namespace {

using Clock = std::chrono::steady_clock;
constexpr int kMaxPcgIterations = 200;
// After this many Gauss-Newton steps of a solve (an outer iteration), a step that lowers the
// energy by less than kLateTolerance ends it. Each step linearizes every element again and
// makes a new factor, while the next outer iteration's pairs and hold of hidden turns move
// the problem anyway (docs/notes/2026-11-30-equilibrium-steps.md).
constexpr int kFullSteps = 4;
constexpr double kLateTolerance = 1e-2;
// A whole step (PCG converged, the line search took all of it) that moved no vertex more than
// BackendOptions::equilibrium_step_tolerance and lowered the energy by less than this share
// ends the solve: on a stiff body a short step can still balance much of the forces, and a cut
// or truncated step is short for other reasons (docs/notes/2026-12-01-equilibrium-inexact-solves.md).
// With forces.pushing_only so must a step below the step tolerance: under that penalty's
// stiffness a move of a micrometre still halved the energy, and the frame was left at a shape
// that pulls hold (docs/notes/2026-12-05-pushing-only-smooth-start.md).
constexpr double kSmallStepDecrease = 0.1;
// A step's PCG stops at kPcgTolerance of its own gradient or at this share of the solve's
// first gradient, whichever is larger, and the solve stops once the gradient is below that
// share: a gradient ten thousand times smaller than the solve's first promises about 1e-8 of
// what the first step gained (the model's decrease goes as |G|^2), and took 50-100 PCG
// iterations a step
// (docs/notes/2026-12-01-equilibrium-balance.md).
constexpr double kGradientFloor = 1e-4;
// A step whose PCG took more than this many iterations on K~'s factor has the next ones
// preconditioned with the factor of K~ + s H instead (AddDataShift), for as long as they take
// no more than this either: where the data hold soft modes of K (a slender tail, a body on
// soft anchors), K Phi K is tiny along them, H is not, and M = K~ Phi~ K~ misses them one PCG
// iteration each. Not lower: hand_press's steps pass 30 now and then, and there the shifted
// factor took more steps (docs/notes/2026-12-01-soft-modes.md).
constexpr int kShiftAfterIterations = 60;
// ResolveWithClosingContacts' re-solves of a step at most: one left hand_press's pushing-only
// steps closing contacts the re-solved step did not model, each line search then cut short
// (docs/notes/2026-12-03-closing-contacts-rounds.md).
constexpr int kContactRounds = 3;
// A pushing-only step whose line search cuts it below this share (seven halvings and more), or
// refuses it, gains next to nothing: its model of the cone's pieces missed a curvature across
// a kink. Such a step is solved again with the cone's curvature at its bound on every free
// vertex, a model above the penalty on every piece, and the lower of the two is taken. Without
// it a frame of tool_table stalled where the exact pieces' step was cut to 1/256 in every outer
// iteration. Not at larger shares: far from the solution the forces' own curvature cuts steps
// to 1/2-1/32, the exact step still gains, and the majorized one's short steps left a twisted
// armadillo's frames far from their minimum (docs/notes/2026-12-06-pushing-only-majorized-step.md).
constexpr double kMajorizeBelow = 1.0 / 64;
// ResolveAcrossPenaltyKinks' re-solves of a step at most. A round that changes more than half
// as many pieces as the one before shows that they do not settle (a free body whose
// tangential forces nothing bounds), and the solve's later steps make none: there they cost
// more PCG iterations than they saved (docs/notes/2026-12-07-what-the-pushing-hand-costs.md).
constexpr int kPieceRounds = 3;
// Their PCG iterations at least, however cheap the factor: without, a small mesh's steps
// stalled at the friction cone's kinks (docs/notes/2026-12-04-pushing-only-on-public-meshes.md).
constexpr int kMinPieceIterations = 10;

}  // namespace

struct EquilibriumSolver::Impl {
  BackendOptions options;
  int threads = 1;
  energy::Assembler objective;  // E_obj's Gauss-Newton system: H, g
  energy::Assembler physics;    // K = d2Pi/dx2 and f = dPi/dx
  // Where K is not positive definite (compressed or turning elements): its projection
  // (energy/term.h, Curvature) for the preconditioner's factor.
  energy::Assembler projected;
  uint64_t pattern_revision = 0;

  EquilibriumFactor factor;  // K~'s, the preconditioner's
  // The per-vertex blocks Phi~^-1 of the preconditioner.
  std::vector<Eigen::Matrix3d> phi_inverse;
  double first_gradient_norm = 0.0;  // |G| at the solve's start (kGradientFloor)
  // Whether the next step's factor takes the data in (kShiftAfterIterations); kept from solve
  // to solve while the pattern holds.
  bool shift_data = false;

  // The linearization at x: penalties, their gradients and curvatures; G the objective's gradient.
  Eigen::VectorXd g, f, phi_gradient, G;
  std::vector<Eigen::Matrix3d> phi;
  double equilibrium_energy = 0.0;

  // The penalties at f (set by Linearize): value, gradients, curvatures, and Phi~^-1.
  void Penalties(const energy::Equilibrium& eq) {
    const int n = physics.num_vertices();
    phi.resize(static_cast<size_t>(n));
    phi_inverse.resize(static_cast<size_t>(n));
    phi_gradient.setZero(3 * n);
    equilibrium_energy = 0.0;
    for (int v = 0; v < n; ++v) {
      Eigen::Vector3d gradient;
      Eigen::Matrix3d& c = phi[static_cast<size_t>(v)];
      equilibrium_energy += eq.Penalty(v, f.segment<3>(3 * v), &gradient, &c);
      phi_gradient.segment<3>(3 * v) = gradient;
      phi_inverse[static_cast<size_t>(v)] = PenaltyBlockInverse(eq, v, c);
    }
  }

  // The pushing-only penalties' curvature with the cone's part at its bound on every free
  // vertex (Equilibrium::Penalty's cone_at_bound): a model that majorizes the penalty across
  // its kinks.
  void MajorizeCone(const energy::Equilibrium& eq) {
    for (size_t v = 0; v < phi.size(); ++v) {
      if (eq.site[v] != energy::ForceSite::kFree) continue;
      const int i = static_cast<int>(v);
      eq.Penalty(i, f.segment<3>(3 * i), nullptr, &phi[v], /*cone_at_bound=*/true);
      phi_inverse[v] = PenaltyBlockInverse(eq, i, phi[v]);
    }
  }

  // Where the line search cut the step to below kMajorizeBelow (or refused it): the step again
  // from x_start on the majorized model (MajorizeCone, the same factor), kept where its line
  // search ends lower; *b, *x and *dx are then its own. The penalties are x_start's again after.
  // Whether it was kept.
  bool MajorizedStep(const energy::Problem& problem, double energy, const Vertices& x_start, Backtracked* b,
                     Vertices* x, Eigen::VectorXd* dx, SolveReport* report) {
    const energy::Equilibrium& eq = *problem.equilibrium();
    MajorizeCone(eq);
    Eigen::VectorXd dm;
    bool kept = false;
    if (Pcg(-G, kMaxPcgIterations, &dm, report) && dm.dot(G) < 0.0) {
      Vertices moved = x_start, trial;
      const Backtracked bm = Backtrack(problem, dm, energy, 10, threads, &trial, &moved, report);
      if (bm.accepted && (!b->accepted || bm.energy < b->energy)) {
        *b = bm;
        x->swap(moved);
        dx->swap(dm);
        plain_step = false;
        kept = true;
      }
    }
    Penalties(eq);
    return kept;
  }

  // The last PCG's residual, and whether the last step is the plain PCG solution of x's step
  // model (no re-solve replaced it): then what its model promised is comparable with what the
  // energy gave, and the residual says what a next step on that model could still gain.
  Eigen::VectorXd last_residual, step_residual;
  bool plain_step = false;
  // Whether the re-solves across the pushing-only penalty's kinks settled in this solve's
  // steps so far (ResolveAcrossPenaltyKinks; kPieceRounds).
  bool piece_rounds_settle = true;

  // The rigid modes and the held turns at x (solvers/fast/step_modes.h).
  StepModes modes;
  // The contacts the step being solved closes, closed in its model (empty otherwise).
  ClosingContacts closing;

  // H, g, K, f, the penalties and G at x; *terms (first only) the energy there.
  void Linearize(const energy::Problem& problem, const Vertices& x, bool first, EnergyTerms* terms,
                 SolveReport* report) {
    const auto t0 = Clock::now();
    closing.Clear();
    objective.AssembleGaussNewton(problem, x, first, &g, terms);
    physics.AssembleSecondOrder(problem, x, energy::Curvature::kExact, true, &f);
    physics.Finish(problem, 0.0, &f);
    Penalties(*problem.equilibrium());
    modes.Build(problem, x, [this](const Eigen::VectorXd& p, Eigen::VectorXd* y) { Product(p, y); });
    G = ModelGradient();  // in the steps' space: its norm is what the stops compare
    if (terms != nullptr) terms->equilibrium = equilibrium_energy;
    report->assemble_s += Seconds(t0);
  }

  // The step model's gradient g + K phi' at the current penalties (with the contacts a re-solve
  // holds closed: their stiffness in K's product), on the held turns' complement.
  Eigen::VectorXd ModelGradient() {
    Eigen::VectorXd gradient;
    BlockProduct(physics.H(), physics.block_rows(), phi_gradient, threads, &gradient);
    closing.AddProduct(phi_gradient, &gradient);
    gradient += g;
    modes.ProjectHeld(&gradient);
    return gradient;
  }

  // y = P_W (H + K Phi K) p, P_W = I - W W^T (p orthogonal to the held turns W: the step's
  // matrix on their complement).
  void Product(const Eigen::VectorXd& p, Eigen::VectorXd* y) {
    Eigen::VectorXd kp, hp;
    BlockProduct(physics.H(), physics.block_rows(), p, threads, &kp);
    closing.AddProduct(p, &kp);
    for (size_t v = 0; v < phi.size(); ++v) kp.segment<3>(3 * v) = phi[v] * kp.segment<3>(3 * v).eval();
    BlockProduct(physics.H(), physics.block_rows(), kp, threads, y);
    closing.AddProduct(kp, y);
    BlockProduct(objective.H(), objective.block_rows(), p, threads, &hp);
    *y += hp;
    modes.ProjectHeld(y);
  }

  // The decrease the step model at x promises for its plain step dx, -(G^T dx + 1/2 dx^T M dx):
  // with PCG from zero on M dx = -G, M dx = -G - r, so 1/2 dx^T (r - G) (as the classic solve).
  double ModelDecrease(const Eigen::VectorXd& dx) const { return 0.5 * dx.dot(step_residual - G); }

  // What a next step on x's model could still gain from the step's PCG residual r: about
  // 1/2 r^T M^-1 r, with the preconditioner for M^-1.
  double ResidualGain(SolveReport* report) {
    const ScopedThreads one_thread(1);  // as in Pcg
    Eigen::VectorXd z;
    Precondition(step_residual, &z, report);
    return 0.5 * step_residual.dot(z);
  }

  // z = B Phi~^-1 B r + R (R^T A R)^-1 R^T r with B = P K~^-1 P, P = I - R R^T - W W^T (no
  // rigid modes and no held turns: B = K~^-1). On the held turns' complement, where PCG runs.
  void Precondition(const Eigen::VectorXd& r, Eigen::VectorXd* z, SolveReport* report) {
    Eigen::VectorXd u, projected = r;
    modes.Project(&projected);
    auto solve = [&](const Eigen::VectorXd& b, Eigen::VectorXd* out) {
      factor.Solve(b, out);
      ++report->linear_solves;
    };
    solve(projected, &u);
    modes.Project(&u);
    for (size_t v = 0; v < phi_inverse.size(); ++v) u.segment<3>(3 * v) = phi_inverse[v] * u.segment<3>(3 * v).eval();
    modes.Project(&u);
    solve(u, z);
    modes.Project(z);
    modes.AddCoarse(r, z);
  }

  // PCG on P_W (H + K Phi K) dx = b from dx = 0, or from *start where that is nearer (b, dx
  // and *start orthogonal to the held turns); false if it did not converge in max_iterations.
  // From a start the target is relative to the start's residual: a re-solve's change is local,
  // and within a share of |b| the start would come back unchanged
  // (docs/notes/2026-12-04-warm-re-solves.md).
  bool Pcg(const Eigen::VectorXd& b, int max_iterations, Eigen::VectorXd* dx, SolveReport* report,
           const Eigen::VectorXd* start = nullptr) {
    const ScopedThreads one_thread(1);
    const auto t0 = Clock::now();
    const double b_norm = b.norm();
    double target = std::max(kPcgTolerance * b_norm, kGradientFloor * first_gradient_norm);
    Eigen::VectorXd r = b, z, q;
    bool warm = false;
    if (b_norm > 0.0 && start != nullptr && start->size() == b.size() && start->allFinite()) {
      Product(*start, &q);
      q = b - q;  // the start's residual
      const double r_norm = q.norm();
      warm = r_norm < b_norm;  // else from zero: the start is worse than nothing
      if (warm) {
        r.swap(q);
        target = std::max(kPcgTolerance * r_norm, kGradientFloor * first_gradient_norm);
      }
    }
    if (warm) {
      *dx = *start;  // (start may be dx itself)
    } else {
      dx->setZero(b.size());
    }
    if (b_norm == 0.0) return true;
    if (r.norm() <= target) {
      report->linear_solve_s += Seconds(t0);
      last_residual.swap(r);
      return true;
    }
    Precondition(r, &z, report);
    Eigen::VectorXd p = z;
    double rz = r.dot(z);
    bool converged = false;
    for (int k = 0; k < max_iterations; ++k) {
      Product(p, &q);
      const double pq = p.dot(q);
      if (!(pq > 0.0) || !(rz > 0.0) || !std::isfinite(rz)) break;
      const double step = rz / pq;
      *dx += step * p;
      r -= step * q;
      ++report->pcg_iterations;
      if (r.norm() <= target) {
        converged = true;
        break;
      }
      Precondition(r, &z, report);
      const double rz_next = r.dot(z);
      p = z + (rz_next / rz) * p;
      rz = rz_next;
    }
    report->linear_solve_s += Seconds(t0);
    last_residual.swap(r);
    return converged && dx->allFinite();
  }

  // Where *dx closes contacts that are open at x, solves the step again with them closed in
  // its model (solvers/fast/closing_contacts.h), and keeps that step if PCG converged and it
  // goes downhill; again with the contacts that step closes added, up to kContactRounds
  // times (an active-set update of the step's piecewise-linear contact model). The
  // preconditioner stays x's (its factor and its coarse matrix): the change is a few rank-one
  // terms. f, the penalties and G stay x's own.
  void ResolveWithClosingContacts(const energy::Problem& problem, const Vertices& x, Eigen::VectorXd* dx,
                                  SolveReport* report) {
    const Eigen::VectorXd f_at_x = f;
    for (int round = 0; round < kContactRounds; ++round) {
      if (closing.Find(problem, x, *dx, /*add=*/round > 0) == 0) break;
      f = f_at_x;
      closing.AddForce(&f);
      Penalties(*problem.equilibrium());
      Eigen::VectorXd resolved;
      if (!(Pcg(-ModelGradient(), kMaxPcgIterations, &resolved, report, dx) && resolved.dot(G) < 0.0)) break;
      *dx = resolved;
      plain_step = false;
    }
    if (closing.empty()) return;
    f = f_at_x;
    Penalties(*problem.equilibrium());
    closing.Clear();
  }

  // Where *dx carries forces across the pushing-only penalty's kinks, solves the step again
  // with the penalty modelled around the predicted forces (solvers/fast/penalty_pieces.h), on
  // the same factor; repeated while the predicted pieces change, up to kPieceRounds times,
  // within the PCG iterations a factorization costs (past them a new step is cheaper; at
  // least kMinPieceIterations), and kept while PCG converges and the step goes downhill. A
  // round that changes more than half as many pieces as the one before ends them, and the
  // solve's later steps make none (kPieceRounds). Its
  // model leaves out the contacts the step closes (ResolveWithClosingContacts' model): with
  // them hand_press, pushing only, erred the most of the versions tried
  // (docs/notes/2026-12-02-penalty-kinks.md); Step solves for those its result closes
  // afterwards. Whether it changed *dx.
  bool ResolveAcrossPenaltyKinks(const energy::Problem& problem, Eigen::VectorXd* dx, SolveReport* report) {
    const energy::Equilibrium& eq = *problem.equilibrium();
    if (!eq.pushing_only || !piece_rounds_settle) return false;
    int budget = std::min(std::max(factor.factorization_iterations(), kMinPieceIterations), kMaxPcgIterations);
    bool changed = false;
    PenaltyPieces pieces;
    pieces.Start(eq, f);
    bool remodelled = false;
    int last_changed = 0;
    for (int round = 0; round < kPieceRounds && budget > 0; ++round) {
      Eigen::VectorXd kdx;
      BlockProduct(physics.H(), physics.block_rows(), *dx, threads, &kdx);
      const int changed_pieces = pieces.Remodel(eq, f, kdx, &phi, &phi_gradient, &phi_inverse);
      if (changed_pieces == 0) break;
      if (round > 0 && 2 * changed_pieces > last_changed) {
        piece_rounds_settle = false;
        break;
      }
      last_changed = changed_pieces;
      remodelled = true;
      Eigen::VectorXd resolved;
      const int before = report->pcg_iterations;
      const bool converged = Pcg(-ModelGradient(), budget, &resolved, report, dx);
      budget -= report->pcg_iterations - before;
      if (!(converged && resolved.dot(G) < 0.0)) break;
      *dx = resolved;
      changed = true;
      plain_step = false;
    }
    if (remodelled) Penalties(eq);  // x's own model again
    return changed;
  }

  // The step: a new factor of K~ at x, then PCG with it. A factor kept from an earlier step
  // (while K moves with the turning elements and the contacts) failed more often than it
  // served: the failed attempts cost more PCG iterations than the factorizations it saved
  // (docs/notes/2026-12-01-equilibrium-fresh-factor.md). *truncated: PCG did not converge.
  bool Step(const energy::Problem& problem, const Vertices& x, Eigen::VectorXd* dx, bool* truncated,
            SolveReport* report) {
    *truncated = false;
    std::vector<double> plain_values;
    if (shift_data) plain_values = AddDataShift(problem, objective.H(), &physics.H());
    const bool factored = factor.Factorize(problem, x, &physics, &projected, threads, report);
    if (!plain_values.empty()) std::copy(plain_values.begin(), plain_values.end(), physics.H().valuePtr());
    if (!factored) return false;
    const int iterations_before = report->pcg_iterations;
    const bool converged = Pcg(-G, kMaxPcgIterations, dx, report);
    plain_step = converged;
    if (converged) step_residual.swap(last_residual);
    // On K~'s factor: more than the threshold switches the shift on; on K~ + s H's: more
    // switches it off, and the next step measures K~'s factor again. (One PCG's count: the
    // re-solve below is another system.)
    const int iterations = report->pcg_iterations - iterations_before;
    if (converged) ResolveWithClosingContacts(problem, x, dx, report);
    // The contacts the step across the kinks closes: its model had none of them.
    if (converged && ResolveAcrossPenaltyKinks(problem, dx, report)) ResolveWithClosingContacts(problem, x, dx, report);
    shift_data = plain_values.empty() ? iterations > kShiftAfterIterations : iterations <= kShiftAfterIterations;
    if (converged) return true;
    // PCG's iterates lower the step's quadratic model from 0, so one that has not converged
    // still points downhill: the line search takes it. Where soft anchors hold most of a
    // body the preconditioner (which takes an anchored vertex's free force as a surface
    // one's) can need more than kMaxPcgIterations (docs/notes/2026-12-01-equilibrium-fresh-factor.md).
    *truncated = true;
    return dx->allFinite() && dx->dot(G) < 0.0;
  }
};

EquilibriumSolver::EquilibriumSolver(const BackendOptions& options, int threads) : impl_(new Impl) {
  impl_->options = options;
  impl_->threads = threads;
  impl_->objective.set_threads(threads);
  impl_->physics.set_threads(threads);
  impl_->objective.set_groups(energy::ObjectiveGroups());
  impl_->physics.set_groups(energy::PhysicsGroups());
  impl_->projected.set_threads(threads);
  impl_->projected.set_groups(energy::PhysicsGroups());
}
EquilibriumSolver::~EquilibriumSolver() = default;

void EquilibriumSolver::set_threads(int threads) {
  impl_->threads = threads;
  impl_->objective.set_threads(threads);
  impl_->physics.set_threads(threads);
  impl_->projected.set_threads(threads);
}

SolveReport EquilibriumSolver::SolveAside(const energy::Problem& problem, double time_limit_s, Vertices* x) {
  const bool shift_data = impl_->shift_data;
  const uint64_t pattern_revision = impl_->pattern_revision;
  SolveReport report = Solve(problem, time_limit_s, x);
  // The same pattern (the next Solve would not measure K~'s factor again): its mode as before.
  if (impl_->pattern_revision == pattern_revision) impl_->shift_data = shift_data;
  return report;
}

SolveReport EquilibriumSolver::Solve(const energy::Problem& problem, double time_limit_s, Vertices* x) {
  const auto start = Clock::now();
  Impl& m = *impl_;
  SolveReport report;
  const energy::Equilibrium* eq = problem.equilibrium();
  if (eq == nullptr || !eq->IsValid(problem.num_vertices()) || x->rows() != problem.num_vertices()) {
    report.message = "fast back end: the equilibrium problem is not set up for its vertices";
    report.stop = StopReason::kFailure;
    return report;
  }
  const ScopedThreads threads(m.threads);
  auto t0 = Clock::now();
  report.pattern_rebuilds += m.objective.Prepare(problem, *x);
  report.pattern_rebuilds += m.physics.Prepare(problem, *x);
  if (m.physics.pattern_revision() != m.pattern_revision) {
    m.pattern_revision = m.physics.pattern_revision();
    m.factor.Reset();
    m.shift_data = false;  // another mesh or set of terms: K~'s factor is measured again
    ++report.analyses;
  }
  report.assemble_s += Seconds(t0);
  m.piece_rounds_settle = true;
  m.Linearize(problem, *x, /*first=*/true, &report.before, &report);
  report.after = report.before;
  double energy = report.before.total();
  m.first_gradient_norm = m.G.norm();
  report.largest_force_before = m.G.lpNorm<Eigen::Infinity>();
  bool refused = false;  // the last step: refused by the line search, or cut below the step tolerance
  report.success = true;
  report.stop = StopReason::kMaxIterations;
  Eigen::VectorXd dx;
  Vertices trial, x_start;
  const int max_steps = eq->max_steps > 0 ? std::min(eq->max_steps, m.options.max_iterations) : m.options.max_iterations;
  for (int step = 0; step < max_steps; ++step) {
    // (The floor also covers the earlier stop at 1e-9 of the first gradient's largest entry.)
    const double gradient = m.G.norm();
    if (gradient == 0.0 || (step > 0 && gradient <= kGradientFloor * m.first_gradient_norm)) {
      report.stop = StopReason::kGradient;
      break;
    }
    bool truncated = false;
    const bool stepped = m.Step(problem, *x, &dx, &truncated, &report);
    Backtracked b;
    if (eq->pushing_only) x_start = *x;
    if (stepped) {
      ++report.iterations;
      b = Backtrack(problem, dx, energy, 10, m.threads, &trial, x, &report);
    }
    // The majorized step stands in for a cut one: a solve whose last step it was, and short,
    // counts as refused (the frame is stalled if its forces stay unbalanced), as the cut step
    // would have.
    bool majorized = false;
    if (stepped && eq->pushing_only && (!b.accepted || b.alpha < kMajorizeBelow) &&
        !(time_limit_s > 0 && Seconds(start) >= time_limit_s)) {
      majorized = m.MajorizedStep(problem, energy, x_start, &b, x, &dx, &report);
      if (majorized) truncated = false;  // its PCG converged
    }
    // A truncated step that the line search cannot use is the solver's failure, not a
    // stationary point.
    if (!stepped || (truncated && !b.accepted)) {
      report.success = false;
      report.stop = StopReason::kFailure;
      report.message = "fast back end: the equilibrium step did not converge";
      break;
    }
    if (!b.accepted) {
      refused = true;
      report.stop = StopReason::kNoDecrease;
      break;
    }
    const double largest = b.largest_move;
    const double decrease = (energy - b.energy) / std::max(energy, 1e-300);
    const double gain = energy - b.energy;
    energy = b.energy;
    report.after = b.terms;
    const bool settled = !truncated && b.alpha == 1.0 && largest <= m.options.equilibrium_step_tolerance &&
                         decrease < kSmallStepDecrease;
    const bool tiny = largest <= m.options.step_tolerance && (!eq->pushing_only || decrease < kSmallStepDecrease);
    if (tiny || largest == 0.0 || settled) {
      refused = b.alpha < 1.0 || majorized;
      report.stop = StopReason::kStep;
      break;
    }
    const double tolerance = step + 1 >= kFullSteps ? std::max(m.options.relative_tolerance, kLateTolerance)
                                                    : m.options.relative_tolerance;
    if (decrease < tolerance) {
      report.stop = StopReason::kEnergy;
      break;
    }
    // A whole step that is the plain solution of x's model, on a smooth penalty (no pushing-only
    // kinks): the next step gains about what this one's model promised and the energy did not
    // give, plus what PCG left. Below the tolerance it is not made
    // (docs/notes/2026-12-04-model-gap-stop.md).
    if (m.plain_step && b.alpha == 1.0 && !eq->pushing_only) {
      const double limit = tolerance * energy;
      const double gap = std::abs(m.ModelDecrease(dx) - gain);
      if (gap < limit && gap + m.ResidualGain(&report) < limit) {
        report.stop = StopReason::kPredicted;
        break;
      }
    }
    if (time_limit_s > 0 && Seconds(start) >= time_limit_s) {
      report.stop = StopReason::kTimeLimit;
      break;
    }
    if (step + 1 == max_steps) break;
    m.Linearize(problem, *x, /*first=*/false, nullptr, &report);
  }
  // Its one step refused or cut to nothing, as the classic solve's (a refused or cut step ends
  // a solve; docs/theory/stopping.md#stalled): G was linearized where the solve stopped, or a
  // step shorter than the step tolerance before.
  if (report.iterations == 1 && refused) {
    report.mostly_refused = true;
    report.largest_force_after = m.G.lpNorm<Eigen::Infinity>();
  }
  if (report.success) report.message = std::string("fast back end (equilibrium): ") + ToString(report.stop);
  if (!x->allFinite()) {
    report.success = false;
    report.stop = StopReason::kFailure;
    report.message = "fast back end: the step made the positions non-finite";
  }
  return report;
}

}  // namespace fast_backend
}  // namespace femreg
