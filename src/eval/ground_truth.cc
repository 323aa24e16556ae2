#include "femreg/ground_truth.h"

#include <algorithm>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <sstream>
#include <string_view>
#include <system_error>

#include "femreg/io.h"

namespace femreg {

namespace {
// Parses one field of a row, "  -1.5e-3 " (blanks around it, a leading '+' allowed), up to
// the next comma or the end; *p moves past the comma. False if it is not a number.
bool ParseField(const char** p, const char* end, double* value) {
  const char* q = *p;
  while (q < end && (*q == ' ' || *q == '\t')) ++q;
  if (q < end && *q == '+') ++q;
  const std::from_chars_result r = std::from_chars(q, end, *value);
  if (r.ec != std::errc() || r.ptr == q) return false;
  q = r.ptr;
  while (q < end && (*q == ' ' || *q == '\t' || *q == '\r')) ++q;
  if (q < end && *q != ',') return false;
  *p = q < end ? q + 1 : q;
  return true;
}
}  // namespace

// The whole file at once and std::from_chars per field: an istringstream per line was slow for a
// file read once per frame by `register`, `bench` and the sweeps
// (docs/notes/2026-11-28-figures-from-code-comments.md).
Status ReadGroundTruthFrame(const std::string& path, GroundTruthFrame* frame) {
  std::string text;
  {
    std::FILE* file = std::fopen(path.c_str(), "rb");
    if (file == nullptr) return Status::Error(path + ": cannot open");
    char buffer[1 << 16];
    size_t got = 0;
    while ((got = std::fread(buffer, 1, sizeof(buffer), file)) > 0) text.append(buffer, got);
    const bool failed = std::ferror(file) != 0;
    std::fclose(file);
    if (failed) return Status::Error(path + ": read failed");
  }
  std::vector<double> xyz;
  frame->visible.clear();
  static const char* const kNames[4] = {"x", "y", "z", "visible"};
  int line_no = 0;
  for (size_t begin = 0; begin < text.size();) {
    size_t stop = text.find('\n', begin);
    if (stop == std::string::npos) stop = text.size();
    const char* p = text.data() + begin;
    const char* end = text.data() + stop;
    begin = stop + 1;
    ++line_no;
    if (end > p && end[-1] == '\r') --end;
    if (p == end || *p == '#') continue;
    if (line_no == 1 && std::string_view(p, static_cast<size_t>(end - p)).rfind("x,", 0) == 0) continue;  // header
    double v[4];
    for (int k = 0; k < 4; ++k) {
      if (p == end && k > 0 && end[-1] != ',') {
        return Status::Error(path + ":" + std::to_string(line_no) + ": expected 'x,y,z,visible', the row ends after " +
                             kNames[k - 1]);
      }
      if (!ParseField(&p, end, &v[k])) {
        return Status::Error(path + ":" + std::to_string(line_no) + ": expected 'x,y,z,visible', " + kNames[k] +
                             " is not a number");
      }
    }
    if (p != end || end[-1] == ',') {
      return Status::Error(path + ":" + std::to_string(line_no) + ": expected 'x,y,z,visible', the row has more fields");
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
