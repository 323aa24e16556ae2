// femreg hand-press-data: writes the bundled hand_press sequence (ground truth, forces, clouds).
#include <cstdio>
#include <iostream>
#include <memory>

#include "cli_util.h"
#include "commands.h"
#include "femreg/datasets.h"

namespace femreg {
namespace cli {
void AddHandPressDataCommand(CLI::App* app) {
  auto out = std::make_shared<std::string>();
  auto force = std::make_shared<bool>(false);
  auto frames = std::make_shared<int>(0);
  CLI::App* cmd = app->add_subcommand(
      "hand-press-data",
      "Write the hand_press sequence: a foam ball on a table pressed by a hand whose points are "
      "in the clouds, then grasped, lifted, tilted and set down (corotational FEM with sticking "
      "contacts on a finer mesh than the tracked one, one depth camera above and in front). "
      "Writes OUT/scene.yaml, OUT/clouds/*.pcd, OUT/clouds_without_hand/*.pcd (the hand's points "
      "left out), OUT/ground_truth/*.csv, OUT/truth/*.vtu, "
      "OUT/forces.csv, OUT/truth_solve.csv and OUT/README.md.");
  cmd->add_option("--out,-o", *out, "Output folder")->required();
  cmd->add_flag("--force", *force, "Write into a non-empty folder (the folders of frames it writes, a last run's, are removed first)");
  cmd->add_option("--frames", *frames,
                  "Make only the first N frames of the 30 (the same files as a full run's)")
      ->check(CLI::Range(1, 30));
  cmd->callback([out, force, frames] {
    Status status = PrepareOutputDir(*out, *force, {"clouds", "clouds_without_hand", "ground_truth", "truth"});
    HandPressReport report;
    if (status.ok()) {
      StartGeneratorProgress("hand-press-data");
      status = GenerateHandPressSequence(*out, *frames, &report, &GeneratorProgress);
      StopGeneratorProgress();
    }
    if (!status.ok()) {
      std::cerr << "femreg hand-press-data: " << status.message() << "\n";
      SetExitCode(1);
      return;
    }
    std::printf(
        "Wrote hand_press to %s: %d frames, %d to %d points per cloud; largest force "
        "imbalance %.2e N, torque imbalance %.2e N m\n",
        out->c_str(), report.frames, report.min_points, report.max_points,
        report.max_force_imbalance_N, report.max_torque_imbalance_Nm);
  });
}

}  // namespace cli
}  // namespace femreg
