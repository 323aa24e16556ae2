// The files a registration run writes about its frames: stats.csv (a row per frame) and
// summary.json (the run's totals and what it ran), as `femreg register` writes them, for a
// program that tracks a sequence with the Tracker itself and wants the same files.
#ifndef FEMREG_RESULTS_H_
#define FEMREG_RESULTS_H_

#include <cstddef>
#include <cstdio>
#include <memory>
#include <string>
#include <vector>

#include "femreg/ground_truth.h"
#include "femreg/registration.h"
#include "femreg/scene.h"
#include "femreg/status.h"
#include "femreg/tracker.h"

namespace femreg {

// One registered frame, as stats.csv and summary.json record it.
struct FrameRecord {
  std::string file;
  FrameSummary summary;
  bool have_errors = false;
  VertexErrors errors;
  std::string read_error;
  int pieces = 1;                  // connected pieces of all objects (fracture)
  std::vector<ErrorStats> piece_errors;  // per piece, with ground truth and fracture on
  std::vector<ErrorStats> piece_seen, piece_hidden;  // the same, seen / hidden vertices
  int break_frame = -1;  // the first frame in more pieces than the run started with (-1: none yet)
  // The embedded surfaces' vertices (objects[i].surface, in scene order) against
  // GROUND_TRUTH/surface/NAME.csv, when both are there.
  bool have_surface_errors = false;
  VertexErrors surface_errors;
};

// stats.csv's header line.
extern const char kStatsHeader[];
// Row i of stats.csv.
std::string StatsRow(size_t i, const FrameRecord& row);

// stats.csv, a row appended (and flushed) per frame: every finished frame's row is on disk.
class StatsFile {
 public:
  // Creates the file and writes the header.
  Status Open(const std::string& path);
  Status Append(const std::string& text);

 private:
  std::string path_;
  std::unique_ptr<std::FILE, int (*)(std::FILE*)> file_{nullptr, &std::fclose};
};

// The run's totals over its frames (summary.json's, and the command line's closing lines).
struct RunTotals {
  int frames = 0, usable = 0;
  double median_ms = 0, mean_ms = 0, fps = 0;
  bool have_errors = false;
  double err_mean = 0, err_max = 0, seen_mean = 0, seen_max = 0, hidden_mean = 0, hidden_max = 0;
};

RunTotals ComputeRunTotals(const std::vector<FrameRecord>& rows);

// What summary.json records of how the run was started.
struct RunInputs {
  std::string scene;                    // the scene file, as given
  std::string frames_source;            // the frames' folder, pattern or list, as given
  std::vector<std::string> frame_files;  // the frames, in order
  std::vector<std::string> truth_files;  // the ground truth's files (empty: none)
  std::vector<std::string> overrides;   // --set key.path=value
  std::string tum_list;                 // the TUM RGB-D list the frames come from, if any
  bool interrupted = false;             // the run ended before its last frame
  std::string interrupted_by;           // by what ("SIGINT", "SIGTERM")
  // The command line's flags (summary.json's command_line).
  bool no_collision = false;
  int max_frames = 0;
  int threads = 0;
  double depth_scale = 0.001;  // m per unit of 16-bit depth frames, as used
  std::string mask_dir;
  std::string intrinsics;
};

// summary.json: the run's totals (fields read by scripts and tests), and what it ran: the
// version, the back end, the resolved options, the overrides and the input files.
std::string SummaryJson(const RunInputs& run, const Scene& scene, const Tracker& tracker,
                        const std::vector<FrameRecord>& rows);

// The names in a summary.json's "objects" (scene order), as SummaryJson writes them, for a
// program that reads a run's folder (femreg eval). An error names the file: it cannot be
// read, is not JSON, or has no "objects" list of objects with a "name".
Status ReadSummaryObjectNames(const std::string& path, std::vector<std::string>* names);

// Whether the run behind a summary.json estimated the external forces
// (registration.forces.estimate): 1 or 0, -1 when the summary does not say (an older one).
// An error names the file: it cannot be read or is not JSON.
Status ReadSummaryForcesEstimated(const std::string& path, int* estimated);

}  // namespace femreg

#endif  // FEMREG_RESULTS_H_
