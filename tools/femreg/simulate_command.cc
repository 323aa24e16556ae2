#include "commands.h"

namespace femreg {
namespace cli {

void AddSimulateCommand(CLI::App* app) {
  CLI::App* cmd = app->add_subcommand("simulate", "(not built yet)");
  cmd->callback([] { SetExitCode(1); });
}

}  // namespace cli
}  // namespace femreg
