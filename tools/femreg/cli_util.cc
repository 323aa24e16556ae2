#include "cli_util.h"

#include <sys/wait.h>
#include <time.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <cctype>
#include <cmath>
#include <csignal>
#include <cstdio>
#include <cstdint>
#include <cstdlib>
#include <filesystem>
#include <memory>
#include <sstream>

#include "femreg/experiment.h"
#include "femreg/io.h"

namespace fs = std::filesystem;

namespace femreg {
namespace cli {

std::string JsonString(const std::string& s) {
  std::string out = "\"";
  for (char c : s) {
    if (c == '"' || c == '\\') {
      out += '\\';
      out += c;
    } else if (static_cast<unsigned char>(c) < 0x20) {
      char buf[8];
      std::snprintf(buf, sizeof(buf), "\\u%04x", c);
      out += buf;
    } else {
      out += c;
    }
  }
  return out + "\"";
}

std::string JsonNumber(double v) {
  if (!std::isfinite(v)) return "null";
  char buf[64];
  std::snprintf(buf, sizeof(buf), "%.10g", v);
  return buf;
}

std::string CapForMessage(const std::string& text, size_t max_chars) {
  if (text.size() <= max_chars) return text;
  return text.substr(0, max_chars) + "... (" + std::to_string(text.size()) + " bytes)";
}

Status PrepareOutputDir(const std::string& dir, bool force, const std::vector<std::string>& owned,
                        const std::vector<std::string>& inputs) {
  std::error_code ec;
  if (fs::exists(dir, ec)) {
    if (!fs::is_directory(dir, ec)) return Status::Error(dir + ": exists and is not a folder");
    if (!fs::is_empty(dir, ec) && !force) {
      return Status::Error(dir + ": folder is not empty; pass --force to write into it anyway");
    }
    auto inside = [](const fs::path& path, const fs::path& folder) {
      std::error_code e;
      const fs::path p = fs::weakly_canonical(path, e), f = fs::weakly_canonical(folder, e);
      const auto mismatch = std::mismatch(f.begin(), f.end(), p.begin(), p.end());
      return mismatch.first == f.end();
    };
    for (const std::string& name : owned) {
      const fs::path sub = fs::path(dir) / name;
      if (!fs::is_directory(sub, ec)) continue;
      for (const std::string& input : inputs) {
        if (!input.empty() && inside(input, sub)) {
          return Status::Error(sub.string() + ": --force would remove this folder, which holds the input " + input +
                               ": write the results elsewhere (--out)");
        }
      }
    }
    for (const std::string& name : owned) {
      const fs::path sub = fs::path(dir) / name;
      if (!fs::is_directory(sub, ec)) continue;
      fs::remove_all(sub, ec);
      if (ec) return Status::Error(sub.string() + ": cannot remove the last run's files: " + ec.message());
    }
    return Status::Ok();
  }
  fs::create_directories(dir, ec);
  if (ec) return Status::Error(dir + ": cannot create: " + ec.message());
  return Status::Ok();
}

ProgressBar::ProgressBar(const std::string& label, int total, bool enabled)
    : label_(label), total_(std::max(1, total)), enabled_(enabled),
      tty_(isatty(fileno(stderr)) != 0), start_(std::chrono::steady_clock::now()) {}

void ProgressBar::Update(int done, const std::string& note) {
  if (!enabled_) return;
  const double elapsed =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count();
  const double rate = elapsed > 0 ? done / elapsed : 0.0;
  const double eta = rate > 0 ? (total_ - done) / rate : 0.0;
  if (tty_) {
    const int width = 30;
    const int filled = width * done / total_;
    std::fprintf(stderr, "\r%s [%s%s] %d/%d  %.1f frames/s  eta %.0fs  %s\033[K", label_.c_str(),
                 std::string(filled, '#').c_str(), std::string(width - filled, '.').c_str(), done,
                 total_, rate, eta, note.c_str());
    std::fflush(stderr);
  } else {
    const int decile = 10 * done / total_;
    if (decile != last_decile_) {
      last_decile_ = decile;
      std::fprintf(stderr, "%s %d/%d (%.1f frames/s) %s\n", label_.c_str(), done, total_, rate,
                   note.c_str());
    }
  }
}

void ProgressBar::Finish() {
  if (enabled_ && tty_) std::fprintf(stderr, "\n");
}

namespace {
std::unique_ptr<ProgressBar> generator_bar;
}  // namespace

void StartGeneratorProgress(const std::string& label) {
  generator_bar = std::make_unique<ProgressBar>(label, 1);  // the generator gives the total
}

void GeneratorProgress(int done, int total) {
  if (generator_bar == nullptr) return;
  generator_bar->set_total(total);
  generator_bar->Update(done);
  if (done == total) generator_bar->Finish();
}

void StopGeneratorProgress() { generator_bar.reset(); }

void AddSetOption(CLI::App* cmd, std::vector<std::string>* sets) {
  cmd->add_option("--set", *sets,
                  "Override one scene key for this run, checked like the scene file: "
                  "--set registration.solver.backend=fast --set "
                  "objects[0].material.youngs_modulus=2e5 (repeatable; the value is YAML)")
      ->type_name("KEY.PATH=VALUE")
      ->take_all()
      ->allow_extra_args(false);
}

Status LoadSceneWithSets(const std::string& path, const std::vector<std::string>& sets, Scene* scene) {
  std::vector<SceneOverride> overrides;
  for (const std::string& text : sets) {
    SceneOverride o;
    Status status = ParseSceneOverride(text, &o);
    if (!status.ok()) return status;
    overrides.push_back(o);
  }
  return LoadSceneWithOverrides(path, overrides, scene);
}

namespace {
bool IsExecutable(const fs::path& p) {
  std::error_code ec;
  return fs::is_regular_file(p, ec) && access(p.c_str(), X_OK) == 0;
}
std::string OnPath(const std::string& name) {
  const char* path = std::getenv("PATH");
  if (path == nullptr) return "";
  std::stringstream dirs(path);
  std::string dir;
  while (std::getline(dirs, dir, ':')) {
    if (dir.empty()) continue;
    const fs::path candidate = fs::path(dir) / name;
    if (IsExecutable(candidate)) return candidate.string();
  }
  return "";
}

// Whether `python` imports matplotlib (quietly: its traceback is not the user's business).
bool HasMatplotlib(const std::string& python) {
  if (python.empty() || python.find('\'') != std::string::npos) return false;
  return std::system(("'" + python + "' -c 'import matplotlib' >/dev/null 2>&1").c_str()) == 0;
}
}  // namespace

std::string FindPython() {
  const char* env = std::getenv("FEMREG_PYTHON");
  if (env != nullptr && *env != '\0') {
    const std::string p = env;
    return p.find('/') == std::string::npos ? OnPath(p) : (IsExecutable(p) ? p : "");
  }
  std::string p = OnPath("python3");
  if (p.empty()) p = OnPath("python");
  // A python3 first on PATH without matplotlib (a pyenv or virtualenv one) while the
  // system's has it (Debian's python3-matplotlib, which tools/setup.sh installs).
  const std::string system = "/usr/bin/python3";
  if (p != system && IsExecutable(system) && !HasMatplotlib(p) && HasMatplotlib(system)) return system;
  return p;
}

int RunProgram(const std::vector<std::string>& argv) {
  if (argv.empty()) return -1;
  std::vector<char*> args;
  for (const std::string& a : argv) args.push_back(const_cast<char*>(a.c_str()));
  args.push_back(nullptr);
  std::fflush(stdout);
  std::fflush(stderr);
  const pid_t pid = fork();
  if (pid < 0) return -1;
  if (pid == 0) {
    execvp(args[0], args.data());
    std::_Exit(127);
  }
  int status = 0;
  if (waitpid(pid, &status, 0) < 0) return -1;
  if (WIFEXITED(status)) return WEXITSTATUS(status) == 127 ? -1 : WEXITSTATUS(status);
  return -1;
}

namespace {
std::atomic<bool> g_interrupted{false};
std::atomic<int> g_signal{0};
std::atomic<int64_t> g_first_signal_ns{0};
// Monotonic nanoseconds (clock_gettime is async-signal-safe).
int64_t NowNs() {
  timespec t{};
  clock_gettime(CLOCK_MONOTONIC, &t);
  return static_cast<int64_t>(t.tv_sec) * 1000000000 + t.tv_nsec;
}
// The first signal asks the command to finish the frame and write its files; a second one a
// second or more later (Ctrl-C again) ends the process at once. One within the second is
// the same request: GNU timeout sends SIGTERM to the command and then to its process group,
// microseconds apart, and a handler that took the second for a "again" exited without its
// files (RegisterCommand.SigtermLeavesWholeFilesAndAnHonestSummary, now and then).
void OnInterrupt(int signal) {
  const int64_t now = NowNs();
  int64_t first = 0;
  if (!g_first_signal_ns.compare_exchange_strong(first, now)) {  // not the first
    if (now - first >= 1000000000) std::_Exit(128 + signal);
    return;
  }
  g_signal.store(signal);
  g_interrupted.store(true);
}
static_assert(std::atomic<int64_t>::is_always_lock_free, "the signal handler's clock");
}  // namespace

void InstallInterruptHandler() {
  std::signal(SIGINT, OnInterrupt);
  std::signal(SIGTERM, OnInterrupt);  // what timeout, schedulers and docker stop send
}
bool Interrupted() { return g_interrupted.load(); }
int InterruptExitCode() { return 128 + (g_signal.load() != 0 ? g_signal.load() : SIGINT); }
const char* InterruptName() { return g_signal.load() == SIGTERM ? "SIGTERM" : "SIGINT"; }

}  // namespace cli
}  // namespace femreg

namespace femreg {
namespace cli {

void PrintFractureReport(const std::vector<FractureFrame>& frames, const std::string& truth_dir,
                         bool counts_vertices) {
  int splits = 0, first_split = -1, first_break = -1;
  for (size_t f = 0; f < frames.size(); ++f) {
    splits += frames[f].splits;
    if (first_split < 0 && frames[f].splits > 0) first_split = static_cast<int>(f);
    if (first_break < 0 && frames[f].pieces >= 2) first_break = static_cast<int>(f);
  }
  std::printf("Fracture: %d %s; first split at frame %d, in pieces from frame %d", splits,
              counts_vertices ? "vertices added by splits" : "node splits", first_split, first_break);
  const std::filesystem::path events = std::filesystem::path(truth_dir) / "events.csv";
  if (!truth_dir.empty() && std::filesystem::exists(events)) {
    std::FILE* in = std::fopen(events.string().c_str(), "r");
    int gt_split = -1, gt_break = -1;
    char line[256];
    if (in != nullptr && std::fgets(line, sizeof(line), in)) {
      while (std::fgets(line, sizeof(line), in)) {
        int frame = 0, node = 0, pieces = 0;
        double nx, ny, nz, measure;
        if (std::sscanf(line, "%d,%d,%lf,%lf,%lf,%lf,%d", &frame, &node, &nx, &ny, &nz, &measure, &pieces) != 7) continue;
        if (gt_split < 0) gt_split = frame;
        if (gt_break < 0 && pieces >= 2) gt_break = frame;
      }
    }
    if (in != nullptr) std::fclose(in);
    std::printf(" (ground truth: first split at frame %d, in pieces from frame %d)", gt_split, gt_break);
  }
  std::printf("\n");
  if (first_break < 0) return;
  std::vector<double> sum, max;
  std::vector<int> count;
  for (size_t f = static_cast<size_t>(first_break); f < frames.size(); ++f) {
    const auto& pe = frames[f].piece_errors;
    for (size_t p = 0; p < pe.size(); ++p) {
      if (sum.size() <= p) {
        sum.resize(p + 1, 0.0);
        max.resize(p + 1, 0.0);
        count.resize(p + 1, 0);
      }
      sum[p] += pe[p].mean;
      max[p] = std::max(max[p], pe[p].max);
      ++count[p];
    }
  }
  for (size_t p = 0; p < sum.size(); ++p) {
    std::printf("  piece %zu after the break (%d frames): vertex error mean %.2f mm, max %.2f mm\n", p,
                count[p], 1e3 * sum[p] / std::max(count[p], 1), 1e3 * max[p]);
  }
}

}  // namespace cli
}  // namespace femreg
