// femreg simulate's summary.json and femreg calibrate's calibration.json; see
// femreg/forward_results.h.
#include "femreg/forward_results.h"

#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "femreg/version.h"
#include "results/provenance.h"

namespace femreg {

namespace {

using json = nlohmann::ordered_json;
using results_internal::Number;
using results_internal::Vector;

// A file name or message that is not UTF-8 must not fail the write: its bytes are replaced.
std::string Dump(const json& j) { return j.dump(2, ' ', false, json::error_handler_t::replace) + "\n"; }

json OrNull(const std::string& s) { return s.empty() ? json(nullptr) : json(s); }

// Per load step: [{"load_step": 1, "load_factor": 0.5, "termination": ..., ...}, ...].
json LoadStepsJson(const ForwardSummary& s) {
  json steps = json::array();
  for (const ForwardLoadStep& step : s.load_steps) {
    steps.push_back({{"load_step", step.load_step},
                     {"load_factor", Number(step.load_factor)},
                     {"termination", ToString(step.termination)},
                     {"newton_iterations", step.iterations},
                     {"projected_iterations", step.projected_iterations},
                     {"relaxed_steps", step.relaxed_steps},
                     {"watchdog_restarts", step.watchdog_restarts},
                     {"initial_residual", Number(step.initial_residual_norm)},
                     {"final_residual", Number(step.final_residual_norm)}});
  }
  return steps;
}

json SimulateObjectJson(const SimulateObjectResult& r) {
  const ForwardSummary& s = r.summary;
  return {{"name", r.name},
          {"vtu", OrNull(r.vtu)},
          {"ok", r.error.empty()},
          {"error", OrNull(r.error)},
          {"vertices", r.num_vertices},
          {"elements", r.num_tets},
          {"model", r.model},
          {"volume", r.volume},
          {"clamped_vertices", r.num_clamped},
          {"prescribed_vertices", r.num_prescribed},
          {"loaded_vertices", r.num_loaded},
          {"termination", ToString(s.termination)},
          {"message", s.message},
          {"iterations", s.NumNewtonIterations()},
          {"load_steps", LoadStepsJson(s)},
          {"free_dofs", s.num_free_dofs},
          {"initial_residual", Number(s.initial_residual_norm)},
          {"final_residual", Number(s.final_residual_norm)},
          {"final_energy", Number(s.final_energy)},
          {"max_displacement", Number(r.max_displacement)},
          {"inverted_elements", s.inverted_elements},
          {"max_displacement_vertex", r.max_vertex},
          {"max_displacement_rest_position", Vector(r.max_rest)},
          {"free_end_vertex", r.end_vertex},
          {"free_end_displacement", Vector(r.end_displacement)},
          {"max_at_free_end", r.max_at_free_end},
          {"time_s",
           {{"load", Number(r.load_time_s)},
            {"solve", Number(r.solve_time_s)},
            {"factorization", Number(s.factorization_time_s)},
            {"write", Number(r.write_time_s)}}},
          {"threads", s.num_threads}};
}

json SamplesJson(const CalibrationSummary& s) {
  json samples = json::array();
  for (const CalibrationSample& c : s.samples) {
    samples.push_back({{"value", Number(c.value)},
                       {"objective", Number(c.objective)},
                       {"far_objective", Number(c.far_objective)},
                       {"mean_mm", Number(c.mean_distance * 1e3)},
                       {"rms_mm", Number(c.rms_distance * 1e3)},
                       {"inlier_fraction", Number(c.inlier_fraction)},
                       {"newton_iterations", c.newton_iterations},
                       {"time_s", Number(c.time_s)},
                       {"stage", c.grid ? "grid" : "golden"}});
  }
  return samples;
}

}  // namespace

std::string SimulateSummaryJson(const SimulateRun& run, const Scene& scene,
                                const std::vector<SimulateObjectResult>& objects) {
  // The forward solve's options by their table (the same keys as a register run's
  // provenance.scene_options.forward); the flat keys below echo it.
  const json forward = results_internal::FieldsJson(run.forward);
  json j;
  j["femreg_version"] = Version();
  j["scene"] = run.scene;
  j["overrides"] = run.overrides;
  j["model"] = ToString(run.model);
  j["tangent"] = ToString(run.forward.tangent);  // the command line's, not a scene key
  j["load_steps"] = forward.at("load_steps");
  j["max_iterations"] = forward.at("max_iterations");
  j["gravity"] = Vector(scene.gravity);
  j["forward"] = forward;
  json list = json::array();
  for (const SimulateObjectResult& r : objects) list.push_back(SimulateObjectJson(r));
  j["objects"] = list;
  j["total_time_s"] = Number(run.total_time_s);
  return Dump(j);
}

std::string CalibrationJson(const CalibrationRun& run, const Scene& scene, const CalibrationOptions& options,
                            const CalibrationSummary& s) {
  const json table = results_internal::FieldsJson(options);
  const bool width = s.sigma_t > 0;
  auto if_width = [width](double v) { return width ? Number(v) : json(nullptr); };
  json j;
  j["femreg_version"] = Version();
  j["scene"] = run.scene;
  json observed = json::array();
  for (size_t i = 0; i < run.observed.size(); ++i) {
    observed.push_back({{"file", run.observed[i]}, {"points", i < run.points.size() ? run.points[i] : 0}});
  }
  j["observed"] = observed;
  const bool object_known = options.object >= 0 && options.object < static_cast<int>(scene.objects.size());
  j["object"] = object_known ? json(scene.objects[options.object].name) : json(nullptr);
  j["parameter"] = table.at("parameter");
  j["region"] = options.parameter == CalibrationParameter::kRegionYoungsModulus ? table.at("region") : json(nullptr);
  j["options"] = table;
  j["termination"] = ToString(s.termination);
  j["message"] = s.message;
  j["usable"] = s.IsSolutionUsable();
  j["value"] = Number(s.value);
  j["initial_value"] = Number(s.initial_value);
  j["interval"] = {Number(s.lower), Number(s.upper)};
  j["misfit_mean_mm"] = Number(s.mean_distance * 1e3);
  j["misfit_rms_mm"] = Number(s.rms_distance * 1e3);
  j["objective"] = Number(s.objective);
  j["inlier_fraction"] = Number(s.inlier_fraction);
  j["points"] = s.num_points;
  j["uncertainty"] = {{"sigma", if_width(s.sigma_t)},
                      {"sigma_of", options.parameter == CalibrationParameter::kPoissonRatio ? "nu" : "ln E"},
                      {"one_sigma", {if_width(s.value_low), if_width(s.value_high)}},
                      {"rms_within_10_percent", {if_width(s.width_low), if_width(s.width_high)}}};
  j["loss"] = {{"huber_scale_m", table.at("loss_scale")}, {"max_distance_m", table.at("max_distance")}};
  j["evaluations"] = s.evaluations;
  j["newton_iterations"] = s.newton_iterations;
  j["time_s"] = Number(s.total_time_s);
  j["forward_time_s"] = Number(s.forward_time_s);
  j["samples"] = SamplesJson(s);
  return Dump(j);
}

}  // namespace femreg
