// Equilibrium registration (energy/equilibrium.h) in the Ceres back end. The penalty on the
// forces f = dPi/dx is least squares in f (Equilibrium::Residuals), and f_v depends on the
// vertices whose blocks reach v, so each vertex that may not take any force is one residual
// block over those vertices, with the Jacobian (dr/df) K_v., K = d2Pi/dx2 the exact Hessian.
// f and K are shared by all vertices: an EvaluationCallback assembles them once per point
// Ceres evaluates (the one assembler, as the fast back end's step does), and the costs read
// them. Ceres then solves with K^T Phi K as the fast back end does, without its held turns.
#ifndef FEMREG_SOLVERS_CERES_EQUILIBRIUM_COSTS_H_
#define FEMREG_SOLVERS_CERES_EQUILIBRIUM_COSTS_H_

#include <ceres/ceres.h>

#include <Eigen/Core>
#include <memory>
#include <vector>

#include "energy/assembler.h"
#include "energy/equilibrium.h"
#include "energy/problem.h"
#include "femreg/mesh.h"

namespace femreg {
namespace ceres_backend {

// f and K at the point Ceres evaluates (the user's parameters: x itself).
class EquilibriumState final : public ceres::EvaluationCallback {
 public:
  EquilibriumState(const energy::Problem& problem, const Vertices* x, int threads);
  void PrepareForEvaluation(bool evaluate_jacobians, bool new_evaluation_point) override;

  const energy::Problem& problem() const { return problem_; }
  const Eigen::VectorXd& f() const { return f_; }
  const Eigen::SparseMatrix<double>& K() const { return physics_.H(); }
  bool finite() const { return finite_; }

 private:
  const energy::Problem& problem_;
  const Vertices* x_;
  energy::Assembler physics_;
  Eigen::VectorXd f_;
  bool have_jacobians_ = false;
  bool finite_ = false;
};

// The penalty at vertex v over the vertices of K's block row v (vertices(), a parameter
// block each): r = Equilibrium::Residuals(v, f_v) (6 values), or with `sparse` r = f_v (3),
// for the sparse term's loss.
class EquilibriumVertexCost : public ceres::CostFunction {
 public:
  EquilibriumVertexCost(const EquilibriumState* state, int v, bool sparse);
  bool Evaluate(double const* const* parameters, double* residuals, double** jacobians) const override;
  const std::vector<int>& vertices() const { return vertices_; }

 private:
  const EquilibriumState* state_;
  int v_;
  bool sparse_;
  std::vector<int> vertices_;
  // Per entry of K's columns 3v..3v+2: the parameter block, the row's component and the column's.
  struct Entry {
    int block, row, column, value;
  };
  std::vector<Entry> entries_;
};

// The sparse term s (sqrt(|f|^2 + eps^2) - eps) on f as residuals: Ceres' cost 1/2 rho(|f|^2).
class SparsityLoss : public ceres::LossFunction {
 public:
  SparsityLoss(double weight, double floor) : weight_(weight), floor_(floor) {}
  void Evaluate(double z, double rho[3]) const override;

 private:
  double weight_, floor_;
};

// Adds the equilibrium's residual blocks for every vertex that is not a support or fixed;
// the costs and losses are kept in the given lists (the problem does not own them).
void AddEquilibriumCosts(const EquilibriumState* state, double* x, ceres::Problem* ceres_problem,
                         std::vector<std::unique_ptr<ceres::CostFunction>>* costs,
                         std::vector<std::unique_ptr<ceres::LossFunction>>* losses);

}  // namespace ceres_backend
}  // namespace femreg

#endif  // FEMREG_SOLVERS_CERES_EQUILIBRIUM_COSTS_H_
