#include "commands.h"

namespace femreg {
namespace cli {
namespace {
int g_exit_code = 0;
}  // namespace

int ExitCode() { return g_exit_code; }
void SetExitCode(int code) { g_exit_code = code; }

void RegisterCommands(CLI::App* app) {
  AddInfoCommand(app);
  AddSimulateCommand(app);
  AddRegisterCommand(app);
  AddBenchCommand(app);
  AddCompareCommand(app);
  AddSynthCommand(app);
  AddEvalCommand(app);
  AddFractureDataCommand(app);
  AddContactDataCommand(app);
  AddOrganDataCommand(app);
  AddHandPressDataCommand(app);
  AddMeshCommand(app);
  AddCalibrateCommand(app);
}

}  // namespace cli
}  // namespace femreg
