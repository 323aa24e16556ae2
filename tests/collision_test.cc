// Collision: the contact cost functions' Jacobians, the forward solve resolving a
// penetration, scenes (one object: nothing built, nothing added), surface readers, and
// registered contact sequences touching without crossing. (The exact closest points
// and the AABB hierarchy it builds on are tested in geometry_test.cc.)
#include <ceres/ceres.h>
#include <ceres/gradient_checker.h>
#include <dlfcn.h>
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

// The forward solver's OpenMP loops spin-wait on a loaded machine; these small problems run
// faster on one thread (libgomp comes in through libfemreg, hence the look-up).
const bool kOneThread = [] {
  using SetThreads = void (*)(int);
  if (auto f = reinterpret_cast<SetThreads>(dlsym(RTLD_DEFAULT, "omp_set_num_threads"))) f(1);
  return true;
}();

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

// --- surfaces, scenes and the tracker -----------------------------------------------------

TEST(TriangleSurface, ReadsObjAndAsciiAndBinaryStl) {
  const std::string dir = testing::TempDir();
  {
    std::ofstream o(dir + "/quad.obj");
    o << "# quad\nv 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nf 1/1 2/2 3/3 4/4\n";
  }
  Vertices v;
  Triangles t;
  ASSERT_TRUE(ReadTriangleSurface(dir + "/quad.obj", &v, &t).ok());
  EXPECT_EQ(v.rows(), 4);
  EXPECT_EQ(t.rows(), 2);
  {
    std::ofstream o(dir + "/tri.stl");
    o << "solid t\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex 1 0 0\nvertex 0 1 0\n"
         "endloop\nendfacet\nfacet normal 0 0 1\nouter loop\nvertex 1 0 0\nvertex 1 1 0\n"
         "vertex 0 1 0\nendloop\nendfacet\nendsolid t\n";
  }
  ASSERT_TRUE(ReadTriangleSurface(dir + "/tri.stl", &v, &t).ok());
  EXPECT_EQ(v.rows(), 4);  // welded
  EXPECT_EQ(t.rows(), 2);
  {
    std::ofstream o(dir + "/bin.stl", std::ios::binary);
    char header[80] = {0};
    o.write(header, 80);
    uint32_t n = 1;
    o.write(reinterpret_cast<const char*>(&n), 4);
    float rec[12] = {0, 0, 1, 0, 0, 0, 2, 0, 0, 0, 2, 0};
    o.write(reinterpret_cast<const char*>(rec), 48);
    uint16_t attr = 0;
    o.write(reinterpret_cast<const char*>(&attr), 2);
  }
  ASSERT_TRUE(ReadTriangleSurface(dir + "/bin.stl", &v, &t).ok());
  EXPECT_EQ(t.rows(), 1);
  EXPECT_EQ(v(1, 0), 2.0);
  {
    std::ofstream o(dir + "/bad.obj");
    o << "v 0 0 0\nf 1 2 3\n";
  }
  const Status s = ReadTriangleSurface(dir + "/bad.obj", &v, &t);
  EXPECT_FALSE(s.ok());
  EXPECT_NE(s.message().find("bad.obj:2"), std::string::npos) << s.message();
}

TEST(ObstaclePose, InterpolatesKeyframes) {
  std::vector<ObstacleKeyframe> k(2);
  k[0].frame = 0;
  k[1].frame = 10;
  k[1].translation = V3(1, 0, 0);
  k[1].rotation = V3(0, 0, 1);
  const Eigen::Isometry3d T = ObstaclePose(k, 5);
  EXPECT_NEAR(T.translation().x(), 0.5, 1e-12);
  EXPECT_NEAR(Eigen::AngleAxisd(T.linear()).angle(), 0.5, 1e-12);
  EXPECT_NEAR(ObstaclePose(k, 20).translation().x(), 1.0, 1e-12);
}

const char* kTwoObjectScene = R"(
objects:
  - {name: lower, generate: {shape: box, size: [0.04, 0.04, 0.02], cells: [4, 4, 2]}, label: 1}
  - {name: upper, generate: {shape: box, size: [0.03, 0.03, 0.02], cells: [3, 3, 2], origin: [0.005, 0.005, 0.021]}, label: 2}
effects: {collision: true}
collision:
  pairs: [[lower, upper]]
  stiffness: 2000
  distance: 0.002
  obstacles:
    - {name: table, plane: {point: [0, 0, -0.001], normal: [0, 0, 1]}, objects: [lower]}
    - name: block
      box: {size: [0.01, 0.01, 0.01]}
      keyframes: [{frame: 0, translation: [0.2, 0, 0]}, {frame: 4, translation: [0.3, 0, 0]}]
registration:
  solver: {max_outer_iterations: 3}
)";

TEST(CollisionScene, ParsesAndRejectsWithLocations) {
  Scene scene;
  ASSERT_TRUE(ParseScene(kTwoObjectScene, "two.yaml", "", &scene).ok());
  EXPECT_TRUE(scene.effects.collision);
  ASSERT_EQ(scene.collision.pairs.size(), 1u);
  EXPECT_EQ(scene.collision.obstacles.size(), 2u);
  EXPECT_EQ(scene.collision.obstacles[1].keyframes.size(), 2u);
  EXPECT_EQ(scene.objects[1].label, 2);
  std::string bad = kTwoObjectScene;
  bad.replace(bad.find("[[lower, upper]]"), 16, "[[lower, uper]]");
  Status s = ParseScene(bad, "two.yaml", "", &scene);
  ASSERT_FALSE(s.ok());
  EXPECT_NE(s.message().find("two.yaml:7: collision.pairs[0][1]: unknown object 'uper'"), std::string::npos)
      << s.message();
  bad = kTwoObjectScene;
  bad.replace(bad.find("distance: 0.002"), 15, "distance: -1");
  s = ParseScene(bad, "two.yaml", "", &scene);
  ASSERT_FALSE(s.ok());
  EXPECT_NE(s.message().find("collision.distance: must be > 0"), std::string::npos) << s.message();
}

PointCloud SurfaceCloud(const Tracker& t) {
  PointCloud cloud;
  int n = 0;
  for (int i = 0; i < t.num_objects(); ++i) n += static_cast<int>(t.mesh(i).surface_vertices.size());
  cloud.points.resize(n, 3);
  cloud.labels.resize(n);
  int row = 0;
  for (int i = 0; i < t.num_objects(); ++i)
    for (int v : t.mesh(i).surface_vertices) {
      cloud.points.row(row) = t.vertices(i).row(v);
      cloud.labels(row++) = i + 1;
    }
  return cloud;
}

TEST(CollisionTracker, OneObjectSceneBuildsNothingAndAddsNoResidual) {
  Scene scene;
  ASSERT_TRUE(ParseScene(R"(
objects: [{name: only, generate: {shape: box, size: [0.04, 0.04, 0.02], cells: [4, 4, 2]}}]
effects: {collision: true}
)", "one.yaml", "", &scene).ok());
  std::unique_ptr<Tracker> tracker;
  ASSERT_TRUE(Tracker::Create(scene, &tracker).ok());
  EXPECT_EQ(tracker->collision(), nullptr);
  FrameSummary summary;
  ASSERT_TRUE(tracker->Track(SurfaceCloud(*tracker), &summary).ok());
  EXPECT_EQ(summary.final.collision, 0.0);
  EXPECT_EQ(summary.contacts, 0);
  EXPECT_EQ(summary.time.collision, 0.0);
  for (const OuterIteration& it : summary.iterations) EXPECT_EQ(it.contacts, 0);
}

TEST(CollisionTracker, TwoObjectsWithLabelsAreRegisteredJointlyWithContacts) {
  Scene scene;
  ASSERT_TRUE(ParseScene(kTwoObjectScene, "two.yaml", "", &scene).ok());
  std::unique_ptr<Tracker> tracker;
  ASSERT_TRUE(Tracker::Create(scene, &tracker).ok());
  ASSERT_NE(tracker->collision(), nullptr);
  EXPECT_EQ(tracker->collision()->num_trees_built(), 2);  // the box obstacle needs both
  // A cloud that pulls the upper box 2 mm into the lower one: the penalty keeps them apart.
  PointCloud cloud = SurfaceCloud(*tracker);
  const int n_lower = static_cast<int>(tracker->mesh(0).surface_vertices.size());
  for (int i = n_lower; i < cloud.size(); ++i) cloud.points(i, 2) -= 0.003;
  FrameSummary summary;
  ASSERT_TRUE(tracker->Track(cloud, &summary).ok());
  EXPECT_TRUE(summary.IsSolutionUsable()) << summary.FullReport();
  EXPECT_GT(summary.iterations.front().contacts, 0);
  EXPECT_GT(summary.final.collision, 0.0);
  EXPECT_LT(summary.max_penetration, 0.002) << summary.FullReport();
  EXPECT_NE(summary.FullReport().find("collision:"), std::string::npos);
}

// The fast back end takes the contact term too (pairs couple vertices of two objects, so it
// widens its sparsity pattern) and reaches the Ceres back end's minimum.
TEST(CollisionTracker, FastBackEndMatchesCeresWithContacts) {
  Vertices result[2];
  FrameSummary summary[2];
  for (int b = 0; b < 2; ++b) {
    std::string text = kTwoObjectScene;
    // One outer iteration: both back ends minimize the same energy (the same pairs and
    // contacts). Over several, the contacts and pairs are re-detected at each back end's
    // result, and where a vertex sits exactly on an edge of the other surface (as here,
    // box on box) the last bit decides between the triangles that tie.
    text.replace(text.find("solver: {max_outer_iterations: 3}"), 33,
                 b == 0 ? "solver: {max_outer_iterations: 1, max_inner_iterations: 50, backend: ceres}"
                        : "solver: {max_outer_iterations: 1, max_inner_iterations: 50, backend: fast}");
    Scene scene;
    ASSERT_TRUE(ParseScene(text, "two.yaml", "", &scene).ok());
    std::unique_ptr<Tracker> tracker;
    ASSERT_TRUE(Tracker::Create(scene, &tracker).ok());
    PointCloud cloud = SurfaceCloud(*tracker);
    const int n_lower = static_cast<int>(tracker->mesh(0).surface_vertices.size());
    for (int i = n_lower; i < cloud.size(); ++i) cloud.points(i, 2) -= 0.003;
    ASSERT_TRUE(tracker->Track(cloud, &summary[b]).ok());
    EXPECT_TRUE(summary[b].IsSolutionUsable()) << summary[b].FullReport();
    result[b].resize(tracker->mesh(0).num_vertices() + tracker->mesh(1).num_vertices(), 3);
    result[b] << tracker->vertices(0), tracker->vertices(1);
  }
  EXPECT_EQ(summary[0].backend, SolverBackend::kCeres);
  EXPECT_EQ(summary[1].backend, SolverBackend::kFast);
  EXPECT_GT(summary[1].final.collision, 0.0);
  EXPECT_GT(summary[1].contacts, 0);
  EXPECT_LT(summary[1].max_penetration, 0.002);
  EXPECT_NEAR(summary[1].final.collision, summary[0].final.collision,
              1e-3 * summary[0].final.collision);
  EXPECT_NEAR(summary[1].final.total(), summary[0].final.total(), 2e-4 * summary[0].final.total());
  EXPECT_LT((result[1] - result[0]).cwiseAbs().maxCoeff(), 2e-5);
}

// A block resting on a table plane (issue 42): collision.distance only detects, so the block
// ends touching the table (not held D above it), and the contact holds also against a dense
// cloud pulling it 5 mm into the table; the bare penalty (augmented off) lets that pull
// through by more than the tolerance.
const char* kRestingScene = R"(
objects:
  - {name: block, generate: {shape: box, size: [0.04, 0.04, 0.02], cells: [4, 4, 2]},
     material: {youngs_modulus: 20000, poisson_ratio: 0.4, density: 80}}
gravity: [0, 0, -9.81]
effects: {collision: true}
collision:
  obstacles:
    - {name: table, plane: {point: [0, 0, 0], normal: [0, 0, 1]}}
)";

// Points every 2 mm on the six faces of the box [0, 0.04] x [0, 0.04] x [0, 0.02].
PointCloud BoxFaceCloud() {
  std::vector<Eigen::Vector3d> points;
  const V3 size(0.04, 0.04, 0.02);
  for (int axis = 0; axis < 3; ++axis) {
    const int u = (axis + 1) % 3, w = (axis + 2) % 3;
    const int nu = static_cast<int>(std::lround(size[u] / 0.002)), nw = static_cast<int>(std::lround(size[w] / 0.002));
    for (int side = 0; side < 2; ++side)
      for (int i = 0; i <= nu; ++i)
        for (int j = 0; j <= nw; ++j) {
          V3 p;
          p[axis] = side * size[axis];
          p[u] = i * 0.002;
          p[w] = j * 0.002;
          points.push_back(p);
        }
  }
  PointCloud cloud;
  cloud.points.resize(static_cast<int>(points.size()), 3);
  for (size_t i = 0; i < points.size(); ++i) cloud.points.row(static_cast<int>(i)) = points[i].transpose();
  return cloud;
}

struct RestingRun {
  FrameSummary touching, pulled;
  double lowest_touching = 0.0, lowest_pulled = 0.0;  // the block's lowest z (m)
};

RestingRun RegisterResting(bool augmented) {
  RestingRun run;
  std::string text = kRestingScene;
  if (!augmented) text.replace(text.find("collision:\n"), 11, "collision:\n  augmented: false\n");
  Scene scene;
  EXPECT_TRUE(ParseScene(text, "resting.yaml", "", &scene).ok());
  std::unique_ptr<Tracker> tracker;
  EXPECT_TRUE(Tracker::Create(scene, &tracker).ok());
  if (!tracker) return run;
  const PointCloud rest = BoxFaceCloud();
  for (int f = 0; f < 2; ++f) {  // at rest on the table
    EXPECT_TRUE(tracker->Track(rest, &run.touching).ok());
  }
  run.lowest_touching = tracker->vertices(0).col(2).minCoeff();
  PointCloud pulled = rest;
  pulled.points.col(2).array() -= 0.005;
  for (int f = 0; f < 3; ++f) {
    EXPECT_TRUE(tracker->Track(pulled, &run.pulled).ok());
  }
  run.lowest_pulled = tracker->vertices(0).col(2).minCoeff();
  return run;
}

TEST(CollisionTracker, BlockOnATableRestsAtZeroGapAndDoesNotLeakUnderAStrongPull) {
  const RestingRun on = RegisterResting(true);
  EXPECT_TRUE(on.touching.IsSolutionUsable()) << on.touching.FullReport();
  EXPECT_LE(on.touching.min_gap, 0.3e-3) << on.touching.FullReport();
  EXPECT_LE(on.touching.max_penetration, 0.5e-3) << on.touching.FullReport();
  EXPECT_NEAR(on.lowest_touching, on.touching.min_gap, 1e-9);  // the gap is the geometry's
  EXPECT_GT(on.touching.contacts, 0);
  EXPECT_TRUE(on.pulled.IsSolutionUsable()) << on.pulled.FullReport();
  EXPECT_LE(on.pulled.max_penetration, 0.5e-3) << on.pulled.FullReport();
  EXPECT_GE(on.lowest_pulled, -0.5e-3);
  EXPECT_NEAR(-on.lowest_pulled, on.pulled.max_penetration, 1e-9);
  const RestingRun bare = RegisterResting(false);
  EXPECT_GT(bare.pulled.max_penetration, 0.5e-3) << bare.pulled.FullReport();
}

// Labels: points labelled with no object's label (a hand, clutter) pair with no object when
// every object has a label; an object without a label takes only the unlabelled points.
TEST(CollisionTracker, PointsWithUnknownLabelsAreIgnoredAndLabelsAreNotCrossed) {
  Scene scene;
  std::string text = kTwoObjectScene;
  text.replace(text.find("effects: {collision: true}"), 26, "effects: {collision: false}");
  ASSERT_TRUE(ParseScene(text, "two.yaml", "", &scene).ok());
  std::unique_ptr<Tracker> tracker;
  ASSERT_TRUE(Tracker::Create(scene, &tracker).ok());
  // The objects' own surfaces, plus a slab of clutter (label 7) 4 mm beside the lower box.
  PointCloud cloud = SurfaceCloud(*tracker);
  const int n = cloud.size(), clutter = 200;
  cloud.points.conservativeResize(n + clutter, 3);
  cloud.labels.conservativeResize(n + clutter);
  for (int i = 0; i < clutter; ++i) {
    cloud.points.row(n + i) << 0.044, 0.002 * (i % 20), 0.002 * (i / 20);
    cloud.labels(n + i) = 7;
  }
  FrameSummary summary;
  ASSERT_TRUE(tracker->Track(cloud, &summary).ok());
  for (int o = 0; o < 2; ++o) {
    EXPECT_LT((tracker->vertices(o) - tracker->mesh(o).rest).cwiseAbs().maxCoeff(), 1e-6) << o;
  }
  // The lower box without a label: it takes the clutter (the nearest unlabelled points) but
  // never the upper box's points.
  text.replace(text.find(", label: 1}"), 11, "}");
  ASSERT_TRUE(ParseScene(text, "two.yaml", "", &scene).ok());
  ASSERT_TRUE(Tracker::Create(scene, &tracker).ok());
  for (int i = 0; i < n; ++i) cloud.labels(i) = cloud.labels(i) == 1 ? 0 : cloud.labels(i);
  ASSERT_TRUE(tracker->Track(cloud, &summary).ok());
  EXPECT_GT(tracker->vertices(0).col(0).maxCoeff(), 0.0401);  // pulled towards the clutter
  EXPECT_LT((tracker->vertices(1) - tracker->mesh(1).rest).cwiseAbs().maxCoeff(), 1e-6);
}

// The bundled contact sequences registered end to end, with collision on and off: per frame
// the deepest penetration (measured with the scene's collision section also when the tracker
// has collision off) and the mean vertex error against the ground truth, seen and hidden.
struct SequenceRun {
  std::vector<double> penetration, seen, hidden;  // per frame (m)
  double D = 0.0;
  double Mean(const std::vector<double>& v) const {
    double sum = 0.0;
    for (double e : v) sum += e;
    return v.empty() ? 0.0 : sum / v.size();
  }
  double Max(const std::vector<double>& v) const {
    return v.empty() ? 0.0 : *std::max_element(v.begin(), v.end());
  }
};

SequenceRun RegisterSequence(const std::string& name, bool collision) {
  SequenceRun run;
  const std::string dir = std::string(FEMREG_DATASETS_DIR) + "/" + name;
  Scene scene;
  EXPECT_TRUE(LoadScene(dir + "/scene.yaml", &scene).ok());
  EXPECT_TRUE(scene.effects.collision);
  scene.effects.collision = collision;
  run.D = scene.collision.distance;
  std::unique_ptr<Tracker> tracker;
  EXPECT_TRUE(Tracker::Create(scene, &tracker).ok());
  if (!tracker) return run;
  EXPECT_EQ(tracker->collision() != nullptr, collision);
  // The meter: the same spec, outside the tracker.
  std::vector<std::string> names;
  std::vector<Triangles> surfaces;
  int total = 0;
  for (int i = 0; i < tracker->num_objects(); ++i) {
    names.push_back(scene.objects[i].name);
    surfaces.push_back(tracker->mesh(i).surface.array() + total);
    total += tracker->mesh(i).num_vertices();
  }
  CollisionWorld meter;
  Vertices x(total, 3);
  for (int f = 0;; ++f) {
    char file[64];
    std::snprintf(file, sizeof(file), "frame_%04d", f);
    const std::string cloud_path = dir + "/clouds/" + file + ".pcd";
    if (!std::filesystem::exists(cloud_path)) break;
    PointCloud cloud;
    EXPECT_TRUE(ReadPointCloud(cloud_path, &cloud).ok());
    FrameSummary summary;
    EXPECT_TRUE(tracker->Track(cloud, &summary).ok());
    EXPECT_TRUE(summary.IsSolutionUsable()) << name << " frame " << f << ": " << summary.message;
    int row = 0;
    for (int i = 0; i < tracker->num_objects(); ++i) {
      x.middleRows(row, tracker->vertices(i).rows()) = tracker->vertices(i);
      row += static_cast<int>(tracker->vertices(i).rows());
    }
    if (f == 0) {
      EXPECT_TRUE(meter.Init(scene.collision, names, surfaces, x).ok());
    }
    meter.SetFrame(f);
    std::vector<Contact> contacts;
    meter.Detect(x, 0.0, &contacts);
    run.penetration.push_back(meter.Evaluate(contacts, x).max_penetration);
    if (collision) {
      EXPECT_NEAR(summary.max_penetration, run.penetration.back(), 1e-12);
    }
    GroundTruthFrame truth;
    EXPECT_TRUE(ReadGroundTruthFrame(dir + "/ground_truth/" + file + ".csv", &truth).ok());
    const VertexErrors e = ComputeVertexErrors(x, truth);
    run.seen.push_back(e.seen.mean);
    run.hidden.push_back(e.hidden.mean);
  }
  EXPECT_EQ(run.penetration.size(), 12u) << name;
  return run;
}

// contact_pair: a block pressed 7 mm onto another, then sheared. With collision on the
// surfaces never cross and the hidden vertices (the contact faces) are tracked to a fraction
// of a millimetre; off, the top block sinks into the base by several millimetres.
// (The figures when the bounds were set: docs/notes/2026-11-28-figures-from-code-comments.md.)
TEST(CollisionSequences, ContactPairStaysApartAndTracksTheHiddenContactFaces) {
  const SequenceRun on = RegisterSequence("contact_pair", true);
  const SequenceRun off = RegisterSequence("contact_pair", false);
  EXPECT_LT(on.Max(on.penetration), 0.5e-3);
  EXPECT_GT(off.Max(off.penetration), 2e-3);
  EXPECT_LT(on.Mean(on.seen), 0.3e-3);
  EXPECT_LT(on.Mean(on.hidden), 0.3e-3);
  EXPECT_LT(2 * on.Mean(on.hidden), off.Mean(off.hidden));
}

// tool_table: a slab pushed onto a table by a tool. On, nothing crosses the tool or the
// table; off, the slab passes into the tool it cannot see under (the figures when the bounds
// were set: docs/notes/2026-11-28-figures-from-code-comments.md).
TEST(CollisionSequences, ToolTableStaysOutOfTheToolAndTheTable) {
  const SequenceRun on = RegisterSequence("tool_table", true);
  const SequenceRun off = RegisterSequence("tool_table", false);
  EXPECT_LT(on.Max(on.penetration), 0.5e-3);
  EXPECT_GT(off.Max(off.penetration), 2 * on.Max(on.penetration));
  EXPECT_LT(on.Mean(on.seen), 0.5e-3);
  EXPECT_LT(on.Mean(on.hidden), 0.5e-3);
  EXPECT_LT(on.Mean(on.hidden), off.Mean(off.hidden));
}

// truth_contacts.csv rows: frame,newton_iterations,termination,final_residual_N,contacts,
// max_penetration_mm.
void CompareTruthContacts(const std::string& bundled, const std::string& regenerated, double max_shift) {
  auto rows = [](const std::string& path) {
    std::vector<std::vector<std::string>> out;
    std::ifstream in(path);
    std::string line;
    while (std::getline(in, line)) {
      std::vector<std::string> cells;
      std::stringstream ls(line);
      for (std::string c; std::getline(ls, c, ',');) cells.push_back(c);
      out.push_back(cells);
    }
    return out;
  };
  const auto a = rows(bundled), b = rows(regenerated);
  ASSERT_EQ(a.size(), b.size());
  ASSERT_FALSE(a.empty());
  EXPECT_EQ(a[0], b[0]);  // header
  for (size_t r = 1; r < a.size(); ++r) {
    SCOPED_TRACE("row " + std::to_string(r));
    ASSERT_EQ(a[r].size(), 6u);
    ASSERT_EQ(b[r].size(), 6u);
    EXPECT_EQ(a[r][0], b[r][0]);  // frame
    EXPECT_EQ(a[r][2], b[r][2]);  // termination
    const double ca = std::atof(a[r][4].c_str()), cb = std::atof(b[r][4].c_str());
    EXPECT_LE(std::abs(ca - cb), 0.1 * std::max(ca, cb)) << "contacts";
    EXPECT_LE(std::abs(std::atof(a[r][5].c_str()) - std::atof(b[r][5].c_str())), max_shift * 1e3)
        << "max_penetration_mm";
  }
}

// forces.csv rows: frame and the contact forces' resultant and torque. The resultant balances
// the clamp's reaction, which follows the slab's deformation as a whole, not which pairs at
// the pressed face's edge are active: `max_force` bounds it by the slab's axial stiffness
// times the mean shift allowed, `max_torque` by that force times the slab's length.
void CompareBundledForces(const std::string& bundled, const std::string& regenerated,
                          double max_force, double max_torque) {
  std::vector<ForceFrame> a, b;
  bool columns_a = false, columns_b = false;
  ASSERT_TRUE(ReadForces(bundled, &a, &columns_a).ok());
  ASSERT_TRUE(ReadForces(regenerated, &b, &columns_b).ok());
  ASSERT_TRUE(columns_a && columns_b);
  ASSERT_EQ(a.size(), b.size());
  for (size_t r = 0; r < a.size(); ++r) {
    SCOPED_TRACE("frame " + std::to_string(a[r].frame));
    EXPECT_EQ(a[r].frame, b[r].frame);
    EXPECT_LE((a[r].force - b[r].force).norm(), max_force);
    EXPECT_LE((a[r].torque - b[r].torque).norm(), max_torque);
  }
}

// The bundled contact sequences are what `femreg contact-data` writes today (one thread, as
// tools/make_datasets.sh runs it), within tolerances that say what can vary from one CPU or
// BLAS build to another:
//
// - What is integer by construction is compared exactly: the files and their rows, the
//   vertex counts, and scene.yaml, README.md and tool.stl (written from constants).
// - Ground-truth positions: the solve converges to a force imbalance below 1e-8 N (see
//   truth_contacts.csv); with a stiffness of order E h = 3e4 Pa x 7.5 mm = 225 N/m for the
//   softest block that alone is 1e-8 / 225 = 4e-11 m. What varies far more is which contact
//   pairs are active: ContactPotential re-detects them when a vertex has moved more than half
//   the margin, a floating-point comparison, and its header measures that two detection
//   histories differ by up to 0.27 mm at the edge of the pressed face. Roundoff (OpenBLAS
//   picks its kernels by CPU; CHOLMOD factorizes through it) can change that history, so a
//   vertex may move by up to kMaxShift = 0.3 mm; only the vertices near that edge do, so the
//   mean over all vertices stays below a tenth of it (the figures measured against the
//   bundled files: docs/notes/2026-11-28-figures-from-code-comments.md).
// - Visibility: a vertex is seen when it lies within 2 mm of the depth image; one within
//   0.3 mm of that threshold may flip: at most 2 per frame.
// - Clouds: as regen::CloudsAgree says (the camera sees the moved surface; a pixel that
//   flips shifts the noise draws of the pixels after it).
// - truth_contacts.csv: the same frames, terminations and (within 10%) contact counts; the
//   deepest penetration within kMaxShift; the Newton iteration counts may differ.
// - forces.csv (tool_table): as CompareBundledForces says, with the slab's E A / L and a tenth of
//   kMaxShift, the bound on the mean shift.
TEST(CollisionSequences, BundledSequencesRegenerateWithinTolerance) {
  namespace fs = std::filesystem;
  const double kMaxShift = 3e-4;  // m
  for (const std::string name : {"tool_table", "contact_pair"}) {
    SCOPED_TRACE(name);
    testing_util::TempDir dir("femreg_contact_regen");
    ASSERT_TRUE(GenerateContactSequence(name, dir.path()).ok());
    const fs::path bundled = fs::path(FEMREG_DATASETS_DIR) / name;
    int files = 0;
    for (const auto& entry : fs::recursive_directory_iterator(dir.path())) {
      if (!entry.is_regular_file()) continue;
      const fs::path rel = fs::relative(entry.path(), dir.path());
      const std::string mine = entry.path().string(), theirs = (bundled / rel).string();
      SCOPED_TRACE(rel.string() + " (regenerate with tools/make_datasets.sh)");
      ASSERT_TRUE(fs::is_regular_file(theirs)) << "not bundled";
      ++files;
      const std::string ext = rel.extension().string();
      if (rel.parent_path() == "ground_truth") {
        const regen::Deviation d = regen::CompareGroundTruth(theirs, mine);
        ASSERT_TRUE(d.ok) << d.Report();
        EXPECT_LE(d.max, kMaxShift) << d.Report();
        EXPECT_LE(d.mean, 0.1 * kMaxShift) << d.Report();
        EXPECT_LE(d.flips, 2) << d.Report();
      } else if (ext == ".pcd") {
        std::string why;
        EXPECT_TRUE(regen::CloudsAgree(theirs, mine, &why)) << why;
      } else if (rel == "truth_contacts.csv") {
        CompareTruthContacts(theirs, mine, kMaxShift);
      } else if (rel == "forces.csv") {
        const double length = 0.12, axial = 5e4 * 0.04 * 0.01 / length;  // tool_table's slab, N/m
        CompareBundledForces(theirs, mine, axial * 0.1 * kMaxShift,
                             axial * 0.1 * kMaxShift * length);
      } else {
        EXPECT_TRUE(regen::ReadBytes(theirs) == regen::ReadBytes(mine)) << "differs";
      }
    }
    EXPECT_GT(files, 24);
  }
}

#ifdef FEMREG_CLI_PATH
// The last value of a stats.csv column.
double LastColumn(const std::string& csv, const std::string& column) {
  std::ifstream in(csv);
  std::string header, line, last;
  std::getline(in, header);
  while (std::getline(in, line)) last = line;
  std::vector<std::string> names, cells;
  std::stringstream hs(header), ls(last);
  for (std::string c; std::getline(hs, c, ',');) names.push_back(c);
  for (std::string c; std::getline(ls, c, ',');) cells.push_back(c);
  for (size_t i = 0; i < names.size() && i < cells.size(); ++i)
    if (names[i] == column) return std::atof(cells[i].c_str());
  ADD_FAILURE() << column << " not in " << csv;
  return 0.0;
}

// `femreg register --no-collision` registers without the contact term but still measures the
// penetration with the scene's collision section, so on and off compare in stats.csv.
TEST(CollisionCli, RegisterWithAndWithoutCollisionReportsThePenetration) {
  testing_util::TempDir dir("femreg_collision_test");
  const std::string data = std::string(FEMREG_DATASETS_DIR) + "/contact_pair";
  const std::string base = std::string(FEMREG_CLI_PATH) + " register --scene " + data +
                           "/scene.yaml --frames " + data + "/clouds --ground-truth " + data +
                           "/ground_truth --no-progress --report none --out " + dir.path();
  ASSERT_EQ(std::system((base + "/on > " + dir.path() + "/on.txt").c_str()), 0);
  ASSERT_EQ(std::system((base + "/off --no-collision > " + dir.path() + "/off.txt").c_str()), 0);
  const double D_mm = 1.5;
  EXPECT_LT(LastColumn(dir.path() + "/on/stats.csv", "max_penetration_mm"), 0.5);
  EXPECT_LT(LastColumn(dir.path() + "/on/stats.csv", "min_gap_mm"), D_mm);  // detected
  EXPECT_GT(LastColumn(dir.path() + "/off/stats.csv", "max_penetration_mm"), 2.0);
  // Both from the same signed gap: the penetration is the negative smallest gap.
  EXPECT_NEAR(LastColumn(dir.path() + "/off/stats.csv", "max_penetration_mm"),
              -LastColumn(dir.path() + "/off/stats.csv", "min_gap_mm"), 1e-4);
  EXPECT_EQ(LastColumn(dir.path() + "/off/stats.csv", "t_collision_ms"), 0.0);  // not in the tracker
  std::ifstream off(dir.path() + "/off.txt");
  const std::string text((std::istreambuf_iterator<char>(off)), std::istreambuf_iterator<char>());
  EXPECT_NE(text.find("collision off, measured only"), std::string::npos) << text;
  EXPECT_NE(text.find("deeper than collision.tolerance"), std::string::npos) << text;
}
#endif  // FEMREG_CLI_PATH

}  // namespace
}  // namespace femreg
