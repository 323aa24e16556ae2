// The virtual depth camera, the scene's synth section and femreg synth: noise model, z-buffer
// occlusion, grazing drop-outs, validation messages, and the bundled datasets regenerating
// from their seeds (within tolerances that hold across CPUs).
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <unistd.h>

#include "femreg/datasets.h"
#include "femreg/ground_truth.h"
#include "femreg/io.h"
#include "femreg/scene.h"
#include "femreg/synth.h"
#include "femreg_test_config.h"
#include "regenerate_compare.h"
#include "synth_samples.h"
#include "test_util.h"

namespace fs = std::filesystem;

namespace femreg {
namespace {

using testing_util::AxisSensor;
using testing_util::BarSynthScene;

class TempDir : public testing_util::TempDir {
 public:
  TempDir() : testing_util::TempDir("femreg_synth_test") {}
};

// A square of edge `size` at depth z facing the camera, tilted by `tilt` about the y axis.
void Square(double z, double size, double tilt, Vertices* points, Triangles* triangles) {
  const double h = 0.5 * size;
  points->resize(4, 3);
  const Eigen::Vector3d a(std::cos(tilt) * h, 0, std::sin(tilt) * h);
  *points << -a.x(), -h, z - a.z(), a.x(), -h, z + a.z(), a.x(), h, z + a.z(), -a.x(), h, z - a.z();
  triangles->resize(2, 3);
  *triangles << 0, 1, 2, 0, 2, 3;
}

void Box(const Eigen::Vector3d& lo, const Eigen::Vector3d& hi, Vertices* points, Triangles* triangles) {
  TetMesh m = MakeBox(hi - lo, 1, 1, 1, lo);
  *points = m.rest;
  *triangles = m.surface;
}

TEST(DepthSensorTest, PlaneAtKnownDepthHasTheNoiseModelsSpread) {
  DepthSensorOptions options = AxisSensor();
  options.noise_coefficient = 2.85e-3;
  const DepthSensor sensor(options);
  Vertices points;
  Triangles triangles;
  const double z = 1.2;
  Square(z, 10.0, 0.0, &points, &triangles);  // fills the view
  const std::vector<RenderSurface> surfaces = {{&points, &triangles}};
  const DepthImage image = sensor.Render(surfaces);
  const PointCloud cloud = sensor.Sample(image, surfaces, 7);
  ASSERT_EQ(cloud.size(), options.camera.width * options.camera.height);
  const double mean = cloud.points.col(2).mean();
  const double sd = std::sqrt((cloud.points.col(2).array() - mean).square().mean());
  const double sigma = options.noise_coefficient * z * z;  // 4.1 mm
  EXPECT_NEAR(mean, z, 4 * sigma / std::sqrt(cloud.size()));
  EXPECT_NEAR(sd, sigma, 0.05 * sigma);

  // Noiseless: exactly on the plane.
  options.noise_coefficient = 0.0;
  const DepthSensor exact(options);
  const PointCloud flat = exact.Sample(exact.Render(surfaces), surfaces, 7);
  EXPECT_NEAR((flat.points.col(2).array() - z).abs().maxCoeff(), 0.0, 1e-6);
}

TEST(DepthSensorTest, ABoxBehindAnotherIsHidden) {
  DepthSensorOptions options = AxisSensor();
  options.noise_coefficient = 0.0;
  const DepthSensor sensor(options);
  Vertices front_points, back_points;
  Triangles front_triangles, back_triangles;
  Box(Eigen::Vector3d(-0.2, -0.2, 0.8), Eigen::Vector3d(0.2, 0.2, 0.9), &front_points, &front_triangles);
  Box(Eigen::Vector3d(-0.1, -0.1, 1.2), Eigen::Vector3d(0.1, 0.1, 1.3), &back_points, &back_triangles);
  const std::vector<RenderSurface> surfaces = {{&back_points, &back_triangles},
                                               {&front_points, &front_triangles}};
  const DepthImage image = sensor.Render(surfaces);
  const PointCloud cloud = sensor.Sample(image, surfaces, 1);
  ASSERT_GT(cloud.size(), 100);
  EXPECT_LT(cloud.points.col(2).maxCoeff(), 0.8 + 1e-6);  // only the front face
  const std::vector<char> back_seen = sensor.Visible(image, back_points, 2e-3);
  for (char seen : back_seen) EXPECT_FALSE(seen);
  const std::vector<char> front_seen = sensor.Visible(image, front_points, 2e-3);
  int seen = 0;
  for (int v = 0; v < front_points.rows(); ++v) {
    if (front_points(v, 2) < 0.85) {
      EXPECT_TRUE(front_seen[v]) << "front-face vertex " << v;
    } else {
      seen += front_seen[v];
    }
  }
  EXPECT_EQ(seen, 0);  // the back corners of the front box

  // Without the back box in the image, it returns points; a masked occluder (returns = false)
  // still hides it but adds none.
  const std::vector<RenderSurface> alone = {{&back_points, &back_triangles}};
  EXPECT_GT(sensor.Sample(sensor.Render(alone), alone, 1).size(), 100);
  const std::vector<RenderSurface> masked = {{&back_points, &back_triangles},
                                             {&front_points, &front_triangles, false}};
  EXPECT_EQ(sensor.Sample(sensor.Render(masked), masked, 1).size(), 0);
}

TEST(DepthSensorTest, GrazingSurfacesDropOut) {
  DepthSensorOptions options = AxisSensor();
  options.noise_coefficient = 0.0;
  options.grazing_angle_deg = 80.0;
  Vertices points;
  Triangles triangles;
  const double kDeg = M_PI / 180.0;
  // Tilted by 85 degrees: the rays near the axis meet it at about 85 degrees incidence.
  Square(1.0, 0.5, 85 * kDeg, &points, &triangles);
  const std::vector<RenderSurface> surfaces = {{&points, &triangles}};
  const DepthSensor sensor(options);
  const DepthImage image = sensor.Render(surfaces);
  int hit = 0;
  for (int t : image.triangle) hit += t >= 0;
  ASSERT_GT(hit, 20);  // the z-buffer sees it...
  EXPECT_EQ(sensor.Sample(image, surfaces, 1).size(), 0);  // ...the sensor returns nothing
  options.grazing_angle_deg = 89.9;
  const DepthSensor tolerant(options);
  EXPECT_GT(tolerant.Sample(image, surfaces, 1).size(), 20);
  // Tilted by 30 degrees: all returned.
  Square(1.0, 0.5, 30 * kDeg, &points, &triangles);
  const DepthImage facing = sensor.Render(surfaces);
  int facing_hit = 0;
  for (int t : facing.triangle) facing_hit += t >= 0;
  EXPECT_EQ(sensor.Sample(facing, surfaces, 1).size(), facing_hit);
}


std::string ParseError(const std::string& text) {
  Scene scene;
  const Status status = ParseScene(text, "synth.yaml", "", &scene);
  return status.ok() ? std::string("(no error)") : status.message();
}

TEST(SynthSceneTest, ParsesTheSection) {
  Scene scene;
  const Status status = ParseScene(
      BarSynthScene("  frames: 7\n"
                 "  seed: 3\n"
                 "  ground_truth: {refinement: 2, material: {poisson_ratio: 0.4}}\n"
                 "  sensor: {pixel_stride: 2, noise_coefficient: 0.001}\n"
                 "  background: {point: [0, 0, -0.01], normal: [0, 0, 1], size: 0.5}\n"
                 "  motion:\n"
                 "    - {name: end, select: {box: {min: [0.0999, -1, -1], max: [1, 1, 1]}},\n"
                 "       anchor: hard, keyframes: [{frame: 0}, {frame: 6, translation: [0, 0, 0.01]}]}\n"
                 "  bodies:\n"
                 "    - {name: hand, box: {min: [0, -0.1, 0], max: [0.02, -0.05, 0.05]}, in_cloud: true}\n"),
      "synth.yaml", "", &scene);
  ASSERT_TRUE(status.ok()) << status.message();
  const SynthSpec& s = scene.synth;
  EXPECT_TRUE(s.enabled);
  EXPECT_EQ(s.frames, 7);
  EXPECT_EQ(s.seed, 3u);
  EXPECT_EQ(s.refinement, 2);
  EXPECT_EQ(s.material.poisson_ratio, 0.4);
  EXPECT_EQ(s.material.youngs_modulus, 1e5);  // inherited
  EXPECT_EQ(s.sensor.pixel_stride, 2);
  EXPECT_TRUE(s.sensor.camera.enabled);
  EXPECT_EQ(s.sensor.camera.width, 80);
  EXPECT_TRUE(s.background);
  ASSERT_EQ(s.motion.size(), 1u);
  EXPECT_EQ(s.motion[0].anchor, MotionTrackSpec::Anchor::kHard);
  ASSERT_EQ(s.bodies.size(), 1u);
  EXPECT_TRUE(s.bodies[0].in_cloud);
  // The tracking scene: no synth or boundary keys, an anchor per known gripper.
  const std::string tracking_yaml = SceneToYaml(SynthTrackingScene(scene, ""));
  EXPECT_EQ(tracking_yaml.find("synth:"), std::string::npos);
  EXPECT_EQ(tracking_yaml.find("boundary"), std::string::npos);
  EXPECT_NE(tracking_yaml.find("name: end"), std::string::npos);
  Scene tracking;
  const Status reparsed = ParseScene(tracking_yaml, "scene.yaml", "", &tracking);
  ASSERT_TRUE(reparsed.ok()) << reparsed.message() << "\n" << tracking_yaml;
  ASSERT_EQ(tracking.anchors.size(), 1u);
  EXPECT_TRUE(tracking.anchors[0].hard);
  ASSERT_EQ(tracking.anchors[0].translations.size(), 7u);
  EXPECT_NEAR(tracking.anchors[0].translations[3].z(), 0.005, 1e-12);

  Eigen::Vector3d t, r;
  InterpolateKeyframes(s.motion[0].keyframes, 100, &t, &r);  // held after the last
  EXPECT_NEAR(t.z(), 0.01, 1e-15);
}

TEST(SynthSceneTest, ErrorsNameTheFileLineAndKey) {
  EXPECT_EQ(ParseError(BarSynthScene("  frames: 5\n  ground_truth: {refinement: 2}\n  sede: 3\n")),
            "synth.yaml:13: synth.sede: unknown key (did you mean 'seed'?)");
  EXPECT_EQ(ParseError(BarSynthScene("  frames: 0\n  ground_truth: {refinement: 2}\n")),
            "synth.yaml:11: synth.frames: must be >= 1 (got 0)");
  EXPECT_EQ(ParseError(BarSynthScene("  ground_truth: {refinement: 2}\n  sensor: {pixel_stride: 0}\n")),
            "synth.yaml:12: synth.sensor.pixel_stride: must be >= 1 (got 0)");
  EXPECT_EQ(ParseError(BarSynthScene("  ground_truth: {refinement: 2}\n"
                                  "  sensor: {grazing_angle_deg: 95}\n")),
            "synth.yaml:12: synth.sensor.grazing_angle_deg: must be in (0, 90] (got 95)");
  // The tracked mesh and material: an inverse crime unless labelled.
  EXPECT_NE(ParseError(BarSynthScene("  frames: 3\n")).find("synth.yaml:11: synth: the ground truth "
                                                        "would come from the tracked mesh"),
            std::string::npos);
  EXPECT_EQ(ParseError(BarSynthScene("  frames: 3\n  sanity_check: true\n")), "(no error)");
  EXPECT_NE(ParseError(BarSynthScene("  sanity_check: true\n  ground_truth: {refinement: 2}\n"))
                .find("synth.yaml:12: synth.ground_truth: a sanity check"),
            std::string::npos);
  EXPECT_EQ(ParseError(BarSynthScene("  ground_truth: {refinement: 2}\n"
                                  "  motion:\n"
                                  "    - select: {all: true}\n"
                                  "      anchor: hard\n"
                                  "      keyframes: [{frame: 0}, {frame: 4, rotation: [0, 0, 1]}]\n")),
            "synth.yaml:14: synth.motion[0].anchor: this track rotates: its anchor turns about the "
            "track's centre, so give centre: [x, y, z]");
  EXPECT_EQ(ParseError(BarSynthScene("  ground_truth: {refinement: 2}\n"
                                  "  motion:\n"
                                  "    - select: {all: true}\n"
                                  "      keyframes: [{frame: 3}, {frame: 3}]\n")),
            "synth.yaml:14: synth.motion[0].keyframes[1].frame: must be greater than the "
            "previous keyframe's (3)");
  EXPECT_EQ(ParseError(BarSynthScene("  ground_truth: {refinement: 2}\n"
                                  "  bodies:\n"
                                  "    - {box: {min: [0, 0, 0], max: [0, 1, 1]}}\n")),
            "synth.yaml:13: synth.bodies[0].box.max: must be > min in every coordinate");
  // No camera.
  std::string no_camera = BarSynthScene("  ground_truth: {refinement: 2}\n");
  no_camera.erase(no_camera.find("registration:"), no_camera.find("synth:") - no_camera.find("registration:"));
  EXPECT_EQ(ParseError(no_camera),
            "synth.yaml:8: synth: needs registration.camera: the virtual depth camera renders from it");
}

std::string ReadFile(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::ostringstream os;
  os << in.rdbuf();
  return os.str();
}

TEST(SynthSequenceTest, SanityCheckIsLabelledAndThePressMovesThePatch) {
  Scene scene;
  const std::string text = testing_util::BlockPressSynthScene("  frames: 2\n  sanity_check: true\n");
  ASSERT_TRUE(ParseScene(text, "press.yaml", "", &scene).ok());
  TempDir dir;
  SynthReport report;
  const Status status = GenerateSynthSequence(scene, dir.path(), 0, &report);
  ASSERT_TRUE(status.ok()) << status.message();
  EXPECT_EQ(report.frames, 2);
  EXPECT_EQ(report.truth_vertices, report.tracked_vertices);
  EXPECT_NE(ReadFile(dir.path() + "/README.md").find("SANITY CHECK"), std::string::npos);
  EXPECT_NE(ReadFile(dir.path() + "/scene.yaml").find("SANITY CHECK"), std::string::npos);
  for (const char* f : {"/clouds/frame_0001.pcd", "/ground_truth/frame_0001.csv", "/truth/frame_0001.vtu"}) {
    EXPECT_TRUE(fs::is_regular_file(dir.path() + f)) << f;
  }
  // Frame 1: the tool's bottom is at z = 0.016, the block's top at 0.02; the top vertices
  // under the footprint (x, y in [0.01, 0.03]) are moved down to it.
  GroundTruthFrame truth;
  ASSERT_TRUE(ReadGroundTruthFrame(dir.path() + "/ground_truth/frame_0001.csv", &truth).ok());
  TetMesh mesh = MakeBox(Eigen::Vector3d(0.04, 0.04, 0.02), 4, 4, 2);
  int pressed = 0;
  for (int v = 0; v < mesh.num_vertices(); ++v) {
    const Eigen::Vector3d X = mesh.rest.row(v);
    if (X.z() > 0.0199 && X.x() > 0.0099 && X.x() < 0.0301 && X.y() > 0.0099 && X.y() < 0.0301) {
      EXPECT_NEAR(truth.positions(v, 2), 0.016, 1e-6);
      ++pressed;
    }
  }
  EXPECT_EQ(pressed, 9);
  EXPECT_LT(truth.positions(0, 2), 1e-9);  // clamped bottom stays
}

// A nearly incompressible ground truth (nu >= 0.45) with no element chosen is simulated with
// the neo-Hookean nodal-volume element, as simulate does, and the report and README say so;
// forward.model keeps the element the scene names.
TEST(SynthSequenceTest, NearlyIncompressibleTruthGetsTheNodalElementUnlessOneIsChosen) {
  const std::string synth = "  frames: 2\n  ground_truth: {material: {poisson_ratio: 0.49}}\n";
  for (const bool chosen : {false, true}) {
    SCOPED_TRACE(chosen ? "forward.model: corotational" : "no element chosen");
    Scene scene;
    const Status parsed = ParseScene(
        testing_util::BlockPressSynthScene(synth, "{frame: 1, translation: [0, 0, -0.012]}",
                                           chosen ? "forward: {model: corotational}\n" : ""),
        "soft.yaml", "", &scene);
    ASSERT_TRUE(parsed.ok()) << parsed.message();
    TempDir dir;
    SynthReport report;
    const Status status = GenerateSynthSequence(scene, dir.path(), 0, &report);
    ASSERT_TRUE(status.ok()) << status.message();
    const std::string readme = ReadFile(dir.path() + "/README.md");
    if (chosen) {
      EXPECT_TRUE(report.note.empty()) << report.note;
      EXPECT_NE(readme.find("quasi-static corotational FEM"), std::string::npos) << readme;
    } else {
      EXPECT_NE(report.note.find("neo-Hookean"), std::string::npos) << report.note;
      EXPECT_NE(readme.find("neo-Hookean FEM (nodal volume)"), std::string::npos) << readme;
    }
  }
}

// Each bundled dataset regenerates from its seed: its first two frames and its scene.yaml,
// within tolerances that say what can vary from one CPU or BLAS build to another:
//
// - Exactly: scene.yaml (written from the synth section), the vertex counts, and the
//   truth surfaces' triangles (integer topology).
// - Ground-truth positions (CSV and truth VTU): each frame is a quasi-static solve stopped
//   when the force imbalance is below its tolerance, so a position may be off the exact
//   equilibrium by up to |r| / k with k the stiffness of the softest mode. The loosest case
//   is occlusion: absolute_tolerance 1e-5 N on a clamped beam 0.25 m long of 4 x 4 cm,
//   E = 5e4 Pa, whose tip stiffness 3 E I / L^3 = 3 * 5e4 * 2.1e-7 / 0.0156 is about 2 N/m:
//   5 um from the exact solution, so two machines may differ by 10 um; kMaxShift = 20 um
//   leaves a factor 2 (the VTU stores float32: 0.3 m * 6e-8 adds 2e-8 m). This is 10 times
//   below the camera's depth noise at 0.3 m, so it cannot hide a change that matters.
// - Visibility: a vertex within 2 mm of the depth image is seen; one within kMaxShift of that
//   threshold may flip: at most 2 per frame.
// - Clouds: regen::CloudsAgree.
// - forces.csv: within a millinewton, or a thousandth of the force.
TEST(SynthSequenceTest, BundledDatasetsRegenerateWithinTolerance) {
  const double kMaxShift = 20e-6;  // m
  int checked = 0;
  for (const auto& entry : fs::directory_iterator(FEMREG_DATASETS_DIR)) {
    const fs::path synth = entry.path() / "synth.yaml";
    if (!fs::is_regular_file(synth)) continue;
    SCOPED_TRACE(synth.string());
    Scene scene;
    Status status = LoadScene(synth.string(), &scene);
    ASSERT_TRUE(status.ok()) << status.message();
    TempDir dir;
    SynthReport report;
    status = GenerateSynthSequence(scene, dir.path(), 2, &report);
    ASSERT_TRUE(status.ok()) << status.message();
    const std::string bundled_yaml = ReadFile((entry.path() / "scene.yaml").string());
    ASSERT_FALSE(bundled_yaml.empty()) << "scene.yaml is not bundled";
    EXPECT_TRUE(bundled_yaml == ReadFile(dir.path() + "/scene.yaml")) << "scene.yaml differs";
    for (const char* frame : {"frame_0000", "frame_0001"}) {
      SCOPED_TRACE(frame);
      const std::string name(frame);
      auto bundled = [&](const std::string& f) { return (entry.path() / f).string(); };
      auto mine = [&](const std::string& f) { return dir.path() + "/" + f; };
      const regen::Deviation truth =
          regen::CompareGroundTruth(bundled("ground_truth/" + name + ".csv"), mine("ground_truth/" + name + ".csv"));
      ASSERT_TRUE(truth.ok) << truth.Report();
      EXPECT_LE(truth.max, kMaxShift) << truth.Report();
      EXPECT_LE(truth.flips, 2) << truth.Report();
      const regen::Deviation surface =
          regen::CompareVtuSurfaces(bundled("truth/" + name + ".vtu"), mine("truth/" + name + ".vtu"));
      ASSERT_TRUE(surface.ok) << surface.Report();
      EXPECT_LE(surface.max, kMaxShift) << surface.Report();
      std::string why;
      EXPECT_TRUE(regen::CloudsAgree(bundled("clouds/" + name + ".pcd"), mine("clouds/" + name + ".pcd"), &why))
          << why;
    }
    // The true forces of the frames made: what the positions' tolerance moves them by is far
    // below a millinewton or a thousandth of the force; a changed definition is not.
    std::vector<ForceFrame> bundled_forces, my_forces;
    bool has_columns = false;
    ASSERT_TRUE(ReadForces((entry.path() / "forces.csv").string(), &bundled_forces, &has_columns).ok());
    ASSERT_TRUE(ReadForces(dir.path() + "/forces.csv", &my_forces, &has_columns).ok());
    ASSERT_EQ(my_forces.size(), 2u);
    ASSERT_GE(bundled_forces.size(), 2u);
    for (size_t f = 0; f < 2; ++f) {
      const double tolerance = 1e-3 * std::max(1.0, bundled_forces[f].force.norm());
      EXPECT_LE((my_forces[f].force - bundled_forces[f].force).norm(), tolerance) << "forces.csv frame " << f;
      EXPECT_LE((my_forces[f].torque - bundled_forces[f].torque).norm(), 0.1 * tolerance) << "forces.csv frame " << f;
    }
    ++checked;
  }
  EXPECT_GE(checked, 6);
}

}  // namespace
}  // namespace femreg

namespace femreg {
namespace {

// organ-data --divisions: the tracked body's size, and a clear refusal outside 2-9 (the
// ground truth's mesh, divisions 10, must stay finer) before anything is written.
TEST(OrganPatchData, DivisionsSetTheTrackedMeshAndAreChecked) {
  const TetMesh bundled = OrganPatchMesh(4);
  EXPECT_EQ(bundled.num_vertices(), 729);
  EXPECT_EQ(bundled.num_tets(), 3072);
  const TetMesh fine = OrganPatchMesh(7);
  EXPECT_EQ(fine.num_vertices(), 3375);
  EXPECT_EQ(fine.num_tets(), 16464);
  for (int divisions : {1, 10}) {
    const std::string dir = ::testing::TempDir() + "/organ_divisions_" + std::to_string(divisions);
    const Status status = GenerateOrganPatchSequence(dir, nullptr, divisions);
    ASSERT_FALSE(status.ok());
    EXPECT_NE(status.message().find("divisions must be 2 to 9"), std::string::npos) << status.message();
    EXPECT_FALSE(std::filesystem::exists(dir));
  }
  // --truth-divisions: 3-16, and the tracked mesh must stay coarser than the truth's.
  const std::string dir = ::testing::TempDir() + "/organ_truth_divisions";
  Status status = GenerateOrganPatchSequence(dir, nullptr, 4, 17);
  ASSERT_FALSE(status.ok());
  EXPECT_NE(status.message().find("truth divisions must be 3 to 16"), std::string::npos) << status.message();
  status = GenerateOrganPatchSequence(dir, nullptr, 5, 5);
  ASSERT_FALSE(status.ok());
  EXPECT_NE(status.message().find("divisions must be 2 to 4"), std::string::npos) << status.message();
  EXPECT_FALSE(std::filesystem::exists(dir));
}

// The ground truth's element does not lock: it is the neo-Hookean one with the nodal volume,
// and on the same mesh the locked corotational element at the truth's nu pushes the tool back
// harder (docs/notes/2026-11-29-organ-truth.md). Its forces balance: with no gravity the
// tool's force and the clamp's reaction, and their torques, sum to zero.
TEST(OrganPatchData, TruthIsLockingFreeAndItsForcesBalance) {
  const ObjectMaterial material = OrganPatchTruthMaterial();
  EXPECT_EQ(material.model, MaterialModel::kNeoHookean);
  EXPECT_TRUE(material.nodal_volume);
  EXPECT_DOUBLE_EQ(material.material.poisson_ratio, 0.47);
  // The deepest press (frame 7) on the tracked mesh's size, by the glued tool (solved from
  // rest, where the contact tool goes through the frames before), to keep the test short.
  OrganTruthFrame truth, locked;
  Status status = SolveOrganPatchTruth(7, 4, material, &truth, OrganTool::kGlued);
  ASSERT_TRUE(status.ok()) << status.message();
  EXPECT_EQ(truth.summary.termination, ForwardTermination::kConverged);
  EXPECT_EQ(truth.positions.rows(), 729);
  const double force = truth.tool.force.norm();
  EXPECT_LT(truth.tool.force.z(), 0.0);  // pushing down into the body
  EXPECT_GT(force, 0.05);
  EXPECT_LT((truth.tool.force + truth.clamp.force).norm(), 1e-4 * force);
  // A torque scale: the tool's force at the body's half length.
  EXPECT_LT((truth.tool.torque + truth.clamp.torque).norm(), 1e-4 * force * 0.08);
  EXPECT_GT(truth.tool.torque.norm(), 1e-3 * force * 0.08);  // not a zero that balances trivially

  ObjectMaterial hooke(material.material);  // the corotational element, as before
  status = SolveOrganPatchTruth(7, 4, hooke, &locked, OrganTool::kGlued);
  ASSERT_TRUE(status.ok()) << status.message();
  std::printf("organ_patch truth, frame 7 on 729 vertices: tool force %.4f N (nodal volume), %.4f N "
              "(corotational); imbalance %.2e N\n",
              force, locked.tool.force.norm(), (truth.tool.force + truth.clamp.force).norm());
  EXPECT_GT(locked.tool.force.norm(), 1.1 * force);
}

// organ-data --tool contact: a rigid, frictionless tool pressing by contact. At the deepest
// press its force pushes down into the body, nearly along the top's normal (the glued tool's
// no-slip footprint adds a pull along the surface nearly as large as the push,
// docs/notes/2026-11-30-organ-contact-tool.md), the solve converged and the clamp's reaction
// balances it, force and torque.
TEST(OrganPatchData, ContactToolPushesAlongTheNormalAndBalances) {
  const ObjectMaterial material = OrganPatchTruthMaterial();
  OrganTruthFrame contact, glued;
  Status status = SolveOrganPatchTruth(7, 3, material, &contact, OrganTool::kContact);
  ASSERT_TRUE(status.ok()) << status.message();
  EXPECT_EQ(contact.summary.termination, ForwardTermination::kConverged);
  const Eigen::Vector3d force = contact.tool.force;
  EXPECT_LT(force.z(), -0.05);  // pushing down into the body
  const double along = force.head<2>().norm();
  EXPECT_LT(along, 0.35 * -force.z());
  EXPECT_LT(std::abs(force.y()), 0.05 * force.norm());  // mirror symmetric while it only presses
  EXPECT_LT((contact.tool.force + contact.clamp.force).norm(), 1e-4 * force.norm());
  EXPECT_LT((contact.tool.torque + contact.clamp.torque).norm(), 1e-4 * force.norm() * 0.08);
  EXPECT_GT(contact.tool.torque.norm(), 1e-3 * force.norm() * 0.08);
  EXPECT_GT(contact.contacts, 0);
  EXPECT_LT(contact.max_penetration, 1e-4);  // the penalty's give, small against the tool's push

  status = SolveOrganPatchTruth(7, 3, material, &glued, OrganTool::kGlued);
  ASSERT_TRUE(status.ok()) << status.message();
  std::printf("organ_patch truth, frame 7 on 343 vertices: contact tool (%.4f, %.4f, %.4f) N, glued "
              "(%.4f, %.4f, %.4f) N\n",
              force.x(), force.y(), force.z(), glued.tool.force.x(), glued.tool.force.y(), glued.tool.force.z());
  EXPECT_GT(glued.tool.force.head<2>().norm(), 0.5 * -glued.tool.force.z());
}

// The bundled organ_patch/forces.csv (the contact tool): a row per frame, the tool's force on
// the body pointing down into it, nearly along the top's normal; while the tool only presses
// (frames 0-7) the body's mirror symmetry in y leaves next to no y force and the force grows
// with the depth; the frictionless drag at that depth (frames 8-11) keeps its size.
TEST(OrganPatchData, BundledToolForcePushesIntoTheBody) {
  std::vector<ForceFrame> forces;
  bool has_columns = false;
  const Status status = ReadForces(std::string(FEMREG_DATASETS_DIR) + "/organ_patch/forces.csv",
                                   &forces, &has_columns);
  ASSERT_TRUE(status.ok()) << status.message();
  ASSERT_TRUE(has_columns);
  ASSERT_EQ(forces.size(), 12u);
  for (int f = 0; f < 12; ++f) {
    SCOPED_TRACE("frame " + std::to_string(f));
    EXPECT_EQ(forces[f].frame, f);
    const Eigen::Vector3d& force = forces[f].force;
    EXPECT_LT(force.z(), 0.0);
    EXPECT_LT(force.head<2>().norm(), 0.35 * -force.z());
    if (f < 8) {
      EXPECT_LT(std::abs(force.y()), 0.01 * force.norm());
      if (f > 0) {
        EXPECT_GT(force.norm(), forces[f - 1].force.norm());
      }
    } else {
      EXPECT_NEAR(force.norm(), forces[7].force.norm(), 0.05 * forces[7].force.norm());
    }
  }
}

}  // namespace
}  // namespace femreg
