// Ceres cost functions for the energy terms of one frame. Each term writes its residual
// and analytic Jacobian once; tests check every one against central differences and
// ceres::GradientChecker. All parameter blocks are single vertices (3 doubles).
#ifndef FEMREG_SOLVERS_CERES_COST_FUNCTIONS_H_
#define FEMREG_SOLVERS_CERES_COST_FUNCTIONS_H_

#include <ceres/ceres.h>

#include <Eigen/Core>

#include "femreg/fem.h"

namespace femreg {
namespace ceres_backend {

// Elastic term of one element: r = sqrt(w) S (R^T x_e - X_e), 6 residuals, four vertex
// blocks. R is read from *rotation at every evaluation, so refreshing the rotations between
// outer iterations needs no new cost function. For the linear model *rotation stays I.
class ElasticCost : public ceres::SizedCostFunction<6, 3, 3, 3, 3> {
 public:
  ElasticCost(const ElementRest* rest, const Eigen::Matrix3d* rotation, double weight)
      : rest_(rest), rotation_(rotation), sqrt_weight_(std::sqrt(weight)) {}
  bool Evaluate(double const* const* parameters, double* residuals,
                double** jacobians) const override;

 private:
  const ElementRest* rest_;
  const Eigen::Matrix3d* rotation_;
  double sqrt_weight_;
};

// A point on the model, sum_k b_k x_k over N vertices (N = 1: a vertex; N = 3: a point on a
// surface triangle), tied to a target point: point-to-point r = sqrt(w) (p - q) (3
// residuals), or point-to-plane r = sqrt(w) n.(p - q) (1 residual).

class PointToPointCost1 : public ceres::SizedCostFunction<3, 3> {
 public:
  PointToPointCost1(const Eigen::Vector3d& target, double weight)
      : target_(target), sqrt_weight_(std::sqrt(weight)) {}
  bool Evaluate(double const* const* parameters, double* residuals,
                double** jacobians) const override;

 private:
  Eigen::Vector3d target_;
  double sqrt_weight_;
};

class PointToPlaneCost1 : public ceres::SizedCostFunction<1, 3> {
 public:
  PointToPlaneCost1(const Eigen::Vector3d& target, const Eigen::Vector3d& normal, double weight)
      : target_(target), normal_(normal), sqrt_weight_(std::sqrt(weight)) {}
  bool Evaluate(double const* const* parameters, double* residuals,
                double** jacobians) const override;

 private:
  Eigen::Vector3d target_, normal_;
  double sqrt_weight_;
};

class PointToPointCost3 : public ceres::SizedCostFunction<3, 3, 3, 3> {
 public:
  PointToPointCost3(const Eigen::Vector3d& barycentric, const Eigen::Vector3d& target,
                    double weight)
      : bary_(barycentric), target_(target), sqrt_weight_(std::sqrt(weight)) {}
  bool Evaluate(double const* const* parameters, double* residuals,
                double** jacobians) const override;

 private:
  Eigen::Vector3d bary_, target_;
  double sqrt_weight_;
};

class PointToPlaneCost3 : public ceres::SizedCostFunction<1, 3, 3, 3> {
 public:
  PointToPlaneCost3(const Eigen::Vector3d& barycentric, const Eigen::Vector3d& target,
                    const Eigen::Vector3d& normal, double weight)
      : bary_(barycentric), target_(target), normal_(normal), sqrt_weight_(std::sqrt(weight)) {}
  bool Evaluate(double const* const* parameters, double* residuals,
                double** jacobians) const override;

 private:
  Eigen::Vector3d bary_, target_, normal_;
  double sqrt_weight_;
};

// A spring on a mesh edge: r = sqrt(k) (|x_a - x_b| - L), two vertex blocks. At zero length
// the direction is undefined; the Jacobian is then zero.
class EdgeSpringCost : public ceres::SizedCostFunction<1, 3, 3> {
 public:
  EdgeSpringCost(double rest_length, double stiffness)
      : rest_length_(rest_length), sqrt_stiffness_(std::sqrt(stiffness)) {}
  bool Evaluate(double const* const* parameters, double* residuals,
                double** jacobians) const override;

 private:
  double rest_length_;
  double sqrt_stiffness_;
};

// Temporal and anchor terms have the same form: r = sqrt(w) (x - target) with w = w_t m_i
// (temporal, target = previous position) or the anchor stiffness.
using SpringCost = PointToPointCost1;

}  // namespace ceres_backend
}  // namespace femreg

#endif  // FEMREG_SOLVERS_CERES_COST_FUNCTIONS_H_
