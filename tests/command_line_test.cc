// The command line's contract as a user meets it: --help and argument errors, warnings that
// say what was not done, and --force over a last run.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <string>

#include "femreg_test_config.h"
#include "synth_samples.h"
#include "test_util.h"

namespace femreg {
namespace {

namespace fs = std::filesystem;
using testing_util::CliRun;
using testing_util::Femreg;
using testing_util::StatsColumn;
using testing_util::TempDir;

std::string Demo() { return std::string(FEMREG_DATASETS_DIR) + "/demo"; }

std::string RegisterArgs(const std::string& frames, const std::string& out) {
  return "register --scene " + Demo() + "/scene.yaml --frames " + frames + " --ground-truth " + Demo() +
         "/ground_truth --no-progress --report none --threads 1 --force --out " + out;
}

}  // namespace

// --force writes over a last run: a shorter run leaves none of the longer one's frames, which
// `femreg eval` would count.
TEST(CommandLine, ForceRemovesTheLastRunsFrames) {
  TempDir tmp;
  const std::string out = tmp.File("out");
  auto vtus = [&] {
    int n = 0;
    for (const auto& entry : fs::directory_iterator(out + "/frames")) n += entry.path().extension() == ".vtu";
    return n;
  };
  CliRun run = Femreg(RegisterArgs(Demo() + "/clouds", out) + " --max-frames 3");
  ASSERT_EQ(run.code, 0) << run.out;
  EXPECT_EQ(vtus(), 3);
  std::ofstream(out + "/notes.txt") << "the user's own file\n";
  run = Femreg(RegisterArgs(Demo() + "/clouds", out) + " --max-frames 1");
  ASSERT_EQ(run.code, 0) << run.out;
  EXPECT_EQ(vtus(), 1);
  EXPECT_TRUE(fs::is_regular_file(out + "/notes.txt"));  // only the frames/ folder goes
  EXPECT_EQ(StatsColumn(out, "err_mean_mm").size(), 1u);
  // Not when an input lies in it: the recording in OUT/frames stays, and the run is refused.
  const std::string rec = tmp.File("rec");
  fs::create_directories(rec + "/frames");
  fs::copy_file(Demo() + "/clouds/frame_0000.pcd", rec + "/frames/frame_0000.pcd");
  run = Femreg(RegisterArgs(rec + "/frames", rec));
  EXPECT_NE(run.code, 0) << run.out;
  EXPECT_NE(run.out.find("holds the input"), std::string::npos) << run.out;
  EXPECT_TRUE(fs::is_regular_file(rec + "/frames/frame_0000.pcd"));
}

// The command line's contract: --help exits 0; an argument error (a missing file
// included) exits 2 with the command's name and where to look; a keyframe past the end of
// a synth sequence is said, not silently cut.
TEST(CommandLine, HelpExitsZeroArgumentErrorsExitTwoNamingTheCommand) {
  for (const char* command : {"", "register ", "synth ", "mesh ", "eval "}) {
    const CliRun run = Femreg(std::string(command) + "--help");
    EXPECT_EQ(run.code, 0) << command << run.out;
    EXPECT_NE(run.out.find("Usage:"), std::string::npos) << run.out;
  }
  TempDir tmp;
  CliRun run = Femreg("mesh " + tmp.File("missing.ply") + " --out " + tmp.File("m.vtu"));
  EXPECT_EQ(run.code, 2) << run.out;
  EXPECT_EQ(run.out.rfind("femreg mesh: ", 0), 0u) << run.out;
  EXPECT_NE(run.out.find("Run 'femreg mesh --help'"), std::string::npos) << run.out;
  run = Femreg("register --scene " + Demo() + "/scene.yaml --frames " + Demo() + "/clouds --no-such-flag");
  EXPECT_EQ(run.code, 2) << run.out;
  EXPECT_EQ(run.out.rfind("femreg register: ", 0), 0u) << run.out;

  const std::string scene = tmp.File("late.yaml");
  std::ofstream(scene) << testing_util::BlockPressSynthScene("  frames: 2\n  sanity_check: true\n",
                                                         "{frame: 5, translation: [0, 0, -0.014]}");
  run = Femreg("synth " + scene + " --out " + tmp.File("late") + " --no-progress");
  EXPECT_EQ(run.code, 0) << run.out;
  EXPECT_NE(run.out.find("femreg synth: warning: synth.bodies[0] (tool)'s last keyframe is at frame 5"), std::string::npos)
      << run.out;
}

}  // namespace femreg
