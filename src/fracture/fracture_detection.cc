// Fracture detection: the separation tensor, and per node the measure and the plane
// (docs/theory/fracture.md#detection); see femreg/fracture.h.
#include "femreg/fracture.h"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <sstream>

#include "fracture/measure_bound.h"
#include "fracture/split_state.h"

namespace femreg {

bool FractureOptions::IsValid(std::string* error) const {
  std::ostringstream os;
  if (!std::isfinite(toughness)) {
    os << "toughness must be finite (got " << toughness << ")";
  } else if (!(crossing_tolerance >= 0 && crossing_tolerance < 1)) {
    os << "crossing_tolerance must be in [0, 1) (got " << crossing_tolerance << ")";
  } else if (!(min_piece_fraction >= 0 && min_piece_fraction < 0.5)) {
    os << "min_piece_fraction must be in [0, 0.5) (got " << min_piece_fraction << ")";
  } else if (max_splits_per_iteration < 1) {
    os << "max_splits_per_iteration must be >= 1 (got " << max_splits_per_iteration << ")";
  } else if (max_splits_per_frame < 1) {
    os << "max_splits_per_frame must be >= 1 (got " << max_splits_per_frame << ")";
  } else if (max_cracks < 0) {
    os << "max_cracks must be >= 0 (got " << max_cracks << ")";
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
  const Vector12 fp = rest.volume * rest.L.transpose() * TensorToVoigt(sp);
  const Vector12 fm = rest.volume * rest.L.transpose() * TensorToVoigt(sm);
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

// Bounds of the stress s's (Voigt) extreme eigenvalues without its eigen-decomposition: the
// tighter of Gershgorin's and the deviatoric ones (the deviator's eigenvalues sum to 0, so none
// is farther from 0 than sqrt(2/3) of its norm). top >= the largest, bottom <= the smallest.
void StressEigenvalueBounds(const Vector6& s, double* top, double* bottom, double* norm) {
  const double mean = (s(0) + s(1) + s(2)) / 3.0;
  const double shear2 = s(3) * s(3) + s(4) * s(4) + s(5) * s(5);
  const double dev2 = (s(0) - mean) * (s(0) - mean) + (s(1) - mean) * (s(1) - mean) +
                      (s(2) - mean) * (s(2) - mean) + 2.0 * shear2;
  const double spread = std::sqrt(2.0 / 3.0 * dev2);
  const double r0 = std::abs(s(5)) + std::abs(s(4)), r1 = std::abs(s(5)) + std::abs(s(3)),
               r2 = std::abs(s(4)) + std::abs(s(3));
  *top = std::min(mean + spread, std::max({s(0) + r0, s(1) + r1, s(2) + r2}));
  *bottom = std::max(mean - spread, std::min({s(0) - r0, s(1) - r1, s(2) - r2}));
  *norm = std::sqrt(s(0) * s(0) + s(1) * s(1) + s(2) * s(2) + 2.0 * shear2);
}

// MeasureBound's sums (N) before the division by the area.
Eigen::VectorXd BoundSums(const ElasticModel& model, const std::vector<Eigen::Matrix3d>* rotations,
                          const Vertices& x, int nv) {
  Eigen::VectorXd sum = Eigen::VectorXd::Zero(nv);
  for (int e = 0; e < model.num_elements(); ++e) {
    const ElementRest& rest = model.rest(e);
    const Vector6 s = ElementStress(rest, RotationOf(model, rotations, e), model.Gather(x, e));
    double top, bottom, norm;
    StressEigenvalueBounds(s, &top, &bottom, &norm);
    // A margin for the round-off of the full evaluation's closed-form eigen-solvers (a
    // compressed node's measure is 0 up to some 1e-9 of the stress, not exactly).
    const double slack = 1e-7 * norm;
    const double plus = std::max(0.0, top) + slack, minus = std::max(0.0, -bottom) + slack;
    // The tensile part's force on node k is V sigma+ g (g = grad N_k); the largest eigenvalue
    // of zeta is at most half the sum of their norms (m(a) has the one eigenvalue |a|, and the
    // other terms are negative semi-definite). With 0 <= sigma+ <= plus I and
    // sigma+ <= sigma + minus I: |sigma+ g|^2 <= plus g^T sigma+ g <= plus (g^T sigma g + minus |g|^2),
    // which is |sigma+ g| itself for a uniaxial tension.
    const Eigen::Matrix3d sigma = VoigtToTensor(s);
    for (int k = 0; k < 4; ++k) {
      const Eigen::Vector3d g(rest.L(0, 3 * k), rest.L(1, 3 * k + 1), rest.L(2, 3 * k + 2));
      const double g2 = g.squaredNorm();
      const double along = std::sqrt(std::max(0.0, plus * (g.dot(sigma * g) + minus * g2)));
      sum(model.tets()(e, k)) += 0.5 * rest.volume * std::min(plus * std::sqrt(g2), along + slack * std::sqrt(g2));
    }
  }
  return sum * (1.0 + 1e-9);
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

Eigen::VectorXd MeasureBound(const TetMesh& mesh, const ElasticModel& model, const Vertices& x,
                             const std::vector<Eigen::Matrix3d>* rotations) {
  const int nv = mesh.num_vertices();
  Eigen::VectorXd bound = BoundSums(model, rotations, x, nv);
  Eigen::VectorXd area, toughness;
  NodeAreas(mesh, model, FractureOptions(), &area, &toughness);
  for (int j = 0; j < nv; ++j) bound(j) = area(j) > 0 ? bound(j) / area(j) : 0.0;
  return bound;
}

int DetectFractureAbove(const TetMesh& mesh, const ElasticModel& model, const Vertices& x,
                        const FractureOptions& options, double floor, NodeSeparation* out) {
  const int nv = mesh.num_vertices();
  Eigen::VectorXd area;
  NodeAreas(mesh, model, options, &area, &out->toughness);
  const Eigen::VectorXd sum = BoundSums(model, nullptr, x, nv);
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
  const std::vector<Eigen::Matrix3d> zeta = Tensors(mesh, model, nullptr, x, want);
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
  for (int e = 0; e < model.num_elements(); ++e) {
    if (model.type() == ElasticModelType::kLinear) {
      rotations[static_cast<size_t>(e)] = model.rotation(e);
      continue;
    }
    Eigen::Matrix<double, 3, 4> xe;
    for (int k = 0; k < 4; ++k) xe.col(k) = x.row(model.tets()(e, k)).transpose();
    rotations[static_cast<size_t>(e)] =
        PolarRotation(DeformationGradient(xe, model.rest(e).dm_inv), model.rotation(e));
  }
  return rotations;
}

}  // namespace fracture_internal

}  // namespace femreg
