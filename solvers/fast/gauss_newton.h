// The fast back end: the same energy terms as the Ceres back end, minimized by
// Gauss-Newton / Levenberg-Marquardt with iteratively reweighted robust losses over a
// directly assembled sparse system. The sparsity pattern is that of the tetrahedral meshes
// (every data and spring term couples vertices of one tet face or edge), so it is analysed
// once per topology and CHOLMOD's symbolic factorization is reused across iterations and
// frames. With the rotations and correspondences fixed the energy is quadratic but for the
// robust losses, so one outer iteration takes one factorization and a few solves.
#ifndef FEMREG_SOLVERS_FAST_GAUSS_NEWTON_H_
#define FEMREG_SOLVERS_FAST_GAUSS_NEWTON_H_

#include <Eigen/Core>
#include <Eigen/SparseCore>
#include <array>
#include <memory>
#include <string>
#include <unordered_map>
#include <utility>
#include <vector>

#include "femreg/fem.h"
#include "femreg/mesh.h"
#include "femreg/registration.h"

namespace femreg {
namespace fast_backend {

// 0.5 w |S (R^T x_e - X_e)|^2 over the element's four vertices.
struct ElasticTerm {
  std::array<int, 4> vertices;
  const ElementRest* rest = nullptr;
  const Eigen::Matrix3d* rotation = nullptr;
  double weight = 1.0;
};
// 0.5 k (|x_a - x_b| - L)^2 (mass-spring), linearized about the current direction.
struct EdgeSpringTerm {
  int a = 0, b = 0;
  double length = 0.0, stiffness = 0.0;
};
// A point on the model (1 vertex or 3 with barycentrics) against a target, point-to-point
// or point-to-plane (normal non-zero), with weight w and the robust loss of the problem.
struct PointTerm {
  int num_vertices = 1;
  std::array<int, 3> vertices = {0, 0, 0};
  Eigen::Vector3d barycentric = Eigen::Vector3d(1, 0, 0);
  Eigen::Vector3d target = Eigen::Vector3d::Zero();
  Eigen::Vector3d normal = Eigen::Vector3d::Zero();
};
// 0.5 w |x_v - target|^2 (temporal and soft anchor terms).
struct SpringTerm {
  int vertex = 0;
  Eigen::Vector3d target = Eigen::Vector3d::Zero();
  double weight = 0.0;
};

// The contact penalty (femreg/collision.h): 0.5 k max(0, delta)^2 with delta linear in x
// while the normal is held: delta = offset - sum_i w_i n . x_i (w_i: the barycentrics of
// side a, minus those of side b; offset: D, plus n . p_b for an obstacle point).
struct ContactTerm {
  int num_vertices = 3;  // 3 (against an obstacle) or 6 (between objects)
  std::array<int, 6> vertices = {0, 0, 0, 0, 0, 0};
  std::array<double, 6> weights = {0, 0, 0, 0, 0, 0};
  Eigen::Vector3d normal = Eigen::Vector3d::UnitZ();
  double offset = 0.0;
  double Penetration(const Vertices& x) const {
    double d = offset;
    for (int i = 0; i < num_vertices; ++i) d -= weights[i] * normal.dot(x.row(vertices[i]).transpose());
    return d;
  }
};

struct Problem {
  std::vector<ElasticTerm> elastic;
  std::vector<EdgeSpringTerm> edges;
  std::vector<PointTerm> data;
  double data_weight = 1.0;
  RobustLoss loss = RobustLoss::kNone;
  double loss_scale = 1.0;
  std::vector<SpringTerm> temporal, anchors;
  std::vector<char> fixed;  // per vertex: held where it is (hard anchors); may be empty
  std::vector<ContactTerm> contacts;
  double contact_stiffness = 0.0;  // k (N/m)
};

// Per term energies, robust losses applied: the same numbers the Ceres back end reports.
EnergyTerms Evaluate(const Problem& problem, const Vertices& x);

struct SolveSummary {
  int iterations = 0;        // accepted and rejected steps
  int factorizations = 0;
  int pattern_rebuilds = 0;  // contacts widened the pattern (a new symbolic analysis)
  bool success = true;
  std::string message;
};

class Solver {
 public:
  Solver();
  ~Solver();
  // The pattern: every pair of vertices sharing a tetrahedron (global numbering). Call once
  // per topology; the symbolic factorization is computed at the first Solve after it.
  // Contacts between objects couple vertices that share no tetrahedron: Solve then widens
  // the pattern by those pairs (kept until the next SetPattern, so a contact that comes back
  // costs no new analysis).
  void SetPattern(int num_vertices, const std::vector<std::array<int, 4>>& tets);
  // Minimizes the problem from x (updated in place) with at most max_iterations
  // factorizations; stops when a step changes the energy by less than
  // relative_tolerance (Ceres' default function tolerance is 1e-6).
  SolveSummary Solve(const Problem& problem, int max_iterations, Vertices* x,
                     double relative_tolerance = 1e-6);

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace fast_backend
}  // namespace femreg

#endif  // FEMREG_SOLVERS_FAST_GAUSS_NEWTON_H_
