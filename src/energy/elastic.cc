#include "energy/elastic.h"

namespace femreg {
namespace energy {

bool ElasticElement::Evaluate(const double* const* x, double* r, double** J) const {
  Vector12 xe;
  for (int i = 0; i < 4; ++i) xe.segment<3>(3 * i) = Eigen::Map<const Eigen::Vector3d>(x[i]);
  Eigen::Map<Vector6>{r} = ElementResidual(*rest, *rotation, xe);
  if (J == nullptr) return true;
  for (int i = 0; i < 4; ++i) {
    if (J[i] == nullptr) continue;
    Eigen::Map<Eigen::Matrix<double, 6, 3, Eigen::RowMajor>> Ji(J[i]);
    Ji = ElementResidualJacobianBlock(*rest, *rotation, i);
  }
  return true;
}

bool EdgeSpring::Evaluate(const double* const* x, double* r, double** J) const {
  const Eigen::Vector3d d =
      Eigen::Map<const Eigen::Vector3d>(x[0]) - Eigen::Map<const Eigen::Vector3d>(x[1]);
  const double norm = d.norm();
  r[0] = norm - length;
  if (J == nullptr) return true;
  const Eigen::Vector3d u = norm > 0 ? Eigen::Vector3d(d / norm) : Eigen::Vector3d::Zero();
  if (J[0] != nullptr) Eigen::Map<Eigen::Vector3d>{J[0]} = u;
  if (J[1] != nullptr) Eigen::Map<Eigen::Vector3d>{J[1]} = -u;
  return true;
}

}  // namespace energy
}  // namespace femreg
