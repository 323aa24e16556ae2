#include "femreg/ground_truth.h"

#include <algorithm>
#include <cmath>
#include <fstream>
#include <sstream>

#include "femreg/io.h"

namespace femreg {

Status ReadGroundTruthFrame(const std::string& path, GroundTruthFrame* frame) {
  std::ifstream in(path);
  if (!in) return Status::Error(path + ": cannot open");
  std::string line;
  int line_no = 0;
  std::vector<double> xyz;
  frame->visible.clear();
  while (std::getline(in, line)) {
    ++line_no;
    if (line.empty() || line[0] == '#') continue;
    if (line_no == 1 && line.rfind("x,", 0) == 0) continue;  // header
    std::istringstream ls(line);
    double v[4];
    char comma;
    if (!(ls >> v[0] >> comma >> v[1] >> comma >> v[2] >> comma >> v[3])) {
      return Status::Error(path + ":" + std::to_string(line_no) + ": expected 'x,y,z,visible'");
    }
    if (!(std::isfinite(v[0]) && std::isfinite(v[1]) && std::isfinite(v[2]))) {
      return Status::Error(path + ":" + std::to_string(line_no) + ": non-finite coordinate");
    }
    xyz.insert(xyz.end(), v, v + 3);
    frame->visible.push_back(v[3] != 0.0 ? 1 : 0);
  }
  frame->positions = Eigen::Map<Vertices>(xyz.data(), static_cast<Eigen::Index>(xyz.size() / 3), 3);
  if (frame->positions.rows() == 0) return Status::Error(path + ": no vertex rows");
  return Status::Ok();
}

Status WriteGroundTruthFrame(const std::string& path, const GroundTruthFrame& frame) {
  std::ostringstream os;
  os << "x,y,z,visible\n";
  char buf[128];
  for (int i = 0; i < frame.positions.rows(); ++i) {
    // Fixed 0.1 nm resolution: the last bits of a simulation (a coordinate that should be 0
    // comes out as 1e-21 one way and -1e-21 another) do not reach the file, so a dataset
    // regenerates to the same bytes.
    auto fixed = [](double v) {
      const double r = std::round(v * 1e10) / 1e10;
      return r == 0.0 ? 0.0 : r;  // no negative zero
    };
    std::snprintf(buf, sizeof(buf), "%.10f,%.10f,%.10f,%d\n", fixed(frame.positions(i, 0)),
                  fixed(frame.positions(i, 1)), fixed(frame.positions(i, 2)),
                  i < static_cast<int>(frame.visible.size()) ? frame.visible[i] : 0);
    os << buf;
  }
  return WriteFileAtomically(path, os.str());
}

ErrorStats ComputeErrorStats(std::vector<double> errors) {
  ErrorStats s;
  s.count = static_cast<int>(errors.size());
  if (errors.empty()) return s;
  std::sort(errors.begin(), errors.end());
  double sum = 0.0, sum2 = 0.0;
  for (double e : errors) {
    sum += e;
    sum2 += e * e;
  }
  s.mean = sum / s.count;
  s.rms = std::sqrt(sum2 / s.count);
  s.max = errors.back();
  const size_t k = static_cast<size_t>(std::ceil(0.95 * s.count)) - 1;
  s.p95 = errors[std::min(k, errors.size() - 1)];
  return s;
}

VertexErrors ComputeVertexErrors(const Vertices& positions, const GroundTruthFrame& truth) {
  std::vector<double> all, seen, hidden;
  const int n = static_cast<int>(std::min(positions.rows(), truth.positions.rows()));
  for (int i = 0; i < n; ++i) {
    const double e = (positions.row(i) - truth.positions.row(i)).norm();
    all.push_back(e);
    if (i < static_cast<int>(truth.visible.size()) && truth.visible[i]) {
      seen.push_back(e);
    } else {
      hidden.push_back(e);
    }
  }
  VertexErrors out;
  out.all = ComputeErrorStats(all);
  out.seen = ComputeErrorStats(seen);
  out.hidden = ComputeErrorStats(hidden);
  return out;
}

}  // namespace femreg
