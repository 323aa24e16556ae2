// femreg fracture-data: writes a bundled fracture sequence (ground truth and clouds).
#include <iostream>
#include <memory>

#include "cli_util.h"
#include "commands.h"
#include "femreg/datasets.h"

namespace femreg {
namespace cli {
namespace {
void Progress(int done, int total) {
  static std::unique_ptr<ProgressBar> bar;
  if (done == 1 || bar == nullptr) bar = std::make_unique<ProgressBar>("fracture-data", total);
  bar->Update(done);
  if (done == total) bar->Finish();
}
}  // namespace

void AddFractureDataCommand(CLI::App* app) {
  auto out = std::make_shared<std::string>();
  auto scenario = std::make_shared<std::string>();
  auto force = std::make_shared<bool>(false);
  CLI::App* cmd = app->add_subcommand(
      "fracture-data",
      "Write a fracture sequence: beam_break (a beam bent until it breaks), slab_tear (a "
      "slab torn by two grippers), simulated with corotational FEM and the fracture model on "
      "a mesh twice as fine as the tracked one, or beam_cut (a beam bent, then cut by "
      "removing a slab of elements of a finer mesh), seen by a virtual depth camera. Writes "
      "OUT/scene.yaml, OUT/clouds/*.pcd, OUT/ground_truth/*.csv and OUT/README.md.");
  cmd->add_option("--scenario", *scenario, "beam_break, slab_tear or beam_cut")
      ->required()
      ->check(CLI::IsMember(FractureScenarios()));
  cmd->add_option("--out,-o", *out, "Output folder")->required();
  cmd->add_flag("--force", *force, "Write into a non-empty folder");
  cmd->callback([out, scenario, force] {
    Status status = PrepareOutputDir(*out, *force);
    if (status.ok()) status = GenerateFractureSequence(*scenario, *out, &Progress);
    if (!status.ok()) {
      std::cerr << "femreg fracture-data: " << status.message() << "\n";
      SetExitCode(1);
      return;
    }
    std::cout << "Wrote " << *scenario << " to " << *out << "\n";
  });
}

}  // namespace cli
}  // namespace femreg
