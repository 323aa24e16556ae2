#include "energy/equilibrium.h"

#include <algorithm>
#include <cmath>

#include "energy/nodal_volume.h"
#include "energy/problem.h"

namespace femreg {
namespace energy {

namespace {

// The part of f outside the admissible cone {f . n <= 0, |f_t| <= mu (-f . n)} (mu < 0: the
// half-space f . n <= 0): f minus its projection on the cone, and the Hessian of
// 1/2 |outside|^2 (docs/theory/equilibrium.md#pushing-only): I where f projects on the apex,
// n n^T on the half-space's face, and u u^T + side b b^T on the cone's side, u the outward
// unit normal of the cone there and b the tangent direction across f's plane (n, f_t), along
// which the projection turns with f.
struct ConeExcess {
  enum Region { kInside, kFace, kSide, kApex } region = kInside;
  Eigen::Vector3d outside = Eigen::Vector3d::Zero();
  Eigen::Vector3d u = Eigen::Vector3d::Zero(), b = Eigen::Vector3d::Zero();
  double side = 0.0;
};

ConeExcess OutsideCone(const Eigen::Vector3d& f, const Eigen::Vector3d& n, double mu) {
  ConeExcess excess;
  const double fn = f.dot(n);
  if (mu < 0.0) {
    if (fn > 0.0) {
      excess.region = ConeExcess::kFace;
      excess.outside = fn * n;
    }
    return excess;
  }
  const Eigen::Vector3d ft = f - fn * n;
  const double t = ft.norm();
  const double a = -fn;  // along the inward axis
  // (a >= 0: a pull along the normal, t = 0, is outside a frictionless cone, the ray.)
  if (a >= 0.0 && t <= mu * a) return excess;  // inside
  // The cone's generator in the plane of the axis and f: e = cos(theta) (-n) + sin(theta) t_dir.
  const double c = 1.0 / std::sqrt(1.0 + mu * mu), s = mu * c;
  const Eigen::Vector3d t_dir = t > 0.0 ? Eigen::Vector3d(ft / t) : Eigen::Vector3d::Zero();
  const Eigen::Vector3d e = -c * n + s * t_dir;
  const double along = f.dot(e);
  if (along <= 0.0 || t == 0.0) {  // in the polar cone: the projection is the apex
    excess.region = ConeExcess::kApex;
    excess.outside = f;
    return excess;
  }
  // The cone's outward normal in f's plane, exact (f - along e loses digits near the cone).
  excess.region = ConeExcess::kSide;
  excess.u = s * n + c * t_dir;
  excess.outside = std::max(0.0, f.dot(excess.u)) * excess.u;
  // The projection along * e turns about n as f_t does: d(t_dir) = (b b^T / t) df, so its
  // Jacobian has (along s / t) b b^T besides e e^T; 0 < 1 - along s / t <= 1 here.
  excess.b = n.cross(t_dir);
  excess.side = std::max(0.0, 1.0 - along * s / t);
  return excess;
}

}  // namespace

double Equilibrium::Penalty(int v, const Eigen::Vector3d& f, Eigen::Vector3d* gradient,
                            Eigen::Matrix3d* curvature, bool cone_at_bound) const {
  const ForceSite where = site[static_cast<size_t>(v)];
  if (where == ForceSite::kSupport) {
    if (gradient != nullptr) gradient->setZero();
    if (curvature != nullptr) curvature->setZero();
    return 0.0;
  }
  const double beta = strong_weight[static_cast<size_t>(v)];
  if (where == ForceSite::kBalanced) {
    if (gradient != nullptr) *gradient = beta * f;
    if (curvature != nullptr) *curvature = beta * Eigen::Matrix3d::Identity();
    return 0.5 * beta * f.squaredNorm();
  }
  const double alpha = force_weight[static_cast<size_t>(v)];
  double value = 0.5 * alpha * f.squaredNorm();
  if (gradient != nullptr) *gradient = alpha * f;
  if (curvature != nullptr) *curvature = alpha * Eigen::Matrix3d::Identity();
  const double s = sparsity.empty() ? 0.0 : sparsity[static_cast<size_t>(v)];
  if (s > 0.0) {
    const double root = std::sqrt(f.squaredNorm() + sparsity_floor * sparsity_floor);
    value += s * (root - sparsity_floor);
    if (gradient != nullptr) *gradient += (s / root) * f;
    if (curvature != nullptr) curvature->diagonal().array() += s / root;
  }
  if (pushing_only) {
    const ConeExcess excess = OutsideCone(f, normal[static_cast<size_t>(v)], friction);
    const double d2 = excess.outside.squaredNorm();
    if (cone_at_bound && curvature != nullptr) curvature->diagonal().array() += beta;
    if (excess.region != ConeExcess::kInside && d2 > 0.0) {
      value += 0.5 * beta * d2;
      if (gradient != nullptr) *gradient += beta * excess.outside;
      if (curvature != nullptr && !cone_at_bound) {
        switch (excess.region) {
          case ConeExcess::kSide:
            *curvature += beta * (excess.u * excess.u.transpose() + excess.side * excess.b * excess.b.transpose());
            break;
          case ConeExcess::kFace: {
            const Eigen::Vector3d& nv = normal[static_cast<size_t>(v)];
            *curvature += beta * nv * nv.transpose();
            break;
          }
          case ConeExcess::kApex:
            curvature->diagonal().array() += beta;
            break;
          case ConeExcess::kInside:
            break;
        }
      }
    }
  }
  return value;
}

void Equilibrium::Residuals(int v, const Eigen::Vector3d& f, Eigen::Matrix<double, 6, 1>* r,
                            Eigen::Matrix<double, 6, 3>* dr_df) const {
  r->setZero();
  dr_df->setZero();
  const ForceSite where = site[static_cast<size_t>(v)];
  if (where == ForceSite::kSupport) return;
  const double beta = strong_weight[static_cast<size_t>(v)];
  const double w = std::sqrt(where == ForceSite::kBalanced ? beta : force_weight[static_cast<size_t>(v)]);
  r->head<3>() = w * f;
  dr_df->topRows<3>() = w * Eigen::Matrix3d::Identity();
  if (where != ForceSite::kFree || !pushing_only) return;
  const Eigen::Vector3d& n = normal[static_cast<size_t>(v)];
  const ConeExcess excess = OutsideCone(f, n, friction);
  const double root_beta = std::sqrt(beta);
  r->tail<3>() = root_beta * excess.outside;
  switch (excess.region) {
    case ConeExcess::kFace:
      dr_df->bottomRows<3>() = root_beta * n * n.transpose();
      break;
    case ConeExcess::kApex:
      dr_df->bottomRows<3>() = root_beta * Eigen::Matrix3d::Identity();
      break;
    case ConeExcess::kSide: {
      // outside = (f . u) u, u = s n + c t_dir: d(u) = (c / t) b b^T df, and f . b = 0.
      const double t = (f - f.dot(n) * n).norm();
      const double c = 1.0 / std::sqrt(1.0 + friction * friction);
      dr_df->bottomRows<3>() = root_beta * (excess.u * excess.u.transpose() +
                                            (std::max(0.0, f.dot(excess.u)) * c / t) * excess.b * excess.b.transpose());
      break;
    }
    case ConeExcess::kInside:
      break;
  }
}

int Equilibrium::PenaltyPiece(int v, const Eigen::Vector3d& f) const {
  if (!pushing_only || site[static_cast<size_t>(v)] != ForceSite::kFree) return 0;
  return static_cast<int>(OutsideCone(f, normal[static_cast<size_t>(v)], friction).region);
}

void Equilibrium::ScaleWeights(double factor) {
  for (double& w : force_weight) w *= factor;
  for (double& w : strong_weight) w *= factor;
  for (double& w : sparsity) w *= factor;
}

bool Equilibrium::IsValid(int num_vertices) const {
  const size_t n = static_cast<size_t>(num_vertices);
  return site.size() == n && force_weight.size() == n && strong_weight.size() == n &&
         (sparsity.empty() || sparsity.size() == n) && (!pushing_only || normal.size() == n) &&
         (sparsity.empty() || sparsity_floor > 0.0) &&
         std::all_of(held_turns.begin(), held_turns.end(), [&](const HeldTurn& h) {
           return h.first >= 0 && h.count >= 0 && h.count <= num_vertices - h.first && h.axis.allFinite();
         });
}

uint32_t PhysicsGroups() {
  return (1u << static_cast<int>(TermGroup::kElastic)) | (1u << static_cast<int>(TermGroup::kLoad)) |
         (1u << static_cast<int>(TermGroup::kCollision)) | (1u << static_cast<int>(TermGroup::kBarrier));
}

// The barrier in both: its force is the body's, and its energy the wall no step may cross.
uint32_t ObjectiveGroups() {
  return (((1u << kNumTermGroups) - 1u) & ~PhysicsGroups()) | (1u << static_cast<int>(TermGroup::kBarrier));
}

void ForceResidual(const Problem& problem, const Vertices& x, Eigen::VectorXd* f, uint32_t groups,
                   Curvature curvature) {
  f->setZero(3 * problem.num_vertices());
  problem.ForEachSet([&](const auto& set) {
    if (!InGroups(groups, set.group())) return;
    using T = typename std::decay_t<decltype(set)>::Block;
    Linearization<T> lin;
    for (const T& block : set.blocks()) {
      if (!LinearizeSecondOrder(block, set.loss(), x, curvature, &lin, /*with_hessian=*/false) ||
          lin.scale == 0.0) {
        continue;
      }
      for (int i = 0; i < T::kVertices; ++i) f->segment<3>(3 * block.vertices[i]) += lin.gradient[i];
    }
  });
  if (problem.nodal_volume() != nullptr && InGroups(groups, TermGroup::kElastic)) {
    problem.nodal_volume()->Evaluate(x, f);
  }
  for (int v = 0; v < problem.num_vertices(); ++v) {
    if (problem.is_fixed(v)) f->segment<3>(3 * v).setZero();
  }
}

double EquilibriumEnergy(const Equilibrium& equilibrium, const Eigen::VectorXd& f) {
  double total = 0.0;
  const int n = static_cast<int>(f.size() / 3);
  for (int v = 0; v < n; ++v) total += equilibrium.Penalty(v, f.segment<3>(3 * v), nullptr, nullptr);
  return total;
}

}  // namespace energy
}  // namespace femreg
