// The bundled demo sequence: ground truth from a finer mesh, clouds from a virtual depth
// camera. Deterministic from the seed.
#include <Eigen/Geometry>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <sstream>

#include "femreg/forward.h"
#include "femreg/ground_truth.h"
#include "femreg/io.h"
#include "femreg/point_cloud.h"
#include "femreg/synth.h"

namespace fs = std::filesystem;

namespace femreg {

DemoOptions DefaultDemoOptions() {
  DemoOptions o;
  CameraOptions& c = o.sensor.camera;
  c.enabled = true;
  c.position = Eigen::Vector3d(0.15, -0.32, 0.28);
  c.target = Eigen::Vector3d(0.15, 0.03, -0.01);
  c.up = Eigen::Vector3d::UnitZ();
  c.width = 320;
  c.height = 240;
  c.fx = c.fy = 262.5;
  c.cx = 159.5;
  c.cy = 119.5;
  o.sensor.pixel_stride = 2;
  return o;
}

namespace {

// Prescribed motion of the free end at s in [0, 1]: bend down, swing sideways, twist.
Eigen::Vector3d EndDisplacement(const DemoOptions& o, double s, const Eigen::Vector3d& X) {
  const double kPi = 3.14159265358979323846;
  const double twist = 0.5 * std::sin(2 * kPi * s);
  const Eigen::Vector3d shift(0.0, 0.04 * std::sin(2 * kPi * s), -0.08 * std::sin(kPi * s));
  const Eigen::Vector3d centre(o.length, 0.5 * o.width, 0.5 * o.width);
  const Eigen::Vector3d moved =
      centre + Eigen::AngleAxisd(twist, Eigen::Vector3d::UnitX()) * (X - centre) + shift;
  return moved - X;
}

std::string SceneYaml(const DemoOptions& o) {
  const CameraOptions& c = o.sensor.camera;
  std::ostringstream os;
  os.precision(10);
  os << "# The bundled demo: a soft foam beam, clamped at x = 0, whose free end is bent,\n"
     << "# swung and twisted. Made by `femreg demo-data` (see README.md beside this file).\n"
     << "description: \"demo beam, " << o.frames << " frames\"\n"
     << "objects:\n"
     << "  - name: beam\n"
     << "    generate: {shape: box, size: [" << o.length << ", " << o.width << ", " << o.width
     << "], cells: [" << o.coarse_cells_x << ", " << o.coarse_cells_yz << ", " << o.coarse_cells_yz
     << "]}\n"
     << "    material: {youngs_modulus: " << o.youngs_modulus << ", poisson_ratio: " << o.poisson_ratio
     << ", density: " << o.density << "}\n"
     << "registration:\n"
     << "  regularizer: corotational\n"
     << "  camera: {position: [" << c.position.x() << ", " << c.position.y() << ", " << c.position.z()
     << "], target: [" << c.target.x() << ", " << c.target.y() << ", " << c.target.z()
     << "], up: [" << c.up.x() << ", " << c.up.y() << ", " << c.up.z() << "], fx: " << c.fx
     << ", fy: " << c.fy << ", cx: " << c.cx << ", cy: " << c.cy << ", width: " << c.width
     << ", height: " << c.height << "}\n"
     << "  data: {max_distance: 0.03, loss: huber, loss_scale: 0.005, metric: point_to_plane, visibility: true}\n"
     << "  weights: {data: 200, elastic: 1, temporal: 1}\n"
     << "  solver: {max_outer_iterations: 5, max_inner_iterations: 10}\n"
     << "anchors:\n"
     << "  - {name: clamp, select: {box: {min: [-1, -1, -1], max: [0.0001, 1, 1]}}, hard: true}\n";
  return os.str();
}

}  // namespace

Status GenerateDemoSequence(const DemoOptions& o, const std::string& dir,
                            void (*progress)(int done, int total)) {
  std::string error;
  if (!o.sensor.IsValid(&error)) return Status::Error(error);
  std::error_code ec;
  fs::create_directories(fs::path(dir) / "clouds", ec);
  fs::create_directories(fs::path(dir) / "ground_truth", ec);
  if (ec) return Status::Error(dir + ": cannot create: " + ec.message());

  const Eigen::Vector3d size(o.length, o.width, o.width);
  TetMesh coarse = MakeBox(size, o.coarse_cells_x, o.coarse_cells_yz, o.coarse_cells_yz);
  TetMesh fine = MakeBox(size, o.coarse_cells_x * o.refinement, o.coarse_cells_yz * o.refinement,
                         o.coarse_cells_yz * o.refinement);
  ComputeLumpedMasses(&fine, o.density);
  Material material;
  material.youngs_modulus = o.youngs_modulus;
  material.poisson_ratio = o.poisson_ratio;
  material.density = o.density;
  ElasticModel model;
  model.Build(fine, ElasticModelType::kCorotational, material);
  const EmbeddedPoints embedded = EmbedPoints(fine, coarse.rest);

  std::vector<int> clamped, moved;
  const double tol = 1e-9;
  for (int v = 0; v < fine.num_vertices(); ++v) {
    if (fine.rest(v, 0) <= tol) clamped.push_back(v);
    if (fine.rest(v, 0) >= o.length - tol) moved.push_back(v);
  }
  ForwardOptions forward;
  forward.max_iterations = 50;
  forward.load_steps = 1;
  const DepthSensor sensor(o.sensor);

  Status status = WriteFileAtomically((fs::path(dir) / "scene.yaml").string(), SceneYaml(o));
  if (!status.ok()) return status;
  for (int f = 0; f < o.frames; ++f) {
    const double s = o.frames > 1 ? static_cast<double>(f) / (o.frames - 1) : 0.0;
    ForwardProblem problem;
    problem.clamped = clamped;
    for (int v : moved) problem.prescribed.emplace_back(v, EndDisplacement(o, s, fine.rest.row(v)));
    ForwardSummary summary;
    status = SolveQuasiStatic(problem, forward, &model, &fine, &summary);
    if (!status.ok()) return status;
    if (!summary.IsSolutionUsable()) {
      return Status::Error("demo frame " + std::to_string(f) + ": forward solve failed: " +
                           summary.message);
    }
    const std::vector<RenderSurface> surfaces = {{&fine.x, &fine.surface}};
    const DepthImage image = sensor.Render(surfaces);
    const PointCloud cloud = sensor.Sample(image, surfaces, o.seed * 1000003ull + static_cast<uint64_t>(f));
    GroundTruthFrame truth;
    truth.positions = InterpolateEmbedded(fine, fine.x, embedded);
    truth.visible = sensor.Visible(image, truth.positions, 2e-3);
    char name[64];
    std::snprintf(name, sizeof(name), "frame_%04d", f);
    status = WritePointCloud((fs::path(dir) / "clouds" / (std::string(name) + ".pcd")).string(), cloud);
    if (!status.ok()) return status;
    status = WriteGroundTruthFrame((fs::path(dir) / "ground_truth" / (std::string(name) + ".csv")).string(), truth);
    if (!status.ok()) return status;
    if (progress) progress(f + 1, o.frames);
  }
  std::ostringstream readme;
  readme << "# Demo sequence: a soft beam bent, swung and twisted\n\n"
         << "Made by `femreg demo-data --out " << dir << "` (deterministic; seed " << o.seed << ").\n\n"
         << "- `scene.yaml`: the tracking scene: a " << o.length << " x " << o.width << " x " << o.width
         << " m foam beam (E = " << o.youngs_modulus << " Pa, nu = " << o.poisson_ratio << "), "
         << coarse.num_vertices() << " vertices, " << coarse.num_tets() << " tetrahedra, clamped at x = 0 "
         << "(a hard anchor), and the camera.\n"
         << "- `clouds/frame_NNNN.pcd`: " << o.frames << " clouds from a virtual " << o.sensor.camera.width
         << "x" << o.sensor.camera.height << " depth camera (z-buffer, every " << o.sensor.pixel_stride
         << "nd pixel, depth noise sigma = " << o.sensor.noise_coefficient << " z^2, no returns beyond "
         << o.sensor.grazing_angle_deg << " deg incidence).\n"
         << "- `ground_truth/frame_NNNN.csv`: per tracked vertex, its true position and whether the "
         << "camera saw it.\n\n"
         << "The ground truth is a corotational FEM simulation on a mesh " << o.refinement
         << " times finer (" << fine.num_vertices() << " vertices) with the free end's motion "
         << "prescribed, interpolated at the tracked mesh's rest positions: the tracker does not "
         << "share the generator's mesh (no inverse crime), but it does share its material law.\n";
  return WriteFileAtomically((fs::path(dir) / "README.md").string(), readme.str());
}

}  // namespace femreg
