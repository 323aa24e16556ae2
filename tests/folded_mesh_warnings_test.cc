// Every command that reads a rest mesh warns about folded elements (two elements on the same
// side of their shared face): register and info did; simulate and synth do too, for the
// object's mesh and for synth's ground truth mesh file. They warn and go on.
#include <gtest/gtest.h>
#include <sys/wait.h>

#include <cstdlib>
#include <fstream>
#include <sstream>
#include <string>

#include "test_util.h"

namespace femreg {
namespace {

#ifdef FEMREG_CLI_PATH

// Two tetrahedra on the triangle (0, 1, 2). folded: both apexes above it (the second element is
// inverted in the file, and the reader re-orients it, which hides the fold); else the second
// apex is below and the mesh is sound.
void WriteTwoTets(const std::string& stem, bool folded) {
  std::ofstream(stem + ".node") << "5 3 0 0\n0 0 0 0\n1 1 0 0\n2 0 1 0\n3 0 0 1\n4 0.2 0.2 "
                                << (folded ? "0.5" : "-0.5") << "\n";
  std::ofstream(stem + ".ele") << "2 4 0\n0 0 1 2 3\n1 0 2 1 4\n";
}

// Runs femreg with `args` in `dir`; the exit code, and stdout and stderr in *output.
int RunFemreg(const std::string& dir, const std::string& args, std::string* output) {
  const std::string log = dir + "/femreg.log";
  const std::string command =
      "cd " + dir + " && " + std::string(FEMREG_CLI_PATH) + " " + args + " > " + log + " 2>&1";
  const int status = std::system(command.c_str());
  std::stringstream text;
  text << std::ifstream(log).rdbuf();
  *output = text.str();
  return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
}

const char kObject[] =
    "objects:\n"
    "  - name: fold\n"
    "    mesh: mesh.node\n"
    "    material: {youngs_modulus: 1e5, poisson_ratio: 0.3, density: 100}\n"
    "boundary:\n"
    "  - {select: {box: {min: [-1, -1, -0.001], max: [2, 2, 0.001]}}, clamp: true}\n";

const char kWarning[] = "warning: object 'fold' has 2 folded rest element(s)";

TEST(FoldedMeshWarnings, SimulateWarnsAndSolves) {
  for (const bool folded : {true, false}) {
    SCOPED_TRACE(folded ? "folded" : "sound");
    testing_util::TempDir tmp;
    WriteTwoTets(tmp.path() + "/mesh", folded);
    std::ofstream(tmp.path() + "/scene.yaml")
        << kObject << "loads:\n  - {select: {box: {min: [-1, -1, 0.9], max: [2, 2, 2]}}, force: [0, 0, -0.01]}\n";
    std::string out;
    EXPECT_EQ(RunFemreg(tmp.path(), "simulate scene.yaml --out out", &out), 0) << out;
    EXPECT_EQ(out.find(std::string("femreg simulate: ") + kWarning) != std::string::npos, folded) << out;
    EXPECT_EQ(out.find("folded") != std::string::npos, folded) << out;
    EXPECT_NE(out.find("wrote out/summary.json"), std::string::npos) << out;
  }
}

TEST(FoldedMeshWarnings, SynthWarnsForTheObjectAndTheGroundTruthMesh) {
  testing_util::TempDir tmp;
  WriteTwoTets(tmp.path() + "/mesh", true);
  WriteTwoTets(tmp.path() + "/truth", true);
  std::ofstream(tmp.path() + "/scene.yaml")
      << kObject
      << "registration:\n"
         "  camera: {position: [0.3, -2, 1], target: [0.3, 0.3, 0.3], up: [0, 0, 1], fx: 100,\n"
         "           fy: 100, cx: 39.5, cy: 29.5, width: 80, height: 60}\n"
         "synth:\n"
         "  frames: 2\n"
         "  ground_truth: {mesh: truth.node}\n"
         "  motion:\n"
         "    - {name: top, select: {box: {min: [-1, -1, 0.9], max: [2, 2, 2]}},\n"
         "       keyframes: [{frame: 0}, {frame: 1, translation: [0, 0, -0.01]}]}\n";
  std::string out;
  EXPECT_EQ(RunFemreg(tmp.path(), "synth scene.yaml --out out --no-progress", &out), 0) << out;
  EXPECT_NE(out.find(std::string("femreg synth: ") + kWarning), std::string::npos) << out;
  EXPECT_NE(out.find("femreg synth: warning: the ground truth mesh"), std::string::npos) << out;
  EXPECT_NE(out.find("truth.node has 2 folded rest element(s)"), std::string::npos) << out;
  EXPECT_NE(out.find("Wrote 2 frames"), std::string::npos) << out;
}

#endif  // FEMREG_CLI_PATH

}  // namespace
}  // namespace femreg
