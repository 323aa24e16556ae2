#include "solvers/ceres/contact_cost.h"

namespace femreg {
namespace ceres_backend {

bool ContactPairCost::Evaluate(double const* const* parameters, double* residuals,
                               double** jacobians) const {
  Eigen::Vector3d pa = Eigen::Vector3d::Zero(), pb = Eigen::Vector3d::Zero();
  for (int k = 0; k < 3; ++k) {
    pa += bary_a_[k] * Eigen::Map<const Eigen::Vector3d>(parameters[k]);
    pb += bary_b_[k] * Eigen::Map<const Eigen::Vector3d>(parameters[3 + k]);
  }
  const double delta = distance_ - normal_.dot(pa - pb);
  const bool active = delta > 0;
  residuals[0] = active ? sqrt_k_ * delta : 0.0;
  if (jacobians != nullptr) {
    for (int k = 0; k < 6; ++k) {
      if (jacobians[k] == nullptr) continue;
      Eigen::Map<Eigen::Vector3d> J(jacobians[k]);
      if (!active) {
        J.setZero();
      } else if (k < 3) {
        J = -sqrt_k_ * bary_a_[k] * normal_;
      } else {
        J = sqrt_k_ * bary_b_[k - 3] * normal_;
      }
    }
  }
  return true;
}

bool ContactObstacleCost::Evaluate(double const* const* parameters, double* residuals,
                                   double** jacobians) const {
  Eigen::Vector3d pa = Eigen::Vector3d::Zero();
  for (int k = 0; k < 3; ++k) pa += bary_a_[k] * Eigen::Map<const Eigen::Vector3d>(parameters[k]);
  const double delta = distance_ - normal_.dot(pa - point_b_);
  const bool active = delta > 0;
  residuals[0] = active ? sqrt_k_ * delta : 0.0;
  if (jacobians != nullptr) {
    for (int k = 0; k < 3; ++k) {
      if (jacobians[k] == nullptr) continue;
      Eigen::Map<Eigen::Vector3d> J(jacobians[k]);
      if (active) {
        J = -sqrt_k_ * bary_a_[k] * normal_;
      } else {
        J.setZero();
      }
    }
  }
  return true;
}

}  // namespace ceres_backend
}  // namespace femreg
