// femreg/forward_results.h - the files the forward-solve commands write: femreg simulate's
// summary.json and femreg calibrate's calibration.json, beside a registration run's
// (femreg/results.h). Their option blocks come from the options' field tables
// (femreg/field_table.h), as summary.json's do, so that a new option appears in them
// without touching the writers.
#ifndef FEMREG_FORWARD_RESULTS_H_
#define FEMREG_FORWARD_RESULTS_H_

#include <Eigen/Core>
#include <string>
#include <vector>

#include "femreg/calibration.h"
#include "femreg/fem.h"
#include "femreg/forward.h"
#include "femreg/scene.h"

namespace femreg {

// What one object's forward solve produced (femreg simulate).
struct SimulateObjectResult {
  std::string name;
  std::string vtu;  // file name inside the output folder, "" when not written
  int num_vertices = 0, num_tets = 0;
  int num_clamped = 0, num_prescribed = 0, num_loaded = 0;
  ForwardSummary summary;
  std::string model, volume;  // the element it was solved with: model.type(), element/nodal
  std::string error;          // set when the object could not be run
  int max_vertex = -1;
  double max_displacement = 0.0;
  Eigen::Vector3d max_rest = Eigen::Vector3d::Zero();
  int end_vertex = -1;  // the vertex farthest from the clamped ones
  Eigen::Vector3d end_displacement = Eigen::Vector3d::Zero();
  bool max_at_free_end = false;
  double load_time_s = 0.0, solve_time_s = 0.0, write_time_s = 0.0;
};

// How femreg simulate was run.
struct SimulateRun {
  std::string scene;                   // the scene file, as given
  std::vector<std::string> overrides;  // --set key.path=value
  ElasticModelType model = ElasticModelType::kCorotational;  // every object's
  ForwardOptions forward;  // as solved with: the scene's forward:, and the command line's
  double total_time_s = 0.0;
};

// summary.json of femreg simulate: {"femreg_version", "scene", "overrides", "model",
// "tangent", "load_steps", "max_iterations", "gravity", "forward" (every field of the forward
// table, by its scene key), "objects": [per object: the solve and its result], "total_time_s"}.
// Non-finite numbers are null.
std::string SimulateSummaryJson(const SimulateRun& run, const Scene& scene,
                                const std::vector<SimulateObjectResult>& objects);

// How femreg calibrate was run: the scene file and the observed clouds as given, and each
// cloud's points after the preprocess.
struct CalibrationRun {
  std::string scene;
  std::vector<std::string> observed;
  std::vector<int> points;  // one per observed cloud
};

// calibration.json of femreg calibrate: {"femreg_version", "scene", "observed", "object",
// "parameter", "region", "options" (every field of the calibration table), "termination",
// "message", "usable", "value", "initial_value", "interval", the misfit, "uncertainty",
// "loss", the counts and times, "samples": [every forward solve]}.
std::string CalibrationJson(const CalibrationRun& run, const Scene& scene, const CalibrationOptions& options,
                            const CalibrationSummary& summary);

}  // namespace femreg

#endif  // FEMREG_FORWARD_RESULTS_H_
