// femreg_forward_probe: builds a clamped beam (box) or cylinder, solves it with femreg's
// forward quasi-static solver, writes the displacements as CSV and, on request, the same
// problem as a CalculiX input deck, so that tools/compare_calculix.sh can compare.
//
//   femreg_forward_probe key=value ...
//     shape=box|cylinder  length=1  height=0.1 (box section)  radius=0.05 (cylinder)
//     n=4 (cells across; the box has 10 n along)  axial=0 (cells along; 0 = automatic)
//     E=1e6 nu=0.3 density=1000  model=corotational|linear|neo_hookean  load_steps=1
//     volume=element|nodal (neo_hookean)
//     tip_load=0 (N, total, on the free end, along -z for the box, -x for the cylinder)
//     gravity=0 (m/s^2, same direction)  csv=out.csv  inp=out.inp  nlgeom=0|1
//     tangent=full|projected|warped  watchdog=3 (steps)  max_iterations=200
//     verbose=0|1 (the full report)
//     deck: ccx_material=elastic|neo_hooke (*ELASTIC, or *HYPERELASTIC, NEO HOOKE with
//     C10 = mu / 2, D1 = 2 / K, K the bulk modulus: the same small-strain moduli)
//     element=c3d4|c3d10 (c3d10: a node at every edge's midpoint, the corner nodes
//     numbered as femreg's vertices; the loads stay on the corner nodes, gravity on all)
//
// The box lies along +x and is clamped at x = 0; the cylinder along +z, clamped at z = 0.
//
//   femreg_forward_probe shape=cut key=value ...   (separation: tools/cut_case.h)
//     E=5e4 nu=0.35 bend=0.4 (rad) carry_x=0.016 carry_z=0.012 (m) load_steps=8 max_iterations=100
//     csv=out.csv (id,X,Y,Z,ux1,uy1,uz1,ux2,uy2,uz2,piece: after each step)  inp=out.inp
//
//   femreg_forward_probe shape=organ key=value ...   (organ_patch's ground truth, one frame)
//     divisions=10 (the truth's mesh; the bundled one: 10)  frame=7 (0-11)
//     model=neo_hookean|corotational  volume=nodal|element (neo_hookean)  nu=0.47
//     tool=glued|contact (the contact tool solves the frames up to `frame` in order)
//     csv=out.csv (id,X,Y,Z,ux,uy,uz: the truth interpolated at the rest vertices of the
//     organ's mesh at tracked=4 divisions, as ground_truth/ holds it)
//   Prints the tool's force and the clamp's reaction (N) and the solve's Newton iterations.
//
//   femreg_forward_probe shape=press key=value ...   (contact: tools/press_case.h)
//     support=block|plane  E=3e4 (pressed block)  E_base=6e4  nu=0.3  gap=5e-4  press=1.5e-3
//     slide=0 (m, along x)  slide_frames=12  load_steps=8  stiffness=1e5 (k, N/m)  distance=1e-3
//     mu=0  slip=2e-5 (eps, m)  max_iterations=100 (per load step)  ccx_stiffness=1e9 (Pa/m)
//     ccx_stick=5e7 (Pa/m)  model=neo_hookean|corotational
//     csv=out.csv (the pressed block: id,X,Y,Z,ux,uy,uz,free)  forces=forces.csv  inp=out.inp
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <iostream>
#include <map>
#include <string>
#include <utility>
#include <vector>

#include "femreg/datasets.h"
#include "femreg/fem.h"
#include "femreg/forward.h"
#include "femreg/geometry.h"
#include "femreg/io.h"
#include "femreg/mesh.h"
#include "tools/cut_case.h"
#include "tools/press_case.h"

namespace {

std::map<std::string, std::string> ParseArgs(int argc, char** argv) {
  std::map<std::string, std::string> args;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    const size_t eq = a.find('=');
    if (eq == std::string::npos) {
      std::cerr << "femreg_forward_probe: expected key=value, got '" << a << "'\n";
      std::exit(2);
    }
    args[a.substr(0, eq)] = a.substr(eq + 1);
  }
  return args;
}

double Number(const std::map<std::string, std::string>& args, const std::string& key,
              double fallback) {
  const auto it = args.find(key);
  return it == args.end() ? fallback : std::stod(it->second);
}

std::string Text(const std::map<std::string, std::string>& args, const std::string& key,
                 const std::string& fallback) {
  const auto it = args.find(key);
  return it == args.end() ? fallback : it->second;
}

// shape=organ: one frame of organ_patch's ground truth (femreg/datasets.h), to see how far
// the bundled truth's mesh is from converged.
int Organ(const std::map<std::string, std::string>& args) {
  using namespace femreg;
  const int divisions = static_cast<int>(Number(args, "divisions", 10));
  const int frame = static_cast<int>(Number(args, "frame", 7));
  const int tracked = static_cast<int>(Number(args, "tracked", 4));
  ObjectMaterial material = OrganPatchTruthMaterial();
  const std::string model = Text(args, "model", "neo_hookean");
  if (model != "neo_hookean" && model != "corotational") {
    std::cerr << "femreg_forward_probe: shape=organ takes model=neo_hookean or corotational\n";
    return 2;
  }
  material.model = model == "neo_hookean" ? MaterialModel::kNeoHookean : MaterialModel::kHooke;
  material.nodal_volume = model == "neo_hookean" && Text(args, "volume", "nodal") == "nodal";
  material.material.poisson_ratio = Number(args, "nu", material.material.poisson_ratio);
  OrganTool tool = OrganTool::kGlued;
  if (!FromString(Text(args, "tool", "glued"), &tool)) {
    std::cerr << "femreg_forward_probe: shape=organ takes tool=glued or contact\n";
    return 2;
  }
  const auto start = std::chrono::steady_clock::now();
  OrganTruthFrame truth;
  const Status status = SolveOrganPatchTruth(frame, divisions, material, &truth, tool);
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  if (!status.ok()) {
    std::cerr << "femreg_forward_probe: " << status.message() << "\n";
    return 1;
  }
  const TetMesh mesh = OrganPatchMesh(divisions);
  std::printf("organ divisions %d (%d vertices), frame %d, %s%s nu %.3f: %d Newton iterations, %.1f s\n",
              divisions, mesh.num_vertices(), frame, model.c_str(), material.nodal_volume ? " (nodal volume)" : "",
              material.material.poisson_ratio, truth.summary.NumNewtonIterations(), seconds);
  std::printf("tool force   %+.6f %+.6f %+.6f N  |%.6f|\n", truth.tool.force.x(), truth.tool.force.y(),
              truth.tool.force.z(), truth.tool.force.norm());
  std::printf("clamp force  %+.6f %+.6f %+.6f N  imbalance %.2e N\n", truth.clamp.force.x(),
              truth.clamp.force.y(), truth.clamp.force.z(), (truth.tool.force + truth.clamp.force).norm());
  if (tool == OrganTool::kContact) {
    std::printf("contacts %d, deepest penetration %.4f mm\n", truth.contacts, truth.max_penetration * 1e3);
  }
  const std::string csv = Text(args, "csv", "");
  if (!csv.empty()) {
    const TetMesh at = OrganPatchMesh(tracked);
    const Vertices x = InterpolateEmbedded(mesh, truth.positions, EmbedPoints(mesh, at.rest));
    std::ofstream out(csv);
    out << "id,X,Y,Z,ux,uy,uz\n";
    char line[256];
    for (int v = 0; v < at.num_vertices(); ++v) {
      const Eigen::Vector3d X = at.rest.row(v), u = x.row(v) - at.rest.row(v);
      std::snprintf(line, sizeof(line), "%d,%.9g,%.9g,%.9g,%.9g,%.9g,%.9g\n", v, X.x(), X.y(), X.z(), u.x(), u.y(),
                    u.z());
      out << line;
    }
  }
  return 0;
}

// shape=press: the contact case of tools/press_case.h.
int Press(const std::map<std::string, std::string>& args) {
  using namespace femreg;
  PressOptions o;
  const Status parsed = ParsePressOptions(args, &o);
  if (!parsed.ok()) {
    std::cerr << "femreg_forward_probe: " << parsed.message() << "\n";
    return 2;
  }
  PressResult r;
  const Status status = SolvePressCase(o, &r);
  if (!status.ok()) {
    std::cerr << "femreg_forward_probe: " << status.message() << "\n";
    return 1;
  }
  std::cerr << r.report << "press: " << (r.converged ? "converged" : "NOT converged") << ", "
            << r.newton_iterations << " Newton iterations in " << r.frames
            << " frames, deepest penetration " << r.max_penetration * 1e3 << " mm\n";
  const std::string csv = Text(args, "csv", "");
  if (!csv.empty()) {
    std::ofstream out(csv);
    out.precision(12);
    out << "id,X,Y,Z,ux,uy,uz,free\n";
    for (int v = 0; v < r.top_rest.rows(); ++v) {
      const Eigen::RowVector3d u = r.top_x.row(v) - r.top_rest.row(v);
      out << r.top_offset + v + 1 << "," << r.top_rest(v, 0) << "," << r.top_rest(v, 1) << ","
          << r.top_rest(v, 2) << "," << u(0) << "," << u(1) << "," << u(2) << ","
          << int(r.free_surface[v]) << "\n";
    }
  }
  const std::string forces = Text(args, "forces", "");
  if (!forces.empty()) {
    std::ofstream out(forces);
    out.precision(12);
    out << "quantity,fx,fy,fz\n";
    const std::pair<const char*, Eigen::Vector3d> rows[] = {
        {"contact", r.contact_force}, {"friction", r.friction_force}, {"top_reaction", r.top_reaction}};
    for (const auto& [name, f] : rows) out << name << "," << f(0) << "," << f(1) << "," << f(2) << "\n";
  }
  const std::string inp = Text(args, "inp", "");
  if (!inp.empty()) {
    std::ofstream out(inp);
    WritePressDeck(o, r, out);
  }
  return r.converged ? 0 : 1;
}

// shape=cut: the separation case of tools/cut_case.h.
int Cut(const std::map<std::string, std::string>& args) {
  using namespace femreg;
  CutOptions o;
  const Status parsed = ParseCutOptions(args, &o);
  if (!parsed.ok()) {
    std::cerr << "femreg_forward_probe: " << parsed.message() << "\n";
    return 2;
  }
  CutResult r;
  const Status status = SolveCutCase(o, &r);
  if (!status.ok()) {
    std::cerr << "femreg_forward_probe: " << status.message() << "\n";
    return 1;
  }
  std::cerr << r.report << "cut: " << (r.converged ? "converged" : "NOT converged") << ", "
            << r.newton_iterations << " Newton iterations, " << r.slab.size() << " elements removed\n";
  const std::string csv = Text(args, "csv", "");
  if (!csv.empty()) {
    std::ofstream out(csv);
    out.precision(12);
    out << "id,X,Y,Z,ux1,uy1,uz1,ux2,uy2,uz2,piece\n";
    for (int v = 0; v < r.mesh.num_vertices(); ++v) {
      out << v + 1 << "," << r.mesh.rest(v, 0) << "," << r.mesh.rest(v, 1) << "," << r.mesh.rest(v, 2);
      for (const Vertices* u : {&r.u_bent, &r.u_cut}) {
        out << "," << (*u)(v, 0) << "," << (*u)(v, 1) << "," << (*u)(v, 2);
      }
      out << "," << r.piece[static_cast<size_t>(v)] << "\n";
    }
  }
  const std::string inp = Text(args, "inp", "");
  if (!inp.empty()) {
    std::ofstream out(inp);
    WriteCutDeck(o, r, out);
  }
  return r.converged ? 0 : 1;
}

}  // namespace

int main(int argc, char** argv) {
  using namespace femreg;
  const auto args = ParseArgs(argc, argv);
  const std::string shape = Text(args, "shape", "box");
  if (shape == "press") return Press(args);
  if (shape == "cut") return Cut(args);
  if (shape == "organ") return Organ(args);
  const double length = Number(args, "length", 1.0);
  const int n = static_cast<int>(Number(args, "n", 4));
  int axial = static_cast<int>(Number(args, "axial", 0));
  Material material;
  material.youngs_modulus = Number(args, "E", 1e6);
  material.poisson_ratio = Number(args, "nu", 0.3);
  material.density = Number(args, "density", 1000.0);
  ElasticModelType type = ElasticModelType::kCorotational;
  if (!FromString(Text(args, "model", "corotational"), &type)) {
    std::cerr << "femreg_forward_probe: model must be corotational, linear or neo_hookean\n";
    return 2;
  }
  ObjectMaterial object_material(material);
  if (type == ElasticModelType::kNeoHookean) object_material.model = MaterialModel::kNeoHookean;
  object_material.nodal_volume = Text(args, "volume", "element") == "nodal";
  const double tip_load = Number(args, "tip_load", 0.0);
  const double gravity = Number(args, "gravity", 0.0);

  TetMesh mesh;
  int axis = 0;                                   // beam axis
  Eigen::Vector3d direction(0, 0, -1);            // load direction
  if (shape == "box") {
    const double h = Number(args, "height", 0.1);
    if (axial <= 0) axial = static_cast<int>(std::lround(n * length / h));
    mesh = MakeBox(Eigen::Vector3d(length, h, h), axial, n, n);
  } else if (shape == "cylinder") {
    const double radius = Number(args, "radius", 0.05);
    if (axial <= 0) axial = static_cast<int>(std::lround(n * length / radius));
    mesh = MakeCylinder(radius, length, n, axial);
    axis = 2;
    direction = Eigen::Vector3d(-1, 0, 0);
  } else {
    std::cerr << "femreg_forward_probe: shape must be box or cylinder\n";
    return 2;
  }
  if (mesh.num_tets() == 0) {
    std::cerr << "femreg_forward_probe: the generator returned an empty mesh\n";
    return 1;
  }
  ComputeLumpedMasses(&mesh, material.density);

  ForwardProblem problem;
  std::vector<int> tip;
  const double tol = 1e-9 * length;
  for (int v = 0; v < mesh.num_vertices(); ++v) {
    if (mesh.rest(v, axis) < tol) problem.clamped.push_back(v);
    if (mesh.rest(v, axis) > length - tol) tip.push_back(v);
  }
  if (tip_load != 0.0) {
    for (int v : tip) problem.nodal_loads.push_back({v, tip_load / tip.size() * direction});
  }
  problem.gravity = gravity * direction;

  ElasticModel model;
  model.Build(mesh, type, object_material);
  ForwardOptions options;
  options.load_steps = static_cast<int>(Number(args, "load_steps", 1));
  options.max_iterations = static_cast<int>(Number(args, "max_iterations", 200));
  if (!FromString(Text(args, "tangent", "full"), &options.tangent)) {
    std::cerr << "femreg_forward_probe: tangent must be full, projected or warped\n";
    return 2;
  }
  options.watchdog_steps = static_cast<int>(Number(args, "watchdog", 3));
  options.verbose = Number(args, "verbose", 0) != 0;
  ForwardSummary summary;
  const Status status = SolveQuasiStatic(problem, options, &model, &mesh, &summary);
  std::cerr << (options.verbose ? summary.FullReport() : summary.BriefReport()) << "\n";
  if (!status.ok()) {
    std::cerr << status.message() << "\n";
    return 1;
  }

  const std::string csv = Text(args, "csv", "");
  if (!csv.empty()) {
    std::ofstream out(csv);
    out.precision(12);
    out << "id,X,Y,Z,ux,uy,uz,tip\n";
    std::vector<char> is_tip(mesh.num_vertices(), 0);
    for (int v : tip) is_tip[v] = 1;
    for (int v = 0; v < mesh.num_vertices(); ++v) {
      const Eigen::RowVector3d u = mesh.x.row(v) - mesh.rest.row(v);
      out << v + 1 << "," << mesh.rest(v, 0) << "," << mesh.rest(v, 1) << "," << mesh.rest(v, 2)
          << "," << u(0) << "," << u(1) << "," << u(2) << "," << int(is_tip[v]) << "\n";
    }
  }

  const std::string inp = Text(args, "inp", "");
  if (!inp.empty()) {
    const bool nlgeom = Number(args, "nlgeom", 0) != 0;
    const std::string element = Text(args, "element", "c3d4");
    const std::string ccx_material = Text(args, "ccx_material", "elastic");
    if ((element != "c3d4" && element != "c3d10") ||
        (ccx_material != "elastic" && ccx_material != "neo_hooke")) {
      std::cerr << "femreg_forward_probe: element must be c3d4 or c3d10, ccx_material elastic or neo_hooke\n";
      return 2;
    }
    // C3D10: a midside node per edge (CalculiX's order: 1-2, 2-3, 3-1, 1-4, 2-4, 3-4).
    std::map<std::pair<int, int>, int> midside;
    std::vector<int> clamped_nodes;
    for (int v : problem.clamped) clamped_nodes.push_back(v + 1);
    std::vector<char> is_clamped(mesh.num_vertices(), 0);
    for (int v : problem.clamped) is_clamped[v] = 1;
    static const int kEdges[6][2] = {{0, 1}, {1, 2}, {2, 0}, {0, 3}, {1, 3}, {2, 3}};
    std::ofstream out(inp);
    out.precision(15);
    out << "** femreg_forward_probe: " << shape << ", " << mesh.num_vertices() << " vertices, "
        << mesh.num_tets() << " " << element << "\n*NODE, NSET=Nall\n";
    for (int v = 0; v < mesh.num_vertices(); ++v)
      out << v + 1 << ", " << mesh.rest(v, 0) << ", " << mesh.rest(v, 1) << ", " << mesh.rest(v, 2) << "\n";
    if (element == "c3d10") {
      int next = mesh.num_vertices() + 1;
      for (int t = 0; t < mesh.num_tets(); ++t) {
        for (const auto& e : kEdges) {
          int a = mesh.tets(t, e[0]), b = mesh.tets(t, e[1]);
          if (a > b) std::swap(a, b);
          if (!midside.emplace(std::make_pair(a, b), next).second) continue;
          const Eigen::RowVector3d m = 0.5 * (mesh.rest.row(a) + mesh.rest.row(b));
          out << next << ", " << m(0) << ", " << m(1) << ", " << m(2) << "\n";
          if (is_clamped[a] && is_clamped[b]) clamped_nodes.push_back(next);
          ++next;
        }
      }
    }
    out << "*ELEMENT, TYPE=" << (element == "c3d10" ? "C3D10" : "C3D4") << ", ELSET=Eall\n";
    for (int t = 0; t < mesh.num_tets(); ++t) {
      out << t + 1;
      for (int k = 0; k < 4; ++k) out << ", " << mesh.tets(t, k) + 1;
      if (element == "c3d10") {
        for (const auto& e : kEdges) {
          const int a = std::min(mesh.tets(t, e[0]), mesh.tets(t, e[1]));
          const int b = std::max(mesh.tets(t, e[0]), mesh.tets(t, e[1]));
          out << ", " << midside.at({a, b});
        }
      }
      out << "\n";
    }
    out << "*NSET, NSET=Nclamp\n";
    for (size_t i = 0; i < clamped_nodes.size(); ++i)
      out << clamped_nodes[i] << (i % 10 == 9 || i + 1 == clamped_nodes.size() ? "\n" : ", ");
    out << "*BOUNDARY\nNclamp, 1, 3\n";
    out << "*MATERIAL, NAME=M\n";
    if (ccx_material == "neo_hooke") {
      const double E = material.youngs_modulus, nu = material.poisson_ratio;
      const double mu = E / (2 * (1 + nu)), K = E / (3 * (1 - 2 * nu));
      out << "*HYPERELASTIC, NEO HOOKE\n" << mu / 2 << ", " << 2 / K << "\n";
    } else {
      out << "*ELASTIC\n" << material.youngs_modulus << ", " << material.poisson_ratio << "\n";
    }
    out << "*DENSITY\n" << material.density << "\n";
    out << "*SOLID SECTION, ELSET=Eall, MATERIAL=M\n";
    if (nlgeom) {
      out << "*STEP, NLGEOM, INC=1000\n*STATIC\n0.05, 1.0, 1e-6, 0.1\n";
    } else {
      out << "*STEP\n*STATIC\n";
    }
    if (tip_load != 0.0) {
      out << "*CLOAD\n";
      for (int v : tip)
        for (int i = 0; i < 3; ++i)
          if (direction(i) != 0) out << v + 1 << ", " << i + 1 << ", " << tip_load / tip.size() * direction(i) << "\n";
    }
    if (gravity != 0.0) {
      out << "*DLOAD\nEall, GRAV, " << gravity << ", " << direction(0) << ", " << direction(1)
          << ", " << direction(2) << "\n";
    }
    out << "*NODE PRINT, NSET=Nall\nU\n*END STEP\n";
  }
  return 0;
}
