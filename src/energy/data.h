// The data terms: a point on the model — a surface vertex (N = 1) or a point on a surface
// triangle (N = 3, barycentric weights b), or a point of an embedded surface (N = 4: the
// coordinates of its rest position in one tetrahedron of the mesh, extrapolated a little
// outside it) — tied to a cloud point q, point to point
// (r = p - q, 3 residuals) or point to plane (r = n . (p - q), 1 residual, n unit). The
// temporal and anchor springs are point-to-point blocks on one vertex with their own weight.
#ifndef FEMREG_ENERGY_DATA_H_
#define FEMREG_ENERGY_DATA_H_

#include <Eigen/Core>
#include <array>

namespace femreg {
namespace energy {

template <int N>
struct PointToPoint {
  static constexpr int kResiduals = 3;
  static constexpr int kVertices = N;
  static constexpr bool kConstantJacobian = true;
  std::array<int, N> vertices{};
  double weight = 1.0;                                 // N/m
  std::array<double, N> barycentric{};                 // sum 1; {1} for a vertex
  Eigen::Vector3d target = Eigen::Vector3d::Zero();    // q

  bool Evaluate(const double* const* x, double* r, double** J) const {
    Eigen::Map<Eigen::Vector3d> res(r);
    res = -target;
    for (int i = 0; i < N; ++i) res += barycentric[i] * Eigen::Map<const Eigen::Vector3d>(x[i]);
    if (J == nullptr) return true;
    for (int i = 0; i < N; ++i) {
      if (J[i] != nullptr) {
        Eigen::Map<Eigen::Matrix<double, 3, 3, Eigen::RowMajor>> Ji(J[i]);
        Ji = barycentric[i] * Eigen::Matrix3d::Identity();
      }
    }
    return true;
  }
};

template <int N>
struct PointToPlane {
  static constexpr int kResiduals = 1;
  static constexpr int kVertices = N;
  static constexpr bool kConstantJacobian = true;
  std::array<int, N> vertices{};
  double weight = 1.0;
  std::array<double, N> barycentric{};
  Eigen::Vector3d target = Eigen::Vector3d::Zero();
  Eigen::Vector3d normal = Eigen::Vector3d::UnitZ();   // n, unit

  bool Evaluate(const double* const* x, double* r, double** J) const {
    Eigen::Vector3d p = -target;
    for (int i = 0; i < N; ++i) p += barycentric[i] * Eigen::Map<const Eigen::Vector3d>(x[i]);
    r[0] = normal.dot(p);
    if (J == nullptr) return true;
    for (int i = 0; i < N; ++i) {
      if (J[i] == nullptr) continue;
      Eigen::Map<Eigen::Vector3d> Ji(J[i]);
      Ji = barycentric[i] * normal;
    }
    return true;
  }
};

// A vertex pulled towards a target with stiffness w (N/m): the temporal term (w = w_t m_i,
// target = the previous frame) and soft anchors.
using VertexSpring = PointToPoint<1>;
inline VertexSpring MakeVertexSpring(int vertex, const Eigen::Vector3d& target, double weight) {
  VertexSpring s;
  s.vertices = {{vertex}};
  s.barycentric = {{1.0}};
  s.target = target;
  s.weight = weight;
  return s;
}

}  // namespace energy
}  // namespace femreg

#endif  // FEMREG_ENERGY_DATA_H_
