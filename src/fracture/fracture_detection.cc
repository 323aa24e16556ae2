// Fracture detection: the separation tensor, and per node the measure and the plane
// (docs/theory/fracture.md#detection); see femreg/fracture.h.
#include "femreg/fracture.h"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <array>
#include <cmath>
#include <sstream>

#include "fracture/measure_bound.h"
#include "fracture/split_state.h"

namespace femreg {

bool FractureOptions::IsValid(std::string* error) const {
  // The scene's keys by their table (femreg/fracture.h); the rest by hand.
  std::ostringstream os;
  if (!std::isfinite(toughness)) {
    os << "toughness must be finite (got " << toughness << ")";
  } else if (!CheckFieldRanges(*this, error)) {
    return false;
  } else if (!(min_piece_fraction >= 0 && min_piece_fraction < 0.5)) {
    os << "min_piece_fraction must be in [0, 0.5) (got " << min_piece_fraction << ")";
  } else {
    return true;
  }
  if (error) *error = os.str();
  return false;
}

namespace {

using fracture_internal::CanonicalSign;

// m(a) = a a^T / |a|, 0 for a = 0.
Eigen::Matrix3d OuterOverNorm(const Eigen::Vector3d& a) {
  const double n = a.norm();
  if (!(n > 0)) return Eigen::Matrix3d::Zero();
  return a * a.transpose() / n;
}

Eigen::Matrix3d VoigtToTensor(const Vector6& s) {
  Eigen::Matrix3d t;
  t << s(0), s(5), s(4), s(5), s(1), s(3), s(4), s(3), s(2);
  return t;
}

Vector6 TensorToVoigt(const Eigen::Matrix3d& t) {
  Vector6 s;
  s << t(0, 0), t(1, 1), t(2, 2), t(1, 2), t(0, 2), t(0, 1);
  return s;
}

double ElementToughness(const FractureOptions& options, int region) {
  for (const auto& rt : options.region_toughness) {
    if (rt.first == region) return rt.second;
  }
  return options.toughness;
}

const Eigen::Matrix3d& RotationOf(const ElasticModel& model, const std::vector<Eigen::Matrix3d>* rotations,
                                  int e) {
  return rotations ? (*rotations)[static_cast<size_t>(e)] : model.rotation(e);
}

// Element e's rotation at x as ElasticModel::UpdateRotations finds it, from the model's.
Eigen::Matrix3d RotationAt(const ElasticModel& model, const Vertices& x, int e) {
  if (model.type() == ElasticModelType::kLinear) return model.rotation(e);
  Eigen::Matrix<double, 3, 4> xe;
  for (int k = 0; k < 4; ++k) xe.col(k) = x.row(model.tets()(e, k)).transpose();
  return PolarRotation(DeformationGradient(xe, model.rest(e).dm_inv), model.rotation(e));
}

// The per-node sums the separation tensor is made of.
struct NodeSums {
  explicit NodeSums(int nv)
      : f_plus(nv, Eigen::Vector3d::Zero()),
        f_minus(nv, Eigen::Vector3d::Zero()),
        m_plus(nv, Eigen::Matrix3d::Zero()),
        m_minus(nv, Eigen::Matrix3d::Zero()) {}
  std::vector<Eigen::Vector3d> f_plus, f_minus;
  std::vector<Eigen::Matrix3d> m_plus, m_minus;
};

// Element e's tensile and compressive nodal forces, added to its nodes' sums (Eqs. 8-12).
void AddElement(const ElasticModel& model, int e, const Eigen::Matrix3d& R, const Vector6& stress,
                NodeSums* sums) {
  const ElementRest& rest = model.rest(e);
  const Eigen::Matrix3d sigma = VoigtToTensor(stress);
  // Eqs. 8-9: the tensile and compressive parts by the eigen-decomposition.
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eig;
  eig.computeDirect(sigma);  // closed form: the detection runs every outer iteration
  const Eigen::Vector3d nu = eig.eigenvalues();
  const Eigen::Matrix3d& n = eig.eigenvectors();
  const Eigen::Matrix3d sp = n * nu.cwiseMax(0.0).asDiagonal() * n.transpose();
  const Eigen::Matrix3d sm = n * nu.cwiseMin(0.0).asDiagonal() * n.transpose();
  // Eqs. 11-12: nodal forces V L^T sigma+-, rotated to the world frame.
  const Matrix6x12 L = StrainDisplacement(rest);
  const Vector12 fp = rest.volume * L.transpose() * TensorToVoigt(sp);
  const Vector12 fm = rest.volume * L.transpose() * TensorToVoigt(sm);
  for (int k = 0; k < 4; ++k) {
    const int j = model.tets()(e, k);
    const Eigen::Vector3d a = R * fp.segment<3>(3 * k), b = R * fm.segment<3>(3 * k);
    sums->f_plus[j] += a;
    sums->f_minus[j] += b;
    sums->m_plus[j] += OuterOverNorm(a);
    sums->m_minus[j] += OuterOverNorm(b);
  }
}

Eigen::Matrix3d NodeTensor(const NodeSums& sums, int j) {
  // The compressive half only holds a node together: its positive part (which appears
  // at surface nodes under triaxial compression, where the element forces are not
  // parallel) is dropped, so that compression alone never separates.
  const Eigen::Matrix3d compressive = 0.5 * (OuterOverNorm(sums.f_minus[j]) - sums.m_minus[j]);
  Eigen::Matrix3d held = compressive;
  if (compressive.squaredNorm() > 0) {
    Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eig;
    eig.computeDirect(compressive);
    held = eig.eigenvectors() * eig.eigenvalues().cwiseMin(0.0).asDiagonal() *
           eig.eigenvectors().transpose();
  }
  return 0.5 * (sums.m_plus[j] - OuterOverNorm(sums.f_plus[j])) + held;
}

// The separation tensors of the nodes with want[j] (every node if want is empty; the others
// are left 0), each summed over its elements in element order, so that a node's tensor does
// not depend on which other nodes are wanted.
std::vector<Eigen::Matrix3d> Tensors(const TetMesh& mesh, const ElasticModel& model,
                                     const std::vector<Eigen::Matrix3d>* rotations, const Vertices& x,
                                     const std::vector<char>& want) {
  const int nv = mesh.num_vertices();
  const bool all = want.empty();
  NodeSums sums(nv);
  for (int e = 0; e < model.num_elements(); ++e) {
    bool needed = all;
    for (int k = 0; k < 4 && !needed; ++k) needed = want[static_cast<size_t>(model.tets()(e, k))] != 0;
    if (!needed) continue;
    const Eigen::Matrix3d& R = RotationOf(model, rotations, e);
    AddElement(model, e, R, ElementStress(model.rest(e), R, model.Gather(x, e)), &sums);
  }
  std::vector<Eigen::Matrix3d> zeta(nv, Eigen::Matrix3d::Zero());
  for (int j = 0; j < nv; ++j) {
    if (all || want[static_cast<size_t>(j)]) zeta[j] = NodeTensor(sums, j);
  }
  return zeta;
}

// Per node: the area A_j = V_j^(2/3) (V_j its share of the rest volume) and the toughness.
void NodeAreas(const TetMesh& mesh, const ElasticModel& model, const FractureOptions& options,
               Eigen::VectorXd* area, Eigen::VectorXd* toughness) {
  const int nv = mesh.num_vertices();
  Eigen::VectorXd node_volume = Eigen::VectorXd::Zero(nv);
  *toughness = Eigen::VectorXd::Zero(nv);
  for (int e = 0; e < model.num_elements(); ++e) {
    const double t = ElementToughness(options, e < mesh.region.size() ? mesh.region(e) : 0);
    for (int k = 0; k < 4; ++k) {
      const int j = model.tets()(e, k);
      node_volume(j) += 0.25 * model.rest(e).volume;
      if (t > 0 && ((*toughness)(j) <= 0 || t < (*toughness)(j))) (*toughness)(j) = t;
    }
  }
  area->resize(nv);
  for (int j = 0; j < nv; ++j) (*area)(j) = std::pow(node_volume(j), 2.0 / 3.0);
}

// The measure and plane of node j from its tensor.
void NodeMeasure(const Eigen::Matrix3d& zeta, double area, int j, NodeSeparation* out) {
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eig;
  eig.computeDirect(zeta);
  const double top = eig.eigenvalues()(2);
  out->measure(j) = area > 0 && top > 0 ? top / area : 0.0;
  out->normal.row(j) = CanonicalSign(eig.eigenvectors().col(2)).transpose();
}

void Detect(const TetMesh& mesh, const ElasticModel& model, const std::vector<Eigen::Matrix3d>* rotations,
            const Vertices& x, const FractureOptions& options, NodeSeparation* out) {
  const int nv = mesh.num_vertices();
  const std::vector<Eigen::Matrix3d> zeta = Tensors(mesh, model, rotations, x, {});
  Eigen::VectorXd area;
  NodeAreas(mesh, model, options, &area, &out->toughness);
  out->measure.resize(nv);
  out->normal.resize(nv, 3);
  for (int j = 0; j < nv; ++j) NodeMeasure(zeta[j], area(j), j, out);
}

// Bounds of a symmetric matrix's extreme eigenvalues without its eigen-decomposition: the
// tighter of Gershgorin's and the deviatoric ones (the deviator's eigenvalues sum to 0, so none
// is farther from the mean than sqrt(2/3) of its norm).
void EigenvalueBounds(const Eigen::Matrix3d& a, double* top, double* bottom) {
  const double mean = a.trace() / 3.0;
  const double spread = std::sqrt(2.0 / 3.0 * (a - mean * Eigen::Matrix3d::Identity()).squaredNorm());
  const double r0 = std::abs(a(0, 1)) + std::abs(a(0, 2)), r1 = std::abs(a(0, 1)) + std::abs(a(1, 2)),
               r2 = std::abs(a(0, 2)) + std::abs(a(1, 2));
  *top = std::min(mean + spread, std::max({a(0, 0) + r0, a(1, 1) + r1, a(2, 2) + r2}));
  *bottom = std::max(mean - spread, std::min({a(0, 0) - r0, a(1, 1) - r1, a(2, 2) - r2}));
}

// MeasureBound's sums (N) before the division by the area. The tensile part's force on node k
// is V sigma+ g (g = grad N_k); the largest eigenvalue of zeta is at most half the sum of their
// norms (m(a) has the one eigenvalue |a|, and the other terms are negative semi-definite). With
// 0 <= sigma+ <= plus I and sigma+ <= sigma + minus I (plus, minus: bounds of the largest
// principal stress and of minus the smallest, clamped at 0),
//   |sigma+ g|^2 <= plus g^T sigma+ g <= plus (g^T sigma g + minus |g|^2),
// which is |sigma+ g|^2 itself for a uniaxial tension. The corotational stress needs no
// rotation: with F = R S, R^T x - X has the gradient S - I, so sigma = lambda tr(S - I) I +
// 2 mu (S - I), and S's eigenvalues are those of C = F^T F's square roots (one of them
// negative for an inverted element), and g^T S g <= |g| |S g| = |g| sqrt(g^T C g). The linear
// element's stress (no rotation) is taken as it is.
// A corotated element's part of the bound: the bounds of its principal stresses (plus, minus,
// with the round-off slack), and for the refinement along each gradient the weights of
// |g| sqrt(g^T C g) (2 mu) and of |g|^2 (diagonal), with C = F^T F (its upper triangle).
struct ElementScalars {
  double plus, minus, slack, diagonal;
  double c[6];
  bool tensile;  // a tensile part beyond round-off
};

ElementScalars CorotatedScalars(const fracture_internal::BoundData::Element& el, const Vertices& x) {
  ElementScalars r;
  Eigen::Matrix<double, 3, 4> xe;
  for (int k = 0; k < 4; ++k) xe.col(k) = x.row(el.vertices[k]).transpose();
  const Eigen::Matrix3d F = DeformationGradient(xe, el.dm_inv);
  const Eigen::Matrix3d C = F.transpose() * F;
  double c_top, c_bottom;
  EigenvalueBounds(C, &c_top, &c_bottom);
  const double trace = C.trace();
  const double c_low = std::max(0.0, c_bottom);
  const double s_top = std::sqrt(std::max(0.0, std::min(c_top, trace))), s_low = std::sqrt(c_low);
  // tr S: at most sum |s_i| <= sqrt(3 tr C). At least, when no s_i is negative, the chord of
  // the square root between C's eigenvalue bounds (it lies below the concave root) summed:
  // 3 sqrt(c_low) + (tr C - 3 c_low) / (sqrt(c_top) + sqrt(c_low)).
  const bool inverted = !(F.determinant() > 0.0);
  const double tr_high = std::sqrt(3.0 * trace);
  const double tr_low = inverted ? -tr_high
                                 : 3.0 * s_low + (s_top + s_low > 0 ? (trace - 3.0 * c_low) / (s_top + s_low) : 0.0);
  const double s_bottom = inverted ? -s_top : s_low;
  const double lambda = el.lambda, mu = el.mu;
  const double volumetric_high = lambda * ((lambda >= 0 ? tr_high : tr_low) - 3.0);
  const double volumetric_low = lambda * ((lambda >= 0 ? tr_low : tr_high) - 3.0);
  // Round-off of the full evaluation (the rotation, the closed-form eigen-solvers): a
  // compressed node's measure is 0 only to some 1e-9 of the stress.
  r.slack = 1e-7 * (3.0 * std::abs(lambda) + 2.0 * mu) * (1.0 + s_top);
  r.plus = std::max(0.0, volumetric_high + 2.0 * mu * (s_top - 1.0)) + r.slack;
  r.minus = std::max(0.0, -(volumetric_low + 2.0 * mu * (s_bottom - 1.0))) + r.slack;
  r.tensile = r.plus > r.slack;
  r.diagonal = volumetric_high - 2.0 * mu;
  r.c[0] = C(0, 0), r.c[1] = C(1, 1), r.c[2] = C(2, 2), r.c[3] = C(1, 2), r.c[4] = C(0, 2), r.c[5] = C(0, 1);
  return r;
}

// Element e's terms of its nodes' sums: with plus alone (|sigma+ g| <= plus |g|: `coarse`), or
// with the refinement along each gradient (every term at most the coarse one).
void CorotatedTerms(const fracture_internal::BoundData::Element& el, const ElementScalars& r, bool coarse,
                    double term[4]) {
  if (!r.tensile) {  // no tensile part beyond round-off
    for (int k = 0; k < 4; ++k) term[k] = 0.5 * el.volume * r.plus * el.g1[k];
    return;
  }
  if (coarse) {
    for (int k = 0; k < 4; ++k) term[k] = 0.5 * el.volume * (r.plus * el.g1[k] + r.slack * el.g1[k]);
    return;
  }
  Eigen::Matrix3d C;  // C = F^T F is exactly symmetric (the same products in the same order)
  C << r.c[0], r.c[5], r.c[4], r.c[5], r.c[1], r.c[3], r.c[4], r.c[3], r.c[2];
  const double root_scale = 2.0 * el.mu;
  for (int k = 0; k < 4; ++k) {
    const double q = el.g[k].dot(C * el.g[k]);
    // g^T sigma g, from above.
    const double along_g = root_scale * el.g1[k] * std::sqrt(std::max(0.0, q)) + r.diagonal * el.g2[k];
    const double along = std::sqrt(std::max(0.0, r.plus * (along_g + r.minus * el.g2[k])));
    term[k] = 0.5 * el.volume * (std::min(r.plus * el.g1[k], along) + r.slack * el.g1[k]);
  }
}

// MeasureBound's sums (N) before the division by the area, at the nodes that can reach `floor`
// times their toughness (every node if floor < 0); at the others a sum that is below it. A
// corotated model's are found in two passes: the coarse sums (plus |g| per term) everywhere,
// then the refined ones only from the elements around the nodes whose coarse sum reaches the
// floor. Every refined term is at most its coarse one, and both are summed in element order, so
// a node the coarse sums leave out cannot reach the floor, and a node kept has the refined sum
// of a single pass to the bit.
Eigen::VectorXd BoundSums(const ElasticModel& model, const fracture_internal::BoundData& data, const Vertices& x,
                          int nv, double floor) {
  constexpr double kMargin = 1.0 + 1e-9;
  Eigen::VectorXd sum = Eigen::VectorXd::Zero(nv);
  if (model.type() == ElasticModelType::kLinear) {
    for (int e = 0; e < model.num_elements(); ++e) {
      const ElementRest& rest = model.rest(e);
      const Vector6 s = ElementStress(rest, model.rotation(e), model.Gather(x, e));
      const Eigen::Matrix3d sigma = VoigtToTensor(s);
      double top, bottom;
      EigenvalueBounds(sigma, &top, &bottom);
      const double slack = 1e-7 * sigma.norm();
      const double plus = std::max(0.0, top) + slack, minus = std::max(0.0, -bottom) + slack;
      const Eigen::Matrix<double, 3, 4> gradients = ShapeGradients(rest);
      for (int k = 0; k < 4; ++k) {
        const Eigen::Vector3d g = gradients.col(k);
        const double g2 = g.squaredNorm(), g1 = std::sqrt(g2);
        const double q = g.dot(sigma * g);
        const double along = std::sqrt(std::max(0.0, plus * (q + minus * g2)));
        sum(model.tets()(e, k)) += 0.5 * rest.volume * (std::min(plus * g1, along) + slack * g1);
      }
    }
    return sum * kMargin;
  }
  const int ne = model.num_elements();
  std::vector<ElementScalars> scalars(static_cast<size_t>(ne));
  double term[4];
  for (int e = 0; e < ne; ++e) {
    const fracture_internal::BoundData::Element& el = data.elements[static_cast<size_t>(e)];
    scalars[static_cast<size_t>(e)] = CorotatedScalars(el, x);
    CorotatedTerms(el, scalars[static_cast<size_t>(e)], /*coarse=*/floor >= 0, term);
    for (int k = 0; k < 4; ++k) sum(el.vertices[k]) += term[k];
  }
  if (floor < 0) return sum * kMargin;
  std::vector<char> kept(static_cast<size_t>(nv), 0);
  bool any = false;
  for (int j = 0; j < nv; ++j) {
    const double t = data.toughness(j);
    kept[static_cast<size_t>(j)] = t > 0 && data.area(j) > 0 && sum(j) * kMargin >= floor * t * data.area(j);
    any = any || kept[static_cast<size_t>(j)];
  }
  if (!any) return sum * kMargin;
  Eigen::VectorXd refined = Eigen::VectorXd::Zero(nv);
  for (int e = 0; e < ne; ++e) {
    const fracture_internal::BoundData::Element& el = data.elements[static_cast<size_t>(e)];
    bool needed = false;
    for (int k = 0; k < 4 && !needed; ++k) needed = kept[static_cast<size_t>(el.vertices[k])] != 0;
    if (!needed) continue;
    CorotatedTerms(el, scalars[static_cast<size_t>(e)], /*coarse=*/false, term);
    for (int k = 0; k < 4; ++k) refined(el.vertices[k]) += term[k];
  }
  for (int j = 0; j < nv; ++j) {
    if (kept[static_cast<size_t>(j)]) sum(j) = refined(j);
  }
  return sum * kMargin;
}

}  // namespace

std::vector<Eigen::Matrix3d> SeparationTensors(const TetMesh& mesh, const ElasticModel& model,
                                               const Vertices& x) {
  return Tensors(mesh, model, nullptr, x, {});
}

void DetectFracture(const TetMesh& mesh, const ElasticModel& model, const Vertices& x,
                    const FractureOptions& options, NodeSeparation* out) {
  Detect(mesh, model, nullptr, x, options, out);
}

namespace fracture_internal {

void BuildBoundData(const TetMesh& mesh, const ElasticModel& model, const FractureOptions& options,
                    BoundData* data) {
  data->num_vertices = mesh.num_vertices();
  data->num_elements = model.num_elements();
  NodeAreas(mesh, model, options, &data->area, &data->toughness);
  data->elements.clear();
  if (model.type() == ElasticModelType::kLinear) return;
  data->elements.resize(static_cast<size_t>(model.num_elements()));
  for (int e = 0; e < model.num_elements(); ++e) {
    const ElementRest& rest = model.rest(e);
    const Eigen::Matrix<double, 3, 4> gradients = ShapeGradients(rest);
    BoundData::Element& el = data->elements[static_cast<size_t>(e)];
    for (int k = 0; k < 4; ++k) {
      el.vertices[k] = model.tets()(e, k);
      el.g[k] = gradients.col(k);
      el.g2[k] = el.g[k].squaredNorm();
      el.g1[k] = std::sqrt(el.g2[k]);
    }
    el.dm_inv = rest.dm_inv;
    el.volume = rest.volume;
    el.lambda = rest.lambda;
    el.mu = rest.mu;
  }
}

Eigen::VectorXd MeasureBound(const TetMesh& mesh, const ElasticModel& model, const Vertices& x) {
  BoundData data;
  BuildBoundData(mesh, model, FractureOptions(), &data);
  const int nv = mesh.num_vertices();
  Eigen::VectorXd bound = BoundSums(model, data, x, nv, -1.0);
  for (int j = 0; j < nv; ++j) bound(j) = data.area(j) > 0 ? bound(j) / data.area(j) : 0.0;
  return bound;
}

int DetectFractureAbove(const TetMesh& mesh, const ElasticModel& model, const Vertices& x,
                        const FractureOptions& options, double floor, bool rotations_current,
                        NodeSeparation* out) {
  BoundData data;
  BuildBoundData(mesh, model, options, &data);
  return DetectFractureAbove(mesh, model, x, floor, rotations_current, data, out);
}

int DetectFractureAbove(const TetMesh& mesh, const ElasticModel& model, const Vertices& x, double floor,
                        bool rotations_current, const BoundData& data, NodeSeparation* out) {
  const int nv = mesh.num_vertices();
  const Eigen::VectorXd& area = data.area;
  out->toughness = data.toughness;
  const Eigen::VectorXd sum = BoundSums(model, data, x, nv, floor);
  std::vector<char> want(static_cast<size_t>(nv), 0);
  int wanted = 0;
  for (int j = 0; j < nv; ++j) {
    const double t = out->toughness(j);
    if (t > 0 && area(j) > 0 && sum(j) >= floor * t * area(j)) {
      want[static_cast<size_t>(j)] = 1;
      ++wanted;
    }
  }
  out->measure = Eigen::VectorXd::Zero(nv);
  out->normal = Vertices::Zero(nv, 3);
  if (wanted == 0) return 0;
  std::vector<Eigen::Matrix3d> rotations;
  if (!rotations_current) {
    // Only the elements evaluated, found as ElasticModel::UpdateRotations would from the
    // model's (the same start, so the same rotations).
    rotations.resize(static_cast<size_t>(model.num_elements()));
    for (int e = 0; e < model.num_elements(); ++e) {
      bool needed = false;
      for (int k = 0; k < 4 && !needed; ++k) needed = want[static_cast<size_t>(model.tets()(e, k))] != 0;
      if (needed) rotations[static_cast<size_t>(e)] = RotationAt(model, x, e);
    }
  }
  const std::vector<Eigen::Matrix3d> zeta = Tensors(mesh, model, rotations_current ? nullptr : &rotations, x, want);
  for (int j = 0; j < nv; ++j) {
    if (want[static_cast<size_t>(j)]) NodeMeasure(zeta[j], area(j), j, out);
  }
  return wanted;
}

void DetectFractureWith(const TetMesh& mesh, const ElasticModel& model,
                        const std::vector<Eigen::Matrix3d>& rotations, const Vertices& x,
                        const FractureOptions& options, NodeSeparation* out) {
  Detect(mesh, model, &rotations, x, options, out);
}

std::vector<Eigen::Matrix3d> RotationsAt(const ElasticModel& model, const Vertices& x) {
  std::vector<Eigen::Matrix3d> rotations(static_cast<size_t>(model.num_elements()));
  for (int e = 0; e < model.num_elements(); ++e) rotations[static_cast<size_t>(e)] = RotationAt(model, x, e);
  return rotations;
}

}  // namespace fracture_internal

}  // namespace femreg
