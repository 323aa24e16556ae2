// Fracture on the command line: `femreg register` on a sequence that breaks (stats.csv's and
// summary.json's fracture fields) and `femreg eval` on its result.
#include <gtest/gtest.h>

#include <Eigen/Core>
#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <cstdlib>
#include <fstream>
#include <iterator>
#include <sstream>
#include <string>
#include <vector>

#include "femreg_test_config.h"
#include "test_util.h"

namespace femreg {
namespace {

#ifdef FEMREG_CLI_PATH
// `femreg register` on beam_cut reports the break: stats.csv's pieces and break_frame (-1
// before frame 7, 7 from it), the error per piece seen and hidden after it, and summary.json's
// fracture section.
TEST(FractureCli, RegisterReportsTheBreakFrameAndThePieces) {
  testing_util::TempDir dir("femreg_fracture_break");
  const std::string data = std::string(FEMREG_DATASETS_DIR) + "/beam_cut";
  ASSERT_EQ(std::system((std::string(FEMREG_CLI_PATH) + " register --scene " + data + "/scene.yaml --frames " +
                         data + "/clouds --ground-truth " + data + "/ground_truth --no-progress --report none "
                         "--threads 1 --out " + dir.path() + "/run > " + dir.path() + "/register.txt").c_str()),
            0);
  const std::string out = dir.path() + "/run";
  const std::vector<std::string> pieces = testing_util::StatsColumn(out, "pieces");
  const std::vector<std::string> breaks = testing_util::StatsColumn(out, "break_frame");
  const std::vector<std::string> seen = testing_util::StatsColumn(out, "err_piece_seen_mm");
  const std::vector<std::string> hidden = testing_util::StatsColumn(out, "err_piece_hidden_mm");
  ASSERT_EQ(pieces.size(), 12u);
  ASSERT_EQ(breaks.size(), 12u);
  for (size_t f = 0; f < 12; ++f) {
    EXPECT_EQ(pieces[f], f < 7 ? "1" : "2") << "frame " << f;
    EXPECT_EQ(breaks[f], f < 7 ? "-1" : "7") << "frame " << f;
    // One entry per piece, ';' between them.
    EXPECT_EQ(std::count(seen[f].begin(), seen[f].end(), ';'), f < 7 ? 0 : 1) << seen[f];
    EXPECT_EQ(std::count(hidden[f].begin(), hidden[f].end(), ';'), f < 7 ? 0 : 1) << hidden[f];
  }
  std::ifstream in(out + "/summary.json");
  const std::string summary((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  const size_t at = summary.find("\"fracture\"");
  ASSERT_NE(at, std::string::npos) << summary;
  const std::string section = summary.substr(at, 400);
  EXPECT_NE(section.find("\"pieces\": 2"), std::string::npos) << section;
  EXPECT_NE(section.find("\"break_frame\": 7"), std::string::npos) << section;
  EXPECT_NE(section.find("\"piece_error_after_break_mm\""), std::string::npos) << section;
}

// `femreg eval` on a fracture result matches vertices through the VTU's original_vertex
// field, piece by piece, and gives the same errors as `femreg register --ground-truth`.
TEST(FractureCli, EvalMatchesRegisterOnTheBrokenBeam) {
  testing_util::TempDir dir("femreg_fracture_cli");
  const std::string data = std::string(FEMREG_DATASETS_DIR) + "/beam_break";
  const std::string cli = FEMREG_CLI_PATH;
  ASSERT_EQ(std::system((cli + " register --scene " + data + "/scene.yaml --frames " + data +
                         "/clouds --ground-truth " + data + "/ground_truth --max-frames 16 "
                         "--no-progress --report none --out " + dir.path() + "/run > " +
                         dir.path() + "/register.txt").c_str()),
            0);
  ASSERT_EQ(std::system((cli + " eval " + dir.path() + "/run " + data + " > " + dir.path() +
                         "/eval.txt").c_str()),
            0);
  auto read = [&](const std::string& name) {
    std::ifstream in(dir.path() + "/" + name);
    return std::string((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  };
  const std::string reg = read("register.txt"), eval = read("eval.txt");
  // The per-piece lines ("  piece 0 after the break ...") are the same in both.
  auto pieces = [](const std::string& text) {
    std::string out;
    std::istringstream in(text);
    for (std::string line; std::getline(in, line);)
      if (line.rfind("  piece ", 0) == 0) out += line + "\n";
    return out;
  };
  EXPECT_NE(pieces(reg), "") << reg;
  EXPECT_EQ(pieces(eval), pieces(reg)) << eval;
  EXPECT_NE(eval.find("(ground truth: first split at frame 12, in pieces from frame 13)"), std::string::npos)
      << eval;
}

// The cut sequence from another simulator, without it: `fracture-data --calculix-deck` writes
// beam_cut's ground truth as a CalculiX deck (one step per frame, the slab removed in frame 7's,
// every number short enough for ccx's 20-character fields), and `--calculix-result` reads a
// .dat in ccx's format (here made up: each step's end moves every node by (1 mm) x frame, the
// increments before it by something else) and writes the sequence from it.
TEST(FractureCli, CalculixDeckAndResultMakeTheCutSequence) {
  testing_util::TempDir dir("femreg_fracture_ccx");
  const std::string cli = FEMREG_CLI_PATH;
  ASSERT_EQ(std::system((cli + " fracture-data --scenario beam_cut --calculix-deck " + dir.path() +
                         "/cut.inp > " + dir.path() + "/deck.txt").c_str()),
            0);
  std::ifstream deck(dir.path() + "/cut.inp");
  int steps = 0, removals = 0, removal_step = -1, nodes = 0, slab = 0, too_long = 0;
  std::string section;
  for (std::string line; std::getline(deck, line);) {
    if (line.rfind("*STEP", 0) == 0) ++steps;
    if (line.rfind("*MODEL CHANGE", 0) == 0) {
      ++removals;
      removal_step = steps - 1;  // frames count from 0
    }
    if (line[0] == '*') {
      section = line.substr(0, line.find(','));
      continue;
    }
    std::istringstream fields(line);
    for (std::string field; std::getline(fields, field, ',');) too_long += field.size() > 21;  // with its space
    if (section == "*NODE") ++nodes;
    if (section == "*ELSET") slab += static_cast<int>(std::count(line.begin(), line.end(), ',')) + 1;
  }
  EXPECT_EQ(steps, 12);
  EXPECT_EQ(removals, 1);
  EXPECT_EQ(removal_step, 7);
  EXPECT_EQ(nodes, 2009);
  EXPECT_EQ(slab, 216);  // one cell layer of 6 x 6 cells, 6 tetrahedra each
  EXPECT_EQ(too_long, 0);

  auto write_dat = [&](const std::string& path, int frames) {
    std::ofstream dat(path);
    char buf[160];
    for (int f = 0; f < frames; ++f) {
      for (double part : {0.5, 1.0}) {
        std::snprintf(buf, sizeof(buf), " displacements (vx,vy,vz) for set NALL and time  %.7E\n\n", f + part);
        dat << buf;
        for (int n = 1; n <= nodes; ++n) {
          std::snprintf(buf, sizeof(buf), "%10d  %.6E  %.6E  %.6E\n", n, part == 1.0 ? 1e-3 * f : 0.5, 0.0, 0.0);
          dat << buf;
        }
        dat << "\n";
      }
    }
  };
  write_dat(dir.path() + "/cut.dat", 12);
  ASSERT_EQ(std::system((cli + " fracture-data --scenario beam_cut --calculix-result " + dir.path() +
                         "/cut.dat --out " + dir.path() + "/seq > " + dir.path() + "/seq.txt").c_str()),
            0);
  auto first_row = [&](int f) {
    char name[64];
    std::snprintf(name, sizeof(name), "/seq/ground_truth/frame_%04d.csv", f);
    std::ifstream in(dir.path() + name);
    std::string header, row;
    std::getline(in, header);
    std::getline(in, row);
    double x = 0, y = 0, z = 0;
    EXPECT_EQ(std::sscanf(row.c_str(), "%lf,%lf,%lf", &x, &y, &z), 3) << row;
    return Eigen::Vector3d(x, y, z);
  };
  for (int f : {3, 7, 11}) {
    EXPECT_NEAR((first_row(f) - first_row(0) - Eigen::Vector3d(1e-3 * f, 0, 0)).norm(), 0.0, 1e-9) << "frame " << f;
  }
  namespace fs = std::filesystem;
  EXPECT_FALSE(fs::exists(dir.path() + "/seq/ground_truth/frame_0006_pieces.csv"));
  EXPECT_TRUE(fs::exists(dir.path() + "/seq/ground_truth/frame_0007_pieces.csv"));
  std::ifstream readme(dir.path() + "/seq/README.md");
  const std::string text((std::istreambuf_iterator<char>(readme)), std::istreambuf_iterator<char>());
  EXPECT_NE(text.find("# beam_cut_calculix"), std::string::npos) << text;
  EXPECT_NE(text.find("CalculiX"), std::string::npos) << text;
  // A result that lacks a step is refused.
  write_dat(dir.path() + "/short.dat", 11);
  EXPECT_NE(std::system((cli + " fracture-data --scenario beam_cut --calculix-result " + dir.path() +
                         "/short.dat --out " + dir.path() + "/short > " + dir.path() + "/short.txt 2>&1").c_str()),
            0);
}
#endif  // FEMREG_CLI_PATH

}  // namespace
}  // namespace femreg
