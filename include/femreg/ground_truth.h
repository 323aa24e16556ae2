// femreg/ground_truth.h - per-frame ground truth at the tracked mesh's vertices and the
// vertex error against it; the true external force per frame and an estimate's error.
#ifndef FEMREG_GROUND_TRUTH_H_
#define FEMREG_GROUND_TRUTH_H_

#include <Eigen/Core>
#include <limits>
#include <string>
#include <vector>

#include "femreg/mesh.h"
#include "femreg/status.h"

namespace femreg {

// One frame of ground truth: the true position of every tracked vertex (all objects in
// scene order), and whether the camera saw it in that frame.
struct GroundTruthFrame {
  Vertices positions;          // #V by 3 (m)
  std::vector<char> visible;   // #V
};

// CSV with the header "x,y,z,visible" and one row per vertex.
Status ReadGroundTruthFrame(const std::string& path, GroundTruthFrame* frame);
Status WriteGroundTruthFrame(const std::string& path, const GroundTruthFrame& frame);

// Vertex error statistics (m) over all, visible and hidden vertices.
struct ErrorStats {
  int count = 0;
  double mean = 0.0, rms = 0.0, p95 = 0.0, max = 0.0;
};
struct VertexErrors {
  ErrorStats all, seen, hidden;
};
// positions and truth must have the same number of rows.
VertexErrors ComputeVertexErrors(const Vertices& positions, const GroundTruthFrame& truth);
ErrorStats ComputeErrorStats(std::vector<double> errors);

// The resultant of the external forces on the tracked body in one frame (N) and their torque
// about its centroid (N m): gravity, the scene's loads and the clamp and anchor reactions left
// out, contacts with obstacles counted. A dataset's forces.csv holds the true ones, a
// `femreg register` result's stats.csv the estimated ones, in the columns of kForceColumns.
struct ForceFrame {
  int frame = 0;
  Eigen::Vector3d force = Eigen::Vector3d::Zero();
  Eigen::Vector3d torque = Eigen::Vector3d::Zero();
  // The part of `force` the scene's obstacles push with (a table's, a tool's given as an
  // obstacle), in the columns of kContactForceColumns where the file has them.
  bool has_contact = false;
  Eigen::Vector3d contact = Eigen::Vector3d::Zero();
  // stats.csv's forces_estimated: 1 the frame estimated the forces, 0 it did not (its data
  // term's pull), -1 not said (no such column: forces.csv, an older stats.csv).
  int estimated = -1;
};
extern const char* const kForceColumns[6];         // force_x_N, ..., torque_z_Nm
extern const char* const kContactForceColumns[3];  // contact_force_x_N, ..., contact_force_z_N

// forces.csv: the header "frame,force_x_N,...,torque_z_Nm" and a row per frame.
Status WriteForces(const std::string& path, const std::vector<ForceFrame>& frames);
// The columns frame and kForceColumns, found by name in the header of a CSV (forces.csv, or
// stats.csv among its other columns and quoted text): a ForceFrame per row whose six cells
// hold numbers; a row whose force cells are all empty (a frame without an estimate) is left
// out. *has_columns tells whether the header has all seven; without them *frames is empty
// and the status OK. A cell that is neither a number nor empty is an error naming it. Where
// the header also has kContactForceColumns, a row whose three cells hold numbers has
// has_contact set (all three empty: not set; some of the three, in the header or a row, is
// an error naming the missing one).
Status ReadForces(const std::string& path, std::vector<ForceFrame>* frames, bool* has_columns);

// An estimate against the truth in one frame.
struct ForceError {
  int frame = 0;
  double true_force = 0.0;    // |true resultant| (N)
  double error = 0.0;         // |estimated - true| (N)
  double relative = 0.0;      // error / |true|; NaN when the true force is 0
  double torque_error = 0.0;  // |estimated - true torque| (N m)
  // |estimated - true| of the obstacles' push, and |true| (N); NaN unless both frames have it.
  double contact_error = std::numeric_limits<double>::quiet_NaN();
  double true_contact = std::numeric_limits<double>::quiet_NaN();
};
// For every frame of `truth` that `estimated` has too (matched by frame number), in the
// order of `truth`.
std::vector<ForceError> CompareForces(const std::vector<ForceFrame>& estimated,
                                      const std::vector<ForceFrame>& truth);
// Medians over the frames (of an even count, the mean of the middle two); relative leaves
// out the frames without one, contact_error those without the obstacles' push. NaN where no
// frame is left.
struct ForceErrorMedians {
  double error = 0.0, relative = 0.0, torque_error = 0.0;
  double contact_error = 0.0, true_contact = 0.0;
};
ForceErrorMedians MedianForceErrors(const std::vector<ForceError>& errors);

}  // namespace femreg

#endif  // FEMREG_GROUND_TRUTH_H_
