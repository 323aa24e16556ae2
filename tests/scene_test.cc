#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

#include "femreg/io.h"
#include "femreg/scene.h"
#include "femreg_test_config.h"
#include "test_util.h"

namespace femreg {
namespace {

namespace fs = std::filesystem;

// A fresh folder per test under the system temp folder.
class SceneTest : public ::testing::Test {
 protected:
  void SetUp() override {
    const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
    dir_ = fs::temp_directory_path() /
           (std::string("femreg_scene_test_") + info->name() + "_" + std::to_string(::getpid()));
    fs::remove_all(dir_);
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }

  // Writes `text` to dir/beam.yaml and loads it.
  Status Load(const std::string& text, Scene* scene) {
    const std::string path = (dir_ / "beam.yaml").string();
    std::ofstream(path) << text;
    return LoadScene(path, scene);
  }
  // Expects loading to fail with a message containing every part.
  void ExpectError(const std::string& text, const std::vector<std::string>& parts) {
    Scene scene;
    const Status status = Load(text, &scene);
    ASSERT_FALSE(status.ok()) << "expected an error for:\n" << text;
    for (const std::string& part : parts) {
      EXPECT_NE(status.message().find(part), std::string::npos)
          << "message: " << status.message() << "\nmissing: " << part;
    }
  }

  fs::path dir_;
};

// Line numbers matter in the tests below: line 1 is "objects:".
const char kBaseScene[] =
    "objects:\n"                                                                   // 1
    "  - name: beam\n"                                                             // 2
    "    generate: {shape: box, size: [1, 0.1, 0.1], cells: [10, 1, 1]}\n"         // 3
    "    material:\n"                                                              // 4
    "      youngs_modulus: 1e5\n"                                                  // 5
    "      poisson_ratio: 0.3\n"                                                   // 6
    "      density: 1000\n"                                                        // 7
    "boundary:\n"                                                                  // 8
    "  - {select: {box: {min: [0, 0, 0], max: [0, 0.1, 0.1]}}, clamp: true}\n";    // 9

std::string Replace(std::string text, const std::string& from, const std::string& to) {
  const size_t at = text.find(from);
  EXPECT_NE(at, std::string::npos) << from;
  if (at != std::string::npos) text.replace(at, from.size(), to);
  return text;
}

TEST_F(SceneTest, ParsesTheBaseScene) {
  Scene scene;
  const Status status = Load(kBaseScene, &scene);
  ASSERT_TRUE(status.ok()) << status.message();
  ASSERT_EQ(scene.objects.size(), 1u);
  EXPECT_EQ(scene.objects[0].name, "beam");
  EXPECT_EQ(scene.objects[0].generate.shape, MeshGeneratorSpec::Shape::kBox);
  EXPECT_EQ(scene.objects[0].generate.cells, Eigen::Vector3i(10, 1, 1));
  EXPECT_DOUBLE_EQ(scene.objects[0].material.youngs_modulus, 1e5);
  ASSERT_EQ(scene.boundary_conditions.size(), 1u);
  EXPECT_EQ(scene.boundary_conditions[0].object, "beam");  // filled in: one object
  EXPECT_EQ(scene.boundary_conditions[0].type, BoundaryConditionSpec::Type::kClamp);
  EXPECT_NE(scene.boundary_conditions[0].selection.where.find("beam.yaml:9 (boundary[0].select)"),
            std::string::npos)
      << scene.boundary_conditions[0].selection.where;
}

TEST_F(SceneTest, ParsesEverySection) {
  std::ofstream((dir_ / "cube.msh").string()) << "not read at parse time\n";
  const std::string text = R"(description: every section
objects:
  - name: beam
    generate: {shape: box, size: [1, 0.1, 0.1], cells: [10, 2, 2], origin: [0, -0.05, -0.05]}
    scale: 2
    pose: {translation: [1, 2, 3], rotation: [0, 0, 1.5707963267948966]}
    material: {youngs_modulus: 2e5, poisson_ratio: 0.25, density: 900}
    regions: {2: {youngs_modulus: 5e5}, 3: {density: 10}}
    toughness: 100
  - name: cube
    mesh: cube.msh
  - name: rod
    generate: {shape: cylinder, radius: 0.02, length: 0.5, cells: [2, 10]}
  - name: ball
    generate: {shape: sphere, radius: 0.1, cells: 3}
gravity: [0, 0, -9.81]
boundary:
  - {object: beam, select: {box: {min: [0, 0, 0], max: [0, 1, 1]}, tolerance: 1e-6}, clamp: true}
  - {object: beam, select: {plane: {point: [1, 0, 0], normal: [2, 0, 0]}}, displacement: [0, 0, 0.1]}
  - {object: cube, select: {indices: [1, 2, 3]}, clamp: true}
loads:
  - {object: rod, select: {all: true}, force: [0, 0, -1]}
forward: {model: linear, max_iterations: 7, load_steps: 3, tolerance: 1e-6, absolute_tolerance: 1e-9}
registration:
  regularizer: none
  camera: {position: [0, 0, -1], target: [0, 0, 0], up: [0, 1, 0], fx: 500, fy: 501, cx: 320, cy: 240, width: 640, height: 480}
  preprocess:
    crop: {min: [-1, -1, -1], max: [1, 1, 1]}
    voxel_size: 0.005
    outliers: {neighbors: 20, stddev: 2}
    normals: {neighbors: 12}
  data: {model_to_cloud: true, cloud_to_model: false, max_distance: 0.05, loss: cauchy,
         loss_scale: 0.01, metric: point_to_plane, visibility: true, cloud_stride: 2}
  weights: {data: 2, elastic: 3, temporal: 4, anchor: 5}
  solver: {max_outer_iterations: 6, max_inner_iterations: 7, relative_energy_tolerance: 1e-5,
           bulk_step_tolerance: 0.1, time_budget_s: 0.1, trust_region: dogleg,
           linear_solver: sparse_normal_cholesky,
           threads: 2, rigid_prealign: true, rigid_iterations: 30, predict_motion: false}
anchors:
  - {name: gripper, object: beam, select: {indices: [0]}, hard: true, weight: 1e3,
     translations: [[0, 0, 0], [0, 0, 0.01]]}
effects: {fracture: false, collision: false}
)";
  Scene scene;
  const Status status = Load(text, &scene);
  ASSERT_TRUE(status.ok()) << status.message();
  ASSERT_EQ(scene.objects.size(), 4u);
  const ObjectSpec& beam = scene.objects[0];
  EXPECT_EQ(beam.generate.origin, Eigen::Vector3d(0, -0.05, -0.05));
  EXPECT_DOUBLE_EQ(beam.scale, 2);
  EXPECT_EQ(beam.translation, Eigen::Vector3d(1, 2, 3));
  EXPECT_NEAR(beam.rotation.z(), M_PI / 2, 1e-12);
  EXPECT_DOUBLE_EQ(beam.material.poisson_ratio, 0.25);
  ASSERT_EQ(beam.region_materials.size(), 2u);
  EXPECT_EQ(beam.region_materials[0].first, 2);
  EXPECT_DOUBLE_EQ(beam.region_materials[0].second.youngs_modulus, 5e5);
  EXPECT_DOUBLE_EQ(beam.region_materials[0].second.density, 900);  // inherited
  EXPECT_DOUBLE_EQ(beam.region_materials[1].second.youngs_modulus, 2e5);
  EXPECT_DOUBLE_EQ(beam.region_materials[1].second.density, 10);
  EXPECT_DOUBLE_EQ(beam.toughness, 100);
  EXPECT_EQ(scene.objects[1].mesh_path, (dir_ / "cube.msh").lexically_normal().string());
  EXPECT_EQ(scene.objects[2].generate.shape, MeshGeneratorSpec::Shape::kCylinder);
  EXPECT_EQ(scene.objects[2].generate.radial_cells, 2);
  EXPECT_EQ(scene.objects[2].generate.axial_cells, 10);
  EXPECT_EQ(scene.objects[3].generate.shape, MeshGeneratorSpec::Shape::kSphere);
  EXPECT_EQ(scene.objects[3].generate.radial_cells, 3);
  EXPECT_EQ(scene.gravity, Eigen::Vector3d(0, 0, -9.81));

  ASSERT_EQ(scene.boundary_conditions.size(), 3u);
  EXPECT_EQ(scene.boundary_conditions[0].selection.kind, VertexSelection::Kind::kBox);
  EXPECT_DOUBLE_EQ(scene.boundary_conditions[0].selection.tolerance, 1e-6);
  EXPECT_EQ(scene.boundary_conditions[1].type, BoundaryConditionSpec::Type::kDisplacement);
  EXPECT_EQ(scene.boundary_conditions[1].selection.plane_normal, Eigen::Vector3d(1, 0, 0));
  EXPECT_EQ(scene.boundary_conditions[1].displacement, Eigen::Vector3d(0, 0, 0.1));
  EXPECT_EQ(scene.boundary_conditions[2].selection.indices, (std::vector<int>{1, 2, 3}));
  ASSERT_EQ(scene.loads.size(), 1u);
  EXPECT_EQ(scene.loads[0].object, "rod");
  EXPECT_EQ(scene.loads[0].selection.kind, VertexSelection::Kind::kAll);

  EXPECT_EQ(scene.forward.model, ElasticModelType::kLinear);
  EXPECT_EQ(scene.forward.max_iterations, 7);
  EXPECT_EQ(scene.forward.load_steps, 3);
  EXPECT_DOUBLE_EQ(scene.forward.relative_tolerance, 1e-6);
  EXPECT_DOUBLE_EQ(scene.forward.absolute_tolerance, 1e-9);

  const RegistrationOptions& r = scene.registration;
  EXPECT_EQ(r.regularizer, Regularizer::kNone);
  EXPECT_TRUE(r.camera.enabled);
  EXPECT_DOUBLE_EQ(r.camera.fy, 501);
  EXPECT_EQ(r.camera.width, 640);
  EXPECT_TRUE(r.preprocess.crop);
  EXPECT_EQ(r.preprocess.crop_max, Eigen::Vector3d(1, 1, 1));
  EXPECT_DOUBLE_EQ(r.preprocess.voxel_size, 0.005);
  EXPECT_EQ(r.preprocess.outlier_neighbors, 20);
  EXPECT_DOUBLE_EQ(r.preprocess.outlier_stddev, 2);
  EXPECT_EQ(r.preprocess.normal_neighbors, 12);
  EXPECT_FALSE(r.data.cloud_to_model);
  EXPECT_EQ(r.data.loss, RobustLoss::kCauchy);
  EXPECT_EQ(r.data.metric, DataMetric::kPointToPlane);
  EXPECT_TRUE(r.data.visibility);
  EXPECT_EQ(r.data.cloud_stride, 2);
  EXPECT_DOUBLE_EQ(r.weights.temporal, 4);
  EXPECT_DOUBLE_EQ(r.weights.anchor, 5);
  EXPECT_EQ(r.solver.max_outer_iterations, 6);
  EXPECT_DOUBLE_EQ(r.solver.bulk_step_tolerance, 0.1);
  EXPECT_EQ(r.solver.trust_region, TrustRegion::kDogleg);
  EXPECT_EQ(r.solver.linear_solver, LinearSolver::kSparseNormalCholesky);
  EXPECT_EQ(r.solver.num_threads, 2);
  EXPECT_TRUE(r.solver.rigid_prealign);
  EXPECT_EQ(r.solver.rigid_iterations, 30);
  EXPECT_FALSE(r.solver.predict_motion);
  EXPECT_EQ(r.camera.target, Eigen::Vector3d(0, 0, 0));
  EXPECT_EQ(r.camera.up, Eigen::Vector3d(0, 1, 0));

  ASSERT_EQ(scene.anchors.size(), 1u);
  EXPECT_EQ(scene.anchors[0].name, "gripper");
  EXPECT_TRUE(scene.anchors[0].hard);
  EXPECT_DOUBLE_EQ(scene.anchors[0].weight, 1e3);
  ASSERT_EQ(scene.anchors[0].translations.size(), 2u);
  EXPECT_EQ(scene.anchors[0].translations[1], Eigen::Vector3d(0, 0, 0.01));
  EXPECT_FALSE(scene.effects.fracture);
}

// `data.visibility: false` written out turns the automatic test off too (with a camera in
// the scene it would otherwise still decide which vertices pull); unwritten, the automatic
// test stays on; written beside it, auto_visibility wins.
TEST_F(SceneTest, VisibilityFalseWrittenOutTurnsTheAutomaticTestOff) {
  const struct {
    const char* data;
    bool visibility, auto_visibility;
  } cases[] = {{"", false, true},
               {"registration: {data: {visibility: false}}\n", false, false},
               {"registration: {data: {visibility: true}}\n", true, true},
               {"registration: {data: {visibility: false, auto_visibility: true}}\n", false, true},
               {"registration: {data: {auto_visibility: false}}\n", false, false}};
  for (const auto& c : cases) {
    Scene scene;
    const Status status = Load(std::string(kBaseScene) + c.data, &scene);
    ASSERT_TRUE(status.ok()) << status.message();
    EXPECT_EQ(scene.registration.data.visibility, c.visibility) << c.data;
    EXPECT_EQ(scene.registration.data.auto_visibility, c.auto_visibility) << c.data;
  }
}

// The fast back end by default; Ceres' own settings without a backend select Ceres, and are
// refused beside `backend: fast` (they would do nothing there).
TEST_F(SceneTest, BackendDefaultsToFastAndCeresSettingsSelectCeres) {
  Scene scene;
  ASSERT_TRUE(Load(kBaseScene, &scene).ok());
  EXPECT_EQ(scene.registration.solver.backend, SolverBackend::kFast);
  for (const char* solver : {"{trust_region: dogleg}", "{linear_solver: conjugate_gradients}",
                             "{backend: ceres}"}) {
    ASSERT_TRUE(Load(std::string(kBaseScene) + "registration: {solver: " + solver + "}\n", &scene).ok())
        << solver;
    EXPECT_EQ(scene.registration.solver.backend, SolverBackend::kCeres) << solver;
  }
  ExpectError(std::string(kBaseScene) + "registration:\n  solver: {backend: fast, trust_region: dogleg}\n",
              {"beam.yaml:11: registration.solver.trust_region: is a setting of the Ceres back end"});
}

// The fast back end's preconditioner: auto unless the scene names one.
TEST_F(SceneTest, PreconditionerIsAutoUnlessNamed) {
  Scene scene;
  ASSERT_TRUE(Load(kBaseScene, &scene).ok());
  EXPECT_EQ(scene.registration.solver.preconditioner, Preconditioner::kAuto);
  ASSERT_TRUE(Load(std::string(kBaseScene) + "registration: {solver: {preconditioner: multigrid}}\n", &scene).ok());
  EXPECT_EQ(scene.registration.solver.preconditioner, Preconditioner::kMultigrid);
  ASSERT_TRUE(Load(std::string(kBaseScene) + "registration: {solver: {preconditioner: factor}}\n", &scene).ok());
  EXPECT_EQ(scene.registration.solver.preconditioner, Preconditioner::kFactor);
  ExpectError(std::string(kBaseScene) + "registration: {solver: {preconditioner: amg}}\n",
              {"registration.solver.preconditioner", "amg"});
}

// A bad value is quoted by its first 80 characters and its length, not echoed whole.
TEST_F(SceneTest, LongBadValuesAreQuotedShort) {
  const std::string big(100000, 'x');
  Scene scene;
  Status status = Load(Replace(kBaseScene, "youngs_modulus: 1e5", "youngs_modulus: " + big), &scene);
  ASSERT_FALSE(status.ok());
  EXPECT_LT(status.message().size(), 300u) << status.message().substr(0, 300);
  EXPECT_NE(status.message().find("(100000 bytes)"), std::string::npos) << status.message().substr(0, 300);
  status = Load(Replace(kBaseScene, "shape: box", "shape: " + big), &scene);
  ASSERT_FALSE(status.ok());
  EXPECT_LT(status.message().size(), 400u) << status.message().substr(0, 400);
  status = Load(big, &scene);  // a document that is not a map
  ASSERT_FALSE(status.ok());
  EXPECT_LT(status.message().size(), 300u) << status.message().substr(0, 300);
}

TEST_F(SceneTest, UnknownKeySuggestsTheClosest) {
  ExpectError(Replace(kBaseScene, "poisson_ratio", "poison_ratio"),
              {"beam.yaml:6: objects[0].material.poison_ratio: unknown key",
               "did you mean 'poisson_ratio'?"});
  ExpectError(std::string(kBaseScene) + "gravty: [0, 0, -9.81]\n",
              {"beam.yaml:10: gravty: unknown key (did you mean 'gravity'?)"});
  // Nothing close: the allowed keys are listed.
  ExpectError(std::string(kBaseScene) + "zzzzzzzz: 1\n",
              {"beam.yaml:10: zzzzzzzz: unknown key (allowed: description, objects"});
}

TEST_F(SceneTest, WrongTypes) {
  ExpectError(Replace(kBaseScene, "youngs_modulus: 1e5", "youngs_modulus: soft"),
              {"beam.yaml:5: objects[0].material.youngs_modulus: must be a number (got 'soft')"});
  ExpectError(Replace(kBaseScene, "size: [1, 0.1, 0.1]", "size: [1, 0.1]"),
              {"beam.yaml:3: objects[0].generate.size: must be a list of 3 numbers",
               "(got a list of 2)"});
  ExpectError(Replace(kBaseScene, "clamp: true", "clamp: maybe"),
              {"beam.yaml:9: boundary[0].clamp: must be true or false (got 'maybe')"});
  ExpectError(std::string(kBaseScene) + "registration:\n  preprocess: {depth_offset: 2}\n",
              {"beam.yaml:11: registration.preprocess.depth_offset: must be true or false (got '2')"});
  ExpectError(Replace(kBaseScene, "cells: [10, 1, 1]", "cells: [10, 1.5, 1]"),
              {"beam.yaml:3: objects[0].generate.cells[1]: must be an integer (got '1.5')"});
  ExpectError(Replace(kBaseScene, "boundary:\n  - {", "boundary:\n    {"),
              {"beam.yaml:9: boundary: must be a list"});
}

TEST_F(SceneTest, PoissonRatioAtOrAboveOneHalf) {
  ExpectError(Replace(kBaseScene, "poisson_ratio: 0.3", "poisson_ratio: 0.5"),
              {"beam.yaml:6: objects[0].material.poisson_ratio: must be in (-1, 0.5) (got 0.5)"});
}

TEST_F(SceneTest, PoissonRatioAtOrBelowMinusOne) {
  ExpectError(Replace(kBaseScene, "poisson_ratio: 0.3", "poisson_ratio: -1"),
              {"beam.yaml:6: objects[0].material.poisson_ratio: must be in (-1, 0.5) (got -1)"});
}

TEST_F(SceneTest, NonPositiveYoungsModulusAndDensity) {
  ExpectError(Replace(kBaseScene, "youngs_modulus: 1e5", "youngs_modulus: 0"),
              {"beam.yaml:5: objects[0].material.youngs_modulus: must be > 0 (got 0)"});
  ExpectError(Replace(kBaseScene, "density: 1000", "density: -3"),
              {"beam.yaml:7: objects[0].material.density: must be > 0 (got -3)"});
}

TEST_F(SceneTest, MissingMeshFile) {
  ExpectError(Replace(kBaseScene, "generate: {shape: box, size: [1, 0.1, 0.1], cells: [10, 1, 1]}",
                      "mesh: missing.msh"),
              {"beam.yaml:3: objects[0].mesh: mesh file not found: ",
               (dir_ / "missing.msh").string()});
}

TEST_F(SceneTest, DuplicateObjectNames) {
  ExpectError(Replace(kBaseScene, "boundary:",
                      "  - name: beam\n    generate: {shape: sphere}\nboundary:"),
              {"beam.yaml:8: objects[1].name: duplicate object name 'beam'"});
}

TEST_F(SceneTest, SelectionThatPicksNoVertex) {
  Scene scene;
  const Status status =
      Load(Replace(kBaseScene, "max: [0, 0.1, 0.1]", "max: [0, 0.1, 0.1]}}, clamp: true}\n"
                                                     "  - {select: {box: {min: [5, 5, 5], max: [6, 6, 6]"),
           &scene);
  ASSERT_TRUE(status.ok()) << status.message();
  TetMesh mesh;
  mesh.rest.resize(3, 3);
  mesh.rest << 0, 0, 0, 1, 0, 0, 0, 1, 0;
  ForwardProblem problem;
  const Status built = BuildForwardProblem(scene, 0, mesh, &problem);
  ASSERT_FALSE(built.ok());
  EXPECT_NE(built.message().find("beam.yaml:10 (boundary[1].select): the selection picks no vertex"),
            std::string::npos)
      << built.message();
}

TEST_F(SceneTest, UnknownOrMissingObjectName) {
  ExpectError(Replace(kBaseScene, "{select:", "{object: bean, select:"),
              {"beam.yaml:9: boundary[0].object: unknown object 'bean' (did you mean 'beam'?"});
  ExpectError(Replace(kBaseScene, "boundary:",
                      "  - name: ball\n    generate: {shape: sphere}\nboundary:"),
              {"beam.yaml:11: boundary[0]: needs 'object' when the scene has several objects "
               "(beam, ball)"});
}

TEST_F(SceneTest, InvalidFractureAndCollisionSettings) {
  ExpectError(std::string(kBaseScene) + "effects: {fracture: {max_splits_per_frame: 0}}\n",
              {"beam.yaml:10: effects.fracture.max_splits_per_frame: must be >= 1"});
  ExpectError(std::string(kBaseScene) + "effects: {fracture: {cut_through: 2}}\n",
              {"beam.yaml:10: effects.fracture.cut_through: must be true or false"});
  ExpectError(std::string(kBaseScene) + "effects: {fracture: {relax_piece: true}}\n",
              {"relax_piece", "relax_pieces"});
  ExpectError(std::string(kBaseScene) + "collision: {distance: 0}\n",
              {"beam.yaml:10: collision.distance: must be > 0 (got 0)"});
}

TEST_F(SceneTest, InvalidRegistrationOptions) {
  ExpectError(std::string(kBaseScene) + "registration:\n  data:\n    loss: foo\n",
              {"beam.yaml:12: registration.data.loss: unknown value 'foo'",
               "one of: huber, cauchy, tukey, none"});
  ExpectError(std::string(kBaseScene) + "registration:\n  data: {loss: hubber}\n",
              {"beam.yaml:11: registration.data.loss: unknown value 'hubber' (did you mean "
               "'huber'?"});
  ExpectError(std::string(kBaseScene) + "registration:\n  initial_pose: global\n",
              {"beam.yaml:11: registration.initial_pose: unknown value 'global'",
               "one of: given, auto"});
  ExpectError(std::string(kBaseScene) + "registration:\n  data:\n    loss_scale: -1\n",
              {"beam.yaml:12: registration.data.loss_scale: must be > 0 (got -1)"});
  ExpectError(std::string(kBaseScene) + "registration:\n  camera:\n    position: [0, 0, 1]\n",
              {"beam.yaml:12: registration.camera.target: must differ from camera.position"});
  ExpectError(std::string(kBaseScene) + "registration:\n  solver:\n    bulk_step_tolerance: -1\n",
              {"beam.yaml:12: registration.solver.bulk_step_tolerance: must be >= 0 (a fraction of "
               "the mean edge length; 0 = off) (got -1)"});
  ExpectError(std::string(kBaseScene) + "registration:\n  solver:\n    threads: -1\n",
              {"beam.yaml:12: registration.solver.threads: must be >= 0 (0: the cores other processes leave free, per frame) (got -1)"});
}

TEST_F(SceneTest, SyntaxErrorNamesTheLine) {
  ExpectError(std::string(kBaseScene) + "gravity: [0, 0\n", {"beam.yaml:1"});
  ExpectError(std::string(kBaseScene) + "loads:\n  - {force: [0, 0, 1}\n", {"beam.yaml:11"});
}

TEST_F(SceneTest, MissingSceneFile) {
  Scene scene;
  const Status status = LoadScene((dir_ / "nope.yaml").string(), &scene);
  ASSERT_FALSE(status.ok());
  EXPECT_NE(status.message().find("nope.yaml"), std::string::npos);
}

TEST_F(SceneTest, ForwardProblemSpreadsLoadsAndRejectsConflicts) {
  const std::string text = std::string(kBaseScene) +
                           "  - {select: {indices: [2]}, displacement: [0, 0, 0.5]}\n"  // 10
                           "loads:\n"
                           "  - {select: {plane: {point: [2, 0, 0], normal: [1, 0, 0]}}, "
                           "force: [0, 0, -9]}\n"
                           "gravity: [0, 0, -1]\n";
  Scene scene;
  ASSERT_TRUE(Load(text, &scene).ok());
  TetMesh mesh;
  mesh.rest = testing_util::Grid();
  ForwardProblem problem;
  Status status = BuildForwardProblem(scene, 0, mesh, &problem);
  ASSERT_TRUE(status.ok()) << status.message();
  EXPECT_EQ(problem.gravity, Eigen::Vector3d(0, 0, -1));
  // The first box picks x = 0, y <= 0.1, z <= 0.1: vertex 0 only.
  EXPECT_EQ(problem.clamped, (std::vector<int>{0}));
  ASSERT_EQ(problem.prescribed.size(), 1u);
  EXPECT_EQ(problem.prescribed[0].first, 2);
  ASSERT_EQ(problem.nodal_loads.size(), 9u);
  Eigen::Vector3d total = Eigen::Vector3d::Zero();
  for (const auto& [v, f] : problem.nodal_loads) {
    EXPECT_EQ(v % 3, 2);
    EXPECT_NEAR(f.z(), -1.0, 1e-12);
    total += f;
  }
  EXPECT_NEAR(total.z(), -9.0, 1e-12);

  // Vertex 0 clamped by boundary[0] and displaced by boundary[1].
  ASSERT_TRUE(Load(Replace(text, "indices: [2]", "indices: [2, 0]"), &scene).ok());
  status = BuildForwardProblem(scene, 0, mesh, &problem);
  ASSERT_FALSE(status.ok());
  EXPECT_NE(status.message().find("vertex 0"), std::string::npos) << status.message();
  EXPECT_NE(status.message().find("beam.yaml:9 (boundary[0].select)"), std::string::npos)
      << status.message();
  EXPECT_NE(status.message().find("beam.yaml:10 (boundary[1].select)"), std::string::npos)
      << status.message();
}

TEST_F(SceneTest, LoadObjectMeshPosesAndWeighs) {
  const std::string text = Replace(
      kBaseScene, "    material:",
      "    scale: 2\n    pose: {translation: [1, 0, 0], rotation: [0, 0, 1.5707963267948966]}\n"
      "    material:");
  Scene scene;
  ASSERT_TRUE(Load(text, &scene).ok());
  TetMesh mesh;
  const Status status = LoadObjectMesh(scene, 0, &mesh);
  ASSERT_TRUE(status.ok()) << status.message();
  // The box [0,1] x [0,0.1] x [0,0.1], scaled by 2 and turned by 90 degrees about z, then
  // moved by +1 in x: x in [0.8, 1], y in [0, 2], z in [0, 0.2].
  const Eigen::Vector3d lo = mesh.rest.colwise().minCoeff().transpose();
  const Eigen::Vector3d hi = mesh.rest.colwise().maxCoeff().transpose();
  EXPECT_LT((lo - Eigen::Vector3d(0.8, 0, 0)).norm(), 1e-9) << lo.transpose();
  EXPECT_LT((hi - Eigen::Vector3d(1, 2, 0.2)).norm(), 1e-9) << hi.transpose();
  EXPECT_EQ(mesh.x, mesh.rest);
  // Mass = density * volume = 1000 * (2 * 0.2 * 0.2).
  EXPECT_NEAR(mesh.mass.sum(), 1000 * 0.08, 1e-9);
}

TEST_F(SceneTest, LoadObjectMeshReadsAFileWithRegionDensities) {
  fs::create_directories(dir_ / "meshes");
  std::ofstream((dir_ / "meshes" / "tet.msh").string())
      << "$MeshFormat\n2.2 0 8\n$EndMeshFormat\n$Nodes\n4\n1 0 0 0\n2 1 0 0\n3 0 1 0\n"
         "4 0 0 1\n$EndNodes\n$Elements\n1\n1 4 2 7 7 1 2 3 4\n$EndElements\n";
  const std::string text =
      "objects:\n"
      "  - {name: tet, mesh: meshes/tet.msh, scale: 0.5, material: {density: 1000},\n"
      "     regions: {7: {density: 600}}}\n";
  Scene scene;
  Status status = Load(text, &scene);
  ASSERT_TRUE(status.ok()) << status.message();
  TetMesh mesh;
  status = LoadObjectMesh(scene, 0, &mesh);
  ASSERT_TRUE(status.ok()) << status.message();
  ASSERT_EQ(mesh.num_tets(), 1);
  EXPECT_EQ(mesh.region(0), 7);
  EXPECT_LT((mesh.rest.colwise().maxCoeff().transpose() - Eigen::Vector3d(0.5, 0.5, 0.5)).norm(),
            1e-12);
  // Region 7's density, on the scaled volume 0.5^3 / 6.
  EXPECT_NEAR(mesh.mass.sum(), 600 * 0.125 / 6, 1e-12);

  // A mesh file that exists but is broken: the error names the object and the file.
  std::ofstream((dir_ / "meshes" / "tet.msh").string()) << "$MeshFormat\n2.2 0 8\n";
  status = LoadObjectMesh(scene, 0, &mesh);
  ASSERT_FALSE(status.ok());
  EXPECT_NE(status.message().find("objects[0] (tet)"), std::string::npos) << status.message();
  EXPECT_NE(status.message().find("tet.msh"), std::string::npos) << status.message();
}

#ifdef FEMREG_CLI_PATH
// Runs a shell command and returns its exit status.
int RunCommand(const std::string& command) {
  const int status = std::system(command.c_str());
  return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
}

TEST_F(SceneTest, SimulateTheBundledBeam) {
  const std::string out = (dir_ / "out").string();
  const std::string scene = std::string(FEMREG_DATASETS_DIR) + "/beam/beam.yaml";
  const std::string command = std::string(FEMREG_CLI_PATH) + " simulate " + scene + " --out " + out;
  ASSERT_EQ(RunCommand(command + " > " + (dir_ / "log.txt").string() + " 2>&1"), 0)
      << std::ifstream((dir_ / "log.txt").string()).rdbuf();
  EXPECT_TRUE(fs::is_regular_file(fs::path(out) / "beam.vtu"));
  ASSERT_TRUE(fs::is_regular_file(fs::path(out) / "summary.json"));
  std::stringstream summary;
  summary << std::ifstream((fs::path(out) / "summary.json").string()).rdbuf();
  EXPECT_NE(summary.str().find("\"ok\": true"), std::string::npos) << summary.str();
  EXPECT_NE(summary.str().find("\"termination\": "), std::string::npos) << summary.str();
  EXPECT_NE(summary.str().find("\"max_displacement\": "), std::string::npos) << summary.str();

  // The folder is no longer empty: a second run refuses without --force.
  EXPECT_EQ(RunCommand(command + " > /dev/null 2> " + (dir_ / "err.txt").string()), 1);
  std::stringstream err;
  err << std::ifstream((dir_ / "err.txt").string()).rdbuf();
  EXPECT_NE(err.str().find("--force"), std::string::npos) << err.str();
  EXPECT_EQ(RunCommand(command + " --force > /dev/null 2>&1"), 0);
}

TEST_F(SceneTest, SimulateReportsSceneErrors) {
  std::ofstream((dir_ / "bad.yaml").string()) << Replace(kBaseScene, "poisson_ratio: 0.3",
                                                         "poisson_ratio: 0.5");
  const std::string command = std::string(FEMREG_CLI_PATH) + " simulate " +
                              (dir_ / "bad.yaml").string() + " --out " +
                              (dir_ / "out").string() + " > /dev/null 2> " +
                              (dir_ / "err.txt").string();
  EXPECT_EQ(RunCommand(command), 1);
  std::stringstream err;
  err << std::ifstream((dir_ / "err.txt").string()).rdbuf();
  EXPECT_NE(err.str().find("bad.yaml:6: objects[0].material.poisson_ratio: must be in (-1, 0.5)"),
            std::string::npos)
      << err.str();
}
#endif  // FEMREG_CLI_PATH

}  // namespace
}  // namespace femreg
