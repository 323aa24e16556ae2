// The TUM RGB-D layout (https://cvg.cit.tum.de/data/datasets/rgbd-dataset/file_formats): a
// folder with depth/*.png (16-bit, 5000 units per metre), rgb/*.png, and text lists of
// "timestamp path" (depth.txt, rgb.txt) or, from the benchmark's associate.py,
// "timestamp rgb_path timestamp depth_path" (associations.txt).
#include <algorithm>
#include <cctype>
#include <cerrno>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "femreg/camera_io.h"
#include "io/io_internal.h"
#include "io/text_tokens.h"

namespace femreg {
namespace {

namespace fs = std::filesystem;

// The list names looked for in a sequence folder, in order: an associations file names the
// frames the user synchronised; depth.txt every depth image.
const char* const kListNames[] = {"associations.txt", "association.txt", "associate.txt", "depth.txt"};

// A list is a few megabytes at most, even for a long recording; a far larger file is not one.
constexpr uintmax_t kMaxListBytes = 256u << 20;

std::vector<std::string> Fields(const std::string& line) {
  std::vector<std::string> out;
  std::istringstream in(line);
  for (std::string f; in >> f;) out.push_back(f);
  return out;
}

// The line without its comment and its trailing carriage return.
std::string Content(std::string line) {
  const size_t hash = line.find('#');
  if (hash != std::string::npos) line.resize(hash);
  if (!line.empty() && line.back() == '\r') line.pop_back();
  return line;
}

bool IsImagePath(const std::string& path) {
  std::string ext = fs::path(path).extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return std::tolower(c); });
  return ext == ".png" || ext == ".npy";
}

// A path for a message: as it is, unless it is too long to be one (a binary file read as a
// list), then quoted and capped.
std::string Shown(const std::string& path) {
  return path.size() <= 512 ? path : internal::Quoted(path);
}

bool UnderDepthFolder(const std::string& path) {
  const fs::path p(path);
  return std::distance(p.begin(), p.end()) > 1 && p.begin()->string() == "depth";
}

}  // namespace

bool LooksLikeTumList(const std::string& path) {
  std::error_code ec;
  if (!fs::is_regular_file(path, ec)) return false;
  std::ifstream in(path);
  std::string line;
  for (int n = 0; n < 1000 && std::getline(in, line); ++n) {
    const std::vector<std::string> f = Fields(Content(line));
    if (f.empty()) continue;
    double t = 0;
    return (f.size() == 2 || f.size() == 4) && internal::ParseDouble(f[0], &t) && IsImagePath(f[1]);
  }
  return false;
}

std::string FindTumList(const std::string& dir) {
  for (const char* name : kListNames) {
    const std::string path = (fs::path(dir) / name).string();
    if (LooksLikeTumList(path)) return path;
  }
  return "";
}

Status ReadTumSequence(const std::string& path, TumSequence* sequence) {
  using internal::FileError;
  using internal::Quoted;
  std::error_code ec;
  std::string list = path;
  if (fs::is_directory(path, ec)) {
    list = FindTumList(path);
    if (list.empty()) {
      return FileError(path, 0, "not a TUM RGB-D sequence: no associations.txt, association.txt, "
                                "associate.txt or depth.txt of \"timestamp path\" lines");
    }
  }
  const uintmax_t size = fs::file_size(list, ec);
  if (!ec && size > kMaxListBytes) return FileError(list, 0, std::to_string(size) + " bytes: too large for a TUM list");
  std::ifstream in(list);
  if (!in) return FileError(list, 0, std::string("cannot open: ") + std::strerror(errno));
  const fs::path base = fs::path(list).parent_path();
  TumSequence out;
  out.list = list;
  std::string line;
  for (int number = 1; std::getline(in, line); ++number) {
    const std::vector<std::string> f = Fields(Content(line));
    if (f.empty()) continue;
    if (f.size() != 2 && f.size() != 4) {
      return FileError(list, number, "expected \"timestamp depth_path\" or \"timestamp rgb_path "
                                     "timestamp depth_path\" (got " + std::to_string(f.size()) + " fields)");
    }
    double times[2] = {0, 0};
    for (size_t k = 0; k < f.size(); k += 2) {
      if (!internal::ParseDouble(f[k], &times[k / 2]) || !std::isfinite(times[k / 2])) {
        return FileError(list, number, Quoted(f[k]) + " is not a timestamp (seconds)");
      }
    }
    TumFrame frame;
    frame.line = number;
    // Which path is the depth image: the one alone on a depth.txt line; on an associations
    // line the one under depth/, else the second (associate.py rgb.txt depth.txt's order).
    int depth = f.size() == 2 ? 1 : 3;
    if (f.size() == 4 && UnderDepthFolder(f[1]) && !UnderDepthFolder(f[3])) depth = 1;
    frame.time = times[depth / 2];
    frame.depth = (base / f[static_cast<size_t>(depth)]).string();
    if (f.size() == 4) {
      const int rgb = depth == 1 ? 3 : 1;
      frame.rgb_time = times[rgb / 2];
      frame.rgb = (base / f[static_cast<size_t>(rgb)]).string();
    }
    if (!IsImagePath(frame.depth)) {
      return FileError(list, number, Shown(frame.depth) + ": not a depth image (.png or .npy)");
    }
    if (!fs::is_regular_file(frame.depth, ec)) {
      return FileError(list, number, Shown(frame.depth) + ": no such file");
    }
    out.frames.push_back(std::move(frame));
  }
  if (out.frames.empty()) return FileError(list, 0, "no frames (only comments and blank lines)");
  *sequence = std::move(out);
  return Status::Ok();
}

}  // namespace femreg
