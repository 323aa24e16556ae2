// Coulomb friction (docs/theory/contact.md#friction) and the reported contact forces: a block
// pressed onto a table and dragged sideways sticks below mu and slides above it, in the
// forward solve and in registration; the forces per pair and obstacle balance the others; a
// block resting on a table reports its weight there; zero friction changes nothing.
#include <gtest/gtest.h>

#include <cmath>
#include <memory>
#include <string>
#include <vector>

#include "collision/contact_blocks.h"
#include "energy/friction.h"
#include "energy/term.h"
#include "femreg/collision.h"
#include "femreg/forward.h"
#include "femreg/io.h"
#include "femreg/scene.h"
#include "femreg/tracker.h"

namespace femreg {
namespace {

using V3 = Eigen::Vector3d;

// The block's energy is mu lambda |u|^2 / (2 eps) below eps and mu lambda (|u| - eps / 2)
// above: a spring that sticks, then a constant force mu lambda.
TEST(FrictionBlock, SticksAsASpringAndSlidesWithTheForceMuLambda) {
  const double mu = 0.4, lambda = 2.0, eps = 1e-4;
  energy::Friction<3> block;
  block.vertices = {{0, 1, 2}};
  block.coefficients = {{0.2, 0.3, 0.5}};
  block.tangent = energy::TangentBasis(V3(0, 0, 1));
  block.weight = FrictionWeight(mu, lambda, eps);
  const energy::Loss huber{RobustLoss::kHuber, eps};
  for (double slip : {0.3 * eps, 0.9 * eps, 3 * eps, 40 * eps}) {
    Vertices x = Vertices::Zero(3, 3);
    x.col(0).setConstant(slip);  // every vertex, hence the point, moved by slip along x
    energy::Linearization<energy::Friction<3>> share;
    ASSERT_TRUE(energy::Linearize(block, huber, x, &share, false));
    V3 force = V3::Zero();
    for (const V3& g : share.gradient) force -= g;
    if (slip <= eps) {
      EXPECT_NEAR(share.value, mu * lambda * slip * slip / (2 * eps), 1e-12);
      EXPECT_NEAR(force.x(), -mu * lambda * slip / eps, 1e-9);
    } else {
      EXPECT_NEAR(share.value, mu * lambda * (slip - eps / 2), 1e-12);
      EXPECT_NEAR(force.x(), -mu * lambda, 1e-9);
    }
    EXPECT_NEAR(force.y(), 0.0, 1e-12);
    EXPECT_NEAR(force.z(), 0.0, 1e-12);
  }
  EXPECT_EQ(FrictionWeight(0.0, lambda, eps), 0.0);
}

// A soft 4 x 4 x 2 cm block standing on a table plane, its top face pressed 2 mm down (frame 0)
// and then moved 3 mm along x (frame 1), in the forward solve.
struct Dragged {
  Vertices pressed, dragged;  // the solutions of the two frames
  std::vector<ContactForce> forces;  // at the dragged state, per obstacle
  Vertices potential_forces;         // EvaluateForwardForces' potential part
  Vertices reactions, loads;
  std::vector<int> bottom;
  bool converged = false;
  int iterations = 0;  // Newton iterations of both frames
};

// top_dx: the top's move along x in frame 1; table_dx: the table's (keyframed).
Dragged Drag(double mu, double top_dx = 0.003, double table_dx = 0.0) {
  Dragged d;
  TetMesh mesh = MakeBox(V3(0.04, 0.04, 0.02), 4, 4, 2);
  Material soft;
  soft.youngs_modulus = 5e4;
  soft.poisson_ratio = 0.3;
  ElasticModel model;
  model.Build(mesh, ElasticModelType::kCorotational, soft);
  std::vector<int> top;
  for (int v = 0; v < mesh.num_vertices(); ++v) {
    if (mesh.rest(v, 2) > 0.02 - 1e-9) top.push_back(v);
    if (mesh.rest(v, 2) < 1e-9) d.bottom.push_back(v);
  }
  CollisionSpec spec;
  spec.distance = 0.001;
  spec.stiffness = 2e4;
  spec.friction = mu;
  ObstacleSpec table;
  table.name = "table";
  table.keyframes.resize(2);
  table.keyframes[1].frame = 1;
  table.keyframes[1].translation = V3(table_dx, 0, 0);
  spec.obstacles.push_back(table);
  CollisionWorld world;
  EXPECT_TRUE(world.Init(spec, {"block"}, {mesh.surface}, mesh.x).ok());
  ContactPotential potential(&world, 0.001);
  ForwardOptions options;
  options.num_threads = 1;
  d.converged = true;
  ForwardProblem problem;
  problem.potential = &potential;
  for (int f = 0; f < 2; ++f) {
    world.SetFrame(f);
    // Prescribed moves are stepped from rest: the drag in one step, not through a lifted top.
    options.load_steps = f == 0 ? 2 : 1;
    problem.prescribed.clear();
    for (int v : top) problem.prescribed.emplace_back(v, V3(f == 0 ? 0.0 : top_dx, 0, -0.002));
    ForwardSummary summary;
    EXPECT_TRUE(SolveQuasiStatic(problem, options, &model, &mesh, &summary).ok());
    d.converged = d.converged && summary.termination == ForwardTermination::kConverged;
    d.iterations += summary.NumNewtonIterations();
    EXPECT_EQ(summary.termination, ForwardTermination::kConverged) << summary.FullReport();
    (f == 0 ? d.pressed : d.dragged) = mesh.x;
  }
  ForwardForces forces;
  EXPECT_TRUE(EvaluateForwardForces(problem, options, model, mesh, mesh.x, &forces).ok());
  d.potential_forces = forces.potential;
  d.reactions = forces.reactions;
  d.loads = forces.loads;
  d.forces = potential.Forces(mesh.x);
  return d;
}

double MeanSlideX(const Dragged& d) {
  double sum = 0.0;
  for (int v : d.bottom) sum += d.dragged(v, 0) - d.pressed(v, 0);
  return sum / d.bottom.size();
}

TEST(ForwardFriction, ABlockDraggedOnATableSticksBelowMuAndSlidesAboveIt) {
  // Shearing the block by 3 mm over its 2 cm height asks for a tangential force of about
  // half the normal one at the table.
  const Dragged stick = Drag(2.0), slide = Drag(0.1), free = Drag(0.0);
  ASSERT_TRUE(stick.converged && slide.converged && free.converged);
  ASSERT_EQ(stick.forces.size(), 1u);
  ASSERT_EQ(slide.forces.size(), 1u);
  RecordProperty("newton_iterations_mu2_mu01_mu0", std::to_string(stick.iterations) + " " +
                                                       std::to_string(slide.iterations) + " " +
                                                       std::to_string(free.iterations));
  RecordProperty("slide_um_mu2", std::to_string(MeanSlideX(stick) * 1e6));
  RecordProperty("slide_um_mu01", std::to_string(MeanSlideX(slide) * 1e6));
  RecordProperty("slide_um_mu0", std::to_string(MeanSlideX(free) * 1e6));
  RecordProperty("friction_over_normal_mu2", std::to_string(stick.forces[0].friction.norm() / stick.forces[0].force.z()));
  RecordProperty("friction_over_normal_mu01", std::to_string(slide.forces[0].friction.norm() / slide.forces[0].force.z()));
  // Sticking: the bottom stays where it was pressed (within the slip eps), the block shears.
  EXPECT_LT(std::abs(MeanSlideX(stick)), 1.5e-4);
  const ContactForce& fs = stick.forces[0];
  EXPECT_GT(fs.force.z(), 0.0);
  EXPECT_LT(std::abs(fs.friction.x()), 2.0 * fs.force.z());
  EXPECT_GT(std::abs(fs.friction.x()), 0.2 * fs.force.z());
  // Sliding: the bottom moves along and friction is mu times the normal force, against it.
  EXPECT_GT(MeanSlideX(slide), 1.5e-3);
  const ContactForce& fl = slide.forces[0];
  const double normal = fl.force.z() - fl.friction.z();
  EXPECT_NEAR(fl.friction.head<2>().norm(), 0.1 * normal, 0.03 * 0.1 * normal);
  EXPECT_LT(fl.friction.x(), 0.0);
  // Without friction the bottom slides the whole way, and no friction is reported.
  EXPECT_GT(MeanSlideX(free), MeanSlideX(slide));
  EXPECT_EQ(free.forces[0].friction.norm(), 0.0);
  // The reported resultant is the potential's force, and it balances the supports' reactions.
  for (const Dragged* d : {&stick, &slide}) {
    V3 potential = d->potential_forces.colwise().sum().transpose();
    V3 reported = V3::Zero();
    for (const ContactForce& f : d->forces) reported += f.force;
    EXPECT_LT((reported - potential).norm(), 1e-9 * (1 + potential.norm()));
    const V3 balance = reported + d->reactions.colwise().sum().transpose() + d->loads.colwise().sum().transpose();
    EXPECT_LT(balance.norm(), 1e-3 * potential.norm()) << balance.transpose();
  }
}

// The table slides 2 mm under the pressed block whose top is held: sticking, the bottom goes
// along (the slip is relative to the obstacle's motion); frictionless, it stays.
TEST(ForwardFriction, AMovingObstacleDragsWhatSticksToIt) {
  const Dragged stick = Drag(2.0, 0.0, 0.002), free = Drag(0.0, 0.0, 0.002);
  ASSERT_TRUE(stick.converged && free.converged);
  RecordProperty("slide_um_mu2", std::to_string(MeanSlideX(stick) * 1e6));
  EXPECT_NEAR(MeanSlideX(stick), 0.002, 1.5e-4);
  EXPECT_LT(std::abs(MeanSlideX(free)), 1e-5);
  ASSERT_EQ(stick.forces.size(), 1u);
  EXPECT_GT(stick.forces[0].friction.x(), 0.0);  // the table pulls the bottom along +x
}

// Two blocks, the lower clamped at its bottom, the upper 0.5 mm above it, pressed 2 mm down by
// its top (frame 0), then dragged 2 mm along x (frame 1): sticking, the faces move together and
// the pair's force on the lower block pulls it forward; frictionless, they slide.
struct PairDrag {
  double lower_top_slide = 0.0;  // m, frame 1
  double interface_slip = 0.0;   // m, frame 1: the upper's bottom against the lower's top
  std::vector<ContactForce> forces;
  bool converged = true;
};

PairDrag DragPair(double mu) {
  PairDrag d;
  const TetMesh lower = MakeBox(V3(0.04, 0.04, 0.02), 4, 4, 2);
  const TetMesh upper = MakeBox(V3(0.04, 0.04, 0.02), 3, 3, 2, V3(0, 0, 0.0205));
  std::vector<int> offsets;
  TetMesh mesh = MergeMeshes({lower, upper}, &offsets);
  Material soft;
  soft.youngs_modulus = 5e4;
  soft.poisson_ratio = 0.3;
  ElasticModel model;
  model.Build(mesh, ElasticModelType::kCorotational, soft);
  ForwardProblem problem;
  std::vector<int> top, lower_top, upper_bottom;
  for (int v = 0; v < mesh.num_vertices(); ++v) {
    const double z = mesh.rest(v, 2);
    if (v < offsets[1] && z < 1e-9) problem.clamped.push_back(v);
    if (v < offsets[1] && z > 0.02 - 1e-9) lower_top.push_back(v);
    if (v >= offsets[1] && z > 0.0405 - 1e-9) top.push_back(v);
    if (v >= offsets[1] && z < 0.0205 + 1e-9) upper_bottom.push_back(v);
  }
  CollisionSpec spec;
  spec.pairs = {{"lower", "upper", mu}};
  spec.distance = 0.001;
  spec.stiffness = 2e4;
  const std::vector<Triangles> surfaces = {lower.surface, (upper.surface.array() + offsets[1]).matrix()};
  CollisionWorld world;
  EXPECT_TRUE(world.Init(spec, {"lower", "upper"}, surfaces, mesh.x).ok());
  ContactPotential potential(&world, 0.001);
  problem.potential = &potential;
  ForwardOptions options;
  options.num_threads = 1;
  // Sticking under the press takes about as many Newton iterations as the default cap (the
  // pair's lagged normal force settles slowly; 70 and 102 on one CPU, fewer on another): this
  // test is about sticking and sliding, not that count.
  options.max_iterations = 300;
  Vertices pressed;
  for (int f = 0; f < 2; ++f) {
    world.SetFrame(f);
    options.load_steps = f == 0 ? 2 : 1;
    problem.prescribed.clear();
    for (int v : top) problem.prescribed.emplace_back(v, V3(f == 0 ? 0.0 : 0.002, 0, -0.002));
    ForwardSummary summary;
    EXPECT_TRUE(SolveQuasiStatic(problem, options, &model, &mesh, &summary).ok());
    EXPECT_EQ(summary.termination, ForwardTermination::kConverged) << summary.FullReport();
    d.converged = d.converged && summary.termination == ForwardTermination::kConverged;
    if (f == 0) pressed = mesh.x;
  }
  for (int v : lower_top) d.lower_top_slide += (mesh.x(v, 0) - pressed(v, 0)) / lower_top.size();
  d.interface_slip = -d.lower_top_slide;
  for (int v : upper_bottom) d.interface_slip += (mesh.x(v, 0) - pressed(v, 0)) / upper_bottom.size();
  potential.Refresh(mesh.x);
  d.forces = potential.Forces(mesh.x);
  return d;
}

TEST(ForwardFriction, APairSticksBelowMuAndSlidesFrictionless) {
  const PairDrag stick = DragPair(1.0), free = DragPair(0.0);
  ASSERT_TRUE(stick.converged && free.converged);
  RecordProperty("lower_top_slide_um_mu1", std::to_string(stick.lower_top_slide * 1e6));
  RecordProperty("lower_top_slide_um_mu0", std::to_string(free.lower_top_slide * 1e6));
  RecordProperty("interface_slip_um_mu1", std::to_string(stick.interface_slip * 1e6));
  RecordProperty("interface_slip_um_mu0", std::to_string(free.interface_slip * 1e6));
  // Sticking, the faces move together (within the slip eps); frictionless they slide (the
  // upper block's indent still carries the lower one's top part of the way).
  EXPECT_LT(std::abs(stick.interface_slip), 1e-4);
  EXPECT_GT(free.interface_slip, 3e-4);
  EXPECT_GT(stick.lower_top_slide, free.lower_top_slide + 1e-4);
  ASSERT_EQ(stick.forces.size(), 1u);
  EXPECT_EQ(stick.forces[0].object, 0);
  EXPECT_EQ(stick.forces[0].other, 1);
  EXPECT_GT(stick.forces[0].friction.x(), 0.0);  // the upper block pulls the lower one along
  EXPECT_LT(stick.forces[0].force.z(), 0.0);     // and presses it down
  ASSERT_EQ(free.forces.size(), 1u);
  EXPECT_EQ(free.forces[0].friction.norm(), 0.0);
}

// A stiff block (its own weight squeezes it by far less than a micrometre, which the data would
// pull back) resting on a table, seen from above (its top face only, which leaves it free
// to slide: point-to-plane pairs), under gravity and then pushed along x by 0.3 of its weight.
const char* kBlockScene = R"(
objects:
  - {name: block, generate: {shape: box, size: [0.04, 0.04, 0.02], cells: [4, 4, 2]},
     material: {youngs_modulus: 1.0e8, poisson_ratio: 0.3, density: 1000}}
gravity: [0, 0, -9.81]
registration:
  weights: {temporal: 1000}
effects: {collision: true}
collision:
  friction: MU
  obstacles:
    - {name: table, plane: {point: [0, 0, 0], normal: [0, 0, 1]}}
)";

// Points every 2 mm on the top face, 4 mm in from its edges, with its normal: the pairs pull
// along z only, so that the block stays covered and the data hold nothing along x while it
// slides a few millimetres.
PointCloud TopFaceCloud() {
  PointCloud cloud;
  const int n = 17;
  cloud.points.resize(n * n, 3);
  cloud.normals.resize(n * n, 3);
  for (int i = 0; i < n; ++i)
    for (int j = 0; j < n; ++j) {
      cloud.points.row(i * n + j) << 0.004 + 0.002 * i, 0.004 + 0.002 * j, 0.02;
      cloud.normals.row(i * n + j) << 0, 0, 1;
    }
  return cloud;
}

struct Pushed {
  FrameSummary rest, pushed;
  double weight = 0.0;  // N
  double slide = 0.0;   // m: the block's mean move along x in the pushed frame
};

Pushed Push(const std::string& mu) {
  Pushed run;
  std::string text = kBlockScene;
  text.replace(text.find("MU"), 2, mu);
  Scene scene;
  const Status parsed = ParseScene(text, "block.yaml", "", &scene);
  EXPECT_TRUE(parsed.ok()) << parsed.message();
  std::unique_ptr<Tracker> tracker;
  EXPECT_TRUE(Tracker::Create(scene, &tracker).ok());
  if (!tracker) return run;
  const PointCloud cloud = TopFaceCloud();
  for (int f = 0; f < 5; ++f) EXPECT_TRUE(tracker->Track(cloud, &run.rest).ok());
  run.weight = tracker->mesh(0).mass.sum() * 9.81;
  const Vertices before = tracker->vertices(0);
  std::vector<std::pair<int, Eigen::Vector3d>> push;
  const int nv = tracker->mesh(0).num_vertices();
  for (int v = 0; v < nv; ++v) push.emplace_back(v, V3(0.3 * run.weight / nv, 0, 0));
  EXPECT_TRUE(tracker->SetExternalLoads(0, V3(0, 0, -9.81), push).ok());
  EXPECT_TRUE(tracker->Track(cloud, &run.pushed).ok());
  run.slide = (tracker->vertices(0) - before).col(0).mean();
  return run;
}

TEST(RegistrationFriction, ABlockRestingOnATableReportsItsWeightThere) {
  const Pushed run = Push("0.5");
  ASSERT_TRUE(run.rest.IsSolutionUsable()) << run.rest.FullReport();
  ASSERT_EQ(run.rest.contact_forces.size(), 1u);
  const ContactForce& table = run.rest.contact_forces[0];
  EXPECT_EQ(table.object, 0);
  EXPECT_EQ(table.other, -1);
  EXPECT_GT(table.contacts, 0);
  EXPECT_NEAR(table.force.z(), run.weight, 0.01 * run.weight) << run.rest.FullReport();
  EXPECT_LT(table.force.head<2>().norm(), 0.01 * run.weight);
  // The data's pull and the contacts' push (FrameSummary::force) balance the weight.
  EXPECT_NEAR(run.rest.force.z(), run.weight, 0.01 * run.weight);
}

TEST(RegistrationFriction, ABlockPushedOnATableSticksBelowMuAndSlidesAboveIt) {
  const Pushed stick = Push("0.5"), slide = Push("0.1"), free = Push("0.0");
  ASSERT_TRUE(stick.pushed.IsSolutionUsable()) << stick.pushed.FullReport();
  ASSERT_TRUE(slide.pushed.IsSolutionUsable()) << slide.pushed.FullReport();
  ASSERT_TRUE(free.pushed.IsSolutionUsable()) << free.pushed.FullReport();
  // The push is 0.3 of the weight: below mu = 0.5 it sticks (moves less than the slip eps),
  // above mu = 0.1 it slides, less far than without friction.
  EXPECT_LT(std::abs(stick.slide), 1e-4) << stick.pushed.FullReport();
  EXPECT_GT(slide.slide, 5e-4) << slide.pushed.FullReport();
  EXPECT_GT(free.slide, slide.slide + 5e-4);
  ASSERT_EQ(stick.pushed.contact_forces.size(), 1u);
  ASSERT_EQ(slide.pushed.contact_forces.size(), 1u);
  ASSERT_EQ(free.pushed.contact_forces.size(), 1u);
  RecordProperty("slide_um_mu05", std::to_string(stick.slide * 1e6));
  RecordProperty("slide_um_mu01", std::to_string(slide.slide * 1e6));
  RecordProperty("slide_um_mu0", std::to_string(free.slide * 1e6));
  RecordProperty("friction_over_weight_mu05", std::to_string(stick.pushed.contact_forces[0].friction.norm() / stick.weight));
  RecordProperty("friction_over_normal_mu01", std::to_string(slide.pushed.contact_forces[0].friction.norm() /
                                                             slide.pushed.contact_forces[0].force.z()));
  // Sticking: friction holds the push; sliding: it is mu times the normal force, against the
  // motion.
  const ContactForce& s = stick.pushed.contact_forces[0];
  EXPECT_NEAR(s.friction.x(), -0.3 * stick.weight, 0.05 * stick.weight);
  const ContactForce& l = slide.pushed.contact_forces[0];
  const double normal = l.force.z() - l.friction.z();
  EXPECT_NEAR(l.friction.head<2>().norm(), 0.1 * normal, 0.05 * 0.1 * normal);
  EXPECT_LT(l.friction.x(), 0.0);
  EXPECT_EQ(free.pushed.contact_forces[0].friction.norm(), 0.0);
}

TEST(RegistrationFriction, ZeroFrictionIsTheFrictionlessResult) {
  // A scene without the key and one with friction: 0 give the same vertices, bit for bit.
  std::string with = kBlockScene, without = kBlockScene;
  with.replace(with.find("MU"), 2, "0");
  without.replace(without.find("  friction: MU\n"), 15, "");
  std::vector<Vertices> results;
  for (const std::string& text : {with, without}) {
    Scene scene;
    ASSERT_TRUE(ParseScene(text, "block.yaml", "", &scene).ok());
    std::unique_ptr<Tracker> tracker;
    ASSERT_TRUE(Tracker::Create(scene, &tracker).ok());
    FrameSummary summary;
    PointCloud cloud = TopFaceCloud();
    for (int f = 0; f < 2; ++f) {
      cloud.points.col(0).array() += 0.001;
      ASSERT_TRUE(tracker->Track(cloud, &summary).ok());
    }
    results.push_back(tracker->vertices(0));
  }
  EXPECT_EQ((results[0] - results[1]).cwiseAbs().maxCoeff(), 0.0);
}

// The scene keys: a default coefficient, one per obstacle and one per pair, written back.
TEST(FrictionScene, KeysParseAndWriteBack) {
  const char* text = R"(
objects:
  - {name: a, generate: {shape: box, size: [0.02, 0.02, 0.02], cells: [1, 1, 1]}}
  - {name: b, generate: {shape: box, size: [0.02, 0.02, 0.02], cells: [1, 1, 1]}, pose: {translation: [0, 0, 0.03]}}
effects: {collision: true}
collision:
  friction: 0.3
  friction_slip: 0.0002
  pairs: [{objects: [a, b], friction: 0.6}]
  obstacles:
    - {name: table, plane: {point: [0, 0, 0], normal: [0, 0, 1]}, friction: 0.8}
    - {name: wall, plane: {point: [0.1, 0, 0], normal: [-1, 0, 0]}}
)";
  Scene scene;
  const Status status = ParseScene(text, "f.yaml", "", &scene);
  ASSERT_TRUE(status.ok()) << status.message();
  const CollisionSpec& c = scene.collision;
  EXPECT_EQ(c.friction, 0.3);
  EXPECT_EQ(c.friction_slip, 0.0002);
  ASSERT_EQ(c.pairs.size(), 1u);
  EXPECT_EQ(c.pairs[0].friction, 0.6);
  ASSERT_EQ(c.obstacles.size(), 2u);
  EXPECT_EQ(c.obstacles[0].friction, 0.8);
  EXPECT_LT(c.obstacles[1].friction, 0.0);  // the default's
  Scene again;
  const std::string written = SceneToYaml(scene, "");
  ASSERT_TRUE(ParseScene(written, "g.yaml", "", &again).ok()) << written;
  EXPECT_EQ(again.collision.friction, 0.3);
  EXPECT_EQ(again.collision.friction_slip, 0.0002);
  ASSERT_EQ(again.collision.pairs.size(), 1u);
  EXPECT_EQ(again.collision.pairs[0].friction, 0.6);
  EXPECT_EQ(again.collision.obstacles[0].friction, 0.8);
  // The world's coefficient per contact: the pair's, the obstacle's, or the default.
  CollisionWorld world;
  const TetMesh box = MakeBox(V3(0.02, 0.02, 0.02), 1, 1, 1);
  Triangles second = box.surface.array() + box.num_vertices();
  Vertices x(2 * box.num_vertices(), 3);
  x << box.rest, box.rest.rowwise() + Eigen::RowVector3d(0, 0, 0.03);
  ASSERT_TRUE(world.Init(c, {"a", "b"}, {box.surface, second}, x).ok());
  Contact pair, table, wall;
  pair.object_a = 1;
  pair.object_b = 0;
  table.object_b = -1;
  wall.object_b = -2;
  EXPECT_EQ(world.Friction(pair), 0.6);
  EXPECT_EQ(world.Friction(table), 0.8);
  EXPECT_EQ(world.Friction(wall), 0.3);
  EXPECT_TRUE(world.has_friction());
  // Negative coefficients are refused.
  std::string bad = text;
  bad.replace(bad.find("friction: 0.3"), 13, "friction: -1");
  EXPECT_FALSE(ParseScene(bad, "f.yaml", "", &scene).ok());
}

}  // namespace
}  // namespace femreg
