// femreg demo-data: writes the bundled demo sequence (ground truth and clouds).
#include <cstdio>
#include <iostream>
#include <memory>

#include "cli_util.h"
#include "commands.h"
#include "femreg/synth.h"

namespace femreg {
namespace cli {
namespace {
void Progress(int done, int total) {
  static ProgressBar* bar = nullptr;
  static std::unique_ptr<ProgressBar> owner;
  if (done == 1 || bar == nullptr) {
    owner = std::make_unique<ProgressBar>("demo-data", total);
    bar = owner.get();
  }
  bar->Update(done);
  if (done == total) bar->Finish();
}
}  // namespace

void AddDemoDataCommand(CLI::App* app) {
  auto out = std::make_shared<std::string>();
  auto force = std::make_shared<bool>(false);
  auto frames = std::make_shared<int>(30);
  auto seed = std::make_shared<int>(1);
  CLI::App* cmd = app->add_subcommand(
      "demo-data",
      "Write the demo sequence: a soft beam bent, swung and twisted, simulated with corotational "
      "FEM on a mesh twice as fine as the tracked one and seen by a virtual depth camera. Writes "
      "OUT/scene.yaml, OUT/clouds/*.pcd, OUT/ground_truth/*.csv and OUT/README.md.");
  cmd->add_option("--out,-o", *out, "Output folder")->required();
  cmd->add_option("--frames", *frames, "Number of frames")->check(CLI::Range(1, 10000));
  cmd->add_option("--seed", *seed, "Noise seed");
  cmd->add_flag("--force", *force, "Write into a non-empty folder");
  cmd->callback([out, force, frames, seed] {
    Status status = PrepareOutputDir(*out, *force);
    if (status.ok()) {
      DemoOptions options = DefaultDemoOptions();
      options.frames = *frames;
      options.seed = static_cast<uint64_t>(*seed);
      status = GenerateDemoSequence(options, *out, &Progress);
    }
    if (!status.ok()) {
      std::cerr << "femreg demo-data: " << status.message() << "\n";
      SetExitCode(1);
      return;
    }
    std::cout << "Wrote the demo sequence to " << *out << "\n";
  });
}

}  // namespace cli
}  // namespace femreg
