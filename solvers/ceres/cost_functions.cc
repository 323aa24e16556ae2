#include "solvers/ceres/cost_functions.h"

namespace femreg {
namespace ceres_backend {

bool ElasticCost::Evaluate(double const* const* parameters, double* residuals,
                           double** jacobians) const {
  const Eigen::Matrix3d& R = *rotation_;
  Vector12 u;
  for (int i = 0; i < 4; ++i) {
    u.segment<3>(3 * i) =
        R.transpose() * Eigen::Map<const Eigen::Vector3d>(parameters[i]) - rest_->X.segment<3>(3 * i);
  }
  Eigen::Map<Vector6> r(residuals);
  r = sqrt_weight_ * (rest_->S * u);
  if (jacobians != nullptr) {
    for (int i = 0; i < 4; ++i) {
      if (jacobians[i] == nullptr) continue;
      Eigen::Map<Eigen::Matrix<double, 6, 3, Eigen::RowMajor>> J(jacobians[i]);
      J = sqrt_weight_ * rest_->S.block<6, 3>(0, 3 * i) * R.transpose();
    }
  }
  return true;
}

bool PointToPointCost1::Evaluate(double const* const* parameters, double* residuals,
                                 double** jacobians) const {
  Eigen::Map<const Eigen::Vector3d> x(parameters[0]);
  Eigen::Map<Eigen::Vector3d> r(residuals);
  r = sqrt_weight_ * (x - target_);
  if (jacobians != nullptr && jacobians[0] != nullptr) {
    Eigen::Map<Eigen::Matrix<double, 3, 3, Eigen::RowMajor>> J(jacobians[0]);
    J = sqrt_weight_ * Eigen::Matrix3d::Identity();
  }
  return true;
}

bool PointToPlaneCost1::Evaluate(double const* const* parameters, double* residuals,
                                 double** jacobians) const {
  Eigen::Map<const Eigen::Vector3d> x(parameters[0]);
  residuals[0] = sqrt_weight_ * normal_.dot(x - target_);
  if (jacobians != nullptr && jacobians[0] != nullptr) {
    Eigen::Map<Eigen::Vector3d> J(jacobians[0]);
    J = sqrt_weight_ * normal_;
  }
  return true;
}

bool PointToPointCost3::Evaluate(double const* const* parameters, double* residuals,
                                 double** jacobians) const {
  Eigen::Vector3d p = Eigen::Vector3d::Zero();
  for (int k = 0; k < 3; ++k) p += bary_[k] * Eigen::Map<const Eigen::Vector3d>(parameters[k]);
  Eigen::Map<Eigen::Vector3d> r(residuals);
  r = sqrt_weight_ * (p - target_);
  if (jacobians != nullptr) {
    for (int k = 0; k < 3; ++k) {
      if (jacobians[k] == nullptr) continue;
      Eigen::Map<Eigen::Matrix<double, 3, 3, Eigen::RowMajor>> J(jacobians[k]);
      J = sqrt_weight_ * bary_[k] * Eigen::Matrix3d::Identity();
    }
  }
  return true;
}

bool PointToPlaneCost3::Evaluate(double const* const* parameters, double* residuals,
                                 double** jacobians) const {
  Eigen::Vector3d p = Eigen::Vector3d::Zero();
  for (int k = 0; k < 3; ++k) p += bary_[k] * Eigen::Map<const Eigen::Vector3d>(parameters[k]);
  residuals[0] = sqrt_weight_ * normal_.dot(p - target_);
  if (jacobians != nullptr) {
    for (int k = 0; k < 3; ++k) {
      if (jacobians[k] == nullptr) continue;
      Eigen::Map<Eigen::Vector3d> J(jacobians[k]);
      J = sqrt_weight_ * bary_[k] * normal_;
    }
  }
  return true;
}

bool EdgeSpringCost::Evaluate(double const* const* parameters, double* residuals,
                              double** jacobians) const {
  const Eigen::Vector3d d = Eigen::Map<const Eigen::Vector3d>(parameters[0]) -
                            Eigen::Map<const Eigen::Vector3d>(parameters[1]);
  const double length = d.norm();
  residuals[0] = sqrt_stiffness_ * (length - rest_length_);
  if (jacobians != nullptr) {
    const Eigen::Vector3d u = length > 0 ? Eigen::Vector3d(d / length) : Eigen::Vector3d::Zero();
    if (jacobians[0] != nullptr) {
      Eigen::Map<Eigen::Vector3d> J(jacobians[0]);
      J = sqrt_stiffness_ * u;
    }
    if (jacobians[1] != nullptr) {
      Eigen::Map<Eigen::Vector3d> J(jacobians[1]);
      J = -sqrt_stiffness_ * u;
    }
  }
  return true;
}

}  // namespace ceres_backend
}  // namespace femreg
