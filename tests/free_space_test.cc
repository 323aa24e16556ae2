// Free space (issue 39): the rays to the observed points passed through empty space, so the
// model may be behind the observed surface but never in front of it. The block's zero side
// (its derivatives are checked with every registered block type in tests/energy_test.cc),
// the observed depth built from a cloud (holes and the image's outside say nothing; across
// a depth step the nearer depth wins), the options, and a registration whose rest shape bulges
// towards the camera over a flat observed surface: without free space the bulge stays in front
// of what the camera saw; with it, it does not.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <memory>
#include <string>
#include <vector>

#include "energy/free_space.h"
#include "energy/term.h"
#include "femreg/camera_io.h"
#include "femreg/io.h"
#include "femreg/point_cloud.h"
#include "femreg/scene.h"
#include "femreg/tracker.h"
#include "registration/free_space.h"
#include "test_util.h"

namespace femreg {
namespace {

TEST(FreeSpacePenalty, ZeroBehindTheAllowedDepthAndPushesBackAlongTheRayInFront) {
  energy::FreeSpacePenalty block;
  block.vertices = {{0}};
  block.weight = 1e4;
  block.origin = Eigen::Vector3d(0.1, -0.2, 0.3);
  block.ray = Eigen::Vector3d(0.2, 0.3, 1.0).normalized();
  block.depth = 0.5;
  const energy::Loss loss;
  energy::Linearization<energy::FreeSpacePenalty> lin;
  Vertices x(1, 3);
  x.row(0) = (block.origin + 0.6 * block.ray).transpose();  // behind: 0.1 m past the allowed depth
  ASSERT_TRUE(energy::Linearize(block, loss, x, &lin));
  EXPECT_EQ(lin.value, 0.0);
  EXPECT_EQ(lin.scale, 0.0);
  EXPECT_EQ(lin.gradient[0].norm(), 0.0);
  EXPECT_EQ(energy::BlockValue(block, loss, x), 0.0);
  x.row(0) = (block.origin + 0.49 * block.ray + Eigen::Vector3d(0.03, -0.02, 0.0)).transpose();
  const double violation = block.Violation(x.data());
  EXPECT_GT(violation, 0.0);
  ASSERT_TRUE(energy::Linearize(block, loss, x, &lin));
  EXPECT_NEAR(lin.value, 0.5 * block.weight * violation * violation, 1e-12);
  // The gradient points towards the sensor: a descent step moves the vertex back along the ray.
  EXPECT_NEAR(lin.gradient[0].dot(block.ray), -block.weight * violation, 1e-9);
  EXPECT_NEAR((lin.gradient[0] + block.weight * violation * block.ray).norm(), 0.0, 1e-9);
}

// Points on the plane z = 0 seen from (0, 0, 1) looking down -z, with a square hole.
Vertices PlaneWithHole(double spacing, double half, double hole) {
  std::vector<Eigen::Vector3d> points;
  for (double x = -half; x <= half + 1e-12; x += spacing) {
    for (double y = -half; y <= half + 1e-12; y += spacing) {
      if (std::abs(x) < hole && std::abs(y) < hole) continue;
      points.emplace_back(x, y, 0.0);
    }
  }
  Vertices out(static_cast<Eigen::Index>(points.size()), 3);
  for (size_t i = 0; i < points.size(); ++i) out.row(static_cast<Eigen::Index>(i)) = points[i].transpose();
  return out;
}

TEST(ObservedDepth, HolesAndTheOutsideSayNothing) {
  const Eigen::Vector3d eye(0, 0, 1), axis(0, 0, -1);
  ObservedDepth observed;
  observed.Build(PlaneWithHole(0.004, 0.1, 0.03), true, eye, axis, 0.004);
  ASSERT_FALSE(observed.empty());
  Eigen::Vector3d ray, origin;
  double depth = 0;
  // On the plane, 5 cm towards the camera: observed, about 1 m along the ray.
  ASSERT_TRUE(observed.Observed(Eigen::Vector3d(0.06, 0.05, 0.05), &ray, &origin, &depth));
  EXPECT_NEAR(depth, std::sqrt(1 + 0.06 * 0.06 + 0.05 * 0.05), 0.004);
  EXPECT_NEAR((origin - eye).norm(), 0.0, 1e-12);
  EXPECT_NEAR(ray.norm(), 1.0, 1e-12);
  EXPECT_GT(ray.dot(axis), 0.99);
  // In the hole, beyond the points' image, behind the sensor: nothing.
  EXPECT_FALSE(observed.Observed(Eigen::Vector3d(0.0, 0.0, 0.05), &ray, &origin, &depth));
  EXPECT_FALSE(observed.Observed(Eigen::Vector3d(0.3, 0.0, 0.05), &ray, &origin, &depth));
  EXPECT_FALSE(observed.Observed(Eigen::Vector3d(0.06, 0.05, 1.5), &ray, &origin, &depth));
  // Sideways out of the seen-through space: from 5 cm above the plane at (0.05, 0), the
  // nearest way is into the hole, whose edge (x = 0.03) the points' splats move a pixel in:
  // about 2.4 cm off, times 0.95 at that depth; the image's edge is 5 cm off.
  const double exit = observed.SidewaysExit(Eigen::Vector3d(0.05, 0.0, 0.05), 0.01, 0.2);
  EXPECT_GT(exit, 0.015);
  EXPECT_LT(exit, 0.03);
  EXPECT_TRUE(std::isinf(observed.SidewaysExit(Eigen::Vector3d(0.05, 0.0, 0.05), 0.01, 0.01)));
  // On the plane itself (within the tolerance), it is out already: the nearest allowed pixel
  // is next to its own.
  EXPECT_LT(observed.SidewaysExit(Eigen::Vector3d(0.05, 0.0, 0.0), 0.01, 0.2), 0.006);
}

TEST(ObservedDepth, TheNearerDepthWinsAcrossAStepAndOrthographicViewsWork) {
  // Two half-planes: x < 0 at z = 0, x >= 0 at z = -0.1 (farther from a camera above).
  std::vector<Eigen::Vector3d> pts;
  for (double x = -0.1; x <= 0.1 + 1e-12; x += 0.004) {
    for (double y = -0.1; y <= 0.1 + 1e-12; y += 0.004) pts.emplace_back(x, y, x < 0 ? 0.0 : -0.1);
  }
  Vertices points(static_cast<Eigen::Index>(pts.size()), 3);
  for (size_t i = 0; i < pts.size(); ++i) points.row(static_cast<Eigen::Index>(i)) = pts[i].transpose();
  ObservedDepth ortho;
  ortho.Build(points, false, Eigen::Vector3d(0, 0, 1), Eigen::Vector3d::Zero(), 0.004);
  Eigen::Vector3d ray, origin;
  double depth = 0;
  ASSERT_TRUE(ortho.Observed(Eigen::Vector3d(-0.05, 0.0, 0.2), &ray, &origin, &depth));
  EXPECT_NEAR(ray.dot(Eigen::Vector3d(0, 0, -1)), 1.0, 1e-12);
  EXPECT_NEAR(depth, ray.dot(Eigen::Vector3d(-0.05, 0.0, 0.0) - origin), 1e-9);
  ASSERT_TRUE(ortho.Observed(Eigen::Vector3d(0.05, 0.0, 0.2), &ray, &origin, &depth));
  EXPECT_NEAR(depth, ray.dot(Eigen::Vector3d(0.05, 0.0, -0.1) - origin), 1e-9);
  // Just past the step on the far side (its first column of points is at x = 0), the near
  // side's depth is kept: the space said to be free is never more than what was seen through.
  ASSERT_TRUE(ortho.Observed(Eigen::Vector3d(0.0005, 0.0, 0.2), &ray, &origin, &depth));
  EXPECT_NEAR(depth, ray.dot(Eigen::Vector3d(0.0005, 0.0, 0.0) - origin), 1e-9);
}

TEST(FreeSpaceOptions, ParsedCheckedAndWrittenBack) {
  const std::string base =
      "objects:\n"
      "  - name: slab\n"
      "    generate: {shape: box, size: [0.1, 0.1, 0.02], cells: [2, 2, 1]}\n"
      "    material: {youngs_modulus: 10000, poisson_ratio: 0.3}\n"
      "registration:\n";
  Scene scene;
  ASSERT_TRUE(ParseScene(base + "  free_space: {enabled: false, tolerance: 0.02, weight: 500}\n", "s.yaml", "",
                         &scene).ok());
  EXPECT_FALSE(scene.registration.free_space.enabled);
  EXPECT_EQ(scene.registration.free_space.tolerance, 0.02);
  EXPECT_EQ(scene.registration.free_space.weight, 500.0);
  const std::string written = SceneToYaml(scene);
  EXPECT_NE(written.find("free_space"), std::string::npos) << written;
  Scene again;
  ASSERT_TRUE(ParseScene(written, "w.yaml", "", &again).ok()) << written;
  EXPECT_FALSE(again.registration.free_space.enabled);
  EXPECT_EQ(again.registration.free_space.tolerance, 0.02);
  EXPECT_EQ(again.registration.free_space.weight, 500.0);

  Status bad = ParseScene(base + "  free_space: {tolerance: -0.01}\n", "bad.yaml", "", &scene);
  ASSERT_FALSE(bad.ok());
  EXPECT_NE(bad.message().find("bad.yaml"), std::string::npos) << bad.message();
  EXPECT_NE(bad.message().find("registration.free_space.tolerance"), std::string::npos) << bad.message();
  bad = ParseScene(base + "  free_space: {weight: 0}\n", "bad.yaml", "", &scene);
  ASSERT_FALSE(bad.ok());
  EXPECT_NE(bad.message().find("registration.free_space.weight"), std::string::npos) << bad.message();
  bad = ParseScene(base + "  free_space: {margin: 0.01}\n", "bad.yaml", "", &scene);
  ASSERT_FALSE(bad.ok());
  EXPECT_NE(bad.message().find("margin"), std::string::npos) << bad.message();
}

// A slab 20 x 20 x 2 cm whose rest shape has a dome 4 cm high in its middle (towards a camera
// above), clamped at its bottom, registered to its flat top as the camera sees it: the truth
// is the slab pressed flat. The dome is beyond the data's reach (data.max_distance) and its
// rest shape holds it up; free space pushes it back behind the observed top.
enum class Input {
  kCloud,       // points on a 4 mm grid, the camera known
  kDepthImage,  // the camera's depth image of the top, back-projected (as `femreg register` reads one)
  kNoCamera,    // the grid without a camera: the view is the direction estimated for visibility
};

struct Dome {
  double apex = 0.0;  // m: the top surface's highest point above the observed top
  int held = 0;       // free_space_vertices, most in a frame
};

constexpr double kSize = 0.2, kThick = 0.02;

PointCloud DomeCloud(const RegistrationOptions& options, Input input) {
  PointCloud cloud;
  if (input == Input::kDepthImage) {
    // Per pixel, the ray's hit on the plane of the top, where it lies on the slab.
    const CameraOptions& camera = options.camera;
    const Eigen::Matrix3d R = CameraRotation(camera);
    RawDepthImage image;
    image.width = camera.width;
    image.height = camera.height;
    image.metres.assign(static_cast<size_t>(camera.width * camera.height), 0.0f);
    std::vector<uint8_t> keep(image.metres.size(), 0);
    for (int v = 0; v < camera.height; ++v) {
      for (int u = 0; u < camera.width; ++u) {
        const Eigen::Vector3d d = R.transpose() * Eigen::Vector3d((u - camera.cx) / camera.fx, (v - camera.cy) / camera.fy, 1.0);
        const double t = (kThick - camera.position.z()) / d.z();
        const Eigen::Vector3d p = camera.position + t * d;
        if (t > 0 && p.x() >= 0 && p.x() <= kSize && p.y() >= 0 && p.y() <= kSize) {
          image.metres[static_cast<size_t>(v * camera.width + u)] = static_cast<float>(t);
          keep[static_cast<size_t>(v * camera.width + u)] = 1;
        }
      }
    }
    const Status status = BackProjectDepth(image, camera, DepthImageOptions(), &keep, &cloud);
    EXPECT_TRUE(status.ok()) << status.message();
    EXPECT_GT(cloud.size(), 2000);
    return cloud;
  }
  std::vector<Eigen::Vector3d> pts;
  for (double x = 0.002; x < kSize; x += 0.004) {
    for (double y = 0.002; y < kSize; y += 0.004) pts.emplace_back(x, y, kThick);
  }
  cloud.points.resize(static_cast<Eigen::Index>(pts.size()), 3);
  for (size_t i = 0; i < pts.size(); ++i) cloud.points.row(static_cast<Eigen::Index>(i)) = pts[i].transpose();
  return cloud;
}

// The slab with its dome, and its bottom's vertices.
TetMesh DomeMesh(std::vector<int>* bottom) {
  const double radius = 0.07, height = 0.04;
  TetMesh mesh = MakeBox(Eigen::Vector3d(kSize, kSize, kThick), 14, 14, 2);
  for (int v = 0; v < mesh.num_vertices(); ++v) {
    const Eigen::Vector2d d = mesh.rest.row(v).head<2>().transpose() - Eigen::Vector2d(kSize / 2, kSize / 2);
    const double bump = std::max(0.0, 1.0 - d.squaredNorm() / (radius * radius));
    mesh.rest(v, 2) += height * bump * bump * mesh.rest(v, 2) / kThick;
    if (mesh.rest(v, 2) < 1e-9) bottom->push_back(v);
  }
  mesh.x = mesh.rest;
  return mesh;
}

// The slab's material, and a camera 45 cm above its middle (one thread).
ObjectMaterial DomeMaterial() {
  ObjectMaterial material;
  material.material.youngs_modulus = 2e5;
  material.material.poisson_ratio = 0.3;
  material.material.density = 1000;
  return material;
}

RegistrationOptions DomeOptions() {
  RegistrationOptions options;
  options.camera.enabled = true;
  options.camera.position = Eigen::Vector3d(kSize / 2, kSize / 2, 0.45);
  options.camera.target = Eigen::Vector3d(kSize / 2, kSize / 2, 0.0);
  options.camera.up = Eigen::Vector3d(0, 1, 0);
  options.camera.fx = options.camera.fy = 150.0;
  options.camera.width = 160;
  options.camera.height = 120;
  options.camera.cx = 79.5;
  options.camera.cy = 59.5;
  options.solver.num_threads = 1;
  return options;
}

Dome RegisterDome(bool free_space, SolverBackend backend, Input input) {
  std::vector<int> bottom;
  const TetMesh mesh = DomeMesh(&bottom);
  const ObjectMaterial material = DomeMaterial();
  RegistrationOptions options = DomeOptions();
  options.camera.enabled = input != Input::kNoCamera;
  options.solver.backend = backend;
  options.free_space.enabled = free_space;
  std::unique_ptr<Tracker> tracker;
  Status status = Tracker::Create({mesh}, {material}, options, &tracker);
  EXPECT_TRUE(status.ok()) << status.message();
  Dome dome;
  if (!status.ok()) return dome;
  EXPECT_TRUE(tracker->AddAnchor("bottom", 0, bottom, true).ok());
  const PointCloud cloud = DomeCloud(options, input);
  for (int f = 0; f < 3; ++f) {
    FrameSummary s;
    EXPECT_TRUE(tracker->Track(cloud, &s).ok());
    EXPECT_TRUE(s.IsSolutionUsable()) << s.FullReport();
    const Vertices& x = tracker->vertices(0);
    dome.apex = x.col(2).maxCoeff() - kThick;
    dome.held = std::max(dome.held, s.free_space_vertices);
    std::printf("free space %s, %s, input %d, frame %d: apex %.2f mm above the observed top, %d held, "
                "visibility %s, %s\n",
                free_space ? "on" : "off", ToString(backend), static_cast<int>(input), f, dome.apex * 1e3,
                dome.held, s.visibility.c_str(), s.BriefReport().c_str());
  }
  return dome;
}

void ExpectHeldBehind(SolverBackend backend, Input input) {
  const double tolerance = FreeSpaceOptions().tolerance;
  const Dome without = RegisterDome(false, backend, input);
  const Dome with = RegisterDome(true, backend, input);
  // Without: the dome stands in the space the camera saw through, beyond the tolerance.
  EXPECT_GT(without.apex, 2.0 * tolerance);
  EXPECT_EQ(without.held, 0);
  // With: no farther in front of the observed top than the tolerance and the penalty's give.
  EXPECT_LT(with.apex, tolerance + 0.003);
  EXPECT_GT(with.held, 0);
}

TEST(FreeSpace, ADomeInFrontOfTheObservedSurfaceIsHeldBehindItByBothBackEnds) {
  ExpectHeldBehind(SolverBackend::kFast, Input::kCloud);
  ExpectHeldBehind(SolverBackend::kCeres, Input::kCloud);
}

TEST(FreeSpace, FromADepthImageAndWithoutACamera) {
  ExpectHeldBehind(SolverBackend::kFast, Input::kDepthImage);
  ExpectHeldBehind(SolverBackend::kFast, Input::kNoCamera);
}

// A plane the preprocessing removes (preprocess.plane: a table, here the slab's own flat top)
// was seen all the same: the dome in front of it is held back although no data point is left
// on it. The only data are the slab's front face.
int HeldInFrontOfARemovedPlane(bool plane_removed, double* apex) {
  std::vector<int> bottom;
  const TetMesh mesh = DomeMesh(&bottom);
  const ObjectMaterial material = DomeMaterial();
  RegistrationOptions options = DomeOptions();
  if (plane_removed) options.preprocess.plane_distance = 0.002;
  std::unique_ptr<Tracker> tracker;
  EXPECT_TRUE(Tracker::Create({mesh}, {material}, options, &tracker).ok());
  if (!tracker) return -1;
  EXPECT_TRUE(tracker->AddAnchor("bottom", 0, bottom, true).ok());
  // The front face (y = 0) on a 2 mm grid below the plane's reach, and the flat top, the
  // larger plane, on a 4 mm one.
  std::vector<Eigen::Vector3d> pts;
  for (double x = 0.001; x < kSize; x += 0.002) {
    for (double z = 0.001; z < kThick - 0.002; z += 0.002) pts.emplace_back(x, 0.0, z);
  }
  const size_t front = pts.size();
  for (double x = 0.002; x < kSize; x += 0.004) {
    for (double y = 0.002; y < kSize; y += 0.004) pts.emplace_back(x, y, kThick);
  }
  EXPECT_GT(pts.size() - front, 2 * front);
  PointCloud cloud;
  cloud.points.resize(static_cast<Eigen::Index>(pts.size()), 3);
  for (size_t i = 0; i < pts.size(); ++i) cloud.points.row(static_cast<Eigen::Index>(i)) = pts[i].transpose();
  int held = 0;
  for (int f = 0; f < 3; ++f) {
    FrameSummary s;
    EXPECT_TRUE(tracker->Track(cloud, &s).ok());
    EXPECT_TRUE(s.IsSolutionUsable()) << s.FullReport();
    if (plane_removed) EXPECT_EQ(s.points_used, static_cast<int>(front)) << "the plane is the top";
    held = std::max(held, s.free_space_vertices);
    *apex = tracker->vertices(0).col(2).maxCoeff() - kThick;
  }
  return held;
}

TEST(FreeSpace, APlaneThePreprocessingRemovedWasSeen) {
  const double tolerance = FreeSpaceOptions().tolerance;
  double apex_kept = 0.0, apex_removed = 0.0;
  // Held at the tolerance and the penalty's give (about 2.6 mm); left alone, 40 mm out.
  EXPECT_GT(HeldInFrontOfARemovedPlane(false, &apex_kept), 0);
  EXPECT_LT(apex_kept, tolerance + 0.006);
  EXPECT_GT(HeldInFrontOfARemovedPlane(true, &apex_removed), 0);
  EXPECT_LT(apex_removed, tolerance + 0.006);
}

#ifdef FEMREG_CLI_PATH
// `femreg register` on the dome: stats.csv's free_space_vertices, summary.json's free_space,
// and --set reaching the option.
TEST(FreeSpace, RegisterReportsTheHeldVertices) {
  using testing_util::CliRun;
  using testing_util::Femreg;
  using testing_util::Slurp;
  using testing_util::StatsColumn;
  using testing_util::TempDir;
  TempDir tmp("femreg_free_space");
  std::vector<int> bottom;
  const TetMesh mesh = DomeMesh(&bottom);
  ASSERT_TRUE(WriteVtu(tmp.File("dome.vtu"), mesh, mesh.rest).ok());
  std::filesystem::create_directories(tmp.File("clouds"));
  RegistrationOptions options;
  options.camera.enabled = true;
  const PointCloud cloud = DomeCloud(options, Input::kCloud);
  for (const char* name : {"clouds/frame_0000.pcd", "clouds/frame_0001.pcd"}) {
    ASSERT_TRUE(WritePointCloud(tmp.File(name), cloud).ok());
  }
  const std::string scene = tmp.Write(
      "scene.yaml",
      "objects:\n"
      "  - name: slab\n"
      "    mesh: dome.vtu\n"
      "    material: {youngs_modulus: 200000, poisson_ratio: 0.3, density: 1000}\n"
      "registration:\n"
      "  camera: {position: [0.1, 0.1, 0.45], target: [0.1, 0.1, 0], up: [0, 1, 0]}\n"
      "anchors:\n"
      "  - {name: bottom, select: {box: {min: [-1, -1, -1], max: [1, 1, 0.000001]}}, hard: true}\n");
  const std::string common = "register --scene " + scene + " --frames " + tmp.File("clouds") + " --threads 1 --out ";
  const CliRun on = Femreg(common + tmp.File("on"));
  ASSERT_EQ(on.code, 0) << on.out;
  const CliRun off = Femreg(common + tmp.File("off") + " --set registration.free_space.enabled=false");
  ASSERT_EQ(off.code, 0) << off.out;
  const std::vector<std::string> held_on = StatsColumn(tmp.File("on"), "free_space_vertices");
  const std::vector<std::string> held_off = StatsColumn(tmp.File("off"), "free_space_vertices");
  ASSERT_EQ(held_on.size(), 2u);
  ASSERT_EQ(held_off.size(), 2u);
  int most = 0;
  for (const std::string& v : held_on) most = std::max(most, std::stoi(v));
  EXPECT_GT(most, 0);
  for (const std::string& v : held_off) EXPECT_EQ(v, "0");
  const std::string summary = Slurp(tmp.File("on") + "/summary.json");
  EXPECT_NE(summary.find("\"free_space\""), std::string::npos);
  EXPECT_NE(summary.find("vertices_per_frame"), std::string::npos);
}
#endif

}  // namespace
}  // namespace femreg
