// femreg organ-data: writes the bundled partial-view sequence organ_patch.
#include <iostream>
#include <memory>
#include <string>
#include <vector>

#include "cli_util.h"
#include "commands.h"
#include "femreg/datasets.h"

namespace femreg {
namespace cli {

void AddOrganDataCommand(CLI::App* app) {
  auto out = std::make_shared<std::string>();
  auto force = std::make_shared<bool>(false);
  auto divisions = std::make_shared<int>(4);
  auto truth_divisions = std::make_shared<int>(10);
  auto tool = std::make_shared<std::string>(ToString(OrganTool::kContact));
  CLI::App* cmd = app->add_subcommand(
      "organ-data",
      "Write the organ_patch sequence: an organ-like body clamped at one end and pushed by a "
      "tool, seen as 500-point patches on ~15% of its surface with no camera (the neo-Hookean "
      "element with the nodal volume, locking-free, on a finer mesh than the tracked one, 9261 "
      "vertices). Writes OUT/organ.vtu, OUT/scene.yaml, "
      "OUT/clouds/*.pcd, OUT/ground_truth/*.csv, OUT/forces.csv (per frame, the tool's true force "
      "on the body and its torque about the body's centroid, for `femreg eval`) and OUT/README.md.");
  cmd->add_option("--out,-o", *out, "Output folder")->required();
  cmd->add_flag("--force", *force, "Write into a non-empty folder (the folders of frames it writes, a last run's, are removed first)");
  cmd->add_option("--divisions", *divisions,
                  "Divisions of the tracked mesh, 2 to the truth's divisions - 1: (2n+1)^3 vertices, "
                  "48 n^3 tetrahedra (4: the bundled 729 / 3072; 7: 3375 / 16464, the size of a "
                  "benchmark organ). The clouds, the ground-truth solve and forces.csv do not change")
      ->capture_default_str()
      ->check(CLI::Range(2, 15));
  cmd->add_option("--truth-divisions", *truth_divisions,
                  "Divisions of the ground truth's mesh, 3-16 (10: the bundled 9261 vertices). A finer "
                  "one shows how far the bundled truth is from converged; it changes the clouds, the "
                  "ground truth and forces.csv")
      ->capture_default_str()
      ->check(CLI::Range(3, 16));
  cmd->add_option("--tool", *tool,
                  "How the tool holds the body: contact (the bundled sequence: a rigid, frictionless "
                  "flat-ended cylinder pressing by the contact penalty; its force is normal to the "
                  "surface it touches, one a camera can see) or glued (the upper-surface vertices "
                  "within its radius follow it without slip, with a force along the surface that no "
                  "view shows). It changes the clouds, the ground truth and forces.csv")
      ->capture_default_str()
      ->check(CLI::IsMember(std::vector<std::string>{ToString(OrganTool::kGlued), ToString(OrganTool::kContact)}));
  cmd->callback([out, force, divisions, truth_divisions, tool] {
    OrganTool organ_tool = OrganTool::kContact;
    Status status = FromString(*tool, &organ_tool)
                        ? PrepareOutputDir(*out, *force, {"clouds", "ground_truth"})
                        : Status::Error("--tool " + *tool + ": use glued or contact");
    if (status.ok()) {
      StartGeneratorProgress("organ-data");
      status = GenerateOrganPatchSequence(*out, &GeneratorProgress, *divisions, *truth_divisions, organ_tool);
      StopGeneratorProgress();
    }
    if (!status.ok()) {
      std::cerr << "femreg organ-data: " << status.message() << "\n";
      SetExitCode(1);
      return;
    }
    std::cout << "Wrote organ_patch to " << *out << "\n";
  });
}

}  // namespace cli
}  // namespace femreg
