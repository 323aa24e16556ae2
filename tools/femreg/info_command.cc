#include "commands.h"

namespace femreg {
namespace cli {

void AddInfoCommand(CLI::App* app) {
  CLI::App* cmd = app->add_subcommand("info", "(not built yet)");
  cmd->callback([] { SetExitCode(1); });
}

}  // namespace cli
}  // namespace femreg
