// Fracture detection: the separation tensor, and per node the measure and the plane
// (docs/theory/fracture.md#detection); see femreg/fracture.h.
#include "femreg/fracture.h"

#include <Eigen/Eigenvalues>
#include <cmath>
#include <sstream>

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

}  // namespace

std::vector<Eigen::Matrix3d> SeparationTensors(const TetMesh& mesh, const ElasticModel& model,
                                               const Vertices& x) {
  const int nv = mesh.num_vertices();
  std::vector<Eigen::Vector3d> f_plus(nv, Eigen::Vector3d::Zero()),
      f_minus(nv, Eigen::Vector3d::Zero());
  std::vector<Eigen::Matrix3d> m_plus(nv, Eigen::Matrix3d::Zero()),
      m_minus(nv, Eigen::Matrix3d::Zero());
  for (int e = 0; e < model.num_elements(); ++e) {
    const ElementRest& rest = model.rest(e);
    const Eigen::Matrix3d& R = model.rotation(e);
    const Eigen::Matrix3d sigma = VoigtToTensor(ElementStress(rest, R, model.Gather(x, e)));
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
      f_plus[j] += a;
      f_minus[j] += b;
      m_plus[j] += OuterOverNorm(a);
      m_minus[j] += OuterOverNorm(b);
    }
  }
  std::vector<Eigen::Matrix3d> zeta(nv);
  for (int j = 0; j < nv; ++j) {
    // The compressive half only holds a node together: its positive part (which appears
    // at surface nodes under triaxial compression, where the element forces are not
    // parallel) is dropped, so that compression alone never separates.
    const Eigen::Matrix3d compressive = 0.5 * (OuterOverNorm(f_minus[j]) - m_minus[j]);
    Eigen::Matrix3d held = compressive;
    if (compressive.squaredNorm() > 0) {
      Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eig;
      eig.computeDirect(compressive);
      held = eig.eigenvectors() * eig.eigenvalues().cwiseMin(0.0).asDiagonal() *
             eig.eigenvectors().transpose();
    }
    zeta[j] = 0.5 * (m_plus[j] - OuterOverNorm(f_plus[j])) + held;
  }
  return zeta;
}

void DetectFracture(const TetMesh& mesh, const ElasticModel& model, const Vertices& x,
                    const FractureOptions& options, NodeSeparation* out) {
  const int nv = mesh.num_vertices();
  const std::vector<Eigen::Matrix3d> zeta = SeparationTensors(mesh, model, x);
  Eigen::VectorXd node_volume = Eigen::VectorXd::Zero(nv);
  out->toughness = Eigen::VectorXd::Zero(nv);
  for (int e = 0; e < model.num_elements(); ++e) {
    const double t = ElementToughness(options, e < mesh.region.size() ? mesh.region(e) : 0);
    for (int k = 0; k < 4; ++k) {
      const int j = model.tets()(e, k);
      node_volume(j) += 0.25 * model.rest(e).volume;
      if (t > 0 && (out->toughness(j) <= 0 || t < out->toughness(j))) out->toughness(j) = t;
    }
  }
  out->measure.resize(nv);
  out->normal.resize(nv, 3);
  for (int j = 0; j < nv; ++j) {
    Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eig;
    eig.computeDirect(zeta[j]);
    const double area = std::pow(node_volume(j), 2.0 / 3.0);
    const double top = eig.eigenvalues()(2);
    out->measure(j) = area > 0 && top > 0 ? top / area : 0.0;
    out->normal.row(j) = CanonicalSign(eig.eigenvectors().col(2)).transpose();
  }
}

}  // namespace femreg
