// summary.json: the run's totals and what it ran; see femreg/results.h.
#include <algorithm>
#include <cmath>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "femreg/collision.h"
#include "femreg/results.h"
#include "femreg/version.h"
#include "io/io_internal.h"
#include "results/provenance.h"

namespace fs = std::filesystem;

namespace femreg {

namespace {

// Per frame, the contact forces per object pair and obstacle (N): on `object` by `by`.
nlohmann::ordered_json ContactForcesJson(const Scene& scene, const Tracker& tracker,
                                         const std::vector<FrameRecord>& rows) {
  using json = nlohmann::ordered_json;
  auto number = [](double v) { return std::isfinite(v) ? json(v) : json(nullptr); };
  auto object_name = [&](int i) {
    return i >= 0 && i < static_cast<int>(scene.objects.size()) ? scene.objects[i].name : std::to_string(i);
  };
  const CollisionWorld* world = tracker.collision();
  json frames = json::array();
  for (const FrameRecord& r : rows) {
    json list = json::array();
    for (const ContactForce& f : r.summary.contact_forces) {
      const int o = -1 - f.other;
      const std::string by = !f.obstacle() ? object_name(f.other)
                             : world != nullptr && o < world->num_obstacles() ? world->obstacle_name(o)
                                                                              : "obstacle " + std::to_string(o);
      list.push_back({{"object", object_name(f.object)},
                      {"by", by},
                      {"obstacle", f.obstacle()},
                      {"contacts", f.contacts},
                      {"force_N", {number(f.force.x()), number(f.force.y()), number(f.force.z())}},
                      {"friction_N", {number(f.friction.x()), number(f.friction.y()), number(f.friction.z())}}});
    }
    frames.push_back(list);
  }
  return frames;
}

}  // namespace

std::string SummaryJson(const RunInputs& run, const Scene& scene, const Tracker& tracker,
                        const std::vector<FrameRecord>& rows) {
  using json = nlohmann::ordered_json;
  auto number = [](double v) { return std::isfinite(v) ? json(v) : json(nullptr); };
  const RunTotals t = ComputeRunTotals(rows);
  int unreadable = 0;
  double voxel = 0.0, coverage = 1.0;
  std::string visibility = "none";
  for (const FrameRecord& r : rows) {
    if (!r.read_error.empty()) {
      ++unreadable;
      continue;
    }
    voxel = std::max(voxel, r.summary.voxel_size);
    if (r.summary.outer_iterations > 0) {
      coverage = std::min(coverage, r.summary.coverage);
      visibility = r.summary.visibility;
    }
  }
  const RegistrationOptions& o = tracker.options();
  // The options the blocks below echo, from their tables (the same as provenance.options).
  const json options = results_internal::RegistrationOptionsJson(o);
  json j;
  j["femreg_version"] = Version();
  j["scene"] = run.scene;
  j["frames_source"] = run.frames_source;
  j["frames_total"] = run.frame_files.size();
  j["frames_done"] = t.frames;
  j["interrupted"] = run.interrupted;
  if (run.interrupted) j["interrupted_by"] = run.interrupted_by;
  j["frames_usable"] = t.usable;
  j["frames_unreadable"] = unreadable;
  // How the clouds were used: the automatic subsampling's voxel (0: none), how visibility
  // was decided (the last solved frame) and the smallest coverage of the surface.
  j["clouds"] = {{"auto_voxel_m", number(voxel)},
                 {"visibility", visibility},
                 {"reciprocity", options["data"]["reciprocity"]},
                 {"min_coverage", number(coverage)}};
  j["regularizer"] = options["regularizer"];
  j["backend"] = options["solver"]["backend"];
  // What solved the frames (a contact scene runs on Ceres whatever the option says).
  json used = json::array();
  for (const FrameRecord& r : rows) {
    const std::string b = ToString(r.summary.backend);
    if (std::find(used.begin(), used.end(), b) == used.end()) used.push_back(b);
  }
  j["backends_used"] = used;
  json objects = json::array();
  Scene chosen = scene;  // the element and nu the tracker used (Tracker::Create)
  ChooseRegistrationElements(&chosen);
  for (size_t i = 0; i < scene.objects.size(); ++i) {
    const TetMesh& m = tracker.mesh(static_cast<int>(i));
    json object = {{"name", scene.objects[i].name}, {"vertices", m.num_vertices()}, {"tetrahedra", m.num_tets()}};
    object.update(results_internal::MaterialJson(scene.objects[i].material));  // as the scene gives it
    object["element"] = ToString(chosen.objects[i].Model());
    object["elastic_poisson_ratio"] = number(chosen.objects[i].material.poisson_ratio);
    objects.push_back(object);
  }
  j["objects"] = objects;
  // The solver's options by their table (the same keys as provenance.options.solver).
  j["solver"] = options["solver"];
  // How the first frame was posed (registration.initial_pose; FrameSummary::initial_pose).
  if (!rows.empty()) {
    const FrameSummary& first = rows.front().summary;
    j["initial_pose"] = {{"option", options["initial_pose"]},
                         {"chosen", first.initial_pose.empty() ? "given" : first.initial_pose},
                         {"ambiguous", first.pose_ambiguous},
                         {"first_frame_ms", number(first.time.total * 1e3)}};
  }
  if (!tracker.original_vertices(0).empty()) {
    // Fracture: the pieces at the end, the frame the body first came apart in (null: never),
    // the node splits, and after the break the mean error per piece over the frames.
    int splits = 0, break_frame = -1, pieces = 1;
    std::vector<double> sum, sum_seen, sum_hidden;
    std::vector<int> n, n_seen, n_hidden;
    for (const FrameRecord& r : rows) {
      splits += static_cast<int>(r.summary.fractures.size());
      pieces = r.pieces;
      if (break_frame < 0) break_frame = r.break_frame;
      if (r.break_frame < 0) continue;
      auto add = [](const std::vector<ErrorStats>& stats, std::vector<double>* s, std::vector<int>* c) {
        if (s->size() < stats.size()) {
          s->resize(stats.size(), 0.0);
          c->resize(stats.size(), 0);
        }
        for (size_t p = 0; p < stats.size(); ++p) {
          (*s)[p] += stats[p].mean * stats[p].count;
          (*c)[p] += stats[p].count;
        }
      };
      add(r.piece_errors, &sum, &n);
      add(r.piece_seen, &sum_seen, &n_seen);
      add(r.piece_hidden, &sum_hidden, &n_hidden);
    }
    auto means = [&](const std::vector<double>& s, const std::vector<int>& c) {
      json list = json::array();
      for (size_t p = 0; p < s.size(); ++p) list.push_back(c[p] > 0 ? number(1e3 * s[p] / c[p]) : json(nullptr));
      return list;
    };
    j["fracture"] = {{"pieces", pieces},
                     {"break_frame", break_frame >= 0 ? json(break_frame) : json(nullptr)},
                     {"splits", splits},
                     // Pieces in ConnectedPieces order (by their lowest vertex).
                     {"piece_error_after_break_mm",
                      {{"mean", means(sum, n)}, {"seen", means(sum_seen, n_seen)}, {"hidden", means(sum_hidden, n_hidden)}}}};
  }
  j["ms_per_frame_median"] = number(t.median_ms);
  j["ms_per_frame_mean"] = number(t.mean_ms);
  j["frames_per_second"] = number(t.fps);
  if (t.have_errors) {
    j["vertex_error_mm"] = {{"mean", number(t.err_mean * 1e3)},
                            {"max", number(t.err_max * 1e3)},
                            {"seen_mean", number(t.seen_mean * 1e3)},
                            {"seen_max", number(t.seen_max * 1e3)},
                            {"hidden_mean", number(t.hidden_mean * 1e3)},
                            {"hidden_max", number(t.hidden_max * 1e3)}};
  }
  {
    // registration.forces, and the external forces' resultant per frame (N): what the run
    // estimated (or, without forces.estimate, the data term's pull).
    json forces = json::array();
    for (const FrameRecord& r : rows) {
      const FrameSummary& s = r.summary;
      json frame = {{"force_N", {number(s.force.x()), number(s.force.y()), number(s.force.z())}},
                    {"torque_Nm", {number(s.torque.x()), number(s.torque.y()), number(s.torque.z())}}};
      frame["estimated"] = s.forces_estimated;
      frame["quiet_start"] = s.quiet_start;
      if (s.force_weight > 0.0) {  // estimated: the penalty's weight and the misfit it left
        frame["weight"] = number(s.force_weight);
        frame["misfit_ratio"] = number(s.misfit_ratio);
      }
      forces.push_back(frame);
    }
    j["forces"] = options["forces"];
    j["forces"]["per_frame"] = forces;
  }
  {
    // How far each frame can be trusted, and the frames where the object was lost.
    json confidence = json::array(), lost = json::array();
    for (size_t i = 0; i < rows.size(); ++i) {
      confidence.push_back(number(rows[i].summary.confidence.confidence));
      if (rows[i].summary.lost) lost.push_back(i);
    }
    j["tracking"] = {{"confidence_per_frame", confidence}, {"lost_frames", lost}};
  }
  {
    // registration.free_space, and the surface vertices it held back per frame.
    json held = json::array();
    for (const FrameRecord& r : rows) held.push_back(r.summary.free_space_vertices);
    j["free_space"] = options["free_space"];
    j["free_space"]["vertices_per_frame"] = held;
  }
  double deepest = 0.0;
  int contacts = 0;
  json gaps = json::array(), penetrations = json::array();
  for (const FrameRecord& r : rows) {
    deepest = std::max(deepest, r.summary.max_penetration);
    contacts = std::max(contacts, r.summary.contacts);
    gaps.push_back(number(r.summary.min_gap * 1e3));
    penetrations.push_back(number(r.summary.max_penetration * 1e3));
  }
  if (contacts > 0 || deepest > 0) {
    // Per frame from the same signed gaps: penetration_mm = max(0, -min_gap_mm).
    j["contacts"] = {{"max_per_frame", contacts},
                     {"max_penetration_mm", number(deepest * 1e3)},
                     {"min_gap_mm", gaps},
                     {"penetration_mm", penetrations},
                     {"collision", tracker.collision() != nullptr},
                     {"forces_per_frame", ContactForcesJson(scene, tracker, rows)}};
  }
  json flags = {{"no_collision", run.no_collision}, {"max_frames", run.max_frames},
                {"threads", run.threads}, {"depth_scale", run.depth_scale},
                {"mask_dir", run.mask_dir.empty() ? json(nullptr) : json(run.mask_dir)},
                {"intrinsics", run.intrinsics.empty() ? json(nullptr) : json(run.intrinsics)}};
  j["command_line"] = flags;
  j["provenance"] = results_internal::ProvenanceJson(scene, o, run.overrides, run.frame_files, run.truth_files);
  std::error_code ec;
  const fs::path tum_list = run.tum_list.empty() ? fs::path() : fs::absolute(run.tum_list, ec).lexically_normal();
  j["provenance"]["tum_list"] = run.tum_list.empty() ? json(nullptr) : json(ec ? run.tum_list : tum_list.string());
  // A file name or description that is not UTF-8 must not end the run: replace its bytes.
  return j.dump(2, ' ', false, json::error_handler_t::replace) + "\n";
}

namespace {

// A run's summary.json, parsed; an error names the file.
Status ParseSummary(const std::string& path, nlohmann::json* summary) {
  // A long run's summary (a row of contact forces per frame) is megabytes, never gigabytes.
  constexpr std::streamoff kMaxSummaryBytes = std::streamoff(1) << 30;
  std::string text;
  if (Status read = internal::ReadSmallFile(path, kMaxSummaryBytes, "a run's summary.json", &text); !read.ok()) {
    return read;
  }
  *summary = nlohmann::json::parse(text, nullptr, /*allow_exceptions=*/false);
  if (summary->is_discarded()) {
    return Status::Error(path + ": not JSON (not a summary.json written by femreg register)");
  }
  if (!summary->is_object()) {
    return Status::Error(path + ": JSON, but not an object (not a summary.json written by femreg register)");
  }
  return Status::Ok();
}

}  // namespace

Status ReadSummaryObjectNames(const std::string& path, std::vector<std::string>* names) {
  names->clear();
  nlohmann::json summary;
  if (Status parsed = ParseSummary(path, &summary); !parsed.ok()) return parsed;
  if (!summary.contains("objects") || !summary["objects"].is_array()) {
    return Status::Error(path + ": no \"objects\" list (not a summary.json written by femreg register)");
  }
  const nlohmann::json& objects = summary["objects"];
  for (size_t i = 0; i < objects.size(); ++i) {
    const nlohmann::json& o = objects[i];
    if (!o.is_object() || !o.contains("name") || !o["name"].is_string()) {
      names->clear();
      return Status::Error(path + ": objects[" + std::to_string(i) + "] has no \"name\"");
    }
    names->push_back(o["name"].get<std::string>());
  }
  return Status::Ok();
}

Status ReadSummaryForcesEstimated(const std::string& path, int* estimated) {
  *estimated = -1;
  nlohmann::json summary;
  if (Status parsed = ParseSummary(path, &summary); !parsed.ok()) return parsed;
  if (summary.contains("forces") && summary["forces"].is_object() && summary["forces"].contains("estimate") &&
      summary["forces"]["estimate"].is_boolean()) {
    *estimated = summary["forces"]["estimate"].get<bool>() ? 1 : 0;
  }
  return Status::Ok();
}

}  // namespace femreg
