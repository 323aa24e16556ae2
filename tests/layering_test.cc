// The module layout reads top-down: every #include "..." in the library, the back ends, the
// tools and the Python module points to the same module or to one below it. A new module or public header
// fails here until it is given its place in the table.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <map>
#include <regex>
#include <set>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

#include "femreg_test_config.h"

namespace femreg {
namespace {

namespace fs = std::filesystem;

// Bottom to top. A module may include its own headers and those of modules with a lower
// rank; modules of the same rank do not include each other.
const std::map<std::string, int> kRank = {
    {"mesh", 0},          // tetrahedral meshes, topology, Status
    {"parallel", 0},      // the thread count every parallel part follows
    {"io", 1},            // every file format: meshes, clouds, depth images, intrinsics, TUM lists
    {"geometry", 1},      // closest points, AABB tree, nearest-point search
    {"fem", 2},           // materials, element rest data, the elastic models
    {"energy", 3},        // the energy terms: per block residuals and Jacobians, losses
    {"forward", 4},       // the quasi-static forward solve, on the energy layer
    {"collision", 5},     // collision specs, contact detection, the penalty
    {"fracture", 5},      // separation tensor, node splits
    {"solvers", 6},       // the back ends (Ceres, fast) behind one interface
    {"meshing", 6},       // closed surfaces to tetrahedra (TetGen)
    {"registration", 7},  // options, summaries, point clouds, the Tracker
    {"eval", 8},          // ground truth, errors, surfaces
    {"synth", 9},         // the virtual depth camera, the ground truth embedding
    {"scene", 10},        // scene files: reading, writing, setting up meshes and problems
    {"datasets", 11},     // the sequence generators
    {"experiments", 11},  // the bench / compare sweep
    {"calibration", 11},  // material from data: forward solves against observed clouds
    {"results", 12},      // the files runs write: register's, simulate's, calibrate's
    {"tools", 13},        // the femreg command line
    {"python", 13},       // the Python module (python/src)
};

// Public headers (include/femreg/) by module.
const std::map<std::string, std::string> kHeaderModule = {
    {"status.h", "mesh"},           {"mesh.h", "mesh"},
    {"version.h", "mesh"},          {"field_table.h", "mesh"},
    {"blas_kernels.h", "parallel"},
    {"io.h", "io"},                 {"camera_io.h", "io"},
    {"geometry.h", "geometry"},
    {"fem.h", "fem"},               {"forward.h", "forward"},
    {"energy.h", "energy"},         {"solver.h", "solvers"},
    {"meshing.h", "meshing"},
    {"collision_spec.h", "collision"}, {"collision.h", "collision"},
    {"fracture.h", "fracture"},     {"registration.h", "registration"},
    {"point_cloud.h", "registration"}, {"tracker.h", "registration"},
    {"option_fields.h", "registration"},
    {"ground_truth.h", "eval"},     {"eval.h", "eval"},
    {"synth.h", "synth"},           {"scene.h", "scene"},
    {"datasets.h", "datasets"},     {"experiment.h", "experiments"},
    {"calibration.h", "calibration"}, {"results.h", "results"},
    {"forward_results.h", "results"},
};

// Arrows that point up today, each with the change that removes it. Keep this list short.
const std::set<std::pair<std::string, std::string>> kKnownUpward = {
};

struct Include {
  std::string file;    // relative to the source folder
  int line = 0;
  std::string target;  // as written between the quotes
};

std::vector<Include> QuotedIncludes(const fs::path& root, const fs::path& file) {
  std::vector<Include> out;
  std::ifstream in(file);
  const std::regex include_re(R"re(^\s*#\s*include\s+"([^"]+)")re");
  std::string line;
  int number = 0;
  while (std::getline(in, line)) {
    ++number;
    std::smatch m;
    if (std::regex_search(line, m, include_re)) {
      out.push_back({fs::relative(file, root).generic_string(), number, m[1].str()});
    }
  }
  return out;
}

// The module a source file belongs to ("" when it is not part of the layering).
std::string FileModule(const std::string& file) {
  const fs::path p(file);
  auto it = p.begin();
  const std::string top = it->string();
  if (top == "include") return kHeaderModule.count(p.filename().string()) ? kHeaderModule.at(p.filename().string()) : "?";
  if (top == "src") return (++it)->string();
  if (top == "solvers") return "solvers";
  if (top == "tools") return "tools";
  if (top == "python") return "python";
  return "";
}

// The module an include points to; "" for a header beside the including file.
std::string TargetModule(const std::string& target) {
  const fs::path p(target);
  const std::string top = p.begin()->string();
  if (top == "femreg") return kHeaderModule.count(p.filename().string()) ? kHeaderModule.at(p.filename().string()) : "?";
  if (top == "solvers") return "solvers";
  if (std::distance(p.begin(), p.end()) > 1) return top;  // "io/io_internal.h": a private header
  return "";
}

TEST(Layering, EveryIncludePointsDownOrIntoItsOwnModule) {
  const fs::path root(FEMREG_SOURCE_DIR);
  std::vector<fs::path> files;
  for (const char* dir : {"include", "src", "solvers", "tools", "python/src"}) {
    for (const auto& entry : fs::recursive_directory_iterator(root / dir)) {
      const std::string ext = entry.path().extension().string();
      if (entry.is_regular_file() && (ext == ".h" || ext == ".cc")) files.push_back(entry.path());
    }
  }
  ASSERT_GT(files.size(), 50u);
  int checked = 0;
  std::set<std::pair<std::string, std::string>> seen_known;
  for (const fs::path& path : files) {
    const std::string module = FileModule(fs::relative(path, root).generic_string());
    if (module.empty()) continue;
    for (const Include& inc : QuotedIncludes(root, path)) {
      const std::string where = inc.file + ":" + std::to_string(inc.line) + ": \"" + inc.target + "\"";
      ASSERT_TRUE(kRank.count(module)) << where << ": module '" << module
                                       << "' has no place in the layering (kRank)";
      if (fs::path(inc.file).begin()->string() == "include") {
        EXPECT_EQ(fs::path(inc.target).begin()->string(), "femreg")
            << where << ": a public header includes a private one";
      }
      const std::string target = TargetModule(inc.target);
      if (target.empty() || target == module) continue;
      ++checked;
      ASSERT_TRUE(kRank.count(target)) << where << ": '" << target
                                       << "' has no place in the layering (kRank, kHeaderModule)";
      if (kRank.at(target) < kRank.at(module)) continue;
      if (kKnownUpward.count({inc.file, inc.target})) {
        seen_known.insert({inc.file, inc.target});
        continue;
      }
      ADD_FAILURE() << where << ": " << module << " (rank " << kRank.at(module) << ") includes "
                    << target << " (rank " << kRank.at(target) << "), which is not below it";
    }
  }
  EXPECT_GT(checked, 100);
  // A known arrow that is gone leaves the list too.
  for (const auto& known : kKnownUpward) {
    EXPECT_TRUE(seen_known.count(known)) << known.first << " no longer includes " << known.second
                                         << ": remove it from kKnownUpward";
  }
}

}  // namespace
}  // namespace femreg
