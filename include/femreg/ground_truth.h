// femreg/ground_truth.h - per-frame ground truth at the tracked mesh's vertices and the
// vertex error against it.
#ifndef FEMREG_GROUND_TRUTH_H_
#define FEMREG_GROUND_TRUTH_H_

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

}  // namespace femreg

#endif  // FEMREG_GROUND_TRUTH_H_
