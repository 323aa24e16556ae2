// The bundled hand_press sequence (issue 38): a soft foam ball resting on a table under
// gravity, pressed from above by a rigid hand-like body whose points are in the clouds, then
// grasped from two sides, lifted, tilted and set down again, seen by one depth camera above
// and in front of it. Ground truth shapes and the external forces on the ball per frame.
//
// Contacts are sticking (no slip) and unilateral, solved as an active set of prescribed
// displacements: the forward solve needs held vertices (a free body is singular there, and
// its penalty contacts have no friction to hold the ball on the table). A vertex that
// crosses the table or a part of the hand is held at the point of that surface nearest to
// it, moving with the surface; a held vertex whose reaction pulls on the surface is let go.
// The reactions of the held vertices are the contact forces.
#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <map>
#include <sstream>
#include <vector>

#include "femreg/datasets.h"
#include "femreg/eval.h"
#include "femreg/forward.h"
#include "femreg/geometry.h"
#include "femreg/ground_truth.h"
#include "femreg/io.h"
#include "femreg/point_cloud.h"
#include "femreg/synth.h"
#include "parallel/threads.h"
#include "registration/cloud_subset.h"
#include "datasets/hand_press_internal.h"
#include "datasets/truth_surface.h"

namespace fs = std::filesystem;

namespace femreg {
namespace {

using hand_press_internal::Camera;
using hand_press_internal::Foam;
using hand_press_internal::Format;
using hand_press_internal::kCrossing;
using hand_press_internal::kFrames;
using hand_press_internal::kGravity;
using hand_press_internal::kMaxRounds;
using hand_press_internal::kMaxStep;
using hand_press_internal::kPull;
using hand_press_internal::kRadius;
using hand_press_internal::kTrackedCells;
using hand_press_internal::kTruthCells;
using hand_press_internal::Readme;
using hand_press_internal::TrackingScene;


// The points of `cloud` whose pixel saw surface `kept` of `image`: a mask that keeps only
// that surface. A point lies on its pixel's ray (noise moves it along the ray), so projecting
// it gives its pixel back.
PointCloud OnlySurface(const PointCloud& cloud, const DepthImage& image, const DepthSensor& sensor,
                       int kept) {
  PointCloud out = cloud;
  KeepPoints(
      [&](int i) {
        double u = 0, v = 0, z = 0;
        if (!sensor.Project(cloud.points.row(i).transpose(), &u, &v, &z)) return false;
        const long px = std::lround(u), py = std::lround(v);
        if (px < 0 || py < 0 || px >= image.width || py >= image.height) return false;
        return image.surface[static_cast<size_t>(py * image.width + px)] == kept;
      },
      &out);
  return out;
}

// A rounded box: the points within `radius` of the box of half-extents `half` centred at
// the origin of its frame.
struct RoundedBox {
  Eigen::Vector3d half;
  double radius;

  // Signed distance of p (local) to the surface, negative inside; *closest gets the nearest
  // surface point and *normal the outward normal there.
  double Distance(const Eigen::Vector3d& p, Eigen::Vector3d* closest,
                  Eigen::Vector3d* normal) const {
    const Eigen::Vector3d q = p.cwiseMax(-half).cwiseMin(half);
    const Eigen::Vector3d d = p - q;
    const double length = d.norm();
    if (length > 0) {
      *normal = d / length;
      *closest = q + radius * *normal;
      return length - radius;
    }
    int axis = 0;  // inside the core: out through its nearest face
    for (int k = 1; k < 3; ++k) {
      if (half[k] - std::abs(p[k]) < half[axis] - std::abs(p[axis])) axis = k;
    }
    *normal = Eigen::Vector3d::Zero();
    (*normal)[axis] = p[axis] < 0 ? -1.0 : 1.0;
    *closest = p;
    (*closest)[axis] = (*normal)[axis] * (half[axis] + radius);
    return -(half[axis] - std::abs(p[axis])) - radius;
  }

  // The surface as triangles (local): each face of the box grown by `radius` as a grid whose
  // points are moved onto the rounded surface (the grid lines past the core bend round the
  // edges and corners).
  void Surface(Vertices* points, Triangles* triangles) const {
    std::vector<std::vector<double>> ticks(3);
    for (int k = 0; k < 3; ++k) {
      for (double a : {90.0, 60.0, 30.0})
        ticks[k].push_back(-half[k] - radius * std::sin(a * M_PI / 180.0));
      const int inner = std::max(2, static_cast<int>(std::ceil(2.0 * half[k] / 0.01)) + 1);
      for (int i = 0; i < inner; ++i)
        ticks[k].push_back(-half[k] + 2.0 * half[k] * i / (inner - 1));
      for (double a : {30.0, 60.0, 90.0})
        ticks[k].push_back(half[k] + radius * std::sin(a * M_PI / 180.0));
    }
    std::vector<Eigen::Vector3d> pts;
    std::vector<Eigen::Vector3i> tris;
    for (int axis = 0; axis < 3; ++axis) {
      const int u = (axis + 1) % 3, v = (axis + 2) % 3;  // (axis, u, v) right-handed
      for (double side : {-1.0, 1.0}) {
        const int base = static_cast<int>(pts.size());
        const int nu = static_cast<int>(ticks[u].size()), nv = static_cast<int>(ticks[v].size());
        for (int i = 0; i < nu; ++i) {
          for (int j = 0; j < nv; ++j) {
            Eigen::Vector3d p;
            p[axis] = side * (half[axis] + radius);
            p[u] = ticks[u][i];
            p[v] = ticks[v][j];
            const Eigen::Vector3d q = p.cwiseMax(-half).cwiseMin(half);
            pts.push_back(q + radius * (p - q).normalized());
          }
        }
        for (int i = 0; i + 1 < nu; ++i) {
          for (int j = 0; j + 1 < nv; ++j) {
            const int a = base + i * nv + j, b = a + nv, c = b + 1, d = a + 1;
            if (side > 0) {
              tris.emplace_back(a, b, c);
              tris.emplace_back(a, c, d);
            } else {
              tris.emplace_back(a, c, b);
              tris.emplace_back(a, d, c);
            }
          }
        }
      }
    }
    points->resize(static_cast<Eigen::Index>(pts.size()), 3);
    for (size_t i = 0; i < pts.size(); ++i)
      points->row(static_cast<Eigen::Index>(i)) = pts[i].transpose();
    triangles->resize(static_cast<Eigen::Index>(tris.size()), 3);
    for (size_t i = 0; i < tris.size(); ++i)
      triangles->row(static_cast<Eigen::Index>(i)) = tris[i].transpose();
  }
};

// The hand: a palm (9 x 8 x 3 cm) above the ball and two finger pads (a thumb at -x and the
// fingers at +x, 2 x 5.2 x 3.6 cm each), rigid, in a frame whose origin is the ball's rest
// centre. The pads open and close along x and are curled up by `finger_lift` while the
// palm presses.
const RoundedBox kPalm{Eigen::Vector3d(0.035, 0.03, 0.005), 0.01};
const RoundedBox kPad{Eigen::Vector3d(0.004, 0.02, 0.012), 0.006};
constexpr double kPalmHeight = 0.08;  // palm centre above the hand's origin (bottom: 0.065)

struct HandKey {
  int frame;
  Eigen::Vector3d translation;  // of the hand's origin from the ball's rest centre (m)
  Eigen::Vector3d rotation;     // about the hand's origin, axis * angle (rad)
  double opening;               // x of each pad's inner face from the hand's axis (m)
  double finger_lift;           // the pads' height above the hand's origin (m)
};

// The script. Rest (0-2); the palm, tilted 0.1 rad towards the camera, comes down and
// presses the ball 15 mm below its rest top (3-8) and lets go (9-11); the pads close
// 8 mm into its sides (12-14), lift it 4 cm while turning it 0.3 rad about the grasp axis
// and carrying it 2 cm along +x (15-19), set it down there (20-24), open and leave (25-29).
const std::vector<HandKey>& Script() {
  static const std::vector<HandKey> keys = {
      {0, {0, 0, 0.10}, {0.1, 0, 0}, 0.075, 0.02},
      {2, {0, 0, 0.02}, {0.1, 0, 0}, 0.075, 0.02},
      {3, {0, 0, -0.015}, {0.1, 0, 0}, 0.075, 0.02},
      {7, {0, 0, -0.0335}, {0.1, 0, 0}, 0.075, 0.02},
      {8, {0, 0, -0.0335}, {0.1, 0, 0}, 0.075, 0.02},
      {10, {0, 0, 0.0}, {0.1, 0, 0}, 0.075, 0.02},
      {11, {0, 0, 0.0}, {0, 0, 0}, 0.075, 0.0},
      {12, {0, 0, 0.0}, {0, 0, 0}, 0.06, 0.0},
      {13, {0, 0, 0.0}, {0, 0, 0}, 0.05, 0.0},
      {14, {0, 0, 0.0}, {0, 0, 0}, 0.042, 0.0},
      {15, {0, 0, 0.005}, {0, 0, 0}, 0.042, 0.0},
      {16, {0.005, 0, 0.02}, {0.1, 0, 0}, 0.042, 0.0},
      {17, {0.01, 0, 0.035}, {0.2, 0, 0}, 0.042, 0.0},
      {18, {0.02, 0, 0.04}, {0.3, 0, 0}, 0.042, 0.0},
      {19, {0.02, 0, 0.04}, {0.3, 0, 0}, 0.042, 0.0},
      {20, {0.02, 0, 0.03}, {0.2, 0, 0}, 0.042, 0.0},
      {21, {0.02, 0, 0.015}, {0.1, 0, 0}, 0.042, 0.0},
      {22, {0.02, 0, 0.004}, {0, 0, 0}, 0.042, 0.0},
      {23, {0.02, 0, 0.0}, {0, 0, 0}, 0.042, 0.0},
      {24, {0.02, 0, 0.0}, {0, 0, 0}, 0.042, 0.0},
      {25, {0.02, 0, 0.0}, {0, 0, 0}, 0.046, 0.0},
      {26, {0.02, 0, 0.0}, {0, 0, 0}, 0.052, 0.0},
      {27, {0.02, 0, 0.01}, {0, 0, 0}, 0.065, 0.0},
      {28, {0.02, 0, 0.08}, {0, 0, 0}, 0.075, 0.0},
      {29, {0.02, 0, 0.15}, {0, 0, 0}, 0.075, 0.0},
  };
  return keys;
}

// Key i of the script with the palm's press (its descent past frame 3's touch, where it
// holds the ball deepest) scaled by `press_scale`.
HandKey ScriptKey(size_t i, double press_scale) {
  HandKey key = Script()[i];
  constexpr double kTouch = -0.015;  // frame 3's height: the palm's bottom at the ball's top
  if (press_scale != 1.0 && key.translation.z() < kTouch)
    key.translation.z() = kTouch + press_scale * (key.translation.z() - kTouch);
  return key;
}

// The hand at time t (frames; fractions between them): keys interpolated linearly (the
// rotations turn about one axis between keys, so their vectors interpolate exactly).
HandKey HandAt(double t, double press_scale) {
  const std::vector<HandKey>& keys = Script();
  if (t <= keys.front().frame) return ScriptKey(0, press_scale);
  if (t >= keys.back().frame) return ScriptKey(keys.size() - 1, press_scale);
  size_t i = 0;
  while (keys[i + 1].frame <= t) ++i;
  const HandKey a = ScriptKey(i, press_scale), b = ScriptKey(i + 1, press_scale);
  const double s = (t - a.frame) / (b.frame - a.frame);
  return {a.frame, (1 - s) * a.translation + s * b.translation,
          (1 - s) * a.rotation + s * b.rotation, (1 - s) * a.opening + s * b.opening,
          (1 - s) * a.finger_lift + s * b.finger_lift};
}

// The surfaces a vertex can be held by.
enum Surface { kTable = 0, kPalmPart = 1, kThumb = 2, kFingers = 3, kNumSurfaces = 4 };

// World poses of the hand's parts (kPalmPart, kThumb, kFingers; kTable: identity).
std::vector<Eigen::Isometry3d> PartPoses(const HandKey& hand) {
  Eigen::Isometry3d frame = Eigen::Isometry3d::Identity();
  frame.linear() = RotationFromVector(hand.rotation);
  frame.translation() = Eigen::Vector3d(0, 0, kRadius) + hand.translation;
  auto at = [&](const Eigen::Vector3d& local) {
    Eigen::Isometry3d part = Eigen::Isometry3d::Identity();
    part.translation() = local;
    return frame * part;
  };
  const double pad = hand.opening + kPad.half.x() + kPad.radius;  // pad centre from the axis
  return {Eigen::Isometry3d::Identity(), at(Eigen::Vector3d(0, 0, kPalmHeight)),
          at(Eigen::Vector3d(-pad, 0, hand.finger_lift)),
          at(Eigen::Vector3d(pad, 0, hand.finger_lift))};
}

// Signed distance of world point x to surface s (posed), the nearest surface point and
// the surface's outward normal there (world).
double DistanceTo(int s, const std::vector<Eigen::Isometry3d>& poses, const Eigen::Vector3d& x,
                  Eigen::Vector3d* closest, Eigen::Vector3d* normal) {
  if (s == kTable) {
    *closest = Eigen::Vector3d(x.x(), x.y(), 0.0);
    *normal = Eigen::Vector3d::UnitZ();
    return x.z();
  }
  const RoundedBox& box = s == kPalmPart ? kPalm : kPad;
  const Eigen::Isometry3d& pose = poses[static_cast<size_t>(s)];
  Eigen::Vector3d c, n;
  const double d = box.Distance(pose.inverse() * x, &c, &n);
  *closest = pose * c;
  *normal = pose.linear() * n;
  return d;
}

// A held vertex: the surface holding it and the point it is held at, in that surface's frame.
struct Hold {
  int surface;
  Eigen::Vector3d local;
};

std::string FrameName(int f) {
  char name[32];
  std::snprintf(name, sizeof(name), "frame_%04d", f);
  return name;
}


}  // namespace

Status GenerateHandPressSequence(const std::string& dir, int frames, HandPressReport* report,
                                 void (*progress)(int done, int total),
                                 const HandPressOptions& options) {
  if (!(options.youngs_modulus > 0) || !std::isfinite(options.youngs_modulus))
    return Status::Error("hand_press: the Young's modulus must be positive");
  if (!(options.scene_youngs_modulus >= 0) || !std::isfinite(options.scene_youngs_modulus))
    return Status::Error("hand_press: the scene's Young's modulus must be positive, or 0 for the truth's");
  if (!std::isfinite(options.camera_azimuth_deg))
    return Status::Error("hand_press: the camera's azimuth must be finite");
  if (!(options.press_scale >= 0 && options.press_scale <= 1.5))
    return Status::Error("hand_press: the press scale must be within [0, 1.5] (beyond, the palm "
                         "reaches the table through the ball)");
  const int num_frames = frames > 0 ? std::min(frames, kFrames) : kFrames;
  // One thread (OpenMP and BLAS): sums in one order, the same bytes on every run.
  const ScopedThreads one_thread(1);
  std::error_code ec;
  for (const char* sub : {"clouds", "clouds_without_hand", "ground_truth", "truth"}) {
    fs::create_directories(fs::path(dir) / sub, ec);
    if (ec) return Status::Error(dir + "/" + sub + ": cannot create: " + ec.message());
  }
  const Eigen::Vector3d centre(0, 0, kRadius);
  TetMesh coarse = MakeSphere(kRadius, kTrackedCells);
  TetMesh fine = MakeSphere(kRadius, kTruthCells);
  for (TetMesh* mesh : {&coarse, &fine}) {
    mesh->rest.rowwise() += centre.transpose();
    mesh->x = mesh->rest;
  }
  const Material material = Foam(options);
  ComputeLumpedMasses(&fine, material.density);
  const double mass = fine.mass.sum();
  const Eigen::Vector3d gravity(0, 0, -kGravity);
  ElasticModel model;
  model.Build(fine, ElasticModelType::kCorotational, material);
  const EmbeddedPoints embedded = EmbedPoints(fine, coarse.rest);

  ForwardOptions forward;
  forward.num_threads = 1;
  forward.max_iterations = 60;
  forward.relative_tolerance = 1e-9;
  forward.absolute_tolerance = 1e-10;

  DepthSensorOptions sensor_options;
  sensor_options.camera = Camera(options);
  const DepthSensor sensor(sensor_options);
  // The table occludes but returns no points: the segmentation mask keeps the ball and the
  // hand only.
  Vertices table_points(4, 3);
  table_points << -0.5, -0.5, 0, 0.5, -0.5, 0, 0.5, 0.5, 0, -0.5, 0.5, 0;
  Triangles table_triangles(2, 3);
  table_triangles << 0, 1, 2, 0, 2, 3;
  Vertices palm_local, pad_local;
  Triangles palm_triangles, pad_triangles;
  kPalm.Surface(&palm_local, &palm_triangles);
  kPad.Surface(&pad_local, &pad_triangles);
  const datasets_internal::TruthSurface truth_surface(fine);

  // Held from the start: the bottom vertices within 1 mm of the table, where the ball sinks
  // under its weight (at least three, so that the first solve is not singular).
  std::map<int, Hold> held;
  for (int v : fine.surface_vertices) {
    if (fine.rest(v, 2) < 1e-3)
      held[v] = {kTable, Eigen::Vector3d(fine.rest(v, 0), fine.rest(v, 1), 0.0)};
  }

  HandPressReport r;
  r.frames = num_frames;
  r.tracked_vertices = coarse.num_vertices();
  r.truth_vertices = fine.num_vertices();
  r.mass_kg = mass;
  r.min_points = 1 << 30;
  std::ostringstream forces;
  forces << "frame,force_x_N,force_y_N,force_z_N,torque_x_Nm,torque_y_Nm,torque_z_Nm,table_force_N,"
            "hand_force_x_N,hand_force_y_N,hand_force_z_N,contact_force_x_N,contact_force_y_N,contact_force_z_N\n";
  std::ostringstream log;
  log << "frame,substeps,active_set_rounds,newton_iterations,free_residual_N,table_vertices,palm_"
         "vertices,"
         "thumb_vertices,finger_vertices,force_imbalance_N,torque_imbalance_Nm,min_z_mm,"
         "inverted_elements\n";
  double seen_sum = 0.0;
  // The hand's parts as they are rendered; also the points whose motion sets the substeps.
  auto part_points = [&](const std::vector<Eigen::Isometry3d>& poses, int s) {
    const Vertices& local = s == kPalmPart ? palm_local : pad_local;
    Vertices world(local.rows(), 3);
    for (Eigen::Index i = 0; i < local.rows(); ++i) {
      world.row(i) =
          (poses[static_cast<size_t>(s)] * Eigen::Vector3d(local.row(i).transpose())).transpose();
    }
    return world;
  };
  Eigen::VectorXd gradient;  // of the elastic energy at the last solution (3 #V)
  ForwardSummary summary;
  int rounds = 0, newton = 0;
  // Settles the contacts with the hand's parts at `poses`: solves, holds the vertices that
  // crossed a surface where they crossed it and, only when none did, lets go of the held
  // vertices that pull hardest on their surface (a vertex let go with a crossing pending
  // could be caught again); until nothing changes. `solve`: at least once.
  auto settle = [&](int f, const std::vector<Eigen::Isometry3d>& poses, bool solve) -> Status {
    ForwardProblem problem;
    problem.gravity = gravity;
    // Nothing to do while the hand neither holds nor touches the ball: the solution stands.
    bool touched = false;
    for (const auto& h : held) touched = touched || h.second.surface != kTable;
    for (size_t i = 0; i < fine.surface_vertices.size() && !touched && !solve; ++i) {
      const Eigen::Vector3d x = fine.x.row(fine.surface_vertices[i]).transpose();
      for (int s = kPalmPart; s < kNumSurfaces && !touched; ++s) {
        Eigen::Vector3d closest, normal;
        touched = DistanceTo(s, poses, x, &closest, &normal) < -kCrossing;
      }
    }
    if (!touched && !solve) return Status::Ok();
    for (int round = 0;; ++round) {
      ++rounds;
      if (round == kMaxRounds) {
        return Status::Error("hand_press frame " + std::to_string(f) +
                             ": the contacts did not settle in " + std::to_string(kMaxRounds) +
                             " rounds");
      }
      problem.prescribed.clear();
      for (const auto& h : held) {
        const Eigen::Vector3d target =
            poses[static_cast<size_t>(h.second.surface)] * h.second.local;
        problem.prescribed.emplace_back(h.first, target - fine.rest.row(h.first).transpose());
      }
      Status status = SolveQuasiStatic(problem, forward, &model, &fine, &summary);
      if (!status.ok()) return status;
      newton += summary.NumNewtonIterations();
      if (summary.termination != ForwardTermination::kConverged) {
        return Status::Error("hand_press frame " + std::to_string(f) + ": " + summary.message);
      }
      std::vector<std::pair<int, Hold>> crossed;
      for (int v : fine.surface_vertices) {
        if (held.count(v)) continue;
        const Eigen::Vector3d x = fine.x.row(v).transpose();
        for (int s = 0; s < kNumSurfaces; ++s) {
          Eigen::Vector3d closest, normal;
          if (DistanceTo(s, poses, x, &closest, &normal) < -kCrossing) {
            crossed.push_back({v, {s, poses[static_cast<size_t>(s)].inverse() * closest}});
            break;
          }
        }
      }
      for (const auto& c : crossed) held[c.first] = c.second;
      if (!crossed.empty()) continue;
      model.UpdateRotations(fine.x);
      Vertices g = Vertices::Zero(fine.num_vertices(), 3);
      model.AddGradient(fine.x, &g);
      gradient = Eigen::Map<const Eigen::VectorXd>(g.data(), 3 * fine.num_vertices());
      // Only the vertices that pull hardest go: a hand moving away pulls the ball up off the
      // table too, and its own contacts, once let go, give the table's back their load.
      std::vector<std::pair<int, double>> pulling;
      double strongest = 0.0;
      for (const auto& h : held) {
        const int v = h.first;
        const Eigen::Vector3d reaction = gradient.segment<3>(3 * v) - fine.mass(v) * gravity;
        Eigen::Vector3d closest, normal;
        DistanceTo(h.second.surface, poses, fine.x.row(v).transpose(), &closest, &normal);
        const double pull = -reaction.dot(normal);
        if (pull > kPull) pulling.emplace_back(v, pull);
        strongest = std::max(strongest, pull);
      }
      if (pulling.empty()) return Status::Ok();
      for (const auto& p : pulling) {
        if (p.second >= 0.5 * strongest) held.erase(p.first);
      }
    }
  };
  for (int f = 0; f < num_frames; ++f) {
    const std::vector<Eigen::Isometry3d> poses = PartPoses(HandAt(f, options.press_scale));
    // From the previous frame in substeps that move no point of the hand more than kMaxStep:
    // a held vertex dragged far in one solve stretches its elements beyond what Newton
    // converges from.
    int substeps = 1;
    if (f > 0) {
      const std::vector<Eigen::Isometry3d> before = PartPoses(HandAt(f - 1, options.press_scale));
      double motion = 0.0;
      for (int s = kPalmPart; s < kNumSurfaces; ++s) {
        motion = std::max(
            motion, (part_points(poses, s) - part_points(before, s)).rowwise().norm().maxCoeff());
      }
      substeps = std::max(1, static_cast<int>(std::ceil(motion / kMaxStep)));
    }
    rounds = newton = 0;
    for (int k = 1; k <= substeps; ++k) {
      const Status status = settle(
          f,
          k == substeps
              ? poses
              : PartPoses(HandAt(f - 1 + static_cast<double>(k) / substeps, options.press_scale)),
          f == 0);
      if (!status.ok()) return status;
    }

    // The external forces: each held vertex's reaction (the elastic force it transmits minus
    // its weight), summed per surface; the balance with gravity is what is left over.
    Eigen::Vector3d table_force = Eigen::Vector3d::Zero(), hand_force = Eigen::Vector3d::Zero();
    Eigen::Vector3d centroid = Eigen::Vector3d::Zero();
    for (int v = 0; v < fine.num_vertices(); ++v)
      centroid += fine.mass(v) * fine.x.row(v).transpose();
    centroid /= mass;
    Eigen::Vector3d torque = Eigen::Vector3d::Zero();
    int counts[kNumSurfaces] = {0, 0, 0, 0};
    std::vector<char> is_held(static_cast<size_t>(fine.num_vertices()), 0);
    for (const auto& h : held) {
      const int v = h.first;
      is_held[static_cast<size_t>(v)] = 1;
      const Eigen::Vector3d reaction = gradient.segment<3>(3 * v) - fine.mass(v) * gravity;
      (h.second.surface == kTable ? table_force : hand_force) += reaction;
      torque += (fine.x.row(v).transpose() - centroid).cross(reaction);
      ++counts[h.second.surface];
    }
    double free_residual = 0.0;
    for (int v = 0; v < fine.num_vertices(); ++v) {
      if (is_held[static_cast<size_t>(v)]) continue;
      free_residual =
          std::max(free_residual, (gradient.segment<3>(3 * v) - fine.mass(v) * gravity).norm());
    }
    const Eigen::Vector3d force = table_force + hand_force;
    const double imbalance = (force + mass * gravity).norm();
    // Gravity's torque about the centre of mass is zero: the contacts' torque must balance alone.
    const double torque_imbalance = torque.norm();
    r.max_force_imbalance_N = std::max(r.max_force_imbalance_N, imbalance);
    r.max_torque_imbalance_Nm = std::max(r.max_torque_imbalance_Nm, torque_imbalance);
    // Balance to a millionth of the weight and of its moment over the radius: the solve's
    // tolerance leaves orders of magnitude less.
    if (imbalance > 1e-6 * mass * kGravity || torque_imbalance > 1e-6 * mass * kGravity * kRadius) {
      return Status::Error("hand_press frame " + std::to_string(f) +
                           ": the forces do not balance (|F + M g| = " + Format("%.3e", imbalance) +
                           " N, |torque| = " + Format("%.3e", torque_imbalance) + " N m)");
    }
    {
      char line[512];
      // The table is the tracking scene's obstacle: its push is the contact force femreg reports.
      std::snprintf(line, sizeof(line), "%d,%.6e,%.6e,%.6e,%.6e,%.6e,%.6e,%.6e,%.6e,%.6e,%.6e,%.6e,%.6e,%.6e\n", f,
                    force.x(), force.y(), force.z(), torque.x(), torque.y(), torque.z(),
                    table_force.z(), hand_force.x(), hand_force.y(), hand_force.z(), table_force.x(),
                    table_force.y(), table_force.z());
      forces << line;
      std::snprintf(line, sizeof(line), "%d,%d,%d,%d,%.3e,%d,%d,%d,%d,%.3e,%.3e,%.4f,%d\n", f,
                    substeps, rounds, newton, free_residual, counts[kTable], counts[kPalmPart],
                    counts[kThumb], counts[kFingers], imbalance, torque_imbalance,
                    fine.x.col(2).minCoeff() * 1e3, summary.inverted_elements);
      log << line;
    }

    // The camera's view: the ball and the hand's parts return points, the table hides.
    std::vector<Vertices> parts;
    for (int s = kPalmPart; s < kNumSurfaces; ++s) parts.push_back(part_points(poses, s));
    std::vector<RenderSurface> surfaces = {{&fine.x, &fine.surface, true},
                                           {&table_points, &table_triangles, false}};
    for (int s = kPalmPart; s < kNumSurfaces; ++s) {
      surfaces.push_back({&parts[static_cast<size_t>(s - kPalmPart)],
                          s == kPalmPart ? &palm_triangles : &pad_triangles, true});
    }
    const DepthImage image = sensor.Render(surfaces);
    const uint64_t stream = 0x68616e64ull + options.seed * 0x9e3779b97f4a7c15ull;
    const PointCloud cloud =
        sensor.Sample(image, surfaces, stream * 1000003ull + static_cast<uint64_t>(f));
    GroundTruthFrame truth;
    truth.positions = InterpolateEmbedded(fine, fine.x, embedded);
    truth.visible = sensor.Visible(image, truth.positions, 2e-3);

    const std::string name = FrameName(f);
    Status status = WritePointCloud((fs::path(dir) / "clouds" / (name + ".pcd")).string(), cloud);
    if (status.ok()) {  // surfaces[0] is the ball: the hand hides it but returns nothing
      status = WritePointCloud((fs::path(dir) / "clouds_without_hand" / (name + ".pcd")).string(),
                               OnlySurface(cloud, image, sensor, 0));
    }
    if (status.ok()) {
      status =
          WriteGroundTruthFrame((fs::path(dir) / "ground_truth" / (name + ".csv")).string(), truth);
    }
    if (status.ok()) status = truth_surface.Write((fs::path(dir) / "truth" / (name + ".vtu")).string(), fine);
    if (!status.ok()) return status;
    r.min_points = std::min(r.min_points, cloud.size());
    r.max_points = std::max(r.max_points, cloud.size());
    int seen = 0;
    for (char c : truth.visible) seen += c ? 1 : 0;
    seen_sum += static_cast<double>(seen) / coarse.num_vertices();
    r.max_hand_force_N = std::max(r.max_hand_force_N, hand_force.norm());
    r.max_lift_m = std::max(r.max_lift_m, fine.x.col(2).minCoeff());
    r.min_top_m =
        f == 0 ? fine.x.col(2).maxCoeff() : std::min(r.min_top_m, fine.x.col(2).maxCoeff());
    if (f == 0) r.rest_top_m = fine.x.col(2).maxCoeff();
    if (progress) progress(f + 1, num_frames);
  }
  r.mean_seen_fraction = seen_sum / num_frames;
  Status status = WriteFileAtomically((fs::path(dir) / "forces.csv").string(), forces.str());
  if (status.ok())
    status = WriteFileAtomically((fs::path(dir) / "truth_solve.csv").string(), log.str());
  if (status.ok())
    status = WriteFileAtomically((fs::path(dir) / "scene.yaml").string(), TrackingScene(options));
  if (status.ok())
    status = WriteFileAtomically((fs::path(dir) / "README.md").string(), Readme(r, fine, options));
  if (!status.ok()) return status;
  if (report) *report = r;
  return Status::Ok();
}

}  // namespace femreg
