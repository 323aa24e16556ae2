// femreg/experiment.h - run registration settings over a dataset with ground truth and
// measure what accuracy costs in time (femreg bench, femreg compare).
#ifndef FEMREG_EXPERIMENT_H_
#define FEMREG_EXPERIMENT_H_

#include <functional>
#include <string>
#include <utility>
#include <vector>

#include "femreg/scene.h"
#include "femreg/status.h"

namespace femreg {

// A folder with scene.yaml (the tracking scene), clouds/ and ground_truth/ (one CSV per
// frame with a row per tracked vertex: see ground_truth.h).
struct Dataset {
  std::string dir;
  std::string name;
  Scene scene;
  std::vector<std::string> clouds;
  std::vector<std::string> truth;
};
Status LoadDataset(const std::string& dir, Dataset* dataset, int max_frames = 0);

// One setting: a name, the parameters it sets (for the CSV), and how it changes the scene.
struct Setting {
  std::string name;
  std::vector<std::pair<std::string, std::string>> parameters;
  std::function<void(Scene*)> apply;
  // Multiplies the cell counts of generated meshes (tracked mesh resolution); errors are
  // still measured at the dataset's own vertices, interpolated in the tracked mesh.
  double resolution = 1.0;
};

struct Outcome {
  std::string setting;
  int frames = 0, usable = 0;
  int vertices = 0, elements = 0;  // the tracked mesh(es)
  double median_ms = 0.0, mean_ms = 0.0;
  double median_solve_ms = 0.0, median_correspondences_ms = 0.0;
  double seen_mean = 0.0, hidden_mean = 0.0, all_mean = 0.0, all_max = 0.0;  // m
  double seen_rms = 0.0, hidden_rms = 0.0;                                   // m
  std::string error;  // set when the setting could not run
};

// Runs one setting over the dataset (in this process, timing every frame).
// `progress(done, total)` may be null.
Outcome RunSetting(const Dataset& dataset, const Setting& setting,
                   const std::function<void(int, int)>& progress = nullptr);

// The settings `femreg bench` sweeps by default: the scene's own settings, then one
// parameter at a time (mesh resolution, outer and inner iterations, cloud subsampling,
// linear solver, elastic weight, Young's modulus).
std::vector<Setting> DefaultBenchSweep(const Scene& scene);
// The regularizers `femreg compare` puts side by side: data only, temporal only,
// mass-spring, small-strain linear FEM, corotational FEM at several E and nu.
std::vector<Setting> DefaultComparison(const Scene& scene);

// Indices of the outcomes on the Pareto front of (median ms per frame, mean error):
// no other outcome is both faster and more accurate.
std::vector<int> ParetoFront(const std::vector<Outcome>& outcomes);

// CSV of the outcomes (one row per setting, its parameters as columns).
std::string OutcomesCsv(const std::vector<Setting>& settings, const std::vector<Outcome>& outcomes);

}  // namespace femreg

#endif  // FEMREG_EXPERIMENT_H_
