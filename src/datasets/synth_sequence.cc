// femreg synth: a scene's motion script simulated on a ground truth mesh and seen by the
// virtual depth camera. Deterministic from the seed: the forward solve runs on one thread
// and every random draw comes from a per-frame generator.
#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <map>
#include <sstream>

#include "datasets/scene_numbers.h"
#include "datasets/truth_surface.h"
#include "parallel/threads.h"
#include "femreg/datasets.h"
#include "femreg/eval.h"
#include "femreg/geometry.h"
#include "femreg/forward.h"
#include "femreg/ground_truth.h"
#include "femreg/io.h"
#include "femreg/point_cloud.h"
#include "femreg/scene.h"
#include "femreg/synth.h"

namespace fs = std::filesystem;

namespace femreg {

namespace {

// A box as a closed triangle surface (12 triangles).
void BoxSurface(const Eigen::Vector3d& lo, const Eigen::Vector3d& hi, Vertices* points,
                Triangles* triangles) {
  points->resize(8, 3);
  for (int i = 0; i < 8; ++i) {
    points->row(i) << ((i & 1) ? hi.x() : lo.x()), ((i & 2) ? hi.y() : lo.y()),
        ((i & 4) ? hi.z() : lo.z());
  }
  triangles->resize(12, 3);
  *triangles << 0, 2, 1, 1, 2, 3,  // z = lo
      4, 5, 6, 5, 7, 6,            // z = hi
      0, 1, 4, 1, 5, 4,            // y = lo
      2, 6, 3, 3, 6, 7,            // y = hi
      0, 4, 2, 2, 4, 6,            // x = lo
      1, 3, 5, 3, 7, 5;            // x = hi
}

// A square of edge `size` centred at `point`, perpendicular to `normal` (2 triangles).
void Quad(const Eigen::Vector3d& point, const Eigen::Vector3d& normal, double size,
          Vertices* points, Triangles* triangles) {
  const Eigen::Vector3d n = normal.normalized();
  const Eigen::Vector3d a = n.unitOrthogonal() * (0.5 * size);
  const Eigen::Vector3d b = n.cross(a);
  points->resize(4, 3);
  points->row(0) = (point - a - b).transpose();
  points->row(1) = (point + a - b).transpose();
  points->row(2) = (point + a + b).transpose();
  points->row(3) = (point - a + b).transpose();
  triangles->resize(2, 3);
  *triangles << 0, 1, 2, 0, 2, 3;
}

// A sphere of unit radius at the origin (a UV sphere, 16 slices, 8 stacks).
void UnitSphere(Vertices* points, Triangles* triangles) {
  const int slices = 16, stacks = 8;
  points->resize(2 + slices * (stacks - 1), 3);
  points->row(0) << 0, 0, 1;
  points->row(1) << 0, 0, -1;
  for (int i = 1; i < stacks; ++i) {
    const double theta = M_PI * i / stacks;
    for (int j = 0; j < slices; ++j) {
      const double phi = 2 * M_PI * j / slices;
      points->row(2 + (i - 1) * slices + j) << std::sin(theta) * std::cos(phi),
          std::sin(theta) * std::sin(phi), std::cos(theta);
    }
  }
  const auto ring = [&](int i, int j) { return 2 + (i - 1) * slices + (j % slices); };
  triangles->resize(2 * slices * (stacks - 1), 3);
  int t = 0;
  for (int j = 0; j < slices; ++j) {
    triangles->row(t++) << 0, ring(1, j), ring(1, j + 1);
    triangles->row(t++) << 1, ring(stacks - 1, j + 1), ring(stacks - 1, j);
    for (int i = 1; i + 1 < stacks; ++i) {
      triangles->row(t++) << ring(i, j), ring(i + 1, j), ring(i + 1, j + 1);
      triangles->row(t++) << ring(i, j), ring(i + 1, j + 1), ring(i, j + 1);
    }
  }
}

// The occluder's centre at frame f: `standoff` nearer the camera than the object's nearest
// vertex, level with the object's middle, crossing its view from left to right over the
// sequence's timeline. False when it would not fit in front of the camera.
bool OccluderCentre(const DepthSensor& sensor, const Vertices& object, double radius,
                    double standoff, int f, int frames, Eigen::Vector3d* centre) {
  const Eigen::Matrix3d& R = sensor.rotation();
  const Eigen::Vector3d position = sensor.options().camera.position;
  double z_min = 1e300, tx_min = 1e300, tx_max = -1e300, ty_sum = 0.0;
  int count = 0;
  for (int v = 0; v < object.rows(); ++v) {
    const Eigen::Vector3d p = R * (object.row(v).transpose() - position);
    if (!(p.z() > 0)) continue;
    z_min = std::min(z_min, p.z());
    tx_min = std::min(tx_min, p.x() / p.z());
    tx_max = std::max(tx_max, p.x() / p.z());
    ty_sum += p.y() / p.z();
    ++count;
  }
  const double z = z_min - standoff - radius;
  if (count == 0 || z - radius <= sensor.options().near) return false;
  const double alpha = frames > 1 ? static_cast<double>(f) / (frames - 1) : 0.5;
  const double x = (z * tx_min - radius) + alpha * (z * (tx_max - tx_min) + 2 * radius);
  *centre = position + R.transpose() * Eigen::Vector3d(x, z * ty_sum / count, z);
  return true;
}

std::string FrameName(int f) {
  char name[32];
  std::snprintf(name, sizeof(name), "frame_%04d", f);
  return name;
}

std::string Fixed(double v, int digits = 3) {
  char buf[64];
  std::snprintf(buf, sizeof(buf), "%.*f", digits, v);
  return buf;
}

// Marks the ground truth vertices that the tracking scene's anchors hold. A box, a plane or
// "all" is evaluated on the truth mesh's rest positions; an index list names tracked
// vertices, so a truth vertex counts when its nearest tracked vertex at rest is listed (the
// very vertex when the truth mesh is the tracked one; of two as near, the lower index, as a
// refined truth's mid-edge vertices are), as it does for a box that selects no truth vertex.
Status MarkAnchoredTruthVertices(const std::vector<AnchorSpec>& anchors, const TetMesh& tracked,
                                 const TetMesh& truth, std::vector<char>* known) {
  const bool same_mesh = tracked.num_vertices() == truth.num_vertices() && tracked.rest == truth.rest;
  std::vector<int> nearest;  // truth vertex -> nearest tracked vertex, built on first need
  for (const AnchorSpec& anchor : anchors) {
    std::vector<int> vertices;
    if ((anchor.selection.kind != VertexSelection::Kind::kIndices || same_mesh) &&
        SelectVertices(anchor.selection, truth.rest, &vertices).ok()) {
      for (int v : vertices) (*known)[static_cast<size_t>(v)] = 1;
      continue;
    }
    // An index list, or a box that holds no truth vertex (a truth mesh of its own): by the
    // nearest tracked vertex.
    const Status status = SelectVertices(anchor.selection, tracked.rest, &vertices);
    if (!status.ok()) return Status::Error("anchor '" + anchor.name + "' (on either mesh): " + status.message());
    std::vector<char> listed(static_cast<size_t>(tracked.num_vertices()), 0);
    for (int v : vertices) listed[static_cast<size_t>(v)] = 1;
    if (nearest.empty()) {
      nearest.resize(static_cast<size_t>(truth.num_vertices()));
      for (int v = 0; v < truth.num_vertices(); ++v) {
        Eigen::Index closest = 0;
        (tracked.rest.rowwise() - truth.rest.row(v)).rowwise().squaredNorm().minCoeff(&closest);
        nearest[static_cast<size_t>(v)] = static_cast<int>(closest);
      }
    }
    for (int v = 0; v < truth.num_vertices(); ++v) {
      if (listed[static_cast<size_t>(nearest[static_cast<size_t>(v)])]) (*known)[static_cast<size_t>(v)] = 1;
    }
  }
  return Status::Ok();
}

struct Track {
  const MotionTrackSpec* spec;
  std::vector<int> vertices;
  Eigen::Vector3d centre;
};

}  // namespace

Scene SynthTrackingScene(const Scene& scene, const std::string& dir) {
  const SynthSpec& s = scene.synth;
  Scene tracking;
  tracking.description = "Tracking scene written by femreg synth from " + s.source_name + " (seed " +
                         std::to_string(s.seed) + ")";
  tracking.description += s.sanity_check
                              ? ". SANITY CHECK: the data were made with this very mesh and material"
                              : "; the ground truth comes from another mesh or material";
  tracking.objects = scene.objects;
  for (ObjectSpec& object : tracking.objects) {
    if (!object.mesh_path.empty()) {
      object.mesh_path = (fs::path(dir) / fs::path(object.mesh_path).filename()).string();
    }
    if (!object.surface_path.empty()) {
      object.surface_path = (fs::path(dir) / fs::path(object.surface_path).filename()).string();
    }
  }
  tracking.registration = scene.registration;
  // Gravity is a fact of the world the robot knows; loads, clamps and prescribed motion
  // drive the ground truth only (the robot knows what it holds: the anchors below).
  tracking.gravity = scene.gravity;
  tracking.anchors = scene.anchors;
  tracking.effects = scene.effects;
  tracking.collision = scene.collision;
  for (const MotionTrackSpec& track : s.motion) {
    if (track.anchor == MotionTrackSpec::Anchor::kNone) continue;
    AnchorSpec anchor;
    anchor.name = track.name;
    anchor.object = scene.objects.empty() ? std::string() : scene.objects[0].name;
    anchor.selection = track.selection;
    anchor.selection.where.clear();
    anchor.hard = track.anchor == MotionTrackSpec::Anchor::kHard;
    bool rotates = false;
    for (int f = 0; f < s.frames; ++f) {
      Eigen::Vector3d t, r;
      InterpolateKeyframes(track.keyframes, f, &t, &r);
      t = datasets_internal::RoundSignificant(t, 9);
      r = datasets_internal::RoundSignificant(r, 9);
      for (int k = 0; k < 3; ++k) t[k] = t[k] == 0 ? 0.0 : t[k];  // no "-0"
      for (int k = 0; k < 3; ++k) r[k] = r[k] == 0 ? 0.0 : r[k];
      anchor.translations.push_back(t);
      anchor.rotations.push_back(r);
      rotates = rotates || r.norm() > 0;
    }
    // The anchor turns about the track's centre (required when the track rotates).
    if (rotates) {
      anchor.centre = track.centre;
    } else {
      anchor.rotations.clear();
    }
    while (anchor.translations.size() > 1 &&
           anchor.translations.back() == anchor.translations[anchor.translations.size() - 2] &&
           (!rotates || anchor.rotations.back() == anchor.rotations[anchor.rotations.size() - 2])) {
      anchor.translations.pop_back();
      if (rotates) anchor.rotations.pop_back();
    }
    tracking.anchors.push_back(anchor);
  }
  return tracking;
}

Status GenerateSynthSequence(const Scene& scene, const std::string& dir, int frames,
                             SynthReport* report, void (*progress)(int done, int total)) {
  const SynthSpec& s = scene.synth;
  if (!s.enabled) return Status::Error(scene.path + ": the scene has no synth section");
  if (scene.objects.size() != 1) return Status::Error(scene.path + ": synth needs one object");
  const int num_frames = frames > 0 ? frames : s.frames;
  std::string error;
  if (!s.sensor.IsValid(&error)) return Status::Error(scene.path + ": synth." + error);
  // One thread (OpenMP and BLAS): sums in one order, the same bytes on every run.
  const ScopedThreads one_thread(1);

  // The tracked mesh and the ground truth mesh (the same object, refined or replaced).
  TetMesh coarse, fine;
  Status status = LoadObjectMesh(scene, 0, &coarse);
  if (!status.ok()) return status;
  Scene truth_scene = scene;
  ObjectSpec& truth_object = truth_scene.objects[0];
  truth_object.material = s.material;
  if (s.refinement > 1) {
    MeshGeneratorSpec& g = truth_object.generate;
    g.cells *= s.refinement;
    g.radial_cells *= s.refinement;
    g.axial_cells *= s.refinement;
  } else if (!s.mesh_path.empty()) {
    truth_object.mesh_path = s.mesh_path;
    truth_object.generate = MeshGeneratorSpec();
  } else if (s.generate.shape != MeshGeneratorSpec::Shape::kNone) {
    truth_object.generate = s.generate;
  }
  status = LoadObjectMesh(truth_scene, 0, &fine);
  if (!status.ok()) return Status::Error(s.ground_truth_where + ": " + status.message());
  // As simulate: a nearly incompressible truth (no element chosen) gets the neo-Hookean
  // element with the nodal volume, since linear tetrahedra lock and come out too stiff.
  const std::vector<std::string> chosen = ChooseForwardElements(&truth_scene);
  const std::string truth_note = chosen.empty() ? std::string() : "ground truth: " + chosen.front();
  ElasticModel model;
  const ObjectMaterial truth_material = truth_object.Materials();
  model.Build(fine, scene.forward.Model(), truth_material);
  const std::string truth_element =
      truth_material.model == MaterialModel::kNeoHookean
          ? std::string("neo-Hookean FEM") + (truth_material.nodal_volume ? " (nodal volume)" : "")
          : std::string(ToString(scene.forward.Model())) + " FEM";

  // Static boundary conditions and loads of the scene, on the ground truth mesh.
  ForwardProblem base;
  status = BuildForwardProblem(truth_scene, 0, fine, &base);
  if (!status.ok()) return status;
  std::map<int, std::string> held;  // vertex -> what holds it
  for (int v : base.clamped) held[v] = "a boundary clamp";
  for (const auto& p : base.prescribed) held[p.first] = "a boundary displacement";

  std::vector<Track> tracks;
  for (const MotionTrackSpec& spec : s.motion) {
    Track track{&spec, {}, spec.centre};
    status = SelectVertices(spec.selection, fine.rest, &track.vertices);
    if (!status.ok()) return status;
    if (!spec.has_centre) {
      track.centre.setZero();
      for (int v : track.vertices) track.centre += fine.rest.row(v).transpose();
      track.centre /= static_cast<double>(track.vertices.size());
    }
    for (int v : track.vertices) {
      auto inserted = held.emplace(v, "motion track '" + spec.name + "'");
      if (!inserted.second) {
        return Status::Error(spec.selection.where + ": vertex " + std::to_string(v) +
                             " of the ground truth mesh is held by " + inserted.first->second +
                             " as well; a vertex takes one motion");
      }
    }
    if (spec.anchor != MotionTrackSpec::Anchor::kNone) {
      std::vector<int> tracked;
      status = SelectVertices(spec.selection, coarse.rest, &tracked);
      if (!status.ok()) {
        return Status::Error(status.message() + " (on the tracked mesh, for the anchor of track '" +
                             spec.name + "')");
      }
    }
    tracks.push_back(track);
  }

  // forces.csv's truth is every external force but gravity and what the tracking scene's
  // anchors hold (the robot knows those): pressing bodies, tracks without an anchor, the
  // boundary and loads (which the tracking scene leaves out) and obstacle contacts.
  const Scene tracking_scene = SynthTrackingScene(scene, dir);
  std::vector<char> known(static_cast<size_t>(fine.num_vertices()), 0);
  status = MarkAnchoredTruthVertices(tracking_scene.anchors, coarse, fine, &known);
  if (!status.ok()) return status;
  std::vector<ForceFrame> true_forces;

  const EmbeddedPoints embedded = EmbedPoints(fine, coarse.rest);
  // The tracked object's embedded surface (objects[0].surface), if any: its vertices' ground
  // truth is where the truth mesh carries them (extrapolated like the tracker's, not clamped:
  // a scan vertex a little outside the truth mesh moves with the element next to it).
  Vertices embedded_rest;
  Triangles embedded_triangles;
  status = LoadObjectSurface(scene, 0, &embedded_rest, &embedded_triangles);
  if (!status.ok()) return status;
  const EmbeddedPoints surface_embedded =
      embedded_rest.rows() > 0 ? EmbedPoints(fine, embedded_rest, /*clamp=*/false) : EmbeddedPoints();
  const DepthSensor sensor(s.sensor);
  Vertices table_points, sphere, occluder_points;
  Triangles table_triangles, occluder_triangles;
  UnitSphere(&sphere, &occluder_triangles);
  // The timeline's third unless given, so a shorter run (--frames) keeps the same frames.
  const int leave_start = s.leave_start >= 0 ? s.leave_start : s.frames / 3;
  if (s.background) {
    Quad(s.background_point, s.background_normal, s.background_size, &table_points, &table_triangles);
  }
  const datasets_internal::TruthSurface truth_surface(fine);

  std::error_code ec;
  for (const char* sub : {"clouds", "ground_truth", "truth"}) {
    fs::create_directories(fs::path(dir) / sub, ec);
    if (ec) return Status::Error(dir + "/" + sub + ": cannot create: " + ec.message());
  }
  if (embedded_rest.rows() > 0) {
    fs::create_directories(fs::path(dir) / "ground_truth" / "surface", ec);
    if (ec) return Status::Error(dir + "/ground_truth/surface: cannot create: " + ec.message());
  }
  if (!scene.objects[0].mesh_path.empty()) {
    const fs::path target = fs::path(dir) / fs::path(scene.objects[0].mesh_path).filename();
    fs::copy_file(scene.objects[0].mesh_path, target, fs::copy_options::overwrite_existing, ec);
    if (ec) return Status::Error(target.string() + ": cannot copy the mesh: " + ec.message());
  }
  if (!scene.objects[0].surface_path.empty()) {
    const fs::path target = fs::path(dir) / fs::path(scene.objects[0].surface_path).filename();
    fs::copy_file(scene.objects[0].surface_path, target, fs::copy_options::overwrite_existing, ec);
    if (ec) return Status::Error(target.string() + ": cannot copy the surface: " + ec.message());
  }
  std::string comment =
      "Tracking scene written by `femreg synth " + s.source_name + "`: the tracked mesh, the\n"
      "camera, the registration settings and the anchors the robot knows about. Run\n"
      "  femreg register --scene scene.yaml --frames clouds --ground-truth ground_truth --out OUT";
  if (s.sanity_check) comment += "\nSANITY CHECK: the data were made with this very mesh and material.";
  status = WriteScene(tracking_scene, (fs::path(dir) / "scene.yaml").string(), comment);
  if (!status.ok()) return status;

  // The last run's forces.csv goes first: a run that fails must not leave it beside new clouds.
  std::error_code removed;
  if (!fs::remove(fs::path(dir) / "forces.csv", removed) && removed) return Status::Error(dir + "/forces.csv: " + removed.message());

  SynthReport r;
  r.note = truth_note;
  r.frames = num_frames;
  r.tracked_vertices = coarse.num_vertices();
  r.tracked_tets = coarse.num_tets();
  r.truth_vertices = fine.num_vertices();
  r.truth_tets = fine.num_tets();
  r.min_points = 1 << 30;
  double seen_sum = 0.0;
  for (int f = 0; f < num_frames; ++f) {
    ForwardProblem problem = base;
    for (const Track& track : tracks) {
      Eigen::Vector3d t, rv;
      InterpolateKeyframes(track.spec->keyframes, f, &t, &rv);
      const Eigen::Matrix3d R = RotationFromVector(rv);
      for (int v : track.vertices) {
        const Eigen::Vector3d X = fine.rest.row(v).transpose();
        problem.prescribed.emplace_back(v, track.centre + t + R * (X - track.centre) - X);
      }
    }
    // Bodies at this frame; pressing ones move their contact patch.
    std::vector<Vertices> body_points(s.bodies.size());
    std::vector<Triangles> body_triangles(s.bodies.size());
    for (size_t b = 0; b < s.bodies.size(); ++b) {
      const SynthBodySpec& body = s.bodies[b];
      Eigen::Vector3d t, rv;
      InterpolateKeyframes(body.keyframes, f, &t, &rv);
      const Eigen::Vector3d lo = body.box_min + t, hi = body.box_max + t;
      BoxSurface(lo, hi, &body_points[b], &body_triangles[b]);
      if (!body.press) continue;
      std::vector<int> under;
      double top = -1e300;
      for (int v : fine.surface_vertices) {
        const Eigen::Vector3d X = fine.rest.row(v).transpose();
        if (X.x() < lo.x() || X.x() > hi.x() || X.y() < lo.y() || X.y() > hi.y()) continue;
        under.push_back(v);
        top = std::max(top, X.z());
      }
      for (int v : under) {
        const double z = fine.rest(v, 2);
        if (z < top - body.contact_tolerance || lo.z() >= z) continue;
        if (held.count(v)) continue;  // the script holds it already
        problem.prescribed.emplace_back(v, Eigen::Vector3d(0, 0, lo.z() - z));
      }
    }
    ForwardSummary summary;
    ForwardOptions forward = scene.forward;
    forward.num_threads = 1;
    status = SolveQuasiStatic(problem, forward, &model, &fine, &summary);
    if (!status.ok()) return Status::Error(scene.path + ": frame " + std::to_string(f) + ": " + status.message());
    if (!summary.IsSolutionUsable()) {
      return Status::Error(scene.path + ": frame " + std::to_string(f) +
                           ": the forward solve failed: " + summary.message);
    }

    ForwardForces forces;
    status = EvaluateForwardForces(problem, forward, model, fine, fine.x, &forces);
    if (!status.ok()) return Status::Error(scene.path + ": frame " + std::to_string(f) + ": " + status.message());
    // Contacts, loads and unanchored reactions; nothing where an anchor holds (as the tracker).
    Vertices external = forces.potential + forces.loads - fine.mass * problem.gravity.transpose();
    for (int v = 0; v < fine.num_vertices(); ++v) {
      if (known[static_cast<size_t>(v)]) external.row(v).setZero();
      else external.row(v) += forces.reactions.row(v);
    }
    ForceResultant resultant = ResultantAboutCentroid(external, fine.x, fine.mass);
    // What is left of forces that balance (a rigidly carried body) is the solve's unbalanced
    // residual, not a force: below what the solve left unbalanced (its free vertices' residual,
    // whose resultant is at most sqrt(N) times its norm) or a millionth of the forces that act,
    // it is written as zero.
    double acting = (fine.mass.sum() * problem.gravity).norm();
    for (int v = 0; v < fine.num_vertices(); ++v) acting += forces.reactions.row(v).norm();
    const double free_vertices = std::max(1.0, summary.num_free_dofs / 3.0);
    const double floor = std::max(1e-6 * acting, std::sqrt(free_vertices) * summary.final_residual_norm);
    const double size = (fine.x.colwise().maxCoeff() - fine.x.colwise().minCoeff()).norm();
    if (resultant.force.norm() < floor) resultant.force.setZero();
    if (resultant.torque.norm() < floor * size) resultant.torque.setZero();
    true_forces.push_back({f, resultant.force, resultant.torque});

    const bool left = f >= leave_start && f < leave_start + s.leave_frames;
    std::vector<RenderSurface> surfaces;
    if (!left) surfaces.push_back({&fine.x, &fine.surface, true});
    if (s.occluder_radius > 0) {
      Eigen::Vector3d centre;
      if (!OccluderCentre(sensor, fine.x, s.occluder_radius, s.occluder_standoff, f, s.frames,
                          &centre)) {
        return Status::Error(scene.path + ": frame " + std::to_string(f) +
                             ": the occluder does not fit between the camera and the object "
                             "(a smaller radius or standoff)");
      }
      occluder_points = (sphere * s.occluder_radius).rowwise() + centre.transpose();
      surfaces.push_back({&occluder_points, &occluder_triangles, true});
    }
    if (s.background) surfaces.push_back({&table_points, &table_triangles, true});
    for (size_t b = 0; b < s.bodies.size(); ++b) {
      surfaces.push_back({&body_points[b], &body_triangles[b], s.bodies[b].in_cloud});
    }
    const DepthImage image = sensor.Render(surfaces);
    const PointCloud cloud = sensor.Sample(image, surfaces, s.seed * 1000003ull + static_cast<uint64_t>(f));
    GroundTruthFrame truth;
    truth.positions = InterpolateEmbedded(fine, fine.x, embedded);
    truth.visible = sensor.Visible(image, truth.positions, 2e-3);
    if (left) std::fill(truth.visible.begin(), truth.visible.end(), 0);

    const std::string name = FrameName(f);
    status = WritePointCloud((fs::path(dir) / "clouds" / (name + ".pcd")).string(), cloud);
    if (status.ok()) {
      status = WriteGroundTruthFrame((fs::path(dir) / "ground_truth" / (name + ".csv")).string(), truth);
    }
    if (status.ok() && embedded_rest.rows() > 0) {
      // One row per vertex of the embedded surface (ground_truth/surface/NAME.csv).
      GroundTruthFrame surface_truth;
      surface_truth.positions = InterpolateEmbedded(fine, fine.x, surface_embedded);
      surface_truth.visible = left ? std::vector<char>(static_cast<size_t>(surface_truth.positions.rows()), 0)
                                   : sensor.Visible(image, surface_truth.positions, 2e-3);
      status = WriteGroundTruthFrame((fs::path(dir) / "ground_truth" / "surface" / (name + ".csv")).string(),
                                     surface_truth);
    }
    if (status.ok()) status = truth_surface.Write((fs::path(dir) / "truth" / (name + ".vtu")).string(), fine);
    if (!status.ok()) return status;
    r.min_points = std::min(r.min_points, cloud.size());
    r.max_points = std::max(r.max_points, cloud.size());
    int seen = 0;
    for (char c : truth.visible) seen += c ? 1 : 0;
    seen_sum += static_cast<double>(seen) / std::max(1, coarse.num_vertices());
    if (progress) progress(f + 1, num_frames);
  }
  r.mean_seen_fraction = seen_sum / num_frames;

  status = WriteForces((fs::path(dir) / "forces.csv").string(), true_forces);
  if (!status.ok()) return status;

  const ObjectSpec& object = scene.objects[0];
  const CameraOptions& c = s.sensor.camera;
  std::ostringstream md;
  md << "# " << s.source_name << ": synthetic sequence with ground truth\n\n";
  if (s.sanity_check) {
    md << "**SANITY CHECK**: the data were made with the very mesh and material that "
       << "`scene.yaml` tracks with (an inverse crime). Errors on it show what the tracker "
       << "does at best; they are not an accuracy estimate.\n\n";
  }
  md << "Made by `femreg synth " << s.source_name << " --out DIR` (seed " << s.seed << ", "
     << num_frames
     << " frames; deterministic: the same command rewrites the same bytes on the same machine).\n\n"
     << "- `scene.yaml`: the tracking scene: object `" << object.name << "`, "
     << coarse.num_vertices() << " vertices, " << coarse.num_tets() << " tetrahedra, E = "
     << object.material.youngs_modulus << " Pa, nu = " << object.material.poisson_ratio
     << "; the camera; the registration settings and the anchors the robot knows about.\n"
     << "- `clouds/frame_NNNN.pcd`: " << r.min_points << " to " << r.max_points
     << " points per frame from a virtual " << c.width << "x" << c.height
     << " depth camera (z-buffer, "
     << (s.sensor.pixel_stride == 1 ? std::string("every pixel")
                                    : "one pixel in " + std::to_string(s.sensor.pixel_stride) + " in u and v")
     << ", depth noise sigma = " << s.sensor.noise_coefficient
     << " z^2, no returns beyond " << s.sensor.grazing_angle_deg << " deg incidence, "
     << s.sensor.outlier_fraction * 100 << "% outliers)";
  if (s.background) md << ", with a " << s.background_size << " m table quad in view";
  const std::string artefacts = SynthArtefactSummary(s);
  if (!artefacts.empty()) md << "; artefacts (femreg synth's `artefacts`): " << artefacts;
  md << ".\n"
     << "- `ground_truth/frame_NNNN.csv`: per tracked vertex, its true position (x,y,z in m) "
     << "and whether the camera saw it (on average " << Fixed(100 * r.mean_seen_fraction, 1)
     << "% of the vertices).\n"
     << "- `truth/frame_NNNN.vtu`: the ground truth mesh's surface per frame (for "
     << "`femreg eval`).\n"
     << "- `forces.csv`: per frame, the resultant of the external forces on the ground truth "
     << "(N) and their torque about its centroid (N m): what presses, pulls or supports it, "
     << "gravity and the reactions of the tracking scene's anchors left out (the estimate "
     << "`femreg register` makes with `registration.forces.estimate`, compared by `femreg "
     << "eval`).\n\n"
     << "The ground truth is a quasi-static " << truth_element << " "
     << "simulation on ";
  if (s.sanity_check) {
    md << "the tracked mesh itself";
  } else if (s.refinement > 1) {
    md << "the tracked mesh refined " << s.refinement << " times";
  } else {
    md << "a mesh of its own";
  }
  md << " (" << fine.num_vertices() << " vertices, " << fine.num_tets() << " tetrahedra; E = "
     << s.material.youngs_modulus << " Pa, nu = " << s.material.poisson_ratio
     << "), interpolated at the tracked mesh's rest positions.\n";
  if (!s.motion.empty()) {
    md << "\nMotion script (vertex sets moved rigidly from rest, keyframes interpolated "
       << "linearly):\n\n";
    for (const Track& t : tracks) {
      md << "- `" << t.spec->name << "`: " << t.vertices.size() << " vertices, "
         << t.spec->keyframes.size() << " keyframes"
         << (t.spec->anchor == MotionTrackSpec::Anchor::kNone
                 ? ""
                 : std::string("; the tracking scene holds it with a ") +
                       ToString(t.spec->anchor) +
                       " anchor")
         << ".\n";
    }
  }
  for (const SynthBodySpec& body : s.bodies) {
    md << "- `" << body.name << "`: a rigid box, rendered"
       << (body.in_cloud ? " into the clouds" : " as an occluder (its own points are masked out)")
       << (body.press ? "; pressed into the object: the object's top surface vertices under its "
                        "footprint are moved down to its bottom face (prescribed displacements "
                        "of the contact patch, not a contact solve)"
                      : "")
       << "; it is not part of the ground truth.\n";
  }
  status = WriteFileAtomically((fs::path(dir) / "README.md").string(), md.str());
  if (!status.ok()) return status;
  if (report) *report = r;
  return Status::Ok();
}

}  // namespace femreg
