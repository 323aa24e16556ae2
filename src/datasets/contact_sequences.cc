// The bundled contact sequences (contact_pair, tool_table): ground truth from a forward solve
// with the contact penalty on meshes twice as fine as the tracked ones, clouds from the
// virtual depth camera.
#include <cstdio>
#include <filesystem>
#include <sstream>

#include "datasets/binary_stl.h"
#include "datasets/scene_numbers.h"
#include "femreg/collision.h"
#include "femreg/datasets.h"
#include "femreg/forward.h"
#include "femreg/ground_truth.h"
#include "femreg/io.h"
#include "femreg/point_cloud.h"
#include "femreg/scene.h"
#include "femreg/synth.h"

namespace fs = std::filesystem;

namespace femreg {

std::vector<std::string> ContactScenarios() { return {"contact_pair", "tool_table"}; }

namespace {

struct Block {
  std::string name;
  Eigen::Vector3d size, origin;
  Eigen::Vector3i cells;
};

DepthSensorOptions Sensor(const Eigen::Vector3d& position, const Eigen::Vector3d& target) {
  DepthSensorOptions s;
  CameraOptions& c = s.camera;
  c.enabled = true;
  c.position = position;
  c.target = target;
  c.up = Eigen::Vector3d::UnitZ();
  c.width = 320;
  c.height = 240;
  c.fx = c.fy = 262.5;
  c.cx = 159.5;
  c.cy = 119.5;
  s.pixel_stride = 2;
  return s;
}

// contact_pair's gripper at frame f of `frames`: down through the gap in the first half, then
// along +x while pressing (the amounts below).
Eigen::Vector3d GripperPath(int f, int frames) {
  const double s = static_cast<double>(f) / (frames - 1);
  return Eigen::Vector3d(0.006 * std::max(0.0, 2 * s - 1), 0.0, -0.007 * std::min(1.0, 2 * s));
}

}  // namespace

Status GenerateContactSequence(const std::string& scenario, const std::string& dir,
                               void (*progress)(int done, int total)) {
  const bool pair = scenario == "contact_pair";
  if (!pair && scenario != "tool_table") {
    return Status::Error("unknown contact scenario '" + scenario + "' (contact_pair, tool_table)");
  }
  std::error_code ec;
  fs::create_directories(fs::path(dir) / "clouds", ec);
  fs::create_directories(fs::path(dir) / "ground_truth", ec);
  if (ec) return Status::Error(dir + ": cannot create: " + ec.message());

  const int frames = 12, refinement = 2;
  const double D = 0.0015, k = pair ? 3000.0 : 2000.0;
  Material material;
  material.youngs_modulus = pair ? 3.0e4 : 5.0e4;
  material.poisson_ratio = 0.35;
  material.density = 200.0;
  std::vector<Block> blocks;
  if (pair) {
    blocks.push_back({"base", {0.06, 0.06, 0.03}, {0, 0, 0}, {5, 5, 2}});
    blocks.push_back({"top", {0.04, 0.04, 0.03}, {0.01, 0.01, 0.0325}, {4, 4, 2}});
  } else {
    blocks.push_back({"slab", {0.12, 0.04, 0.01}, {0, 0, 0.006}, {12, 4, 2}});
  }
  // Tracked (coarse) and ground-truth (fine) meshes, one merged fine mesh for the solve.
  std::vector<TetMesh> coarse, fine;
  for (const Block& b : blocks) {
    coarse.push_back(MakeBox(b.size, b.cells.x(), b.cells.y(), b.cells.z(), b.origin));
    fine.push_back(MakeBox(b.size, refinement * b.cells.x(), refinement * b.cells.y(),
                           refinement * b.cells.z(), b.origin));
    ComputeLumpedMasses(&fine.back(), material.density);
  }
  std::vector<int> offsets;
  TetMesh merged = MergeMeshes(fine, &offsets);
  std::vector<EmbeddedPoints> embedded;
  for (size_t i = 0; i < blocks.size(); ++i) embedded.push_back(EmbedPoints(fine[i], coarse[i].rest));
  ElasticModel model;
  model.Build(merged, ElasticModelType::kCorotational, material);

  // Boundary conditions and obstacles.
  ForwardProblem problem;
  const double tol = 1e-9;
  std::vector<int> moved;  // contact_pair: the top block's top face, a gripper
  for (int v = 0; v < merged.num_vertices(); ++v) {
    const Eigen::Vector3d X = merged.rest.row(v);
    if (pair) {
      if (v < offsets[1] && X.z() <= tol) problem.clamped.push_back(v);
      if (v >= offsets[1] && X.z() >= 0.0625 - tol) moved.push_back(v);
    } else if (X.x() <= tol) {
      problem.clamped.push_back(v);
    }
  }
  CollisionSpec spec;
  spec.stiffness = k;
  spec.distance = D;
  std::vector<std::string> names;
  for (const Block& b : blocks) names.push_back(b.name);
  std::vector<ObstacleKeyframe> tool_keys(3);
  const std::string tool_file = "tool.stl";
  if (pair) {
    spec.pairs = {{"base", "top"}};
  } else {
    ObstacleSpec table;
    table.name = "table";
    table.kind = ObstacleSpec::Kind::kPlane;
    spec.obstacles.push_back(table);
    // The tool: a 2 x 5 x 2 cm box surface written as binary STL, centred at its origin.
    const TetMesh box = MakeBox(Eigen::Vector3d(0.02, 0.05, 0.02), 1, 1, 1,
                                Eigen::Vector3d(-0.01, -0.025, -0.01));
    Status status = WriteFileAtomically((fs::path(dir) / tool_file).string(),
                                        datasets_internal::BinaryStl(box.rest, box.surface));
    if (!status.ok()) return status;
    ObstacleSpec tool;
    tool.name = "tool";
    tool.kind = ObstacleSpec::Kind::kMesh;
    tool.mesh_path = (fs::path(dir) / tool_file).string();
    // Down onto the free end (the tool's bottom from above the slab's top into it), then along -x.
    tool_keys[0].frame = 0;
    tool_keys[0].translation = Eigen::Vector3d(0.105, 0.02, 0.028);
    tool_keys[1].frame = 9;
    tool_keys[1].translation = Eigen::Vector3d(0.105, 0.02, 0.0225);
    tool_keys[2].frame = frames - 1;
    tool_keys[2].translation = Eigen::Vector3d(0.085, 0.02, 0.0225);
    tool.keyframes = tool_keys;
    spec.obstacles.push_back(tool);
  }
  std::vector<Triangles> surfaces;
  for (size_t i = 0; i < fine.size(); ++i) surfaces.push_back(fine[i].surface.array() + offsets[i]);
  CollisionWorld world;
  Status status = world.Init(spec, names, surfaces, merged.x);
  if (!status.ok()) return status;
  ContactPotential potential(&world, 0.5 * D);
  problem.potential = &potential;
  ForwardOptions forward;
  forward.num_threads = 1;  // one summation order: the same bytes on every machine load
  forward.max_iterations = 25;
  forward.load_steps = pair ? 3 : 2;

  const DepthSensorOptions sensor_options =
      pair ? Sensor(Eigen::Vector3d(0.03, -0.16, 0.16), Eigen::Vector3d(0.03, 0.03, 0.03))
           : Sensor(Eigen::Vector3d(0.06, -0.2, 0.16), Eigen::Vector3d(0.06, 0.02, 0.0));
  const DepthSensor sensor(sensor_options);
  // Occluders without returns: the table (a square) and the tool.
  Vertices table_v(4, 3);
  table_v << -0.1, -0.1, 0, 0.3, -0.1, 0, 0.3, 0.2, 0, -0.1, 0.2, 0;
  Triangles table_t(2, 3);
  table_t << 0, 1, 2, 0, 2, 3;
  Vertices tool_world;
  Triangles tool_tris;

  // Per frame: the solve's iterations, the active contacts and the deepest penetration of the
  // ground truth itself (the penalty, zero at contact, lets it in by force / k).
  std::ostringstream log;
  log << "frame,newton_iterations,termination,final_residual_N,contacts,max_penetration_mm\n";
  // tool_table: the contacts' resultant on the slab per frame (the tool's and the table's
  // pushes; no gravity, and the clamp's reaction left out).
  std::vector<ForceFrame> contact_forces;
  for (int f = 0; f < frames; ++f) {
    world.SetFrame(f);
    ForwardProblem step = problem;
    if (pair) {
      for (int v : moved) step.prescribed.emplace_back(v, GripperPath(f, frames));
    }
    ForwardSummary summary;
    status = SolveQuasiStatic(step, forward, &model, &merged, &summary);
    if (!status.ok()) return status;
    if (!summary.IsSolutionUsable()) {
      return Status::Error(scenario + " frame " + std::to_string(f) + ": " + summary.message);
    }
    if (!pair) {
      ForwardForces forces;
      status = EvaluateForwardForces(step, forward, model, merged, merged.x, &forces);
      if (!status.ok()) return status;
      const ForceResultant contact =
          ResultantAboutCentroid(forces.potential, merged.x, merged.mass);
      contact_forces.push_back({f, contact.force, contact.torque});
    }
    {
      std::vector<Contact> contacts;
      world.Detect(merged.x, 0.0, &contacts);
      const ContactStats cs = world.Evaluate(contacts, merged.x);
      char line[160];
      std::snprintf(line, sizeof(line), "%d,%zu,%s,%.3e,%d,%.4f\n", f, summary.iterations.size(),
                    ToString(summary.termination), summary.final_residual_norm, cs.contacts,
                    cs.max_penetration * 1e3);
      log << line;
    }
    std::vector<RenderSurface> render = {{&merged.x, &merged.surface, true}};
    if (!pair) {
      tool_world = world.obstacle_vertices(1);
      tool_tris = world.obstacle_triangles(1);
      render.push_back({&table_v, &table_t, false});
      render.push_back({&tool_world, &tool_tris, false});
    }
    const DepthImage image = sensor.Render(render);
    const PointCloud cloud = sensor.Sample(image, render, 7919ull * (pair ? 1 : 2) + static_cast<uint64_t>(f));
    GroundTruthFrame truth;
    int rows = 0;
    for (const TetMesh& c : coarse) rows += c.num_vertices();
    truth.positions.resize(rows, 3);
    int row = 0;
    for (size_t i = 0; i < blocks.size(); ++i) {
      const Vertices xi = merged.x.middleRows(offsets[i], fine[i].num_vertices());
      truth.positions.middleRows(row, coarse[i].num_vertices()) = InterpolateEmbedded(fine[i], xi, embedded[i]);
      row += coarse[i].num_vertices();
    }
    truth.visible = sensor.Visible(image, truth.positions, 2e-3);
    char name[64];
    std::snprintf(name, sizeof(name), "frame_%04d", f);
    status = WritePointCloud((fs::path(dir) / "clouds" / (std::string(name) + ".pcd")).string(), cloud);
    if (!status.ok()) return status;
    status = WriteGroundTruthFrame((fs::path(dir) / "ground_truth" / (std::string(name) + ".csv")).string(), truth);
    if (!status.ok()) return status;
    if (progress) progress(f + 1, frames);
  }

  status = WriteFileAtomically((fs::path(dir) / "truth_contacts.csv").string(), log.str());
  if (status.ok() && !pair) {
    status = WriteForces((fs::path(dir) / "forces.csv").string(), contact_forces);
  }
  if (!status.ok()) return status;

  // The tracking scene: the coarse blocks, the camera, the known support and gripper, and
  // the contacts (the tool's mesh beside it). The gripper's path keeps the 10 significant
  // digits the scene has always been written with.
  Scene tracking;
  tracking.description = scenario + ", " + std::to_string(frames) + " frames";
  for (const Block& b : blocks) {
    ObjectSpec object;
    object.name = b.name;
    object.generate.shape = MeshGeneratorSpec::Shape::kBox;
    object.generate.size = b.size;
    object.generate.cells = b.cells;
    object.generate.origin = b.origin;
    object.material = material;
    tracking.objects.push_back(object);
  }
  tracking.registration.camera = sensor_options.camera;
  tracking.registration.data.max_distance = 0.02;
  tracking.registration.data.visibility = true;
  auto box = [](const Eigen::Vector3d& lo, const Eigen::Vector3d& hi) {
    VertexSelection selection;
    selection.kind = VertexSelection::Kind::kBox;
    selection.box_min = lo;
    selection.box_max = hi;
    return selection;
  };
  AnchorSpec support;
  support.name = "support";
  support.object = blocks[0].name;
  support.hard = true;
  support.selection = pair ? box(Eigen::Vector3d(-1, -1, -1), Eigen::Vector3d(1, 1, 0.0001))
                           : box(Eigen::Vector3d(-1, -1, -1), Eigen::Vector3d(0.0001, 1, 1));
  tracking.anchors.push_back(support);
  if (pair) {
    AnchorSpec gripper;
    gripper.name = "gripper";
    gripper.object = "top";
    gripper.hard = true;
    gripper.selection = box(Eigen::Vector3d(-1, -1, 0.0624), Eigen::Vector3d(1, 1, 1));
    for (int f = 0; f < frames; ++f) {
      gripper.translations.push_back(datasets_internal::RoundSignificant(GripperPath(f, frames), 10));
    }
    tracking.anchors.push_back(gripper);
  }
  tracking.effects.collision = true;
  tracking.collision = spec;
  status = WriteScene(tracking, (fs::path(dir) / "scene.yaml").string(),
                      scenario + ": made by `femreg contact-data --scenario " + scenario +
                          "` (see README.md beside this file).");
  if (!status.ok()) return status;

  std::ostringstream readme;
  readme << "# " << scenario << ": a contact sequence with ground truth\n\n"
         << "Made by `femreg contact-data --scenario " << scenario << " --out <dir>` (deterministic).\n\n";
  if (pair) {
    readme << "Two soft blocks (E = " << material.youngs_modulus << " Pa): `base` (6 x 6 x 3 cm) is "
           << "clamped at its bottom; `top` (4 x 4 x 3 cm) starts 2.5 mm above it and its top face is "
           << "moved by a gripper: 7 mm down over the first half, then 6 mm along +x while pressing.\n";
  } else {
    readme << "A soft slab (12 x 4 x 1 cm, E = " << material.youngs_modulus << " Pa), clamped at x = 0 "
           << "6 mm above a table (the plane z = 0), is pushed down onto the table by a rigid tool (a 2 x "
           << "5 x 2 cm box, `tool.stl`) moving down and then along -x (keyframes in scene.yaml). The "
           << "tool and the table occlude but return no points (segmented out).\n";
  }
  readme << "\n- `scene.yaml`: the tracking scene, with `effects: {collision: true}` and the "
         << "`collision:` section (k = " << k << " N/m, D = " << D * 1e3 << " mm).\n"
         << "- `clouds/frame_NNNN.pcd`: " << frames << " clouds of a virtual 320x240 depth camera.\n"
         << "- `ground_truth/frame_NNNN.csv`: one row per tracked vertex of all objects in scene "
         << "order: true position and whether the camera saw it.\n"
         << "- `truth_contacts.csv`: per frame, the ground-truth solve's Newton iterations, its "
         << "termination and final force imbalance, its touching contacts and its deepest penetration "
         << "(mm, the most a vertex crossed the other surface: the penalty, zero at contact, lets a "
         << "contact in by its force / k).\n";
  if (!pair) {
    readme << "- `forces.csv`: per frame, the resultant of the contact forces on the slab (N; the "
           << "tool's and the table's pushes, from the ground-truth solve's contact penalty) and "
           << "their torque about the slab's centroid (N m; the lumped-mass-weighted mean of the "
           << "true vertex positions). There is no gravity; the clamp's reaction, the only other "
           << "force on the slab, is left out, as an estimate in `femreg register`'s stats.csv "
           << "leaves it out (`femreg eval` compares the two).\n";
  }
  readme << "\n"
         << "Ground truth: corotational FEM with the same penalty contacts (refreshed per Newton "
         << "iteration) on meshes " << refinement << " times finer, interpolated at the tracked "
         << "vertices. Register with collision on, and with `femreg register --no-collision` to "
         << "compare (the penetration is then measured, not prevented).\n";
  return WriteFileAtomically((fs::path(dir) / "README.md").string(), readme.str());
}

}  // namespace femreg
