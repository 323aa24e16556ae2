// femreg bench and femreg compare: settings over a dataset (with ground truth, or a
// recording without), a table, a CSV and a plot of error (or residual) against time; one
// setting per job (--setting) and the jobs' CSVs merged (--merge).
#include <cstdio>
#include <cstdlib>
#include <unistd.h>
#include <algorithm>
#include <filesystem>
#include <map>
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
  std::vector<std::string> sets;      // --set key.path=value
  bool list_settings = false;         // print the sweep's settings and stop
  std::vector<std::string> settings;  // --setting NAME_OR_INDEX: run only these
  std::vector<std::string> merge;     // shard folders or CSVs to merge into one table
};

// The plotting script: beside the sources (a build tree) or installed beside the binary.
std::string FindPlotScript() {
  std::error_code ec;
  const std::vector<fs::path> candidates = {
      fs::path(FEMREG_SOURCE_DIR) / "tools" / "plot_tradeoff.py",
      fs::read_symlink("/proc/self/exe", ec).parent_path() / ".." / "share" / "femreg" /
          "plot_tradeoff.py"};
  for (const auto& c : candidates) {
    if (fs::exists(c, ec)) return c.string();
  }
  return "";
}

std::string Mm(double metres, bool measured, int width, int precision = 2) {
  char buf[32];
  if (measured) {
    std::snprintf(buf, sizeof(buf), "%*.*f", width, precision, metres * 1e3);
  } else {
    std::snprintf(buf, sizeof(buf), "%*s", width, "n/a");
  }
  return buf;
}

void PrintTable(const std::string& title, const std::vector<Outcome>& outcomes) {
  const std::vector<int> front = ParetoFront(outcomes);
  std::printf("\n%s\n", title.c_str());
  std::printf("%-30s %7s %9s %7s %6s %9s %9s %9s %10s %10s %9s  %s\n", "setting", "verts", "ms/frame",
              "frames/s", "outer", "conv", "resid mm", "mean mm", "seen mm", "hidden mm", "max mm", "pareto");
  for (size_t i = 0; i < outcomes.size(); ++i) {
    const Outcome& o = outcomes[i];
    if (!o.error.empty()) {
      std::printf("%-30s  failed: %s\n", o.setting.c_str(), o.error.c_str());
      continue;
    }
    const bool on_front = std::find(front.begin(), front.end(), static_cast<int>(i)) != front.end();
    char conv[32];
    std::snprintf(conv, sizeof(conv), "%d/%d", o.converged, o.frames);
    std::printf("%-30s %7d %9.1f %7.1f %6.2f %9s %s %s %s %s %s  %s\n", o.setting.c_str(), o.vertices,
                o.median_ms, o.median_ms > 0 ? 1e3 / o.median_ms : 0.0, o.mean_outer_iterations, conv,
                Mm(o.median_rms_residual, true, 9, 3).c_str(), Mm(o.all_mean, o.has_truth, 9).c_str(),
                Mm(o.seen_mean, o.has_truth, 10).c_str(), Mm(o.hidden_mean, o.has_truth, 10).c_str(),
                Mm(o.all_max, o.has_truth, 9).c_str(), on_front ? "*" : "");
  }
}

std::string TableTitle(const std::string& name, const std::vector<Outcome>& outcomes) {
  const int frames = outcomes.empty() ? 0 : outcomes.front().frames;
  const bool truth = !outcomes.empty() && outcomes.front().has_truth;
  return name + " (" + std::to_string(frames) + " frames; " +
         (truth ? "errors at the dataset's vertices; * = Pareto front of time and error)"
                : "no ground truth: errors n/a; * = Pareto front of time and RMS residual)");
}

// Draws OUT/<verb>.png from the CSVs with tools/plot_tradeoff.py, when Python and
// matplotlib are there.
void Plot(const ExperimentArgs& args, bool compare, const std::vector<std::string>& csv_files) {
  const char* verb = compare ? "compare" : "bench";
  const std::string script = FindPlotScript();
  const std::string python = FindPython();
  const std::string png = (fs::path(args.out) / (std::string(verb) + ".png")).string();
  if (script.empty() || python.empty()) {
    std::fprintf(stderr, "femreg %s: no plot drawn (%s)\n", verb,
                 script.empty() ? "plot_tradeoff.py not found"
                                : "no python3 on PATH; set FEMREG_PYTHON to an interpreter with "
                                  "matplotlib");
    return;
  }
  std::vector<std::string> argv = {python, script};
  if (compare) argv.push_back("--compare");
  argv.push_back("--out");
  argv.push_back(png);
  argv.insert(argv.end(), csv_files.begin(), csv_files.end());
  const int rc = RunProgram(argv);
  if (rc != 0) {
    std::fprintf(stderr, "femreg %s: no plot drawn (%s %s exited with %d; it needs matplotlib)\n",
                 verb, python.c_str(), script.c_str(), rc);
  } else {
    std::printf("Plot: %s\n", png.c_str());
  }
}

void PrintCsvFiles(const std::vector<std::string>& csv_files) {
  std::printf("\nCSV: ");
  for (const auto& f : csv_files) std::printf("%s ", f.c_str());
  std::printf("\n");
}

// The shards' CSVs (<dataset>_<verb>.csv in each folder, or files named directly) merged
// into OUT/<dataset>_<verb>.csv per dataset, the table printed and the plot drawn.
int RunMerge(const ExperimentArgs& args, bool compare) {
  const std::string verb = compare ? "compare" : "bench";
  const std::string suffix = "_" + verb + ".csv";
  std::map<std::string, std::vector<std::string>> by_dataset;  // name -> shard CSVs
  for (const std::string& path : args.merge) {
    std::error_code ec;
    std::vector<std::string> files;
    if (fs::is_directory(path, ec)) {
      for (const auto& e : fs::directory_iterator(path, ec)) {
        const std::string n = e.path().filename().string();
        if (e.is_regular_file() && n.size() > suffix.size() &&
            n.compare(n.size() - suffix.size(), suffix.size(), suffix) == 0) {
          files.push_back(e.path().string());
        }
      }
      if (files.empty()) {
        std::cerr << "femreg " << verb << ": --merge " << path << ": no *" << suffix
                  << " in this folder\n";
        return 1;
      }
    } else if (fs::is_regular_file(path, ec)) {
      files.push_back(path);
    } else {
      std::cerr << "femreg " << verb << ": --merge " << path << ": no such file or folder\n";
      return 1;
    }
    for (const std::string& f : files) {
      std::string name = fs::path(f).filename().string();
      if (name.size() > suffix.size() &&
          name.compare(name.size() - suffix.size(), suffix.size(), suffix) == 0) {
        name.resize(name.size() - suffix.size());
      }
      by_dataset[name].push_back(f);
    }
  }
  Status status = PrepareOutputDir(args.out, args.force);
  if (!status.ok()) {
    std::cerr << "femreg " << verb << ": " << status.message() << "\n";
    return 1;
  }
  std::vector<std::string> csv_files;
  for (const auto& [name, files] : by_dataset) {
    std::vector<std::vector<Setting>> shard_settings(files.size());
    std::vector<std::vector<Outcome>> shard_outcomes(files.size());
    for (size_t k = 0; k < files.size(); ++k) {
      status = ReadOutcomesCsv(files[k], &shard_settings[k], &shard_outcomes[k]);
      if (!status.ok()) {
        std::cerr << "femreg " << verb << ": " << status.message() << "\n";
        return 1;
      }
    }
    std::vector<Setting> settings;
    std::vector<Outcome> outcomes;
    status = MergeOutcomes(shard_settings, shard_outcomes, &settings, &outcomes);
    if (!status.ok()) {
      std::cerr << "femreg " << verb << ": " << name << ": " << status.message() << "\n";
      return 1;
    }
    const std::string csv = (fs::path(args.out) / (name + suffix)).string();
    if (fs::exists(csv) && std::find(files.begin(), files.end(), csv) != files.end()) {
      std::cerr << "femreg " << verb << ": " << csv << " is a shard; merge into another folder\n";
      return 1;
    }
    status = WriteFileAtomically(csv, OutcomesCsv(settings, outcomes));
    if (!status.ok()) {
      std::cerr << "femreg " << verb << ": " << status.message() << "\n";
      return 1;
    }
    csv_files.push_back(csv);
    PrintTable(TableTitle(name, outcomes) + ", merged from " + std::to_string(files.size()) +
                   " shard(s)",
               outcomes);
  }
  PrintCsvFiles(csv_files);
  if (args.plot) Plot(args, compare, csv_files);
  return 0;
}

int RunExperiment(const ExperimentArgs& args, bool compare) {
  const char* verb = compare ? "compare" : "bench";
  if (!args.merge.empty()) {
    if (!args.datasets.empty() || !args.settings.empty() || !args.sets.empty() || args.list_settings) {
      std::cerr << "femreg " << verb << ": --merge only reads the shards' CSVs; it takes no "
                   "--dataset, --setting, --set or --list-settings\n";
      return 1;
    }
    if (args.out.empty()) {
      std::cerr << "femreg " << verb << ": --out is required\n";
      return 1;
    }
    return RunMerge(args, compare);
  }
  if (args.datasets.empty()) {
    std::cerr << "femreg " << verb << ": --dataset is required (or --merge SHARD...)\n";
    return 1;
  }
  std::vector<SceneOverride> overrides;
  for (const std::string& text : args.sets) {
    SceneOverride o;
    Status status = ParseSceneOverride(text, &o);
    if (!status.ok()) {
      std::cerr << "femreg " << verb << ": " << status.message() << "\n";
      return 1;
    }
    overrides.push_back(o);
  }
  if (args.list_settings) {
    // One line per setting: its index and name, tab-separated, for a job array or a loop.
    for (const std::string& dir : args.datasets) {
      Dataset dataset;
      Status status = LoadDataset(dir, &dataset, args.max_frames, overrides);
      if (!status.ok()) {
        std::cerr << "femreg " << verb << ": " << status.message() << "\n";
        return 1;
      }
      const std::vector<Setting> settings =
          compare ? DefaultComparison(dataset.scene) : DefaultBenchSweep(dataset.scene);
      if (args.datasets.size() > 1) std::printf("# %s\n", dataset.name.c_str());
      for (size_t i = 0; i < settings.size(); ++i) {
        std::printf("%zu\t%s\n", i, settings[i].name.c_str());
      }
    }
    return 0;
  }
  if (args.out.empty()) {
    std::cerr << "femreg " << verb << ": --out is required\n";
    return 1;
  }
  // Every dataset is loaded (and its scene checked) before anything is written.
  std::vector<Dataset> datasets(args.datasets.size());
  for (size_t d = 0; d < args.datasets.size(); ++d) {
    Status status = LoadDataset(args.datasets[d], &datasets[d], args.max_frames, overrides);
    if (!status.ok()) {
      std::cerr << "femreg " << verb << ": " << status.message() << "\n";
      return 1;
    }
  }
  Status status = PrepareOutputDir(args.out, args.force);
  if (!status.ok()) {
    std::cerr << "femreg " << verb << ": " << status.message() << "\n";
    return 1;
  }
  InstallInterruptHandler();
  std::vector<std::string> csv_files;
  for (const Dataset& dataset : datasets) {
    const std::vector<Setting> sweep =
        compare ? DefaultComparison(dataset.scene) : DefaultBenchSweep(dataset.scene);
    std::vector<Setting> settings;
    std::vector<int> indices;
    if (!args.settings.empty()) {
      status = SelectSettings(sweep, args.settings, &settings, &indices);
      if (!status.ok()) {
        std::cerr << "femreg " << verb << ": " << dataset.name << ": " << status.message() << "\n";
        return 1;
      }
    } else {
      settings = sweep;
      if (args.quick && settings.size() > 4) settings.resize(4);
      for (size_t i = 0; i < settings.size(); ++i) indices.push_back(static_cast<int>(i));
    }
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
      outcomes.back().setting_index = indices[i];
      bar.Finish();
      if (!tty) {
        if (outcomes.back().has_truth) {
          std::fprintf(stderr, "%s %.1f ms/frame, mean error %.2f mm\n", label,
                       outcomes.back().median_ms, outcomes.back().all_mean * 1e3);
        } else {
          std::fprintf(stderr, "%s %.1f ms/frame, RMS residual %.3f mm\n", label,
                       outcomes.back().median_ms, outcomes.back().median_rms_residual * 1e3);
        }
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
    PrintTable(TableTitle(dataset.name, outcomes), outcomes);
  }
  PrintCsvFiles(csv_files);
  if (args.plot) Plot(args, compare, csv_files);
  return Interrupted() ? 130 : 0;
}

void AddOptions(CLI::App* cmd, ExperimentArgs* args) {
  cmd->add_option("--dataset,-d", args->datasets,
                  "Dataset folder(s): scene.yaml, clouds/ and, when there is one, ground_truth/ "
                  "(e.g. datasets/demo); without ground truth the table has time, residuals and "
                  "convergence, and n/a for the errors")
      ->check(CLI::ExistingDirectory);
  cmd->add_option("--out,-o", args->out, "Output folder for the CSV and the plot");
  cmd->add_option("--max-frames", args->max_frames, "Use only the first N frames of each dataset");
  cmd->add_flag("--force", args->force, "Write into a non-empty output folder");
  cmd->add_flag("!--no-plot", args->plot, "Do not draw the PNG");
  cmd->add_flag("--quick", args->quick, "Only the first four settings (a smoke run)");
  AddSetOption(cmd, &args->sets);
  cmd->add_flag("--list-settings", args->list_settings,
                "Print the sweep's settings (index, tab, name) for the dataset(s) and stop");
  cmd->add_option("--setting", args->settings,
                  "Run only this setting, by name or index from --list-settings (repeatable): "
                  "one job of a sweep fanned out; merge the jobs' folders with --merge")
      ->type_name("NAME|INDEX");
  cmd->add_option("--merge", args->merge,
                  "Merge the CSVs of shard folders (or files) written by --setting jobs into "
                  "OUT/<dataset>_<verb>.csv in sweep order, with the table and the plot; runs "
                  "nothing")
      ->type_name("DIR|CSV");
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
      "OUT/bench.png (error against time, Pareto front marked). On a recording without "
      "ground truth: time, RMS residual and convergence. A sweep as one job per setting: "
      "--list-settings, then --setting N --out shards/N per job, then --merge shards/* --out OUT.");
  AddOptions(cmd, args.get());
  cmd->callback([args] { SetExitCode(RunExperiment(*args, false)); });
}

void AddCompareCommand(CLI::App* app) {
  auto args = std::make_shared<ExperimentArgs>();
  CLI::App* cmd = app->add_subcommand(
      "compare",
      "Regularizers side by side on the same sequence: data only, temporal only, a "
      "mass-spring model on the mesh edges, small-strain linear FEM, corotational FEM at "
      "several E and nu. Writes OUT/<dataset>_compare.csv and OUT/compare.png. --setting, "
      "--list-settings and --merge as for bench.");
  AddOptions(cmd, args.get());
  cmd->callback([args] { SetExitCode(RunExperiment(*args, true)); });
}

}  // namespace cli
}  // namespace femreg
