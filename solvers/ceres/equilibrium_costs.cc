#include "solvers/ceres/equilibrium_costs.h"

#include <algorithm>
#include <cmath>
#include <map>

namespace femreg {
namespace ceres_backend {

EquilibriumState::EquilibriumState(const energy::Problem& problem, const Vertices* x, int threads)
    : problem_(problem), x_(x), physics_(threads) {
  physics_.set_groups(energy::PhysicsGroups());
  physics_.Prepare(problem_, *x_);
  PrepareForEvaluation(true, true);  // the pattern's values, which the costs' entries index
}

void EquilibriumState::PrepareForEvaluation(bool evaluate_jacobians, bool new_evaluation_point) {
  if (!new_evaluation_point && (have_jacobians_ || !evaluate_jacobians)) return;
  // Ceres has written the point into the user's parameters, x.
  physics_.AssembleSecondOrder(problem_, *x_, energy::Curvature::kExact, evaluate_jacobians, &f_);
  physics_.Finish(problem_, 0.0, &f_);
  have_jacobians_ = evaluate_jacobians;
  finite_ = f_.allFinite();
}

EquilibriumVertexCost::EquilibriumVertexCost(const EquilibriumState* state, int v, bool sparse)
    : state_(state), v_(v), sparse_(sparse) {
  const Eigen::SparseMatrix<double>& K = state->K();
  // K is symmetric: row 3v + i of K is its column 3v + i.
  std::map<int, int> block_of;
  for (int i = 0; i < 3; ++i) {
    for (Eigen::SparseMatrix<double>::InnerIterator it(K, 3 * v + i); it; ++it) {
      const int u = static_cast<int>(it.row()) / 3;
      auto found = block_of.find(u);
      if (found == block_of.end()) {
        found = block_of.emplace(u, static_cast<int>(vertices_.size())).first;
        vertices_.push_back(u);
      }
      const int value = static_cast<int>(&it.value() - K.valuePtr());
      entries_.push_back({found->second, i, static_cast<int>(it.row()) % 3, value});
    }
  }
  set_num_residuals(sparse_ ? 3 : 6);
  for (size_t k = 0; k < vertices_.size(); ++k) mutable_parameter_block_sizes()->push_back(3);
}

bool EquilibriumVertexCost::Evaluate(double const* const* /*parameters: x, as the state read it*/,
                                     double* residuals, double** jacobians) const {
  if (!state_->finite()) return false;
  const Eigen::Vector3d f = state_->f().segment<3>(3 * v_);
  Eigen::Matrix<double, 6, 1> r;
  Eigen::Matrix<double, 6, 3> dr_df;
  if (sparse_) {
    r.head<3>() = f;
    dr_df.topRows<3>().setIdentity();
  } else {
    state_->problem().equilibrium()->Residuals(v_, f, &r, &dr_df);
  }
  const int m = num_residuals();
  for (int k = 0; k < m; ++k) residuals[k] = r[k];
  if (jacobians == nullptr) return true;
  // df_v / dx_u = K_vu, block by block.
  std::vector<Eigen::Matrix3d> K(vertices_.size(), Eigen::Matrix3d::Zero());
  const double* values = state_->K().valuePtr();
  for (const Entry& e : entries_) K[static_cast<size_t>(e.block)](e.row, e.column) = values[e.value];
  for (size_t b = 0; b < vertices_.size(); ++b) {
    if (jacobians[b] == nullptr) continue;
    Eigen::Map<Eigen::Matrix<double, Eigen::Dynamic, 3, Eigen::RowMajor>> J(jacobians[b], m, 3);
    J = dr_df.topRows(m) * K[b];
  }
  return true;
}

void SparsityLoss::Evaluate(double z, double rho[3]) const {
  const double root = std::sqrt(z + floor_ * floor_);
  rho[0] = 2.0 * weight_ * (root - floor_);
  rho[1] = weight_ / root;
  rho[2] = -0.5 * weight_ / (root * root * root);
}

void AddEquilibriumCosts(const EquilibriumState* state, double* x, ceres::Problem* ceres_problem,
                         std::vector<std::unique_ptr<ceres::CostFunction>>* costs,
                         std::vector<std::unique_ptr<ceres::LossFunction>>* losses) {
  const energy::Problem& problem = state->problem();
  const energy::Equilibrium& eq = *problem.equilibrium();
  std::vector<double*> blocks;
  auto add = [&](std::unique_ptr<EquilibriumVertexCost> cost, ceres::LossFunction* loss) {
    blocks.clear();
    for (int u : cost->vertices()) blocks.push_back(x + 3 * u);
    ceres_problem->AddResidualBlock(cost.get(), loss, blocks);
    costs->push_back(std::move(cost));
  };
  for (int v = 0; v < problem.num_vertices(); ++v) {
    if (problem.is_fixed(v) || eq.site[static_cast<size_t>(v)] == energy::ForceSite::kSupport) continue;
    add(std::make_unique<EquilibriumVertexCost>(state, v, false), nullptr);
    const double s = eq.sparsity.empty() ? 0.0 : eq.sparsity[static_cast<size_t>(v)];
    if (s > 0.0 && eq.site[static_cast<size_t>(v)] == energy::ForceSite::kFree) {
      losses->push_back(std::make_unique<SparsityLoss>(s, eq.sparsity_floor));
      add(std::make_unique<EquilibriumVertexCost>(state, v, true), losses->back().get());
    }
  }
}

}  // namespace ceres_backend
}  // namespace femreg
