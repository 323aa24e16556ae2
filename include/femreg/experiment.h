// femreg/experiment.h - run registration settings over a dataset and measure what accuracy
// costs in time (femreg bench, femreg compare); scene overrides (--set key.path=value); a
// sweep run as one job per setting and merged again.
#ifndef FEMREG_EXPERIMENT_H_
#define FEMREG_EXPERIMENT_H_

#include <functional>
#include <string>
#include <utility>
#include <vector>

#include "femreg/scene.h"
#include "femreg/status.h"

namespace femreg {

// One `--set key.path=value`: a scene key and a YAML value that replaces (or adds) it before
// the scene is parsed, so that it is checked like the file's own keys and errors name it.
// Keys are written as the scene parser's messages name them: map keys joined by '.', list
// entries by [i] ("objects[0].material.youngs_modulus", "registration.solver.backend").
// Missing maps on the way are created; list entries must exist.
struct SceneOverride {
  std::string key;
  std::string value;  // YAML: "fast", "3", "[0, 0, 1]", "{fracture: true}"
  std::string Text() const { return key + "=" + value; }
};
// Splits "key.path=value" at the first '='; errors name the text.
Status ParseSceneOverride(const std::string& text, SceneOverride* override_out);
// LoadScene (scene.h) with the overrides applied, in order, to the YAML document before the
// scene parser runs. An error in an overridden value names its key and the --set that gave
// it; a key that does not exist in the scene format is refused by the parser like a typo in
// the file ("did you mean ...").
Status LoadSceneWithOverrides(const std::string& path, const std::vector<SceneOverride>& overrides,
                              Scene* scene);

// A folder with scene.yaml (the tracking scene), clouds/ and, optionally, ground_truth/ (one
// CSV per frame with a row per tracked vertex: see ground_truth.h). A recording has no
// ground truth: then `truth` is empty and only time, residuals and convergence are measured.
struct Dataset {
  std::string dir;
  std::string name;
  Scene scene;
  std::vector<std::string> clouds;
  std::vector<std::string> truth;  // empty, or one per cloud
  bool has_truth() const { return !truth.empty(); }
};
// `overrides` apply to scene.yaml as LoadSceneWithOverrides does. A ground_truth/ folder
// with fewer frames than clouds is an error (a partial truth would bias the errors).
Status LoadDataset(const std::string& dir, Dataset* dataset, int max_frames = 0,
                   const std::vector<SceneOverride>& overrides = {});

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
  int setting_index = -1;  // its place in the full sweep (the order a merge restores)
  bool has_truth = false;  // false: the error fields below are not measured (CSV: empty)
  int frames = 0, usable = 0;
  int converged = 0;                   // frames that stopped on the energy tolerance
  double mean_outer_iterations = 0.0;  // per frame
  double median_rms_residual = 0.0;    // m, median over frames of the RMS data residual
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

// The settings of `sweep` picked by `selectors`, each an exact setting name or its 0-based
// index in the sweep (as `femreg bench --list-settings` prints them), in the sweep's order
// and without repeats; *indices receives their places in the sweep. An unknown name is an
// error that lists the sweep's names.
Status SelectSettings(const std::vector<Setting>& sweep, const std::vector<std::string>& selectors,
                      std::vector<Setting>* selected, std::vector<int>* indices);

// Indices of the outcomes on the Pareto front of (median ms per frame, mean error; the
// median RMS residual when an outcome has no ground truth): no other outcome is both faster
// and more accurate.
std::vector<int> ParetoFront(const std::vector<Outcome>& outcomes);

// CSV of the outcomes (one row per setting, its parameters as columns). Error columns are
// empty for outcomes without ground truth.
std::string OutcomesCsv(const std::vector<Setting>& settings, const std::vector<Outcome>& outcomes);

// Reads a CSV written by OutcomesCsv back (the setting's parameters, name and index, and the
// outcome); errors name the file and the line. For merging the shards of a sweep.
Status ReadOutcomesCsv(const std::string& path, std::vector<Setting>* settings,
                       std::vector<Outcome>* outcomes);
// Merges shards (settings and outcomes read from several CSVs of the same dataset) into one
// table in sweep order (by setting_index). The same setting in two shards is an error, and
// so are shards that ran a different number of frames or differ in having ground truth.
Status MergeOutcomes(const std::vector<std::vector<Setting>>& shard_settings,
                     const std::vector<std::vector<Outcome>>& shard_outcomes,
                     std::vector<Setting>* settings, std::vector<Outcome>* outcomes);

}  // namespace femreg

#endif  // FEMREG_EXPERIMENT_H_
