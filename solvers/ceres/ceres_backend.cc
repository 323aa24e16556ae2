#include "solvers/ceres/ceres_backend.h"

#include <algorithm>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include "parallel/threads.h"
#include "solvers/ceres/equilibrium_costs.h"

namespace femreg {
namespace ceres_backend {

SolveReport CeresBackend::Solve(const energy::Problem& problem, double time_limit_s, Vertices* x) {
  // With an equilibrium the physics groups' energy is not minimized: its forces' penalty is
  // (solvers/ceres/equilibrium_costs.h).
  const energy::Equilibrium* equilibrium = problem.equilibrium();
  const uint32_t minimized = equilibrium != nullptr ? energy::ObjectiveGroups() : ~0u;
  std::unique_ptr<EquilibriumState> equilibrium_state;
  if (equilibrium != nullptr) {
    equilibrium_state = std::make_unique<EquilibriumState>(problem, x, ResolveThreadCount(options_.num_threads));
  }
  ceres::Problem::Options problem_options;
  problem_options.cost_function_ownership = ceres::DO_NOT_TAKE_OWNERSHIP;
  problem_options.loss_function_ownership = ceres::DO_NOT_TAKE_OWNERSHIP;
  problem_options.enable_fast_removal = false;
  problem_options.evaluation_callback = equilibrium_state.get();
  ceres::Problem ceres_problem(problem_options);
  std::vector<std::unique_ptr<ceres::CostFunction>> costs;
  std::vector<std::unique_ptr<ceres::LossFunction>> losses;
  costs.reserve(static_cast<size_t>(problem.num_blocks()));
  double* const data = x->data();
  double offset = 0.0;  // the minimized blocks' constant (the neo-Hookean element's)
  problem.ForEachSet([&](const auto& set) {
    if (!energy::InGroups(minimized, set.group())) return;
    using T = typename std::decay_t<decltype(set.blocks())>::value_type;
    const energy::Loss& loss = set.loss();
    std::map<double, ceres::LossFunction*> loss_of_weight;  // one adapter per distinct w
    std::vector<double*> blocks(T::kVertices);
    for (const T& block : set.blocks()) {
      offset += energy::OffsetValue(block, loss);
      ceres::LossFunction* loss_function = nullptr;
      if (loss.robust()) {
        auto it = loss_of_weight.find(block.weight);
        if (it == loss_of_weight.end()) {
          losses.push_back(std::make_unique<LossAdapter>(loss, block.weight));
          it = loss_of_weight.emplace(block.weight, losses.back().get()).first;
        }
        loss_function = it->second;
        costs.push_back(std::make_unique<TermCost<T>>(&block, 1.0));
      } else {
        costs.push_back(std::make_unique<TermCost<T>>(&block, std::sqrt(block.weight)));
      }
      for (int i = 0; i < T::kVertices; ++i) blocks[i] = data + 3 * block.vertices[i];
      ceres_problem.AddResidualBlock(costs.back().get(), loss_function, blocks);
    }
  });
  if (equilibrium_state) AddEquilibriumCosts(equilibrium_state.get(), data, &ceres_problem, &costs, &losses);
  const energy::NodalVolume* nodal = energy::InGroups(minimized, energy::TermGroup::kElastic) ? problem.nodal_volume() : nullptr;
  if (nodal != nullptr) {
    std::vector<double*> star_blocks;
    for (int a = 0; a < nodal->num_vertices(); ++a) {
      auto cost = std::make_unique<NodalVolumeCost>(nodal->StarOf(a));
      if (cost->vertices().empty()) continue;
      star_blocks.clear();
      for (int v : cost->vertices()) star_blocks.push_back(data + 3 * v);
      costs.push_back(std::move(cost));
      ceres_problem.AddResidualBlock(costs.back().get(), nullptr, star_blocks);
    }
  }
  for (int v = 0; v < problem.num_vertices(); ++v) {
    double* block = data + 3 * v;
    if (problem.is_fixed(v) && ceres_problem.HasParameterBlock(block)) {
      ceres_problem.SetParameterBlockConstant(block);
    }
  }

  ceres::Solver::Options solver_options;
  solver_options.max_num_iterations = options_.max_iterations;
  if (problem.equilibrium() != nullptr && problem.equilibrium()->max_steps > 0) {
    solver_options.max_num_iterations = std::min(options_.max_iterations, problem.equilibrium()->max_steps);
  }
  solver_options.function_tolerance = options_.relative_tolerance;
  solver_options.num_threads = ResolveThreadCount(options_.num_threads);
  solver_options.logging_type = ceres::SILENT;
  solver_options.minimizer_progress_to_stdout = false;
  solver_options.trust_region_strategy_type = options_.trust_region == TrustRegion::kDogleg
                                                  ? ceres::DOGLEG
                                                  : ceres::LEVENBERG_MARQUARDT;
  if (options_.linear_solver == LinearSolver::kConjugateGradients) {
    solver_options.linear_solver_type = ceres::CGNR;
    solver_options.preconditioner_type = ceres::JACOBI;
  } else {
    solver_options.linear_solver_type = ceres::SPARSE_NORMAL_CHOLESKY;
    solver_options.sparse_linear_algebra_library_type = ceres::SUITE_SPARSE;
  }
  if (time_limit_s > 0) solver_options.max_solver_time_in_seconds = time_limit_s;
  // Start with Gauss-Newton steps (damping 1e-8 of the scaled diagonal, as the fast back
  // end): with rotations and pairs held the energy is quadratic but for the robust losses,
  // and Ceres' default start (1e-4) truncates the steps along soft modes so much that a
  // soft material stops on the parameter tolerance far from the minimum.
  solver_options.initial_trust_region_radius = 1e8;

  SolveReport report;
  report.before = problem.Evaluate(*x);
  report.after = report.before;
  // Ceres' relative decrease is over its cost, which carries the blocks' offsets (the
  // neo-Hookean element's constant): scaled so that it means the same decrease of the
  // energy (at its value at the start).
  if (offset > 0) {
    const double energy = std::max(report.before.total(), 0.0);
    solver_options.function_tolerance *= energy / (energy + offset);
  }
  if (ceres_problem.NumResidualBlocks() == 0) {
    report.success = true;
    report.message = "nothing to solve";
    return report;
  }
  const Vertices start = *x;
  ceres::Solver::Summary summary;
  // Ceres' own threads (solver_options.num_threads) evaluate the residuals; OpenMP and the BLAS
  // under CHOLMOD stay on one thread: BLAS threads made the solve slower
  // (docs/notes/2026-11-28-figures-from-code-comments.md).
  // CHOLMOD's own OpenMP teams (4 threads, whatever OpenMP is told) are held to one too.
  const ScopedThreads blas_threads(1);
  WithThreadLimit(1, [&] { ceres::Solve(solver_options, &ceres_problem, &summary); });
  report.success = summary.IsSolutionUsable() && x->allFinite();
  report.message = "Ceres: " + summary.message;
  report.iterations = static_cast<int>(summary.iterations.size()) - 1;
  report.linear_solves = summary.num_linear_solves;
  report.factorizations =
      options_.linear_solver == LinearSolver::kSparseNormalCholesky ? summary.num_linear_solves : 0;
  report.stop = report.success ? StopReason::kSolver : StopReason::kFailure;
  if (report.success && !summary.iterations.empty()) {
    report.mostly_refused = 2 * summary.num_unsuccessful_steps > report.iterations;
    report.largest_force_before = summary.iterations.front().gradient_max_norm;
    report.largest_force_after = summary.iterations.back().gradient_max_norm;
  }
  report.assemble_s = summary.jacobian_evaluation_time_in_seconds;
  report.evaluate_s = summary.residual_evaluation_time_in_seconds;
  report.linear_solve_s = summary.linear_solver_time_in_seconds;
  if (!report.success) *x = start;
  report.after = problem.Evaluate(*x);
  return report;
}

}  // namespace ceres_backend
}  // namespace femreg
