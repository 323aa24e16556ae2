// femreg eval's forces: the estimated resultant external force (and the obstacles' push)
// of a register result's stats.csv against a dataset's forces.csv, frame by frame.
#ifndef FEMREG_TOOLS_EVAL_FORCES_H_
#define FEMREG_TOOLS_EVAL_FORCES_H_

#include <cstddef>
#include <map>
#include <string>
#include <vector>

#include "femreg/ground_truth.h"
#include "femreg/status.h"

namespace femreg {
namespace cli {

// The estimated resultant force against the true one, frame by frame.
struct ForceReport {
  bool compared = false;          // both files there, and frames in common
  std::string note;               // why not, when one file is there without the other
  std::vector<ForceError> errors;
  std::map<int, size_t> of_frame;  // frame -> its entry in errors
  std::string truth_path;
  int estimated = -1;  // summary.json's forces.estimate: 1, 0, or -1 (not said)
  bool contact = false;  // some frame has the obstacles' push in both files
  // The frames stats.csv says estimated the forces (forces_estimated 1): with estimate false,
  // those forces.when_occluded switched.
  std::vector<int> estimated_frames;

  // eval.csv's force cells of frame f: empty when that frame has no estimate.
  std::string Cells(int f) const;
  // The totals row: medians over the frames.
  std::string MedianCells() const;
  // The table, the medians and what the columns hold.
  void Print() const;
};

// Reads RESULT/stats.csv's force columns and DATASET/forces.csv; compares the first
// `num_frames` frames. Without either (or without the columns), *report says so and nothing
// is compared; a forces.csv that cannot be read is an error.
Status CompareForceFiles(const std::string& result, const std::string& truth_dir, size_t num_frames,
                         ForceReport* report);

}  // namespace cli
}  // namespace femreg

#endif  // FEMREG_TOOLS_EVAL_FORCES_H_
