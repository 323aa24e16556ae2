// femreg register's output files: the command's arguments, the files rewritten at most once a
// second, summary.json's record of the run, and each frame's meshes, cloud and surfaces (stats.csv
// and summary.json themselves are written by the library: femreg/results.h).
#ifndef FEMREG_TOOLS_REGISTER_OUTPUTS_H_
#define FEMREG_TOOLS_REGISTER_OUTPUTS_H_

#include <chrono>
#include <functional>
#include <string>
#include <utility>
#include <vector>

#include "femreg/io.h"
#include "femreg/point_cloud.h"
#include "femreg/registration.h"
#include "femreg/results.h"
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

// summary.json's record of the run: the command's arguments (as resolved), its frames and
// ground truth, and whether it was interrupted (and by what).
RunInputs MakeRunInputs(const RegisterArgs& args, const std::vector<std::string>& files,
                        const std::vector<std::string>& truth_files, bool interrupted);

// Frame f's files in args.out/frames: the cloud it was fitted to (`used`), each object's mesh
// (VTU: displacement, residual, observed; fracture_measure and original_vertex with fracture;
// error and error_vector where vertex_error has rows; force) and each embedded surface (VTP,
// error where surface_error has rows; PLY too with --surface-ply), each added to its
// collection.
Status WriteFrameFiles(const RegisterArgs& args, size_t f, const Scene& scene, const Tracker& tracker,
                       const PointCloud& used, const Vertices& vertex_error, const Vertices& surface_error,
                       std::vector<PvdEntry>* cloud_pvd, std::vector<std::vector<PvdEntry>>* pvd,
                       std::vector<std::vector<PvdEntry>>* surface_pvd);

}  // namespace register_outputs
}  // namespace cli
}  // namespace femreg

#endif  // FEMREG_TOOLS_REGISTER_OUTPUTS_H_
