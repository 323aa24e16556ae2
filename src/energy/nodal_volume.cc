#include "energy/nodal_volume.h"

#include <algorithm>
#include <cmath>

namespace femreg {
namespace energy {

namespace {
Vector12 ElementPositions(const Tets& tets, int e, const Vertices& x) {
  Vector12 xe;
  for (int k = 0; k < 4; ++k) xe.segment<3>(3 * k) = x.row(tets(e, k)).transpose();
  return xe;
}
}  // namespace

void NodalVolume::Build(const Tets& tets, const std::vector<const ElementRest*>& rests,
                        int num_vertices, int threads, double scale) {
  tets_ = tets;
  rests_ = rests;
  num_vertices_ = num_vertices;
  threads_ = threads;
  const int nt = static_cast<int>(tets.rows());
  rest_volume_.assign(num_vertices, 0.0);
  stiffness_.assign(num_vertices, 0.0);
  element_offsets_.assign(num_vertices + 1, 0);
  for (int e = 0; e < nt; ++e) {
    for (int k = 0; k < 4; ++k) {
      const int v = tets(e, k);
      rest_volume_[v] += 0.25 * rests[e]->volume;
      stiffness_[v] += 0.25 * scale * rests[e]->volume * BulkModulus(*rests[e]);
      ++element_offsets_[v + 1];
    }
  }
  for (int v = 0; v < num_vertices; ++v) element_offsets_[v + 1] += element_offsets_[v];
  element_slots_.assign(element_offsets_[num_vertices], 0);
  std::vector<int> fill(element_offsets_.begin(), element_offsets_.end() - 1);
  for (int e = 0; e < nt; ++e)
    for (int k = 0; k < 4; ++k) element_slots_[fill[tets(e, k)]++] = 4 * e + k;
  std::vector<std::pair<int, int>>& pairs = pairs_;
  pairs.clear();
  std::vector<int> star;
  for (int v = 0; v < num_vertices_; ++v) {
    star.clear();
    for (int s = element_offsets_[v]; s < element_offsets_[v + 1]; ++s)
      for (int k = 0; k < 4; ++k) star.push_back(tets_(element_slots_[s] / 4, k));
    std::sort(star.begin(), star.end());
    star.erase(std::unique(star.begin(), star.end()), star.end());
    for (size_t i = 0; i < star.size(); ++i)
      for (size_t j = i + 1; j < star.size(); ++j) pairs.emplace_back(star[i], star[j]);
  }
  std::sort(pairs.begin(), pairs.end());
  pairs.erase(std::unique(pairs.begin(), pairs.end()), pairs.end());
}

NodalVolume::Star NodalVolume::StarOf(int a) const {
  Star star;
  star.rest_volume = rest_volume_[a];
  star.stiffness = stiffness_[a];
  for (int s = element_offsets_[a]; s < element_offsets_[a + 1]; ++s) {
    for (int k = 0; k < 4; ++k) star.vertices.push_back(tets_(element_slots_[s] / 4, k));
  }
  std::sort(star.vertices.begin(), star.vertices.end());
  star.vertices.erase(std::unique(star.vertices.begin(), star.vertices.end()), star.vertices.end());
  for (int s = element_offsets_[a]; s < element_offsets_[a + 1]; ++s) {
    const int e = element_slots_[s] / 4;
    std::array<int, 4> places;
    for (int k = 0; k < 4; ++k) {
      places[k] = static_cast<int>(std::lower_bound(star.vertices.begin(), star.vertices.end(), tets_(e, k)) -
                                   star.vertices.begin());
    }
    star.elements.push_back(places);
    star.rests.push_back(rests_[e]);
  }
  return star;
}

double NodalVolume::StarResidual(const Star& star, const double* const* x, double** jacobians) {
  if (!(star.rest_volume > 0)) {
    if (jacobians != nullptr) {
      for (size_t i = 0; i < star.vertices.size(); ++i) {
        if (jacobians[i] != nullptr) std::fill(jacobians[i], jacobians[i] + 3, 0.0);
      }
    }
    return 0.0;
  }
  // r_a = sqrt(K_a V_a) / V_a * sum_e (v_e - V_e) / 4.
  const double factor = std::sqrt(star.stiffness) / star.rest_volume;
  if (jacobians != nullptr) {
    for (size_t i = 0; i < star.vertices.size(); ++i) {
      if (jacobians[i] != nullptr) std::fill(jacobians[i], jacobians[i] + 3, 0.0);
    }
  }
  double change = 0.0;
  for (size_t e = 0; e < star.elements.size(); ++e) {
    const ElementRest& rest = *star.rests[e];
    Vector12 xe;
    Eigen::Matrix<double, 3, 4> xm;
    for (int k = 0; k < 4; ++k) {
      const double* p = x[star.elements[e][k]];
      xe.segment<3>(3 * k) = Eigen::Vector3d(p[0], p[1], p[2]);
      xm.col(k) = xe.segment<3>(3 * k);
    }
    change += 0.25 * rest.volume * DeterminantMinusOne(DeformationGradient(xm, rest.dm_inv));
    if (jacobians == nullptr) continue;
    const Vector12 g = VolumeGradient(rest, xe);
    for (int k = 0; k < 4; ++k) {
      double* j = jacobians[star.elements[e][k]];
      if (j == nullptr) continue;
      for (int d = 0; d < 3; ++d) j[d] += 0.25 * factor * g[3 * k + d];
    }
  }
  return factor * change;
}

double NodalVolume::Pressures(const Vertices& x, std::vector<double>* pressure,
                              std::vector<Vector12>* volume_gradient) const {
  const int nt = static_cast<int>(tets_.rows());
  std::vector<double> volume_change(nt);  // v_e - V_e
  if (volume_gradient != nullptr) volume_gradient->resize(nt);
#pragma omp parallel for schedule(static) num_threads(threads_)
  for (int e = 0; e < nt; ++e) {
    const ElementRest& rest = *rests_[e];
    const Vector12 xe = ElementPositions(tets_, e, x);
    Eigen::Matrix<double, 3, 4> xm;
    for (int k = 0; k < 4; ++k) xm.col(k) = xe.segment<3>(3 * k);
    volume_change[e] = rest.volume * DeterminantMinusOne(DeformationGradient(xm, rest.dm_inv));
    if (volume_gradient != nullptr) (*volume_gradient)[e] = VolumeGradient(rest, xe);
  }
  std::vector<double> vertex_pressure(num_vertices_, 0.0), vertex_energy(num_vertices_, 0.0);
#pragma omp parallel for schedule(static) num_threads(threads_)
  for (int v = 0; v < num_vertices_; ++v) {
    const double V = rest_volume_[v];
    if (!(V > 0)) continue;
    double change = 0.0;
    for (int s = element_offsets_[v]; s < element_offsets_[v + 1]; ++s)
      change += 0.25 * volume_change[element_slots_[s] / 4];
    const double K = stiffness_[v] / V, strain = change / V;  // J_a - 1
    vertex_pressure[v] = K * strain;
    vertex_energy[v] = 0.5 * K * V * strain * strain;
  }
  pressure->resize(nt);
  for (int e = 0; e < nt; ++e) {
    double p = 0.0;
    for (int k = 0; k < 4; ++k) p += 0.25 * vertex_pressure[tets_(e, k)];
    (*pressure)[e] = p;
  }
  return Problem::SumBlockValues(vertex_energy);  // the same sum on any thread count
}

double NodalVolume::Evaluate(const Vertices& x, Eigen::VectorXd* gradient) const {
  std::vector<double> pressure;
  std::vector<Vector12> volume_gradient;
  const double energy = Pressures(x, &pressure, gradient != nullptr ? &volume_gradient : nullptr);
  if (gradient == nullptr) return energy;
  // Per vertex, its elements' shares in element order: no race, the same sums on any thread count.
#pragma omp parallel for schedule(static) num_threads(threads_)
  for (int v = 0; v < num_vertices_; ++v) {
    Eigen::Vector3d g = Eigen::Vector3d::Zero();
    for (int s = element_offsets_[v]; s < element_offsets_[v + 1]; ++s) {
      const int e = element_slots_[s] / 4, k = element_slots_[s] % 4;
      g += pressure[e] * volume_gradient[e].segment<3>(3 * k);
    }
    gradient->segment<3>(3 * v) += g;
  }
  return energy;
}

void NodalVolume::AddHessian(const Vertices& x, Curvature curvature, Assembler* assembler) const {
  std::vector<double> pressure;
  std::vector<Vector12> volume_gradient;
  Pressures(x, &pressure, &volume_gradient);
  // Per element: p_e d2v_e/dx2 = V_e B^T (p_e H_J) B, the pressure times the Hessian of the
  // element's volume (the neo-Hookean tangent with mu = kappa = 0 is exactly that). Not in
  // Gauss-Newton's matrix.
  const int nt = static_cast<int>(tets_.rows());
  const TangentProjection projection = curvature == Curvature::kExact
                                           ? TangentProjection::kNone
                                           : TangentProjection::kPositiveSemiDefinite;
  for (int e = 0; curvature != Curvature::kGaussNewton && e < nt; ++e) {
    ElementRest rest = *rests_[e];
    rest.mu = 0.0;
    const Vector12 xe = ElementPositions(tets_, e, x);
    if (projection == TangentProjection::kNone) {  // -V p [F (b_a x b_b)]x, block by block
      const Eigen::Matrix3d F =
          DeformationGradient(Eigen::Map<const Eigen::Matrix<double, 3, 4>>(xe.data()), rest.dm_inv);
      Eigen::Matrix3d blocks[16];
      NeoHookeanTangentBlocks(rest, 0.0, pressure[e], F, blocks);
      for (int i = 0; i < 4; ++i) {
        for (int j = i; j < 4; ++j) assembler->AddBlock(tets_(e, i), tets_(e, j), blocks[4 * i + j]);
      }
      continue;
    }
    const Matrix12 K = NeoHookeanTangent(rest, 0.0, pressure[e], xe, projection);
    for (int i = 0; i < 4; ++i) {
      for (int j = i; j < 4; ++j) assembler->AddBlock(tets_(e, i), tets_(e, j), K.block<3, 3>(3 * i, 3 * j));
    }
  }
  // Per vertex: K_a / V_a (dv_a/dx)(dv_a/dx)^T over its star.
  std::vector<std::pair<int, Eigen::Vector3d>> w;  // star vertex, d v_a / d x_vertex
  for (int v = 0; v < num_vertices_; ++v) {
    const double V = rest_volume_[v];
    if (!(V > 0)) continue;
    w.clear();
    for (int s = element_offsets_[v]; s < element_offsets_[v + 1]; ++s) {
      const int e = element_slots_[s] / 4;
      for (int k = 0; k < 4; ++k) {
        const int u = tets_(e, k);
        auto it = std::find_if(w.begin(), w.end(), [u](const auto& p) { return p.first == u; });
        if (it == w.end()) {
          w.emplace_back(u, Eigen::Vector3d::Zero());
          it = w.end() - 1;
        }
        it->second += 0.25 * volume_gradient[e].segment<3>(3 * k);
      }
    }
    const double scale = stiffness_[v] / (V * V);  // K_a / V_a
    for (size_t i = 0; i < w.size(); ++i) {
      for (size_t j = i; j < w.size(); ++j) {
        assembler->AddBlock(w[i].first, w[j].first, scale * w[i].second * w[j].second.transpose());
      }
    }
  }
}

}  // namespace energy
}  // namespace femreg
