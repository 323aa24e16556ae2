// The bundled organ_patch sequence: a soft organ-like body clamped at one end and pushed
// by a tool, seen only as ~500-point patches on ~15% of its surface, with no camera (the
// case that pulled a whole surface onto the patch before the reciprocity trim and the
// estimated viewing direction; docs/hard_cases.md).
//
// The body is a ball mapped to a flattened, bent ellipsoid (x, y, z) -> (a x, b y, c z +
// d x^2), a map with a constant positive Jacobian, so every element stays positively
// oriented. The ground truth is solved on the same shape 2.5 times as finely divided, with a
// stiffer Poisson ratio than the tracker's, and interpolated at the tracked vertices; the
// tool's true force is the reaction at the vertices it moves in that solve (or, with the
// contact tool, the resultant of its contacts on the body). At that nu
// linear tetrahedra lock, so the truth uses the nodal volume: a benchmark's true force must
// not be set by locked elements' stiffness (docs/notes/2026-11-29-organ-truth.md).
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <memory>
#include <random>
#include <sstream>

#include "femreg/collision.h"
#include "femreg/datasets.h"
#include "femreg/forward.h"
#include "femreg/ground_truth.h"
#include "femreg/io.h"
#include "femreg/point_cloud.h"
#include "femreg/synth.h"

namespace fs = std::filesystem;

namespace femreg {
namespace {

constexpr double kA = 0.08, kB = 0.055, kC = 0.035, kD = 0.012;  // m
constexpr double kClampX = -0.056;       // vertices with x <= this are clamped (the far lobe)
constexpr int kFrames = 12;
constexpr int kTruthDivisions = 10;      // the ground truth's mesh (9261 vertices)
constexpr int kMaxTruthDivisions = 16;   // 35937 vertices: enough to check convergence
constexpr double kBalanceTolerance = 1e-4;  // |tool + clamp force| over |tool force|
constexpr int kPoints = 500;             // per cloud
constexpr double kNoise = 3e-4;          // m, per coordinate
constexpr double kPatchFraction = 0.15;  // of the rest surface area
const Eigen::Vector3d kToolCentre(0.025, 0.0, 0.0);  // x, y of the tool's tip (z: the top)
constexpr double kToolRadius = 0.012;    // m
// The contact tool: its edge's rounding, its height, how far above the top it starts (a flat
// end touches the sloped top first at its edge), the poses it is moved through per frame (a
// fraction of the detection distance each, so no vertex starts a solve deep inside it) and
// the penalty (per contact, tool_table's; its penetration, force / k, is small against the push).
constexpr double kToolFillet = 0.003, kToolHeight = 0.05, kToolLift = 0.001;  // m
constexpr int kToolSubsteps = 4;
constexpr double kContactStiffness = 2000.0, kContactDistance = 0.0015;  // N/m, m

TetMesh OrganMesh(int n) {
  TetMesh mesh = MakeSphere(1.0, n);
  for (int v = 0; v < mesh.num_vertices(); ++v) {
    const Eigen::Vector3d p = mesh.rest.row(v);
    mesh.rest.row(v) = Eigen::RowVector3d(kA * p.x(), kB * p.y(), kC * p.z() + kD * p.x() * p.x());
  }
  mesh.x = mesh.rest;
  return mesh;
}

// On the upper side: above the mid-surface z = d (x/a)^2.
bool Upper(const Eigen::Vector3d& X) { return X.z() > kD * (X.x() / kA) * (X.x() / kA); }

// The tool's displacement at frame f: down 14 mm in 8 steps (frames 0..7), then 6 mm along +y.
Eigen::Vector3d ToolPath(int f) {
  const double down = 0.014 * std::min(1.0, (f + 1) / 8.0);
  const double side = 0.006 * std::max(0.0, (f - 7) / 4.0);
  return Eigen::Vector3d(0.0, side, -down);
}

// The upper surface's height above (x, y) on the smooth body (not on a mesh's facets).
double TopHeight(double x, double y) {
  const double u = x / kA, v = y / kB;
  return kC * std::sqrt(std::max(0.0, 1.0 - u * u - v * v)) + kD * u * u;
}

// The contact tool's surface in its own frame, outward normals: a cylinder of radius
// kToolRadius standing on the origin, its flat end's edge rounded by kToolFillet. A surface
// of revolution of the profile (r, z) from the end's centre to the top's, in rings of
// `segments` vertices.
void ContactToolSurface(Vertices* vertices, Triangles* triangles) {
  constexpr int segments = 48, fillet_steps = 6;
  std::vector<Eigen::Vector2d> ring;  // (r, z) of each ring between the two axis points
  const double flat = kToolRadius - kToolFillet;
  for (double r = 0.0015; r < flat - 1e-9; r += 0.0015) ring.emplace_back(r, 0.0);
  for (int k = 0; k <= fillet_steps; ++k) {
    const double t = 0.5 * M_PI * k / fillet_steps;
    ring.emplace_back(flat + kToolFillet * std::sin(t), kToolFillet * (1.0 - std::cos(t)));
  }
  for (double z = 0.005; z <= kToolHeight + 1e-9; z += 0.005) ring.emplace_back(kToolRadius, z);
  const int rings = static_cast<int>(ring.size());
  vertices->resize(2 + rings * segments, 3);
  vertices->row(0) << 0.0, 0.0, 0.0;
  vertices->row(1) << 0.0, 0.0, kToolHeight;
  auto at = [&](int i, int s) { return 2 + i * segments + s % segments; };
  for (int i = 0; i < rings; ++i) {
    for (int s = 0; s < segments; ++s) {
      const double phi = 2.0 * M_PI * s / segments;
      vertices->row(at(i, s)) << ring[i].x() * std::cos(phi), ring[i].x() * std::sin(phi), ring[i].y();
    }
  }
  triangles->resize(2 * segments * rings, 3);
  int t = 0;
  for (int s = 0; s < segments; ++s) {
    triangles->row(t++) << 0, at(0, s + 1), at(0, s);
    triangles->row(t++) << 1, at(rings - 1, s), at(rings - 1, s + 1);
    // Each quad's diagonal mirrored across y = 0 (s and segments - 1 - s): the tool is as
    // mirror-symmetric as the body.
    const bool left = 2 * s < segments;
    for (int i = 0; i + 1 < rings; ++i) {
      if (left) {
        triangles->row(t++) << at(i, s), at(i + 1, s + 1), at(i + 1, s);
        triangles->row(t++) << at(i, s), at(i, s + 1), at(i + 1, s + 1);
      } else {
        triangles->row(t++) << at(i, s), at(i, s + 1), at(i + 1, s);
        triangles->row(t++) << at(i, s + 1), at(i + 1, s + 1), at(i + 1, s);
      }
    }
  }
}

// The contact tool as an obstacle: its end's centre on the top above the tool's centre,
// kToolLift above it at collision frame 0, then along ToolPath: frame f's pose is collision
// frame f + 1.
ObstacleSpec ContactToolObstacle() {
  ObstacleSpec tool;
  tool.name = "tool";
  tool.kind = ObstacleSpec::Kind::kMesh;
  tool.surface.emplace();
  ContactToolSurface(&tool.surface->vertices, &tool.surface->triangles);
  // Its corners as floats, as the STL it was first read from held them: the push, symmetric
  // in y through frame 7, takes one of two mirror-image solutions by the tool's rounding, and
  // the data keep theirs (docs/notes/2026-11-30-organ-contact-tool.md).
  tool.surface->vertices = tool.surface->vertices.cast<float>().cast<double>();
  tool.friction = 0.0;
  const Eigen::Vector3d start(kToolCentre.x(), kToolCentre.y(), TopHeight(kToolCentre.x(), kToolCentre.y()));
  tool.keyframes.push_back({0, start + Eigen::Vector3d(0.0, 0.0, kToolLift), Eigen::Vector3d::Zero()});
  for (int f = 0; f < kFrames; ++f) tool.keyframes.push_back({f + 1, start + ToolPath(f), Eigen::Vector3d::Zero()});
  return tool;
}

// A point of the patch (rest positions): the upper side, within `radius` of the patch
// centre in x and y, outside the tool's footprint (the tool hides it).
bool InPatch(const Eigen::Vector3d& X, double radius) {
  const Eigen::Vector2d c(-0.005, 0.0);
  const Eigen::Vector2d tool(kToolCentre.x(), kToolCentre.y());
  return Upper(X) && (X.head<2>() - c).norm() <= radius &&
         (X.head<2>() - tool).norm() > kToolRadius + 0.003;
}

double TriangleArea(const Vertices& x, const Triangles& t, int f) {
  const Eigen::Vector3d a = x.row(t(f, 0)), b = x.row(t(f, 1)), c = x.row(t(f, 2));
  return 0.5 * (b - a).cross(c - a).norm();
}

// The patch's triangles (all three vertices in it) and their rest area.
std::vector<int> PatchTriangles(const TetMesh& mesh, double radius, double* area) {
  std::vector<int> tris;
  *area = 0.0;
  for (int f = 0; f < mesh.num_surface_triangles(); ++f) {
    bool in = true;
    for (int k = 0; k < 3; ++k) in = in && InPatch(mesh.rest.row(mesh.surface(f, k)), radius);
    if (in) {
      tris.push_back(f);
      *area += TriangleArea(mesh.rest, mesh.surface, f);
    }
  }
  return tris;
}

// Normal deviates from a 64-bit Mersenne twister by Box-Muller (the same on every
// standard library, unlike std::normal_distribution).
struct Gaussian {
  explicit Gaussian(uint64_t seed) : rng(seed) {}
  double Uniform() { return (static_cast<double>(rng() >> 11) + 0.5) * (1.0 / 9007199254740992.0); }
  double Normal() {
    const double u1 = Uniform(), u2 = Uniform();
    return std::sqrt(-2.0 * std::log(u1)) * std::cos(2.0 * M_PI * u2);
  }
  std::mt19937_64 rng;
};

// The ground truth's body, element, clamp and tool, built once for all frames.
struct Truth {
  TetMesh mesh;
  ElasticModel model;
  ForwardProblem problem;  // the clamp (and the contact tool's potential)
  std::vector<int> tool;   // the glued tool: the upper surface vertices under its tip
  // The contact tool: its world, its penalty (problem.potential) and the last frame solved
  // (mesh.x holds it).
  std::unique_ptr<CollisionWorld> world;
  std::unique_ptr<ContactPotential> contact;
  int solved_through = -1;
};

ForwardOptions TruthForwardOptions() {
  ForwardOptions forward;
  forward.num_threads = 1;  // one summation order: the same bytes on every machine load
  forward.max_iterations = 60;
  forward.load_steps = 2;
  return forward;
}

// The contact tool's world and penalty.
Status BuildContactTool(Truth* truth) {
  CollisionSpec spec;
  spec.stiffness = kContactStiffness;
  spec.distance = kContactDistance;
  spec.obstacles.push_back(ContactToolObstacle());
  truth->world = std::make_unique<CollisionWorld>();
  const Status status = truth->world->Init(spec, {"organ"}, {truth->mesh.surface}, truth->mesh.x);
  if (!status.ok()) return status;
  truth->contact = std::make_unique<ContactPotential>(truth->world.get(), 0.5 * kContactDistance);
  truth->problem.potential = truth->contact.get();
  return Status::Ok();
}

Status BuildTruth(int divisions, const ObjectMaterial& material, OrganTool tool, Truth* truth) {
  std::string error;
  if (!material.IsValid(&error)) return Status::Error("organ_patch truth material: " + error);
  truth->mesh = OrganMesh(divisions);
  ComputeLumpedMasses(&truth->mesh, material.material.density);
  truth->model.Build(truth->mesh, ElasticModelType::kCorotational, material);
  truth->problem = ForwardProblem();
  truth->tool.clear();
  truth->solved_through = -1;
  for (int v = 0; v < truth->mesh.num_vertices(); ++v) {
    const Eigen::Vector3d X = truth->mesh.rest.row(v);
    if (X.x() <= kClampX) truth->problem.clamped.push_back(v);
  }
  if (tool == OrganTool::kContact) {
    if (truth->problem.clamped.empty()) return Status::Error("organ_patch: empty clamp");
    return BuildContactTool(truth);
  }
  for (int v : truth->mesh.surface_vertices) {
    const Eigen::Vector3d X = truth->mesh.rest.row(v);
    if (Upper(X) && (X.head<2>() - kToolCentre.head<2>()).norm() <= kToolRadius) truth->tool.push_back(v);
  }
  if (truth->tool.empty() || truth->problem.clamped.empty()) {
    return Status::Error("organ_patch: empty tool or clamp");
  }
  return Status::Ok();
}

Status RequireConverged(int f, const ForwardSummary& summary) {
  if (summary.termination == ForwardTermination::kConverged) return Status::Ok();
  return Status::Error("organ_patch frame " + std::to_string(f) + ": the ground truth's solve did not converge: " +
                       summary.message);
}

// The glued tool's frame f: from rest, its vertices moved along the path.
Status SolveGluedFrame(int f, Truth* truth, ForwardProblem* step, ForwardSummary* summary) {
  *step = truth->problem;
  for (int v : truth->tool) step->prescribed.emplace_back(v, ToolPath(f));
  truth->mesh.x = truth->mesh.rest;
  Status status = SolveQuasiStatic(*step, TruthForwardOptions(), &truth->model, &truth->mesh, summary);
  return status.ok() ? RequireConverged(f, *summary) : status;
}

// The contact tool's frame f: the frames up to it in order, each from the last through
// kToolSubsteps poses (from rest the body would start inside the tool).
Status SolveContactFrame(int f, Truth* truth, ForwardProblem* step, ForwardSummary* summary) {
  *step = truth->problem;
  if (truth->solved_through >= f) {
    truth->mesh.x = truth->mesh.rest;
    truth->solved_through = -1;
  }
  ForwardOptions forward = TruthForwardOptions();
  forward.load_steps = 1;  // nothing is prescribed: the poses are the steps
  for (int g = truth->solved_through + 1; g <= f; ++g) {
    for (int s = 1; s <= kToolSubsteps; ++s) {
      truth->world->SetFrame(g + static_cast<double>(s) / kToolSubsteps);
      Status status = SolveQuasiStatic(*step, forward, &truth->model, &truth->mesh, summary);
      if (status.ok()) status = RequireConverged(g, *summary);
      if (!status.ok()) return status;
    }
    truth->solved_through = g;
  }
  return Status::Ok();
}

// Frame f's equilibrium (in truth->mesh.x), and the tool's and the clamp's forces.
Status SolveTruthFrame(int f, Truth* truth, OrganTruthFrame* out) {
  ForwardProblem step;
  Status status = truth->contact ? SolveContactFrame(f, truth, &step, &out->summary)
                                 : SolveGluedFrame(f, truth, &step, &out->summary);
  if (!status.ok()) return status;
  TetMesh& mesh = truth->mesh;
  ForwardForces forces;
  status = EvaluateForwardForces(step, TruthForwardOptions(), truth->model, mesh, mesh.x, &forces);
  if (!status.ok()) return status;
  Vertices by_tool = truth->contact ? forces.potential : Vertices::Zero(mesh.num_vertices(), 3);
  Vertices by_clamp = Vertices::Zero(mesh.num_vertices(), 3);
  for (int v : truth->tool) by_tool.row(v) = forces.reactions.row(v);
  for (int v : truth->problem.clamped) by_clamp.row(v) = forces.reactions.row(v);
  if (truth->contact) {
    std::vector<Contact> contacts;
    truth->world->Detect(mesh.x, 0.0, &contacts);
    const ContactStats stats = truth->world->Evaluate(contacts, mesh.x);
    out->contacts = stats.contacts;
    out->max_penetration = stats.max_penetration;
  }
  out->positions = mesh.x;
  out->tool = ResultantAboutCentroid(by_tool, mesh.x, mesh.mass);
  out->clamp = ResultantAboutCentroid(by_clamp, mesh.x, mesh.mass);
  return Status::Ok();
}

// The README's line on the command that made the sequence.
std::string MadeBy(int divisions, int truth_divisions, OrganTool tool) {
  if (divisions == 4 && truth_divisions == kTruthDivisions && tool == OrganTool::kContact) {
    return "Made by `femreg organ-data --out datasets/organ_patch` (tools/make_datasets.sh); ";
  }
  return "Made by `femreg organ-data --divisions " + std::to_string(divisions) +
         (truth_divisions == kTruthDivisions ? std::string() : " --truth-divisions " + std::to_string(truth_divisions)) +
         (tool == OrganTool::kGlued ? " --tool glued" : "") + "`; ";
}

}  // namespace

const char* ToString(OrganTool tool) { return tool == OrganTool::kContact ? "contact" : "glued"; }

bool FromString(const std::string& name, OrganTool* tool) {
  for (OrganTool t : {OrganTool::kGlued, OrganTool::kContact}) {
    if (name == ToString(t)) {
      *tool = t;
      return true;
    }
  }
  return false;
}

TetMesh OrganPatchMesh(int divisions) { return OrganMesh(divisions); }

ObjectMaterial OrganPatchTruthMaterial() {
  Material m;
  m.youngs_modulus = 5e3;
  m.poisson_ratio = 0.47;
  m.density = 1000.0;
  ObjectMaterial material(m);
  material.model = MaterialModel::kNeoHookean;
  material.nodal_volume = true;
  return material;
}

Status SolveOrganPatchTruth(int frame, int divisions, const ObjectMaterial& material, OrganTruthFrame* out,
                            OrganTool tool) {
  if (frame < 0 || frame >= kFrames) {
    return Status::Error("organ_patch: frame must be 0 to " + std::to_string(kFrames - 1));
  }
  if (divisions < 2 || divisions > kMaxTruthDivisions) {
    return Status::Error("organ_patch: truth divisions must be 2 to " + std::to_string(kMaxTruthDivisions));
  }
  Truth truth;
  Status status = BuildTruth(divisions, material, tool, &truth);
  if (!status.ok()) return status;
  return SolveTruthFrame(frame, &truth, out);
}

Status GenerateOrganPatchSequence(const std::string& dir, void (*progress)(int done, int total),
                                  int divisions, int truth_divisions, OrganTool tool) {
  if (truth_divisions < 3 || truth_divisions > kMaxTruthDivisions) {
    return Status::Error("organ_patch: truth divisions must be 3 to " + std::to_string(kMaxTruthDivisions) +
                         ", got " + std::to_string(truth_divisions));
  }
  if (divisions < 2 || divisions > truth_divisions - 1) {
    return Status::Error("organ_patch: divisions must be 2 to " + std::to_string(truth_divisions - 1) +
                         " (the ground truth's mesh has " + std::to_string(truth_divisions) +
                         "), got " + std::to_string(divisions));
  }
  std::error_code ec;
  fs::create_directories(fs::path(dir) / "clouds", ec);
  fs::create_directories(fs::path(dir) / "ground_truth", ec);
  if (ec) return Status::Error(dir + ": cannot create: " + ec.message());

  const TetMesh coarse = OrganMesh(divisions);
  Truth truth;
  Status built = BuildTruth(truth_divisions, OrganPatchTruthMaterial(), tool, &truth);
  if (!built.ok()) return built;
  TetMesh& fine = truth.mesh;
  const EmbeddedPoints embedded = EmbedPoints(fine, coarse.rest);

  // The patch radius that covers kPatchFraction of the surface (bisection on the rest area).
  double total_area = 0.0;
  for (int f = 0; f < fine.num_surface_triangles(); ++f) total_area += TriangleArea(fine.rest, fine.surface, f);
  double lo = 0.0, hi = 0.2, area = 0.0;
  for (int it = 0; it < 40; ++it) {
    const double mid = 0.5 * (lo + hi);
    PatchTriangles(fine, mid, &area);
    (area < kPatchFraction * total_area ? lo : hi) = mid;
  }
  const double radius = hi;
  const std::vector<int> patch = PatchTriangles(fine, radius, &area);

  double mean_motion = 0.0;
  std::vector<ForceFrame> tool_forces;
  for (int f = 0; f < kFrames; ++f) {
    OrganTruthFrame solved;
    Status status = SolveTruthFrame(f, &truth, &solved);
    if (!status.ok()) return status;
    // The tool's force on the body (the clamp's, the only other external force, left out).
    tool_forces.push_back({f, solved.tool.force, solved.tool.torque});
    // With no gravity the clamp's reaction balances the tool's force: a truth whose forces
    // do not is not an equilibrium to benchmark against.
    const double imbalance = (solved.tool.force + solved.clamp.force).norm();
    if (!(imbalance <= kBalanceTolerance * solved.tool.force.norm())) {
      char why[160];
      std::snprintf(why, sizeof(why), "organ_patch frame %d: the tool's and the clamp's forces do not balance (%.3g N)",
                    f, imbalance);
      return Status::Error(why);
    }
    // 500 points spread over the patch by area, with noise.
    std::vector<double> cumulative;
    double sum = 0.0;
    for (int t : patch) cumulative.push_back(sum += TriangleArea(fine.x, fine.surface, t));
    Gaussian rng(0x6f7267616eull * 1000003ull + static_cast<uint64_t>(f));
    PointCloud cloud;
    cloud.points.resize(kPoints, 3);
    for (int i = 0; i < kPoints; ++i) {
      const double r = rng.Uniform() * sum;
      const size_t j = std::min(cumulative.size() - 1,
                                static_cast<size_t>(std::lower_bound(cumulative.begin(), cumulative.end(), r) -
                                                    cumulative.begin()));
      double u = rng.Uniform(), w = rng.Uniform();
      if (u + w > 1.0) {
        u = 1.0 - u;
        w = 1.0 - w;
      }
      const int t = patch[j];
      const Eigen::Vector3d a = fine.x.row(fine.surface(t, 0)), b = fine.x.row(fine.surface(t, 1)),
                            c = fine.x.row(fine.surface(t, 2));
      const Eigen::Vector3d noise(rng.Normal(), rng.Normal(), rng.Normal());
      cloud.points.row(i) = (a + u * (b - a) + w * (c - a) + kNoise * noise).transpose();
    }
    GroundTruthFrame at_tracked;
    at_tracked.positions = InterpolateEmbedded(fine, fine.x, embedded);
    at_tracked.visible.assign(static_cast<size_t>(coarse.num_vertices()), 0);
    for (int v : coarse.surface_vertices) {
      at_tracked.visible[static_cast<size_t>(v)] = InPatch(coarse.rest.row(v), radius);
    }
    mean_motion = (at_tracked.positions - coarse.rest).rowwise().norm().mean();
    char name[64];
    std::snprintf(name, sizeof(name), "frame_%04d", f);
    status = WritePointCloud((fs::path(dir) / "clouds" / (std::string(name) + ".pcd")).string(), cloud);
    if (status.ok()) {
      status = WriteGroundTruthFrame((fs::path(dir) / "ground_truth" / (std::string(name) + ".csv")).string(), at_tracked);
    }
    if (!status.ok()) return status;
    if (progress) progress(f + 1, kFrames);
  }
  Status status = WriteVtu((fs::path(dir) / "organ.vtu").string(), coarse, coarse.rest);
  if (status.ok()) status = WriteForces((fs::path(dir) / "forces.csv").string(), tool_forces);
  if (!status.ok()) return status;

  std::ostringstream scene;
  scene << "# Tracking scene of the organ_patch sequence (femreg organ-data): no camera, default\n"
           "# visibility and data settings. Run\n"
           "#   femreg register --scene scene.yaml --frames clouds --ground-truth ground_truth --out OUT\n"
           "objects:\n"
           "  - name: organ\n"
           "    mesh: organ.vtu\n"
           "    material: {youngs_modulus: 5000, poisson_ratio: 0.45, density: 1000}\n"
           "registration:\n"
           "  solver: {backend: fast}\n"
           "anchors:\n"
           "  - {name: clamp, select: {box: {min: [-1, -1, -1], max: ["
        << kClampX << ", 1, 1]}}, hard: true}\n";
  status = WriteFileAtomically((fs::path(dir) / "scene.yaml").string(), scene.str());
  if (!status.ok()) return status;

  const bool contact = tool == OrganTool::kContact;
  char line[512];
  std::ostringstream readme;
  readme << "# organ_patch\n\n"
            "A soft organ-like body (a ball mapped to a flattened, bent ellipsoid, 16 x 11 x 7 cm; "
            "tracked mesh "
         << coarse.num_vertices() << " vertices / " << coarse.num_tets()
         << " tetrahedra in `organ.vtu`), clamped at its far lobe (x <= " << kClampX * 1e3
         << " mm), pushed 14 mm down by a tool of radius " << kToolRadius * 1e3 << " mm"
         << (contact ? " (a rigid, frictionless flat-ended cylinder with a rounded edge, pressing by contact)" : "")
         << " and then dragged 6 mm sideways; " << kFrames
         << " frames. Each cloud has " << kPoints << " points (noise " << kNoise * 1e3
         << " mm per coordinate) on one patch of the upper side that covers ";
  std::snprintf(line, sizeof(line), "%.0f%%", 100.0 * area / total_area);
  readme << line
         << " of the surface (the tool's footprint hidden). The clouds carry no viewpoint and "
            "the scene no camera: the partial-view case of docs/hard_cases.md.\n\n"
            "Ground truth: the neo-Hookean element with the nodal volume (locking-free) on the "
            "same shape more finely divided ("
         << fine.num_vertices() << " vertices), Poisson ratio 0.47 against the tracker's 0.45, "
            "interpolated at the tracked vertices; `visible` marks the tracked vertices in the "
            "patch. ";
  std::snprintf(line, sizeof(line), "Mean vertex motion at the last frame: %.2f mm (the error of doing nothing).\n\n",
                mean_motion * 1e3);
  readme << line;
  double peak = 0.0;
  for (const ForceFrame& t : tool_forces) peak = std::max(peak, t.force.norm());
  std::snprintf(line, sizeof(line), "%.2f N", peak);
  readme << "`forces.csv`: per frame, the tool's true force on the body (`force_x_N, force_y_N, "
            "force_z_N`: "
         << (contact ? "the resultant of its contact forces on the body" : "the reaction at the ground truth's vertices the tool moves")
         << ", pointing into the body; up to "
         << line
         << ") and its torque about the body's centroid (`torque_x_Nm, torque_y_Nm, torque_z_Nm`; "
            "the centroid is the lumped-mass-weighted mean of the true vertex positions). "
         << (contact ? "The tool is frictionless: its force is normal to the surface it touches, the top "
                       "and, once the tool has sunk in, the sides around it."
                     : "The tool moves the vertices it touches without slip, so its force also has a part "
                       "along the surface.")
         << " There is no gravity; the clamp's reaction, the only other force on the body, "
            "balances it and is left out, as an estimate in `femreg register`'s stats.csv leaves "
            "it out: `femreg eval` compares the two.\n\n"
         << MadeBy(divisions, truth_divisions, tool) << "deterministic.\n\n"
            "    femreg register --scene datasets/organ_patch/scene.yaml --frames datasets/organ_patch/clouds \\\n"
            "        --ground-truth datasets/organ_patch/ground_truth --out /tmp/organ_patch\n";
  return WriteFileAtomically((fs::path(dir) / "README.md").string(), readme.str());
}

}  // namespace femreg
