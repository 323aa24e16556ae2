// The fast back end reaches the same minimum as Ceres on the same problem: every term
// (corotational elastic, edge springs, data point-to-point and point-to-plane through each
// robust loss, temporal and anchor springs, hard-fixed vertices).
#include <ceres/ceres.h>
#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <memory>
#include <random>

#include "femreg/io.h"
#include "solvers/ceres/cost_functions.h"
#include "solvers/fast/gauss_newton.h"

namespace femreg {
namespace {

struct Setup {
  TetMesh mesh;
  ElasticModel model;
  fast_backend::Problem problem;
  std::vector<std::array<int, 4>> tets;
};

std::unique_ptr<Setup> MakeSetup(RobustLoss loss, bool springs, bool fixed, uint64_t seed) {
  auto s = std::make_unique<Setup>();
  s->mesh = MakeBox(Eigen::Vector3d(0.1, 0.04, 0.04), 5, 2, 2);
  ComputeLumpedMasses(&s->mesh, 500);
  Material material;
  material.youngs_modulus = 2e4;
  material.poisson_ratio = 0.4;
  s->model.Build(s->mesh, ElasticModelType::kCorotational, material);
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> n(0.0, 1.0);
  // A bent state to take rotations from.
  Vertices bent = s->mesh.rest;
  for (int v = 0; v < bent.rows(); ++v) {
    const double t = bent(v, 0) / 0.1;
    bent(v, 2) += 0.02 * t * t;
  }
  s->model.UpdateRotations(bent);
  for (int e = 0; e < s->model.num_elements(); ++e) {
    fast_backend::ElasticTerm t;
    for (int k = 0; k < 4; ++k) t.vertices[k] = s->model.tets()(e, k);
    t.rest = &s->model.rest(e);
    t.rotation = &s->model.rotation(e);
    t.weight = 1.5;
    s->problem.elastic.push_back(t);
    s->tets.push_back(t.vertices);
    if (springs) {
      fast_backend::EdgeSpringTerm edge;
      edge.a = t.vertices[0];
      edge.b = t.vertices[1];
      edge.length = (s->mesh.rest.row(edge.a) - s->mesh.rest.row(edge.b)).norm();
      edge.stiffness = 50.0;
      s->problem.edges.push_back(edge);
    }
  }
  // Data: surface vertices and points on surface triangles, pulled towards the bent shape
  // plus noise, some point-to-plane, some far off (for the robust losses).
  int i = 0;
  for (int v : s->mesh.surface_vertices) {
    fast_backend::PointTerm p;
    p.vertices[0] = v;
    p.target = bent.row(v).transpose() + 0.001 * Eigen::Vector3d(n(rng), n(rng), n(rng));
    if (++i % 7 == 0) p.target += Eigen::Vector3d(0.0, 0.0, 0.02);
    if (i % 2) p.normal = Eigen::Vector3d(n(rng), n(rng), n(rng)).normalized();
    s->problem.data.push_back(p);
  }
  for (int f = 0; f < s->mesh.num_surface_triangles(); f += 3) {
    fast_backend::PointTerm p;
    p.num_vertices = 3;
    p.barycentric = Eigen::Vector3d(0.2, 0.3, 0.5);
    Eigen::Vector3d q = Eigen::Vector3d::Zero();
    for (int k = 0; k < 3; ++k) {
      p.vertices[k] = s->mesh.surface(f, k);
      q += p.barycentric[k] * bent.row(p.vertices[k]).transpose();
    }
    p.target = q + 0.001 * Eigen::Vector3d(n(rng), n(rng), n(rng));
    if (f % 2) p.normal = Eigen::Vector3d(n(rng), n(rng), n(rng)).normalized();
    s->problem.data.push_back(p);
  }
  s->problem.data_weight = 200.0;
  s->problem.loss = loss;
  s->problem.loss_scale = 0.005;
  for (int v = 0; v < s->mesh.num_vertices(); ++v) {
    s->problem.temporal.push_back({v, s->mesh.rest.row(v).transpose(), 3.0 * s->mesh.mass(v)});
  }
  s->problem.anchors.push_back({0, s->mesh.rest.row(0).transpose() + Eigen::Vector3d(0, 0, 0.001), 1e3});
  if (fixed) {
    s->problem.fixed.assign(s->mesh.num_vertices(), 0);
    for (int v = 0; v < s->mesh.num_vertices(); ++v) {
      if (s->mesh.rest(v, 0) < 1e-9) s->problem.fixed[v] = 1;
    }
  }
  return s;
}

Vertices SolveWithCeres(const fast_backend::Problem& p, const Vertices& start,
                        double* initial_cost = nullptr) {
  Vertices x = start;
  ceres::Problem problem;
  auto block = [&](int v) { return x.data() + 3 * v; };
  for (const auto& e : p.elastic) {
    problem.AddResidualBlock(new ceres_backend::ElasticCost(e.rest, e.rotation, e.weight), nullptr,
                             block(e.vertices[0]), block(e.vertices[1]), block(e.vertices[2]),
                             block(e.vertices[3]));
  }
  for (const auto& s : p.edges) {
    problem.AddResidualBlock(new ceres_backend::EdgeSpringCost(s.length, s.stiffness), nullptr,
                             block(s.a), block(s.b));
  }
  for (const auto& d : p.data) {
    ceres::LossFunction* loss = nullptr;
    if (p.loss == RobustLoss::kHuber) loss = new ceres::HuberLoss(p.loss_scale);
    if (p.loss == RobustLoss::kCauchy) loss = new ceres::CauchyLoss(p.loss_scale);
    if (p.loss == RobustLoss::kTukey) loss = new ceres::TukeyLoss(p.loss_scale);
    ceres::LossFunction* scaled = new ceres::ScaledLoss(loss, p.data_weight, ceres::TAKE_OWNERSHIP);
    const bool plane = d.normal.squaredNorm() > 0;
    if (d.num_vertices == 1) {
      ceres::CostFunction* c = plane ? static_cast<ceres::CostFunction*>(
                                           new ceres_backend::PointToPlaneCost1(d.target, d.normal, 1.0))
                                     : new ceres_backend::PointToPointCost1(d.target, 1.0);
      problem.AddResidualBlock(c, scaled, block(d.vertices[0]));
    } else {
      ceres::CostFunction* c = plane ? static_cast<ceres::CostFunction*>(new ceres_backend::PointToPlaneCost3(
                                           d.barycentric, d.target, d.normal, 1.0))
                                     : new ceres_backend::PointToPointCost3(d.barycentric, d.target, 1.0);
      problem.AddResidualBlock(c, scaled, block(d.vertices[0]), block(d.vertices[1]), block(d.vertices[2]));
    }
  }
  for (const auto* springs : {&p.temporal, &p.anchors}) {
    for (const auto& s : *springs) {
      problem.AddResidualBlock(new ceres_backend::SpringCost(s.target, s.weight), nullptr, block(s.vertex));
    }
  }
  for (size_t v = 0; v < p.fixed.size(); ++v) {
    if (p.fixed[v]) problem.SetParameterBlockConstant(block(static_cast<int>(v)));
  }
  if (initial_cost != nullptr) {
    problem.Evaluate(ceres::Problem::EvaluateOptions(), initial_cost, nullptr, nullptr, nullptr);
  }
  ceres::Solver::Options options;
  options.max_num_iterations = 200;
  options.function_tolerance = 1e-15;
  options.gradient_tolerance = 1e-15;
  options.parameter_tolerance = 1e-15;
  options.linear_solver_type = ceres::SPARSE_NORMAL_CHOLESKY;
  ceres::Solver::Summary summary;
  ceres::Solve(options, &problem, &summary);
  EXPECT_TRUE(summary.IsSolutionUsable()) << summary.BriefReport();
  return x;
}

class FastBackendTest : public ::testing::TestWithParam<std::tuple<RobustLoss, bool, bool>> {};

TEST_P(FastBackendTest, ReachesTheSameMinimumAsCeres) {
  const auto [loss, springs, fixed] = GetParam();
  auto s = MakeSetup(loss, springs, fixed, 3);
  const Vertices start = s->mesh.rest;
  const Vertices x_ceres = SolveWithCeres(s->problem, start);
  fast_backend::Solver solver;
  solver.SetPattern(s->mesh.num_vertices(), s->tets);
  Vertices x_fast = start;
  const fast_backend::SolveSummary summary = solver.Solve(s->problem, 100, &x_fast, 1e-15);
  EXPECT_TRUE(summary.success) << summary.message;
  const double e_ceres = fast_backend::Evaluate(s->problem, x_ceres).total();
  const double e_fast = fast_backend::Evaluate(s->problem, x_fast).total();
  const double e_start = fast_backend::Evaluate(s->problem, start).total();
  ASSERT_GT(e_start - e_ceres, 1e-6) << "the problem must not start at its minimum";
  EXPECT_NEAR(e_fast, e_ceres, 1e-7 * e_ceres + 1e-12);
  // Tukey is not convex: the two may stop in different (equally good) minima.
  if (loss != RobustLoss::kTukey) {
    EXPECT_LT((x_fast - x_ceres).cwiseAbs().maxCoeff(), 1e-6);
  }
  if (fixed) {
    for (int v = 0; v < start.rows(); ++v) {
      if (s->problem.fixed[v]) EXPECT_EQ((x_fast.row(v) - start.row(v)).norm(), 0.0);
    }
  }
}

INSTANTIATE_TEST_SUITE_P(
    AllTerms, FastBackendTest,
    ::testing::Values(std::make_tuple(RobustLoss::kNone, false, false),
                      std::make_tuple(RobustLoss::kHuber, false, false),
                      std::make_tuple(RobustLoss::kCauchy, false, true),
                      std::make_tuple(RobustLoss::kTukey, false, false),
                      std::make_tuple(RobustLoss::kHuber, true, true)));

TEST(FastBackend, EvaluateMatchesCeresCost) {
  for (RobustLoss loss : {RobustLoss::kNone, RobustLoss::kHuber, RobustLoss::kCauchy, RobustLoss::kTukey}) {
    auto s = MakeSetup(loss, true, false, 5);
    Vertices x = s->mesh.rest;
    x.col(2).array() += 0.03 * x.col(0).array();
    double ceres_cost = 0.0;
    SolveWithCeres(s->problem, x, &ceres_cost);
    const EnergyTerms t = fast_backend::Evaluate(s->problem, x);
    EXPECT_GT(t.elastic, 0.0);
    EXPECT_GT(t.data, 0.0);
    EXPECT_GT(t.temporal, 0.0);
    EXPECT_GT(t.anchor, 0.0);
    EXPECT_NEAR(t.total(), ceres_cost, 1e-10 * ceres_cost);
  }
}

}  // namespace
}  // namespace femreg
