// Sweeps and provenance: --set overrides checked like the scene file, bench on a recording
// without ground truth, a sweep run one setting per job and merged, summary.json, and the
// per-vertex error and used cloud written beside each frame.
#include <gtest/gtest.h>
#include <sys/wait.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <map>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>
#include <vector>

#include "femreg/experiment.h"
#include "femreg/version.h"
#include "femreg_test_config.h"
#include "test_util.h"

namespace femreg {
namespace {

namespace fs = std::filesystem;
using testing_util::TempDir;

std::string ReadText(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

const char kScene[] = R"(# a test scene
objects:
  - name: block
    generate: {shape: box, size: [0.08, 0.08, 0.04], cells: [4, 4, 2]}
    material: {youngs_modulus: 30000, poisson_ratio: 0.35, density: 300}
registration:
  data: {visibility: false}
  solver: {max_outer_iterations: 4}
)";

class SceneOverrideTest : public ::testing::Test {
 protected:
  void SetUp() override {
    path_ = (fs::path(dir_.path()) / "scene.yaml").string();
    std::ofstream(path_) << kScene;
  }
  Status Load(const std::vector<std::string>& sets, Scene* scene) {
    std::vector<SceneOverride> overrides;
    for (const std::string& text : sets) {
      SceneOverride o;
      Status status = ParseSceneOverride(text, &o);
      if (!status.ok()) return status;
      overrides.push_back(o);
    }
    return LoadSceneWithOverrides(path_, overrides, scene);
  }
  TempDir dir_{"femreg_sweep"};
  std::string path_;
};

TEST_F(SceneOverrideTest, ReplacesAndAddsKeys) {
  Scene scene;
  ASSERT_TRUE(Load({}, &scene).ok());
  EXPECT_EQ(scene.registration.solver.max_outer_iterations, 4);
  EXPECT_EQ(scene.registration.solver.backend, SolverBackend::kFast);

  ASSERT_TRUE(Load({"registration.solver.max_outer_iterations=7",     // replaces a key
                    "registration.solver.backend=ceres",              // adds one to a map
                    "registration.weights.elastic=0.3",               // adds a map
                    "objects[0].material.youngs_modulus=2e5",         // through a list
                    "objects[0].generate.cells=[2, 2, 1]",            // a YAML list value
                    "gravity=[0, 0, -9.81]"},                         // a top-level key
                   &scene)
                  .ok());
  EXPECT_EQ(scene.registration.solver.max_outer_iterations, 7);
  EXPECT_EQ(scene.registration.solver.backend, SolverBackend::kCeres);
  EXPECT_EQ(scene.registration.weights.elastic, 0.3);  // exact: parsed from the same text
  EXPECT_EQ(scene.objects[0].material.youngs_modulus, 2e5);
  EXPECT_EQ(scene.objects[0].generate.cells, Eigen::Vector3i(2, 2, 1));
  EXPECT_EQ(scene.gravity.z(), -9.81);
  // Untouched keys keep the file's values; the later --set of the same key wins.
  EXPECT_EQ(scene.objects[0].material.poisson_ratio, 0.35);
  ASSERT_TRUE(Load({"registration.solver.max_outer_iterations=2",
                    "registration.solver.max_outer_iterations=3"},
                   &scene)
                  .ok());
  EXPECT_EQ(scene.registration.solver.max_outer_iterations, 3);
}

TEST_F(SceneOverrideTest, ErrorsNameTheKeyAndTheSet) {
  Scene scene;
  struct Case {
    std::string set;
    std::vector<std::string> expected;  // substrings of the message
  };
  const std::vector<Case> cases = {
      // A bad value: checked by the scene parser like the file's own.
      {"objects[0].material.poisson_ratio=0.5",
       {"scene.yaml:", "objects[0].material.poisson_ratio: must be in (-1, 0.5)",
        "(from --set objects[0].material.poisson_ratio=0.5)"}},
      {"registration.solver.max_outer_iterations=abc",
       {"registration.solver.max_outer_iterations", "must be an integer", "(from --set"}},
      {"registration.solver.backend=fastest",
       {"registration.solver.backend", "unknown value 'fastest'", "did you mean 'fast'"}},
      // A typo in a key: the parser's unknown-key check with its suggestion.
      {"registration.solver.max_outer_iteration=3",
       {"registration.solver.max_outer_iteration: unknown key",
        "did you mean 'max_outer_iterations'", "(from --set"}},
      {"registration.solverx.backend=fast",
       {"registration.solverx: unknown key", "did you mean 'solver'"}},
      // The path itself.
      {"objects[3].material.youngs_modulus=1", {"objects has 1 entries; [3] does not exist"}},
      {"registration[0]=1", {"registration is not a list"}},
      {"objects[0].material.youngs_modulus.x=1", {"is a value, not a map with key 'x'"}},
      {"registration..solver=1", {"empty key between dots"}},
      {"registration.solver.backend", {"expected key.path=value"}},
      {"registration.solver.backend=[fast", {"--set registration.solver.backend=[fast: the value is not valid YAML"}},
  };
  for (const Case& c : cases) {
    const Status status = Load({c.set}, &scene);
    ASSERT_FALSE(status.ok()) << c.set;
    for (const std::string& e : c.expected) {
      EXPECT_NE(status.message().find(e), std::string::npos) << c.set << "\n" << status.message();
    }
  }
  // An error in the file itself is not blamed on a --set.
  std::ofstream(path_) << std::string(kScene) + "gravity: [0, 0]\n";
  const Status status = Load({"registration.solver.backend=fast"}, &scene);
  ASSERT_FALSE(status.ok());
  EXPECT_NE(status.message().find("gravity"), std::string::npos) << status.message();
  EXPECT_EQ(status.message().find("--set"), std::string::npos) << status.message();
  // A syntax error in the file: the message LoadScene gives (file, line and column).
  std::ofstream(path_) << std::string(kScene) + "gravity: [0, 0\n";
  Scene plain;
  const Status without_sets = LoadScene(path_, &plain);
  ASSERT_FALSE(without_sets.ok());
  EXPECT_EQ(without_sets.message().rfind(path_ + ":", 0), 0u) << without_sets.message();
  EXPECT_EQ(Load({"registration.solver.backend=fast"}, &scene).message(), without_sets.message());
}

TEST(SelectSettings, ByNameOrIndexInSweepOrder) {
  Scene scene;
  scene.objects.emplace_back();
  const std::vector<Setting> sweep = DefaultBenchSweep(scene);
  ASSERT_GT(sweep.size(), 4u);
  std::vector<Setting> picked;
  std::vector<int> indices;
  ASSERT_TRUE(SelectSettings(sweep, {"3", sweep[1].name, "3"}, &picked, &indices).ok());
  ASSERT_EQ(indices, (std::vector<int>{1, 3}));
  EXPECT_EQ(picked[0].name, sweep[1].name);
  Status status = SelectSettings(sweep, {"no such"}, &picked, &indices);
  ASSERT_FALSE(status.ok());
  EXPECT_NE(status.message().find("'baseline'"), std::string::npos) << status.message();
  status = SelectSettings(sweep, {std::to_string(sweep.size())}, &picked, &indices);
  ASSERT_FALSE(status.ok());
  EXPECT_NE(status.message().find("settings 0 to"), std::string::npos) << status.message();
}

TEST(OutcomesCsv, ReadsBackWhatItWrote) {
  std::vector<Setting> settings = {{"baseline", {}, nullptr, 1.0},
                                   {"outer 2, \"quoted\"", {{"max_outer_iterations", "2"}}, nullptr, 1.0}};
  std::vector<Outcome> outcomes(2);
  outcomes[0].setting = settings[0].name;
  outcomes[0].setting_index = 0;
  outcomes[0].has_truth = true;
  outcomes[0].frames = 3;
  outcomes[0].median_ms = 12.3456;
  outcomes[0].all_mean = 1.23456e-3;
  outcomes[0].median_rms_residual = 4.5e-4;
  outcomes[1].setting = settings[1].name;
  outcomes[1].setting_index = 5;
  outcomes[1].has_truth = false;
  outcomes[1].converged = 2;
  outcomes[1].mean_outer_iterations = 2.5;
  TempDir dir("femreg_sweep");
  const std::string path = (fs::path(dir.path()) / "x_bench.csv").string();
  std::ofstream(path) << OutcomesCsv(settings, outcomes);
  std::vector<Setting> s;
  std::vector<Outcome> o;
  ASSERT_TRUE(ReadOutcomesCsv(path, &s, &o).ok());
  ASSERT_EQ(o.size(), 2u);
  EXPECT_EQ(o[1].setting, "outer 2, 'quoted'");  // quotes in names are written as '
  EXPECT_EQ(s[1].parameters.size(), 1u);
  EXPECT_EQ(o[1].setting_index, 5);
  EXPECT_FALSE(o[1].has_truth);
  EXPECT_EQ(o[1].converged, 2);
  EXPECT_TRUE(o[0].has_truth);
  // Written with 3 decimals in ms and 4 in mm: read back to within half the last digit.
  EXPECT_NEAR(o[0].median_ms, 12.3456, 0.5e-3);
  EXPECT_NEAR(o[0].all_mean, 1.23456e-3, 0.5e-7);
  EXPECT_NEAR(o[0].median_rms_residual, 4.5e-4, 0.5e-8);
  // Merging puts the shards back in sweep order and refuses a setting twice.
  Outcome like = o[1];  // the second setting as it would run beside the first
  like.has_truth = true;
  like.frames = 3;
  std::vector<Setting> ms;
  std::vector<Outcome> mo;
  ASSERT_TRUE(MergeOutcomes({{s[1]}, {s[0]}}, {{like}, {o[0]}}, &ms, &mo).ok());
  EXPECT_EQ(mo[0].setting, "baseline");
  EXPECT_EQ(ms[1].parameters.size(), 1u);
  EXPECT_FALSE(MergeOutcomes({{s[0]}, {s[0]}}, {{o[0]}, {o[0]}}, &ms, &mo).ok());
  // Shards of different runs (another frame count, or without ground truth) are refused.
  like.frames = 4;
  Status mixed = MergeOutcomes({{s[0]}, {s[1]}}, {{o[0]}, {like}}, &ms, &mo);
  ASSERT_FALSE(mixed.ok());
  EXPECT_NE(mixed.message().find("ran 4 frames with ground truth"), std::string::npos)
      << mixed.message();
  mixed = MergeOutcomes({{s[0]}, {s[1]}}, {{o[0]}, {o[1]}}, &ms, &mo);
  ASSERT_FALSE(mixed.ok());
  EXPECT_NE(mixed.message().find("without ground truth"), std::string::npos) << mixed.message();
  // A file that is not such a CSV is named with its line.
  std::ofstream(path) << "setting,vertices\n\"a\",1\n";
  const Status status = ReadOutcomesCsv(path, &s, &o);
  ASSERT_FALSE(status.ok());
  EXPECT_NE(status.message().find(path + ":1: column"), std::string::npos) << status.message();
}

#ifdef FEMREG_CLI_PATH
int RunShell(const std::string& command) {
  const int status = std::system(command.c_str());
  return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
}

// Rows of a bench/compare CSV by setting name, each a column -> text map.
std::map<std::string, std::map<std::string, std::string>> ReadCsv(const fs::path& path) {
  std::map<std::string, std::map<std::string, std::string>> rows;
  std::ifstream in(path);
  std::string header_line, line;
  std::getline(in, header_line);
  std::vector<std::string> header;
  std::stringstream hs(header_line);
  for (std::string h; std::getline(hs, h, ',');) header.push_back(h);
  while (std::getline(in, line)) {
    // Setting names and messages are quoted; the tests' settings have no comma in them.
    std::vector<std::string> fields;
    std::stringstream ls(line);
    for (std::string f; std::getline(ls, f, ',');) fields.push_back(f);
    if (!line.empty() && line.back() == ',') fields.emplace_back();
    std::map<std::string, std::string> row;
    for (size_t i = 0; i < header.size() && i < fields.size(); ++i) row[header[i]] = fields[i];
    rows[row["setting"]] = row;
  }
  return rows;
}

const std::string kCli = FEMREG_CLI_PATH;
const std::string kBlock = std::string(FEMREG_DATASETS_DIR) + "/block_press";

TEST(SweepCli, SetOnRegisterAndSimulateIsCheckedLikeTheFile) {
  TempDir dir("femreg_sweep");
  const fs::path err = fs::path(dir.path()) / "err.txt";
  EXPECT_EQ(RunShell(kCli + " register --scene " + kBlock + "/scene.yaml --frames " + kBlock +
                "/clouds --out " + dir.path() + "/r --set registration.weights.elastc=2 2> " +
                err.string()),
            1);
  std::string message = ReadText(err);
  EXPECT_NE(message.find("registration.weights.elastc: unknown key (did you mean 'elastic'?)"),
            std::string::npos)
      << message;
  EXPECT_FALSE(fs::exists(fs::path(dir.path()) / "r"));  // nothing written

  const std::string beam = std::string(FEMREG_DATASETS_DIR) + "/beam/beam.yaml";
  EXPECT_EQ(RunShell(kCli + " simulate " + beam + " --out " + dir.path() + "/s --set forward.load_steps=0 2> " +
                err.string()),
            1);
  message = ReadText(err);
  EXPECT_NE(message.find("forward.load_steps"), std::string::npos) << message;
  EXPECT_NE(message.find("(from --set forward.load_steps=0)"), std::string::npos) << message;
  // A valid override changes the run: three load steps instead of the file's two.
  ASSERT_EQ(RunShell(kCli + " simulate " + beam + " --out " + dir.path() + "/s --set forward.load_steps=3 > " +
                err.string() + " 2>&1"),
            0)
      << ReadText(err);
  const std::string json = ReadText(fs::path(dir.path()) / "s" / "summary.json");
  EXPECT_NE(json.find("\"load_steps\": 3"), std::string::npos) << json;
  const nlohmann::json parsed = nlohmann::json::parse(json);
  EXPECT_EQ(parsed["overrides"], nlohmann::json::array({"forward.load_steps=3"}));
  EXPECT_EQ(parsed["femreg_version"], Version());
}

// One frame registered with ground truth: the VTU carries the per-vertex error, the cloud
// the tracker used is written beside it, and summary.json says what ran.
TEST(SweepCli, RegisterWritesErrorFieldCloudAndProvenance) {
  TempDir dir("femreg_sweep");
  const fs::path out = fs::path(dir.path()) / "r";
  const fs::path log = fs::path(dir.path()) / "log.txt";
  ASSERT_EQ(RunShell(kCli + " register --scene " + kBlock + "/scene.yaml --frames " + kBlock +
                "/clouds --ground-truth " + kBlock + "/ground_truth --max-frames 2 --no-progress "
                "--report none --set registration.solver.backend=ceres --set "
                "registration.solver.max_outer_iterations=3 --out " + out.string() + " > " +
                log.string() + " 2>&1"),
            0)
      << ReadText(log);
  const std::string vtu = ReadText(out / "frames" / "block_0001.vtu");
  EXPECT_NE(vtu.find("Name=\"error\""), std::string::npos);
  EXPECT_NE(vtu.find("Name=\"error_vector\""), std::string::npos);
  const std::string vtp = ReadText(out / "frames" / "cloud_0001.vtp");
  ASSERT_EQ(vtp.rfind("<?xml", 0), 0u);
  EXPECT_NE(vtp.find("type=\"PolyData\""), std::string::npos);
  EXPECT_NE(ReadText(out / "cloud.pvd").find("frames/cloud_0001.vtp"), std::string::npos);

  const nlohmann::json s = nlohmann::json::parse(ReadText(out / "summary.json"));
  // Fields that scripts read (tools/contact_tables.py, the docs' tables) stay.
  for (const char* key : {"scene", "frames_done", "frames_usable", "regularizer", "objects",
                          "solver", "ms_per_frame_median", "frames_per_second", "vertex_error_mm"}) {
    EXPECT_TRUE(s.contains(key)) << key;
  }
  EXPECT_EQ(s["frames_done"], 2);
  EXPECT_EQ(s["femreg_version"], Version());
  EXPECT_EQ(s["backend"], "ceres");
  EXPECT_EQ(s["backends_used"], nlohmann::json::array({"ceres"}));
  const nlohmann::json& p = s["provenance"];
  EXPECT_EQ(p["femreg_version"], Version());
  EXPECT_EQ(p["overrides"].size(), 2u);
  EXPECT_EQ(p["options"]["solver"]["max_outer_iterations"], 3);
  EXPECT_EQ(p["options"]["data"]["visibility"], true);  // from the scene file
  ASSERT_EQ(p["frame_files"].size(), 2u);
  EXPECT_NE(p["frame_files"][1].get<std::string>().find("frame_0001.pcd"), std::string::npos);
  EXPECT_EQ(p["ground_truth_files"].size(), 2u);
  EXPECT_NE(p["scene_resolved"].get<std::string>().find("backend: ceres"), std::string::npos)
      << p["scene_resolved"];
  // The error field agrees with the run's totals: the mean over vertices of frame 1 is in
  // stats.csv; here only its presence and the max of the totals are checked by value.
  EXPECT_GT(s["vertex_error_mm"]["max"].get<double>(), 0.0);
}

// The "must show" of the issue: a 4-setting sweep run as 4 separate jobs (--setting N, one
// output folder each) and merged gives the same table as one bench run of those settings.
TEST(SweepCli, FourJobsMergedEqualOneRun) {
  TempDir dir("femreg_sweep");
  const fs::path root(dir.path());
  const std::string common = " --dataset " + kBlock + " --max-frames 3 --no-plot";
  const fs::path log = root / "log.txt";
  ASSERT_EQ(RunShell(kCli + " bench" + common + " --quick --out " + (root / "one").string() + " > " +
                log.string() + " 2>&1"),
            0)
      << ReadText(log);
  std::string shards;
  for (int i = 0; i < 4; ++i) {
    const fs::path shard = root / "shards" / std::to_string(i);
    ASSERT_EQ(RunShell(kCli + " bench" + common + " --setting " + std::to_string(i) + " --out " +
                  shard.string() + " > " + log.string() + " 2>&1"),
              0)
        << ReadText(log);
    shards = " " + shard.string() + shards;  // last first: the merge restores sweep order
  }
  // The merge runs nothing: it reads the shards' CSVs, in any order.
  ASSERT_EQ(RunShell(kCli + " bench --no-plot --merge" + shards + " --out " +
                (root / "merged").string() + " > " + log.string() + " 2>&1"),
            0)
      << ReadText(log);
  EXPECT_NE(ReadText(log).find("merged from 4 shard(s)"), std::string::npos) << ReadText(log);
  const auto one = ReadCsv(root / "one" / "block_press_bench.csv");
  const auto merged = ReadCsv(root / "merged" / "block_press_bench.csv");
  ASSERT_EQ(one.size(), 4u);
  ASSERT_EQ(merged.size(), one.size());
  for (const auto& [name, row] : one) {
    ASSERT_TRUE(merged.count(name)) << name;
    const auto& m = merged.at(name);
    // Counts are exact; the errors and residuals come from the same deterministic solve
    // (one thread, same binary and inputs) and are printed with 4-5 decimals in mm, so they
    // agree to the printed digit; 2e-4 mm allows one unit of rounding in the last digit
    // should a platform's libm differ by an ulp. Times are measured, not compared.
    for (const char* exact : {"setting_index", "vertices", "elements", "frames", "usable", "converged"}) {
      EXPECT_EQ(row.at(exact), m.at(exact)) << name << " " << exact;
    }
    for (const char* col : {"err_mean_mm", "err_seen_mean_mm", "err_hidden_mean_mm", "err_max_mm",
                            "median_rms_residual_mm", "mean_outer_iterations"}) {
      EXPECT_NEAR(std::stod(row.at(col)), std::stod(m.at(col)), 2e-4) << name << " " << col;
    }
  }
  // The merged file is in sweep order.
  const std::string merged_text = ReadText(root / "merged" / "block_press_bench.csv");
  EXPECT_LT(merged_text.find("\"baseline\""), merged_text.find("\"resolution x0.5\""));
  // A setting in two shards is refused.
  EXPECT_EQ(RunShell(kCli + " bench --no-plot --merge" + shards + " " + (root / "shards" / "0").string() +
                " --out " + (root / "twice").string() + " > " + log.string() + " 2>&1"),
            1);
  EXPECT_NE(ReadText(log).find("in two shards"), std::string::npos) << ReadText(log);
}

// A recording without ground truth: bench and compare run and report time, residual and
// convergence, with the accuracy columns empty (n/a in the table).
TEST(SweepCli, BenchAndCompareWithoutGroundTruth) {
  TempDir dir("femreg_sweep");
  const fs::path rec = fs::path(dir.path()) / "recording";
  fs::create_directories(rec);
  fs::copy_file(kBlock + "/scene.yaml", rec / "scene.yaml");
  fs::copy(kBlock + "/clouds", rec / "clouds");
  const fs::path log = fs::path(dir.path()) / "log.txt";

  ASSERT_EQ(RunShell(kCli + " bench --dataset " + rec.string() + " --list-settings > " + log.string()), 0);
  const std::string listing = ReadText(log);
  EXPECT_EQ(listing.rfind("0\tbaseline\n", 0), 0u) << listing;

  // A nonexistent interpreter in FEMREG_PYTHON: no plot, said so, and the run still succeeds.
  ASSERT_EQ(RunShell("FEMREG_PYTHON=/nonexistent/python " + kCli + " bench --dataset " + rec.string() +
                " --max-frames 2 --setting baseline --setting 'outer 1' --out " +
                (fs::path(dir.path()) / "b").string() + " > " + log.string() + " 2>&1"),
            0)
      << ReadText(log);
  const std::string text = ReadText(log);
  EXPECT_NE(text.find("no ground truth"), std::string::npos) << text;
  EXPECT_NE(text.find("n/a"), std::string::npos) << text;
  EXPECT_NE(text.find("no plot drawn"), std::string::npos) << text;
  const auto rows = ReadCsv(fs::path(dir.path()) / "b" / "recording_bench.csv");
  ASSERT_EQ(rows.size(), 2u);
  for (const auto& [name, row] : rows) {
    EXPECT_EQ(row.at("err_mean_mm"), "") << name;
    EXPECT_EQ(row.at("frames"), "2") << name;
    EXPECT_GT(std::stod(row.at("median_rms_residual_mm")), 0.0) << name;
    EXPECT_GE(std::stod(row.at("mean_outer_iterations")), 1.0) << name;
  }
  EXPECT_EQ(rows.at("\"outer 1\"").at("mean_outer_iterations"), "1.000");

  ASSERT_EQ(RunShell(kCli + " compare --no-plot --dataset " + rec.string() +
                " --max-frames 1 --setting 'linear FEM' --out " +
                (fs::path(dir.path()) / "c").string() + " > " + log.string() + " 2>&1"),
            0)
      << ReadText(log);
  EXPECT_EQ(ReadCsv(fs::path(dir.path()) / "c" / "recording_compare.csv").size(), 1u);
}
#endif  // FEMREG_CLI_PATH

}  // namespace
}  // namespace femreg
