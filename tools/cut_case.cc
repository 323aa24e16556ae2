// The cut case of tools/cut_case.h: femreg's forward solve and the CalculiX deck.
#include "tools/cut_case.h"

#include <Eigen/Geometry>
#include <cmath>
#include <exception>

#include "femreg/fem.h"
#include "femreg/forward.h"
#include "femreg/io.h"

namespace femreg {
namespace {

using V3 = Eigen::Vector3d;

// The gripped vertices' displacements from rest: turned by `angle` about y about their rest
// centroid c, which moves along the arc of a pure bending of the beam up to c (curvature
// angle / c.x), then by `carry`.
Vertices GripMotion(const TetMesh& mesh, const std::vector<int>& gripped, double angle, const V3& carry) {
  V3 c = V3::Zero();
  for (int v : gripped) c += mesh.rest.row(v).transpose();
  c /= static_cast<double>(gripped.size());
  const Eigen::Matrix3d R = Eigen::AngleAxisd(angle, V3::UnitY()).toRotationMatrix();
  V3 t = carry;
  if (angle != 0.0) {
    const double kappa = angle / c.x();
    t += V3(std::sin(angle) / kappa - c.x(), 0.0, -(1.0 - std::cos(angle)) / kappa);
  }
  Vertices u(static_cast<Eigen::Index>(gripped.size()), 3);
  for (size_t i = 0; i < gripped.size(); ++i) {
    const V3 X = mesh.rest.row(gripped[i]);
    u.row(static_cast<Eigen::Index>(i)) = (c + R * (X - c) + t - X).transpose();
  }
  return u;
}

void WriteSet(const std::string& kind, const std::string& name, const std::vector<int>& ids,
              std::ostream& out) {
  out << "*" << kind << ", " << kind << "=" << name << "\n";
  for (size_t i = 0; i < ids.size(); ++i) out << ids[i] + 1 << (i % 10 == 9 || i + 1 == ids.size() ? "\n" : ", ");
}

}  // namespace

Status ParseCutOptions(const std::map<std::string, std::string>& args, CutOptions* options) {
  CutOptions& o = *options;
  const std::map<std::string, double*> numbers = {{"E", &o.youngs_modulus}, {"nu", &o.poisson_ratio},
                                                  {"bend", &o.bend},        {"carry_x", &o.carry.x()},
                                                  {"carry_z", &o.carry.z()}};
  for (const auto& [key, value] : args) {
    try {
      if (key == "load_steps" || key == "max_iterations") {
        (key == "load_steps" ? o.load_steps : o.max_iterations) = std::stoi(value);
      } else if (numbers.count(key)) {
        *numbers.at(key) = std::stod(value);
      }
    } catch (const std::exception&) {
      return Status::Error(key + "=" + value + ": not a number");
    }
  }
  if (o.load_steps < 1) return Status::Error("load_steps must be >= 1");
  return Status::Ok();
}

Status SolveCutCase(const CutOptions& o, CutResult* result) {
  CutResult& r = *result;
  r.mesh = MakeBox(V3(o.length, o.width, o.width), o.cells_along, o.cells_across, o.cells_across);
  TetMesh mesh = r.mesh;
  for (int v = 0; v < mesh.num_vertices(); ++v) {
    if (mesh.rest(v, 0) < 1e-9) r.clamped.push_back(v);
    if (mesh.rest(v, 0) >= o.grip_x - 1e-9) r.gripped.push_back(v);
  }
  for (int e = 0; e < mesh.num_tets(); ++e) {
    double cx = 0.0;
    for (int k = 0; k < 4; ++k) cx += 0.25 * mesh.rest(mesh.tets(e, k), 0);
    if (cx > o.cut_lo && cx < o.cut_hi) r.slab.push_back(e);
  }
  r.grip_bent = GripMotion(mesh, r.gripped, o.bend, V3::Zero());
  r.grip_cut = GripMotion(mesh, r.gripped, o.bend, o.carry);
  Material material;
  material.youngs_modulus = o.youngs_modulus;
  material.poisson_ratio = o.poisson_ratio;
  ElasticModel model;
  model.Build(mesh, ElasticModelType::kCorotational, material);
  ForwardOptions forward;
  forward.num_threads = 1;
  forward.max_iterations = o.max_iterations;
  r.converged = true;
  for (int step = 0; step < 2; ++step) {
    if (step == 1) {
      // The slab's elements go; every vertex stays (the slab is one cell thick, its vertices
      // on the faces of the cells beside it).
      std::vector<char> drop(static_cast<size_t>(mesh.num_tets()), 0);
      for (int e : r.slab) drop[static_cast<size_t>(e)] = 1;
      Tets kept(mesh.num_tets() - static_cast<int>(r.slab.size()), 4);
      int row = 0;
      for (int e = 0; e < mesh.num_tets(); ++e) {
        if (!drop[static_cast<size_t>(e)]) kept.row(row++) = mesh.tets.row(e);
      }
      mesh.tets = kept;
      mesh.region = Eigen::VectorXi::Zero(kept.rows());
      BuildTopology(&mesh);
      model.Build(mesh, ElasticModelType::kCorotational, material);
    }
    ForwardProblem problem;
    problem.clamped = r.clamped;
    const Vertices& grip = step == 0 ? r.grip_bent : r.grip_cut;
    for (size_t i = 0; i < r.gripped.size(); ++i) {
      problem.prescribed.emplace_back(r.gripped[i], grip.row(static_cast<Eigen::Index>(i)).transpose());
    }
    // Step 1 from rest in load steps; step 2 in one from the bent beam (the prescribed moves
    // are scaled from rest: more steps would first take the gripper back).
    forward.load_steps = step == 0 ? o.load_steps : 1;
    ForwardSummary summary;
    const Status status = SolveQuasiStatic(problem, forward, &model, &mesh, &summary);
    if (!status.ok()) return status;
    r.converged = r.converged && summary.termination == ForwardTermination::kConverged;
    r.newton_iterations += summary.NumNewtonIterations();
    r.report += "step " + std::to_string(step + 1) + ": " + summary.BriefReport() + "\n";
    (step == 0 ? r.u_bent : r.u_cut) = mesh.x - mesh.rest;
  }
  ConnectedPieces(mesh, &r.piece);
  // Numbered by the smallest vertex: the clamped piece holds vertex 0.
  for (int& p : r.piece) p = p == r.piece[0] ? 0 : 1;
  return Status::Ok();
}

void WriteCutDeck(const CutOptions& o, const CutResult& r, std::ostream& out) {
  const TetMesh& mesh = r.mesh;
  out.precision(15);
  out << "** femreg_forward_probe cut: " << mesh.num_vertices() << " nodes, " << mesh.num_tets()
      << " C3D4, " << r.slab.size() << " of them removed in step 2\n*NODE, NSET=Nall\n";
  for (int v = 0; v < mesh.num_vertices(); ++v) {
    out << v + 1 << ", " << mesh.rest(v, 0) << ", " << mesh.rest(v, 1) << ", " << mesh.rest(v, 2) << "\n";
  }
  out << "*ELEMENT, TYPE=C3D4, ELSET=Eall\n";
  for (int t = 0; t < mesh.num_tets(); ++t) {
    out << t + 1;
    for (int k = 0; k < 4; ++k) out << ", " << mesh.tets(t, k) + 1;
    out << "\n";
  }
  WriteSet("ELSET", "Eslab", r.slab, out);
  WriteSet("NSET", "Nclamp", r.clamped, out);
  WriteSet("NSET", "Ngrip", r.gripped, out);
  out << "*MATERIAL, NAME=M\n*ELASTIC\n" << o.youngs_modulus << ", " << o.poisson_ratio
      << "\n*SOLID SECTION, ELSET=Eall, MATERIAL=M\n*BOUNDARY\nNclamp, 1, 3\n";
  for (int step = 0; step < 2; ++step) {
    const double increment = step == 0 ? 1.0 / o.load_steps : 0.1;
    out << "*STEP, NLGEOM, INC=1000\n";
    if (step == 1) out << "*MODEL CHANGE, TYPE=ELEMENT, REMOVE\nEslab\n";
    out << "*STATIC\n" << increment << ", 1.0, 1e-6, " << increment << "\n*BOUNDARY\n";
    const Vertices& grip = step == 0 ? r.grip_bent : r.grip_cut;
    for (size_t i = 0; i < r.gripped.size(); ++i) {
      for (int a = 0; a < 3; ++a) {
        out << r.gripped[i] + 1 << ", " << a + 1 << ", " << a + 1 << ", " << grip(static_cast<Eigen::Index>(i), a) << "\n";
      }
    }
    out << "*NODE PRINT, NSET=Nall\nU\n*END STEP\n";
  }
}

}  // namespace femreg
