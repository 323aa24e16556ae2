// WriteScene / SceneToYaml: what is written reads back (ParseScene, LoadScene) into the same
// Scene, section by section, for a scene that sets every key, for scenes built in code and
// for every bundled scene; and only what differs from the defaults is written.
//
// Doubles are compared exactly: writing and reading a number are decimal conversions with
// correct rounding in both directions (no arithmetic), the same on every CPU, and the writer
// prints the shortest decimal that reads back to the same double. The one exception is a
// selection's plane normal, which the reader normalizes again (a unit vector divided by its
// computed length moves by at most an ulp or two: 1e-15).
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "femreg/io.h"
#include "femreg/scene.h"
#include "femreg_test_config.h"
#include "member_count.h"
#include "test_util.h"

namespace femreg {
namespace {

using testing_tables::ExpectSameFields;

namespace fs = std::filesystem;

void ExpectSameMaterial(const Material& a, const Material& b) {
  EXPECT_EQ(a.youngs_modulus, b.youngs_modulus);
  EXPECT_EQ(a.poisson_ratio, b.poisson_ratio);
  EXPECT_EQ(a.density, b.density);
}

void ExpectSameGenerator(const MeshGeneratorSpec& a, const MeshGeneratorSpec& b) {
  EXPECT_EQ(a.shape, b.shape);
  if (a.shape == MeshGeneratorSpec::Shape::kBox) {
    EXPECT_EQ(a.size, b.size);
    EXPECT_EQ(a.cells, b.cells);
    EXPECT_EQ(a.origin, b.origin);
  } else if (a.shape != MeshGeneratorSpec::Shape::kNone) {  // cylinder, sphere
    EXPECT_EQ(a.radius, b.radius);
    EXPECT_EQ(a.radial_cells, b.radial_cells);
    if (a.shape == MeshGeneratorSpec::Shape::kCylinder) {
      EXPECT_EQ(a.length, b.length);
      EXPECT_EQ(a.axial_cells, b.axial_cells);
    }
  }
}

void ExpectSameSelection(const VertexSelection& a, const VertexSelection& b) {
  EXPECT_EQ(a.kind, b.kind);
  EXPECT_EQ(a.box_min, b.box_min);
  EXPECT_EQ(a.box_max, b.box_max);
  EXPECT_EQ(a.plane_point, b.plane_point);
  EXPECT_LT((a.plane_normal - b.plane_normal).norm(), 1e-15);  // normalized again on reading
  EXPECT_EQ(a.tolerance, b.tolerance);
  EXPECT_EQ(a.indices, b.indices);
}

void ExpectSameKeyframes(const std::vector<MotionKeyframe>& a, const std::vector<MotionKeyframe>& b) {
  ASSERT_EQ(a.size(), b.size());
  for (size_t i = 0; i < a.size(); ++i) {
    EXPECT_EQ(a[i].frame, b[i].frame);
    EXPECT_EQ(a[i].translation, b[i].translation);
    EXPECT_EQ(a[i].rotation, b[i].rotation);
  }
}

void ExpectSameRegistration(const RegistrationOptions& a, const RegistrationOptions& b) {
  EXPECT_EQ(a.regularizer, b.regularizer);
  EXPECT_EQ(a.initial_pose, b.initial_pose);
  const CameraOptions &c = a.camera, &d = b.camera;
  EXPECT_EQ(c.enabled, d.enabled);
  EXPECT_EQ(c.position, d.position);
  EXPECT_EQ(c.target, d.target);
  EXPECT_EQ(c.up, d.up);
  EXPECT_EQ(c.fx, d.fx);
  EXPECT_EQ(c.fy, d.fy);
  EXPECT_EQ(c.cx, d.cx);
  EXPECT_EQ(c.cy, d.cy);
  EXPECT_EQ(c.width, d.width);
  EXPECT_EQ(c.height, d.height);
  const PreprocessOptions &p = a.preprocess, &q = b.preprocess;
  EXPECT_EQ(p.crop, q.crop);
  EXPECT_EQ(p.crop_min, q.crop_min);
  EXPECT_EQ(p.crop_max, q.crop_max);
  EXPECT_EQ(p.voxel_size, q.voxel_size);
  EXPECT_EQ(p.outlier_neighbors, q.outlier_neighbors);
  EXPECT_EQ(p.outlier_stddev, q.outlier_stddev);
  EXPECT_EQ(p.normal_neighbors, q.normal_neighbors);
  EXPECT_EQ(p.plane_distance, q.plane_distance);
  EXPECT_EQ(p.plane_iterations, q.plane_iterations);
  EXPECT_EQ(p.flying_pixels, q.flying_pixels);
  EXPECT_EQ(p.depth_offset, q.depth_offset);
  EXPECT_EQ(p.mask_dir, q.mask_dir);
  const DataTermOptions &e = a.data, &f = b.data;
  EXPECT_EQ(e.model_to_cloud, f.model_to_cloud);
  EXPECT_EQ(e.cloud_to_model, f.cloud_to_model);
  EXPECT_EQ(e.max_distance, f.max_distance);
  EXPECT_EQ(e.loss, f.loss);
  EXPECT_EQ(e.loss_scale, f.loss_scale);
  EXPECT_EQ(e.metric, f.metric);
  EXPECT_EQ(e.visibility, f.visibility);
  EXPECT_EQ(e.cloud_stride, f.cloud_stride);
  EXPECT_EQ(a.weights.data, b.weights.data);
  EXPECT_EQ(a.weights.elastic, b.weights.elastic);
  EXPECT_EQ(a.weights.temporal, b.weights.temporal);
  EXPECT_EQ(a.weights.anchor, b.weights.anchor);
  EXPECT_EQ(a.weights.data_per_area, b.weights.data_per_area);
  EXPECT_EQ(a.weights.model_to_cloud_share, b.weights.model_to_cloud_share);
  EXPECT_EQ(a.weights.model_to_cloud_area_cap, b.weights.model_to_cloud_area_cap);
  EXPECT_EQ(a.weights.model_to_cloud_balance, b.weights.model_to_cloud_balance);
  const SolverOptions &s = a.solver, &t = b.solver;
  EXPECT_EQ(s.max_outer_iterations, t.max_outer_iterations);
  EXPECT_EQ(s.max_inner_iterations, t.max_inner_iterations);
  EXPECT_EQ(s.relative_energy_tolerance, t.relative_energy_tolerance);
  EXPECT_EQ(s.bulk_step_tolerance, t.bulk_step_tolerance);
  EXPECT_EQ(s.time_budget_s, t.time_budget_s);
  EXPECT_EQ(s.backend, t.backend);
  EXPECT_EQ(s.trust_region, t.trust_region);
  EXPECT_EQ(s.linear_solver, t.linear_solver);
  EXPECT_EQ(s.preconditioner, t.preconditioner);
  EXPECT_EQ(s.num_threads, t.num_threads);
  EXPECT_EQ(s.predict_motion, t.predict_motion);
  EXPECT_EQ(s.rigid_prealign, t.rigid_prealign);
  EXPECT_EQ(s.rigid_iterations, t.rigid_iterations);
}

// Every field but the derived ones (path, selections' where, synth.source_name and
// synth.ground_truth_where).
void ExpectSameScene(const Scene& a, const Scene& b) {
  EXPECT_EQ(a.description, b.description);
  ASSERT_EQ(a.objects.size(), b.objects.size());
  for (size_t i = 0; i < a.objects.size(); ++i) {
    SCOPED_TRACE("objects[" + std::to_string(i) + "]");
    const ObjectSpec &o = a.objects[i], &p = b.objects[i];
    EXPECT_EQ(o.name, p.name);
    EXPECT_EQ(o.mesh_path, p.mesh_path);
    ExpectSameGenerator(o.generate, p.generate);
    ExpectSameFields(o, p, "a round trip");  // scale, pose, toughness, label
    ExpectSameMaterial(o.material, p.material);
    ASSERT_EQ(o.region_materials.size(), p.region_materials.size());
    for (size_t r = 0; r < o.region_materials.size(); ++r) {
      EXPECT_EQ(o.region_materials[r].first, p.region_materials[r].first);
      ExpectSameMaterial(o.region_materials[r].second, p.region_materials[r].second);
    }
    EXPECT_EQ(o.region_toughness, p.region_toughness);
  }
  EXPECT_EQ(a.gravity, b.gravity);
  ASSERT_EQ(a.boundary_conditions.size(), b.boundary_conditions.size());
  for (size_t i = 0; i < a.boundary_conditions.size(); ++i) {
    const BoundaryConditionSpec &c = a.boundary_conditions[i], &d = b.boundary_conditions[i];
    EXPECT_EQ(c.object, d.object);
    ExpectSameSelection(c.selection, d.selection);
    EXPECT_EQ(c.type, d.type);
    EXPECT_EQ(c.displacement, d.displacement);
  }
  ASSERT_EQ(a.loads.size(), b.loads.size());
  for (size_t i = 0; i < a.loads.size(); ++i) {
    EXPECT_EQ(a.loads[i].object, b.loads[i].object);
    ExpectSameSelection(a.loads[i].selection, b.loads[i].selection);
    EXPECT_EQ(a.loads[i].force, b.loads[i].force);
  }
  ExpectSameFields(a.forward, b.forward, "a round trip");  // the model and the solve's limits
  ExpectSameRegistration(a.registration, b.registration);
  ASSERT_EQ(a.anchors.size(), b.anchors.size());
  for (size_t i = 0; i < a.anchors.size(); ++i) {
    SCOPED_TRACE("anchors[" + std::to_string(i) + "]");
    const AnchorSpec &c = a.anchors[i], &d = b.anchors[i];
    EXPECT_EQ(c.name, d.name);
    EXPECT_EQ(c.object, d.object);
    ExpectSameSelection(c.selection, d.selection);
    ExpectSameFields(c, d, "a round trip");  // hard, weight
    EXPECT_EQ(c.translations, d.translations);
    EXPECT_EQ(c.rotations, d.rotations);
    if (!c.rotations.empty()) {
      EXPECT_EQ(c.centre, d.centre);  // written with the rotations
    }
  }
  EXPECT_EQ(a.effects.fracture, b.effects.fracture);
  EXPECT_EQ(a.effects.collision, b.effects.collision);
  const FractureOptions &f = a.effects.fracture_options, &g = b.effects.fracture_options;
  EXPECT_EQ(f.crossing_tolerance, g.crossing_tolerance);
  EXPECT_EQ(f.min_piece_fraction, g.min_piece_fraction);
  EXPECT_EQ(f.max_splits_per_iteration, g.max_splits_per_iteration);
  EXPECT_EQ(f.max_splits_per_frame, g.max_splits_per_frame);
  EXPECT_EQ(f.max_cracks, g.max_cracks);
  EXPECT_EQ(f.data_gap, g.data_gap);
  EXPECT_EQ(f.cut_through, g.cut_through);
  EXPECT_EQ(f.piece_prealign, g.piece_prealign);
  EXPECT_EQ(f.relax_pieces, g.relax_pieces);
  const CollisionSpec &c = a.collision, &d = b.collision;
  EXPECT_EQ(c.pairs, d.pairs);
  EXPECT_EQ(c.stiffness, d.stiffness);
  EXPECT_EQ(c.distance, d.distance);
  EXPECT_EQ(c.tolerance, d.tolerance);
  EXPECT_EQ(c.augmented, d.augmented);
  ASSERT_EQ(c.obstacles.size(), d.obstacles.size());
  for (size_t i = 0; i < c.obstacles.size(); ++i) {
    SCOPED_TRACE("collision.obstacles[" + std::to_string(i) + "]");
    const ObstacleSpec &o = c.obstacles[i], &p = d.obstacles[i];
    EXPECT_EQ(o.name, p.name);
    EXPECT_EQ(o.kind, p.kind);
    EXPECT_EQ(o.plane_point, p.plane_point);
    EXPECT_EQ(o.plane_normal, p.plane_normal);
    EXPECT_EQ(o.box_size, p.box_size);
    EXPECT_EQ(o.mesh_path, p.mesh_path);
    EXPECT_EQ(o.surface.has_value(), p.surface.has_value());  // a scene names files only
    ExpectSameFields(o, p, "a round trip");  // scale, friction
    EXPECT_EQ(o.objects, p.objects);
    ASSERT_EQ(o.keyframes.size(), p.keyframes.size());
    for (size_t k = 0; k < o.keyframes.size(); ++k) {
      EXPECT_EQ(o.keyframes[k].frame, p.keyframes[k].frame);
      EXPECT_EQ(o.keyframes[k].translation, p.keyframes[k].translation);
      EXPECT_EQ(o.keyframes[k].rotation, p.keyframes[k].rotation);
    }
  }
  const SynthSpec &s = a.synth, &t = b.synth;
  EXPECT_EQ(s.enabled, t.enabled);
  if (!s.enabled) return;
  ExpectSameFields(s, t, "a round trip");  // frames, seed, sanity_check, refinement, background
  EXPECT_EQ(s.mesh_path, t.mesh_path);
  ExpectSameGenerator(s.generate, t.generate);
  ExpectSameMaterial(s.material, t.material);
  const DepthSensorOptions &m = s.sensor, &n = t.sensor;
  EXPECT_EQ(m.camera.position, n.camera.position);
  EXPECT_EQ(m.near, n.near);
  EXPECT_EQ(m.noise_coefficient, n.noise_coefficient);
  EXPECT_EQ(m.grazing_angle_deg, n.grazing_angle_deg);
  EXPECT_EQ(m.pixel_stride, n.pixel_stride);
  EXPECT_EQ(m.outlier_fraction, n.outlier_fraction);
  EXPECT_EQ(m.outlier_margin, n.outlier_margin);
  for (const SynthArtefactKey& k : SynthArtefactKeys()) {
    EXPECT_EQ(k.get(s), k.get(t)) << "synth.artefacts." << k.artefact << "." << k.key;
  }
  ASSERT_EQ(s.motion.size(), t.motion.size());
  for (size_t i = 0; i < s.motion.size(); ++i) {
    SCOPED_TRACE("synth.motion[" + std::to_string(i) + "]");
    EXPECT_EQ(s.motion[i].name, t.motion[i].name);
    ExpectSameSelection(s.motion[i].selection, t.motion[i].selection);
    EXPECT_EQ(s.motion[i].has_centre, t.motion[i].has_centre);
    EXPECT_EQ(s.motion[i].centre, t.motion[i].centre);
    ExpectSameKeyframes(s.motion[i].keyframes, t.motion[i].keyframes);
    ExpectSameFields(s.motion[i], t.motion[i], "a round trip");  // anchor
  }
  ASSERT_EQ(s.bodies.size(), t.bodies.size());
  for (size_t i = 0; i < s.bodies.size(); ++i) {
    SCOPED_TRACE("synth.bodies[" + std::to_string(i) + "]");
    const SynthBodySpec &x = s.bodies[i], &y = t.bodies[i];
    EXPECT_EQ(x.name, y.name);
    ExpectSameKeyframes(x.keyframes, y.keyframes);
    ExpectSameFields(x, y, "a round trip");  // box, in_cloud, press, contact_tolerance
  }
}

// Writes `scene` as text, reads it back (paths resolved against `dir`) and compares.
Scene RoundTrip(const Scene& scene, const std::string& dir) {
  const std::string text = SceneToYaml(scene, dir);
  Scene back;
  const Status status = ParseScene(text, "written.yaml", dir, &back);
  EXPECT_TRUE(status.ok()) << status.message() << "\n" << text;
  ExpectSameScene(scene, back);
  return back;
}

// A scene that sets every section and most keys away from their defaults (two objects for
// the collision pairs; synth needs one object, so it has a scene of its own below).
const char kEverything[] =
    "description: \"every section: a beam and a ball, pressed\"\n"
    "objects:\n"
    "  - name: beam\n"
    "    mesh: beam.mesh\n"
    "    scale: 0.001\n"
    "    pose: {translation: [0.1, -0.2, 0.30000000000000004], rotation: [0, 0, 1.5707963267948966]}\n"
    "    material: {youngs_modulus: 2.5e5, poisson_ratio: 0.45, density: 950}\n"
    "    regions: {2: {youngs_modulus: 5e5, toughness: 1200}, 3: {density: 10}}\n"
    "    toughness: 3000\n"
    "    label: 1\n"
    "  - name: ball\n"
    "    generate: {shape: sphere, radius: 0.05, cells: 3}\n"
    "    label: 2\n"
    "  - name: rod\n"
    "    generate: {shape: cylinder, radius: 0.01, length: 0.2, cells: [2, 9]}\n"
    "gravity: [0, 0, -9.81]\n"
    "boundary:\n"
    "  - {object: beam, select: {box: {min: [-1, -1, -1], max: [0.0001, 1, 1]}, tolerance: 1e-6}, clamp: true}\n"
    "  - {object: ball, select: {plane: {point: [0, 0, 0.05], normal: [0, 0, 3]}}, displacement: [0, 0, -0.01]}\n"
    "  - {object: rod, select: {indices: [0, 1, 2]}, clamp: true}\n"
    "loads:\n"
    "  - {object: beam, select: {all: true}, force: [0, 1e-3, -2]}\n"
    "forward: {model: linear, max_iterations: 40, load_steps: 3, tolerance: 1e-9, absolute_tolerance: 0}\n"
    "registration:\n"
    "  regularizer: mass_spring\n"
    "  initial_pose: given\n"
    "  camera: {position: [0.1, -0.5, 0.3], target: [0.1, 0, 0], up: [0, 0, 1], fx: 300, fy: 301,\n"
    "           cx: 159.5, cy: 119.5, width: 320, height: 240}\n"
    "  preprocess: {mask_dir: masks, crop: {min: [-1, -1, -0.01], max: [1, 1, 1]}, plane: {distance: 0.004, iterations: 50},\n"
    "               voxel_size: 0.002, outliers: {neighbors: 8, stddev: 2.5}, normals: {neighbors: 12},\n"
    "               flying_pixels: 3, depth_offset: false}\n"
    "  data: {model_to_cloud: false, max_distance: 0.02, loss: cauchy, loss_scale: 0.003,\n"
    "         metric: point_to_point, visibility: true, cloud_stride: 2}\n"
    "  weights: {data: 150, model_to_cloud_balance: false, elastic: 2, temporal: 0.5, anchor: 2e4}\n"
    "  solver: {max_outer_iterations: 7, max_inner_iterations: 4, relative_energy_tolerance: 1e-4,\n"
    "           bulk_step_tolerance: 0.02, time_budget_s: 0.25,\n"
    "           threads: 2, rigid_prealign: true, rigid_iterations: 12, predict_motion: false,\n"
    "           backend: fast}\n"
    "anchors:\n"
    "  - {name: grip, object: beam, select: {box: {min: [0.9, -1, -1], max: [1, 1, 1]}}, weight: 500,\n"
    "     translations: [[0, 0, 0], [0, 0, 0.1], [0, 0.0001, 0.30000000000000004]]}\n"
    "  - {name: hold, object: ball, select: {all: true}, hard: true}\n"
    "effects: {fracture: {max_splits_per_iteration: 4, max_splits_per_frame: 20,\n"
    "          crossing_tolerance: 0.3, max_cracks: 2, data_gap: true, cut_through: true,\n"
    "          piece_prealign: true, relax_pieces: false}, collision: true}\n"
    "collision:\n"
    "  pairs: [[beam, ball], [ball, rod]]\n"
    "  stiffness: 5000\n"
    "  distance: 0.001\n"
    "  tolerance: 0.0003\n"
    "  augmented: false\n"
    "  obstacles:\n"
    "    - {name: table, plane: {point: [0, 0, -0.1], normal: [0, 0, 1]}, objects: [beam, ball]}\n"
    "    - {name: wall, box: {size: [0.1, 1, 1]}, pose: {translation: [1, 0, 0], rotation: [0, 0.1, 0]}}\n"
    "    - name: tool\n"
    "      mesh: tool.obj\n"
    "      scale: 0.01\n"
    "      keyframes: [{frame: 0, translation: [0, 0, 1]}, {frame: 9, rotation: [0, 0, 0.5]}]\n";

class SceneWriterTest : public ::testing::Test {
 protected:
  void SetUp() override {
    // The files the scenes name: a tetrahedral mesh and a triangle surface.
    std::ofstream(fs::path(dir_.path()) / "beam.mesh")
        << "MeshVersionFormatted 2\nDimension 3\nVertices\n4\n0 0 0 1\n1 0 0 1\n0 1 0 1\n"
           "0 0 1 1\nTetrahedra\n1\n1 2 3 4 2\nEnd\n";
    std::ofstream(fs::path(dir_.path()) / "tool.obj") << "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n";
  }
  testing_util::TempDir dir_{"femreg_scene_writer_test"};
};

TEST_F(SceneWriterTest, EverySectionReadsBackTheSame) {
  const std::string path = (fs::path(dir_.path()) / "everything.yaml").string();
  std::ofstream(path) << kEverything;
  Scene scene;
  const Status status = LoadScene(path, &scene);
  ASSERT_TRUE(status.ok()) << status.message();
  // The scene sets what it was meant to (the test is not vacuous).
  EXPECT_EQ(scene.description, "every section: a beam and a ball, pressed");
  ASSERT_EQ(scene.objects.size(), 3u);
  EXPECT_EQ(scene.objects[0].region_materials.size(), 2u);
  EXPECT_EQ(scene.collision.obstacles.size(), 3u);
  EXPECT_TRUE(scene.effects.fracture);
  EXPECT_EQ(scene.registration.solver.backend, SolverBackend::kFast);
  EXPECT_EQ(scene.anchors[0].translations[2].z(), 0.30000000000000004);
  EXPECT_EQ(scene.registration.preprocess.flying_pixels, 3.0);
  EXPECT_FALSE(scene.registration.preprocess.depth_offset);

  RoundTrip(scene, dir_.path());

  // Into a file in another folder: mesh paths are written relative to it and resolve to
  // the same files.
  const fs::path other = fs::path(dir_.path()) / "out" / "sub";
  fs::create_directories(other);
  ASSERT_TRUE(WriteScene(scene, (other / "scene.yaml").string(), "a comment\n\nover lines").ok());
  std::ifstream in(other / "scene.yaml");
  std::string first, second, third;
  std::getline(in, first);
  std::getline(in, second);
  std::getline(in, third);
  EXPECT_EQ(first, "# a comment");
  EXPECT_EQ(second, "#");
  EXPECT_EQ(third, "# over lines");
  Scene back;
  ASSERT_TRUE(LoadScene((other / "scene.yaml").string(), &back).ok());
  EXPECT_EQ(fs::canonical(back.objects[0].mesh_path), fs::canonical(scene.objects[0].mesh_path));
  EXPECT_EQ(fs::canonical(back.collision.obstacles[2].mesh_path),
            fs::canonical(scene.collision.obstacles[2].mesh_path));
  back.objects[0].mesh_path = scene.objects[0].mesh_path;
  back.collision.obstacles[2].mesh_path = scene.collision.obstacles[2].mesh_path;
  ExpectSameScene(scene, back);
}

// A mesh obstacle whose surface is in memory has no file for a scene to name: WriteScene
// refuses the scene, naming the obstacle, and writes nothing; the text says what it was.
TEST_F(SceneWriterTest, ObstacleSurfaceInMemoryIsRefusedByName) {
  Scene scene;
  ASSERT_TRUE(ParseScene("objects:\n  - {name: beam, mesh: beam.mesh}\n", "inline", dir_.path(), &scene).ok());
  ObstacleSpec tool;
  tool.name = "probe";
  tool.kind = ObstacleSpec::Kind::kMesh;
  tool.surface.emplace();
  tool.surface->vertices.resize(3, 3);
  tool.surface->vertices << 0, 0, 0, 1, 0, 0, 0, 1, 0;
  tool.surface->triangles.resize(1, 3);
  tool.surface->triangles << 0, 1, 2;
  scene.collision.obstacles.push_back(tool);
  const std::string path = (fs::path(dir_.path()) / "refused.yaml").string();
  const Status status = WriteScene(scene, path);
  ASSERT_FALSE(status.ok());
  EXPECT_NE(status.message().find("'probe'"), std::string::npos) << status.message();
  EXPECT_NE(status.message().find("in memory"), std::string::npos) << status.message();
  EXPECT_FALSE(fs::exists(path));
  EXPECT_NE(SceneToYaml(scene).find("in memory: 3 vertices, 1 triangles"), std::string::npos)
      << SceneToYaml(scene);
  scene.collision.obstacles[0].surface.reset();  // named by a file: written
  scene.collision.obstacles[0].mesh_path = (fs::path(dir_.path()) / "tool.obj").string();
  EXPECT_TRUE(WriteScene(scene, path).ok());
}

TEST_F(SceneWriterTest, SynthSectionReadsBackTheSame) {
  const char text[] =
      "objects:\n"
      "  - name: beam\n"
      "    generate: {shape: box, size: [0.2, 0.02, 0.02], cells: [10, 1, 1], origin: [0, -0.01, -0.01]}\n"
      "    material: {youngs_modulus: 1e4}\n"
      "boundary:\n"
      "  - {select: {box: {min: [-1, -1, -1], max: [0.0001, 1, 1]}}, clamp: true}\n"
      "registration:\n"
      "  camera: {position: [0.1, -0.3, 0.2], target: [0.1, 0, 0], up: [0, 0, 1], fx: 60, fy: 60,\n"
      "           cx: 39.5, cy: 29.5, width: 80, height: 60}\n"
      "  solver: {trust_region: dogleg}\n"
      "synth:\n"
      "  frames: 9\n"
      "  seed: 12\n"
      "  ground_truth: {mesh: beam.mesh, material: {poisson_ratio: 0.41}}\n"
      "  sensor: {noise_coefficient: 0.001, grazing_angle_deg: 70, pixel_stride: 2,\n"
      "           outlier_fraction: 0.01, outlier_margin: 0.02, near: 0.1}\n"
      "  background: {point: [0, 0, -0.02], normal: [0, 0, 1], size: 0.5}\n"
      "  motion:\n"
      "    - {name: end, select: {box: {min: [0.1999, -1, -1], max: [1, 1, 1]}}, centre: [0.2, 0, 0],\n"
      "       anchor: soft, keyframes: [{frame: 0}, {frame: 8, translation: [0, 0, -0.03]}]}\n"
      "    - {name: twist, select: {plane: {point: [0.1, 0, 0], normal: [1, 1, 0]}},\n"
      "       keyframes: [{frame: 2, rotation: [0.1, 0, 0]}]}\n"
      "  bodies:\n"
      "    - {name: hand, box: {min: [0, -0.1, 0], max: [0.02, -0.05, 0.05]}, in_cloud: true,\n"
      "       keyframes: [{frame: 0}, {frame: 4, translation: [0.01, 0, 0]}], press: true,\n"
      "       contact_tolerance: 0.002}\n"
      "  artefacts: {flying_pixels: 0.3, multipath: {bias: 0.004, radius: 0.025},\n"
      "              grazing_holes: {blob_px: 4}, leave_view: {frames: 3, start: 2},\n"
      "              occluder: 0.015}\n";
  const std::string path = (fs::path(dir_.path()) / "synth.yaml").string();
  std::ofstream(path) << text;
  Scene scene;
  const Status status = LoadScene(path, &scene);
  ASSERT_TRUE(status.ok()) << status.message();
  ASSERT_TRUE(scene.synth.enabled);
  ASSERT_EQ(scene.synth.motion.size(), 2u);
  EXPECT_EQ(scene.synth.sensor.artefacts.hole_blob_px, 4);
  EXPECT_EQ(scene.synth.leave_start, 2);
  RoundTrip(scene, dir_.path());
  // Every artefact on, at values that are not round.
  for (const SynthArtefactKey& k : SynthArtefactKeys()) {
    k.set(&scene.synth, k.integer ? k.realistic + 1 : k.realistic * 0.7);
  }
  RoundTrip(scene, dir_.path());

  // The other two ways to give the ground truth mesh.
  scene.synth.mesh_path.clear();
  scene.synth.refinement = 3;
  RoundTrip(scene, dir_.path());
  scene.synth.refinement = 1;
  scene.synth.generate.shape = MeshGeneratorSpec::Shape::kCylinder;
  scene.synth.generate.radius = 0.01;
  scene.synth.generate.length = 0.2;
  RoundTrip(scene, dir_.path());
}

TEST_F(SceneWriterTest, NumbersBuiltInCodeReadBackExactly) {
  Scene scene;
  ObjectSpec object;
  object.name = "block";
  object.generate.shape = MeshGeneratorSpec::Shape::kBox;
  object.generate.size = Eigen::Vector3d(0.1 + 0.2, 1.0 / 3.0, 2e-7);
  object.generate.cells = Eigen::Vector3i(3, 2, 1);
  object.translation = Eigen::Vector3d(-0.0, 1e-300, 6.02214076e23);
  object.material.youngs_modulus = 1234567.89;
  object.material.density = 0.000123;
  scene.objects.push_back(object);
  AnchorSpec anchor;
  anchor.name = "a";
  anchor.object = "block";
  anchor.selection.kind = VertexSelection::Kind::kAll;
  for (int f = 0; f < 5; ++f) anchor.translations.emplace_back(0.0015 * f, -0.007 * f / 11, std::sqrt(f));
  scene.anchors.push_back(anchor);
  RoundTrip(scene, "");
  // The numbers are written short where they can be.
  const std::string text = SceneToYaml(scene);
  EXPECT_NE(text.find("[0.30000000000000004, 0.3333333333333333, 2.0e-7]"), std::string::npos) << text;
  EXPECT_NE(text.find("youngs_modulus: 1234567.89"), std::string::npos) << text;
  EXPECT_NE(text.find("density: 0.000123"), std::string::npos) << text;
  EXPECT_NE(text.find("[-0, 1.0e-300, 6.02214076e+23]"), std::string::npos) << text;
}

TEST_F(SceneWriterTest, WritesOnlyWhatDiffersFromTheDefaults) {
  Scene scene;
  ObjectSpec object;
  object.name = "cube";
  object.generate.shape = MeshGeneratorSpec::Shape::kBox;
  object.generate.cells = Eigen::Vector3i(2, 2, 2);
  scene.objects.push_back(object);
  EXPECT_EQ(SceneToYaml(scene),
            "objects:\n"
            "  - name: cube\n"
            "    generate: {shape: box, size: [1, 1, 1], cells: [2, 2, 2]}\n");
  scene.description = "a cube: the defaults";
  EXPECT_EQ(SceneToYaml(scene, "", "made by hand"),
            "# made by hand\n"
            "description: \"a cube: the defaults\"\n"
            "objects:\n"
            "  - name: cube\n"
            "    generate: {shape: box, size: [1, 1, 1], cells: [2, 2, 2]}\n");
  RoundTrip(scene, "");
  scene.description.clear();
  scene.registration.data.visibility = true;
  scene.registration.solver.max_outer_iterations = 12;
  scene.registration.solver.preconditioner = Preconditioner::kMultigrid;
  scene.effects.fracture = true;
  AnchorSpec anchor;
  anchor.name = "base";
  anchor.object = "cube";  // the only object: left out
  anchor.selection.kind = VertexSelection::Kind::kBox;
  anchor.selection.box_min = Eigen::Vector3d(-1, -1, -1);
  anchor.selection.box_max = Eigen::Vector3d(1, 1, 0.001);
  anchor.hard = true;
  scene.anchors.push_back(anchor);
  EXPECT_EQ(SceneToYaml(scene),
            "objects:\n"
            "  - name: cube\n"
            "    generate: {shape: box, size: [1, 1, 1], cells: [2, 2, 2]}\n"
            "registration:\n"
            "  data: {visibility: true}\n"
            "  solver: {max_outer_iterations: 12, preconditioner: multigrid}\n"
            "anchors:\n"
            "  - {name: base, select: {box: {min: [-1, -1, -1], max: [1, 1, 0.001]}}, hard: true}\n"
            "effects: {fracture: true}\n");
  RoundTrip(scene, "");
}

// Every bundled scene reads back the same after writing, every entry of its lists by its
// table, and writes the same text again.
TEST(SceneWriterBundled, EveryBundledSceneReadsBackTheSame) {
  int checked = 0;
  for (const auto& entry : fs::directory_iterator(FEMREG_DATASETS_DIR)) {
    for (const char* name : {"scene.yaml", "synth.yaml", "beam.yaml"}) {
      const fs::path path = entry.path() / name;
      if (!fs::is_regular_file(path)) continue;
      SCOPED_TRACE(path.string());
      Scene scene;
      const Status status = LoadScene(path.string(), &scene);
      ASSERT_TRUE(status.ok()) << status.message();
      const Scene back = RoundTrip(scene, entry.path().string());
      EXPECT_EQ(SceneToYaml(scene, entry.path().string()), SceneToYaml(back, entry.path().string()));
      ++checked;
    }
  }
  EXPECT_GE(checked, 16);
}

}  // namespace
}  // namespace femreg
