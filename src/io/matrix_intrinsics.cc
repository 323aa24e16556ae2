// A pinhole camera matrix as text, as numpy.savetxt writes it: the 3x3 K, or K padded to a
// 4x4 homogeneous matrix (DeepDeform's intrinsics.txt), row by row.
#include <cctype>
#include <cerrno>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "femreg/camera_io.h"
#include "io/io_internal.h"

namespace femreg {
using internal::ExactNumber;

bool LooksLikeJsonFile(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  // A UTF-8 byte order mark (some Windows editors write one) is not the content.
  char bom[3] = {0, 0, 0};
  in.read(bom, 3);
  if (!(in.gcount() == 3 && bom[0] == '\xEF' && bom[1] == '\xBB' && bom[2] == '\xBF')) {
    in.clear();
    in.seekg(0);
  }
  char c = 0;
  while (in.get(c)) {
    if (!std::isspace(static_cast<unsigned char>(c))) return c == '{';
  }
  return false;
}

Status ReadMatrixIntrinsics(const std::string& path, PinholeIntrinsics* intrinsics) {
  using internal::FileError;
  std::string text;
  if (Status read = internal::ReadSmallFile(path, internal::kMaxIntrinsicsBytes, "an intrinsics file", &text); !read.ok()) return read;
  std::istringstream in(text);
  // The rows that hold numbers, each with its line.
  std::vector<std::vector<double>> rows;
  std::vector<int> row_lines;
  std::string line;
  for (int number = 1; std::getline(in, line); ++number) {
    const size_t hash = line.find('#');
    if (hash != std::string::npos) line.resize(hash);
    std::istringstream fields(line);
    std::vector<double> row;
    for (std::string f; fields >> f;) {
      char* end = nullptr;
      errno = 0;
      const double v = std::strtod(f.c_str(), &end);
      if (end == f.c_str() || *end != '\0' || errno == ERANGE || !std::isfinite(v)) {
        return FileError(path, number, "'" + (f.size() > 40 ? f.substr(0, 40) + "..." : f) +
                                           "' is not a finite number (a camera matrix as text: rows of "
                                           "numbers, as numpy.savetxt writes it)");
      }
      row.push_back(v);
    }
    if (row.empty()) continue;
    rows.push_back(row);
    row_lines.push_back(number);
  }
  const size_t n = rows.size();
  if (n != 3 && n != 4) {
    return FileError(path, 0, "has " + std::to_string(n) + " rows of numbers; a camera matrix as text has 3 "
                              "(K) or 4 (K in a 4x4 homogeneous matrix)");
  }
  for (size_t i = 0; i < n; ++i) {
    if (rows[i].size() != n) {
      return FileError(path, row_lines[i], "row " + std::to_string(i) + " has " + std::to_string(rows[i].size()) +
                                               " numbers; a " + std::to_string(n) + "x" + std::to_string(n) +
                                               " matrix has " + std::to_string(n) + " in every row");
    }
  }
  // K row-major: [0][0] fx, [0][1] the skew, [0][2] cx, [1][1] fy, [1][2] cy, [2][2] 1; the
  // padding of a 4x4 is zero but for [3][3] = 1.
  auto entry = [&](size_t i, size_t j) -> std::string {
    return "[" + std::to_string(i) + "][" + std::to_string(j) + "]";
  };
  for (size_t i : {0, 1}) {
    if (!(rows[i][i] > 0)) {
      return FileError(path, row_lines[i], entry(i, i) + (i == 0 ? " (fx)" : " (fy)") + ": must be > 0 (got " +
                                               ExactNumber(rows[i][i]) + ")");
    }
  }
  for (size_t i = 0; i < n; ++i) {
    for (size_t j = 0; j < n; ++j) {
      if (i == j && i < 2) continue;
      if ((i == 0 || i == 1) && j == 2) continue;  // cx, cy
      const double want = i == j ? 1.0 : 0.0;
      if (rows[i][j] != want) {
        const std::string hint = i == 2 && j < 2 && rows[0][2] == 0 && rows[1][2] == 0
                                     ? "; cx and cy are in the last row, as in a transposed (column-major) "
                                       "matrix: K is read row by row"
                                     : "";
        return FileError(path, row_lines[i], entry(i, j) + (i == 0 && j == 1 ? " (the skew)" : "") +
                                                 ": must be " + ExactNumber(want) + " in a pinhole matrix (got " +
                                                 ExactNumber(rows[i][j]) + ")" + hint);
      }
    }
  }
  PinholeIntrinsics k;
  k.fx = rows[0][0];
  k.fy = rows[1][1];
  k.cx = rows[0][2];
  k.cy = rows[1][2];
  *intrinsics = k;
  return Status::Ok();
}

}  // namespace femreg
