#include "commands.h"

namespace femreg {
namespace cli {

void AddRegisterCommand(CLI::App* app) {
  CLI::App* cmd = app->add_subcommand("register", "(not built yet)");
  cmd->callback([] { SetExitCode(1); });
}

}  // namespace cli
}  // namespace femreg
