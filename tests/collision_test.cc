// Collision: the contact cost functions' Jacobians and the forward solve resolving a
// penetration (the exact closest points and the AABB hierarchy it builds on are tested in
// geometry_test.cc). Surfaces, scenes and the tracker with contacts are tested in
// collision_tracker_test.cc, the registered contact sequences and the CLI in
// collision_sequences_test.cc.
#include <ceres/ceres.h>
#include <ceres/gradient_checker.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <random>
#include <set>
#include <sstream>
#include <string>

#include "femreg/collision.h"
#include "femreg/datasets.h"
#include "femreg/forward.h"
#include "femreg/ground_truth.h"
#include "femreg/io.h"
#include "femreg/point_cloud.h"
#include "femreg/scene.h"
#include "femreg/tracker.h"
#include "femreg_test_config.h"
#include "regenerate_compare.h"
#include "test_util.h"

namespace femreg {
namespace {

using V3 = Eigen::Vector3d;

// These small problems run faster on one thread (testing_util::UseOneOpenMpThread).
const bool kOneThread = testing_util::UseOneOpenMpThread();

// --- detection and the forward solve ---------------------------------------------------

// Two boxes: `lower` at the origin, `upper` above it with a gap.
std::vector<TetMesh> TwoBoxes(double gap) {
  TetMesh lower = MakeBox(V3(0.04, 0.04, 0.02), 4, 4, 2);
  TetMesh upper = MakeBox(V3(0.03, 0.03, 0.02), 3, 3, 2);
  upper.rest.rowwise() += V3(0.005, 0.005, 0.02 + gap).transpose();
  upper.x = upper.rest;
  return {lower, upper};
}

struct Merged {
  TetMesh mesh;
  std::vector<int> offsets;
  std::vector<Triangles> surfaces;
};

Merged Merge(const std::vector<TetMesh>& meshes) {
  Merged m;
  m.mesh = MergeMeshes(meshes, &m.offsets);
  for (size_t i = 0; i < meshes.size(); ++i) m.surfaces.push_back(meshes[i].surface.array() + m.offsets[i]);
  return m;
}

TEST(CollisionWorld, DetectsPairContactsWithSignedGaps) {
  Merged m = Merge(TwoBoxes(0.001));
  CollisionSpec spec;
  spec.pairs = {{"lower", "upper"}};
  spec.distance = 0.002;
  CollisionWorld world;
  ASSERT_TRUE(world.Init(spec, {"lower", "upper"}, m.surfaces, m.mesh.x).ok());
  EXPECT_EQ(world.num_trees_built(), 2);
  std::vector<Contact> contacts;
  world.Detect(m.mesh.x, 0.0, &contacts);
  ASSERT_GT(contacts.size(), 0u);
  for (const Contact& c : contacts) {
    EXPECT_NEAR(std::abs(c.normal.z()), 1.0, 1e-9);
    EXPECT_NEAR(world.Gap(c, m.mesh.x), 0.001, 1e-9);  // detected within D = 2 mm
    EXPECT_NEAR(world.Penetration(c, m.mesh.x), -0.001, 1e-9);
  }
  EXPECT_EQ(world.Evaluate(contacts, m.mesh.x).contacts, 0);  // near, not touching
  EXPECT_NEAR(world.Evaluate(contacts, m.mesh.x).min_gap, 0.001, 1e-9);
  EXPECT_EQ(world.Evaluate(contacts, m.mesh.x).max_penetration, 0.0);
  // Push the upper box 1.5 mm into the lower one: gaps become negative.
  Vertices x = m.mesh.x;
  for (int v = m.offsets[1]; v < x.rows(); ++v) x(v, 2) -= 0.0025;
  world.Detect(x, 0.0, &contacts);
  const ContactStats s = world.Evaluate(contacts, x);
  EXPECT_GT(s.contacts, 0);
  EXPECT_NEAR(s.max_penetration, 0.0015, 1e-6);
  EXPECT_NEAR(s.min_gap, -0.0015, 1e-6);
}

// A tool whose bottom face is 2 large triangles (split along a diagonal) 1.4 mm above a finely
// meshed slab: one contact per slab vertex under it, all with the vertical normal. (Per
// triangle pair, a slab vertex came up to 8 times, and pairs whose closest point fell on the
// tool's diagonal edge pushed sideways: the forward solve then swung the slab 20 mm aside.)
TEST(CollisionWorld, ToolOverSlabGivesOneVerticalContactPerVertex) {
  TetMesh slab = MakeBox(V3(0.12, 0.04, 0.01), 24, 8, 4, V3(0, 0, 0.006));
  CollisionSpec spec;
  spec.distance = 0.0015;
  ObstacleSpec tool;
  tool.name = "tool";
  tool.kind = ObstacleSpec::Kind::kBox;
  tool.box_size = V3(0.02, 0.05, 0.02);
  tool.keyframes.resize(1);
  tool.keyframes[0].translation = V3(0.105, 0.02, 0.016 + 0.0014 + 0.01);
  spec.obstacles.push_back(tool);
  CollisionWorld world;
  ASSERT_TRUE(world.Init(spec, {"slab"}, {slab.surface}, slab.x).ok());
  std::vector<Contact> contacts;
  world.Detect(slab.x, 0.0, &contacts);
  // Slab top vertices with x in [0.095, 0.115] (5 columns) and y in [0, 0.04] (9 rows).
  ASSERT_EQ(contacts.size(), 45u);
  std::set<std::pair<int, int>> points;
  for (const Contact& c : contacts) {
    EXPECT_TRUE(c.obstacle());
    EXPECT_NEAR((c.normal - V3(0, 0, -1)).norm(), 0.0, 1e-9);
    EXPECT_NEAR(c.gap, 0.0014, 1e-9);
    int k = 0;
    c.bary_a.maxCoeff(&k);
    EXPECT_EQ(c.bary_a[k], 1.0);  // at a slab vertex
    EXPECT_TRUE(points.emplace(c.vertices_a[k], c.object_b).second) << "vertex twice";
  }
  // Tilted 30 degrees about x, the tool's corner edge comes first: still one contact per
  // vertex, each along the direction to its closest point on the tool.
  tool.keyframes[0].rotation = V3(0.5, 0, 0);
  tool.keyframes[0].translation.z() = 0.016 + 0.001 + 0.025 * std::sin(0.5) + 0.01 * std::cos(0.5);
  spec.obstacles[0] = tool;
  ASSERT_TRUE(world.Init(spec, {"slab"}, {slab.surface}, slab.x).ok());
  world.Detect(slab.x, 0.005, &contacts);
  ASSERT_GT(contacts.size(), 0u);
  points.clear();
  for (const Contact& c : contacts) {
    Eigen::Vector3d pa = Eigen::Vector3d::Zero();
    for (int j = 0; j < 3; ++j) pa += c.bary_a[j] * slab.x.row(c.vertices_a[j]).transpose();
    EXPECT_NEAR(c.gap, (pa - c.point_b).norm(), 1e-9);  // outside: the gap is the distance
    EXPECT_NEAR((c.normal - (pa - c.point_b).normalized()).norm(), 0.0, 1e-9);
    int k = 0;
    c.bary_a.maxCoeff(&k);
    if (c.bary_a[k] == 1.0) {
      EXPECT_TRUE(points.emplace(c.vertices_a[k], c.object_b).second);
    }
  }
}

// A vertex pushed deeper into the other object than D (no surface within D of it) is still
// found through the triangles that cut the other surface, and its contact points out.
TEST(CollisionWorld, VertexDeeperThanDIsFoundAndPushedOut) {
  Merged m = Merge(TwoBoxes(0.001));
  CollisionSpec spec;
  spec.pairs = {{"lower", "upper"}};
  spec.distance = 0.001;
  CollisionWorld world;
  ASSERT_TRUE(world.Init(spec, {"lower", "upper"}, m.surfaces, m.mesh.x).ok());
  Vertices x = m.mesh.x;
  for (int v = m.offsets[1]; v < x.rows(); ++v) x(v, 2) -= 0.005;  // 4 mm into the lower box
  std::vector<Contact> contacts;
  world.Detect(x, 0.0, &contacts);
  const ContactStats s = world.Evaluate(contacts, x);
  EXPECT_NEAR(s.max_penetration, 0.004, 1e-9);
  bool deep = false;
  for (const Contact& c : contacts) {
    if (world.Penetration(c, x) > 0.004 - 1e-9) {
      deep = true;
      // The upper box's bottom vertices: out through the lower box's top (up for the upper
      // box as side a, down for the lower box as side a).
      EXPECT_NEAR(std::abs(c.normal.z()), 1.0, 1e-9);
    }
  }
  EXPECT_TRUE(deep);
}

// A mesh obstacle given in memory (ObstacleSpec::surface) meets the slab as the same surface
// read from a file does: the same contacts and forces, with the scale and pose applied alike.
// A surface in memory with no triangle or an index past its vertices is refused by name.
TEST(CollisionWorld, MeshObstacleInMemoryActsAsTheSameSurfaceFromAFile) {
  TetMesh slab = MakeBox(V3(0.06, 0.04, 0.01), 12, 8, 2);
  TetMesh block = MakeBox(V3(20, 16, 10), 2, 2, 1, V3(-10, -8, 0));  // mm: scale 0.001
  testing_util::TempDir tmp;
  std::ostringstream obj;
  obj.precision(17);
  for (int v = 0; v < block.rest.rows(); ++v)
    obj << "v " << block.rest(v, 0) << " " << block.rest(v, 1) << " " << block.rest(v, 2) << "\n";
  for (int f = 0; f < block.surface.rows(); ++f)
    obj << "f " << block.surface(f, 0) + 1 << " " << block.surface(f, 1) + 1 << " " << block.surface(f, 2) + 1 << "\n";
  ObstacleSpec tool;
  tool.name = "tool";
  tool.kind = ObstacleSpec::Kind::kMesh;
  tool.scale = 0.001;
  tool.keyframes.resize(1);  // tilted, its lowest edge 0.6 mm into the slab's top
  tool.keyframes[0].rotation = V3(0.3, 0.2, 0);
  tool.keyframes[0].translation = V3(0.03, 0.02, 0.0137);
  CollisionSpec spec;
  spec.distance = 0.002;
  spec.stiffness = 1e3;
  ObstacleSpec from_file = tool, in_memory = tool;
  from_file.mesh_path = tmp.Write("block.obj", obj.str());
  in_memory.surface = ObstacleSpec::Surface{block.rest, block.surface};
  CollisionWorld worlds[2];
  ContactPotential potentials[2] = {ContactPotential(&worlds[0], 0.001), ContactPotential(&worlds[1], 0.001)};
  const ObstacleSpec* tools[2] = {&from_file, &in_memory};
  for (int w = 0; w < 2; ++w) {
    spec.obstacles = {*tools[w]};
    const Status status = worlds[w].Init(spec, {"slab"}, {slab.surface}, slab.x);
    ASSERT_TRUE(status.ok()) << status.message();
    potentials[w].Refresh(slab.x);
  }
  ASSERT_EQ(worlds[1].obstacle_vertices(0).rows(), worlds[0].obstacle_vertices(0).rows());
  EXPECT_NEAR((worlds[1].obstacle_vertices(0) - worlds[0].obstacle_vertices(0)).norm(), 0.0, 1e-15);
  const std::vector<Contact>& a = potentials[0].contacts();
  const std::vector<Contact>& b = potentials[1].contacts();
  ASSERT_GT(worlds[0].Evaluate(a, slab.x).max_penetration, 0.0);
  ASSERT_EQ(a.size(), b.size());
  for (size_t k = 0; k < a.size(); ++k) {
    EXPECT_EQ(a[k].source, b[k].source) << k;
    EXPECT_EQ(a[k].vertices_a, b[k].vertices_a) << k;
    EXPECT_NEAR(a[k].gap, b[k].gap, 1e-15) << k;
    EXPECT_NEAR((a[k].normal - b[k].normal).norm(), 0.0, 1e-12) << k;
  }
  const std::vector<ContactForce> fa = potentials[0].Forces(slab.x), fb = potentials[1].Forces(slab.x);
  ASSERT_EQ(fa.size(), 1u);
  ASSERT_EQ(fb.size(), 1u);
  EXPECT_GT(fa[0].force.norm(), 0.0);
  EXPECT_EQ(fa[0].contacts, fb[0].contacts);
  EXPECT_NEAR((fa[0].force - fb[0].force).norm(), 0.0, 1e-12 * fa[0].force.norm());

  CollisionWorld bad;
  spec.obstacles = {in_memory};
  spec.obstacles[0].surface->triangles(3, 1) = static_cast<int>(block.rest.rows());
  Status status = bad.Init(spec, {"slab"}, {slab.surface}, slab.x);
  ASSERT_FALSE(status.ok());
  EXPECT_NE(status.message().find("'tool'"), std::string::npos) << status.message();
  EXPECT_NE(status.message().find("index"), std::string::npos) << status.message();
  spec.obstacles[0].surface->triangles.resize(0, 3);
  status = bad.Init(spec, {"slab"}, {slab.surface}, slab.x);
  ASSERT_FALSE(status.ok());
  EXPECT_NE(status.message().find("no triangle"), std::string::npos) << status.message();
}

TEST(ContactPotential, GradientMatchesFiniteDifferences) {
  Merged m = Merge(TwoBoxes(-0.0005));  // 0.5 mm into each other: the penalty is zero at contact
  CollisionSpec spec;
  spec.pairs = {{"a", "b"}};
  spec.distance = 0.002;
  spec.stiffness = 1e3;
  CollisionWorld world;
  ASSERT_TRUE(world.Init(spec, {"a", "b"}, m.surfaces, m.mesh.x).ok());
  ContactPotential potential(&world, 0.002);
  Vertices x = m.mesh.x;
  std::mt19937 rng(5);
  std::normal_distribution<double> n(0, 1e-4);
  for (int v = 0; v < x.rows(); ++v) x.row(v) += V3(n(rng), n(rng), n(rng)).transpose();
  potential.Refresh(x);
  ASSERT_GT(potential.contacts().size(), 0u);
  Eigen::VectorXd g = Eigen::VectorXd::Zero(3 * x.rows());
  potential.Evaluate(x, &g);
  ASSERT_GT(g.norm(), 0.0);
  const double h = 1e-8;
  for (int d = 0; d < 3 * x.rows(); d += 7) {
    Vertices xp = x, xm = x;
    xp.data()[d] += h;
    xm.data()[d] -= h;
    const double num = (potential.Evaluate(xp, nullptr) - potential.Evaluate(xm, nullptr)) / (2 * h);
    EXPECT_NEAR(g(d), num, 1e-5 * (1 + std::abs(num)));
  }
}

TEST(ForwardContact, PressingOneBoxOntoAnotherResolvesThePenetration) {
  const double D = 0.002;
  Merged m = Merge(TwoBoxes(0.003));
  Material soft;
  soft.youngs_modulus = 2e4;
  soft.poisson_ratio = 0.3;
  ElasticModel model;
  model.Build(m.mesh, ElasticModelType::kCorotational, soft);
  ForwardProblem problem;
  // Lower box clamped at its bottom; upper box's top pushed down 8 mm (through the 3 mm
  // gap and 5 mm further).
  for (int v = 0; v < m.offsets[1]; ++v)
    if (m.mesh.rest(v, 2) < 1e-9) problem.clamped.push_back(v);
  const double top = m.mesh.rest.col(2).maxCoeff();
  for (int v = m.offsets[1]; v < m.mesh.num_vertices(); ++v)
    if (m.mesh.rest(v, 2) > top - 1e-9) problem.prescribed.emplace_back(v, V3(0, 0, -0.008));
  ForwardOptions options;
  options.load_steps = 8;
  options.max_iterations = 60;
  options.verbose = getenv("FV") != nullptr;

  // Without contacts the boxes pass through each other.
  TetMesh free_mesh = m.mesh;
  ForwardSummary summary;
  ASSERT_TRUE(SolveQuasiStatic(problem, options, &model, &free_mesh, &summary).ok());
  CollisionSpec spec;
  spec.pairs = {{"lower", "upper"}};
  spec.distance = D;
  spec.stiffness = 2e3;
  CollisionWorld world;
  ASSERT_TRUE(world.Init(spec, {"lower", "upper"}, m.surfaces, m.mesh.x).ok());
  std::vector<Contact> contacts;
  world.Detect(free_mesh.x, 0.0, &contacts);
  EXPECT_GT(world.Evaluate(contacts, free_mesh.x).max_penetration, 0.0);

  // With the penalty (zero at contact: D only detects) the surfaces touch, crossed by at most
  // the penalty's force / k, and the lower box is compressed.
  ContactPotential potential(&world, D);
  problem.potential = &potential;
  model.Build(m.mesh, ElasticModelType::kCorotational, soft);
  TetMesh mesh = m.mesh;
  ASSERT_TRUE(SolveQuasiStatic(problem, options, &model, &mesh, &summary).ok()) << summary.message;
  EXPECT_TRUE(summary.IsSolutionUsable()) << summary.FullReport();
  world.Detect(mesh.x, 0.0, &contacts);
  const ContactStats s = world.Evaluate(contacts, mesh.x);
  EXPECT_GT(s.contacts, 0);
  EXPECT_LT(s.max_penetration, 0.5e-3);
  const double lower_top = mesh.x.topRows(m.offsets[1]).col(2).maxCoeff();
  EXPECT_LT(lower_top, 0.02 - 1e-4);  // pressed down
}

TEST(ForwardContact, PlaneObstacleHoldsABentCantilever) {
  TetMesh beam = MakeBox(V3(0.1, 0.02, 0.01), 10, 2, 1);
  beam.rest.rowwise() += V3(0, 0, 0.005).transpose();
  beam.x = beam.rest;
  Material soft;
  soft.youngs_modulus = 5e4;
  ElasticModel model;
  model.Build(beam, ElasticModelType::kCorotational, soft);
  ForwardProblem problem;
  for (int v = 0; v < beam.num_vertices(); ++v) {
    if (beam.rest(v, 0) < 1e-9) problem.clamped.push_back(v);
    if (beam.rest(v, 0) > 0.1 - 1e-9) problem.prescribed.emplace_back(v, V3(0, 0, -0.015));
  }
  CollisionSpec spec;
  spec.distance = 0.001;
  spec.stiffness = 5e3;
  ObstacleSpec table;
  table.name = "table";
  spec.obstacles.push_back(table);
  CollisionWorld world;
  ASSERT_TRUE(world.Init(spec, {"beam"}, {beam.surface}, beam.x).ok());
  EXPECT_EQ(world.num_trees_built(), 0);  // a plane needs no hierarchy
  ContactPotential potential(&world, 0.001);
  problem.potential = &potential;
  ForwardOptions options;
  options.load_steps = 6;
  ForwardSummary summary;
  ASSERT_TRUE(SolveQuasiStatic(problem, options, &model, &beam, &summary).ok());
  // The free end is pushed 15 mm down, the table is 5 mm below: only the clamped / pushed
  // vertices may go below the plane; every other vertex stays within 1 mm of it.
  std::vector<char> held(beam.num_vertices(), 0);
  for (const auto& p : problem.prescribed) held[p.first] = 1;
  for (int v = 0; v < beam.num_vertices(); ++v)
    if (!held[v]) {
      EXPECT_GT(beam.x(v, 2), -0.001) << v;
    }
}
}  // namespace
}  // namespace femreg
