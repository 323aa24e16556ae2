// femreg fracture-data: writes a bundled fracture sequence (ground truth and clouds).
#include <cmath>
#include <cstdlib>
#include <fstream>
#include <iostream>
#include <map>
#include <memory>
#include <sstream>
#include <string>
#include <vector>

#include "cli_util.h"
#include "commands.h"
#include "femreg/datasets.h"

namespace femreg {
namespace cli {
namespace {
void Progress(int done, int total) {
  static std::unique_ptr<ProgressBar> bar;
  if (done == 1 || bar == nullptr) bar = std::make_unique<ProgressBar>("fracture-data", total);
  bar->Update(done);
  if (done == total) bar->Finish();
}

// A number as CalculiX prints it (a three-digit exponent may lose its 'E': 1.234-100).
double FortranNumber(const std::string& text, bool* ok) {
  std::string t = text;
  const size_t sign = t.find_first_of("+-", 1);
  if (sign != std::string::npos && t[sign - 1] != 'E' && t[sign - 1] != 'e') t.insert(sign, "E");
  char* end = nullptr;
  const double value = std::strtod(t.c_str(), &end);
  *ok = end != t.c_str() && *end == '\0';
  return value;
}

// The displacements at the end of each step of a CalculiX .dat file, in order (the deck of
// WriteFractureSequenceDeck: step f ends at total time f + 1): the last block printed at each
// whole time, one row per node (node n in row n - 1).
Status ReadStepEnds(const std::string& path, std::vector<Vertices>* out) {
  std::ifstream in(path);
  if (!in) return Status::Error(path + ": cannot read");
  std::map<long, std::map<int, Eigen::Vector3d>> at;  // step end -> its last block
  std::map<int, Eigen::Vector3d>* block = nullptr;
  std::string line;
  while (std::getline(in, line)) {
    if (line.find("displacements") != std::string::npos) {
      block = nullptr;
      const size_t t = line.find("time");
      if (t == std::string::npos) continue;
      bool ok = false;
      std::istringstream words(line.substr(t + 4));
      std::string word;
      words >> word;
      const double time = FortranNumber(word, &ok);
      const long step = std::lround(time);
      if (!ok || std::abs(time - static_cast<double>(step)) > 1e-6 || step < 1) continue;
      block = &at[step];
      block->clear();
      continue;
    }
    std::istringstream words(line);
    std::vector<std::string> parts;
    for (std::string w; words >> w;) parts.push_back(w);
    if (block == nullptr || parts.empty()) continue;
    bool ok = parts.size() == 4;
    const int node = ok ? std::atoi(parts[0].c_str()) : 0;
    ok = ok && node >= 1;
    Eigen::Vector3d u;
    for (int a = 0; a < 3 && ok; ++a) u(a) = FortranNumber(parts[static_cast<size_t>(a) + 1], &ok);
    if (!ok) {
      block = nullptr;
      continue;
    }
    (*block)[node] = u;
  }
  out->clear();
  for (const auto& [step, nodes] : at) {
    if (step != static_cast<long>(out->size()) + 1) {
      return Status::Error(path + ": no displacements at the end of step " + std::to_string(out->size() + 1));
    }
    const int n = nodes.empty() ? 0 : nodes.rbegin()->first;
    if (static_cast<int>(nodes.size()) != n) return Status::Error(path + ": step " + std::to_string(step) + " lacks nodes");
    Vertices u(n, 3);
    for (const auto& [node, d] : nodes) u.row(node - 1) = d.transpose();
    out->push_back(u);
  }
  if (out->empty()) return Status::Error(path + ": no displacements");
  return Status::Ok();
}
}  // namespace

void AddFractureDataCommand(CLI::App* app) {
  auto out = std::make_shared<std::string>();
  auto scenario = std::make_shared<std::string>();
  auto force = std::make_shared<bool>(false);
  auto deck = std::make_shared<std::string>();
  auto result = std::make_shared<std::string>();
  CLI::App* cmd = app->add_subcommand(
      "fracture-data",
      "Write a fracture sequence: beam_break (a beam bent until it breaks), slab_tear (a "
      "slab torn by two grippers), simulated with corotational FEM and the fracture model on "
      "a mesh twice as fine as the tracked one, or beam_cut (a beam bent, then cut by "
      "removing a slab of elements of a finer mesh), seen by a virtual depth camera. Writes "
      "OUT/scene.yaml, OUT/clouds/*.pcd, OUT/ground_truth/*.csv and OUT/README.md.");
  cmd->add_option("--scenario", *scenario, "beam_break, slab_tear or beam_cut")
      ->required()
      ->check(CLI::IsMember(FractureScenarios()));
  cmd->add_option("--out,-o", *out, "Output folder (not with --calculix-deck)");
  cmd->add_flag("--force", *force, "Write into a non-empty folder (the folders of frames it writes, a last run's, are removed first)");
  cmd->add_option("--calculix-deck", *deck,
                  "beam_cut only: write the ground truth's CalculiX deck (one NLGEOM step per frame, "
                  "the slab removed by *MODEL CHANGE) to this file, and nothing else");
  cmd->add_option("--calculix-result", *result,
                  "beam_cut only: take the ground truth from this .dat file (ccx's solution of the "
                  "--calculix-deck deck) instead of femreg's solve; writes beam_cut_calculix");
  cmd->callback([out, scenario, force, deck, result] {
    Status status;
    if (!deck->empty()) {
      std::ofstream file(*deck);
      status = file ? WriteFractureSequenceDeck(*scenario, file) : Status::Error(*deck + ": cannot write");
      if (status.ok()) {
        std::cout << "Wrote " << *scenario << "'s CalculiX deck to " << *deck << "\n";
        return;
      }
    } else if (out->empty()) {
      status = Status::Error("--out is required");
    } else if (!result->empty()) {
      std::vector<Vertices> truth;
      status = ReadStepEnds(*result, &truth);
      if (status.ok()) status = PrepareOutputDir(*out, *force, {"clouds", "ground_truth"});
      if (status.ok()) {
        status = GenerateFractureSequence(*scenario, *out, truth, "CalculiX's solution (`ccx`)", &Progress);
      }
    } else {
      status = PrepareOutputDir(*out, *force, {"clouds", "ground_truth"});
      if (status.ok()) status = GenerateFractureSequence(*scenario, *out, &Progress);
    }
    if (!status.ok()) {
      std::cerr << "femreg fracture-data: " << status.message() << "\n";
      SetExitCode(1);
      return;
    }
    std::cout << "Wrote " << *scenario << (result->empty() ? "" : "_calculix") << " to " << *out << "\n";
  });
}

}  // namespace cli
}  // namespace femreg
