#include "solvers/fast/penalty_pieces.h"

#include <Eigen/LU>
#include <algorithm>

namespace femreg {
namespace fast_backend {

Eigen::Matrix3d PenaltyBlockInverse(const energy::Equilibrium& eq, int v, const Eigen::Matrix3d& c) {
  double floor = 1e-6 * eq.force_weight[static_cast<size_t>(v)];
  if (eq.site[static_cast<size_t>(v)] == energy::ForceSite::kSupport) floor = eq.force_weight[static_cast<size_t>(v)];
  floor = std::max(floor, 1e-300);
  return Eigen::Matrix3d(c + floor * Eigen::Matrix3d::Identity()).inverse();
}

void PenaltyPieces::Start(const energy::Equilibrium& eq, const Eigen::VectorXd& f) {
  const int n = static_cast<int>(f.size() / 3);
  piece_.resize(static_cast<size_t>(n));
  for (int v = 0; v < n; ++v) piece_[static_cast<size_t>(v)] = eq.PenaltyPiece(v, f.segment<3>(3 * v));
}

int PenaltyPieces::Remodel(const energy::Equilibrium& eq, const Eigen::VectorXd& f, const Eigen::VectorXd& kdx,
                           std::vector<Eigen::Matrix3d>* phi, Eigen::VectorXd* phi_gradient,
                           std::vector<Eigen::Matrix3d>* phi_inverse) {
  int changed = 0;
  for (int v = 0; v < static_cast<int>(piece_.size()); ++v) {
    const Eigen::Vector3d predicted = f.segment<3>(3 * v) + kdx.segment<3>(3 * v);
    const int p = eq.PenaltyPiece(v, predicted);
    if (p == piece_[static_cast<size_t>(v)]) continue;
    piece_[static_cast<size_t>(v)] = p;
    ++changed;
    Eigen::Vector3d gradient;
    Eigen::Matrix3d& c = (*phi)[static_cast<size_t>(v)];
    eq.Penalty(v, predicted, &gradient, &c);
    phi_gradient->segment<3>(3 * v) = gradient - c * kdx.segment<3>(3 * v);
    (*phi_inverse)[static_cast<size_t>(v)] = PenaltyBlockInverse(eq, v, c);
  }
  return changed;
}

}  // namespace fast_backend
}  // namespace femreg
