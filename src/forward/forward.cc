// The forward quasi-static solve: Newton iterations on the exact Hessian of the potential
// (the consistent corotational tangent, or the stable neo-Hookean element's), with the exact
// gradient, a backtracking line search on the total potential (rotations recomputed at every
// trial point), load stepping, and clamped / prescribed DOFs eliminated. By default the exact
// Hessian is tried first and, when CHOLMOD finds it not positive definite, its element-wise
// PSD projection is used for that iteration. The energy is the energy layer's (one block per
// element, and with the neo-Hookean nodal volume energy::NodalVolume beside them), assembled
// by its assembler (energy/assembler.h); the free rows and columns of that system, lower
// triangle, are solved with CHOLMOD's supernodal Cholesky. The pattern is fixed, so the
// symbolic analysis is done once per solve.
#include "femreg/forward.h"

#include <Eigen/Geometry>
#include <Eigen/LU>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <iomanip>
#include <limits>
#include <sstream>

#include "forward/quasi_static_solver.h"
#include "parallel/threads.h"

namespace femreg {
namespace forward_internal {

bool QuasiStaticSolver::LineSearch(const Vertices& x, const Eigen::VectorXd& step, double slope,
                                   double potential, double residual_norm,
                                   const Eigen::VectorXd& load, bool may_relax, double* alpha,
                                   bool* relaxed, Trial* trial) {
  *relaxed = false;
  Eigen::VectorXd trial_gradient;
  // The neo-Hookean energy sums terms of about 4 mu V per element that cancel at small
  // strain, so its round-off is that sum's, not a fraction of the (small) net energy.
  double cancelling = 0.0;
  if (neo_hookean()) {
    for (int e = 0; e < nt(); ++e) cancelling += 4.0 * model_.rest(e).mu * model_.rest(e).volume;
  }
  while (*alpha >= options_.min_step) {
    trial->x = x;
    ScatterFree(step, *alpha, &trial->x);
    trial->elastic = Elastic(trial->x, &trial->gradient);
    trial->potential = Potential(trial->elastic, trial->x, load) + Extra(trial->x, nullptr);
    const double value = trial->potential;
    if (std::isfinite(value)) {
      if (value <= potential + 1e-4 * *alpha * slope) return true;
      // Near the solution the decrease drowns in round-off of the energy: accept a step
      // that does not raise the potential beyond that noise and reduces the force imbalance.
      const double noise = 1e-12 * (std::abs(trial->elastic) + std::abs(value)) +
                           64 * std::numeric_limits<double>::epsilon() * cancelling +
                           std::numeric_limits<double>::min();
      if (value - potential <= noise) {
        trial_gradient = trial->gradient;
        Extra(trial->x, &trial_gradient);
        if (FreeNorm(trial_gradient - load) < residual_norm) return true;
      }
      if (may_relax && *alpha == 1.0) {
        *relaxed = true;
        return true;
      }
    }
    // Safeguarded quadratic interpolation of the potential along the step.
    double next = 0.5 * *alpha;
    if (std::isfinite(value)) {
      const double denom = 2.0 * (value - potential - slope * *alpha);
      if (denom > 0) next = std::clamp(-slope * *alpha * *alpha / denom, 0.1 * *alpha, 0.5 * *alpha);
    }
    *alpha = next;
  }
  return false;
}

void QuasiStaticSolver::Run() {
  Vertices x = mesh_.x;
  for (int v : problem_.clamped) x.row(v) = mesh_.rest.row(v);
  Eigen::VectorXd elastic_gradient;  // of the elastic energy at x
  Trial trial;
  Eigen::VectorXd gradient, residual(3 * nv()), load(3 * nv());
  Eigen::VectorXd rhs(free_dofs_.size()), step(free_dofs_.size());
  // The watchdog (Chamberlain et al. 1982): when the full Newton step raises the potential,
  // take it anyway; if within options.watchdog_steps further iterations (full steps too) the
  // potential has not dropped below the point before it (the reference), return there and
  // backtrack. A slender or nearly incompressible body makes the full step
  // from a rotating configuration stretch stiff directions that are curved in x: the
  // potential rises although the next iterate lands next to the solution (the Maratos
  // effect), and a monotone search would crawl with short steps instead. Contact potentials
  // change their active set per iteration, so their potentials are not compared across
  // iterations: no watchdog with problem.potential.
  struct Watchdog {
    bool active = false;
    int steps = 0;  // iterations since the reference
    Vertices x;
    Eigen::VectorXd gradient;
    double elastic = 0.0, potential = 0.0, residual_norm = 0.0;
    Eigen::VectorXd step;
    double slope = 0.0;
    double full_step_potential = 0.0;  // at reference + step
  } watch;
  const bool watchdog_allowed =
      options_.watchdog_steps > 0 && model_.type() == ElasticModelType::kCorotational &&
      problem_.potential == nullptr;
  bool have_initial = false;
  double reference = 0.0;  // force scale of the relative tolerance
  double potential = 0.0, residual_norm = 0.0;

  double tolerance = 0.0;  // N, of the current iteration
  summary_.termination = ForwardTermination::kConverged;
  summary_.message = "converged";
  for (int load_step = 1; load_step <= options_.load_steps; ++load_step) {
    const double scale = static_cast<double>(load_step) / options_.load_steps;
    load = scale * full_load_;
    ForwardLoadStep record;
    record.load_step = load_step;
    record.load_factor = scale;
    // A factorization failure ends the solve; its step is reported as such.
    auto fail_step = [&] {
      record.termination = summary_.termination;
      record.final_residual_norm = residual_norm;
      summary_.load_steps.push_back(record);
    };

    // Move the prescribed vertices; predict the free ones with the current stiffness
    // (K_ff dx_f = -K_fp dx_p), so that elements next to them are not crushed.
    if (!problem_.prescribed.empty()) {
      Vertices delta = Vertices::Zero(nv(), 3);
      bool moved = false;
      for (const auto& p : problem_.prescribed) {
        delta.row(p.first) = (mesh_.rest.row(p.first) + scale * p.second.transpose()) - x.row(p.first);
        moved = moved || delta.row(p.first).squaredNorm() > 0;
      }
      if (moved && !free_dofs_.empty()) {
        if (!AssembleAndFactorize(x)) return fail_step();
        // The coupling with the matrix just factorized (the assembler's, over all DOFs).
        const Eigen::Map<const Eigen::VectorXd> moved_dofs(delta.data(), 3 * nv());
        const Eigen::VectorXd coupling = assembler_.H() * moved_dofs;
        for (size_t i = 0; i < free_dofs_.size(); ++i) rhs(i) = -coupling(free_dofs_[i]);
        step = factorization_.solve(rhs);
        if (step.allFinite()) ScatterFree(step, 1.0, &x);
      }
      x += delta;
    }

    double elastic = Elastic(x, &elastic_gradient);
    gradient = elastic_gradient;
    residual = gradient - load;
    potential = Potential(elastic, x, load);
    residual_norm = FreeNorm(residual);
    if (!have_initial) {
      summary_.initial_residual_norm = residual_norm;
      reference = residual_norm;
      have_initial = true;
    }

    double step_length = 0.0;
    // The residual at x: the elastic force held in elastic_gradient, the extra terms' added.
    auto refresh_residual = [&] {
      gradient = elastic_gradient;
      Extra(x, &gradient);
      residual = gradient - load;
      residual_norm = FreeNorm(residual);
    };
    // Moves to the line search's trial point, taken at step length a.
    auto take_trial = [&](double a) {
      Accept(&trial, &x, &elastic_gradient);
      elastic = trial.elastic;
      potential = trial.potential;
      refresh_residual();
      step_length = a;
    };
    watch.active = false;
    ForwardTangent step_tangent = options_.tangent;
    ForwardTermination step_result = ForwardTermination::kMaxIterations;
    for (int iteration = 0;; ++iteration) {
      if (problem_.potential != nullptr) {  // e.g. contacts: refreshed per Newton iteration
        problem_.potential->Refresh(x);
        gradient = elastic_gradient;
        potential = Potential(elastic, x, load) + Extra(x, &gradient);
        residual = gradient - load;
        residual_norm = FreeNorm(residual);
      }
      // Reference force: external loads, support reactions, and the first imbalance.
      double reaction = 0.0;
      for (int d = 0; d < 3 * nv(); ++d)
        if (free_index_[d] < 0) reaction += residual(d) * residual(d);
      reference = std::max({reference, load.norm(), std::sqrt(reaction)});
      summary_.iterations.push_back(
          {load_step, iteration, potential, residual_norm, step_length, step_tangent});
      if (iteration == 0) record.initial_residual_norm = residual_norm;
      tolerance = std::max({options_.absolute_tolerance, options_.relative_tolerance * reference,
                            RoundoffFloor(x)});
      if (options_.verbose) {
        std::printf("forward step %d iter %3d  potential %+.9e  |r| %.3e  alpha %.3g%s\n",
                    load_step, iteration, potential, residual_norm, step_length,
                    iteration > 0 && step_tangent == ForwardTangent::kProjected &&
                            options_.tangent == ForwardTangent::kFull
                        ? "  (projected)"
                        : "");
      }
      if (free_dofs_.empty() || residual_norm <= tolerance) {
        step_result = ForwardTermination::kConverged;
        break;
      }
      if (iteration >= options_.max_iterations) break;

      if (!AssembleAndFactorize(x)) return fail_step();
      ++record.iterations;
      step_tangent = element_matrix_ == ElementMatrix::kExact       ? ForwardTangent::kFull
                     : element_matrix_ == ElementMatrix::kProjected ? ForwardTangent::kProjected
                                                                    : ForwardTangent::kWarped;
      if (options_.tangent == ForwardTangent::kFull && step_tangent == ForwardTangent::kProjected) {
        ++record.projected_iterations;
      }
      for (size_t i = 0; i < free_dofs_.size(); ++i) rhs(i) = -residual(free_dofs_[i]);
      step = factorization_.solve(rhs);
      if (!step.allFinite()) {
        Fail(ForwardTermination::kFactorizationFailed,
             "the Newton step is not finite: the reduced stiffness is singular");
        return fail_step();
      }
      const double slope = -rhs.dot(step);  // directional derivative, < 0

      // Line search on the total potential, rotations recomputed at every trial point.
      double alpha = 1.0;
      bool relaxed = false;
      const bool may_relax = watchdog_allowed &&
                             (!watch.active || watch.steps <= options_.watchdog_steps);
      if (!LineSearch(x, step, slope, potential, residual_norm, load, may_relax, &alpha,
                      &relaxed, &trial)) {
        step_result = ForwardTermination::kLineSearchFailed;
        break;
      }
      if (relaxed) {
        ++record.relaxed_steps;
        if (!watch.active) {  // the last accepted point becomes the watchdog's reference
          watch.active = true;
          watch.steps = 0;
          watch.x = x;
          watch.gradient = elastic_gradient;
          watch.elastic = elastic;
          watch.potential = potential;
          watch.residual_norm = residual_norm;
          watch.step = step;
          watch.slope = slope;
          watch.full_step_potential = trial.potential;
        }
      }
      take_trial(alpha);

      if (watch.active) {
        ++watch.steps;
        if (potential <= watch.potential + 1e-4 * watch.slope || residual_norm <= tolerance) {
          watch.active = false;  // the relaxed steps paid off (or reached an equilibrium)
        } else if (watch.steps > options_.watchdog_steps) {
          // They did not: back to the reference, and the monotone search along its step
          // (the full step there is known to fail, so start from the interpolated length).
          watch.active = false;
          ++record.watchdog_restarts;
          x = watch.x;
          elastic_gradient = watch.gradient;
          elastic = watch.elastic;
          potential = watch.potential;
          residual_norm = watch.residual_norm;
          double start = 0.5;
          const double denom = 2.0 * (watch.full_step_potential - potential - watch.slope);
          if (std::isfinite(watch.full_step_potential) && denom > 0) {
            start = std::clamp(-watch.slope / denom, 0.1, 0.5);
          }
          alpha = start;
          if (!LineSearch(x, watch.step, watch.slope, potential, residual_norm, load,
                          /*may_relax=*/false, &alpha, &relaxed, &trial)) {
            refresh_residual();
            step_result = ForwardTermination::kLineSearchFailed;
            break;
          }
          take_trial(alpha);
        }
      }
    }

    record.termination = step_result;
    record.final_residual_norm = residual_norm;
    summary_.load_steps.push_back(record);
  }

  // The last load step decides: an earlier one that stopped short only gave the next a
  // worse start (load steps are a continuation device), but the records and the message
  // keep it.
  const ForwardLoadStep& last = summary_.load_steps.back();
  summary_.termination = last.termination;
  std::ostringstream os;
  os << std::setprecision(4);
  const int steps = options_.load_steps;
  std::string earlier;
  for (const ForwardLoadStep& step : summary_.load_steps) {
    if (&step == &last || step.termination == ForwardTermination::kConverged) continue;
    earlier += (earlier.empty() ? "" : ", ") + std::to_string(step.load_step) + " (" +
               ToString(step.termination) + ")";
  }
  switch (last.termination) {
    case ForwardTermination::kConverged:
      os << "converged: |residual| " << residual_norm << " N <= " << tolerance
         << " N; Newton iterations per load step: " << IterationsPerStep(summary_.load_steps);
      if (!earlier.empty()) os << "; earlier load steps that did not converge: " << earlier;
      break;
    case ForwardTermination::kMaxIterations:
      os << "not converged: max_iterations (" << options_.max_iterations
         << ") reached at load step " << last.load_step << " of " << steps << " (load factor "
         << last.load_factor << "), |residual| " << residual_norm << " N > " << tolerance << " N";
      break;
    default:
      os << "not converged: the line search found no decrease of the potential above min_step ("
         << options_.min_step << ") at load step " << last.load_step << " of " << steps
         << " (load factor " << last.load_factor << "), |residual| " << residual_norm
         << " N > " << tolerance << " N";
      break;
  }
  if (last.termination != ForwardTermination::kConverged && last.load_step > 1) {
    if (earlier.empty()) {
      os << " (the earlier load steps converged)";
    } else {
      os << " (earlier load steps that did not converge: " << earlier << ")";
    }
  }
  if (last.termination != ForwardTermination::kConverged) {
    os << ". Try more load steps (forward.load_steps, now " << steps
       << ") or a larger forward.max_iterations; if it still fails, the load may have no "
          "equilibrium that the model can represent: look for inverted elements ("
       << "inverted_elements in the summary), e.g. a very soft material under its own weight";
  }
  summary_.message = os.str();

  mesh_.x = x;
  summary_.final_residual_norm = residual_norm;
  summary_.final_energy = potential;
  summary_.max_displacement = (x - mesh_.rest).rowwise().norm().maxCoeff();
  int inverted = 0;
  for (int e = 0; e < nt(); ++e) {
    const Vector12 xe = model_.Gather(x, e);
    Eigen::Matrix<double, 3, 4> xm;
    for (int k = 0; k < 4; ++k) xm.col(k) = xe.segment<3>(3 * k);
    if (!(DeformationGradient(xm, model_.rest(e).dm_inv).determinant() > 0)) ++inverted;
  }
  summary_.inverted_elements = inverted;
}

}  // namespace forward_internal

using forward_internal::QuasiStaticSolver;
using forward_internal::Clock;

Status SolveQuasiStatic(const ForwardProblem& problem, const ForwardOptions& options,
                        ElasticModel* model, TetMesh* mesh, ForwardSummary* summary) {
  const auto start = Clock::now();
  *summary = ForwardSummary();
  QuasiStaticSolver solver(problem, options, model, mesh, summary);
  {
    const ScopedThreads threads(summary->num_threads);
    if (solver.Validate() && solver.Setup()) solver.Run();
  }
  // Leave the model's rotations consistent with the result.
  if (summary->termination != ForwardTermination::kInvalidInput) model->UpdateRotations(mesh->x);
  summary->total_time_s = Seconds(start);
  if (summary->termination == ForwardTermination::kInvalidInput ||
      summary->termination == ForwardTermination::kFactorizationFailed) {
    return Status::Error(std::string("SolveQuasiStatic: ") + ToString(summary->termination) +
                         ": " + summary->message);
  }
  return Status::Ok();
}

Status EvaluateForwardSystem(const ForwardProblem& problem, const ForwardOptions& options,
                             const ElasticModel& model, const TetMesh& mesh, const Vertices& x,
                             Eigen::VectorXd* residual, Eigen::SparseMatrix<double>* tangent,
                             std::vector<int>* free_dofs) {
  if (x.rows() != mesh.num_vertices() || x.cols() != 3 || !x.allFinite()) {
    return Status::Error("EvaluateForwardSystem: x must be a finite #V by 3 matrix");
  }
  ForwardSummary summary;
  TetMesh copy = mesh;  // the solver's mesh is writable; this one is not written
  QuasiStaticSolver solver(problem, options, &model, &copy, &summary);
  const ScopedThreads threads(summary.num_threads);
  if (!solver.Validate() || !solver.Setup()) {
    return Status::Error(std::string("EvaluateForwardSystem: ") + ToString(summary.termination) +
                         ": " + summary.message);
  }
  solver.EvaluateSystem(x, options.tangent, residual, tangent, free_dofs);
  return Status::Ok();
}

Status EvaluateForwardForces(const ForwardProblem& problem, const ForwardOptions& options,
                             const ElasticModel& model, const TetMesh& mesh, const Vertices& x,
                             ForwardForces* forces) {
  if (x.rows() != mesh.num_vertices() || x.cols() != 3 || !x.allFinite()) {
    return Status::Error("EvaluateForwardForces: x must be a finite #V by 3 matrix");
  }
  ForwardSummary summary;
  TetMesh copy = mesh;  // the solver's mesh is writable; this one is not written
  QuasiStaticSolver solver(problem, options, &model, &copy, &summary);
  const ScopedThreads threads(summary.num_threads);
  // No reduced system: only gradients are evaluated.
  if (!solver.Validate() || !solver.Setup(/*reduced=*/false)) {
    return Status::Error(std::string("EvaluateForwardForces: ") + ToString(summary.termination) +
                         ": " + summary.message);
  }
  solver.EvaluateForces(x, forces);
  return Status::Ok();
}

ForceResultant ResultantAboutCentroid(const Vertices& forces, const Vertices& positions,
                                      const Eigen::VectorXd& mass) {
  const Eigen::Vector3d centroid = (positions.transpose() * mass) / mass.sum();
  ForceResultant r;
  for (Eigen::Index v = 0; v < forces.rows(); ++v) {
    const Eigen::Vector3d f = forces.row(v).transpose();
    r.force += f;
    r.torque += (positions.row(v).transpose() - centroid).cross(f);
  }
  return r;
}

}  // namespace femreg
