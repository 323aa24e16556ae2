// Fracture on the command line: `femreg register` on a sequence that breaks (stats.csv's and
// summary.json's fracture fields) and `femreg eval` on its result.
#include <gtest/gtest.h>

#include <algorithm>
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
#endif  // FEMREG_CLI_PATH

}  // namespace
}  // namespace femreg
