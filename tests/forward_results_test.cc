// femreg simulate's summary.json and femreg calibrate's calibration.json
// (femreg/forward_results.h), written and read back with nlohmann-json: every key there, the
// options given, and option blocks that are exactly their tables' rows (so that a row added
// to a table is written without touching the writers).
#include <gtest/gtest.h>

#include <cmath>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "femreg/forward_results.h"
#include "femreg/version.h"

namespace femreg {
namespace {

using json = nlohmann::ordered_json;  // in the order written

// The keys of a table's rows, in its order (a grouped row by its Python name, as the blocks
// write it).
template <class Options>
std::vector<std::string> TableKeys() {
  std::vector<std::string> keys;
  OptionFields<Options>::Visit(
      [&](auto, const FieldInfo& f) { keys.push_back(f.group != nullptr ? f.python_name() : f.key); });
  return keys;
}

std::vector<std::string> Keys(const json& object) {
  std::vector<std::string> keys;
  for (auto it = object.begin(); it != object.end(); ++it) keys.push_back(it.key());
  return keys;
}

TEST(SimulateSummaryJson, RecordsTheRunAndTheForwardTableWhole) {
  Scene scene;
  scene.gravity = Eigen::Vector3d(0, 0, -9.81);
  SimulateRun run;
  run.scene = "beam.yaml";
  run.overrides = {"forward.load_steps=3"};
  run.model = ElasticModelType::kNeoHookean;
  run.forward.model = ElasticModelType::kNeoHookean;
  run.forward.load_steps = 3;
  run.forward.max_iterations = 17;
  run.forward.relative_tolerance = 2.5e-7;
  run.forward.absolute_tolerance = 1e-9;
  run.forward.tangent = ForwardTangent::kProjected;
  run.total_time_s = 1.5;
  SimulateObjectResult ok;
  ok.name = "beam";
  ok.vtu = "beam.vtu";
  ok.num_vertices = 40, ok.num_tets = 60, ok.num_clamped = 8;
  ok.model = "neo_hookean", ok.volume = "element";
  ok.summary.termination = ForwardTermination::kConverged;
  ok.summary.load_steps.resize(2);
  ok.summary.load_steps[1].load_step = 2;
  ok.summary.load_steps[1].load_factor = 1.0;
  ok.summary.load_steps[1].iterations = 4;
  ok.summary.final_energy = NAN;  // JSON has no NaN: null
  ok.max_displacement = 0.012;
  ok.max_rest = Eigen::Vector3d(1, 0.05, 0.05);
  SimulateObjectResult failed;
  failed.name = "other";
  failed.error = "the solve did not reach equilibrium";

  const json j = json::parse(SimulateSummaryJson(run, scene, {ok, failed}));
  EXPECT_EQ(j["femreg_version"], Version());
  EXPECT_EQ(j["scene"], "beam.yaml");
  EXPECT_EQ(j["overrides"], json({"forward.load_steps=3"}));
  EXPECT_EQ(j["model"], "neo_hookean");
  EXPECT_EQ(j["tangent"], "projected");
  EXPECT_EQ(j["load_steps"], 3);
  EXPECT_EQ(j["max_iterations"], 17);
  EXPECT_EQ(j["gravity"], json({0.0, 0.0, -9.81}));
  EXPECT_EQ(j["total_time_s"], 1.5);
  // The forward block: every row of the table, by its scene key, with the values given.
  const json& forward = j["forward"];
  EXPECT_EQ(Keys(forward), TableKeys<ForwardOptions>());
  EXPECT_EQ(forward["model"], "neo_hookean");
  EXPECT_EQ(forward["tolerance"], 2.5e-7);
  EXPECT_EQ(forward["absolute_tolerance"], 1e-9);
  run.forward.model.reset();  // unset: null
  EXPECT_TRUE(json::parse(SimulateSummaryJson(run, scene, {}))["forward"]["model"].is_null());

  ASSERT_EQ(j["objects"].size(), 2u);
  const json& a = j["objects"][0];
  EXPECT_EQ(a["name"], "beam");
  EXPECT_EQ(a["vtu"], "beam.vtu");
  EXPECT_EQ(a["ok"], true);
  EXPECT_TRUE(a["error"].is_null());
  EXPECT_EQ(a["vertices"], 40);
  EXPECT_EQ(a["elements"], 60);
  EXPECT_EQ(a["clamped_vertices"], 8);
  EXPECT_EQ(a["model"], "neo_hookean");
  EXPECT_EQ(a["termination"], "CONVERGED");
  EXPECT_TRUE(a["final_energy"].is_null());
  EXPECT_EQ(a["max_displacement"], 0.012);
  EXPECT_EQ(a["max_displacement_rest_position"], json({1.0, 0.05, 0.05}));
  ASSERT_EQ(a["load_steps"].size(), 2u);
  EXPECT_EQ(a["load_steps"][1]["load_step"], 2);
  EXPECT_EQ(a["load_steps"][1]["load_factor"], 1.0);
  EXPECT_EQ(a["load_steps"][1]["newton_iterations"], 4);
  for (const char* key : {"load", "solve", "factorization", "write"}) EXPECT_TRUE(a["time_s"].contains(key)) << key;
  const json& b = j["objects"][1];
  EXPECT_EQ(b["ok"], false);
  EXPECT_TRUE(b["vtu"].is_null());
  EXPECT_EQ(b["error"], "the solve did not reach equilibrium");
}

TEST(CalibrationJson, RecordsTheFitAndTheCalibrationTableWhole) {
  Scene scene;
  scene.objects.resize(2);
  scene.objects[1].name = "slab";
  CalibrationOptions options;
  options.parameter = CalibrationParameter::kRegionYoungsModulus;
  options.object = 1;
  options.region = 3;
  options.grid_samples = 7;
  options.tolerance = 4e-3;
  options.loss_scale = 0.003;
  options.max_distance = 0.03;
  options.warm_start = false;
  CalibrationSummary s;
  s.termination = CalibrationTermination::kConverged;
  s.message = "converged";
  s.parameter = options.parameter;
  s.value = 2.5e5, s.initial_value = 1e5, s.lower = 1e4, s.upper = 1e6;
  s.mean_distance = 0.0015;
  s.num_points = 1200;
  s.sigma_t = 0.0;  // no width: the uncertainty is null
  s.samples.resize(1);
  s.samples[0].value = 2.5e5;
  s.samples[0].grid = true;
  s.evaluations = 1;

  const json j = json::parse(CalibrationJson({"scene.yaml", {"a.pcd", "b.pcd"}, {100, 1100}}, scene, options, s));
  EXPECT_EQ(j["scene"], "scene.yaml");
  EXPECT_EQ(j["observed"], json::parse(R"([{"file": "a.pcd", "points": 100}, {"file": "b.pcd", "points": 1100}])"));
  EXPECT_EQ(j["object"], "slab");
  EXPECT_EQ(j["parameter"], "region_E");
  EXPECT_EQ(j["region"], 3);
  // The options block: every row of the table, with the values given.
  const json& o = j["options"];
  EXPECT_EQ(Keys(o), TableKeys<CalibrationOptions>());
  EXPECT_EQ(o["parameter"], "region_E");
  EXPECT_EQ(o["object"], 1);
  EXPECT_EQ(o["grid_samples"], 7);
  EXPECT_EQ(o["tolerance"], 4e-3);
  EXPECT_EQ(o["warm_start"], false);
  EXPECT_EQ(o["min_overlap"], options.min_overlap);
  EXPECT_EQ(j["loss"], json::parse(R"({"huber_scale_m": 0.003, "max_distance_m": 0.03})"));
  EXPECT_EQ(j["termination"], "converged");
  EXPECT_EQ(j["usable"], true);
  EXPECT_EQ(j["value"], 2.5e5);
  EXPECT_EQ(j["interval"], json({1e4, 1e6}));
  EXPECT_EQ(j["misfit_mean_mm"], 1.5);
  EXPECT_EQ(j["points"], 1200);
  EXPECT_TRUE(j["uncertainty"]["sigma"].is_null());
  EXPECT_EQ(j["uncertainty"]["sigma_of"], "ln E");
  ASSERT_EQ(j["samples"].size(), 1u);
  EXPECT_EQ(j["samples"][0]["stage"], "grid");
  // Another parameter than region_E: no region.
  options.parameter = CalibrationParameter::kPoissonRatio;
  const json nu = json::parse(CalibrationJson({"scene.yaml", {}, {}}, scene, options, s));
  EXPECT_TRUE(nu["region"].is_null());
  EXPECT_EQ(nu["parameter"], "nu");
  EXPECT_EQ(nu["uncertainty"]["sigma_of"], "nu");
}

}  // namespace
}  // namespace femreg
