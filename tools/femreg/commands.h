// Subcommands of the femreg command line.
#ifndef FEMREG_TOOLS_COMMANDS_H_
#define FEMREG_TOOLS_COMMANDS_H_

#include <CLI/CLI.hpp>

namespace femreg {
namespace cli {

// Each Add*Command adds one subcommand with its callback to `app`.
void AddInfoCommand(CLI::App* app);
void AddSimulateCommand(CLI::App* app);
void AddRegisterCommand(CLI::App* app);
void AddBenchCommand(CLI::App* app);
void AddCompareCommand(CLI::App* app);
void AddSynthCommand(CLI::App* app);
void AddEvalCommand(CLI::App* app);
void AddFractureDataCommand(CLI::App* app);
void AddContactDataCommand(CLI::App* app);
void AddOrganDataCommand(CLI::App* app);
void AddHandPressDataCommand(CLI::App* app);
void AddMeshCommand(CLI::App* app);
void AddCalibrateCommand(CLI::App* app);

// Adds all of the above.
void RegisterCommands(CLI::App* app);

// The exit code the callback that ran asked for (0 when none ran or all went well).
int ExitCode();
void SetExitCode(int code);

}  // namespace cli
}  // namespace femreg

#endif  // FEMREG_TOOLS_COMMANDS_H_
