// Helpers shared by the subcommands: JSON strings, output folders, a progress bar, Ctrl-C.
#ifndef FEMREG_TOOLS_CLI_UTIL_H_
#define FEMREG_TOOLS_CLI_UTIL_H_

#include <CLI/CLI.hpp>
#include <chrono>
#include <string>
#include <utility>
#include <vector>

#include "femreg/ground_truth.h"
#include "femreg/point_cloud.h"
#include "femreg/scene.h"
#include "femreg/status.h"

namespace femreg {
namespace cli {

// A JSON string literal with escapes.
std::string JsonString(const std::string& s);
// A JSON number (null for NaN or infinity).
std::string JsonNumber(double v);

// `text` for a message, at most `max_chars` characters of it: longer text is cut and
// "... (N bytes)" added, so that a 4 MB bad token is not echoed whole.
std::string CapForMessage(const std::string& text, size_t max_chars = 80);

// Makes `dir` (and parents). A non-empty existing folder is refused unless `force`; with
// `force`, its subfolders named in `owned` (those only the command writes, e.g. register's
// frames/) are removed first, so that a shorter run leaves none of a longer one's frames,
// unless one of the command's `inputs` lies in one of them: then nothing is removed and the
// run is refused.
Status PrepareOutputDir(const std::string& dir, bool force, const std::vector<std::string>& owned = {},
                        const std::vector<std::string>& inputs = {});

// A one-line progress bar on stderr when it is a terminal; a line every 10% otherwise.
class ProgressBar {
 public:
  ProgressBar(const std::string& label, int total, bool enabled = true);
  void Update(int done, const std::string& note = "");
  void Finish();
  void set_total(int total) { total_ = total > 0 ? total : 1; }

 private:
  std::string label_;
  int total_;
  bool enabled_, tty_;
  int last_decile_ = -1;
  std::chrono::steady_clock::time_point start_;
};

// The bar of a dataset generator that reports (done, total) through a plain function pointer:
// StartGeneratorProgress before the generator runs (so that the rate counts the first frame's
// time), GeneratorProgress as its callback, StopGeneratorProgress after it, also on failure.
void StartGeneratorProgress(const std::string& label);
void GeneratorProgress(int done, int total);
void StopGeneratorProgress();

// Per frame of a tracked fracture sequence: node splits, connected pieces and the error of
// each piece against the ground truth (empty without one).
struct FractureFrame {
  int splits = 0;
  int pieces = 1;
  std::vector<ErrorStats> piece_errors;
};
// Prints when the tracker first split and when it was first in pieces, against the
// ground truth's events.csv in truth_dir when there is one, and each piece's mean and max
// error over the frames after the break.
// With counts_vertices, `splits` counts the vertices the splits added (all a result file
// tells), not the node splits.
void PrintFractureReport(const std::vector<FractureFrame>& frames, const std::string& truth_dir,
                         bool counts_vertices = false);

// --set key.path=value (repeatable) on a subcommand: scene overrides for LoadSceneWithSets.
void AddSetOption(CLI::App* cmd, std::vector<std::string>* sets);
// LoadScene with the --set overrides applied to the YAML before the scene is parsed
// (femreg/experiment.h: LoadSceneWithOverrides); errors name the file, line and key, and
// the --set when the bad value came from one.
Status LoadSceneWithSets(const std::string& path, const std::vector<std::string>& sets, Scene* scene);

// The Python interpreter for the plotting scripts: $FEMREG_PYTHON when set, else python3
// (then python) found on PATH, unless that one lacks matplotlib and /usr/bin/python3 has
// it; "" when there is none.
std::string FindPython();
// Runs argv[0] (searched on PATH when it has no '/') with the arguments, no shell between;
// returns its exit code, or -1 when it could not start.
int RunProgram(const std::vector<std::string>& argv);

// Ctrl-C: the first SIGINT sets a flag that long loops poll; a second one, a second or more
// later, exits at once (one sooner is the same request: timeout signals the command and its
// process group). SIGTERM (timeout, schedulers, docker stop) is handled the same way.
void InstallInterruptHandler();
bool Interrupted();
int InterruptExitCode();      // 128 + the signal (130 for SIGINT, 143 for SIGTERM)
const char* InterruptName();  // "SIGINT" or "SIGTERM"

}  // namespace cli
}  // namespace femreg

#endif  // FEMREG_TOOLS_CLI_UTIL_H_
