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
  auto options = std::make_shared<HandPressOptions>();
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
  // Variants: data like the bundled sequence but not the same, to check that registration
  // holds on them (tools/hand_press_variants.sh).
  cmd->add_option("--youngs-modulus", options->youngs_modulus,
                  "Variant: the ball's Young's modulus in the ground truth (Pa; the bundled "
                  "sequence's: 20000)")
      ->check(CLI::PositiveNumber);
  cmd->add_option("--scene-youngs-modulus", options->scene_youngs_modulus,
                  "Variant: the Young's modulus the tracking scene says (Pa; default: the truth's)")
      ->check(CLI::PositiveNumber);
  cmd->add_option("--camera-azimuth", options->camera_azimuth_deg,
                  "Variant: the camera turned about the vertical through the ball (degrees; 0: "
                  "in front, the bundled sequence's; 90: at +x, where the ball is carried to)");
  cmd->add_option("--seed", options->seed, "Variant: the depth noise's draws (0: the bundled sequence's)");
  cmd->add_option("--press-scale", options->press_scale,
                  "Variant: the palm's press past the ball's top, as a multiple of the bundled "
                  "one (1; up to 1.5)")
      ->check(CLI::Range(0.0, 1.5));
  cmd->callback([out, force, frames, options] {
    Status status = PrepareOutputDir(*out, *force, {"clouds", "clouds_without_hand", "ground_truth", "truth"});
    HandPressReport report;
    if (status.ok()) {
      StartGeneratorProgress("hand-press-data");
      status = GenerateHandPressSequence(*out, *frames, &report, &GeneratorProgress, *options);
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
