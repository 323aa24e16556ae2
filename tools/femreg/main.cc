// femreg: the command line. Each subcommand lives in its own file and registers itself
// through the functions declared in commands.h.
#include <unistd.h>

#include <CLI/CLI.hpp>
#include <cstdlib>
#include <iostream>
#include <new>
#include <stdexcept>

#include "cli_util.h"
#include "commands.h"
#include "femreg/blas_kernels.h"
#include "femreg/version.h"

namespace {

// "femreg NAME" for the subcommand that was running ("femreg" before one was chosen).
std::string CommandName(const CLI::App& app) {
  std::string name = "femreg";
  for (const CLI::App* sub : app.get_subcommands()) name += " " + sub->get_name();
  return name;
}

}  // namespace

int main(int argc, char** argv) {
  // OpenMP's threads sleep between teams instead of spinning for milliseconds on cores that
  // other processes need. libgomp reads OMP_WAIT_POLICY once, as it loads (before main, and
  // before glibc sets up the environment for a .preinit_array): unless the user chose a policy
  // or a spin count, the command starts itself again with it set (docs/guide/busy-machines.md).
  // OpenBLAS's kernels likewise, where it took slower ones than this CPU runs (a CPU newer
  // than the OpenBLAS: femreg/blas_kernels.h).
  bool again = false;
  if (std::getenv("OMP_WAIT_POLICY") == nullptr && std::getenv("GOMP_SPINCOUNT") == nullptr &&
      setenv("OMP_WAIT_POLICY", "passive", 1) == 0) {
    again = true;
  }
  if (const char* kernels = femreg::BetterBlasCoreType()) {
    if (setenv("OPENBLAS_CORETYPE", kernels, 1) == 0) again = true;
  }
  if (again) execv("/proc/self/exe", argv);  // returns only if it failed: then on as it is
  CLI::App app{
      "femreg - physics-regularized non-rigid registration of tetrahedral meshes to point "
      "clouds.\nRun 'femreg SUBCOMMAND --help' for the options of one subcommand."};
  app.require_subcommand(1);
  app.set_version_flag("--version", std::string("femreg ") + femreg::Version());
  femreg::cli::RegisterCommands(&app);
  // The subcommands run inside parse(). Readers refuse what a file cannot hold before they
  // allocate, and return what they cannot read as a Status; what still escapes as an
  // exception (memory exhausted by a valid but huge input, a library's own throw) ends the
  // command here with a message instead of std::terminate.
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    // --help and --version as CLI11 prints them; a wrong or missing argument (a file that
    // does not exist included) named after the command, exit code 2.
    if (e.get_exit_code() == static_cast<int>(CLI::ExitCodes::Success)) return app.exit(e);
    std::cerr << CommandName(app) << ": " << e.what() << "\nRun '" << CommandName(app)
              << " --help' for its options.\n";
    return 2;
  } catch (const std::bad_alloc&) {
    std::cerr << CommandName(app) << ": out of memory (an input larger than this machine can hold?)\n";
    return 2;
  } catch (const std::length_error& e) {
    std::cerr << CommandName(app) << ": a size is too large (" << femreg::cli::CapForMessage(e.what())
              << ")\n";
    return 2;
  } catch (const std::exception& e) {
    std::cerr << CommandName(app) << ": unexpected error: " << femreg::cli::CapForMessage(e.what())
              << "\n";
    return 2;
  } catch (...) {
    std::cerr << CommandName(app) << ": unexpected error\n";
    return 2;
  }
  return femreg::cli::ExitCode();
}
