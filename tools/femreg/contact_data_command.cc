// femreg contact-data: writes a bundled contact sequence (ground truth and clouds).
#include <chrono>
#include <iostream>
#include <memory>

#include "cli_util.h"
#include "commands.h"
#include "femreg/datasets.h"

namespace femreg {
namespace cli {
void AddContactDataCommand(CLI::App* app) {
  auto out = std::make_shared<std::string>();
  auto scenario = std::make_shared<std::string>();
  auto force = std::make_shared<bool>(false);
  CLI::App* cmd = app->add_subcommand(
      "contact-data",
      "Write a contact sequence: contact_pair (a soft block pressed and sheared onto another) "
      "or tool_table (a soft slab pushed onto a table by a rigid tool), simulated with "
      "corotational FEM and penalty contacts on meshes twice as fine as the tracked ones, seen "
      "by a virtual depth camera. Writes OUT/scene.yaml, OUT/clouds/*.pcd, "
      "OUT/ground_truth/*.csv, OUT/truth_contacts.csv, for tool_table OUT/forces.csv (per frame, "
      "the contact forces' resultant on the slab and its torque about the slab's centroid, for "
      "`femreg eval`) and OUT/README.md.");
  cmd->add_option("--scenario", *scenario, "contact_pair or tool_table")
      ->required()
      ->check(CLI::IsMember(ContactScenarios()));
  cmd->add_option("--out,-o", *out, "Output folder")->required();
  cmd->add_flag("--force", *force, "Write into a non-empty folder (the folders of frames it writes, a last run's, are removed first)");
  cmd->callback([out, scenario, force] {
    Status status = PrepareOutputDir(*out, *force, {"clouds", "ground_truth"});
    if (status.ok()) {
      StartGeneratorProgress("contact-data");
      status = GenerateContactSequence(*scenario, *out, &GeneratorProgress);
      StopGeneratorProgress();
    }
    if (!status.ok()) {
      std::cerr << "femreg contact-data: " << status.message() << "\n";
      SetExitCode(1);
      return;
    }
    std::cout << "Wrote " << *scenario << " to " << *out << "\n";
  });
}

}  // namespace cli
}  // namespace femreg
