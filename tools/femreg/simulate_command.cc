// femreg simulate SCENE --out DIR: the quasi-static equilibrium of every object of a scene
// under its clamps, prescribed displacements, loads and gravity, written as VTU files and
// a summary.json.
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <iomanip>
#include <iostream>
#include <limits>
#include <memory>
#include <sstream>
#include <string>
#include <vector>

#include "cli_util.h"
#include "commands.h"
#include "mesh_warnings.h"
#include "femreg/fem.h"
#include "femreg/forward.h"
#include "femreg/forward_results.h"
#include "femreg/io.h"
#include "femreg/scene.h"

namespace femreg {
namespace cli {
namespace {

namespace fs = std::filesystem;

struct SimulateOptions {
  std::string scene_path;
  std::string out_dir;
  std::string object;      // "" = every object
  std::string model;       // "" = the scene's forward.model
  int load_steps = 0;      // 0 = the scene's forward.load_steps
  int max_iterations = 0;  // 0 = the scene's forward.max_iterations
  std::string tangent;     // "" = ForwardOptions' default (full)
  int threads = 0;         // 0 = OpenMP's default
  bool verbose = false;
  bool force = false;
  std::vector<std::string> sets;  // --set key.path=value
};

using ObjectResult = SimulateObjectResult;

double Seconds(std::chrono::steady_clock::time_point since) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - since).count();
}

std::string Vec(const Eigen::Vector3d& v) {
  std::ostringstream os;
  os << std::setprecision(4) << "(" << v.x() << ", " << v.y() << ", " << v.z() << ")";
  return os.str();
}

// Loads, solves and writes one object. Returns false (with result->error) on failure.
bool RunObject(const Scene& scene, int index, ElasticModelType model_type,
               const ForwardOptions& forward, const fs::path& out_dir, ObjectResult* result) {
  const ObjectSpec& spec = scene.objects[index];
  result->name = spec.name;
  auto start = std::chrono::steady_clock::now();
  TetMesh mesh;
  Status status = LoadObjectMesh(scene, index, &mesh);
  ForwardProblem problem;
  if (status.ok()) status = BuildForwardProblem(scene, index, mesh, &problem);
  if (!status.ok()) {
    result->error = status.message();
    return false;
  }
  WarnFoldedElements("simulate", "object '" + spec.name + "'", mesh);
  result->num_vertices = mesh.num_vertices();
  result->num_tets = mesh.num_tets();
  result->num_clamped = static_cast<int>(problem.clamped.size());
  result->num_prescribed = static_cast<int>(problem.prescribed.size());
  result->num_loaded = static_cast<int>(problem.nodal_loads.size());
  ElasticModel model;
  model.Build(mesh, model_type, spec.Materials());
  result->model = ToString(model.type());
  result->volume = model.nodal_volume() ? "nodal" : "element";
  result->load_time_s = Seconds(start);

  start = std::chrono::steady_clock::now();
  status = SolveQuasiStatic(problem, forward, &model, &mesh, &result->summary);
  result->solve_time_s = Seconds(start);
  if (!status.ok()) {
    result->error = status.message();
    return false;
  }

  const Vertices displacement = mesh.x - mesh.rest;
  for (int v = 0; v < mesh.num_vertices(); ++v) {
    const double d = displacement.row(v).norm();
    if (d > result->max_displacement || result->max_vertex < 0) {
      result->max_displacement = d;
      result->max_vertex = v;
    }
  }
  if (result->max_vertex >= 0) result->max_rest = mesh.rest.row(result->max_vertex).transpose();
  // The free end: the vertex farthest from the clamped set (from the centroid of the
  // clamped vertices; from nothing when there are none).
  if (!problem.clamped.empty()) {
    Eigen::Vector3d centroid = Eigen::Vector3d::Zero();
    for (int v : problem.clamped) centroid += mesh.rest.row(v).transpose();
    centroid /= static_cast<double>(problem.clamped.size());
    double farthest = -1.0;
    for (int v = 0; v < mesh.num_vertices(); ++v) {
      const double d = (mesh.rest.row(v).transpose() - centroid).norm();
      if (d > farthest) {
        farthest = d;
        result->end_vertex = v;
      }
    }
    result->end_displacement = displacement.row(result->end_vertex).transpose();
    // "At the free end": within 5% of the largest distance from the clamps.
    result->max_at_free_end =
        (result->max_rest - centroid).norm() >= 0.95 * farthest;
  }

  // Only a converged solve is an equilibrium; a state left at max_iterations is not
  // written (summary.json says how far each load step got).
  if (result->summary.termination != ForwardTermination::kConverged) {
    result->error = "the solve did not reach equilibrium (" +
                    std::string(ToString(result->summary.termination)) + "): " +
                    result->summary.message;
    return false;
  }

  // Point fields: the displacement, and which boundary condition holds each vertex
  // (0 free, 1 clamped, 2 prescribed displacement). WriteVtu adds the region per cell.
  start = std::chrono::steady_clock::now();
  Eigen::MatrixXd boundary = Eigen::MatrixXd::Zero(mesh.num_vertices(), 1);
  for (int v : problem.clamped) boundary(v, 0) = 1;
  for (const auto& [v, u] : problem.prescribed) boundary(v, 0) = 2;
  Eigen::MatrixXd loads = Eigen::MatrixXd::Zero(mesh.num_vertices(), 3);
  for (const auto& [v, f] : problem.nodal_loads) loads.row(v) = f.transpose();
  std::vector<MeshField> fields = {{"displacement", Eigen::MatrixXd(displacement), false},
                                   {"boundary", boundary, false},
                                   {"nodal_load", loads, false}};
  result->vtu = spec.name + ".vtu";
  status = WriteVtu((out_dir / result->vtu).string(), mesh, mesh.x, fields);
  result->write_time_s = Seconds(start);
  if (!status.ok()) {
    result->vtu.clear();
    result->error = status.message();
    return false;
  }
  return true;
}

// Fails with a message on stderr and exit code 1.
void Fail(const std::string& message) {
  std::cerr << "femreg simulate: " << message << "\n";
  SetExitCode(1);
}

void RunSimulate(const SimulateOptions& options) {
  const auto start = std::chrono::steady_clock::now();
  Scene scene;
  Status status = LoadSceneWithSets(options.scene_path, options.sets, &scene);
  if (!status.ok()) return Fail(status.message());

  std::vector<int> objects;
  for (int i = 0; i < static_cast<int>(scene.objects.size()); ++i) {
    if (options.object.empty() || scene.objects[i].name == options.object) objects.push_back(i);
  }
  if (objects.empty()) {
    std::string names;
    for (const ObjectSpec& o : scene.objects) names += (names.empty() ? "" : ", ") + o.name;
    return Fail("--object " + options.object + ": the scene has no such object (objects: " +
                names + ")");
  }

  ElasticModelType model_type = scene.forward.Model();
  if (!options.model.empty() && !FromString(options.model, &model_type)) {
    return Fail("--model " + options.model + ": use corotational, linear or neo_hookean");
  }
  if (!options.model.empty()) {  // every object, whatever its material.model says
    for (ObjectSpec& o : scene.objects) {
      const bool neo_hookean = model_type == ElasticModelType::kNeoHookean;
      o.model = neo_hookean ? MaterialModel::kNeoHookean : MaterialModel::kHooke;  // chosen
      if (!neo_hookean) o.volume.reset();  // the nodal volume is neo-Hookean's
    }
  }
  for (const std::string& line : ChooseForwardElements(&scene)) std::cout << line << "\n";
  ForwardOptions forward = scene.forward;
  if (!options.model.empty()) forward.model = model_type;  // summary.json's forward block says so
  if (options.load_steps > 0) forward.load_steps = options.load_steps;
  if (options.max_iterations > 0) forward.max_iterations = options.max_iterations;
  if (!options.tangent.empty() && !FromString(options.tangent, &forward.tangent)) {
    return Fail("--tangent " + options.tangent + ": use full, projected or warped");
  }
  forward.num_threads = options.threads;
  forward.verbose = options.verbose;

  // The output folder: created when missing; an existing non-empty one only with --force.
  const fs::path out_dir(options.out_dir);
  const Status prepared = PrepareOutputDir(options.out_dir, options.force);
  if (!prepared.ok()) return Fail("--out " + prepared.message());

  std::vector<ObjectResult> results;
  bool all_ok = true;
  for (int index : objects) {
    ObjectResult result;
    if (objects.size() > 1 || options.verbose) {
      std::cout << "== " << scene.objects[index].name << "\n";
    }
    const bool ok = RunObject(scene, index, model_type, forward, out_dir, &result);
    all_ok = all_ok && ok;
    if (result.summary.termination != ForwardTermination::kNotRun) {
      std::cout << (options.verbose ? result.summary.FullReport() : result.summary.BriefReport())
                << "\n";
    }
    if (ok) {
      std::cout << result.name << ": " << result.num_vertices << " vertices, "
                << result.num_tets << " elements; max displacement " << std::setprecision(4)
                << result.max_displacement << " m at vertex " << result.max_vertex << " (rest "
                << Vec(result.max_rest) << ")";
      if (result.end_vertex >= 0) {
        std::cout << (result.max_at_free_end ? ", at the free end" : ", not at the free end")
                  << "; free end (farthest from the clamps) moved by "
                  << Vec(result.end_displacement) << " m";
      }
      std::cout << "\n  wrote " << (out_dir / result.vtu).string() << "\n";
    } else {
      std::cerr << "femreg simulate: " << result.name << ": " << result.error << "\n";
    }
    results.push_back(std::move(result));
  }

  SimulateRun run;
  run.scene = options.scene_path;
  run.overrides = options.sets;
  run.model = model_type;
  run.forward = forward;
  run.total_time_s = Seconds(start);
  const std::string json = SimulateSummaryJson(run, scene, results);
  status = WriteFileAtomically((out_dir / "summary.json").string(), json);
  if (!status.ok()) return Fail(status.message());
  std::cout << "wrote " << (out_dir / "summary.json").string() << "\n";
  if (!all_ok) SetExitCode(1);
}

}  // namespace

void AddSimulateCommand(CLI::App* app) {
  auto options = std::make_shared<SimulateOptions>();
  CLI::App* cmd = app->add_subcommand(
      "simulate",
      "Solve the quasi-static equilibrium of a scene's objects under its clamps, prescribed "
      "displacements, loads and gravity.");
  cmd->footer(
      "Writes DIR/<object>.vtu (point fields: displacement, boundary [0 free, 1 clamped,\n"
      "2 displaced], nodal_load; cell field: region) and DIR/summary.json (termination,\n"
      "Newton iterations and termination per load step, residuals, max displacement,\n"
      "times). Exit code 1 on any error, and when a solve does not converge (no VTU is\n"
      "written for that object; try more --load-steps).\n"
      "The scene format is described in datasets/README.md.\n"
      "Example: femreg simulate datasets/beam/beam.yaml --out /tmp/beam");
  // No CLI::ExistingFile check: LoadScene reports a missing file with exit code 1 like any
  // other scene error.
  cmd->add_option("scene", options->scene_path, "Scene file (YAML)")->required();
  cmd->add_option("-o,--out", options->out_dir, "Output folder (created when missing)")
      ->required();
  cmd->add_option("--object", options->object, "Simulate only the object of this name");
  cmd->add_option("--model", options->model,
                  "Elastic model of every object, overrides the scene's forward.model and its "
                  "objects' material.model: corotational, linear (small strain) or neo_hookean "
                  "(stable neo-Hookean, large strain and nu -> 0.5; per object: "
                  "objects[i].material.model, with material.volume: nodal against locking)")
      ->check(CLI::IsMember({"corotational", "linear", "neo_hookean"}));
  cmd->add_option("--load-steps", options->load_steps,
                  "Apply loads and displacements in N steps, overrides forward.load_steps")
      ->check(CLI::PositiveNumber);
  cmd->add_option("--max-iterations", options->max_iterations,
                  "Newton iterations per load step, overrides forward.max_iterations")
      ->check(CLI::PositiveNumber);
  cmd->add_option("--tangent", options->tangent,
                  "Newton matrix: full (consistent tangent, default), projected (its PSD "
                  "projection per element) or warped (R K R^T, the rotations held fixed)")
      ->check(CLI::IsMember({"full", "projected", "warped"}));
  cmd->add_option("--threads", options->threads,
                  "Threads for the element loops and the BLAS under CHOLMOD (default: "
                  "OpenMP's, OMP_NUM_THREADS)")
      ->check(CLI::PositiveNumber);
  cmd->add_flag("-v,--verbose", options->verbose,
                "One line per Newton iteration and the full report");
  cmd->add_flag("-f,--force", options->force, "Write into a non-empty output folder");
  AddSetOption(cmd, &options->sets);
  cmd->callback([options] { RunSimulate(*options); });
}

}  // namespace cli
}  // namespace femreg
