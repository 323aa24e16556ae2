// Ceres cost functions of the collision penalty (seed eq. 15), see femreg/collision.h for the
// sign conventions. The normal n (from b towards a) is held fixed within an inner solve and
// refreshed by the next detection, so the residual is one-sided linear:
//   r = sqrt(k) max(0, delta),  delta = D - n . (p_a - p_b),  E = 1/2 r^2 = 1/2 k delta^2,
// with p_a = sum_i a_i x_i on a triangle of object a and p_b = sum_j b_j y_j on a triangle of
// object b (6 vertex blocks) or a fixed obstacle point (3 vertex blocks). The Jacobian is
// dr/dx_i = -sqrt(k) a_i n^T, dr/dy_j = +sqrt(k) b_j n^T while delta > 0, else 0.
#ifndef FEMREG_SOLVERS_CERES_CONTACT_COST_H_
#define FEMREG_SOLVERS_CERES_CONTACT_COST_H_

#include <ceres/ceres.h>

#include <Eigen/Core>

namespace femreg {
namespace ceres_backend {

class ContactPairCost : public ceres::SizedCostFunction<1, 3, 3, 3, 3, 3, 3> {
 public:
  ContactPairCost(const Eigen::Vector3d& bary_a, const Eigen::Vector3d& bary_b,
                  const Eigen::Vector3d& normal, double distance, double stiffness)
      : bary_a_(bary_a), bary_b_(bary_b), normal_(normal), distance_(distance),
        sqrt_k_(std::sqrt(stiffness)) {}
  bool Evaluate(double const* const* parameters, double* residuals,
                double** jacobians) const override;

 private:
  Eigen::Vector3d bary_a_, bary_b_, normal_;
  double distance_, sqrt_k_;
};

class ContactObstacleCost : public ceres::SizedCostFunction<1, 3, 3, 3> {
 public:
  ContactObstacleCost(const Eigen::Vector3d& bary_a, const Eigen::Vector3d& point_b,
                      const Eigen::Vector3d& normal, double distance, double stiffness)
      : bary_a_(bary_a), point_b_(point_b), normal_(normal), distance_(distance),
        sqrt_k_(std::sqrt(stiffness)) {}
  bool Evaluate(double const* const* parameters, double* residuals,
                double** jacobians) const override;

 private:
  Eigen::Vector3d bary_a_, point_b_, normal_;
  double distance_, sqrt_k_;
};

}  // namespace ceres_backend
}  // namespace femreg

#endif  // FEMREG_SOLVERS_CERES_CONTACT_COST_H_
