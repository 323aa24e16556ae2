// What the back end tests share (backend_test.cc, multigrid_test.cc, supernodal_test.cc):
// a box with every energy term (MakeSetup), a minimization by one back end that checks its
// reported energies (Minimize), and beams' stiffness systems (BeamsSystem).
#ifndef FEMREG_TESTS_BACKEND_SETUP_H_
#define FEMREG_TESTS_BACKEND_SETUP_H_

#include <gtest/gtest.h>

#include <csignal>

#include <Eigen/CholmodSupport>
#include <Eigen/Geometry>
#include <algorithm>
#include <memory>
#include <numeric>
#include <map>
#include <random>

#include "energy/problem.h"
#include "femreg/ground_truth.h"
#include "femreg/io.h"
#include "femreg/point_cloud.h"
#include "femreg/scene.h"
#include "femreg/tracker.h"
#include "femreg_test_config.h"
#include "parallel/threads.h"
#include "solvers/backend.h"
#include "solvers/fast/fast_backend.h"
#include "solvers/fast/multigrid.h"
#include "solvers/fast/supernodal_solve.h"

namespace femreg {
namespace backend_testing {

using energy::TermGroup;

struct Setup {
  TetMesh mesh;
  ElasticModel model;
  energy::Problem problem;
};

// neo_hookean: the elastic blocks are the neo-Hookean element's (no rotations held).
// shuffled: the box's vertices numbered in random order, as a mesh generator's often are.
inline std::unique_ptr<Setup> MakeSetup(RobustLoss loss, bool springs, bool fixed, bool contacts, uint64_t seed,
                                        bool loads = false, int refine = 1, bool neo_hookean = false,
                                        bool shuffled = false) {
  auto s = std::make_unique<Setup>();
  s->mesh = MakeBox(Eigen::Vector3d(0.1, 0.04, 0.04), 5 * refine, 2 * refine, 2 * refine);
  if (shuffled) {
    std::vector<int> number(static_cast<size_t>(s->mesh.num_vertices()));
    std::iota(number.begin(), number.end(), 0);
    std::shuffle(number.begin(), number.end(), std::mt19937(static_cast<uint32_t>(seed)));
    TetMesh renumbered;
    renumbered.rest.resize(s->mesh.num_vertices(), 3);
    for (int v = 0; v < s->mesh.num_vertices(); ++v) renumbered.rest.row(number[static_cast<size_t>(v)]) = s->mesh.rest.row(v);
    renumbered.tets = s->mesh.tets;
    for (int e = 0; e < renumbered.tets.rows(); ++e) {
      for (int k = 0; k < 4; ++k) renumbered.tets(e, k) = number[static_cast<size_t>(s->mesh.tets(e, k))];
    }
    renumbered.region = s->mesh.region;
    EXPECT_TRUE(FinalizeMesh(&renumbered).ok());
    s->mesh = renumbered;
  }
  ComputeLumpedMasses(&s->mesh, 500);
  Material material;
  material.youngs_modulus = 2e4;
  material.poisson_ratio = 0.4;
  s->model.Build(s->mesh, ElasticModelType::kCorotational, material);
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> n(0.0, 1.0);
  const int nv = s->mesh.num_vertices();
  energy::Problem& p = s->problem;
  p.Reset(nv);
  std::vector<std::array<int, 4>> cells;
  for (int e = 0; e < s->mesh.num_tets(); ++e) {
    cells.push_back({{s->mesh.tets(e, 0), s->mesh.tets(e, 1), s->mesh.tets(e, 2), s->mesh.tets(e, 3)}});
  }
  p.SetCoupling(cells);
  // A bent state to take rotations from.
  Vertices bent = s->mesh.rest;
  for (int v = 0; v < nv; ++v) bent(v, 2) += 0.02 * std::pow(bent(v, 0) / 0.1, 2);
  s->model.UpdateRotations(bent);
  auto& elastic = p.AddSet<energy::ElasticElement>(TermGroup::kElastic);
  auto& neo = p.AddSet<energy::NeoHookeanElement>(TermGroup::kElastic);
  auto& edges = p.AddSet<energy::EdgeSpring>(TermGroup::kElastic);
  for (int e = 0; e < s->model.num_elements(); ++e) {
    energy::ElasticElement b;
    for (int k = 0; k < 4; ++k) b.vertices[k] = s->model.tets()(e, k);
    b.rest = &s->model.rest(e);
    b.rotation = &s->model.rotation(e);
    b.weight = 1.5;
    if (neo_hookean) {
      energy::NeoHookeanElement nh;
      nh.vertices = b.vertices;
      nh.rest = b.rest;
      nh.weight = b.weight;
      neo.Add(nh);
    } else {
      elastic.Add(b);
    }
    if (springs) {
      energy::EdgeSpring edge;
      edge.vertices = {{b.vertices[0], b.vertices[1]}};
      edge.length = (s->mesh.rest.row(edge.vertices[0]) - s->mesh.rest.row(edge.vertices[1])).norm();
      edge.weight = 50.0;
      edges.Add(edge);
    }
  }
  // Data: surface vertices and points on surface triangles, pulled towards the bent shape
  // plus noise, some point-to-plane, some far off (for the robust losses).
  const energy::Loss data_loss{loss, 0.005};
  auto& p1 = p.AddSet<energy::PointToPoint<1>>(TermGroup::kData, data_loss);
  auto& l1 = p.AddSet<energy::PointToPlane<1>>(TermGroup::kData, data_loss);
  auto& p3 = p.AddSet<energy::PointToPoint<3>>(TermGroup::kData, data_loss);
  auto& l3 = p.AddSet<energy::PointToPlane<3>>(TermGroup::kData, data_loss);
  int i = 0;
  for (int v : s->mesh.surface_vertices) {
    Eigen::Vector3d target = bent.row(v).transpose() + 0.001 * Eigen::Vector3d(n(rng), n(rng), n(rng));
    if (++i % 7 == 0) target += Eigen::Vector3d(0.0, 0.0, 0.02);
    if (i % 2) {
      energy::PointToPlane<1> b;
      b.vertices = {{v}};
      b.barycentric = {{1.0}};
      b.target = target;
      b.normal = Eigen::Vector3d(n(rng), n(rng), n(rng)).normalized();
      b.weight = 200.0;
      l1.Add(b);
    } else {
      p1.Add(energy::MakeVertexSpring(v, target, 200.0));
    }
  }
  for (int f = 0; f < s->mesh.num_surface_triangles(); f += 3) {
    Eigen::Vector3d q = Eigen::Vector3d::Zero();
    const std::array<double, 3> bary = {{0.2, 0.3, 0.5}};
    std::array<int, 3> tri;
    for (int k = 0; k < 3; ++k) {
      tri[k] = s->mesh.surface(f, k);
      q += bary[k] * bent.row(tri[k]).transpose();
    }
    q += 0.001 * Eigen::Vector3d(n(rng), n(rng), n(rng));
    if (f % 2) {
      energy::PointToPlane<3> b;
      b.vertices = tri;
      b.barycentric = bary;
      b.target = q;
      b.normal = Eigen::Vector3d(n(rng), n(rng), n(rng)).normalized();
      b.weight = 200.0;
      l3.Add(b);
    } else {
      energy::PointToPoint<3> b;
      b.vertices = tri;
      b.barycentric = bary;
      b.target = q;
      b.weight = 200.0;
      p3.Add(b);
    }
  }
  auto& temporal = p.AddSet<energy::VertexSpring>(TermGroup::kTemporal);
  for (int v = 0; v < nv; ++v) temporal.Add(energy::MakeVertexSpring(v, s->mesh.rest.row(v).transpose(), 3.0 * s->mesh.mass(v)));
  p.AddSet<energy::VertexSpring>(TermGroup::kAnchor)
      .Add(energy::MakeVertexSpring(0, s->mesh.rest.row(0).transpose() + Eigen::Vector3d(0, 0, 0.001), 1e3));
  if (contacts) {
    // A ceiling at z = 0.05 over the bent beam's tip (the data pull it to 0.06) pushes it down;
    // and two vertices not in a common tetrahedron held apart (a contact that widens the fast
    // pattern).
    auto& ceiling = p.AddSet<energy::ContactPenalty<3>>(TermGroup::kCollision);
    for (int f = 0; f < s->mesh.num_surface_triangles(); ++f) {
      energy::ContactPenalty<3> c;
      Eigen::Vector3d centre = Eigen::Vector3d::Zero();
      for (int k = 0; k < 3; ++k) {
        c.vertices[k] = s->mesh.surface(f, k);
        c.coefficients[k] = 1.0 / 3.0;
        centre += bent.row(c.vertices[k]).transpose() / 3.0;
      }
      if (centre.x() < 0.07) continue;
      c.normal = Eigen::Vector3d(0, 0, -1);  // the obstacle is above: push down
      c.offset = 0.002 + c.normal.dot(Eigen::Vector3d(0, 0, 0.05));
      c.weight = 1e4;
      ceiling.Add(c);
    }
    energy::ContactPenalty<6> pair;
    const int a = 0, b = nv - 1;
    for (int k = 0; k < 3; ++k) {
      pair.vertices[k] = a + k;
      pair.coefficients[k] = k == 0 ? 1.0 : 0.0;
      pair.vertices[3 + k] = b - k;
      pair.coefficients[3 + k] = k == 0 ? -1.0 : 0.0;
    }
    pair.normal = (s->mesh.rest.row(a) - s->mesh.rest.row(b)).normalized().transpose();
    pair.offset = 0.12;  // wants them 12 cm apart (they are ~11.5)
    pair.weight = 1e3;
    p.AddSet<energy::ContactPenalty<6>>(TermGroup::kCollision).Add(pair);
  }
  if (loads) {  // gravity, about the rest positions, 20x its weight to show against the data
    auto& set = p.AddSet<energy::ExternalLoad>(TermGroup::kLoad);
    for (int v = 0; v < nv; ++v) {
      energy::ExternalLoad b;
      if (energy::MakeExternalLoad(v, s->mesh.mass(v) * Eigen::Vector3d(0, 0, -200), s->mesh.rest.row(v).transpose(),
                                   0.02, &b)) {
        set.Add(b);
      }
    }
  }
  if (fixed) {
    p.fixed().assign(nv, 0);
    for (int v = 0; v < nv; ++v) {
      if (s->mesh.rest(v, 0) < 1e-9) p.fixed()[v] = 1;
    }
  }
  return s;
}

// Each group of `reported` within 1e-12 of `scale` of `evaluated`'s.
inline void ExpectSameEnergies(const EnergyTerms& reported, const EnergyTerms& evaluated, double scale) {
  const double tolerance = 1e-12 * std::abs(scale);
  EXPECT_NEAR(reported.data, evaluated.data, tolerance);
  EXPECT_NEAR(reported.elastic, evaluated.elastic, tolerance);
  EXPECT_NEAR(reported.temporal, evaluated.temporal, tolerance);
  EXPECT_NEAR(reported.anchor, evaluated.anchor, tolerance);
  EXPECT_NEAR(reported.collision, evaluated.collision, tolerance);
  EXPECT_NEAR(reported.load, evaluated.load, tolerance);
}

inline Vertices Minimize(SolverBackend type, const energy::Problem& problem, const Vertices& start,
                         Preconditioner preconditioner = Preconditioner::kAuto, SolveReport* out = nullptr) {
  BackendOptions options;
  options.type = type;
  options.preconditioner = preconditioner;
  options.max_iterations = 200;
  options.relative_tolerance = 1e-15;
  std::unique_ptr<Backend> backend = MakeBackend(options);
  Vertices x = start;
  const SolveReport report = backend->Solve(problem, 0.0, &x);
  EXPECT_TRUE(report.success) << report.message;
  // The energies the report carries (the tracker's per-iteration rows) are the problem's, group
  // by group (the fast back end's starting energy comes from its assembly's linearization,
  // added in Evaluate's order; to round-off, which other compilers and CPUs may change).
  const EnergyTerms at_start = problem.Evaluate(start), at_end = problem.Evaluate(x);
  const double before = at_start.total();
  ExpectSameEnergies(report.before, at_start, before);
  ExpectSameEnergies(report.after, at_end, before);
  EXPECT_LE(report.after.total(), report.before.total());
  if (out != nullptr) *out = report;
  return x;
}


// Beams' corotational stiffness (R = I) side by side, one per (cells along, Young's modulus):
// a forest of independent trees; plus a diagonal of `diagonal` x (1 .. 5).
inline Eigen::SparseMatrix<double> BeamsSystem(const std::vector<std::pair<int, double>>& beams, double diagonal) {
  std::vector<Eigen::Triplet<double>> t;
  int offset = 0;
  for (const auto& [cells, modulus] : beams) {
    const TetMesh mesh = MakeBox(Eigen::Vector3d(0.3, 0.05, 0.05), cells, 3, 3);
    Material material;
    material.youngs_modulus = modulus;
    material.poisson_ratio = 0.45;
    ElasticModel model;
    model.Build(mesh, ElasticModelType::kCorotational, material);
    std::vector<Eigen::Triplet<double>> own;
    model.AddStiffnessTriplets(&own);
    for (const auto& e : own) t.emplace_back(e.row() + offset, e.col() + offset, e.value());
    offset += 3 * mesh.num_vertices();
  }
  for (int i = 0; i < offset; ++i) t.emplace_back(i, i, diagonal * (1 + i % 5));
  Eigen::SparseMatrix<double> H(offset, offset);
  H.setFromTriplets(t.begin(), t.end());
  H.makeCompressed();
  return H;
}

}  // namespace backend_testing
}  // namespace femreg

#endif  // FEMREG_TESTS_BACKEND_SETUP_H_
