// The nodal volume as part of a registration problem (energy/problem.h's SetNodalVolume): the
// assembler's gradient and Hessians and ForceResidual against central differences of
// Problem::Evaluate, rest and rigid motion, Gauss-Newton's matrix positive semi-definite; the
// Ceres back end's per-vertex residuals against the term's energy and gradient; the tracker
// takes it with either back end, to the same result.
#include <gtest/gtest.h>

#include <Eigen/Eigenvalues>
#include <Eigen/Geometry>
#include <memory>
#include <random>
#include <vector>

#include "energy/assembler.h"
#include "energy/equilibrium.h"
#include "energy/nodal_volume.h"
#include "energy/problem.h"
#include "femreg/fem.h"
#include "femreg/io.h"
#include "femreg/tracker.h"
#include "solvers/ceres/ceres_backend.h"

namespace femreg {
namespace {

struct NodalProblem {
  TetMesh mesh;
  ElasticModel model;
  energy::Problem problem;
};

// A 3 x 2 x 2 box of neo-Hookean elements at nu 0.49, deviatoric, with the nodal volume
// weighted by 2 (an elastic weight), as registration builds it.
std::unique_ptr<NodalProblem> MakeNodalProblem() {
  auto p = std::make_unique<NodalProblem>();
  p->mesh = MakeBox(Eigen::Vector3d(0.06, 0.04, 0.04), 3, 2, 2);
  ObjectMaterial material;
  material.material.youngs_modulus = 1e4;
  material.material.poisson_ratio = 0.49;
  material.model = MaterialModel::kNeoHookean;
  material.nodal_volume = true;
  p->model.Build(p->mesh, ElasticModelType::kCorotational, material);
  const int nv = p->mesh.num_vertices(), nt = p->model.num_elements();
  p->problem.Reset(nv);
  std::vector<std::array<int, 4>> cells(nt);
  std::vector<const ElementRest*> rests(nt);
  auto* blocks =
      p->problem.AddSet<energy::NeoHookeanElement>(energy::TermGroup::kElastic).mutable_blocks();
  for (int e = 0; e < nt; ++e) {
    energy::NeoHookeanElement b;
    for (int k = 0; k < 4; ++k) b.vertices[k] = cells[e][k] = p->model.tets()(e, k);
    b.weight = 2.0;
    b.rest = rests[e] = &p->model.rest(e);
    b.deviatoric = true;
    blocks->push_back(b);
  }
  p->problem.SetCoupling(cells);
  auto nodal = std::make_shared<energy::NodalVolume>();
  nodal->Build(p->model.tets(), rests, nv, 1, 2.0);
  p->problem.SetNodalVolume(nodal);
  return p;
}

Vertices Perturbed(const Vertices& rest, double spread, int seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(-spread, spread);
  Vertices x = rest;
  for (int v = 0; v < x.rows(); ++v) x.row(v) += Eigen::RowVector3d(u(rng), u(rng), u(rng));
  return x;
}

double Energy(const energy::Problem& problem, const Vertices& x) {
  return problem.Evaluate(x).total();
}

TEST(NodalVolumeRegistration, GradientHessianAndForcesMatchCentralDifferences) {
  auto p = MakeNodalProblem();
  const Vertices x = Perturbed(p->mesh.rest, 0.004, 3);
  energy::Assembler assembler;
  assembler.Prepare(p->problem, x);
  Eigen::VectorXd g;
  const double e =
      assembler.AssembleSecondOrder(p->problem, x, energy::Curvature::kExact, true, &g);
  const Eigen::MatrixXd H(assembler.H());
  EXPECT_NEAR(e, Energy(p->problem, x), 1e-12 * std::abs(e));
  // Without the nodal volume the energy is smaller: the term is in.
  energy::Problem without = p->problem;
  without.SetNodalVolume(nullptr);
  EXPECT_LT(Energy(without, x), 0.9 * e);

  const int n = 3 * static_cast<int>(x.rows());
  const double h = 1e-7;
  Eigen::VectorXd numeric_g(n);
  Eigen::MatrixXd numeric_H(n, n);
  for (int j = 0; j < n; ++j) {
    Vertices plus = x, minus = x;
    plus(j / 3, j % 3) += h;
    minus(j / 3, j % 3) -= h;
    numeric_g(j) = (Energy(p->problem, plus) - Energy(p->problem, minus)) / (2 * h);
    Eigen::VectorXd gp, gm;
    energy::Assembler a;
    a.Prepare(p->problem, plus);
    a.AssembleSecondOrder(p->problem, plus, energy::Curvature::kExact, false, &gp);
    a.AssembleSecondOrder(p->problem, minus, energy::Curvature::kExact, false, &gm);
    numeric_H.col(j) = (gp - gm) / (2 * h);
  }
  EXPECT_LT((g - numeric_g).cwiseAbs().maxCoeff(), 1e-6 * g.cwiseAbs().maxCoeff());
  EXPECT_LT((H - numeric_H).cwiseAbs().maxCoeff(), 1e-5 * H.cwiseAbs().maxCoeff());

  Eigen::VectorXd f;
  energy::ForceResidual(p->problem, x, &f);
  EXPECT_LT((f - g).cwiseAbs().maxCoeff(), 1e-9 * g.cwiseAbs().maxCoeff());

  // Gauss-Newton's matrix (the nodal part without the pressure term) is positive semi-definite.
  Eigen::VectorXd gn_g;
  EnergyTerms terms;
  assembler.AssembleGaussNewton(p->problem, x, true, &gn_g, &terms);
  EXPECT_NEAR(terms.total(), e, 1e-9 * e);
  EXPECT_LT((gn_g - g).cwiseAbs().maxCoeff(), 1e-9 * g.cwiseAbs().maxCoeff());
  const Eigen::MatrixXd GN(assembler.H());
  const double smallest = Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd>(GN).eigenvalues()(0);
  EXPECT_GT(smallest, -1e-9 * GN.diagonal().maxCoeff());
}

TEST(NodalVolumeRegistration, NoForceAtRestOrUnderRigidMotion) {
  auto p = MakeNodalProblem();
  const Eigen::Matrix3d R =
      Eigen::AngleAxisd(0.7, Eigen::Vector3d(1, 2, -1).normalized()).toRotationMatrix();
  const Vertices moved =
      (p->mesh.rest * R.transpose()).rowwise() + Eigen::RowVector3d(0.1, -0.2, 0.05);
  Eigen::VectorXd f;
  for (const Vertices& x : {p->mesh.rest, moved}) {
    energy::ForceResidual(p->problem, x, &f);
    EXPECT_LT(f.cwiseAbs().maxCoeff(), 1e-9);
    EXPECT_LT(std::abs(Energy(p->problem, x)), 1e-12);
  }
  // A uniform compression costs volume: the nodal term pushes back.
  energy::ForceResidual(p->problem, 0.97 * p->mesh.rest, &f);
  EXPECT_GT(f.cwiseAbs().maxCoeff(), 1e-3);
}

// The Ceres form: one residual r_a per vertex over its star, with 1/2 sum r_a^2 = N(x) and
// sum_a J_a^T r_a = dN/dx, at a deformed x (the term's own gradient is checked against
// central differences above).
TEST(NodalVolumeRegistration, CeresResidualsSumToTheEnergyAndItsGradient) {
  auto p = MakeNodalProblem();
  const energy::NodalVolume& nodal = *p->problem.nodal_volume();
  Vertices x = Perturbed(p->mesh.rest, 4e-3, 11);
  x.col(0) *= 1.05;  // a stretch: J_a - 1 away from 0
  Eigen::VectorXd gradient = Eigen::VectorXd::Zero(x.size());
  const double energy = nodal.Evaluate(x, &gradient);
  ASSERT_GT(energy, 0.0);
  double half_sum = 0.0;
  Eigen::VectorXd jtr = Eigen::VectorXd::Zero(x.size());
  int residuals = 0;
  for (int a = 0; a < nodal.num_vertices(); ++a) {
    const ceres_backend::NodalVolumeCost cost(nodal.StarOf(a));
    const std::vector<int>& star = cost.vertices();
    ASSERT_FALSE(star.empty());
    std::vector<const double*> parameters;
    std::vector<std::vector<double>> jacobian(star.size(), std::vector<double>(3));
    std::vector<double*> jacobians;
    for (size_t i = 0; i < star.size(); ++i) {
      parameters.push_back(x.data() + 3 * star[i]);
      jacobians.push_back(jacobian[i].data());
    }
    double r = 0.0;
    ASSERT_TRUE(cost.Evaluate(parameters.data(), &r, jacobians.data()));
    half_sum += 0.5 * r * r;
    for (size_t i = 0; i < star.size(); ++i) {
      for (int d = 0; d < 3; ++d) jtr[3 * star[i] + d] += jacobian[i][static_cast<size_t>(d)] * r;
    }
    ++residuals;
  }
  EXPECT_EQ(residuals, p->mesh.num_vertices());
  EXPECT_NEAR(half_sum, energy, 1e-10 * energy);
  EXPECT_LE((jtr - gradient).lpNorm<Eigen::Infinity>(), 1e-9 * gradient.lpNorm<Eigen::Infinity>());
}

TEST(NodalVolumeRegistration, TrackerTakesItWithEitherBackEnd) {
  const TetMesh mesh = MakeBox(Eigen::Vector3d(0.1, 0.04, 0.04), 4, 2, 2);
  ObjectMaterial material;
  material.material.poisson_ratio = 0.49;
  material.model = MaterialModel::kNeoHookean;
  material.nodal_volume = true;
  // A cloud of the box's surface, stretched 3 % along x and moved 2 mm: the tracker follows it.
  PointCloud cloud;
  cloud.points.resize(static_cast<Eigen::Index>(mesh.surface_vertices.size()), 3);
  for (size_t i = 0; i < mesh.surface_vertices.size(); ++i) {
    Eigen::RowVector3d p = mesh.rest.row(mesh.surface_vertices[i]);
    p.x() *= 1.03;
    cloud.points.row(static_cast<Eigen::Index>(i)) = p + Eigen::RowVector3d(0.002, 0, 0);
  }
  Vertices result[2];
  int k = 0;
  for (SolverBackend backend : {SolverBackend::kFast, SolverBackend::kCeres}) {
    RegistrationOptions options;
    options.solver.backend = backend;
    std::unique_ptr<Tracker> tracker;
    const Status created = Tracker::Create({mesh}, {material}, options, &tracker);
    ASSERT_TRUE(created.ok()) << created.message();
    FrameSummary summary;
    const Status tracked = tracker->Track(cloud, &summary);
    ASSERT_TRUE(tracked.ok()) << tracked.message();
    result[k] = tracker->vertices(0);
    const Eigen::Vector3d shift = (result[k] - mesh.rest).colwise().mean().transpose();
    const double expected = 0.002 + 0.03 * mesh.rest.col(0).mean();
    EXPECT_NEAR(shift.x(), expected, 3e-4) << ToString(backend);
    ++k;
  }
  // The same energy, minimized by two solvers: the same shape to well below a millimetre.
  const double apart = (result[0] - result[1]).rowwise().norm().maxCoeff();
  std::printf("fast and Ceres, nodal volume: at most %.3g mm apart\n", 1e3 * apart);
  EXPECT_LT(apart, 1e-4);
}

}  // namespace
}  // namespace femreg
