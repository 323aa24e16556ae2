// An energy term of one frame is a set of residual blocks of one type. A block type writes,
// once, its residual and Jacobian on its stencil (a few vertices); everything else — the
// value, the gradient, the Gauss-Newton blocks, the robust loss, the scatter into a global
// system, the Ceres cost — is generic over block types and written once (below, and in the
// back ends, solvers/).
//
// A block type T provides
//   static constexpr int kResiduals;        // m, its residual's size
//   static constexpr int kVertices;         // n, its stencil's size
//   static constexpr bool kConstantJacobian;// J does not depend on x (while the block's
//                                           // parameters, e.g. a rotation, are held)
//   std::array<int, kVertices> vertices;    // the stencil: global vertex indices
//   double weight;                          // w >= 0
//   // r (m) and, where J[i] is not null, J[i] = dr/dx_i (m by 3, row-major), at the stencil's
//   // positions x[i] (3 each). Returns false if the block cannot be evaluated.
//   bool Evaluate(const double* const* x, double* r, double** J) const;
// and its energy is 1/2 w rho(|r|^2) with the set's robust loss rho (none: rho(s) = s).
// It may also provide the normal-equation pieces in closed form, where that is much cheaper
// than forming J (the FEM element):
//   // |r|^2 and, if jtr is not null, J_i^T r (n) and, if jtj is not null too, J_i^T J_j at
//   // i * n + j (n * n).
//   bool Normal(const double* const* x, double* squared_norm, Eigen::Vector3d* jtr,
//               Eigen::Matrix3d* jtj) const;
// Linearize then uses it; the tests check it against Evaluate's r and J.
// A block whose |r|^2 cannot reach 0 (the neo-Hookean element: its energy is a sum of
// squares only up to a constant) provides that constant, |r|^2 at rest:
//   double Offset() const;
// and its value is 1/2 w (rho(|r|^2) - rho(Offset())), zero at rest, so that the energies
// reported and compared (relative tolerances) are the physical ones. The Ceres back end's
// cost still carries it (Problem::Offset).
//
// Second order. Newton's method on an equilibrium (the forward solve) needs the exact Hessian
// of a block's energy, not the Gauss-Newton J^T J. A block type whose residual is affine in
// x (kConstantJacobian, or kPiecewiseAffine: affine wherever it is differentiable) has J^T J
// as that Hessian; every other one provides it:
//   // e = 1/2 |r|^2 of the block's exact energy at x, its gradient (n) and, if hessian is not
//   // null, its Hessian (n * n, (i, j) at i * n + j), projected to positive semi-definite
//   // if asked. Parameters a block holds between evaluations (an element's rotation) follow
//   // x here: e is the energy those parameters approximate, and at x where they are
//   // current, e and its gradient are Evaluate's.
//   bool SecondOrder(const double* const* x, double* energy, Eigen::Vector3d* gradient,
//                    Eigen::Matrix3d* hessian, TangentProjection projection) const;
// LinearizeSecondOrder below applies the loss; tests/energy_test.cc checks every block type's
// Hessian against central differences of its gradient.
#ifndef FEMREG_ENERGY_TERM_H_
#define FEMREG_ENERGY_TERM_H_

#include <Eigen/Core>
#include <array>
#include <cstdint>
#include <type_traits>
#include <vector>

#include "energy/loss.h"
#include "femreg/energy.h"
#include "femreg/fem.h"
#include "femreg/mesh.h"

namespace femreg {
namespace energy {

// Which line of EnergyTerms a set adds to.
// kBarrier: the inversion barrier (energy/barrier.h), reported with the elastic energy; under
// equilibrium registration both a force of the body and a wall the objective keeps.
enum class TermGroup { kElastic, kTemporal, kAnchor, kData, kCollision, kLoad, kBarrier };
constexpr int kNumTermGroups = 7;
double& GroupEnergy(TermGroup group, EnergyTerms* terms);

// A number not handed out before in this process (revisions of sets and couplings).
uint64_t NextRevision();

// Blocks of one type with a common group and loss. `revision` changes whenever the blocks'
// stencils change (a back end may cache per-block data, e.g. where each block scatters,
// for as long as it holds).
template <class T>
class TermSet {
 public:
  using Block = T;
  TermSet(TermGroup group, const Loss& loss) : group_(group), loss_(loss) { Touch(); }

  TermGroup group() const { return group_; }
  const Loss& loss() const { return loss_; }
  const std::vector<T>& blocks() const { return blocks_; }
  int size() const { return static_cast<int>(blocks_.size()); }
  uint64_t revision() const { return revision_; }

  // For changing the blocks' stencils (or adding, removing blocks): a new revision.
  std::vector<T>* mutable_blocks() {
    Touch();
    return &blocks_;
  }
  void Add(const T& block) { mutable_blocks()->push_back(block); }

 private:
  void Touch() { revision_ = NextRevision(); }
  TermGroup group_;
  Loss loss_;
  std::vector<T> blocks_;
  uint64_t revision_ = 0;
};

// Whether T provides Normal (above).
template <class T, class = void>
struct HasNormal : std::false_type {};
template <class T>
struct HasNormal<T, std::void_t<decltype(std::declval<const T&>().Normal(
                        std::declval<const double* const*>(), std::declval<double*>(),
                        std::declval<Eigen::Vector3d*>(), std::declval<Eigen::Matrix3d*>()))>>
    : std::true_type {};

// Whether T provides Offset (above), and 1/2 w rho(Offset()) (0 without).
template <class T, class = void>
struct HasOffset : std::false_type {};
template <class T>
struct HasOffset<T, std::void_t<decltype(std::declval<const T&>().Offset())>> : std::true_type {};
// Whether a Gauss-Newton system takes T's projected Newton Hessian instead of J^T J
// (T::kNewtonCurvature).
template <class T, class = void>
struct HasNewtonCurvature : std::false_type {};
template <class T>
struct HasNewtonCurvature<T, std::void_t<decltype(T::kNewtonCurvature)>>
    : std::bool_constant<T::kNewtonCurvature> {};

// Whether T can tell cheaply that its residual and Jacobian are zero at x (Inactive(x)):
// Linearize then skips the block's evaluation and leaves its Hessian unwritten.
template <class T, class = void>
struct HasInactive : std::false_type {};
template <class T>
struct HasInactive<T, std::void_t<decltype(std::declval<const T&>().Inactive(
                          std::declval<const double* const*>()))>> : std::true_type {};

template <class T>
double OffsetValue(const T& block, const Loss& loss) {
  if constexpr (HasOffset<T>::value) {
    double rho[3];
    loss.Evaluate(block.Offset(), rho);
    return 0.5 * block.weight * rho[0];
  } else {
    return 0.0;
  }
}

// Pointers to the stencil's positions in x (#V by 3, row-major: vertex v is x.data() + 3 v).
template <class T>
std::array<const double*, T::kVertices> StencilPositions(const T& block, const Vertices& x) {
  std::array<const double*, T::kVertices> p;
  for (int i = 0; i < T::kVertices; ++i) p[i] = x.data() + 3 * block.vertices[i];
  return p;
}

// The value of a block whose residual is zero (Inactive): every loss has rho(0) = 0, so
// nothing but the offset, without a loss evaluation per block.
template <class T>
double InactiveValue(const T& block, const Loss& loss) {
  return -OffsetValue(block, loss);
}

// An inactive block's linearization: its value, a zero scale and gradient, the Hessian left
// unwritten (a zero scale says it adds nothing).
template <class T, class Out>
bool SkipInactive(const T& block, const Loss& loss, const std::array<const double*, T::kVertices>& p,
                  Out* out) {
  if constexpr (HasInactive<T>::value) {
    if (block.Inactive(p.data())) {
      out->value = InactiveValue(block, loss);
      out->scale = 0.0;
      for (auto& g : out->gradient) g.setZero();
      return true;
    }
  }
  return false;
}

// |r|^2 added in residual order: BlockValue and Linearize compute a block's value the same
// way (a back end's energy from its linearization is Problem::Evaluate's).
template <int m>
double SquaredSum(const double* r) {
  double s = 0.0;
  for (int i = 0; i < m; ++i) s += r[i] * r[i];
  return s;
}

// 1/2 w rho(|r|^2) of one block at x; 0 if it cannot be evaluated (see Evaluate).
template <class T>
double BlockValue(const T& block, const Loss& loss, const Vertices& x) {
  const auto p = StencilPositions(block, x);
  if constexpr (HasInactive<T>::value) {
    if (block.Inactive(p.data())) return InactiveValue(block, loss);
  }
  double s = 0.0;
  if constexpr (HasNormal<T>::value) {
    if (!block.Normal(p.data(), &s, nullptr, nullptr)) return 0.0;
  } else {
    double r[T::kResiduals];
    if (!block.Evaluate(p.data(), r, nullptr)) return 0.0;
    s = SquaredSum<T::kResiduals>(r);
  }
  double rho[3];
  loss.Evaluate(s, rho);
  return 0.5 * block.weight * rho[0] - OffsetValue(block, loss);
}

// A block's share of the gradient and of the Gauss-Newton Hessian at x: with the loss
// reweighting the residual (iteratively reweighted least squares, as Ceres does for losses
// that bend down), g_i = w rho' J_i^T r and H_ij = w rho' J_i^T J_j, i, j over the stencil.
// `scale` = w rho' (0: the block adds nothing; its gradient is zero and its Hessian is not to
// be read).
template <class T>
struct Linearization {
  static constexpr int kN = T::kVertices;
  std::array<Eigen::Vector3d, kN> gradient;
  std::array<Eigen::Matrix3d, kN * kN> hessian;  // (i, j) at i * kN + j; symmetric
  double value = 0.0;
  double scale = 0.0;
};

// Returns false (and a zero scale) if the block cannot be evaluated.
template <class T>
bool Linearize(const T& block, const Loss& loss, const Vertices& x, Linearization<T>* out,
               bool with_hessian = true) {
  constexpr int m = T::kResiduals, n = T::kVertices;
  if constexpr (HasNormal<T>::value) {
    const auto p = StencilPositions(block, x);
    out->scale = 0.0;
    out->value = 0.0;
    double s = 0.0;
    if (!block.Normal(p.data(), &s, out->gradient.data(), with_hessian ? out->hessian.data() : nullptr)) {
      return false;
    }
    double rho[3];
    loss.Evaluate(s, rho);
    out->value = 0.5 * block.weight * rho[0] - OffsetValue(block, loss);
    out->scale = block.weight * rho[1];
    for (auto& g : out->gradient) g *= out->scale;
    if (with_hessian) {
      for (auto& h : out->hessian) h *= out->scale;
    }
    return true;
  }
  const auto p = StencilPositions(block, x);
  if (SkipInactive(block, loss, p, out)) return true;
  using Jacobian = Eigen::Matrix<double, m, 3, Eigen::RowMajor>;
  Eigen::Matrix<double, m, 1> r;
  std::array<Jacobian, n> J;
  std::array<double*, n> Jp;
  for (int i = 0; i < n; ++i) Jp[i] = J[i].data();
  out->scale = 0.0;
  out->value = 0.0;
  if (!block.Evaluate(p.data(), r.data(), Jp.data())) return false;
  double rho[3];
  loss.Evaluate(SquaredSum<m>(r.data()), rho);
  out->value = 0.5 * block.weight * rho[0] - OffsetValue(block, loss);
  out->scale = block.weight * rho[1];
  // A block with a zero residual and a zero Jacobian (an inactive barrier) adds nothing: a
  // zero scale spares the back ends its products and its scatter.
  bool inactive = r.isZero(0.0);
  for (int i = 0; i < n && inactive; ++i) inactive = J[i].isZero(0.0);
  if (inactive) out->scale = 0.0;
  if (out->scale == 0.0) {  // an outlier past Tukey's scale, an open contact, an inactive block
    for (auto& g : out->gradient) g.setZero();
    if (with_hessian) {
      for (auto& h : out->hessian) h.setZero();
    }
    return true;
  }
  for (int i = 0; i < n; ++i) out->gradient[i].noalias() = out->scale * J[i].transpose() * r;
  if (!with_hessian) return true;
  for (int i = 0; i < n; ++i) {
    for (int j = i; j < n; ++j) {
      out->hessian[i * n + j].noalias() = out->scale * J[i].transpose() * J[j];
      if (j != i) out->hessian[j * n + i] = out->hessian[i * n + j].transpose();
    }
  }
  return true;
}

// Whether T provides SecondOrder (above), and whether its residual is affine in x wherever it
// is differentiable (J^T J is then its exact Hessian).
template <class T, class = void>
struct HasSecondOrder : std::false_type {};
template <class T>
struct HasSecondOrder<T, std::void_t<decltype(std::declval<const T&>().SecondOrder(
                             std::declval<const double* const*>(), std::declval<double*>(),
                             std::declval<Eigen::Vector3d*>(), std::declval<Eigen::Matrix3d*>(),
                             TangentProjection::kNone))>> : std::true_type {};
template <class T, class = void>
struct IsPiecewiseAffine : std::bool_constant<T::kConstantJacobian> {};
template <class T>
struct IsPiecewiseAffine<T, std::void_t<decltype(T::kPiecewiseAffine)>>
    : std::bool_constant<T::kConstantJacobian || T::kPiecewiseAffine> {};

// The Hessian a linearization carries: the Gauss-Newton one (Linearize: w rho' J^T J, with
// the held parameters), the exact Hessian of a block's energy, or its positive semi-definite
// projection.
enum class Curvature { kGaussNewton, kExact, kProjected };

// A block's value, gradient and exact (or projected) Hessian at x (kGaussNewton: Linearize's),
// with the loss:
// d2/dx2 [1/2 w rho(2 e)] = w rho' H_e + 2 w rho'' g_e g_e^T for the block's e, g_e, H_e.
// The projection projects H_e and leaves out the loss' term where rho'' < 0 (the robust
// losses bend down), so that the result is positive semi-definite. `scale` = w rho'.
// Returns false (and a zero scale) if the block cannot be evaluated.
template <class T>
bool LinearizeSecondOrder(const T& block, const Loss& loss, const Vertices& x, Curvature curvature,
                          Linearization<T>* out, bool with_hessian = true) {
  constexpr int m = T::kResiduals, n = T::kVertices;
  static_assert(HasSecondOrder<T>::value || IsPiecewiseAffine<T>::value,
                "a block type whose residual is not affine in x provides SecondOrder");
  if (curvature == Curvature::kGaussNewton) return Linearize(block, loss, x, out, with_hessian);
  const auto p = StencilPositions(block, x);
  if (SkipInactive(block, loss, p, out)) return true;
  out->scale = 0.0;
  out->value = 0.0;
  double e = 0.0;
  std::array<Eigen::Vector3d, n> g;
  if constexpr (HasSecondOrder<T>::value) {
    const TangentProjection projection = curvature == Curvature::kExact
                                             ? TangentProjection::kNone
                                             : TangentProjection::kPositiveSemiDefinite;
    if (!block.SecondOrder(p.data(), &e, g.data(), with_hessian ? out->hessian.data() : nullptr,
                           projection)) {
      return false;
    }
  } else {
    using Jacobian = Eigen::Matrix<double, m, 3, Eigen::RowMajor>;
    Eigen::Matrix<double, m, 1> r;
    std::array<Jacobian, n> J;
    std::array<double*, n> Jp;
    for (int i = 0; i < n; ++i) Jp[i] = J[i].data();
    if (!block.Evaluate(p.data(), r.data(), Jp.data())) return false;
    e = 0.5 * SquaredSum<m>(r.data());
    for (int i = 0; i < n; ++i) {
      g[i].noalias() = J[i].transpose() * r;
      if (!with_hessian) continue;
      for (int j = 0; j < n; ++j) out->hessian[i * n + j].noalias() = J[i].transpose() * J[j];
    }
  }
  double rho[3];
  loss.Evaluate(2.0 * e, rho);
  out->value = 0.5 * block.weight * rho[0] - OffsetValue(block, loss);
  out->scale = block.weight * rho[1];
  const double bend = 2.0 * block.weight * rho[2];
  const bool with_bend = bend > 0.0 || (bend < 0.0 && curvature == Curvature::kExact);
  for (int i = 0; i < n; ++i) out->gradient[i] = out->scale * g[i];
  if (!with_hessian) return true;
  for (int i = 0; i < n; ++i) {
    for (int j = 0; j < n; ++j) {
      Eigen::Matrix3d& h = out->hessian[i * n + j];
      h *= out->scale;
      if (with_bend) h.noalias() += bend * g[i] * g[j].transpose();
    }
  }
  return true;
}

}  // namespace energy
}  // namespace femreg

#endif  // FEMREG_ENERGY_TERM_H_
