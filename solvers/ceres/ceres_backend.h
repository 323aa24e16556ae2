// The Ceres back end: one generic cost adapter over any energy block type (its residual and
// Jacobian, sqrt(w) folded in when the set has no robust loss), the energy layer's robust
// loss wrapped as a ceres::LossFunction, and Levenberg-Marquardt or dogleg with sparse normal
// Cholesky (SuiteSparse CHOLMOD) or CGNR. Every vertex is a parameter block of 3. The
// nodal volume, whose stencil is a vertex's star, has a cost of its own (NodalVolumeCost);
// an equilibrium's penalty has its own (solvers/ceres/equilibrium_costs.h).
#ifndef FEMREG_SOLVERS_CERES_CERES_BACKEND_H_
#define FEMREG_SOLVERS_CERES_CERES_BACKEND_H_

#include <ceres/ceres.h>

#include <cmath>
#include <utility>
#include <vector>

#include "energy/loss.h"
#include "energy/nodal_volume.h"
#include "solvers/backend.h"

namespace femreg {
namespace ceres_backend {

// A block of type T as a Ceres cost: r = s r_T, J = s J_T with s = sqrt_weight.
template <class T>
class TermCost : public ceres::CostFunction {
 public:
  TermCost(const T* block, double sqrt_weight) : block_(block), sqrt_weight_(sqrt_weight) {
    set_num_residuals(T::kResiduals);
    for (int i = 0; i < T::kVertices; ++i) mutable_parameter_block_sizes()->push_back(3);
  }
  bool Evaluate(double const* const* parameters, double* residuals,
                double** jacobians) const override {
    if (!block_->Evaluate(parameters, residuals, jacobians)) return false;
    // An infinite energy (the inversion barrier's flat element): a failed evaluation, which
    // Ceres answers by shrinking the step, without its warning for non-finite residuals.
    for (int k = 0; k < T::kResiduals; ++k) {
      if (!std::isfinite(residuals[k])) return false;
    }
    if (sqrt_weight_ == 1.0) return true;
    for (int k = 0; k < T::kResiduals; ++k) residuals[k] *= sqrt_weight_;
    if (jacobians != nullptr) {
      for (int i = 0; i < T::kVertices; ++i) {
        if (jacobians[i] == nullptr) continue;
        for (int k = 0; k < 3 * T::kResiduals; ++k) jacobians[i][k] *= sqrt_weight_;
      }
    }
    return true;
  }

 private:
  const T* block_;
  double sqrt_weight_;
};

// w rho(s) as a ceres::LossFunction.
class LossAdapter : public ceres::LossFunction {
 public:
  LossAdapter(const energy::Loss& loss, double weight) : loss_(loss), weight_(weight) {}
  void Evaluate(double s, double rho[3]) const override {
    loss_.Evaluate(s, rho);
    for (int i = 0; i < 3; ++i) rho[i] *= weight_;
  }

 private:
  energy::Loss loss_;
  double weight_;
};

// The nodal-volume energy (energy/nodal_volume.h) at one vertex: r_a = sqrt(K_a V_a) (J_a - 1)
// over the vertices of the elements around it, a parameter block each.
class NodalVolumeCost : public ceres::CostFunction {
 public:
  explicit NodalVolumeCost(energy::NodalVolume::Star star) : star_(std::move(star)) {
    set_num_residuals(1);
    for (size_t i = 0; i < star_.vertices.size(); ++i) mutable_parameter_block_sizes()->push_back(3);
  }
  bool Evaluate(double const* const* parameters, double* residuals, double** jacobians) const override {
    residuals[0] = energy::NodalVolume::StarResidual(star_, parameters, jacobians);
    return std::isfinite(residuals[0]);
  }
  const std::vector<int>& vertices() const { return star_.vertices; }

 private:
  energy::NodalVolume::Star star_;
};

class CeresBackend : public Backend {
 public:
  explicit CeresBackend(const BackendOptions& options) : options_(options) {}
  SolverBackend type() const override { return SolverBackend::kCeres; }
  SolveReport Solve(const energy::Problem& problem, double time_limit_s, Vertices* x) override;

 private:
  BackendOptions options_;
};

}  // namespace ceres_backend
}  // namespace femreg

#endif  // FEMREG_SOLVERS_CERES_CERES_BACKEND_H_
