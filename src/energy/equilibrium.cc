#include "energy/equilibrium.h"

#include <algorithm>
#include <cmath>

#include "energy/nodal_volume.h"
#include "energy/problem.h"

namespace femreg {
namespace energy {

namespace {

// The part of f outside the admissible cone {f . n <= 0, |f_t| <= mu (-f . n)} (mu < 0: the
// half-space f . n <= 0): f minus its projection on the cone.
Eigen::Vector3d OutsideCone(const Eigen::Vector3d& f, const Eigen::Vector3d& n, double mu) {
  const double fn = f.dot(n);
  if (mu < 0.0) return fn > 0.0 ? Eigen::Vector3d(fn * n) : Eigen::Vector3d::Zero();
  const Eigen::Vector3d ft = f - fn * n;
  const double t = ft.norm();
  const double a = -fn;  // along the inward axis
  if (t <= mu * a) return Eigen::Vector3d::Zero();  // inside
  // The cone's generator in the plane of the axis and f: e = cos(theta) (-n) + sin(theta) t_dir.
  const double c = 1.0 / std::sqrt(1.0 + mu * mu), s = mu * c;
  const Eigen::Vector3d t_dir = t > 0.0 ? Eigen::Vector3d(ft / t) : Eigen::Vector3d::Zero();
  const Eigen::Vector3d e = -c * n + s * t_dir;
  const double along = f.dot(e);
  if (along <= 0.0) return f;  // in the polar cone: the projection is the apex
  return f - along * e;
}

}  // namespace

double Equilibrium::Penalty(int v, const Eigen::Vector3d& f, Eigen::Vector3d* gradient,
                            Eigen::Matrix3d* curvature) const {
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
    const Eigen::Vector3d out = OutsideCone(f, normal[static_cast<size_t>(v)], friction);
    const double d2 = out.squaredNorm();
    if (d2 > 0.0) {
      value += 0.5 * beta * d2;
      if (gradient != nullptr) *gradient += beta * out;
      if (curvature != nullptr) {
        // The distance's direction (the exact curvature where the projection is a point or a
        // half-space's face; a lower bound on the cone's side).
        const Eigen::Vector3d u = out / std::sqrt(d2);
        *curvature += beta * u * u.transpose();
      }
    }
  }
  return value;
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
