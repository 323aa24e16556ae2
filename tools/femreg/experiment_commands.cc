// femreg bench and femreg compare: settings over a dataset with ground truth, a table, a
// CSV and a plot of error against time.
#include <cstdio>
#include <cstdlib>
#include <unistd.h>
#include <filesystem>
#include <iostream>
#include <memory>
#include <string>
#include <vector>

#include "cli_util.h"
#include "commands.h"
#include "femreg/experiment.h"
#include "femreg/io.h"

namespace fs = std::filesystem;

namespace femreg {
namespace cli {
namespace {

struct ExperimentArgs {
  std::vector<std::string> datasets;
  std::string out;
  int max_frames = 0;
  bool force = false;
  bool plot = true;
  bool quick = false;
};

// The plotting script: beside the sources (a build tree) or installed beside the binary.
std::string FindPlotScript() {
  const std::vector<fs::path> candidates = {
      fs::path(FEMREG_SOURCE_DIR) / "tools" / "plot_tradeoff.py",
      fs::read_symlink("/proc/self/exe").parent_path() / ".." / "share" / "femreg" / "plot_tradeoff.py"};
  std::error_code ec;
  for (const auto& c : candidates) {
    if (fs::exists(c, ec)) return c.string();
  }
  return "";
}

void PrintTable(const std::string& title, const std::vector<Outcome>& outcomes) {
  const std::vector<int> front = ParetoFront(outcomes);
  std::printf("\n%s\n", title.c_str());
  std::printf("%-30s %7s %9s %9s %10s %10s %9s  %s\n", "setting", "verts", "ms/frame", "mean mm",
              "seen mm", "hidden mm", "max mm", "pareto");
  for (size_t i = 0; i < outcomes.size(); ++i) {
    const Outcome& o = outcomes[i];
    if (!o.error.empty()) {
      std::printf("%-30s  failed: %s\n", o.setting.c_str(), o.error.c_str());
      continue;
    }
    const bool on_front = std::find(front.begin(), front.end(), static_cast<int>(i)) != front.end();
    std::printf("%-30s %7d %9.1f %9.2f %10.2f %10.2f %9.2f  %s\n", o.setting.c_str(), o.vertices,
                o.median_ms, o.all_mean * 1e3, o.seen_mean * 1e3, o.hidden_mean * 1e3,
                o.all_max * 1e3, on_front ? "*" : "");
  }
}

int RunExperiment(const ExperimentArgs& args, bool compare) {
  const char* verb = compare ? "compare" : "bench";
  Status status = PrepareOutputDir(args.out, args.force);
  if (!status.ok()) {
    std::cerr << "femreg " << verb << ": " << status.message() << "\n";
    return 1;
  }
  InstallInterruptHandler();
  std::vector<std::string> csv_files;
  for (const std::string& dir : args.datasets) {
    Dataset dataset;
    status = LoadDataset(dir, &dataset, args.max_frames);
    if (!status.ok()) {
      std::cerr << "femreg " << verb << ": " << status.message() << "\n";
      return 1;
    }
    std::vector<Setting> settings =
        compare ? DefaultComparison(dataset.scene) : DefaultBenchSweep(dataset.scene);
    if (args.quick && settings.size() > 4) settings.resize(4);
    std::vector<Outcome> outcomes;
    for (size_t i = 0; i < settings.size(); ++i) {
      if (Interrupted()) break;
      char label[160];
      std::snprintf(label, sizeof(label), "%s [%zu/%zu] %-28s", dataset.name.c_str(), i + 1,
                    settings.size(), settings[i].name.c_str());
      // A live bar on a terminal; one line per setting in a log.
      const bool tty = isatty(fileno(stderr)) != 0;
      ProgressBar bar(label, static_cast<int>(dataset.clouds.size()), tty);
      outcomes.push_back(RunSetting(dataset, settings[i], [&bar](int done, int) { bar.Update(done); }));
      bar.Finish();
      if (!tty) {
        std::fprintf(stderr, "%s %.1f ms/frame, mean error %.2f mm\n", label,
                     outcomes.back().median_ms, outcomes.back().all_mean * 1e3);
      }
    }
    settings.resize(outcomes.size());
    const std::string csv = (fs::path(args.out) / (dataset.name + "_" + verb + ".csv")).string();
    status = WriteFileAtomically(csv, OutcomesCsv(settings, outcomes));
    if (!status.ok()) {
      std::cerr << "femreg " << verb << ": " << status.message() << "\n";
      return 1;
    }
    csv_files.push_back(csv);
    PrintTable(dataset.name + " (" + std::to_string(dataset.clouds.size()) +
                   " frames; errors at the dataset's vertices; * = Pareto front of time and error)",
               outcomes);
  }
  std::printf("\nCSV: ");
  for (const auto& f : csv_files) std::printf("%s ", f.c_str());
  std::printf("\n");
  if (args.plot) {
    const std::string script = FindPlotScript();
    std::string cmd = "/usr/bin/python3 " + script + (compare ? " --compare" : "") + " --out " +
                      (fs::path(args.out) / (std::string(verb) + ".png")).string();
    for (const auto& f : csv_files) cmd += " " + f;
    if (script.empty() || std::system(cmd.c_str()) != 0) {
      std::fprintf(stderr, "femreg %s: no plot drawn (needs tools/plot_tradeoff.py and "
                   "python3-matplotlib)\n", verb);
    } else {
      std::printf("Plot: %s\n", (fs::path(args.out) / (std::string(verb) + ".png")).string().c_str());
    }
  }
  return Interrupted() ? 130 : 0;
}

void AddOptions(CLI::App* cmd, ExperimentArgs* args) {
  cmd->add_option("--dataset,-d", args->datasets,
                  "Dataset folder(s): scene.yaml, clouds/, ground_truth/ (e.g. datasets/demo)")
      ->required()
      ->check(CLI::ExistingDirectory);
  cmd->add_option("--out,-o", args->out, "Output folder for the CSV and the plot")->required();
  cmd->add_option("--max-frames", args->max_frames, "Use only the first N frames of each dataset");
  cmd->add_flag("--force", args->force, "Write into a non-empty output folder");
  cmd->add_flag("!--no-plot", args->plot, "Do not draw the PNG");
  cmd->add_flag("--quick", args->quick, "Only the first four settings (a smoke run)");
}

}  // namespace

void AddBenchCommand(CLI::App* app) {
  auto args = std::make_shared<ExperimentArgs>();
  CLI::App* cmd = app->add_subcommand(
      "bench",
      "What accuracy costs in time: register a dataset with the scene's settings and with one "
      "parameter changed at a time (mesh resolution, outer and inner iterations, cloud "
      "subsampling, linear solver and trust region, elastic weight, Young's modulus). Writes "
      "OUT/<dataset>_bench.csv (median ms per frame, seen and hidden vertex error) and "
      "OUT/bench.png (error against time, Pareto front marked).");
  AddOptions(cmd, args.get());
  cmd->callback([args] { SetExitCode(RunExperiment(*args, false)); });
}

void AddCompareCommand(CLI::App* app) {
  auto args = std::make_shared<ExperimentArgs>();
  CLI::App* cmd = app->add_subcommand(
      "compare",
      "Regularizers side by side on the same sequence: data only, temporal only, a "
      "mass-spring model on the mesh edges, small-strain linear FEM, corotational FEM at "
      "several E and nu. Writes OUT/<dataset>_compare.csv and OUT/compare.png.");
  AddOptions(cmd, args.get());
  cmd->callback([args] { SetExitCode(RunExperiment(*args, true)); });
}

}  // namespace cli
}  // namespace femreg
