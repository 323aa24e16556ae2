// femreg: the command line. Each subcommand lives in its own file and registers itself
// through the functions declared in commands.h.
#include <CLI/CLI.hpp>
#include <iostream>

#include "commands.h"

int main(int argc, char** argv) {
  CLI::App app{
      "femreg - physics-regularized non-rigid registration of tetrahedral meshes to point "
      "clouds.\nRun 'femreg SUBCOMMAND --help' for the options of one subcommand."};
  app.require_subcommand(1);
  app.set_version_flag("--version", "femreg 0.1.0");
  femreg::cli::RegisterCommands(&app);
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return app.exit(e);
  }
  return femreg::cli::ExitCode();
}
