// Helpers shared by the tests.
#ifndef FEMREG_TESTS_TEST_UTIL_H_
#define FEMREG_TESTS_TEST_UTIL_H_

#include <dlfcn.h>
#include <unistd.h>

#include <sys/wait.h>

#include <atomic>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "femreg/ground_truth.h"
#include "femreg/point_cloud.h"
#include "femreg/status.h"

namespace femreg {
namespace testing_util {

// A fresh folder under the system's temporary directory, removed with everything in it.
class TempDir {
 public:
  explicit TempDir(const std::string& prefix = "femreg_test") {
    static std::atomic<int> counter{0};
    path_ = (std::filesystem::temp_directory_path() /
             (prefix + "_" + std::to_string(::getpid()) + "_" + std::to_string(counter++)))
                .string();
    std::filesystem::create_directories(path_);
  }
  ~TempDir() {
    std::error_code ec;
    std::filesystem::remove_all(path_, ec);
  }
  TempDir(const TempDir&) = delete;
  TempDir& operator=(const TempDir&) = delete;
  const std::string& path() const { return path_; }
  // The path of `name` in the folder, and that file written with `contents` (bytes as given).
  std::string File(const std::string& name) const { return path_ + "/" + name; }
  std::string Write(const std::string& name, const std::string& contents) const {
    std::ofstream(File(name), std::ios::binary) << contents;
    return File(name);
  }

 private:
  std::string path_;
};

// Frame `index` of a bundled sequence: clouds/frame_NNNN.pcd and ground_truth/frame_NNNN.csv.
inline Status ReadDatasetFrame(const std::string& dir, int index, PointCloud* cloud, GroundTruthFrame* truth) {
  char name[32];
  std::snprintf(name, sizeof(name), "frame_%04d", index);
  Status status = ReadPointCloud(dir + "/clouds/" + name + ".pcd", cloud);
  if (status.ok()) status = ReadGroundTruthFrame(dir + "/ground_truth/" + name + ".csv", truth);
  return status;
}

// A bundled sequence's clouds (clouds/frame_NNNN.pcd), in frame order, up to the first missing.
inline std::vector<PointCloud> ReadDatasetClouds(const std::string& dir) {
  std::vector<PointCloud> clouds;
  for (int f = 0;; ++f) {
    char name[32];
    std::snprintf(name, sizeof(name), "frame_%04d.pcd", f);
    const std::string path = dir + "/clouds/" + name;
    if (!std::filesystem::exists(path)) break;
    clouds.emplace_back();
    if (!ReadPointCloud(path, &clouds.back()).ok()) break;
  }
  return clouds;
}

// A file's whole contents ("" if it cannot be read).
inline std::string Slurp(const std::string& path) {
  std::ifstream in(path);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

#ifdef FEMREG_CLI_PATH
// The femreg command line run with `args` (after `prefix`, e.g. environment settings or
// `timeout 5`): its exit code and what it printed on stdout and stderr.
struct CliRun {
  int code = -1;
  std::string out;
};
inline CliRun Femreg(const std::string& args, const std::string& prefix = "") {
  TempDir tmp("femreg_cli_out");
  const std::string log = tmp.path() + "/log.txt";
  const std::string cmd = prefix + std::string(FEMREG_CLI_PATH) + " " + args + " > " + log + " 2>&1";
  const int status = std::system(cmd.c_str());
  CliRun r;
  r.code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  r.out = Slurp(log);
  return r;
}
#endif

// The column `name` of OUT/stats.csv (femreg register's), one value per frame (the columns
// before the quoted message).
inline std::vector<std::string> StatsColumn(const std::string& out, const std::string& name) {
  std::ifstream in(out + "/stats.csv");
  std::string line;
  std::getline(in, line);
  std::vector<std::string> header;
  std::stringstream hs(line);
  for (std::string cell; std::getline(hs, cell, ',');) header.push_back(cell);
  size_t column = header.size();
  for (size_t i = 0; i < header.size(); ++i) {
    if (header[i] == name) column = i;
  }
  std::vector<std::string> values;
  while (std::getline(in, line)) {
    std::stringstream ls(line);
    std::string cell;
    for (size_t i = 0; i <= column && std::getline(ls, cell, ','); ++i) {
    }
    values.push_back(cell);
  }
  return values;
}

// Sets OpenMP's thread count to 1 for the rest of the process and returns true: the forward
// solver's OpenMP loops spin-wait on a loaded machine, and small problems run faster on one
// thread. libgomp comes in through libfemreg, hence the look-up.
inline bool UseOneOpenMpThread() {
  using SetThreads = void (*)(int);
  if (auto f = reinterpret_cast<SetThreads>(dlsym(RTLD_DEFAULT, "omp_set_num_threads"))) f(1);
  return true;
}

// A 3 x 3 x 3 grid of points with spacing 1: vertex (i, j, k) is 9 k + 3 j + i.
inline Vertices Grid() {
  Vertices v(27, 3);
  for (int k = 0; k < 3; ++k) {
    for (int j = 0; j < 3; ++j) {
      for (int i = 0; i < 3; ++i) v.row(9 * k + 3 * j + i) << i, j, k;
    }
  }
  return v;
}

// "(x, y, z)" to four decimals, for failure messages.
inline std::string Format(const Eigen::Vector3d& v) {
  char buf[96];
  std::snprintf(buf, sizeof(buf), "(%.4f, %.4f, %.4f)", v.x(), v.y(), v.z());
  return buf;
}

}  // namespace testing_util
}  // namespace femreg

#endif  // FEMREG_TESTS_TEST_UTIL_H_
