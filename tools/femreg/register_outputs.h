// femreg register's output files: the command's arguments, a frame's row, stats.csv (its header,
// rows and the appending file), the files rewritten at most once a second, and summary.json.
#ifndef FEMREG_TOOLS_REGISTER_OUTPUTS_H_
#define FEMREG_TOOLS_REGISTER_OUTPUTS_H_

#include <cerrno>
#include <chrono>
#include <cstdio>
#include <cstring>
#include <functional>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "femreg/eval.h"
#include "femreg/registration.h"
#include "femreg/scene.h"
#include "femreg/status.h"
#include "femreg/tracker.h"

namespace femreg {
namespace cli {
namespace register_outputs {

struct RegisterArgs {
  std::string scene;
  std::string frames;
  std::string out;
  std::string ground_truth;
  std::string material;  // a scene whose objects' materials replace the scene's
  bool force = false;
  bool surface_ply = false;  // --surface-ply: the embedded surfaces as PLY too
  int max_frames = 0;
  std::string report = "brief";
  bool progress = true;
  int threads = 0;
  bool no_collision = false;
  std::vector<std::string> sets;  // --set key.path=value
  bool skip_bad_frames = false;
  double depth_scale = 0.001;  // m per unit of 16-bit depth frames (the one used, once resolved)
  bool depth_scale_given = false;  // --depth-scale was given (else a TUM sequence's 5000 per metre)
  std::string mask_dir;        // masks of depth frames; overrides preprocess.mask_dir
  std::string intrinsics;      // an Open3D intrinsics JSON; overrides the scene camera's intrinsics
  std::string tum_list;        // resolved: the TUM RGB-D list the frames come from, if any
};

struct FrameRow {
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

double Median(std::vector<double> v);

// stats.csv's header line.
extern const char kStatsHeader[];
// Row i of stats.csv.
std::string StatsRow(size_t i, const FrameRow& row);

// stats.csv, a row appended (and flushed) per frame: every finished frame's row is on disk.
class StatsFile {
 public:
  Status Open(const std::string& path) {
    path_ = path;
    file_.reset(std::fopen(path.c_str(), "wb"));
    if (!file_) return Status::Error(path + ": cannot create file: " + std::strerror(errno));
    return Append(kStatsHeader);
  }
  Status Append(const std::string& text) {
    if (std::fwrite(text.data(), 1, text.size(), file_.get()) != text.size() || std::fflush(file_.get()) != 0) {
      return Status::Error(path_ + ": write failed: " + std::strerror(errno));
    }
    return Status::Ok();
  }

 private:
  std::string path_;
  std::unique_ptr<std::FILE, int (*)(std::FILE*)> file_{nullptr, &std::fclose};
};

// Files that are rewritten whole (the .pvd collections, summary.json): after every frame that cost
// O(frames) per frame, O(frames^2) over a run
// (docs/notes/2026-11-28-figures-from-code-comments.md). So at most once a second, and by Flush at
// the end; the destructor writes what is pending on any other way out (an error return), so the
// files still cover the frames done.
class ThrottledWrite {
 public:
  explicit ThrottledWrite(std::function<Status()> write) : write_(std::move(write)) {}
  ~ThrottledWrite() {
    if (pending_) write_();
  }
  ThrottledWrite(const ThrottledWrite&) = delete;
  ThrottledWrite& operator=(const ThrottledWrite&) = delete;
  // After a frame: writes if the last write is a second old (the first frame's at once).
  Status Update() {
    pending_ = true;
    if (written_ && std::chrono::steady_clock::now() - last_ < std::chrono::seconds(1)) return Status::Ok();
    return Flush();
  }
  Status Flush() {
    pending_ = false;
    written_ = true;
    last_ = std::chrono::steady_clock::now();
    return write_();
  }

 private:
  std::function<Status()> write_;
  bool pending_ = false, written_ = false;
  std::chrono::steady_clock::time_point last_;
};

struct Totals {
  int frames = 0, usable = 0;
  double median_ms = 0, mean_ms = 0, fps = 0;
  bool have_errors = false;
  double err_mean = 0, err_max = 0, seen_mean = 0, seen_max = 0, hidden_mean = 0, hidden_max = 0;
};

Totals ComputeTotals(const std::vector<FrameRow>& rows);

// summary.json: the run's totals (fields read by scripts and tests), and what it ran: the
// version, the back end, the resolved options, the --set overrides and the input files.
std::string SummaryJson(const RegisterArgs& args, const Scene& scene, const Tracker& tracker,
                        const std::vector<FrameRow>& rows, const std::vector<std::string>& files,
                        const std::vector<std::string>& truth_files, bool interrupted);

}  // namespace register_outputs
}  // namespace cli
}  // namespace femreg

#endif  // FEMREG_TOOLS_REGISTER_OUTPUTS_H_
