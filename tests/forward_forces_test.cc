// The forces on the body at a forward result (EvaluateForwardForces): a stretched bar,
// reactions balancing loads, gravity and the potential, the resultant's point
// (forward_test.cc has the solves).
#include <dlfcn.h>
#include <gtest/gtest.h>
#include <sys/wait.h>

#include <Eigen/Eigenvalues>
#include <Eigen/Geometry>
#include <Eigen/SparseCholesky>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <random>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

#include "femreg/fem.h"
#include "femreg/forward.h"
#include "femreg/io.h"
#include "femreg/mesh.h"
#include "femreg_test_config.h"
#include "forward_setup.h"

namespace femreg {
namespace {

using namespace forward_testing;  // NOLINT(build/namespaces)

// ---------------------------------------------------------------------------------------
// The forces on the body at a result (EvaluateForwardForces).

// A bar of nu = 0 stretched by u along its axis (clamped at x = 0, its x = L face moved) is
// uniformly strained, which linear tetrahedra represent exactly: the face is pulled with
// E A u / L, the clamp holds with the opposite, and no free vertex needs a support.
TEST(ForwardForces, StretchedBarIsPulledWithEAOverL) {
  const double L = 0.2, h = 0.02, u = 1e-3, E = 1e6;
  for (ElasticModelType type : {ElasticModelType::kLinear, ElasticModelType::kCorotational}) {
    SCOPED_TRACE(type == ElasticModelType::kLinear ? "linear" : "corotational");
    TetMesh mesh = MakeTestBox(Eigen::Vector3d(L, h, h), 10, 2, 2);
    ForwardProblem problem;
    std::vector<char> end(mesh.num_vertices(), 0), clamp(mesh.num_vertices(), 0);
    for (int v = 0; v < mesh.num_vertices(); ++v) {
      if (mesh.rest(v, 0) < 1e-9) {
        problem.clamped.push_back(v);
        clamp[v] = 1;
      } else if (mesh.rest(v, 0) > L - 1e-9) {
        problem.prescribed.push_back({v, Eigen::Vector3d(u, 0, 0)});
        end[v] = 1;
      }
    }
    Material material;
    material.youngs_modulus = E;
    material.poisson_ratio = 0.0;
    ElasticModel model;
    model.Build(mesh, type, material);
    ForwardSummary summary;
    ASSERT_TRUE(SolveQuasiStatic(problem, ForwardOptions(), &model, &mesh, &summary).ok());
    ASSERT_EQ(summary.termination, ForwardTermination::kConverged) << summary.FullReport();
    ForwardForces forces;
    const Status status =
        EvaluateForwardForces(problem, ForwardOptions(), model, mesh, mesh.x, &forces);
    ASSERT_TRUE(status.ok()) << status.message();
    ASSERT_EQ(forces.reactions.rows(), mesh.num_vertices());
    const double pull = E * h * h * u / L;  // N
    Eigen::Vector3d at_end = Eigen::Vector3d::Zero(), at_clamp = Eigen::Vector3d::Zero();
    for (int v = 0; v < mesh.num_vertices(); ++v) {
      const Eigen::Vector3d r = forces.reactions.row(v).transpose();
      if (end[v]) at_end += r;
      if (clamp[v]) at_clamp += r;
      if (!end[v] && !clamp[v]) {
        EXPECT_EQ(r.norm(), 0.0) << "free vertex " << v;
      }
    }
    EXPECT_LT((at_end - Eigen::Vector3d(pull, 0, 0)).norm(), 1e-9 * pull) << at_end.transpose();
    EXPECT_LT((at_clamp + Eigen::Vector3d(pull, 0, 0)).norm(), 1e-9 * pull) << at_clamp.transpose();
    EXPECT_EQ(forces.potential.cwiseAbs().maxCoeff(), 0.0);
    EXPECT_EQ(forces.loads.cwiseAbs().maxCoeff(), 0.0);
  }
}

// Springs from some vertices to fixed points, E = k/2 |x_v - p_v|^2: a potential whose force
// is known in closed form.
class SpringPotential : public ForwardPotential {
 public:
  SpringPotential(std::vector<std::pair<int, Eigen::Vector3d>> anchors, double k)
      : anchors_(std::move(anchors)), k_(k) {}
  void Refresh(const Vertices&) override {}
  double Evaluate(const Vertices& x, Eigen::VectorXd* gradient) const override {
    double energy = 0.0;
    for (const auto& a : anchors_) {
      const Eigen::Vector3d d = x.row(a.first).transpose() - a.second;
      energy += 0.5 * k_ * d.squaredNorm();
      if (gradient != nullptr) gradient->segment<3>(3 * a.first) += k_ * d;
    }
    return energy;
  }
  void AddHessian(const Vertices&, std::vector<Eigen::Triplet<double>>* triplets) const override {
    for (const auto& a : anchors_)
      for (int i = 0; i < 3; ++i) triplets->emplace_back(3 * a.first + i, 3 * a.first + i, k_);
  }
  const std::vector<std::pair<int, Eigen::Vector3d>>& anchors() const { return anchors_; }
  double k() const { return k_; }

 private:
  std::vector<std::pair<int, Eigen::Vector3d>> anchors_;
  double k_;
};

// A cantilever under a tip load, gravity and springs: at the converged result the clamp's
// reactions, the springs' forces and the loads sum to zero, and so do their moments (the
// corotational forces are those of a rotation-invariant energy, so they carry no moment).
TEST(ForwardForces, ReactionsBalanceLoadsGravityAndThePotential) {
  Cantilever c = MakeCantilever(2, Eigen::Vector3d(0, 0.3, -1.0));
  ComputeLumpedMasses(&c.mesh, 100.0);
  c.problem.gravity = Eigen::Vector3d(0, 0, -9.81);
  std::vector<std::pair<int, Eigen::Vector3d>> anchors;
  for (int v = 0; v < c.mesh.num_vertices(); ++v) {
    const Eigen::Vector3d X = c.mesh.rest.row(v).transpose();
    if (std::abs(X.x() - 0.5 * kLength) < 1e-9 && X.z() > kHeight - 1e-9) {
      anchors.push_back({v, X + Eigen::Vector3d(0, 0, -0.002)});  // pulled down
    }
  }
  ASSERT_FALSE(anchors.empty());
  SpringPotential springs(anchors, 200.0);
  c.problem.potential = &springs;
  ElasticModel model;
  model.Build(c.mesh, ElasticModelType::kCorotational, BeamMaterial(1e7));
  ForwardSummary summary;
  ASSERT_TRUE(SolveQuasiStatic(c.problem, ForwardOptions(), &model, &c.mesh, &summary).ok());
  ASSERT_EQ(summary.termination, ForwardTermination::kConverged) << summary.FullReport();

  ForwardForces forces;
  ASSERT_TRUE(
      EvaluateForwardForces(c.problem, ForwardOptions(), model, c.mesh, c.mesh.x, &forces).ok());
  const int nv = c.mesh.num_vertices();
  std::vector<char> clamped(nv, 0);
  for (int v : c.problem.clamped) clamped[v] = 1;
  Vertices loads = Vertices::Zero(nv, 3), pull = Vertices::Zero(nv, 3);
  for (int v = 0; v < nv; ++v) loads.row(v) = c.mesh.mass(v) * c.problem.gravity.transpose();
  for (const auto& l : c.problem.nodal_loads) loads.row(l.first) += l.second.transpose();
  for (const auto& a : anchors) {
    pull.row(a.first) = -springs.k() * (c.mesh.x.row(a.first) - a.second.transpose());
  }
  EXPECT_LT((forces.loads - loads).cwiseAbs().maxCoeff(), 1e-15);
  EXPECT_LT((forces.potential - pull).cwiseAbs().maxCoeff(), 1e-12);
  for (int v = 0; v < nv; ++v) {
    if (!clamped[v]) {
      EXPECT_EQ(forces.reactions.row(v).norm(), 0.0) << "free vertex " << v;
    }
  }

  const Vertices total = forces.reactions + forces.potential + forces.loads;
  const double scale = loads.colwise().sum().norm() + pull.colwise().sum().norm();
  Eigen::Vector3d moment = Eigen::Vector3d::Zero();
  for (int v = 0; v < nv; ++v) {
    moment += c.mesh.x.row(v).transpose().cross(total.row(v).transpose());
  }
  EXPECT_LT(total.colwise().sum().norm(), 1e-7 * scale);
  EXPECT_LT(moment.norm(), 1e-7 * scale * kLength);
  // The clamp holds the rest: its resultant and torque are minus those of the other forces.
  const ForceResultant support = ResultantAboutCentroid(forces.reactions, c.mesh.x, c.mesh.mass);
  const ForceResultant applied =
      ResultantAboutCentroid(forces.potential + forces.loads, c.mesh.x, c.mesh.mass);
  EXPECT_LT((support.force + applied.force).norm(), 1e-7 * scale);
  EXPECT_LT((support.torque + applied.torque).norm(), 1e-7 * scale * kLength);
  // The springs' share is far above the tolerances: a balance without it would fail.
  EXPECT_GT(pull.colwise().sum().norm(), 0.01 * scale);

  Vertices bad = c.mesh.x;
  bad(0, 0) = std::nan("");
  EXPECT_FALSE(
      EvaluateForwardForces(c.problem, ForwardOptions(), model, c.mesh, bad, &forces).ok());
}

// The torque is about the mass-weighted centroid of the positions.
TEST(ForwardForces, ResultantIsAboutTheMassWeightedCentroid) {
  Vertices x(2, 3), f(2, 3);
  x << 0, 0, 0, 4, 0, 0;
  f << 0, 1, 0, 0, 1, 0;
  Eigen::VectorXd mass(2);
  mass << 1, 3;  // centroid (3, 0, 0)
  const ForceResultant r = ResultantAboutCentroid(f, x, mass);
  EXPECT_LT((r.force - Eigen::Vector3d(0, 2, 0)).norm(), 1e-15);
  EXPECT_LT((r.torque - Eigen::Vector3d(0, 0, -2)).norm(), 1e-15);  // -3 e_x x e_y + e_x x e_y
}

// A soft, nearly incompressible cylinder sagging under its own weight (the forward bench's
// sag, coarser: 525 vertices, 1,920 tets): Newton on the full tangent converges in a few
// iterations with a quadratic tail; on the warped stiffness it takes many more.
}  // namespace
}  // namespace femreg
