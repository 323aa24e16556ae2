// The press case of tools/press_case.h: femreg's forward solve and the CalculiX deck.
#include "tools/press_case.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <exception>
#include <utility>

#include "femreg/collision.h"
#include "femreg/fem.h"
#include "femreg/forward.h"
#include "femreg/io.h"

namespace femreg {
namespace {

using V3 = Eigen::Vector3d;

// The support (6 x 6 x 2 cm, 5 mm cells) and the pressed block (3 x 3 x 2 cm, 4.3 mm cells,
// centred on it): their contact faces' nodes do not coincide.
constexpr double kBaseHeight = 0.02, kTopHeight = 0.02;
TetMesh BaseBlock() { return MakeBox(V3(0.06, 0.06, kBaseHeight), 12, 12, 4); }
TetMesh TopBlock(double gap) {
  return MakeBox(V3(0.03, 0.03, kTopHeight), 7, 7, 5, V3(0.015, 0.015, kBaseHeight + gap));
}

// Nodes of the given deck indices, ten per line.
void WriteSet(const std::string& name, const std::vector<int>& nodes, std::ostream& out) {
  out << "*NSET, NSET=" << name << "\n";
  for (size_t i = 0; i < nodes.size(); ++i) {
    out << nodes[i] + 1 << (i % 10 == 9 || i + 1 == nodes.size() ? "\n" : ", ");
  }
}

// An element-face surface: every face of the elements in [first, last) whose three nodes
// are all in `nodes` (CalculiX's C3D4 faces: 1-2-3, 1-4-2, 2-4-3, 3-4-1).
void WriteSurface(const std::string& name, const TetMesh& mesh, int first, int last,
                  const std::vector<int>& nodes, std::ostream& out) {
  static const int kFaces[4][3] = {{0, 1, 2}, {0, 3, 1}, {1, 3, 2}, {2, 3, 0}};
  std::vector<char> in(mesh.num_vertices(), 0);
  for (int v : nodes) in[v] = 1;
  out << "*SURFACE, NAME=" << name << ", TYPE=ELEMENT\n";
  for (int t = first; t < last; ++t) {
    for (int f = 0; f < 4; ++f) {
      bool all = true;
      for (int k = 0; k < 3; ++k) all = all && in[mesh.tets(t, kFaces[f][k])];
      if (all) out << t + 1 << ", S" << f + 1 << "\n";
    }
  }
}

}  // namespace

Status ParsePressOptions(const std::map<std::string, std::string>& args, PressOptions* options) {
  PressOptions& o = *options;
  const std::map<std::string, double*> numbers = {
      {"E", &o.top_modulus},          {"E_base", &o.base_modulus},   {"nu", &o.poisson_ratio},
      {"gap", &o.gap},                {"press", &o.press},           {"slide", &o.slide},
      {"stiffness", &o.stiffness},    {"distance", &o.distance},     {"mu", &o.friction},
      {"slip", &o.friction_slip},     {"ccx_stiffness", &o.ccx_stiffness},
      {"ccx_stick", &o.ccx_stick_slope}};
  for (const auto& [key, value] : args) {
    try {
      if (key == "model") {
        if (value != "neo_hookean" && value != "corotational") {
          return Status::Error("model must be neo_hookean or corotational");
        }
        o.neo_hookean = value == "neo_hookean";
      } else if (key == "support") {
        if (value != "block" && value != "plane") return Status::Error("support must be block or plane");
        o.plane = value == "plane";
      } else if (key == "slide_frames" || key == "load_steps" || key == "max_iterations") {
        (key == "slide_frames" ? o.slide_frames : key == "load_steps" ? o.load_steps : o.max_iterations) =
            std::stoi(value);
      } else if (numbers.count(key)) {
        *numbers.at(key) = std::stod(value);
      }
    } catch (const std::exception&) {
      return Status::Error(key + "=" + value + ": not a number");
    }
  }
  if (o.slide_frames < 1 || o.load_steps < 1) return Status::Error("slide_frames and load_steps must be >= 1");
  return Status::Ok();
}

Status SolvePressCase(const PressOptions& options, PressResult* result) {
  PressResult& r = *result;
  const TetMesh base = BaseBlock(), top = TopBlock(options.gap);
  std::vector<int> offsets;
  r.deck = MergeMeshes({base, top}, &offsets);
  r.top_offset = offsets[1];
  r.top_first_tet = base.num_tets();
  const double tol = 1e-9, top_bottom = kBaseHeight + options.gap, top_top = top_bottom + kTopHeight;
  std::vector<char> on_top_surface(top.num_vertices(), 0);
  for (int i = 0; i < top.surface.size(); ++i) on_top_surface[top.surface.data()[i]] = 1;
  r.free_surface.assign(top.num_vertices(), 0);
  for (int v = 0; v < r.deck.num_vertices(); ++v) {
    const double z = r.deck.rest(v, 2);
    if (v < r.top_offset) {
      if (options.plane || z < tol) r.clamped.push_back(v);
      if (z > kBaseHeight - tol) r.base_surface.push_back(v);
    } else {
      if (z > top_top - tol) r.top_face.push_back(v);
      if (z < top_bottom + tol) r.top_surface.push_back(v);
      const int i = v - r.top_offset;
      r.free_surface[i] = on_top_surface[i] && z > top_bottom + tol && z < top_top - tol;
    }
  }

  // femreg's problem: both blocks (a pair), or the pressed one alone over a plane obstacle.
  TetMesh mesh = options.plane ? top : r.deck;
  const int shift = options.plane ? r.top_offset : 0;  // deck index - femreg index
  Material base_material, top_material;
  base_material.youngs_modulus = options.base_modulus;
  top_material.youngs_modulus = options.top_modulus;
  base_material.poisson_ratio = top_material.poisson_ratio = options.poisson_ratio;
  ObjectMaterial material(top_material);
  if (!options.plane) material.regions = {{0, base_material}, {1, top_material}};
  if (options.neo_hookean) material.model = MaterialModel::kNeoHookean;
  ElasticModel model;
  model.Build(mesh, ElasticModelType::kCorotational, material);
  CollisionSpec spec;
  spec.stiffness = options.stiffness;
  spec.distance = options.distance;
  spec.friction = options.friction;
  spec.friction_slip = options.friction_slip;
  std::vector<std::string> names;
  std::vector<Triangles> surfaces;
  if (options.plane) {
    ObstacleSpec plane;
    plane.name = "plane";
    plane.plane_point = V3(0, 0, kBaseHeight);
    spec.obstacles.push_back(plane);
    names = {"top"};
    surfaces = {mesh.surface};
  } else {
    spec.pairs = {{"base", "top"}};
    names = {"base", "top"};
    surfaces = {base.surface, (top.surface.array() + r.top_offset).matrix()};
  }
  CollisionWorld world;
  Status status = world.Init(spec, names, surfaces, mesh.x);
  if (!status.ok()) return status;
  ContactPotential potential(&world, options.distance);
  ForwardProblem problem;
  problem.potential = &potential;
  if (!options.plane) problem.clamped = r.clamped;
  ForwardOptions forward;
  forward.num_threads = options.num_threads;
  forward.max_iterations = options.max_iterations;
  const int frames = 1 + (options.slide != 0.0 ? options.slide_frames : 0);
  r.converged = true;
  for (int f = 0; f < frames; ++f) {
    world.SetFrame(f);
    // The press from rest in load steps; each slide frame in one step from the last (the
    // prescribed moves are scaled from rest: more steps would lift the face first).
    forward.load_steps = f == 0 ? options.load_steps : 1;
    const double dx = f == 0 ? 0.0 : options.slide * f / options.slide_frames;
    problem.prescribed.clear();
    for (int v : r.top_face) problem.prescribed.emplace_back(v - shift, V3(dx, 0, -options.press));
    ForwardSummary summary;
    status = SolveQuasiStatic(problem, forward, &model, &mesh, &summary);
    if (!status.ok()) return status;
    r.converged = r.converged && summary.termination == ForwardTermination::kConverged;
    r.newton_iterations += summary.NumNewtonIterations();
    r.report += "frame " + std::to_string(f) + ": " + summary.BriefReport() + "\n";
    ++r.frames;
  }

  // The forces at the result: the support's on the pressed block, and the top face's reaction.
  potential.Refresh(mesh.x);
  for (const ContactForce& c : potential.Forces(mesh.x)) {
    const double sign = options.plane ? 1.0 : -1.0;  // a pair's force is the one on the base
    r.contact_force += sign * c.force;
    r.friction_force += sign * c.friction;
  }
  ForwardForces forces;
  status = EvaluateForwardForces(problem, forward, model, mesh, mesh.x, &forces);
  if (!status.ok()) return status;
  for (int v : r.top_face) r.top_reaction += forces.reactions.row(v - shift).transpose();
  r.max_penetration = world.Evaluate(potential.contacts(), mesh.x).max_penetration;
  r.top_rest = top.rest;
  r.top_x = mesh.x.middleRows(r.top_offset - shift, top.num_vertices());
  return Status::Ok();
}

void WritePressDeck(const PressOptions& options, const PressResult& r, std::ostream& out) {
  const TetMesh& mesh = r.deck;
  const int base_tets = r.top_first_tet;
  out.precision(15);
  out << "** femreg_forward_probe press: " << (options.plane ? "rigid plane" : "clamped block")
      << ", " << mesh.num_vertices() << " nodes, " << mesh.num_tets() << " C3D4\n*NODE, NSET=Nall\n";
  for (int v = 0; v < mesh.num_vertices(); ++v) {
    out << v + 1 << ", " << mesh.rest(v, 0) << ", " << mesh.rest(v, 1) << ", " << mesh.rest(v, 2) << "\n";
  }
  out << "*ELEMENT, TYPE=C3D4, ELSET=Ebase\n";
  for (int t = 0; t < mesh.num_tets(); ++t) {
    if (t == base_tets) out << "*ELEMENT, TYPE=C3D4, ELSET=Etop\n";
    out << t + 1;
    for (int k = 0; k < 4; ++k) out << ", " << mesh.tets(t, k) + 1;
    out << "\n";
  }
  std::vector<int> pressed;
  for (int v = r.top_offset; v < mesh.num_vertices(); ++v) pressed.push_back(v);
  WriteSet("Npressed", pressed, out);
  WriteSet("Ntop", r.top_face, out);
  WriteSet("Nclamp", r.clamped, out);
  // The pressed block's bottom is the slave (the smaller, finer face), the support's top the master.
  WriteSurface("Sslave", mesh, base_tets, mesh.num_tets(), r.top_surface, out);
  WriteSurface("Smaster", mesh, 0, base_tets, r.base_surface, out);
  for (const auto& [name, E] : {std::make_pair("Mbase", options.base_modulus),
                                 std::make_pair("Mtop", options.top_modulus)}) {
    const double nu = options.poisson_ratio, mu = E / (2 * (1 + nu)), K = E / (3 * (1 - 2 * nu));
    out << "*MATERIAL, NAME=" << name << "\n";
    if (options.neo_hookean) {
      out << "*HYPERELASTIC, NEO HOOKE\n" << mu / 2 << ", " << 2 / K << "\n";
    } else {
      out << "*ELASTIC\n" << E << ", " << nu << "\n";
    }
  }
  out << "*SOLID SECTION, ELSET=Ebase, MATERIAL=Mbase\n*SOLID SECTION, ELSET=Etop, MATERIAL=Mtop\n"
      << "*CONTACT PAIR, INTERACTION=SI, TYPE=SURFACE TO SURFACE\nSslave, Smaster\n"
      << "*SURFACE INTERACTION, NAME=SI\n*SURFACE BEHAVIOR, PRESSURE-OVERCLOSURE=LINEAR\n"
      << options.ccx_stiffness << "\n";
  if (options.friction > 0) out << "*FRICTION\n" << options.friction << ", " << options.ccx_stick_slope << "\n";
  out << "*BOUNDARY\nNclamp, 1, 3\n";
  const int steps = options.slide != 0.0 ? 2 : 1;
  for (int step = 0; step < steps; ++step) {
    out << "*STEP, NLGEOM, INC=1000\n*STATIC\n" << 1.0 / (step == 0 ? options.load_steps : options.slide_frames)
        << ", 1.0, 1e-6, " << 1.0 / (step == 0 ? options.load_steps : options.slide_frames) << "\n"
        << "*BOUNDARY\nNtop, 1, 1, " << (step == 0 ? 0.0 : options.slide) << "\nNtop, 2, 2, 0\nNtop, 3, 3, "
        << -options.press << "\n*NODE PRINT, NSET=Npressed\nU\n*NODE PRINT, NSET=Ntop, TOTALS=ONLY\nRF\n"
        << "*NODE PRINT, NSET=Nclamp, TOTALS=ONLY\nRF\n*END STEP\n";
  }
}

}  // namespace femreg
